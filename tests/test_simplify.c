/*
 * test_simplify.c - topology-preserving Douglas-Peucker (wm_simplify_rings).
 *
 * Every case is checked against the guarantees of simplify.h with checks
 * written independently of the implementation: output vertices are a
 * subsequence of the input ring, every dropped vertex is within tol of the
 * output segment spanning it, >= 3 vertices and the input's orientation, all
 * border vertices kept, no two output segments meet (a sweep over all
 * segments with exact wm_segments_meet), nesting unchanged.
 */
#include "holes.h"
#include "lattice.h"
#include "ring_check.h"
#include "simplify.h"
#include "tap.h"

#include <math.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

static uint64_t lcg_state = 2024;

static uint32_t lcg(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (uint32_t)(lcg_state >> 33);
}

static double frand(void) /* [0, 1) */
{
    return (double)lcg() / 2147483648.0; /* lcg() has 31 bits */
}

static void push(wm_rings *r, int x, int y)
{
    const size_t b = r->nrings ? r->start[r->nrings] : 0;
    wm_pt p;
    p.x = x;
    p.y = y;
    if (r->npts > b && r->pts[r->npts - 1].x == x && r->pts[r->npts - 1].y == y)
        return; /* no repeated consecutive vertices */
    if (wm_rings_push(r, p) != WM_OK)
        abort();
}

static void close_ring(wm_rings *r)
{
    const size_t b = r->nrings ? r->start[r->nrings] : 0;
    while (r->npts > b + 1 && r->pts[r->npts - 1].x == r->pts[b].x &&
           r->pts[r->npts - 1].y == r->pts[b].y)
        r->npts--;
    if (wm_rings_close(r) != WM_OK)
        abort();
}

/* Noisy circle: n vertices at jittered increasing angles, radius
 * rad +- amp; counter-clockwise if ccw. Star-shaped, hence simple. */
static void noisy_circle(wm_rings *r, double cx, double cy, double rad,
                         double amp, int n, int ccw)
{
    for (int i = 0; i < n; i++)
    {
        const int k = ccw ? i : n - 1 - i;
        const double a = 6.283185307179586 * (k + 0.4 * frand()) / n;
        const double rr = rad + amp * (2.0 * frand() - 1.0);
        push(r, (int)lround(cx + rr * cos(a)), (int)lround(cy + rr * sin(a)));
    }
    close_ring(r);
}

/* A smooth profile with wiggles of amplitude 150 and 400. */
static int wiggle(int y)
{
    return (int)lround(400 * sin(y / 1500.0) + 150 * sin(y / 370.0));
}

/* ---- independent checks ------------------------------------------------ */

typedef struct
{
    wm_pt a, b;
    size_t ring, idx, len;
    int32_t xmin, xmax, ymin, ymax;
} tseg;

static int tseg_cmp(const void *pa, const void *pb)
{
    const tseg *a = pa, *b = pb;
    return (a->xmin > b->xmin) - (a->xmin < b->xmin);
}

/* Number of pairs of segments that meet illegally (sweep on x). */
static size_t bad_pairs(const wm_rings *r)
{
    tseg *s = malloc((r->npts ? r->npts : 1) * sizeof *s);
    size_t m = 0, bad = 0;
    for (size_t k = 0; k < r->nrings; k++)
    {
        const size_t b = r->start[k], n = wm_rings_len(r, k);
        for (size_t i = 0; i < n; i++)
        {
            tseg *t = &s[m++];
            t->a = r->pts[b + i];
            t->b = r->pts[b + (i + 1) % n];
            t->ring = k;
            t->idx = i;
            t->len = n;
            t->xmin = t->a.x < t->b.x ? t->a.x : t->b.x;
            t->xmax = t->a.x > t->b.x ? t->a.x : t->b.x;
            t->ymin = t->a.y < t->b.y ? t->a.y : t->b.y;
            t->ymax = t->a.y > t->b.y ? t->a.y : t->b.y;
        }
    }
    qsort(s, m, sizeof *s, tseg_cmp);
    for (size_t i = 0; i < m; i++)
        for (size_t j = i + 1; j < m && s[j].xmin <= s[i].xmax; j++)
        {
            const tseg *p = &s[i], *q = &s[j];
            if (p->ymax < q->ymin || q->ymax < p->ymin)
                continue;
            int meet;
            if (p->ring == q->ring && p->len >= 3 &&
                (p->idx + 1) % p->len == q->idx)
                meet = wm_on_segment(p->a, p->b, q->b) ||
                       wm_on_segment(q->a, q->b, p->a);
            else if (p->ring == q->ring && p->len >= 3 &&
                     (q->idx + 1) % q->len == p->idx)
                meet = wm_on_segment(q->a, q->b, p->b) ||
                       wm_on_segment(p->a, p->b, q->a);
            else
                meet = wm_segments_meet(p->a, p->b, q->a, q->b);
            if (meet)
            {
                if (bad < 3)
                    printf("#   meet: ring %zu (%d,%d)-(%d,%d) / ring %zu "
                           "(%d,%d)-(%d,%d)\n",
                           p->ring, p->a.x, p->a.y, p->b.x, p->b.y, q->ring,
                           q->a.x, q->a.y, q->b.x, q->b.y);
                bad++;
            }
        }
    free(s);
    return bad;
}

