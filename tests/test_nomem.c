/* test_nomem.c - allocation failure: every allocation of the core fails in
 * turn. The test is linked with -Wl,--wrap=malloc,--wrap=calloc,
 * --wrap=realloc,--wrap=free, so the core's allocations pass through the
 * counters below. A dry run notes the call site of each allocation; then
 * every site fails at its first and at its last allocation (the issue's
 * "every allocation site fails once", in two states). Each run must end
 * in WM_OK (an allocation the code can do without) or WM_ERR_NOMEM with a
 * message, never a crash, and leave no allocation behind (the live count
 * returns to where it was). The sanitizer pass of CI runs this under
 * AddressSanitizer, which also catches a use after free or a double free
 * on an error path. */
#include "block.h"
#include "scene_util.h"
#include "tap.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t m);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t m);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);

/* volatile: the compiler knows malloc's semantics and would otherwise
 * read them across the allocation calls that change them */
static volatile long calls;   /* allocations so far */
static volatile long fail_at; /* the allocation that fails (0: none) */
static volatile long live;    /* allocations not freed */
static volatile int failed;   /* the armed failure happened */
/* a dry run (fail_at == 0, record set) notes each allocation's call site */
static int record;
static void **seq;
static long nseq, capseq;

static int fail_now(void *site)
{
    ++calls;
    if (record && fail_at == 0)
    {
        if (nseq == capseq)
        {
            capseq = capseq ? 2 * capseq : 1024;
            seq = __real_realloc(seq, (size_t)capseq * sizeof *seq);
        }
        seq[nseq++] = site;
    }
    if (calls != fail_at)
        return 0;
    failed = 1;
    return 1;
}

void *__wrap_malloc(size_t n)
{
    if (fail_now(__builtin_return_address(0)))
        return NULL;
    void *p = __real_malloc(n);
    live += p != NULL;
    return p;
}

void *__wrap_calloc(size_t n, size_t m)
{
    if (fail_now(__builtin_return_address(0)))
        return NULL;
    void *p = __real_calloc(n, m);
    live += p != NULL;
    return p;
}

void *__wrap_realloc(void *q, size_t n)
{
    if (fail_now(__builtin_return_address(0)))
        return NULL;
    void *p = __real_realloc(q, n);
    live += q == NULL && p != NULL;
    return p;
}

void __wrap_free(void *p)
{
    live -= p != NULL;
    __real_free(p);
}

static int got_message;
static void on_error(void *user, wm_status st, const char *msg)
{
    (void)user;
    (void)st;
    got_message = msg && *msg;
}

/* Rivers crossing a lake with a hole, a wedge, a thin stream and a tiny
 * island, over 2 x 2 blocks of 64 pixels: every stage has work. */
static void scene(wm_scene *s)
{
    su_init(s, 64);
    const double r1[] = {-10, 30, 40, 34, 90, 60, 140, 62};
    const double r2[] = {40, 34, 90, 40, 140, 50};
    const double r3[] = {20, 100, 60, 101.3, 120, 99};
    const double r4[] = {10, 5, 70, 20};
    su_river(s, r1, 4, 4);
    su_river(s, r2, 3, 3);
    su_river(s, r3, 3, 0.2);
    su_river(s, r4, 2, 0.6);
    const double lake[] = {60,  70, 110, 70,   110, 120,  60,
                           120, 80, 90,  80.3, 90,  80.3, 90.3};
    const int counts[] = {4, 3};
    su_lake(s, lake, counts, 2);
    su_finish(s);
}

/* Runs every block with the k-th allocation failing (k = 0: none). */
static void run_failing(const wm_scene *s, const wm_block_opts *o, long k,
                        int *bad)
{
    const long before = live;
    calls = 0;
    failed = 0;
    fail_at = k;
    for (int64_t by = 0; by < 2; by++)
        for (int64_t bx = 0; bx < 2; bx++)
        {
            wm_block_result r;
            got_message = 0;
            const wm_ctx ctx = {on_error, NULL, NULL};
            const wm_status st = wm_block_run(s, bx, by, o, &r, &ctx);
            if (st == WM_OK)
                wm_block_result_free(&r);
            else if (st != WM_ERR_NOMEM || !got_message)
            {
                if (!*bad)
                    printf("# allocation %ld: block (%lld, %lld) status %d, "
                           "message %d\n",
                           k, (long long)bx, (long long)by, (int)st,
                           got_message);
                *bad = 1;
            }
        }
    fail_at = 0;
    if (live != before && !*bad)
    {
        printf("# allocation %ld: %ld allocation(s) left behind\n", k,
               live - before);
        *bad = 1;
    }
    if (k > 0 && !failed && !*bad)
    {
        printf("# allocation %ld never happened: the runs differ\n", k);
        *bad = 1;
    }
}

int main(void)
{
    wm_scene s;
    scene(&s);
    const wm_block_opts opts[] = {
        {.simplify = 0, .triangulate = 1},
        {.simplify = 0.5 * WM_Q,
         .triangulate = 1,
         .merge = 0.2 * WM_Q,
         .min_area = 4.0 * WM_Q * WM_Q},
        {.simplify = 0.25 * WM_Q, .triangulate = 1, .method = WM_METHOD_PAPER}};
    const char *names[] = {"CONTOUR", "CONTOUR simplify merge min_area",
                           "PAPER"};
    for (size_t o = 0; o < sizeof opts / sizeof *opts; o++)
    {
        int bad = 0;
        /* the dry run: which call site makes each allocation */
        nseq = 0;
        record = 1;
        run_failing(&s, &opts[o], 0, &bad);
        record = 0;
        /* each site fails at its first and at its last allocation */
        long runs = 0, nsites = 0;
        for (long k = 0; k < nseq && !bad; k++)
        {
            int first = 1, last = 1;
            for (long j = 0; j < nseq && (first || last); j++)
                if (seq[j] == seq[k] && j != k)
                {
                    first &= j > k;
                    last &= j < k;
                }
            nsites += first;
            if (first || last)
            {
                run_failing(&s, &opts[o], k + 1, &bad);
                runs++;
            }
        }
        TAP_OK(!bad && nseq > 0,
               "%s: %ld call sites of %ld allocations, each failing at its "
               "first and last (%ld runs): WM_ERR_NOMEM with a message or "
               "WM_OK, nothing left allocated",
               names[o], nsites, nseq, runs);
    }

    /* indexing the scene */
    int bad = 0;
    long k = 1;
    for (;; k++)
    {
        wm_scene t;
        su_init(&t, 64);
        const double r1[] = {0, 0, 300, 10};
        su_river(&t, r1, 2, 3);
        t.poly_start = calloc(1, sizeof *t.poly_start);
        const long before = live;
        calls = 0;
        failed = 0;
        fail_at = k;
        const wm_status st = wm_scene_index(&t, NULL);
        fail_at = 0;
        const int done = !failed;
        bad |= st != WM_OK && st != WM_ERR_NOMEM;
        bad |= done && st != WM_OK;
        wm_scene_free(&t);
        bad |= live != before - 2; /* su_* allocated segs and poly_start */
        if (done || bad)
            break;
    }
    TAP_OK(!bad && k > 1, "wm_scene_index: %ld allocations failing in turn",
           k - 1);
    wm_scene_free(&s);
    return TAP_DONE();
}
