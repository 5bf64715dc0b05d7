/*
 * subpixel.c - where the samples cannot decide the boundary, found from the
 * exact inputs: hidden and loose crossings, and the cells they make
 * ambiguous.
 *
 * Why: marching squares sees the boundary only where two neighbouring
 * samples differ in class, and puts it where the linear interpolation of
 * their values vanishes. A strip of land narrower than a pixel between two
 * rivers, the tip of a junction wedge, a stream narrower than a pixel,
 * cross a cell edge twice between two samples of one class: the samples
 * skip them, and the strip comes out cut short, dashed, or as a row of
 * specks. Across such a thin feature the interpolation is wrong too: a
 * sample inside a stream 0.2 pixel wide is valued by the nearer bank, and
 * the crossing towards the far bank lands up to a pixel off.
 *
 * Rule: the field is 1-Lipschitz and |v| never exceeds the distance to the
 * boundary, so no boundary point lies within |v| of a sample; the balls of
 * the samples around an edge leave a feasible part of it where alone the
 * boundary may meet it (feasible_near/far). An edge of one class with a
 * feasible part "cannot decide" (with |va| + |vb| > 1 pixel it never can). An
 * edge whose samples differ is "loose" when its feasible part reaches more than
 * LOOSE pixel from the interpolated crossing, or when a river capsule may
 * cross it twice inside its feasible part (river_may_hide: two streams or
 * a stream and an island narrower than a pixel between the two samples,
 * three crossings where marching squares draws one), or lake edges cross
 * it twice (lake_twice: an island near a lake's shore). An edge of land
 * that cannot decide is searched only when a capsule may cross it twice
 * (capsule_may_cross: the squared distance to the capsule's axis along the
 * edge, less t^2, is concave). A saddle cell cannot decide
 * which diagonal the boundary separates. Their crossings are computed
 * exactly from the inputs (probe.h: capsule and lake intervals along the
 * edge). A cell with a side holding hidden crossings (or three on a
 * loose side), and a saddle cell, is ambiguous; its boundary is rebuilt by
 * subdividing it: each dividing segment's crossings are again found
 * exactly, until every piece holds one boundary segment between two of its
 * sides (a straight segment, as marching squares draws) or is 3-5 lattice
 * units wide (then its crossings are paired as the inputs join the arcs
 * between them inside it: leaf.c); a piece with no crossing on its sides
 * that holds a small lake ring whole, and no seed of anything else, takes
 * that ring as it is (lone_rings). A loose side with one
 * crossing keeps marching squares' segment, moved to the exact crossing.
 *
 * Why nothing is missed: a boundary component that meets an edge of the
 * sample grid either changes the class between its samples (marching
 * squares sees it; three crossings or more there mean an input crossing
 * it twice, river_may_hide and lake_twice) or crosses it an even number
 * of times between samples of one class, where the balls leave a feasible
 * part, so the edge is searched exactly. A component that meets no edge lies
 * inside one cell; seeds reach it: a point of each input smaller than two
 * pixels, the tip of each river cap narrower than 1.5 pixels, the corners of
 * the union (two input boundaries crossing, corners.c) off their cell's
 * segment, and those of a cell holding two or more (crowded_cells); a point on
 * a cell's side is in both cells (cells_holding), since the boundary may turn
 * at it in either. What stays unseen: a feature narrower than the lattice's
 * rounding (block.c drops rings thinner than half a unit, 2A/P).
 *
 * Seams: an edge's crossings depend on the inputs only, with every
 * coordinate difference formed in integers, so both blocks sharing an edge
 * of their square find the same ones; every edge on the square whose
 * samples differ takes its exact crossing in both; subdivision happens
 * inside cells, which belong to one block.
 *
 * Cost: the field's water and near bits per row of a mixed tile, a few
 * float operations per edge both of whose samples are near, a walk along
 * each lake edge over the sample lines it crosses; one exact
 * search (the items near the edge) per edge that cannot decide (and, on
 * land, that a capsule may cross) or is loose; subdivision only in
 * ambiguous cells, O(depth) searches per crossing.
 */
#include "subpixel.h"

#include "contour.h"
#include "corners.h"
#include "lattice.h"
#include "leaf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Most crossings one segment can hold: one per interior lattice point. */
#define MAXCROSS WM_Q
/* Subdivision depth bound (a cell is 256 units: 7 halvings of each side
 * reach parts 3 units wide). */
#define MAXDEPTH 32
/* river caps narrower than this radius get their tips seeded (lattice
 * units): a wider cap's arc stays within a quarter pixel of its chords */
#define THIN_CAP (1.5 * WM_Q)
/* the most an interpolated crossing may stray along its edge (pixels) */
#define LOOSE 0.4f