/* Checks out against in; returns the number of failed properties and
 * prints the first few problems. */
static int check(const wm_rings *in, const wm_rings *out, int32_t size,
                 double tol, const char *what)
{
    int fails = 0;
    const wm_i128 tol2 = (wm_i128)floor(tol * tol);
    size_t sub_bad = 0, haus_bad = 0, orient_bad = 0, border_bad = 0;
    if (out->nrings != in->nrings)
    {
        printf("#   %s: %zu rings out, %zu in\n", what, out->nrings,
               in->nrings);
        return 1;
    }
    size_t *pos = malloc((in->npts ? in->npts : 1) * sizeof *pos);
    for (size_t r = 0; r < in->nrings; r++)
    {
        const wm_pt *ip = in->pts + in->start[r],
                    *op = out->pts + out->start[r];
        const size_t n = wm_rings_len(in, r), m = wm_rings_len(out, r);
        size_t k = 0;
        for (size_t i = 0; i < n && k < m; i++)
            if (wm_pt_eq(ip[i], op[k]))
                pos[k++] = i;
        if (k != m || m < 3)
        {
            sub_bad++;
            continue;
        }
        const wm_i128 ai = wm_ring_area2(ip, n), ao = wm_ring_area2(op, m);
        if (ao == 0 || (ai > 0) != (ao > 0))
            orient_bad++;
        for (size_t i = 0, kk = 0; i < n; i++)
        {
            if (kk < m && pos[kk] == i)
            {
                kk++;
                continue;
            }
            if (ip[i].x == 0 || ip[i].y == 0 || ip[i].x == size ||
                ip[i].y == size)
                border_bad++;
            /* spanning output segment: pos[kk-1] .. pos[kk] (cyclic) */
            const wm_pt a = op[(kk + m - 1) % m], b = op[kk % m];
            if (wm_seg_dist2_exceeds(a, b, ip[i], tol2))
            {
                if (haus_bad < 3)
                    printf("#   %s: ring %zu vertex %zu (%d,%d) farther than "
                           "tol from (%d,%d)-(%d,%d)\n",
                           what, r, i, ip[i].x, ip[i].y, a.x, a.y, b.x, b.y);
                haus_bad++;
            }
        }
    }
    free(pos);
    const size_t meet = bad_pairs(out);
    int32_t *e1 = malloc((in->nrings ? in->nrings : 1) * sizeof *e1);
    int32_t *e2 = malloc((in->nrings ? in->nrings : 1) * sizeof *e2);
    size_t nest_bad = 0;
    if (wm_holes_nesting(in, e1, NULL) != WM_OK ||
        wm_holes_nesting(out, e2, NULL) != WM_OK)
        nest_bad = 1;
    for (size_t r = 0; r < in->nrings && !nest_bad; r++)
        if (e1[r] != e2[r])
        {
            printf("#   %s: ring %zu nested in %d, was %d\n", what, r, e2[r],
                   e1[r]);
            nest_bad++;
        }
    free(e1);
    free(e2);
    fails = (sub_bad > 0) + (haus_bad > 0) + (orient_bad > 0) +
            (border_bad > 0) + (meet > 0) + (nest_bad > 0);
    if (fails)
        printf("#   %s: subsequence/size %zu, tolerance %zu, orientation %zu, "
               "border %zu, meeting pairs %zu, nesting %zu\n",
               what, sub_bad, haus_bad, orient_bad, border_bad, meet, nest_bad);
    return fails;
}

static size_t bad_in_input(const wm_rings *in)
{
    return bad_pairs(in);
}

