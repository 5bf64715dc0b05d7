/*
 * pinch.c - points where a block's boundary touches itself, opened.
 *
 * Method (pinch.h has the rule): every vertex strictly inside a cell of the
 * sample grid (no other may repeat, in_cell) goes into an open-addressing
 * table keyed by its lattice point; a point met twice is a pinch. Each
 * pinch's passes that turn left are candidates, each with the lattice
 * point it would move to (the first one strictly inside its triangle
 * along the wedge's bisector) or none (then it would be cut); the regions
 * the moves sweep are checked empty by one pass over the vertices (a
 * sorted list of the grid cells the triangles' boxes cover); all passes
 * but one per pinch are chosen among those that passed and moved or cut.
 * A move or cut next to another waits for a next round on the new rings.
 *
 * Complexity: O(n) for the filter, O(m) expected for the table of the m
 * vertices inside cells, once when there is no pinch;
 * where pinches exist, O(n log c) more per round for c candidates (rounds
 * are few: a round stops at neighbouring passes only).
 *
 * Robustness: exact integer orientation tests (lattice.h) decide; doubles
 * only propose the point a pass moves to.
 */
#include "pinch.h"
#include "lattice.h"
#include "scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FREE UINT32_MAX
#define CELL_SHIFT 8 /* bucket of the emptiness check: a pixel */
#define CUT 1        /* mark of a vertex cut */
#define NEXT 2       /* mark of a neighbour of a vertex cut */
#define MAX_ROUNDS 64

/* A lattice point's slot table: slot[h] is the first vertex seen there. */
typedef struct
{
    uint32_t *slot;
    size_t mask;
} ptab;

/* A pass that may move: vertex i (at P) of ring r, between vertices a and
 * b, at a pinch of npass passes, to q (when moves; else cut). */
typedef struct
{
    size_t i, a, b;
    size_t r, pinch, npass; /* pinch: the first vertex at P */
    wm_pt q;
    int moves, ok; /* ok: the region it sweeps holds no vertex */
} cut;

typedef struct
{
    uint64_t cell;
    size_t c; /* index into the cuts */
} cellref;

static uint64_t pt_key(wm_pt p)
{
    return (uint64_t)(uint32_t)p.x << 32 | (uint32_t)p.y;
}

static size_t pt_hash(wm_pt p, size_t mask)
{
    uint64_t k = pt_key(p);
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdULL;
    k ^= k >> 33;
    return (size_t)k & mask;
}

/* The first vertex at p's point (FREE when none yet); *h its slot. */
static uint32_t ptab_find(const ptab *t, const wm_pt *pts, wm_pt p, size_t *h)
{
    size_t k = pt_hash(p, t->mask);
    while (t->slot[k] != FREE && !wm_pt_eq(pts[t->slot[k]], p))
        k = (k + 1) & t->mask;
    *h = k;
    return t->slot[k];
}

static int cmp_size(const void *x, const void *y)
{
    const size_t a = *(const size_t *)x, b = *(const size_t *)y;
    return (a > b) - (a < b);
}

static int cmp_cellref(const void *x, const void *y)
{
    const cellref *a = x, *b = y;
    return (a->cell > b->cell) - (a->cell < b->cell);
}

static uint64_t cell_key(int32_t cx, int32_t cy)
{
    return (uint64_t)(uint32_t)cx << 32 | (uint32_t)cy;
}