static uint64_t edge_id(int32_t n, int32_t c, int32_t r, int vertical)
{
    return 2 * ((uint64_t)r * (uint64_t)(n + 1) + (uint64_t)c) +
           (uint64_t)vertical;
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

static int cmp_edge(const void *a, const void *b)
{
    return cmp_u64(&((const wm_hidden_edge *)a)->id,
                   &((const wm_hidden_edge *)b)->id);
}

/* A set of nonzero 64-bit keys, open addressing. */
typedef struct
{
    uint64_t *k;
    size_t cap, n;
} keyset;

/* Inserts key (stored + 1, so 0 marks a free slot); returns 1 when it is
 * new, 0 when present, -1 when out of memory. */
static int keyset_add(keyset *s, uint64_t key)
{
    if (2 * (s->n + 1) > s->cap)
    {
        const size_t cap = s->cap ? 2 * s->cap : 64;
        uint64_t *k = calloc(cap, sizeof *k);
        if (!k)
            return -1;
        for (size_t i = 0; i < s->cap; i++)
            if (s->k[i])
            {
                size_t j =
                    (size_t)(s->k[i] * UINT64_C(0x9e3779b97f4a7c15) >> 32) &
                    (cap - 1);
                while (k[j])
                    j = (j + 1) & (cap - 1);
                k[j] = s->k[i];
            }
        free(s->k);
        s->k = k;
        s->cap = cap;
    }
    const uint64_t v = key + 1;
    size_t j = (size_t)(v * UINT64_C(0x9e3779b97f4a7c15) >> 32) & (s->cap - 1);
    while (s->k[j])
    {
        if (s->k[j] == v)
            return 0;
        j = (j + 1) & (s->cap - 1);
    }
    s->k[j] = v;
    s->n++;
    return 1;
}

static int add_cell(wm_hidden *h, const wm_field *f, int32_t c, int32_t r)
{
    const int32_t n = f->w - 1;
    if (c < 0 || r < 0 || c >= n || r >= n)
        return 1;
    if (!wm_grow((void **)&h->cell, &h->cellcap, h->ncell + 1, sizeof *h->cell))
        return 0;
    h->cell[h->ncell++] = wm_field_cell_key(f, c, r);
    return 1;
}

/* Makes the cells on both sides of the edge from sample (c, r) along x
 * or y ambiguous. */
static int add_edge_cells(wm_hidden *h, const wm_field *f, int32_t c, int32_t r,
                          int vertical)
{
    return vertical ? add_cell(h, f, c - 1, r) && add_cell(h, f, c, r)
                    : add_cell(h, f, c, r - 1) && add_cell(h, f, c, r);
}

/* Lists edge `id` with its k crossings. */
static int add_edge(wm_hidden *h, uint64_t id, const int32_t *off, int k)
{
    if (!wm_grow((void **)&h->edge, &h->edgecap, h->nedge + 1,
                 sizeof *h->edge) ||
        !wm_grow((void **)&h->off, &h->offcap, h->noff + (size_t)k,
                 sizeof *h->off))
        return 0;
    h->edge[h->nedge++] = (wm_hidden_edge){id, (uint32_t)h->noff, (uint32_t)k};
    memcpy(h->off + h->noff, off, (size_t)k * sizeof *off);
    h->noff += (size_t)k;
    return 1;
}

/* Searches the edge from sample (c, r) along x or y, whose two samples
 * are of class wa; lists it and its cells when it holds crossings. */
static int search_edge(wm_hidden *h, const wm_field *f, wm_probe *probe,
                       int32_t c, int32_t r, int vertical, int wa)
{
    int32_t off[MAXCROSS];
    int cls1 = wa;
    const wm_pt P = {c * WM_Q, r * WM_Q};
    const int k =
        wm_probe_crossings(probe, P, vertical, WM_Q, wa, &cls1, off, MAXCROSS);
    if (k <= 0)
        return k == 0;
    if (!add_edge(h, edge_id(f->w - 1, c, r, vertical), off, k))
        return 0;
    return add_edge_cells(h, f, c, r, vertical);
}

/* An edge of a tile's sample array, from the sample at a to a + along;
 * across: the stride beside its line. before, after: whether the tile holds
 * the sample before a and the one after a + along on the line; lo, hi: how
 * many rows (columns) beside the line it holds on each side (2 are used). */
typedef struct
{
    const float *a;
    ptrdiff_t along, across;
    int before, after, lo, hi;
} edge_view;

/* How far the samples of one foot clear the line of an edge: the sample
 * at s and those k = 1, 2 rows beside it, each valued v clearing
 * sqrt(v^2 - k^2) of the line on both sides of its foot (the field is
 * 1-Lipschitz and |v| never exceeds the distance to the boundary, in land
 * and in water). */
static float clear_of(const float *s, const edge_view *e)
{
    float h2 = s[0] * s[0];
    for (int k = 1; k <= 2; k++)
        for (int sgn = -1; sgn <= 1; sgn += 2)
            if ((sgn < 0 ? e->lo : e->hi) >= k)
            {
                const float v = s[sgn * k * e->across];
                const float e2 = v * v - (float)(k * k);
                h2 = e2 > h2 ? e2 : h2;
            }
    return sqrtf(h2);
}

/* [*L, *U]: the part of the edge (pixels from a) that the balls of the
 * samples at its two ends and beside them leave, where alone the boundary
 * may meet it; feasible_far() narrows it with the feet -1 and 2 of the
 * edge's line (the feet -1 and 0 clear a prefix, 1 and 2 a suffix). */
static void feasible_near(const edge_view *e, float *L, float *U)
{
    *L = clear_of(e->a, e);
    *U = 1.0f - clear_of(e->a + e->along, e);
}

static void feasible_far(const edge_view *e, float *L, float *U)
{
    if (e->before)
    {
        const float l = clear_of(e->a - e->along, e) - 1.0f;
        *L = l > *L ? l : *L;
    }
    if (e->after)
    {
        const float u = 2.0f - clear_of(e->a + 2 * e->along, e);
        *U = u < *U ? u : *U;
    }
}

/* Whether an edge whose two samples are of one class cannot decide: some
 * part of it is feasible (with a margin of 1/1000 pixel for the float
 * values). With |va| + |vb| > 1 pixel it never is: screen() leaves those
 * out. */
static int undecided(const edge_view *e)
{
    float L, U;
    feasible_near(e, &L, &U);
    if (L > U + 0.001f)
        return 0;
    feasible_far(e, &L, &U);
    return L <= U + 0.001f;
}

/* Whether the interpolated crossing of an edge whose samples differ in
 * class may lie more than LOOSE pixel from where the boundary meets it. A
 * straight boundary leaves a short feasible part around the interpolated
 * point; a thin feature (the far side of a stream narrower than a pixel,
 * the land between two rivers) a long one. With |va| + |vb| >= 1 - LOOSE
 * it never does: screen() leaves those out. */
static int loose(const edge_view *e)
{
    const float va = fabsf(e->a[0]), vb = fabsf(e->a[e->along]);
    const float p = va / (va + vb); /* interpolated, pixels from a */
    float L, U;
    feasible_near(e, &L, &U);
    if (p - L <= LOOSE && U - p <= LOOSE)
        return 0;
    feasible_far(e, &L, &U);
    return p - L > LOOSE || U - p > LOOSE;
}

/* Whether a river capsule of radius r pixels or more may cross twice the
 * edge from a to b, whose samples are land valued va and vb. Water meets
 * such an edge only where one item crosses it twice (the item holding the
 * water just past where the water begins on the edge holds neither end);
 * a capsule is its axis grown by r, and its axis lies at least va + r from
 * a and vb + r from b. For any set, the squared distance from the point
 * t along the edge less t^2 is concave in t (a minimum of functions
 * linear in t), so the squared distance to the axis there is at least
 * (1 - t)(va + r)^2 + t (vb + r)^2 - t (1 - t); the capsule reaches the
 * edge only where that falls to r^2. This bound grows with r, so the least
 * radius in reach decides for every capsule (a lake's sharp corners have
 * none: r = 0 leaves only the samples' balls, undecided()). The values
 * are taken 1/1000 pixel smaller, the margin undecided() allows. */
static int capsule_may_cross(float va, float vb, double r)
{
    if (isinf(r))
        return 0; /* no river in reach */
    const double a = (va > 0.001f ? va - 0.001 : 0) + r;
    const double b = (vb > 0.001f ? vb - 0.001 : 0) + r;
    const double A = a * a, B = b * b;
    const double t0 = (A - B + 1) / 2; /* where the bound is least */
    const double t = t0 < 0 ? 0 : (t0 > 1 ? 1 : t0);
    return (1 - t) * A + t * B - t * (1 - t) <= r * r;
}

/* How far from the water end of an edge whose samples differ in class a
 * river capsule of radius r pixels or more may cross it twice (pixels;
 * below 0: nowhere), from the value vl of its land end and v2 of the
 * sample one pixel past it on the edge's line (v2 <= 0: water there, or
 * none). Three crossings hide on such an edge only so: of the water past
 * its second crossing, the item holding the part just past it holds
 * neither end, so it crosses the edge twice, past the first crossing. As in
 * capsule_may_cross, f(s) = (squared distance from the point s along the
 * line to the capsule's axis) - s^2 is concave; f(0) >= r^2 (the capsule
 * does not hold the water end), f(1) >= (vl + r)^2 - 1, f(2) >=
 * (v2 + r)^2 - 4 where v2 is land, and f(1) >= (f(0) + f(2)) / 2. The
 * distance falls under r only where s^2 + (1 - s) r^2 + s f(1) < r^2,
 * that is s < r^2 - f(1). Margins of 1/1000 pixel as there. */
static double hide_reach(float vl, float v2, double r)
{
    if (isinf(r))
        return -1; /* no river in reach */
    const double b = vl > 0.001f ? vl - 0.001 : 0;
    double s = 1 - b * b - 2 * b * r;
    if (v2 > 0)
    {
        const double b2 = v2 > 0.001f ? v2 - 0.001 : 0;
        const double s2 = (4 - b2 * b2 - 2 * b2 * r) / 2;
        s = s2 < s ? s2 : s;
    }
    return s;
}

/* Cell (c, r) of key k. */
static void cell_of(const wm_field *f, uint64_t k, int32_t *c, int32_t *r)
{
    const int64_t t = (int64_t)(k >> 32);
    const int32_t local = (int32_t)(k & 0xffffffffu);
    *c = (int32_t)(t % f->ntx) * WM_TILE + local % WM_TILE;
    *r = (int32_t)(t / f->ntx) * WM_TILE + local / WM_TILE;
}

/* Exact crossings of edge (c, r)-(c + 1, r) or (c, r)-(c, r + 1), whose
 * samples differ in class, listed; returns how many (-1: out of memory). */
static int exact_edge(wm_hidden *h, const wm_field *f, wm_probe *probe,
                      int32_t c, int32_t r, int vertical)
{
    int32_t off[MAXCROSS];
    const int wa = wm_field_at(f, c, r) <= 0;
    int wb =
        (vertical ? wm_field_at(f, c, r + 1) : wm_field_at(f, c + 1, r)) <= 0;
    const wm_pt P = {c * WM_Q, r * WM_Q};
    const int k =
        wm_probe_crossings(probe, P, vertical, WM_Q, wa, &wb, off, MAXCROSS);
    if (k < 0 || !add_edge(h, edge_id(f->w - 1, c, r, vertical), off, k))
        return -1;
    return k;
}

/* Lists the exact crossings of a loose edge from sample (c, r): one
 * replaces the interpolated crossing in both its cells (see link_cells);
 * three or more make its cells ambiguous. Returns 0 when out of memory. */
static int loose_edge(wm_hidden *h, const wm_field *f, wm_probe *probe,
                      int32_t c, int32_t r, int vertical)
{
    const int k = exact_edge(h, f, probe, c, r, vertical);
    if (k < 0)
        return 0;
    if (k < 3)
        return 1;
    return add_edge_cells(h, f, c, r, vertical);
}

/* The sides of the ambiguous cells whose samples differ in class (but
 * those on the block square: the block across could not know) get their
 * exact crossings, listed; three or more make the cell across ambiguous
 * too. Leaves h->cell distinct. */
static int exact_sides(wm_hidden *h, const wm_field *f, wm_probe *probe)
{
    const int32_t n = f->w - 1;
    keyset cells = {NULL, 0, 0}, edges = {NULL, 0, 0};
    int ok = 1;
    size_t m = 0;
    for (size_t i = 0; i < h->nedge && ok; i++)
        ok = keyset_add(&edges, h->edge[i].id) >= 0; /* loose edges */
    for (size_t i = 0; i < h->ncell && ok; i++)
    {
        const int a = keyset_add(&cells, h->cell[i]);
        ok = a >= 0;
        if (a > 0)
            h->cell[m++] = h->cell[i];
    }
    h->ncell = m;
    for (size_t i = 0; i < h->ncell && ok; i++) /* h->cell grows */
    {
        int32_t c, r;
        cell_of(f, h->cell[i], &c, &r);
        for (int side = 0; side < 4 && ok; side++)
        {
            const int vertical = side == 1 || side == 3;
            const int32_t sc = side == 1 ? c + 1 : c;
            const int32_t sr = side == 2 ? r + 1 : r;
            if (vertical ? sc == 0 || sc == n : sr == 0 || sr == n)
                continue; /* listed by the screen (every crossing there) */
            const int wa = wm_field_at(f, sc, sr) <= 0;
            const int wb = (vertical ? wm_field_at(f, sc, sr + 1)
                                     : wm_field_at(f, sc + 1, sr)) <= 0;
            if (wa == wb)
                continue; /* searched already */
            const int a = keyset_add(&edges, edge_id(n, sc, sr, vertical));
            if (a <= 0)
            {
                ok = a == 0;
                continue;
            }
            const int k = exact_edge(h, f, probe, sc, sr, vertical);
            ok = k >= 0;
            if (!ok || k < 3)
                continue;
            /* the cell across */
            const int32_t oc = side == 1 ? c + 1 : (side == 3 ? c - 1 : c);
            const int32_t orow = side == 2 ? r + 1 : (side == 0 ? r - 1 : r);
            const int b = keyset_add(&cells, wm_field_cell_key(f, oc, orow));
            ok = b >= 0 && (b == 0 || add_cell(h, f, oc, orow));
        }
    }
    free(cells.k);
    free(edges.k);
    return ok;
}

typedef struct
{
    uint64_t key;
    size_t i;
} seedkey;

static int cmp_seedkey(const void *a, const void *b)
{
    const seedkey *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->i > y->i) - (x->i < y->i);
}

/* The cells of the block whose closed square holds block-local point
 * (x, y), into c[] and r[]: one, two for a point on a cell's side, four
 * for a sample; returns how many. A point on a side belongs to both cells:
 * the boundary may turn at it in either (a lake's edge along a sample
 * column, met there by a river's bank, leaves its land in the cell on one
 * side and its water in the other). */
static int cells_holding(const wm_field *f, int64_t x, int64_t y, int32_t *c,
                         int32_t *r)
{
    const int64_t n = f->w - 1;
    const int64_t cx = wm_floordiv(x, WM_Q), cy = wm_floordiv(y, WM_Q);
    int k = 0;
    for (int64_t j = cy - (y % WM_Q == 0); j <= cy; j++)
        for (int64_t i = cx - (x % WM_Q == 0); i <= cx; i++)
            if (i >= 0 && j >= 0 && i < n && j < n)
            {
                c[k] = (int32_t)i;
                r[k++] = (int32_t)j;
            }
    return k;
}

/* Seeds point (x, y) (block-local) in cell (c, r), made ambiguous too when
 * `ambiguous`. */
static int seed_cell(wm_hidden *h, const wm_field *f, int64_t x, int64_t y,
                     int32_t c, int32_t r, int ambiguous)
{
    if (!wm_grow((void **)&h->seed, &h->seedcap, h->nseed + 1,
                 sizeof *h->seed) ||
        !wm_grow((void **)&h->seedcell, &h->seedcellcap, h->nseed + 1,
                 sizeof *h->seedcell))
        return 0;
    h->seed[h->nseed] = (wm_pt){(int32_t)x, (int32_t)y};
    h->seedcell[h->nseed++] = wm_field_cell_key(f, c, r);
    return !ambiguous || add_cell(h, f, c, r);
}

/* Seeds point (x, y) (block-local) of a small input in every cell of the
 * block holding it. */
static int add_seed(wm_hidden *h, const wm_field *f, int64_t x, int64_t y,
                    int ambiguous)
{
    int32_t c[4], r[4];
    const int k = cells_holding(f, x, y, c, r);
    for (int i = 0; i < k; i++)
        if (!seed_cell(h, f, x, y, c[i], r[i], ambiguous))
            return 0;
    return 1;
}

/* Seeds the tips of thin segment g's caps that lie on the union's
 * boundary: a cap narrower than a pixel may end inside a cell whose
 * samples one side of the strip covers, where the cell's crossings agree
 * with the samples and only its seed shows the strip going on. The tip of
 * a cap that continues into the next segment of its line lies inside that
 * segment's capsule and is skipped (a floating-point choice: a seed only
 * adds exact work). */
static int add_tips(wm_hidden *h, const wm_field *f, wm_probe *probe,
                    const wm_river_seg *g)
{
    const double ux = (double)(g->bx - g->ax), uy = (double)(g->by - g->ay);
    const double len = hypot(ux, uy);
    if (len == 0)
        return 1;
    for (int end = 0; end < 2; end++)
    {
        const double sg = end ? g->r / len : -g->r / len;
        const int64_t x =
            (end ? g->bx : g->ax) - probe->X0 + (int64_t)llround(sg * ux);
        const int64_t y =
            (end ? g->by : g->ay) - probe->Y0 + (int64_t)llround(sg * uy);
        const int64_t n = (int64_t)(f->w - 1) * WM_Q;
        if (x < 0 || y < 0 || x >= n || y >= n)
            continue;
        if (wm_probe_distance(probe, (double)x, (double)y, g->r + 2) < -1.0)
            continue;
        if (!add_seed(h, f, x, y, 1))
            return 0;
    }
    return 1;
}

/* Whether corner p of the union's boundary (probe->corner) lies under a
 * third input, where it seeds nothing (a floating-point choice: a seed
 * only adds exact work). */