/* Simplifies and checks; returns the output vertex count via *nout. */
static void run_case(const wm_rings *in, int32_t size, double tol,
                     const char *what, size_t *nout)
{
    wm_rings out = {0};
    const size_t inbad = bad_in_input(in);
    const wm_status st = wm_simplify_rings(in, size, tol, &out, NULL);
    TAP_OK(inbad == 0 && st == WM_OK && check(in, &out, size, tol, what) == 0,
           "%s: %zu -> %zu vertices, %zu rings (tol %g)", what, in->npts,
           out.npts, in->nrings, tol);
    if (inbad)
        printf("#   the test input itself is invalid (%zu pairs)\n", inbad);
    if (nout)
        *nout = out.npts;
    wm_rings_free(&out);
}

/* Comb: ring A (CCW) has teeth pointing right, ring B (CCW) teeth pointing
 * left, interleaved with 40-unit gaps; tooth edges carry small noise. */
static void comb(wm_rings *r, int ox, int oy, int teeth)
{
    const int top = teeth * 200;
    /* A: base x in [0, 1000], teeth y in [200k, 200k + 80] to x = 1800 */
    push(r, ox, oy);
    for (int k = 0; k < teeth; k++)
    {
        const int y0 = oy + k * 200, y1 = y0 + 80;
        if (k > 0)
            push(r, ox + 1000, y0);
        for (int x = 1000 + 50; x < 1800; x += 50) /* noisy bottom edge */
            push(r, ox + x, y0 + (int)(lcg() % 11));
        push(r, ox + 1800, y0);
        push(r, ox + 1800, y1);
        for (int x = 1800 - 50; x > 1000; x -= 50)
            push(r, ox + x, y1 - (int)(lcg() % 11));
        if (k < teeth - 1)
            push(r, ox + 1000, y1);
        else
            push(r, ox + 1000, y1);
    }
    push(r, ox, oy + (teeth - 1) * 200 + 80);
    close_ring(r);
    /* B: base x in [2000, 3000], teeth y in [200k+120, 200k+160] to 1200 */
    const int b0 = oy + 120 - 40, b1 = oy + top;
    push(r, ox + 3000, b0);
    push(r, ox + 3000, b1);
    push(r, ox + 2000, b1);
    for (int k = teeth - 1; k >= 0; k--)
    {
        const int y0 = oy + k * 200 + 120, y1 = y0 + 40;
        push(r, ox + 2000, y1);
        for (int x = 2000 - 50; x > 1200; x -= 50)
            push(r, ox + x, y1 - (int)(lcg() % 8));
        push(r, ox + 1200, y1);
        push(r, ox + 1200, y0);
        for (int x = 1200 + 50; x < 2000; x += 50)
            push(r, ox + x, y0 + (int)(lcg() % 8));
        push(r, ox + 2000, y0);
    }
    push(r, ox + 2000, b0);
    close_ring(r);
}

/* Marching squares on a random field, as the extraction stage produces:
 * w x h cells of 256 lattice units, water where the field is > 0, frame
 * forced to land so every ring closes, crossing points interpolated
 * strictly inside cell edges (vertices 1-362 units apart), saddles split
 * by the cell's mean, water on the left. `coarse` sets the feature size in
 * cells, `noise` the amplitude of per-vertex noise (field in [-1, 1]). */