/* The ring holding vertex i. */
static size_t ring_of(const wm_rings *r, size_t i)
{
    size_t lo = 0, hi = r->nrings; /* start[lo] <= i < start[hi] */
    while (hi - lo > 1)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (r->start[mid] <= i)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Whether q lies in the closed counter-clockwise triangle (a, p, b), and
 * strictly inside it. */
static int in_triangle(wm_pt a, wm_pt p, wm_pt b, wm_pt q)
{
    return wm_orient(a, p, q) >= 0 && wm_orient(p, b, q) >= 0 &&
           wm_orient(b, a, q) >= 0;
}

static int inside_triangle(wm_pt a, wm_pt p, wm_pt b, wm_pt q)
{
    return wm_orient(a, p, q) > 0 && wm_orient(p, b, q) > 0 &&
           wm_orient(b, a, q) > 0;
}

/* The lattice point nearest p, along the bisector of the left turn
 * a -> p -> b, strictly inside triangle (a, p, b), into *q; 0 when the
 * steps of 1, 2, 3, 4, 6, 8, ... units up to the shorter side find none. */
static int move_to(wm_pt a, wm_pt p, wm_pt b, wm_pt *q)
{
    const double ax = (double)a.x - p.x, ay = (double)a.y - p.y;
    const double bx = (double)b.x - p.x, by = (double)b.y - p.y;
    const double la = hypot(ax, ay), lb = hypot(bx, by);
    double ux = ax / la + bx / lb, uy = ay / la + by / lb;
    const double lu = hypot(ux, uy);
    if (!(lu > 0))
        return 0;
    ux /= lu;
    uy /= lu;
    const double reach = la < lb ? la : lb;
    for (double k = 1; k < reach; k = k < 4 ? k + 1 : k * 1.5)
    {
        q->x = p.x + (int32_t)lround(k * ux);
        q->y = p.y + (int32_t)lround(k * uy);
        if (inside_triangle(a, p, b, *q))
            return 1;
    }
    return 0;
}

/* Whether p lies strictly inside a cell of the sample grid. A vertex on a
 * sample row or column is a crossing of a cell's side, and the crossings
 * of one side are distinct lattice points (marching squares puts one
 * there; subpixel.c rounds more apart, probe.c round_crossings); only a
 * vertex inside a cell (subdivision, leaves, corners) may repeat. */
static int in_cell(wm_pt p)
{
    return (p.x & (WM_Q - 1)) != 0 && (p.y & (WM_Q - 1)) != 0;
}

/* Step 1: the table of the vertices inside cells; those met at a point
 * already taken go to rep[0 .. *nrep) (a pinch each). Returns 0 when out
 * of memory. */
static int find_repeats(const wm_rings *r, ptab *t, size_t **rep, size_t *nrep)
{
    uint32_t *in = malloc(r->npts * sizeof *in);
    size_t ncell = 0, cap = 16, rcap = 0;
    int ok = 0;
    if (!in)
        return 0;
    for (size_t i = 0; i < r->npts; i++)
    {
        in[ncell] = (uint32_t)i; /* kept only where it is in a cell */
        ncell += (size_t)in_cell(r->pts[i]);
    }
    while (cap < 2 * ncell)
        cap *= 2;
    t->mask = cap - 1;
    if (!(t->slot = malloc(cap * sizeof *t->slot)))
        goto cleanup;
    memset(t->slot, 0xff, cap * sizeof *t->slot);
    for (size_t k = 0; k < ncell; k++)
    {
        const uint32_t i = in[k];
        size_t h;
        if (ptab_find(t, r->pts, r->pts[i], &h) == FREE)
        {
            t->slot[h] = i;
            continue;
        }
        if (*nrep == rcap)
        {
            rcap = rcap ? 2 * rcap : 16;
            size_t *grown = realloc(*rep, rcap * sizeof *grown);
            if (!grown)
                goto cleanup;
            *rep = grown;
        }
        (*rep)[(*nrep)++] = i;
    }
    ok = 1;
cleanup:
    free(in);
    return ok;
}

/* Step 2: the candidates at the pinch of vertex f (the first there) and
 * its repeats rep[lo .. hi): the passes that turn left, each with the
 * number of passes there and the point it would move to. Returns 0 when
 * out of memory. */
static int candidates(const wm_rings *r, size_t f, const size_t *rep, size_t lo,
                      size_t hi, cut **cuts, size_t *ncut, size_t *cap)
{
    for (size_t k = lo; k <= hi; k++)
    {
        const size_t i = k == hi ? f : rep[k];
        const size_t ri = ring_of(r, i), s = r->start[ri];
        const size_t n = wm_rings_len(r, ri);
        const size_t a = s + (i - s + n - 1) % n, b = s + (i - s + 1) % n;
        if (wm_orient(r->pts[a], r->pts[i], r->pts[b]) <= 0)
            continue;
        if (*ncut == *cap)
        {
            *cap = *cap ? 2 * *cap : 16;
            cut *grown = realloc(*cuts, *cap * sizeof *grown);
            if (!grown)
                return 0;
            *cuts = grown;
        }
        cut *c = &(*cuts)[(*ncut)++];
        *c = (cut){i, a, b, ri, f, hi - lo + 1, r->pts[i], 0, 1};
        c->moves = move_to(r->pts[a], r->pts[i], r->pts[b], &c->q);
    }
    return 1;
}

/* Step 3: every candidate that sweeps a vertex other than its own three
 * points is given up: a move sweeps its closed triangle less the open one
 * (a, q, b), a cut the closed triangle. Returns 0 when out of memory. */
static int check_empty(const wm_rings *r, cut *cuts, size_t ncut)
{
    size_t nref = 0, cap = 0;
    cellref *ref = NULL;
    for (size_t c = 0; c < ncut; c++)
    {
        const wm_pt p[3] = {r->pts[cuts[c].a], r->pts[cuts[c].i],
                            r->pts[cuts[c].b]};
        int32_t x0 = p[0].x, x1 = p[0].x, y0 = p[0].y, y1 = p[0].y;
        for (int k = 1; k < 3; k++)
        {
            x0 = p[k].x < x0 ? p[k].x : x0;
            x1 = p[k].x > x1 ? p[k].x : x1;
            y0 = p[k].y < y0 ? p[k].y : y0;
            y1 = p[k].y > y1 ? p[k].y : y1;
        }
        for (int32_t cx = x0 >> CELL_SHIFT; cx <= x1 >> CELL_SHIFT; cx++)
            for (int32_t cy = y0 >> CELL_SHIFT; cy <= y1 >> CELL_SHIFT; cy++)
            {
                if (nref == cap)
                {
                    cap = cap ? 2 * cap : 64;
                    cellref *grown = realloc(ref, cap * sizeof *grown);
                    if (!grown)
                    {
                        free(ref);
                        return 0;
                    }
                    ref = grown;
                }
                ref[nref++] = (cellref){cell_key(cx, cy), c};
            }
    }
    qsort(ref, nref, sizeof *ref, cmp_cellref);
    for (size_t q = 0; q < r->npts; q++)
    {
        const wm_pt v = r->pts[q];
        const uint64_t key = cell_key(v.x >> CELL_SHIFT, v.y >> CELL_SHIFT);
        size_t lo = 0, hi = nref;
        while (lo < hi)
        {
            const size_t mid = lo + (hi - lo) / 2;
            if (ref[mid].cell < key)
                lo = mid + 1;
            else
                hi = mid;
        }
        for (size_t k = lo; k < nref && ref[k].cell == key; k++)
        {
            cut *c = &cuts[ref[k].c];
            const wm_pt a = r->pts[c->a], p = r->pts[c->i], b = r->pts[c->b];
            if (c->ok && !wm_pt_eq(v, a) && !wm_pt_eq(v, p) &&
                !wm_pt_eq(v, b) && in_triangle(a, p, b, v) &&
                !(c->moves && inside_triangle(a, c->q, b, v)))
                c->ok = 0;
        }
    }
    free(ref);
    return 1;
}

/* Step 4: of the candidates of each pinch (consecutive in cuts[]) that
 * sweep no vertex, all passes but one moved or cut, a cut only in a ring
 * that keeps three vertices (left[]: vertices still in each ring), no two
 * next to each other in a ring (mark[]: CUT, or NEXT to one); the moves
 * made, the vertices to remove into gone[0 .. return). */
static size_t apply_cuts(wm_rings *r, const cut *cuts, size_t ncut,
                         size_t *left, uint8_t *mark, size_t *gone,
                         size_t *nmoved)
{
    size_t ngone = 0;
    for (size_t lo = 0, hi; lo < ncut; lo = hi)
    {
        size_t made = 0;
        for (hi = lo + 1; hi < ncut && cuts[hi].pinch == cuts[lo].pinch; hi++)
            ;
        for (size_t k = lo; k < hi && made + 1 < cuts[lo].npass; k++)
        {
            const cut *c = &cuts[k];
            if (!c->ok || (!c->moves && left[c->r] <= 3) || mark[c->i] ||
                mark[c->a] == CUT || mark[c->b] == CUT)
                continue;
            mark[c->i] = CUT;
            mark[c->a] = mark[c->b] = NEXT;
            if (c->moves)
            {
                r->pts[c->i] = c->q;
                (*nmoved)++;
            }
            else
            {
                left[c->r]--;
                gone[ngone++] = c->i;
            }
            made++;
        }
    }
    return ngone;
}

/* Step 5: the cut vertices (sorted gone[0 .. n)) removed from their
 * rings. */
static void remove_vertices(wm_rings *r, const size_t *gone, size_t n)
{
    size_t w = 0, g = 0;
    for (size_t ri = 0; ri < r->nrings; ri++)
    {
        const size_t s = r->start[ri], e = r->start[ri + 1];
        r->start[ri] = w;
        for (size_t i = s; i < e; i++)
        {
            if (g < n && gone[g] == i)
            {
                g++;
                continue;
            }
            r->pts[w++] = r->pts[i];
        }
    }
    r->start[r->nrings] = w;
    r->npts = w;
}

/* One round: the pinches found, and the passes that may be moved or cut
 * there moved or cut; *nchanged: how many. Returns 0 when out of
 * memory. */
static int open_round(wm_rings *r, size_t *nchanged)
{
    ptab t = {NULL, 0};
    size_t *rep = NULL, nrep = 0, *key = NULL, *left = NULL, *gone = NULL;
    uint8_t *mark = NULL;
    cut *cuts = NULL;
    size_t ncut = 0, cap = 0;
    int ok = 0;
    *nchanged = 0;
    if (!find_repeats(r, &t, &rep, &nrep))
        goto cleanup;
    /* the repeats grouped by their pinch (the first vertex there) */
    if (nrep && !(key = malloc(2 * nrep * sizeof *key)))
        goto cleanup;
    for (size_t k = 0; k < nrep; k++)
    {
        size_t h;
        key[2 * k] = ptab_find(&t, r->pts, r->pts[rep[k]], &h);
        key[2 * k + 1] = rep[k];
    }
    if (nrep)
        qsort(key, nrep, 2 * sizeof *key, cmp_size);
    for (size_t k = 0; k < nrep; k++)
        rep[k] = key[2 * k + 1];
    for (size_t lo = 0, hi; lo < nrep; lo = hi)
    {
        for (hi = lo + 1; hi < nrep && key[2 * hi] == key[2 * lo]; hi++)
            ;
        if (!candidates(r, key[2 * lo], rep, lo, hi, &cuts, &ncut, &cap))
            goto cleanup;
    }
    if (ncut)
    {
        left = malloc(r->nrings * sizeof *left);
        mark = calloc(r->npts, 1);
        gone = malloc(ncut * sizeof *gone);
        if (!left || !mark || !gone || !check_empty(r, cuts, ncut))
            goto cleanup;
        for (size_t ri = 0; ri < r->nrings; ri++)
            left[ri] = wm_rings_len(r, ri);
        size_t nmoved = 0;
        const size_t ngone =
            apply_cuts(r, cuts, ncut, left, mark, gone, &nmoved);
        qsort(gone, ngone, sizeof *gone, cmp_size);
        remove_vertices(r, gone, ngone);
        *nchanged = ngone + nmoved;
    }
    ok = 1;
cleanup:
    free(t.slot);
    free(rep);
    free(key);
    free(left);
    free(mark);
    free(cuts);
    free(gone);
    return ok;
}

wm_status wm_rings_open_pinches(wm_rings *r, const wm_ctx *ctx)
{
    if (r->npts >= FREE)
        return wm_fail(ctx, WM_ERR_NOMEM, "pinch: too many vertices");
    /* a pass next to one moved or cut waits for the next round, on the
     * new rings; each round that changes a pass opens a pinch */
    size_t nchanged = 1;
    for (int round = 0; round < MAX_ROUNDS && nchanged > 0 && r->npts; round++)
        if (!open_round(r, &nchanged))
            return wm_fail(ctx, WM_ERR_NOMEM,
                           "out of memory opening pinch points");
    return WM_OK;
}