static int buried(wm_probe *probe, wm_pt p)
{
    return wm_probe_distance(probe, p.x, p.y, 2.0) < -1.0;
}

/* Squared distance from (x, y) to segment [a, b]. */
static double seg_dist2(double x, double y, double ax, double ay, double bx,
                        double by)
{
    const double ux = bx - ax, uy = by - ay, l2 = ux * ux + uy * uy;
    double t = l2 > 0 ? ((x - ax) * ux + (y - ay) * uy) / l2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double dx = ax + t * ux - x, dy = ay + t * uy - y;
    return dx * dx + dy * dy;
}

/* Whether corner p of the union lies farther than a quarter pixel from
 * every segment the samples of its cell (c, r) give (the crossings
 * contour.c puts on the cell's sides, wm_contour_crossing; a saddle's two
 * pairings both count):
 * crease.c recovers a corner only that close to a segment. Such a cell
 * is ambiguous: a cell of one class (an island or a pond smaller than a
 * pixel), or a land triangle at a lake's inner corner that a sub-pixel
 * river cuts off, touching the cell's sides only on the lake's boundary,
 * which is water. */
static int off_contour(const wm_field *f, int32_t c, int32_t r, wm_pt p)
{
    float v[4];
    wm_field_cell(f, c, r, v);
    const int32_t X = c * WM_Q, Y = r * WM_Q;
    /* the sides, counter-clockwise from the bottom, as contour.c draws
     * their crossings: from the lower sample, (x, y, direction) */
    const int a[4] = {0, 1, 3, 0}, b[4] = {1, 2, 2, 3};
    const int32_t sx[4] = {X, X + WM_Q, X, X}, sy[4] = {Y, Y, Y + WM_Q, Y};
    const int dir[4] = {0, 1, 0, 1};
    wm_pt q[4];
    int n = 0;
    for (int k = 0; k < 4; k++)
        if ((v[a[k]] <= 0) != (v[b[k]] <= 0))
            q[n++] =
                wm_contour_crossing(v[a[k]], v[b[k]], sx[k], sy[k], dir[k]);
    const double lim = (double)WM_Q / 4;
    /* a saddle's pairings join neighbouring sides, never opposite ones */
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            if (!(n == 4 && j == i + 2) &&
                seg_dist2(p.x, p.y, q[i].x, q[i].y, q[j].x, q[j].y) <=
                    lim * lim)
                return 0;
    return 1;
}

/* Seeds corner p of the union in the cells holding it that want it: with
 * steer 0, those where it lies off the cell's segments (off_contour; they
 * are made ambiguous); with steer 1, the ambiguous ones (h->cell sorted)
 * where it lies on them, to steer their subdivision. A corner buried under
 * a third input seeds nothing. */
static int seed_corner(wm_hidden *h, const wm_field *f, wm_probe *probe,
                       wm_pt p, int steer)
{
    int32_t c[4], r[4];
    const int k = cells_holding(f, p.x, p.y, c, r);
    for (int j = 0, checked = 0; j < k; j++)
    {
        if ((steer && !wm_hidden_is_cell(h, f, c[j], r[j])) ||
            off_contour(f, c[j], r[j], p) == steer)
            continue;
        if (!checked++ && buried(probe, p))
            return 1;
        if (!seed_cell(h, f, p.x, p.y, c[j], r[j], !steer))
            return 0;
    }
    return 1;
}

/* The key of the window of 2 x 2 cells whose lower left cell is (c, r),
 * -1 <= c, r. */
static uint64_t window_key(int32_t c, int32_t r)
{
    return (uint64_t)(uint32_t)(r + 1) << 32 | (uint32_t)(c + 1);
}

/* Seeds the corners of the union that join neither two capsules sharing
 * an end nor two edges of one lake sharing a vertex (probe->corner_joint
 * is 0), two or more of them in one window of 2 x 2 cells, in the cells
 * holding them, and makes those cells ambiguous. A boundary component
 * narrower and lower than a pixel lies in such a window (its extent meets
 * two columns of cells at most, and two rows); unless it is an input
 * smaller than two pixels (seeded as such) it is bounded by arcs of
 * several capsules and lake edges, and all its corners lie in the window.
 * Group the primitives that share ends: two capsules sharing an end are
 * convex and meet, so a group of them encloses nothing unless it closes a
 * loop, and a lake's edges close its own ring (the exceptions, see
 * architecture.md); a boundary that goes from one group to another comes
 * back, so it has two corners at least that are not joint. This holds
 * wherever the component lies, even within a quarter pixel of the cells'
 * segments (off_contour) and across the sides of its cells where the
 * screen searched none (an island crossing the side between its two cells
 * as three crossings of a side whose samples differ, not loose: spike seed
 * 152138 at 3 m), and does not depend on which corners of shared ends a
 * job finds. */
static int crowded_cells(wm_hidden *h, const wm_field *f, wm_probe *probe)
{
    enum
    {
        OPEN,
        SEED,
        BURIED
    };
    seedkey *o = malloc((9 * probe->ncorner + 1) * sizeof *o);
    uint8_t *state = calloc(probe->ncorner + 1, 1);
    if (!o || !state)
    {
        free(o);
        free(state);
        return 0;
    }
    size_t n = 0;
    for (size_t i = 0; i < probe->ncorner; i++)
    {
        int32_t c[4], r[4];
        const int k = probe->corner_joint[i]
                          ? 0
                          : cells_holding(f, probe->corner[i].x,
                                          probe->corner[i].y, c, r);
        if (k == 0)
            continue;
        /* its cells are adjacent (one, two or four): the windows holding
         * any of them, each once */
        for (int32_t wr = r[0] - 1; wr <= r[k - 1]; wr++)
            for (int32_t wc = c[0] - 1; wc <= c[k - 1]; wc++)
                o[n++] = (seedkey){window_key(wc, wr), i};
    }
    qsort(o, n, sizeof *o, cmp_seedkey);
    for (size_t a = 0, z; a < n; a = z)
    {
        for (z = a + 1; z < n && o[z].key == o[a].key; z++)
            ;
        if (z - a < 2)
            continue;
        size_t kept = 0;
        for (size_t i = a; i < z; i++)
        {
            uint8_t *st = &state[o[i].i];
            if (*st == OPEN && buried(probe, probe->corner[o[i].i]))
                *st = BURIED;
            kept += *st != BURIED;
        }
        for (size_t i = a; kept >= 2 && i < z; i++)
            if (state[o[i].i] != BURIED)
                state[o[i].i] = SEED;
    }
    int ok = 1;
    for (size_t i = 0; ok && i < probe->ncorner; i++)
    {
        if (state[i] != SEED)
            continue;
        int32_t c[4], r[4];
        const int k =
            cells_holding(f, probe->corner[i].x, probe->corner[i].y, c, r);
        for (int j = 0; ok && j < k; j++)
            ok = seed_cell(h, f, probe->corner[i].x, probe->corner[i].y, c[j],
                           r[j], 1);
    }
    free(o);
    free(state);
    return ok;
}

/* Seeds the cells of the inputs smaller than two pixels: lake rings (the
 * runs of edges of a polygon that close) and river segments with their
 * radius, by their first point; the tips of thin caps; and the corners of
 * the union (probe->corner) off their cell's contour (off_contour), whose
 * cells are ambiguous: the corner of an island smaller than a pixel that
 * several rivers enclose, or of a pond between banks, which no side of the
 * cell may cross, or of a land triangle that touches the sides only where
 * they are water. */
static int add_seeds(wm_hidden *h, const wm_field *f, wm_probe *probe)
{
    const wm_scene *s = probe->s;
    const int64_t small = 2 * WM_Q;
    for (size_t k = 0; k < probe->npolys; k++)
    {
        const uint32_t p = probe->polys[k];
        size_t e0 = s->poly_start[p];
        int64_t x0 = INT64_MAX, y0 = INT64_MAX, x1 = INT64_MIN, y1 = INT64_MIN;
        for (size_t e = e0; e < s->poly_start[p + 1]; e++)
        {
            const wm_lake_edge *g = &s->edges[e];
            x0 = g->ax < x0 ? g->ax : x0;
            y0 = g->ay < y0 ? g->ay : y0;
            x1 = g->ax > x1 ? g->ax : x1;
            y1 = g->ay > y1 ? g->ay : y1;
            const int closes = e + 1 == s->poly_start[p + 1] ||
                               s->edges[e + 1].ax != g->bx ||
                               s->edges[e + 1].ay != g->by;
            if (!closes)
                continue;
            if (x1 - x0 < small && y1 - y0 < small &&
                !add_seed(h, f, s->edges[e0].ax - probe->X0,
                          s->edges[e0].ay - probe->Y0, 1))
                return 0;
            e0 = e + 1;
            x0 = y0 = INT64_MAX;
            x1 = y1 = INT64_MIN;
        }
    }
    for (size_t i = 0; i < probe->nsegs; i++)
    {
        const wm_river_seg *g = &s->segs[probe->segs[i]];
        const int64_t dx = g->bx > g->ax ? g->bx - g->ax : g->ax - g->bx;
        const int64_t dy = g->by > g->ay ? g->by - g->ay : g->ay - g->by;
        if ((double)(dx > dy ? dx : dy) + 2 * g->r < (double)small &&
            !add_seed(h, f, g->ax - probe->X0, g->ay - probe->Y0, 1))
            return 0;
        if (g->r < THIN_CAP && !add_tips(h, f, probe, g))
            return 0;
    }
    for (size_t i = 0; i < probe->ncorner; i++)
        if (!seed_corner(h, f, probe, probe->corner[i], 0))
            return 0;
    return crowded_cells(h, f, probe);
}

/* Seeds the other corners of the union in the cells ambiguous for other
 * reasons (h->cell, sorted): there a seed steers the subdivision to the corner
 * (a wedge tip the straight segment of a simple rectangle would cut); crease.c
 * recovers the corners of the other cells, where a seed would not be read. */
static int steer_seeds(wm_hidden *h, const wm_field *f, wm_probe *probe)
{
    for (size_t i = 0; i < probe->ncorner; i++)
        if (!seed_corner(h, f, probe, probe->corner[i], 1))
            return 0;
    return 1;
}

/* Sorts the seeds by cell: (cell, index) pairs sorted, then both arrays
 * permuted. */
static int sort_seeds(wm_hidden *h)
{
    if (h->nseed < 2)
        return 1;
    seedkey *o = malloc(h->nseed * sizeof *o);
    wm_pt *p = malloc(h->nseed * sizeof *p);
    if (!o || !p)
    {
        free(o);
        free(p);
        return 0;
    }
    for (size_t i = 0; i < h->nseed; i++)
        o[i] = (seedkey){h->seedcell[i], i};
    qsort(o, h->nseed, sizeof *o, cmp_seedkey);
    for (size_t i = 0; i < h->nseed; i++)
    {
        p[i] = h->seed[o[i].i];
        h->seedcell[i] = o[i].key;
    }
    free(h->seed);
    h->seed = p;
    h->seedcap = h->nseed;
    free(o);
    return 1;
}

/* Adds the key of cell (c, r), if in the block, to h->link. */
static int add_link(wm_hidden *h, const wm_field *f, int32_t c, int32_t r)
{
    const int32_t n = f->w - 1;
    if (c < 0 || r < 0 || c >= n || r >= n)
        return 1;
    if (!wm_grow((void **)&h->link, &h->linkcap, h->nlink + 1, sizeof *h->link))
        return 0;
    h->link[h->nlink++] = wm_field_cell_key(f, c, r);
    return 1;
}