static void marching(wm_rings *r, int w, int h, int coarse, double noise)
{
    const int gw = w / coarse + 2, gh = h / coarse + 2;
    double *g = malloc((size_t)gw * gh * sizeof *g);
    long *v = malloc((size_t)(w + 1) * (h + 1) * sizeof *v);
    const size_t nh = (size_t)w * (h + 1), ne = nh + (size_t)(w + 1) * h;
    wm_pt *ep = malloc(ne * sizeof *ep);
    size_t *nx = malloc(ne * sizeof *nx);
    for (int i = 0; i < gw * gh; i++)
        g[i] = 2 * frand() - 1;
    for (int j = 0; j <= h; j++)
        for (int i = 0; i <= w; i++)
        {
            const int ci = i / coarse, cj = j / coarse;
            const double fx = (double)(i % coarse) / coarse;
            const double fy = (double)(j % coarse) / coarse;
            double f = g[cj * gw + ci] * (1 - fx) * (1 - fy) +
                       g[cj * gw + ci + 1] * fx * (1 - fy) +
                       g[(cj + 1) * gw + ci] * (1 - fx) * fy +
                       g[(cj + 1) * gw + ci + 1] * fx * fy;
            f += noise * (2 * frand() - 1);
            long q = 2 * (long)floor(f * 1000) + 1; /* odd: never 0 */
            if (i == 0 || j == 0 || i == w || j == h)
                q = -1;
            v[(size_t)j * (w + 1) + i] = q;
        }
#define V(i, j) v[(size_t)(j) * (w + 1) + (i)]
#define EH(i, j) ((size_t)w * (size_t)(j) + (size_t)(i))
#define EV(i, j) (nh + (size_t)(j) * (w + 1) + (i))
    for (size_t e = 0; e < ne; e++)
        nx[e] = SIZE_MAX;
    for (int j = 0; j <= h; j++) /* crossing points */
        for (int i = 0; i <= w; i++)
        {
            for (int d = 0; d < 2; d++)
            {
                const int i2 = i + (d == 0), j2 = j + (d == 1);
                if (i2 > w || j2 > h)
                    continue;
                const long a = V(i, j), b = V(i2, j2);
                if ((a > 0) == (b > 0))
                    continue;
                long off = lround(256.0 * (double)a / (double)(a - b));
                off = off < 1 ? 1 : off > 255 ? 255 : off;
                wm_pt p;
                p.x = 256 * i + (d == 0 ? (int32_t)off : 0);
                p.y = 256 * j + (d == 1 ? (int32_t)off : 0);
                ep[d == 0 ? EH(i, j) : EV(i, j)] = p;
            }
        }
    for (int j = 0; j < h; j++) /* segments, water on the left */
        for (int i = 0; i < w; i++)
        {
            const long c[4] = {V(i, j), V(i + 1, j), V(i + 1, j + 1),
                               V(i, j + 1)};
            wm_pt cp[4];
            const size_t e[4] = {EH(i, j), EV(i + 1, j), EH(i, j + 1),
                                 EV(i, j)};
            /* edge k joins corners k and k+1; corner k touches e[k-1], e[k] */
            size_t cut[4];
            int nc = 0, ncross = 0;
            for (int k = 0; k < 4; k++)
            {
                cp[k].x = 256 * (i + (k == 1 || k == 2));
                cp[k].y = 256 * (j + (k >= 2));
                ncross += (c[k] > 0) != (c[(k + 1) % 4] > 0);
            }
            if (ncross == 0)
                continue;
            if (ncross == 4)
            {
                const int center = c[0] + c[1] + c[2] + c[3] > 0;
                for (int k = 0; k < 4; k++)
                    if ((c[k] > 0) != center)
                        cut[nc++] = (size_t)k;
            }
            else
            {
                /* the corner alone on its side, or a pair: cut the edges */
                for (int k = 0; k < 4; k++)
                    if ((c[k] > 0) != (c[(k + 3) % 4] > 0) &&
                        (c[k] > 0) != (c[(k + 1) % 4] > 0))
                        cut[nc++] = (size_t)k;
            }
            if (ncross == 2 && nc == 0)
            {
                /* two adjacent corners vs two: crossings on two opposite
                 * edges */
                size_t x = SIZE_MAX, y = SIZE_MAX;
                int wc = 0;
                for (int k = 0; k < 4; k++)
                {
                    if ((c[k] > 0) != (c[(k + 1) % 4] > 0))
                    {
                        if (x == SIZE_MAX)
                            x = e[k];
                        else
                            y = e[k];
                    }
                    if (c[k] > 0)
                        wc = k;
                }
                if (wm_orient(ep[x], ep[y], cp[wc]) > 0)
                    nx[x] = y;
                else
                    nx[y] = x;
                continue;
            }
            for (int m = 0; m < nc; m++)
            {
                const size_t k = cut[m];
                const size_t a = e[(k + 3) % 4], b = e[k];
                const int o = wm_orient(ep[a], ep[b], cp[k]);
                if ((c[k] > 0) == (o > 0))
                    nx[a] = b;
                else
                    nx[b] = a;
            }
        }
    for (size_t e0 = 0; e0 < ne; e0++) /* link into rings */
    {
        if (nx[e0] == SIZE_MAX)
            continue;
        size_t e1 = e0;
        do
        {
            const size_t n1 = nx[e1];
            push(r, ep[e1].x, ep[e1].y);
            nx[e1] = SIZE_MAX;
            e1 = n1;
        } while (e1 != e0 && e1 != SIZE_MAX);
        close_ring(r);
    }
#undef V
#undef EH
#undef EV
    free(g);
    free(v);
    free(ep);
    free(nx);
}

int main(void)
{
    wm_rings in = {0}, out = {0}, out2 = {0};
    size_t nout;
    const int32_t SIZE = 1 << 21;

    /* 1. noisy circle */
    noisy_circle(&in, 100000, 100000, 20000, 120, 2000, 1);
    run_case(&in, SIZE, 256, "noisy circle", &nout);
    TAP_OK(nout < in.npts / 4, "noisy circle: vertex count drops (%zu -> %zu)",
           in.npts, nout);
    run_case(&in, SIZE, 128, "noisy circle", NULL);

    /* 2. rings on the block border */
    {
        const int32_t S = 65536;
        wm_rings_clear(&in);
        /* the whole block square, crossing points on its sides, wiggly
         * nowhere (all vertices on the border) */
        const int side[][2] = {{0, 0},     {9000, 0},  {30000, 0}, {S, 0},
                               {S, 20000}, {S, S},     {40000, S}, {100, S},
                               {0, S},     {0, 30000}, {0, 29000}};
        for (size_t i = 0; i < sizeof side / sizeof side[0]; i++)
            push(&in, side[i][0], side[i][1]);
        close_ring(&in);
        /* a noisy hole inside it */
        noisy_circle(&in, 20000, 20000, 8000, 200, 500, 0);
        run_case(&in, S, 256, "block square + hole", NULL);
        {
            wm_rings_clear(&out);
            wm_simplify_rings(&in, S, 256, &out, NULL);
            TAP_EQ(wm_rings_len(&out, 0), 11,
                   "block square: all 11 border vertices kept");
        }
        /* a dry notch shallower than the tolerance between two vertices of
         * the side y == 0: straightened, it would lay an edge along the
         * side (water there in this block only) */
        {
            wm_rings_clear(&in);
            const int notch[][2] = {{10000, 0},  {12000, 0},    {12500, 50},
                                    {13000, 80}, {13500, 50},   {14000, 0},
                                    {20000, 0},  {20000, 5000}, {10000, 5000}};
            for (size_t i = 0; i < sizeof notch / sizeof notch[0]; i++)
                push(&in, notch[i][0], notch[i][1]);
            close_ring(&in);
            wm_rings_clear(&out);
            wm_simplify_rings(&in, S, 256, &out, NULL);
            int kept = 0;
            for (size_t k = 0; k < out.npts; k++)
                kept |= out.pts[k].x == 13000 && out.pts[k].y == 80;
            TAP_OK(kept && wm_rings_len(&out, 0) < 9,
                   "a notch between two vertices of one side keeps its tip "
                   "(%zu vertices)",
                   wm_rings_len(&out, 0));
        }
        wm_rings_clear(&in);
        /* another block: a lake whose bottom lies on y == 0 (several
         * crossing points), a noisy arc above */
        push(&in, 10000, 0);
        push(&in, 12000, 0);
        push(&in, 15000, 0);
        push(&in, 20000, 0);
        push(&in, 30000, 0);
        for (int i = 1; i < 400; i++)
        {
            const double a = 3.141592653589793 * i / 400;
            const double rr = 10000 + 150 * (2 * frand() - 1);
            push(&in, (int)lround(20000 + rr * cos(a)),
                 (int)lround(rr * sin(a)));
        }
        close_ring(&in);
        /* a noisy ring touching x == 0 at exactly one vertex */
        push(&in, 0, 40000);
        for (int i = 1; i < 300; i++)
        {
            const double a = 3.141592653589793 + 6.283185307179586 * i / 300;
            const double rr = 5000 - 100 * frand();
            push(&in, (int)lround(5000 + rr * cos(a)),
                 (int)lround(40000 + rr * sin(a)));
        }
        close_ring(&in);
        run_case(&in, S, 256, "rings touching the border", NULL);
        wm_rings_clear(&out);
        wm_simplify_rings(&in, S, 256, &out, NULL);
        int ok = out.nrings == 2;
        for (size_t i = 0; ok && i < 5; i++)
            ok = wm_pt_eq(out.pts[i], in.pts[i]);
        TAP_OK(ok, "all y == 0 border vertices kept, in order");
    }

    /* 3. adversarial: noisy walls closer than tol; interleaved combs */
    {
        wm_rings_clear(&in);
        /* A: left block whose right side follows a wiggly profile g(y);
         * B: right block whose left side follows g(y) + 60, sampled at
         * other y's; both with +-10 noise: 37+ units apart, wiggles of
         * amplitude 150-400 (at tol 1000 plain DP results cross) */
        push(&in, 1000, 1000);
        for (int y = 1000; y <= 30000; y += 97)
            push(&in, 5000 + wiggle(y) + (int)(lcg() % 21) - 10, y);
        push(&in, 1000, 30000);
        close_ring(&in);
        push(&in, 9000, 1000);
        push(&in, 9000, 30000);
        for (int y = 30000; y >= 1000; y -= 89)
            push(&in, 5060 + wiggle(y) + (int)(lcg() % 21) - 10, y);
        close_ring(&in);
        run_case(&in, SIZE, 256, "two wiggly walls ~60 apart", NULL);
        run_case(&in, SIZE, 1000, "two wiggly walls ~60 apart", NULL);

        wm_rings_clear(&in);
        comb(&in, 1000, 1000, 30);
        run_case(&in, SIZE, 256, "interleaved combs", NULL);
        run_case(&in, SIZE, 3000, "interleaved combs", NULL);
    }

    /* 4. concentric noisy rings, alternating orientation, gap < tol */
    {
        int all = 1;
        for (int t = 0; t < 6; t++)
        {
            wm_rings_clear(&in);
            const double gap = 60 + 20 * t, amp = gap / 2 - 8;
            for (int k = 0; k < 12; k++)
                noisy_circle(&in, 50000, 50000, 20000 - k * gap, amp,
                             1500 + 37 * k, k % 2 == 0);
            wm_rings_clear(&out);
            const size_t inbad = bad_in_input(&in);
            const double tol = t % 2 ? 256 : 128 + 300 * t;
            all = all && inbad == 0 &&
                  wm_simplify_rings(&in, SIZE, tol, &out, NULL) == WM_OK &&
                  check(&in, &out, SIZE, tol, "concentric") == 0;
        }
        TAP_OK(all, "6 sets of 12 concentric noisy rings, gaps 60-160");
    }

    /* 5. tiny hole (and a tiny lake) near the big ring's wiggly edge */
    {
        wm_rings_clear(&in);
        /* outer CCW: bottom, right, top with an outward bump 200 deep
         * (inside tol) holding a tiny hole, left with an inward notch
         * 200 deep holding a tiny separate lake */
        push(&in, 1000, 1000);
        for (int x = 1100; x < 10000; x += 100)
            push(&in, x, 1000 + (int)(lcg() % 60));
        push(&in, 10000, 1000);
        push(&in, 10000, 10000);
        for (int x = 9900; x > 4500; x -= 100)
            push(&in, x, 10000 - (int)(lcg() % 60));
        push(&in, 4500, 10000);
        push(&in, 4400, 10200);
        push(&in, 4100, 10200);
        push(&in, 4000, 10000);
        for (int x = 3900; x > 1000; x -= 100)
            push(&in, x, 10000 - (int)(lcg() % 60));
        push(&in, 1000, 10000);
        push(&in, 1000, 6000);
        push(&in, 1200, 5900);
        push(&in, 1200, 5600);
        push(&in, 1000, 5500);
        close_ring(&in);
        /* hole (CW) inside the bump */
        push(&in, 4200, 10100);
        push(&in, 4200, 10130);
        push(&in, 4230, 10130);
        push(&in, 4230, 10100);
        close_ring(&in);
        /* tiny lake (CCW) inside the notch, outside the outer ring */
        push(&in, 1050, 5700);
        push(&in, 1080, 5700);
        push(&in, 1080, 5760);
        push(&in, 1050, 5760);
        close_ring(&in);
        run_case(&in, SIZE, 256, "tiny hole and lake by a wiggly edge", NULL);
        wm_rings_clear(&out);
        wm_simplify_rings(&in, SIZE, 256, &out, NULL);
        TAP_OK(out.nrings == 3 &&
                   wm_rings_len(&out, 0) < wm_rings_len(&in, 0) / 3,
               "the outer ring is still simplified (%zu -> %zu)",
               wm_rings_len(&in, 0), out.nrings ? wm_rings_len(&out, 0) : 0);
    }

    /* 6. thin rings DP would collapse */
    {
        wm_rings_clear(&in);
        push(&in, 1000, 5000); /* lens, 20 units thick at most */
        for (int i = 1; i < 200; i++)
            push(&in, 1000 + i * 50,
                 4999 - (int)lround(10 * sin(i * 3.141592653589793 / 200)));
        push(&in, 11000, 5000);
        for (int i = 199; i >= 1; i--)
            push(&in, 1000 + i * 50,
                 5001 + (int)lround(10 * sin(i * 3.141592653589793 / 200)));
        close_ring(&in);
        /* a tiny triangle, a thin CW sliver */
        push(&in, 20000, 20000);
        push(&in, 20010, 20000);
        push(&in, 20005, 20007);
        close_ring(&in);
        push(&in, 30000, 30000);
        push(&in, 30500, 30003);
        push(&in, 31000, 30000);
        push(&in, 30500, 29998);
        close_ring(&in);
        run_case(&in, SIZE, 256, "thin rings", NULL);
        run_case(&in, SIZE, 100000, "thin rings, huge tol", NULL);
        wm_rings_clear(&out);
        wm_simplify_rings(&in, SIZE, 100000, &out, NULL);
        int ok = out.nrings == 3;
        for (size_t r = 0; ok && r < 3; r++)
        {
            const wm_i128 ai =
                wm_ring_area2(in.pts + in.start[r], wm_rings_len(&in, r));
            const wm_i128 ao =
                wm_ring_area2(out.pts + out.start[r], wm_rings_len(&out, r));
            ok = wm_rings_len(&out, r) >= 3 && ao != 0 && (ai > 0) == (ao > 0);
        }
        TAP_OK(ok, "thin rings keep >= 3 vertices and their area's sign");
    }

    /* 7. tol <= 0 copies; deterministic */
    {
        wm_rings_clear(&in);
        noisy_circle(&in, 50000, 50000, 20000, 300, 1000, 1);
        noisy_circle(&in, 50000, 50000, 19700, 100, 1000, 0);
        wm_simplify_rings(&in, SIZE, 0, &out, NULL);
        TAP_OK(rings_equal(&in, &out), "tol = 0: identical copy");
        wm_simplify_rings(&in, SIZE, -5, &out, NULL);
        TAP_OK(rings_equal(&in, &out), "tol < 0: identical copy");
        wm_simplify_rings(&in, SIZE, 512, &out, NULL);
        wm_simplify_rings(&in, SIZE, 512, &out2, NULL);
        TAP_OK(out.npts < in.npts && rings_equal(&out, &out2),
               "deterministic: same output twice (%zu vertices)", out.npts);
    }

    /* 8. large: ~1e6 vertices, marching-squares-like spacing; lakes with
     *    islands, neighbours closer than tol */
    {
        wm_rings_clear(&in);
        for (int a = 0; a < 50; a++)
            for (int b = 0; b < 50; b++)
            {
                const double cx = 20000 + a * 40000, cy = 20000 + b * 40000;
                const int n = 300 + (int)(lcg() % 40);
                noisy_circle(&in, cx, cy, 12000, 150, n, 1);
                if ((a + b) % 2 == 0)
                    noisy_circle(&in, cx, cy, 11800 - 20, 40, n / 2, 0);
                else
                    noisy_circle(&in, cx + 3000, cy, 2000, 80, 60, 0);
                /* a neighbour lake 120 units away from the right side */
                noisy_circle(&in, cx + 12000 + 120 + 150 + 5000, cy, 5000, 10,
                             100 + (int)(lcg() % 30), 1);
            }
        wm_rings_clear(&out);
        const clock_t t0 = clock();
        const wm_status st = wm_simplify_rings(&in, SIZE, 256, &out, NULL);
        const double ms = 1000.0 * (double)(clock() - t0) / CLOCKS_PER_SEC;
        TAP_OK(st == WM_OK && check(&in, &out, SIZE, 256, "large") == 0,
               "large: %zu -> %zu vertices, %zu rings", in.npts, out.npts,
               in.nrings);
        printf("# timing: wm_simplify_rings, %zu vertices, %zu rings, "
               "tol 256: %.1f ms\n",
               in.npts, in.nrings, ms);
    }

    /* 9. realistic: marching-squares rings of random fields, features of
     *    1-8 pixels, rings one pixel apart, tol of half to two pixels */
    {
        int all = 1;
        size_t nin = 0, nout2 = 0, nrings = 0;
        for (int t = 0; t < 24; t++)
        {
            wm_rings_clear(&in);
            marching(&in, 60 + 7 * t, 50 + 5 * t, 1 + t % 8, 0.1 * (t % 4));
            const double tol = t % 3 == 0 ? 128 : t % 3 == 1 ? 256 : 512;
            /* a column of fixed vertices inside the field */
            const int32_t size = 256 * (30 + t);
            wm_rings_clear(&out);
            const size_t inbad = bad_in_input(&in);
            const wm_status st = wm_simplify_rings(&in, size, tol, &out, NULL);
            if (inbad || st != WM_OK || check(&in, &out, size, tol, "field"))
            {
                printf("#   field %d: input bad pairs %zu, status %d\n", t,
                       inbad, (int)st);
                all = 0;
            }
            nin += in.npts;
            nout2 += out.npts;
            nrings += in.nrings;
        }
        TAP_OK(all,
               "24 marching-squares fields: %zu rings, %zu -> %zu vertices",
               nrings, nin, nout2);
    }

    /* 10. timing on a marching-squares block of ~1e6 vertices */
    {
        wm_rings_clear(&in);
        marching(&in, 2048, 2048, 6, 0.25);
        wm_rings_clear(&out);
        const clock_t t0 = clock();
        const wm_status st =
            wm_simplify_rings(&in, 256 * 2048, 256, &out, NULL);
        const double ms = 1000.0 * (double)(clock() - t0) / CLOCKS_PER_SEC;
        TAP_OK(st == WM_OK && check(&in, &out, 256 * 2048, 256, "field") == 0,
               "marching-squares block: %zu -> %zu vertices, %zu rings",
               in.npts, out.npts, in.nrings);
        printf("# timing: wm_simplify_rings, marching squares, %zu vertices, "
               "%zu rings, tol 256: %.1f ms\n",
               in.npts, in.nrings, ms);
    }

    /* 11. a stop asked for: the search returns WM_ERR_CANCELLED, no rings
     * (a block-long river's ring kept simplifying for 1.4 s after a
     * signal) */
    {
        const int stop = 1;
        const wm_ctx ctx = {NULL, NULL, &stop};
        wm_rings_clear(&out);
        const wm_status st =
            wm_simplify_rings(&in, 256 * 2048, 256, &out, &ctx);
        TAP_OK(st == WM_ERR_CANCELLED && out.nrings == 0,
               "cancelled: status %d, %zu rings", (int)st, out.nrings);
    }

    /* the side guard: a shore 60 units from the side x = 0 over 2000
     * units, then closing on it; straightened within the tolerance (100)
     * it would run at 22 units from the side, inside the diametral circles
     * of the 64-unit pieces refinement cuts the side into (radius 32),
     * which it may not split; guarded, the vertex that keeps it out stays,
     * and the collinear one still goes */
    {
        wm_rings_clear(&in);
        const int shore[][2] = {
            {0, 1000}, {60, 1000}, {60, 3000}, {30, 4000}, {0, 5000}};
        for (size_t i = 0; i < sizeof shore / sizeof shore[0]; i++)
            push(&in, shore[i][0], shore[i][1]);
        close_ring(&in);
        wm_side_piece pc[63];
        for (int k = 0; k < 63; k++)
            pc[k] = (wm_side_piece){
                {0, 1000 + 64 * k},
                {0, 1000 + 64 * (k + 1) < 5000 ? 1000 + 64 * (k + 1) : 5000}};
        const int32_t S = 65536;
        wm_rings_clear(&out);
        wm_rings_clear(&out2);
        const wm_status s0 = wm_simplify_rings(&in, S, 100, &out, NULL);
        const wm_status s1 =
            wm_simplify_rings_guarded(&in, S, 100, pc, 63, &out2, NULL);
        int kept = 0, collinear = 0;
        for (size_t k = 0; k < out2.npts; k++)
        {
            kept |= out2.pts[k].x == 60 && out2.pts[k].y == 3000;
            collinear |= out2.pts[k].x == 30;
        }
        TAP_OK(s0 == WM_OK && wm_rings_len(&out, 0) == 3,
               "side guard: unguarded, the shore straightened (%zu vertices)",
               wm_rings_len(&out, 0));
        TAP_OK(s1 == WM_OK && kept && !collinear && wm_rings_len(&out2, 0) == 4,
               "side guard: the vertex keeping the shore off the pieces "
               "stays (%zu vertices)",
               wm_rings_len(&out2, 0));
        /* no piece there: the same as unguarded */
        wm_rings_clear(&out2);
        wm_simplify_rings_guarded(&in, S, 100, pc, 4, &out2, NULL);
        TAP_EQ(wm_rings_len(&out2, 0), 3,
               "side guard: pieces far from the shore change nothing");
    }

    wm_rings_free(&in);
    wm_rings_free(&out);
    wm_rings_free(&out2);
    return TAP_DONE();
}