/* h->link: the cells next to an ambiguous cell and the two cells of each
 * edge with one listed crossing (a loose edge, or a side of an ambiguous
 * cell), sorted, distinct: those whose segments take listed crossings. */
static int link_cells(wm_hidden *h, const wm_field *f)
{
    for (size_t i = 0; i < h->ncell; i++)
    {
        int32_t c, r;
        cell_of(f, h->cell[i], &c, &r);
        if (!add_link(h, f, c - 1, r) || !add_link(h, f, c + 1, r) ||
            !add_link(h, f, c, r - 1) || !add_link(h, f, c, r + 1))
            return 0;
    }
    const int64_t stride = (int64_t)f->w; /* edge ids: see subpixel.h */
    for (size_t i = 0; i < h->nedge; i++)
    {
        if (h->edge[i].n != 1)
            continue;
        const int64_t e = (int64_t)(h->edge[i].id >> 1);
        const int32_t c = (int32_t)(e % stride), r = (int32_t)(e / stride);
        const int vertical = (int)(h->edge[i].id & 1);
        if (!add_link(h, f, c, r) ||
            !add_link(h, f, c - vertical, r - !vertical))
            return 0;
    }
    if (h->nlink < 2)
        return 1;
    qsort(h->link, h->nlink, sizeof *h->link, cmp_u64);
    size_t m = 1;
    for (size_t i = 1; i < h->nlink; i++)
        if (h->link[i] != h->link[m - 1])
            h->link[m++] = h->link[i];
    h->nlink = m;
    return 1;
}

/* ---- the sample edges lake edges cross twice --------------------------- */

/* Three crossings hide on an edge whose samples differ only where one item
 * holds water between two of them (see river_may_hide): for a lake, a
 * polygon holding a stretch of the sample edge between two of its own
 * crossings. Its edges then cross the sample edge twice, counted by the
 * field's half-open rule (as on the sample line moved up or right by an
 * infinitesimal: a vertex touching the line from below adds water at one
 * point only), or one lies along it. Those sample edges are found from the
 * lake edges, by a walk along each over the sample lines it crosses (work
 * that grows with shoreline), and searched exactly. */

/* The sample edges met by lake edges, by the mixed tile that screens them
 * (screen_tile: a tile's top row and right column but the block's are its
 * neighbours'): per tile of the block its slot (0: none yet), per slot the
 * rows of edges along x and y met once (seen) and twice or more (twice).
 * A lake edge repeated (a lake's twin, an edge two lakes share) meets them
 * where it did and is walked once (lake_segs). */
typedef struct
{
    uint64_t seen[2][WM_TILE + 1], twice[2][WM_TILE + 1];
} lake_slot;

typedef struct
{
    const wm_field *f;
    uint32_t *slot;
    lake_slot *s;
    size_t nslot, cap;
} lake_meets;

/* Notes that a lake edge meets sample edge (c, r) along x or y, `times`
 * times. */
static int lake_meet(lake_meets *m, int32_t c, int32_t r, int vertical,
                     int times)
{
    const wm_field *f = m->f;
    const int32_t n = f->w - 1;
    const int32_t tx = (c < n ? c : n - 1) / WM_TILE;
    const int32_t ty = (r < n ? r : n - 1) / WM_TILE;
    const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
    if (f->kind[t] != WM_TILE_MIXED)
        return 1; /* no sample edge there has samples of two classes */
    if (!m->slot[t])
    {
        if (!wm_grow((void **)&m->s, &m->cap, m->nslot + 1, sizeof *m->s))
            return 0;
        memset(&m->s[m->nslot], 0, sizeof *m->s);
        m->slot[t] = (uint32_t)++m->nslot;
    }
    lake_slot *s = &m->s[m->slot[t] - 1];
    const int32_t row = r - ty * WM_TILE;
    const uint64_t bit = UINT64_C(1) << (c - tx * WM_TILE);
    if (times > 1 || s->seen[vertical][row] & bit)
        s->twice[vertical][row] |= bit;
    s->seen[vertical][row] |= bit;
    return 1;
}

/* The sample edges of the lines u = k Q (k in 0..n) that the block-local
 * lake edge (au, as) -> (bu, bs), whose box meets the block (so a line it
 * lies along is one of them), crosses (u across the lines, s along them),
 * by the field's half-open rule (a vertex on a line counts for the edge
 * beyond it): the sample edge holding the crossing, and its neighbour too
 * within the rounding of the crossing's position and 1/1000 unit of a
 * sample (a screen: the search is exact). A lake edge lying along a line
 * meets the sample edges it overlaps twice. */
static int lake_edge_lines(lake_meets *m, int64_t au, int64_t as, int64_t bu,
                           int64_t bs, int vertical)
{
    const int32_t n = m->f->w - 1;
    const int64_t hi = (int64_t)n * WM_Q;
    if (au == bu)
    {
        if (au % WM_Q != 0)
            return 1;
        const int64_t s0 = as < bs ? as : bs, s1 = as < bs ? bs : as;
        if (s1 <= 0 || s0 >= hi)
            return 1; /* at a block corner */
        const int32_t k = (int32_t)(au / WM_Q);
        const int32_t j0 = s0 <= 0 ? 0 : (int32_t)(s0 / WM_Q);
        const int32_t j1 = s1 >= hi ? n - 1 : (int32_t)((s1 - 1) / WM_Q);
        for (int32_t j = j0; j <= j1; j++)
            if (!(vertical ? lake_meet(m, k, j, 1, 2)
                           : lake_meet(m, j, k, 0, 2)))
                return 0;
        return 1;
    }
    const int64_t u0 = au < bu ? au : bu, u1 = au < bu ? bu : au;
    if (u1 <= 0)
        return 1;
    const int64_t k0 = u0 <= 0 ? 0 : (u0 + WM_Q - 1) / WM_Q; /* k Q >= u0 */
    const int64_t k1 = u1 > hi ? n : (u1 - 1) / WM_Q;        /* k Q < u1 */
    const double slope = (double)(bs - as) / (double)(bu - au);
    for (int64_t k = k0; k <= k1; k++)
    {
        const double s = (double)as + (double)(k * WM_Q - au) * slope;
        const double e = 1e-3 + 1e-14 * (fabs((double)as) + fabs(s));
        const double lo = floor((s - e) / WM_Q);
        const double up = floor((s + e) / WM_Q);
        if (up < 0 || lo >= n)
            continue;
        for (int32_t j = lo < 0 ? 0 : (int32_t)lo; j <= (int32_t)up && j < n;
             j++)
            if (!(vertical ? lake_meet(m, (int32_t)k, j, 1, 1)
                           : lake_meet(m, j, (int32_t)k, 0, 1)))
                return 0;
    }
    return 1;
}

/* A lake edge meeting the block, block-local, its ends in lexicographic
 * order (so that an edge repeated either way round compares equal). */
typedef struct
{
    int64_t x0, y0, x1, y1;
} lake_seg;

static int cmp_lake_seg(const void *a, const void *b)
{
    const lake_seg *p = a, *q = b;
    const int64_t d[4] = {p->x0 - q->x0, p->y0 - q->y0, p->x1 - q->x1,
                          p->y1 - q->y1};
    for (int i = 0; i < 4; i++)
        if (d[i])
            return d[i] < 0 ? -1 : 1;
    return 0;
}

/* The block's lake edges (the probe's) that meet its square, distinct, in
 * *out (*n of them). Returns 0 when out of memory. */
static int lake_segs(const wm_field *f, const wm_probe *probe, lake_seg **out,
                     size_t *n)
{
    const int64_t hi = (int64_t)(f->w - 1) * WM_Q;
    lake_seg *g = malloc((probe->nledge + 1) * sizeof *g);
    if (!g)
        return 0;
    size_t k = 0;
    for (size_t i = 0; i < probe->nledge; i++)
    {
        const wm_lake_edge *l = &probe->s->edges[probe->ledge[i].e];
        const int64_t ax = l->ax - probe->X0, ay = l->ay - probe->Y0;
        const int64_t bx = l->bx - probe->X0, by = l->by - probe->Y0;
        if ((ax < 0 && bx < 0) || (ay < 0 && by < 0) || (ax > hi && bx > hi) ||
            (ay > hi && by > hi))
            continue;
        const int swap = ax > bx || (ax == bx && ay > by);
        g[k++] = swap ? (lake_seg){bx, by, ax, ay} : (lake_seg){ax, ay, bx, by};
    }
    if (k > 1)
        qsort(g, k, sizeof *g, cmp_lake_seg);
    size_t m = k ? 1 : 0;
    for (size_t i = 1; i < k; i++)
        if (cmp_lake_seg(&g[i], &g[m - 1]) != 0)
            g[m++] = g[i];
    *out = g;
    *n = m;
    return 1;
}

/* Fills m with the sample edges of the block's mixed tiles that the lake
 * edges in reach meet, each edge once. Returns 0 when out of memory. */
static int lake_twice(lake_meets *m, const wm_field *f, const wm_probe *probe)
{
    memset(m, 0, sizeof *m);
    m->f = f;
    if (probe->nledge == 0 || f->mixed == 0)
        return 1;
    lake_seg *g;
    size_t n;
    m->slot = calloc((size_t)f->ntx * (size_t)f->nty, sizeof *m->slot);
    if (!m->slot || !lake_segs(f, probe, &g, &n))
        return 0;
    int ok = 1;
    for (size_t i = 0; ok && i < n; i++)
        ok = lake_edge_lines(m, g[i].y0, g[i].x0, g[i].y1, g[i].x1, 0) &&
             lake_edge_lines(m, g[i].x0, g[i].y0, g[i].x1, g[i].y1, 1);
    free(g);
    return ok;
}

static void lake_meets_free(lake_meets *m)
{
    free(m->slot);
    free(m->s);
}

/* Tile t's rows of sample edges along x and y that lake edges cross twice,
 * or NULL. */
static const uint64_t (*tile_twice(const lake_meets *m, size_t t))[WM_TILE + 1]
{
    return m->slot && m->slot[t]
               ? (const uint64_t(*)[WM_TILE + 1]) m->s[m->slot[t] - 1].twice
               : NULL;
}

/* A mixed tile being screened: its values, first cell and end (exclusive,
 * clamped to the block's n cells). */
typedef struct
{
    const float *v;
    const uint64_t *bits; /* its rows' water and near bits (wm_field.bits) */
    int32_t c0, r0, c1, r1, n;
    double rmin; /* least capsule radius in reach, pixels, lakes' 0 (< 0:
                    not yet) */
    double rriv; /* least river capsule radius in reach, pixels (< 0: not
                    yet) */
    const uint64_t (*twice)[WM_TILE + 1]; /* per row, the edges along x and
                    y that lake edges cross twice (lake_twice), or NULL */
} tile;

/* Edge from sample (c0 + q, r) of T along x or y. */
static edge_view view_of(const tile *T, int32_t q, int32_t r, int vertical)
{
    const ptrdiff_t W = WM_TILE + 1;
    const int32_t cw = T->c1 - T->c0;
    if (vertical)
        return (edge_view){T->v + (ptrdiff_t)(r - T->r0) * W + q,
                           W,
                           1,
                           r > T->r0,
                           r + 2 <= T->r1,
                           q,
                           cw - q};
    return (edge_view){T->v + (ptrdiff_t)(r - T->r0) * W + q,
                       1,
                       W,
                       q > 0,
                       q + 2 <= cw,
                       r - T->r0,
                       T->r1 - r};
}

/* Whether the land edge e of tile T may hold water (capsule_may_cross
 * with the least radius of the rivers in reach of T). */
static int land_may_cross(const wm_probe *probe, tile *T, const edge_view *e)
{
    /* a capsule meeting the tile's last row or column comes within reach
     * of the point a unit before it: the tile's own index cells do */
    if (T->rmin < 0)
        T->rmin = wm_probe_min_radius(probe, T->c0 * WM_Q, T->r0 * WM_Q,
                                      T->c1 * WM_Q - 1, T->r1 * WM_Q - 1, 1) /
                  WM_Q;
    return capsule_may_cross(e->a[0], e->a[e->along], T->rmin);
}

/* Whether the edge e of tile T, whose samples differ in class, may hold
 * three crossings by a river (hide_reach with the least river radius in
 * reach of T, against the water end's ball, then the feasible part). */
static int river_may_hide(const wm_probe *probe, tile *T, const edge_view *e)
{
    const int aw = e->a[0] <= 0; /* the water end is a */
    const float vw = fabsf(aw ? e->a[0] : e->a[e->along]);
    const float vl = fabsf(aw ? e->a[e->along] : e->a[0]);
    const int past = aw ? e->after : e->before; /* the tile holds it */
    const float v2 = !past ? 0 : aw ? e->a[2 * e->along] : e->a[-e->along];
    if (T->rriv < 0)
        T->rriv = wm_probe_min_radius(probe, T->c0 * WM_Q, T->r0 * WM_Q,
                                      T->c1 * WM_Q - 1, T->r1 * WM_Q - 1, 0) /
                  WM_Q;
    const double reach = hide_reach(vl, v2, T->rriv);
    if (vw - 0.001 >= reach)
        return 0;
    float L, U;
    feasible_near(e, &L, &U);
    feasible_far(e, &L, &U);
    return (aw ? L : 1.0f - U) - 0.001 < reach;
}

/* Screens the edges of row r of T at the columns set in m (both samples
 * near): along x or y, whose samples are of one class (kind 0: searched
 * when they cannot decide, and for land when a capsule may cross them) or
 * differ (kind 1: searched when loose, when a river may cross it twice or
 * lake edges cross it twice, and always on the block square, so that the
 * two blocks sharing it take the same crossing). The sum of the two values
 * rules most out before the feet beside are read. */
static int screen(wm_hidden *h, const wm_field *f, wm_probe *probe, tile *T,
                  int32_t r, uint64_t m, int vertical, int kind)
{
    const uint64_t twice = T->twice ? T->twice[vertical][r - T->r0] : 0;
    const float *row = T->v + (ptrdiff_t)(r - T->r0) * (WM_TILE + 1);
    const ptrdiff_t along = vertical ? WM_TILE + 1 : 1;
    while (m)
    {
        const int32_t q = __builtin_ctzll(m);
        m &= m - 1;
        const int32_t c = T->c0 + q;
        const float sum = fabsf(row[q]) + fabsf(row[q + along]);
        if (kind == 0)
        {
            if (sum > 1.0f)
                continue;
            const edge_view e = view_of(T, q, r, vertical);
            if (undecided(&e) &&
                (e.a[0] <= 0 || land_may_cross(probe, T, &e)) &&
                !search_edge(h, f, probe, c, r, vertical, e.a[0] <= 0))
                return 0;
            continue;
        }
        const int sq = vertical ? c == 0 || c == T->n : r == 0 || r == T->n;
        const edge_view e = view_of(T, q, r, vertical);
        if (!sq && !(twice >> q & 1) && !(sum < 1.0f - LOOSE && loose(&e)) &&
            !river_may_hide(probe, T, &e))
            continue;
        if (!loose_edge(h, f, probe, c, r, vertical))
            return 0;
    }
    return 1;
}

/* Screens mixed tile T: per row, the edges both of whose samples lie
 * within a pixel of the boundary (those of one class that cannot decide,
 * those of two that are loose) and the saddle cells (corners alternate:
 * which diagonal the boundary separates is an exact question). */
static int screen_tile(wm_hidden *h, const wm_field *f, wm_probe *probe,
                       tile *T)
{
    /* a tile screens its edges but those of its top row and right column,
     * which the tile beyond screens (it is mixed too: an edge within a
     * pixel of the boundary has no sample at the clamp band), or which lie
     * on the block square */
    const int32_t re = T->r1 == T->n ? T->r1 : T->r1 - 1;
    const int32_t ce = T->c1 == T->n ? T->c1 : T->c1 - 1;
    const uint64_t hcols = (UINT64_C(1) << (T->c1 - T->c0)) - 1;
    const uint64_t vcols = (UINT64_C(1) << (ce - T->c0 + 1)) - 1;
    for (int32_t r = T->r0; r <= re; r++)
    {
        const int up = r < T->r1;
        const uint64_t *cur = T->bits + 2 * (r - T->r0); /* water, near */
        const uint64_t above[2] = {up ? cur[2] : 0, up ? cur[3] : 0};
        /* horizontal edges of row r, vertical ones up from it, both of
         * whose samples are near */
        const uint64_t hn = cur[1] & (cur[1] >> 1) & hcols;
        const uint64_t hx = cur[0] ^ (cur[0] >> 1);
        const uint64_t vn = cur[1] & above[1] & vcols;
        const uint64_t vx = cur[0] ^ above[0];
        const uint64_t saddle = up ? hx & ~(cur[0] ^ (above[0] >> 1)) &
                                         ~((cur[0] >> 1) ^ above[0]) & hcols
                                   : 0;
        /* same class (kind 0) and differing (kind 1), along x and y */
        const uint64_t edges[4] = {hn & ~hx, vn & ~vx, hn & hx, vn & vx};
        for (int k = 0; (hn | vn) && k < 4; k++)
            if (edges[k] && !screen(h, f, probe, T, r, edges[k], k & 1, k >> 1))
                return 0;
        for (uint64_t m = saddle; m; m &= m - 1)
            if (!add_cell(h, f, T->c0 + __builtin_ctzll(m), r))
                return 0;
    }
    return 1;
}

wm_status wm_hidden_find(const wm_field *f, wm_probe *probe, wm_hidden *h,
                         const wm_ctx *ctx)
{
    const int32_t n = f->w - 1;
    memset(h, 0, sizeof *h);
    lake_meets lm;
    if (!lake_twice(&lm, f, probe))
    {
        lake_meets_free(&lm);
        goto nomem;
    }
    for (size_t k = 0; k < f->mixed; k++)
    {
        const size_t t = f->mixed_tile[k];
        const int32_t c0 = (int32_t)(t % (size_t)f->ntx) * WM_TILE;
        const int32_t r0 = (int32_t)(t / (size_t)f->ntx) * WM_TILE;
        tile T = {f->val[t],
                  wm_field_bits(f, k),
                  c0,
                  r0,
                  c0 + WM_TILE < n ? c0 + WM_TILE : n,
                  r0 + WM_TILE < n ? r0 + WM_TILE : n,
                  n,
                  -1,
                  -1,
                  tile_twice(&lm, t)};
        if (wm_cancelled(ctx))
        {
            lake_meets_free(&lm);
            wm_hidden_free(h);
            return wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
        }
        wm_field_prefetch_tile(f, k + 1);
        if (!screen_tile(h, f, probe, &T))
        {
            lake_meets_free(&lm);
            goto nomem;
        }
    }
    lake_meets_free(&lm);
    const wm_status st = wm_corners_find(probe, f, ctx);
    if (st != WM_OK)
    {
        wm_hidden_free(h);
        return st;
    }
    if (!add_seeds(h, f, probe) || !exact_sides(h, f, probe))
        goto nomem;
    if (wm_cancelled(ctx))
    {
        wm_hidden_free(h);
        return wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
    }
    if (h->ncell == 0 && h->nedge == 0)
        return WM_OK; /* nothing hidden */
    if (h->nedge > 1)
        qsort(h->edge, h->nedge, sizeof *h->edge, cmp_edge);
    if (h->ncell > 1)
        qsort(h->cell, h->ncell, sizeof *h->cell, cmp_u64);
    if (!steer_seeds(h, f, probe) || !sort_seeds(h) || !link_cells(h, f))
        goto nomem;
    return WM_OK;
nomem:
    wm_hidden_free(h);
    return wm_fail(ctx, WM_ERR_NOMEM, "out of memory finding hidden crossings");
}

void wm_hidden_free(wm_hidden *h)
{
    if (!h)
        return;
    free(h->edge);
    free(h->off);
    free(h->cell);
    free(h->link);
    free(h->seed);
    free(h->seedcell);
    memset(h, 0, sizeof *h);
}

/* The hidden edge with this id, or NULL. */
static const wm_hidden_edge *find_edge(const wm_hidden *h, uint64_t id)
{
    size_t lo = 0, hi = h->nedge;
    while (lo < hi)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (h->edge[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < h->nedge && h->edge[lo].id == id ? &h->edge[lo] : NULL;
}

int wm_hidden_is_cell(const wm_hidden *h, const wm_field *f, int32_t c,
                      int32_t r)
{
    const int32_t n = f->w - 1;
    if (h->ncell == 0 || c < 0 || r < 0 || c >= n || r >= n)
        return 0;
    const uint64_t key = wm_field_cell_key(f, c, r);
    const size_t lo = wm_lower_u64(h->cell, h->ncell, key);
    return lo < h->ncell && h->cell[lo] == key;
}

int wm_hidden_side_crossing(const wm_hidden *h, const wm_field *f, int32_t c,
                            int32_t r, int side, wm_pt *p)
{
    const int vertical = side == 1 || side == 3;
    const int32_t sc = side == 1 ? c + 1 : c, sr = side == 2 ? r + 1 : r;
    const wm_hidden_edge *e = find_edge(h, edge_id(f->w - 1, sc, sr, vertical));
    if (!e || e->n != 1)
        return 0;
    *p = (wm_pt){sc * WM_Q, sr * WM_Q};
    if (vertical)
        p->y += h->off[e->first];
    else
        p->x += h->off[e->first];
    return 1;
}

/* ---- subdivision of an ambiguous cell ---------------------------------- */

/* A rectangle of the subdivision: corners CCW from (x0, y0), their classes
 * (1: water), and the crossings of each side as ascending coordinates
 * (x for the bottom and top sides, y for the right and left ones). */
enum
{
    SB = 0,
    SR = 1,
    ST = 2,
    SL = 3
};

typedef struct
{
    int32_t x0, y0, x1, y1;
    int cls[4];
    const int32_t *side[4];
    int ns[4];
    const wm_pt *seed; /* seeds of small inputs in the cell (some may be
                          outside this rectangle) */
    size_t nseed;
} rect;

typedef struct
{
    wm_probe *probe;
    wm_segment_fn emit;
    void *user;
} walker;

/* A crossing of a rectangle's boundary, in counter-clockwise order. */
typedef struct
{
    wm_pt p;
    int side;
    int out; /* water before it, walking counter-clockwise */
} xing;

/* The crossings of q counter-clockwise from (x0, y0); returns how many. */
static int boundary(const rect *q, xing *x)
{
    int k = 0, cls = q->cls[0];
    for (int s = 0; s < 4; s++)
    {
        const int n = q->ns[s];
        for (int i = 0; i < n; i++)
        {
            /* bottom and right ascend, top and left descend */
            const int32_t v = q->side[s][s < 2 ? i : n - 1 - i];
            wm_pt p = s == SB   ? (wm_pt){v, q->y0}
                      : s == SR ? (wm_pt){q->x1, v}
                      : s == ST ? (wm_pt){v, q->y1}
                                : (wm_pt){q->x0, v};
            x[k++] = (xing){p, s, cls};
            cls = !cls;
        }
    }
    return k;
}

/* Class at coordinate v of side s of q (v strictly inside the side). */
static int class_at(const rect *q, int s, int32_t v)
{
    /* sides ascend from corner 0 (bottom, left) or 1 (right) or 3 (top) */
    static const int from[4] = {0, 1, 3, 0};
    int cls = q->cls[from[s]];
    for (int i = 0; i < q->ns[s] && q->side[s][i] < v; i++)
        cls = !cls;
    return cls;
}

/* Whether position v is a crossing of side s. */
static int taken(const rect *q, int s, int32_t v)
{
    for (int i = 0; i < q->ns[s]; i++)
        if (q->side[s][i] == v)
            return 1;
    return 0;
}

/* Whether a seed lies on side s of q at position v: a lake's vertex on a
 * sample row or column, say, whose water touches the side there though the
 * side holds no crossing (two coincide at a touching point, and cancel). */
static int seed_on(const rect *q, int s, int32_t v)
{
    for (size_t i = 0; i < q->nseed; i++)
    {
        const wm_pt p = q->seed[i];
        if (s == SB || s == ST ? p.x == v && p.y == (s == SB ? q->y0 : q->y1)
                               : p.y == v && p.x == (s == SL ? q->x0 : q->x1))
            return 1;
    }
    return 0;
}

/* Whether a seed lies strictly inside q on the dividing line x = at
 * (vertical) or y = at with none of its n crossings mid[] (coordinates)
 * within a unit of it: a corner the line only touches (an island's vertex),
 * left on a side of both parts where neither part's boundary passes
 * through it (an island 3.8 units wide among three rivers and two lake
 * pieces was cut into two halves too thin to keep: mosaic seed 139300 at
 * 0.6 m). A line through a corner that the boundary crosses there puts a
 * crossing on it, the corner's own. */
static int seed_touched(const rect *q, int vertical, int32_t at,
                        const int32_t *mid, int n)
{
    for (size_t i = 0; i < q->nseed; i++)
    {
        const wm_pt p = q->seed[i];
        if (vertical ? !(p.x == at && p.y > q->y0 && p.y < q->y1)
                     : !(p.y == at && p.x > q->x0 && p.x < q->x1))
            continue;
        const int32_t u = vertical ? p.y : p.x;
        int crossed = 0;
        for (int j = 0; j < n && !crossed; j++)
            crossed = mid[j] >= u - 1 && mid[j] <= u + 1;
        if (!crossed)
            return 1;
    }
    return 0;
}

/* A split position in [lo + 3, hi - 3] but skip, nearest the middle, on
 * no crossing and no seed of sides a and b; or -1. Parts at least 3 units wide:
 * a part's side then holds two crossings, those of a strip one unit wide. A
 * dividing segment's end classes are those of the sides at its ends, which
 * at a crossing, or at a seed where water touches a side, are not its
 * ends' classes (a lake 0.18 pixel wide touching a cell's side at its
 * vertex vanished so). */
static int32_t split_at(const rect *q, int32_t lo, int32_t hi, int a, int b,
                        int32_t skip)
{
    const int32_t mid = lo + (hi - lo) / 2;
    for (int32_t d = 0; mid - d >= lo + 3 || mid + d <= hi - 3; d++)
        for (int sgn = 0; sgn < 2; sgn++)
        {
            const int32_t v = sgn ? mid + d : mid - d;
            if (v < lo + 3 || v > hi - 3)
                continue;
            if (v != skip && !taken(q, a, v) && !taken(q, b, v) &&
                !seed_on(q, a, v) && !seed_on(q, b, v))
                return v;
        }
    return -1;
}

/* The crossings of side s of q strictly between lo and hi. */
static void sub_side(const rect *q, int s, int32_t lo, int32_t hi,
                     const int32_t **p, int *n)
{
    int i = 0;
    while (i < q->ns[s] && q->side[s][i] <= lo)
        i++;
    int j = i;
    while (j < q->ns[s] && q->side[s][j] < hi)
        j++;
    *p = q->side[s] + i;
    *n = j - i;
}

static int run_rect(walker *w, const rect *q, int depth);

/* The point one unit inside side s of q, midway between crossings a and b
 * of that side: where the path joining them turns. */
static wm_pt detour(const rect *q, const xing *a, const xing *b)
{
    wm_pt m = {(int32_t)(((int64_t)a->p.x + b->p.x) / 2),
               (int32_t)(((int64_t)a->p.y + b->p.y) / 2)};
    switch (a->side)
    {
    case SB:
        m.y = q->y0 + 1;
        break;
    case SR:
        m.x = q->x1 - 1;
        break;
    case ST:
        m.y = q->y1 - 1;
        break;
    default:
        m.x = q->x0 + 1;
        break;
    }
    return m;
}

/* Emits a -> b, or a -> detour() -> b when both are on one side of q (the
 * segment would run along the side). */
static int emit_pair(walker *w, const rect *q, const xing *a, const xing *b)
{
    if (a->side != b->side)
        return w->emit(w->user, a->p, b->p);
    const wm_pt m = detour(q, a, b);
    return w->emit(w->user, a->p, m) && w->emit(w->user, m, b->p);
}

/* Emits each out crossing of x[0 .. k) with the next one counter-clockwise
 * (joined) or the previous one. */
static int pair_all(walker *w, const rect *q, const xing *x, int k, int joined)
{
    for (int i = 0; i < k; i++)
        if (x[i].out)
        {
            const int m = joined ? (i + 1) % k : (i + k - 1) % k;
            if (!emit_pair(w, q, &x[i], &x[m]))
                return 0;
        }
    return 1;
}

/* The position of crossing p of side `side` along q's boundary,
 * counter-clockwise from (x0, y0). */
static int64_t along(const rect *q, wm_pt p, int side)
{
    const int64_t W = q->x1 - q->x0, H = q->y1 - q->y0;
    switch (side)
    {
    case SB:
        return p.x - q->x0;
    case SR:
        return W + (p.y - q->y0);
    case ST:
        return W + H + (q->x1 - p.x);
    default:
        return 2 * W + H + (q->y1 - p.y);
    }
}

/* Pairs on one side in pairing `mate`. */
static int same_side_pairs(const xing *x, const int *mate, int k)
{
    int n = 0;
    for (int i = 0; i < k; i++)
        n += i < mate[i] && x[i].side == x[mate[i]].side;
    return n;
}

/* Emits the boundary from a to b, two crossings of one side of leaf q
 * that the boundary enters and leaves it by, through the corners of the
 * union seeded strictly inside q (a wedge's tip, the corners of an island
 * the side cuts) in their order around the point between a and b; through
 * detour() when there is none. The boundary there is one path (no other
 * crossing), so the corners on the boundary inside q are its own. */
static int through_corners(walker *w, const rect *q, const xing *a,
                           const xing *b)
{
    enum
    {
        MAXC = 8
    };
    wm_pt c[MAXC];
    double th[MAXC];
    int n = 0;
    const double mx = (a->p.x + (double)b->p.x) / 2,
                 my = (a->p.y + (double)b->p.y) / 2;
    /* a at angle 0, b at pi, the inside of q between */
    const double ux = a->p.x - mx, uy = a->p.y - my;
    const double vx = a->side == SR ? -1 : a->side == SL ? 1 : 0;
    const double vy = a->side == ST ? -1 : a->side == SB ? 1 : 0;
    for (size_t i = 0; i < q->nseed; i++)
    {
        const wm_pt p = q->seed[i];
        if (p.x <= q->x0 || p.x >= q->x1 || p.y <= q->y0 || p.y >= q->y1)
            continue;
        int dup = 0;
        for (int j = 0; j < n && !dup; j++)
            dup = c[j].x == p.x && c[j].y == p.y;
        if (dup || fabs(wm_probe_distance(w->probe, p.x, p.y, 2.0)) > 1.0)
            continue;
        if (n == MAXC)
            return emit_pair(w, q, a, b);
        const double dx = p.x - mx, dy = p.y - my;
        c[n] = p;
        th[n] = atan2(dx * vx + dy * vy, dx * ux + dy * uy);
        n++;
    }
    if (n == 0)
        return emit_pair(w, q, a, b);
    for (int i = 1; i < n; i++) /* by angle */
        for (int j = i; j > 0 && th[j - 1] > th[j]; j--)
        {
            const wm_pt tp = c[j];
            c[j] = c[j - 1];
            c[j - 1] = tp;
            const double tt = th[j];
            th[j] = th[j - 1];
            th[j - 1] = tt;
        }
    wm_pt from = a->p;
    for (int i = 0; i < n; i++)
    {
        if (!w->emit(w->user, from, c[i]))
            return 0;
        from = c[i];
    }
    return w->emit(w->user, from, b->p);
}

/* Whether the paths of pairing `mate` of leaf q's k crossings x meet
 * nowhere (exact); the pair of out crossing i, when on one side, turns at
 * d[i]. */
static int paths_apart(const xing *x, int k, const int *mate, const wm_pt *d)
{
    wm_pt seg[2 * WM_LEAF_ARCS * 2][2];
    int path[2 * WM_LEAF_ARCS * 2], n = 0;
    for (int i = 0; i < k; i++)
        if (x[i].out)
        {
            const wm_pt a = x[i].p, b = x[mate[i]].p;
            if (x[i].side == x[mate[i]].side)
            {
                seg[n][0] = a, seg[n][1] = d[i], path[n++] = i;
                seg[n][0] = d[i], seg[n][1] = b, path[n++] = i;
            }
            else
                seg[n][0] = a, seg[n][1] = b, path[n++] = i;
        }
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            if (path[i] != path[j] &&
                wm_segments_meet(seg[i][0], seg[i][1], seg[j][0], seg[j][1]))
                return 0;
    return 1;
}

/* Where the pair a -> b on one side of q may turn, choice t of three: one
 * unit inside the side across from its middle, from a, from b. */
static wm_pt turn_of(const rect *q, const xing *a, const xing *b, int t)
{
    return t == 0   ? detour(q, a, b)
           : t == 1 ? detour(q, a, a)
                    : detour(q, b, b);
}

/* Most pairs on one side draw_pairs() places (3^SAME_PAIRS tries). */
#define SAME_PAIRS 4

/* Emits pairing `mate` of leaf q's k crossings x, of which at most
 * SAME_PAIRS pairs lie on one side (a land wedge entering the leaf from
 * its bottom and one from its top, their water joined between the tips:
 * cluster seed 154495 at 2 m; three land bumps around a pinch point of
 * three lakes). Such a pair turns one unit inside its side, at the first
 * of three places (across from its middle, from its out crossing, from
 * its other crossing), the pairs' places tried together, where no two
 * paths then meet (a path nesting it may leave the side at a slant,
 * passing under the middle's turn: crossings a unit apart, mosaic seed
 * 141419 at 2.5 m). Returns 1, 0 when out of memory, -1 when no places
 * do. */
static int draw_pairs(walker *w, const rect *q, const xing *x, int k,
                      const int *mate)
{
    int s[SAME_PAIRS], m = 0; /* the out crossings of the pairs on one side */
    int tries = 1;
    for (int i = 0; i < k; i++)
        if (x[i].out && x[i].side == x[mate[i]].side)
        {
            if (m == SAME_PAIRS)
                return -1;
            s[m++] = i;
            tries *= 3;
        }
    wm_pt d[2 * WM_LEAF_ARCS];
    for (int t = 0; t < tries; t++)
    {
        for (int j = 0, u = t; j < m; j++, u /= 3)
            d[s[j]] = turn_of(q, &x[s[j]], &x[mate[s[j]]], u % 3);
        if (!paths_apart(x, k, mate, d))
            continue;
        for (int i = 0; i < k; i++)
        {
            if (!x[i].out)
                continue;
            const wm_pt a = x[i].p, b = x[mate[i]].p;
            if (x[i].side != x[mate[i]].side
                    ? !w->emit(w->user, a, b)
                    : !w->emit(w->user, a, d[i]) || !w->emit(w->user, d[i], b))
                return 0;
        }
        return 1;
    }
    return -1;
}

/* Pairs leaf q's k crossings x as the union joins its water arcs inside
 * it (wm_leaf_join): each arc's last crossing with the first of the next
 * arc of its component, counter-clockwise. Returns 1 when done, 0 when
 * out of memory, -1 when the inputs there are beyond that reading, or
 * their pairing is one the paths cannot draw (crossing pairs, more than
 * two pairs on one side each, or paths that would meet: draw_pairs()). */
static int pair_exact(walker *w, const rect *q, const xing *x, int k)
{
    if (k > 2 * WM_LEAF_ARCS)
        return -1;
    const int64_t per = 2 * ((int64_t)(q->x1 - q->x0) + (q->y1 - q->y0));
    int64_t arc[2 * WM_LEAF_ARCS] = {0};
    int from[WM_LEAF_ARCS] = {0}, label[WM_LEAF_ARCS] = {0}, n = 0;
    for (int i = 0; i < k; i++)
        if (x[(i + 1) % k].out) /* water from crossing i to i + 1 */
        {
            const int64_t a = along(q, x[i].p, x[i].side);
            const int64_t b = along(q, x[(i + 1) % k].p, x[(i + 1) % k].side);
            arc[2 * n] = a;
            arc[2 * n + 1] = b > a ? b : b + per;
            from[n++] = i;
        }
    const int got =
        wm_leaf_join(w->probe, q->x0, q->y0, q->x1, q->y1, n, arc, label);
    if (got <= 0)
        return got < 0 ? 0 : -1;
    /* components that interleave give crossing pairs, whose paths meet:
     * draw_pairs() declines them */
    int mate[2 * WM_LEAF_ARCS] = {0};
    for (int a = 0; a < n; a++)
    {
        int b = (a + 1) % n;
        while (label[b] != label[a])
            b = (b + 1) % n;
        const int out = (from[a] + 1) % k; /* arc a's last crossing */
        mate[out] = from[b];
        mate[from[b]] = out;
    }
    return draw_pairs(w, q, x, k, mate);
}

/* mate[]: each out crossing of x[0 .. k) with the next one
 * counter-clockwise (joined) or the previous one, as pair_all() pairs
 * them. */
static void adjacent_mates(const xing *x, int k, int joined, int *mate)
{
    for (int i = 0; i < k; i++)
        if (x[i].out)
        {
            mate[i] = joined ? (i + 1) % k : (i + k - 1) % k;
            mate[mate[i]] = i;
        }
}

/* Whether pairing `mate` drawn as emit_pair() draws it (a pair on one side
 * turning across from its middle) has paths that meet nowhere. */
static int midway_apart(const rect *q, const xing *x, int k, const int *mate)
{
    wm_pt d[2 * WM_LEAF_ARCS];
    for (int i = 0; i < k; i++)
        if (x[i].out)
            d[i] = detour(q, &x[i], &x[mate[i]]);
    return paths_apart(x, k, mate, d);
}

/* Pairs the crossings of a rectangle too small to divide. Two on one side
 * are one path into the leaf and out, through the corners inside it
 * (through_corners()). More on one side: each with the next or previous
 * one, so that no pair wraps around the rectangle (the wrapping pair's
 * path, drawn one unit inside the side as emit_pair() draws it, would
 * cross the others'). Else as the union joins the water arcs inside the
 * leaf (pair_exact()); where the inputs there are beyond that reading,
 * each out crossing with the next in one counter-clockwise (the water
 * corners joined) or the previous (separated), the pairing with fewer
 * pairs on one side winning, the class of the centre deciding a tie (its
 * pair on one side turning where the paths meet nowhere, draw_pairs(),
 * when there is such a place); where its paths would meet, the other
 * pairing, when its paths meet nowhere. */
static int pair_leaf(walker *w, const rect *q, const xing *x, int k)
{
    int one_side = 1;
    for (int i = 1; i < k; i++)
        one_side &= x[i].side == x[0].side;
    if (one_side && k == 2)
        return x[0].out ? through_corners(w, q, &x[0], &x[1])
                        : through_corners(w, q, &x[1], &x[0]);
    if (one_side)
        return pair_all(w, q, x, k, !x[k - 1].out);
    const int exact = pair_exact(w, q, x, k);
    if (exact >= 0)
        return exact;
    int same[2] = {0, 0};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < k; i++)
            if (x[i].out)
            {
                const int m = j ? (i + k - 1) % k : (i + 1) % k;
                same[j] += x[i].side == x[m].side;
            }
    int joined;
    if (same[0] != same[1])
        joined = same[0] < same[1];
    else
        joined = wm_probe_distance(w->probe, (q->x0 + q->x1) / 2.0,
                                   (q->y0 + q->y1) / 2.0, WM_PROBE_REACH) <= 0;
    if (k > 2 * WM_LEAF_ARCS)
        return pair_all(w, q, x, k, joined);
    int mate[2 * WM_LEAF_ARCS];
    adjacent_mates(x, k, joined, mate);
    if (same_side_pairs(x, mate, k) <= 1)
    {
        const int drawn = draw_pairs(w, q, x, k, mate);
        if (drawn >= 0)
            return drawn;
    }
    else if (midway_apart(q, x, k, mate))
        return pair_all(w, q, x, k, joined);
    /* its paths would meet: the other pairing, where it draws apart (a
     * pinch point of three lakes' pieces, one land bump of a unit left
     * under the other pairing's chord) */
    adjacent_mates(x, k, !joined, mate);
    const int drawn = draw_pairs(w, q, x, k, mate);
    if (drawn >= 0)
        return drawn;
    return pair_all(w, q, x, k, joined);
}

/* Crossings of the dividing segment from P (length L, along x or y) with
 * end classes cls0 and *cls1 (< 0: found), into buf. */
static int divide(walker *w, wm_pt P, int vertical, int32_t L, int cls0,
                  int *cls1, int32_t *buf)
{
    const int k =
        wm_probe_crossings(w->probe, P, vertical, L, cls0, cls1, buf, MAXCROSS);
    if (k < 0)
        return -1;
    for (int i = 0; i < k; i++)
        buf[i] += vertical ? P.y : P.x; /* offsets to coordinates */
    return k;
}

/* Splits q in two at x = at (vertical != 0) or y = at, along one
 * dividing segment whose crossings are found exactly (its end classes are
 * those of the sides it starts and ends on), and runs both parts; with
 * retry, returns -2 instead where the segment only touches a seed
 * (seed_touched()), for another position to be tried. */
static int split(walker *w, const rect *q, int vertical, int32_t at, int depth,
                 int retry)
{
    int32_t *mid = malloc(MAXCROSS * sizeof *mid);
    if (!mid)
        return 0;
    /* by vertical, then part k (0: left of x = at or below y = at, 1:
     * right of it or above): the sides the dividing segment starts and
     * ends on, which it cuts; the corners of part k at its ends; the side
     * of part k it becomes */
    static const int cut[2][2] = {{SL, SR}, {SB, ST}};
    static const int ends[2][2][2] = {{{3, 2}, {0, 1}}, {{1, 2}, {0, 3}}};
    static const int made[2][2] = {{ST, SB}, {SR, SL}};
    const int v = vertical != 0;
    const int c0 = class_at(q, cut[v][0], at);
    int c1 = class_at(q, cut[v][1], at);
    const wm_pt P = v ? (wm_pt){at, q->y0} : (wm_pt){q->x0, at};
    const int n =
        divide(w, P, v, v ? q->y1 - q->y0 : q->x1 - q->x0, c0, &c1, mid);
    if (n >= 0 && retry && seed_touched(q, v, at, mid, n))
    {
        free(mid);
        return -2;
    }
    int ok = n >= 0;
    rect part[2];
    for (int k = 0; k < 2 && ok; k++)
    {
        rect *a = &part[k];
        *a = *q;
        int32_t *lo = v ? &a->x0 : &a->y0, *hi = v ? &a->x1 : &a->y1;
        const int32_t from = *lo, to = *hi;
        *(k ? lo : hi) = at;
        a->cls[ends[v][k][0]] = c0;
        a->cls[ends[v][k][1]] = c1;
        for (int j = 0; j < 2; j++)
            sub_side(q, cut[v][j], k ? at : from, k ? to : at,
                     &a->side[cut[v][j]], &a->ns[cut[v][j]]);
        a->side[made[v][k]] = mid;
        a->ns[made[v][k]] = n;
        ok = run_rect(w, a, depth + 1);
    }
    free(mid);
    return ok;
}

/* Divides q across its longer side (where a position is free of
 * crossings, the parts at least 3 units wide; once elsewhere when the
 * first position only touches a seed) and runs the parts; returns 1, 0
 * when out of memory, or -1 when q cannot be divided. */
static int divide_rect(walker *w, const rect *q, int depth)
{
    if (depth >= MAXDEPTH)
        return -1;
    int32_t skip[2] = {-1, -1};
    for (int retry = 1;; retry = 0)
    {
        const int32_t sx = q->x1 - q->x0 >= 6
                               ? split_at(q, q->x0, q->x1, SB, ST, skip[1])
                               : -1;
        const int32_t sy = q->y1 - q->y0 >= 6
                               ? split_at(q, q->y0, q->y1, SL, SR, skip[0])
                               : -1;
        if (sx < 0 && sy < 0)
            return -1;
        const int vertical =
            sx > 0 && (sy < 0 || q->x1 - q->x0 >= q->y1 - q->y0);
        const int32_t at = vertical ? sx : sy;
        const int ok = split(w, q, vertical, at, depth, retry);
        if (ok != -2)
            return ok;
        skip[vertical] = at; /* once: a seed the line only touches */
    }
}

/* Whether a seed lies in q (sides included). */
static int has_seed(const rect *q)
{
    for (size_t i = 0; i < q->nseed; i++)
        if (q->seed[i].x >= q->x0 && q->seed[i].x <= q->x1 &&
            q->seed[i].y >= q->y0 && q->seed[i].y <= q->y1)
            return 1;
    return 0;
}

/* ---- a lake's ring inside one leaf ------------------------------------ */

/* Most vertices of a ring lone_rings() reads: one strictly inside a leaf
 * (under 6 units wide) has at most 25 distinct lattice points. */
#define LONE_MAX 32

/* The ring of scene polygon P through edge e0 (its vertices from its
 * first edge's, block-local, into v; how many, or 0 when it has more than
 * LONE_MAX edges or does not lie strictly inside q). A ring's edges are
 * consecutive in P, each starting where the one before ends. */
static int ring_from(const wm_probe *in, uint32_t P, size_t e0, const rect *q,
                     wm_pt *v)
{
    const wm_scene *s = in->s;
    const size_t begin = s->poly_start[P], end = s->poly_start[P + 1];
    size_t first = e0;
    while (first > begin && e0 - first < LONE_MAX &&
           s->edges[first - 1].bx == s->edges[first].ax &&
           s->edges[first - 1].by == s->edges[first].ay)
        first--;
    int n = 0;
    for (size_t e = first; e < end && n < LONE_MAX; e++)
    {
        const wm_lake_edge *g = &s->edges[e];
        if (e > first &&
            (g->ax != s->edges[e - 1].bx || g->ay != s->edges[e - 1].by))
            return 0; /* a new ring before this one closed */
        const int64_t x = g->ax - in->X0, y = g->ay - in->Y0;
        if (x <= q->x0 || x >= q->x1 || y <= q->y0 || y >= q->y1)
            return 0;
        v[n++] = (wm_pt){(int32_t)x, (int32_t)y};
        if (g->bx == s->edges[first].ax && g->by == s->edges[first].ay)
            return n;
    }
    return 0;
}

/* Whether ring v (n points) is simple: no two edges meet but consecutive
 * ones at their vertex. */
static int ring_simple(const wm_pt *v, int n)
{
    if (n < 3)
        return 0;
    for (int a = 0; a < n; a++)
        for (int b = a + 1; b < n; b++)
        {
            if (b == a + 1 || (a == 0 && b == n - 1))
            {
                if (v[a].x == v[b].x && v[a].y == v[b].y)
                    return 0; /* a repeated vertex */
                continue;
            }
            if (wm_segments_meet(v[a], v[(a + 1) % n], v[b], v[(b + 1) % n]))
                return 0;
        }
    return 1;
}

/* A point strictly inside simple ring v (n points, area2 > 0 when
 * counter-clockwise): the centroid of an ear, a convex vertex whose
 * triangle holds no other vertex. */
static int ring_inner_point(const wm_pt *v, int n, wm_i128 area2, double *x,
                            double *y)
{
    const int turn = area2 > 0 ? 1 : -1;
    for (int i = 0; i < n; i++)
    {
        const wm_pt a = v[(i + n - 1) % n], b = v[i], c = v[(i + 1) % n];
        if (wm_orient(a, b, c) != turn)
            continue;
        int empty = 1;
        for (int j = 0; j < n && empty; j++)
        {
            const wm_pt p = v[j];
            if (j == i || j == (i + 1) % n || j == (i + n - 1) % n)
                continue;
            empty =
                !(wm_orient(a, b, p) != -turn && wm_orient(b, c, p) != -turn &&
                  wm_orient(c, a, p) != -turn);
        }
        if (empty)
        {
            *x = (a.x + (double)b.x + c.x) / 3;
            *y = (a.y + (double)b.y + c.y) / 3;
            return 1;
        }
    }
    return 0;
}

/* Emits ring v (n points) with the water on its left (counter-clockwise
 * around water, clockwise around land). */
static int emit_ring(walker *w, const wm_pt *v, int n, int water_inside,
                     wm_i128 area2)
{
    const int reverse = (area2 > 0) != water_inside;
    for (int i = 0; i < n; i++)
    {
        const wm_pt a = v[reverse ? n - 1 - i : i];
        const wm_pt b = v[reverse ? (2 * n - 2 - i) % n : (i + 1) % n];
        if (!w->emit(w->user, a, b))
            return 0;
    }
    return 1;
}

/* Whether seed p is a vertex of one of the rings found (rings[k] of
 * len[k] points). */
static int seed_on_ring(wm_pt p, wm_pt (*rings)[LONE_MAX], const int *len,
                        int nr)
{
    for (int k = 0; k < nr; k++)
        for (int i = 0; i < len[k]; i++)
            if (rings[k][i].x == p.x && rings[k][i].y == p.y)
                return 1;
    return 0;
}

/* Whether rings[0 .. nr) (len[k] points each) lie apart: no two meet,
 * not even at a point, and none lies inside another (two lakes sharing an
 * edge or a vertex, a lake in another's hole: their rings as drawn are not
 * the union's boundary, and taken so they failed the block). */
static int rings_apart(wm_pt (*rings)[LONE_MAX], const int *len, int nr)
{
    for (int j = 0; j < nr; j++)
        for (int k = j + 1; k < nr; k++)
        {
            if (wm_point_in_ring(rings[k], (size_t)len[k], rings[j][0]) ||
                wm_point_in_ring(rings[j], (size_t)len[j], rings[k][0]))
                return 0;
            for (int a = 0; a < len[j]; a++)
                for (int b = 0; b < len[k]; b++)
                    if (wm_segments_meet(
                            rings[j][a], rings[j][(a + 1) % len[j]],
                            rings[k][b], rings[k][(b + 1) % len[k]]))
                        return 0;
        }
    return 1;
}

/* A rectangle q with no crossing on its sides but seeds inside it: a
 * feature of the union may lie wholly in it, an island smaller than a
 * pixel or a lake as small. Where every seed strictly inside q is a vertex
 * of the lake rings that start at one of them and lie strictly inside q,
 * simple, each the union's boundary (no vertex under other water, no other
 * input's boundary crossing it: that would be a corner, a seed elsewhere)
 * and of the other class than q inside, those rings are emitted as they
 * are: the lattice holds them exactly, where dividing q would round the
 * crossings of its dividing segments (an island 2 x 2 units came out a
 * unit thinner and was dropped as a rounding remnant: held-out lakes seed
 * 193000 at 2.5 m). Returns 1 when emitted, 0 when out of memory, -1
 * when q holds something else. */
static int lone_rings(walker *w, const rect *q)
{
    enum
    {
        MAXR = 4
    };
    wm_probe *in = w->probe;
    wm_pt ring[MAXR][LONE_MAX];
    int len[MAXR], nr = 0;
    wm_i128 area2[MAXR];
    const int water = q->cls[0];
    for (size_t i = 0; i < q->nseed; i++)
    {
        const wm_pt p = q->seed[i];
        if (p.x <= q->x0 || p.x >= q->x1 || p.y <= q->y0 || p.y >= q->y1 ||
            seed_on_ring(p, ring, len, nr))
            continue;
        wm_probe_items it;
        wm_probe_lake_edges_near(in, p.x, p.y, &it);
        for (size_t j = 0; j < it.na + it.nb && nr < MAXR; j++)
        {
            const struct wm_probe_edge *le =
                &in->ledge[j < it.na ? it.a[j] : it.b[j - it.na]];
            const wm_lake_edge *g = &in->s->edges[le->e];
            if (g->ax - in->X0 != p.x || g->ay - in->Y0 != p.y)
                continue;
            const int n = ring_from(in, in->polys[le->k], le->e, q, ring[nr]);
            if (n == 0 || !ring_simple(ring[nr], n))
                continue;
            area2[nr] = wm_ring_area2(ring[nr], (size_t)n);
            double cx, cy;
            if (!ring_inner_point(ring[nr], n, area2[nr], &cx, &cy) ||
                (wm_probe_distance(in, cx, cy, 4.0 * WM_Q) <= 0) == water)
                continue;
            int bare = 1; /* no vertex under other water */
            for (int k = 0; k < n && bare; k++)
                bare = wm_probe_distance(in, ring[nr][k].x, ring[nr][k].y,
                                         4.0 * WM_Q) >= 0;
            if (bare)
                len[nr++] = n;
            break;
        }
        if (!seed_on_ring(p, ring, len, nr))
            return -1; /* a seed of something else */
    }
    if (nr == 0 || !rings_apart(ring, len, nr))
        return -1;
    for (int k = 0; k < nr; k++)
        if (!emit_ring(w, ring[k], len[k], !water, area2[k]))
            return 0;
    return 1;
}

/* The boundary inside q: one segment when two crossings on different
 * sides and no seed leave nothing to decide, else q divided, down to
 * rectangles too small to divide, whose crossings are paired. */
static int run_rect(walker *w, const rect *q, int depth)
{
    const int k = q->ns[0] + q->ns[1] + q->ns[2] + q->ns[3];
    const int seeded = has_seed(q);
    if (k == 0 && !seeded)
        return 1;
    xing *x = malloc(((size_t)k + 1) * sizeof *x);
    if (!x)
        return 0;
    boundary(q, x);
    const int simple = k == 2 && x[0].side != x[1].side;
    int ok = k == 0 ? lone_rings(w, q) : -1;
    if (ok < 0 && (seeded || !simple))
        ok = divide_rect(w, q, depth);
    if (ok < 0 && simple)
        ok = x[0].out ? w->emit(w->user, x[0].p, x[1].p)
                      : w->emit(w->user, x[1].p, x[0].p);
    else if (ok < 0)
        ok = k ? pair_leaf(w, q, x, k) : 1;
    free(x);
    return ok;
}

/* Crossings of side `side` (contour.c's EB..EL) of cell (c, r), ascending,
 * into buf; returns how many. */
static int cell_side(const wm_field *f, const wm_hidden *h, int32_t c,
                     int32_t r, int side, int32_t *buf)
{
    const int32_t n = f->w - 1;
    /* the side's first sample (lower x or y) and its other one */
    const int vertical = side == 1 || side == 3;
    const int32_t sc = side == 1 ? c + 1 : c, sr = side == 2 ? r + 1 : r;
    const wm_hidden_edge *e = find_edge(h, edge_id(n, sc, sr, vertical));
    const int32_t base = vertical ? sr * WM_Q : sc * WM_Q;
    if (e)
    {
        for (uint32_t i = 0; i < e->n; i++)
            buf[i] = base + h->off[e->first + i];
        return (int)e->n;
    }
    const float va = wm_field_at(f, sc, sr);
    const float vb =
        vertical ? wm_field_at(f, sc, sr + 1) : wm_field_at(f, sc + 1, sr);
    if ((va <= 0) == (vb <= 0))
        return 0;
    const wm_pt p = wm_contour_crossing(va, vb, sc * WM_Q, sr * WM_Q, vertical);
    buf[0] = vertical ? p.y : p.x;
    return 1;
}

/* The boundary inside ambiguous cell (c, r). */
static int hidden_cell(const wm_field *f, wm_probe *probe, const wm_hidden *h,
                       int32_t c, int32_t r, wm_segment_fn emit, void *user)
{
    int32_t *buf = malloc(4 * MAXCROSS * sizeof *buf);
    if (!buf)
        return 0;
    const int32_t X = c * WM_Q, Y = r * WM_Q;
    float v[4];
    wm_field_cell(f, c, r, v);
    rect q = {X,
              Y,
              X + WM_Q,
              Y + WM_Q,
              {v[0] <= 0, v[1] <= 0, v[2] <= 0, v[3] <= 0},
              {0},
              {0},
              NULL,
              0};
    for (int s = 0; s < 4; s++)
    {
        q.ns[s] = cell_side(f, h, c, r, s, buf + s * MAXCROSS);
        q.side[s] = buf + s * MAXCROSS;
    }
    /* the cell's seeds */
    const uint64_t key = wm_field_cell_key(f, c, r);
    size_t lo = wm_lower_u64(h->seedcell, h->nseed, key);
    q.seed = h->seed ? h->seed + lo : NULL;
    while (lo < h->nseed && h->seedcell[lo] == key)
        lo++, q.nseed++;
    walker w = {probe, emit, user};
    const int ok = run_rect(&w, &q, 0);
    free(buf);
    return ok;
}

wm_status wm_hidden_cells(const wm_field *f, wm_probe *probe,
                          const wm_hidden *h, wm_segment_fn emit, void *user,
                          const wm_ctx *ctx)
{
    for (size_t i = 0; i < h->ncell; i++)
    {
        if (wm_cancelled(ctx))
            return WM_ERR_CANCELLED;
        int32_t c, r;
        cell_of(f, h->cell[i], &c, &r);
        if (!hidden_cell(f, probe, h, c, r, emit, user))
            return WM_ERR_NOMEM;
    }
    return WM_OK;
}
