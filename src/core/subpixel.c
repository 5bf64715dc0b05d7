/*
 * subpixel.c - boundary crossings the samples cannot see, found from the
 * exact inputs, and the cells they make ambiguous.
 *
 * Why: marching squares sees the boundary only where two neighbouring
 * samples differ in class. A strip of land narrower than a pixel between
 * two rivers, the tip of a junction wedge, a stream narrower than a pixel,
 * cross a cell edge twice between two samples of one class: the samples
 * skip them, and the strip comes out cut short, dashed, or as a row of
 * specks where it happens to cover a sample.
 *
 * Rule: the field is 1-Lipschitz and |d| never exceeds the distance to the
 * boundary, so an edge whose samples are of one class with |va| + |vb| > 1
 * pixel holds no boundary point; every other edge of one class "cannot
 * decide". Its crossings are computed exactly from the inputs (probe.h:
 * capsule and lake intervals along the edge). A cell with a side holding
 * such crossings is ambiguous; its boundary is rebuilt by subdividing it:
 * each dividing segment's crossings are again found exactly, until every
 * piece holds one boundary segment between two of its sides (a straight
 * segment, as marching squares draws) or is 2-3 lattice units wide (then
 * the crossings are paired by the class of the piece's centre).
 *
 * Why nothing is missed: a boundary component that meets an edge of the
 * sample grid either changes the class between its samples (marching
 * squares sees it) or crosses it an even number of times between samples
 * of one class, which the Lipschitz bound does not exclude, so the edge is
 * searched exactly. What stays unseen is a component that meets no edge:
 * inside one cell and touching none of its sides (an island or a pond
 * smaller than a cell, between samples), and a crossing pair hidden on an
 * edge whose samples already differ in class (three crossings on one
 * edge).
 *
 * Seams: an edge's crossings depend on its two samples and the inputs
 * only, with every coordinate difference formed in integers, so both
 * blocks sharing an edge of their square find the same ones; subdivision
 * happens inside cells, which belong to one block.
 *
 * Cost: one exact search (the items near the edge) per edge of a mixed
 * tile that cannot decide; subdivision only in ambiguous cells, O(depth)
 * searches per crossing.
 */
#include "subpixel.h"

#include "contour.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Most crossings one segment can hold: one per interior lattice point. */
#define MAXCROSS WM_Q
/* Subdivision depth bound (a cell is 256 units: 7 halvings of each side
 * reach parts 3 units wide). */
#define MAXDEPTH 32

static uint64_t edge_id(int32_t n, int32_t c, int32_t r, int vertical)
{
    return 2 * ((uint64_t)r * (uint64_t)(n + 1) + (uint64_t)c) +
           (uint64_t)vertical;
}

static uint64_t cell_key(const wm_field *f, int32_t c, int32_t r)
{
    const uint64_t t =
        (uint64_t)(r / WM_TILE) * (uint64_t)f->ntx + (uint64_t)(c / WM_TILE);
    return t << 32 | (uint64_t)((r % WM_TILE) * WM_TILE + c % WM_TILE);
}

/* The first index of sorted a[0 .. n) holding a key >= key. */
static size_t lower_u64(const uint64_t *a, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (a[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
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
    h->cell[h->ncell++] = cell_key(f, c, r);
    return 1;
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
    /* the cells on both sides */
    return vertical ? add_cell(h, f, c - 1, r) && add_cell(h, f, c, r)
                    : add_cell(h, f, c, r - 1) && add_cell(h, f, c, r);
}

/* Bits of a tile row of samples (WM_TILE + 1 values): where |v| < 1 pixel
 * (an edge can be undecided only between two such samples), and where v is
 * water. The compares vectorize into bytes; eight 0/1 bytes are gathered
 * into eight bits by one multiplication (cf. contour.c). */
WM_CLONES static void row_bits(const float *row, uint64_t *near,
                               uint64_t *water)
{
    enum
    {
        NB = (WM_TILE + 1 + 7) / 8 * 8
    };
    unsigned char bn[NB], bw[NB];
    for (int32_t i = 0; i <= WM_TILE; i++)
        bn[i] = (unsigned char)((row[i] < 1.0f) & (row[i] > -1.0f));
    for (int32_t i = 0; i <= WM_TILE; i++)
        bw[i] = row[i] <= 0;
    for (int32_t i = WM_TILE + 1; i < NB; i++)
        bn[i] = bw[i] = 0;
    *near = *water = 0;
    for (int32_t k = 0; k < NB / 8; k++)
    {
        uint64_t x = 0, y = 0;
        for (int j = 0; j < 8; j++)
        {
            x |= (uint64_t)bn[8 * k + j] << (8 * j);
            y |= (uint64_t)bw[8 * k + j] << (8 * j);
        }
        *near |= ((x * UINT64_C(0x0102040810204080)) >> 56) << (8 * k);
        *water |= ((y * UINT64_C(0x0102040810204080)) >> 56) << (8 * k);
    }
}

/* How far from its own end the samples of one column (or row) of the
 * tile certify an edge clear: the edge's end sample a (value va) and the
 * samples k = 1, 2 rows (columns) beside it, at stride `step` in the tile's
 * value array, of the same class. A sample valued v at distance k from the
 * edge's line clears the part of the edge within sqrt(v^2 - k^2) of its
 * foot (the field is 1-Lipschitz and |v| never exceeds the distance to the
 * boundary). lo, hi: how many rows (columns) the tile has on each side. */
static float reach_of(const float *a, ptrdiff_t step, int lo, int hi)
{
    const int wa = a[0] <= 0;
    float h = fabsf(a[0]);
    for (int k = 1; k <= 2; k++)
        for (int sgn = -1; sgn <= 1; sgn += 2)
        {
            if ((sgn < 0 ? lo : hi) < k)
                continue;
            const float v = a[sgn * k * step];
            const float e = v * v - (float)(k * k);
            if ((v <= 0) == wa && e > h * h)
                h = sqrtf(e);
        }
    return h;
}

/* Whether the edge from the sample at a to the one at a + along (values in
 * the tile's array; the rows or columns beside it at stride `across`, lo
 * and hi of them available on each side) cannot decide: both of one class
 * (the caller checks) and the clear parts from both ends, by reach_of, do
 * not cover it (with a margin of 1/1000 pixel for the float values). */
static int undecided(const float *a, ptrdiff_t along, ptrdiff_t across, int lo,
                     int hi)
{
    if (fabsf(a[0]) + fabsf(a[along]) > 1.0f)
        return 0;
    return reach_of(a, across, lo, hi) + reach_of(a + along, across, lo, hi) <=
           1.001f;
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
                continue; /* the block square keeps its sampled crossing */
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
            const int b = keyset_add(&cells, cell_key(f, oc, orow));
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

/* Seeds point p (block-local) of a small input, when inside the block. */
static int add_seed(wm_hidden *h, const wm_field *f, int64_t x, int64_t y)
{
    const int32_t n = f->w - 1;
    if (x < 0 || y < 0 || x >= (int64_t)n * WM_Q || y >= (int64_t)n * WM_Q)
        return 1;
    const int32_t c = (int32_t)(x / WM_Q), r = (int32_t)(y / WM_Q);
    if (!wm_grow((void **)&h->seed, &h->seedcap, h->nseed + 1,
                 sizeof *h->seed) ||
        !wm_grow((void **)&h->seedcell, &h->seedcellcap, h->nseed + 1,
                 sizeof *h->seedcell))
        return 0;
    h->seed[h->nseed] = (wm_pt){(int32_t)x, (int32_t)y};
    h->seedcell[h->nseed++] = cell_key(f, c, r);
    return add_cell(h, f, c, r);
}

/* Seeds the cells of the inputs smaller than two pixels: lake rings (the
 * runs of edges of a polygon that close) and river segments with their
 * radius, by their first point. */
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
                          s->edges[e0].ay - probe->Y0))
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
            !add_seed(h, f, g->ax - probe->X0, g->ay - probe->Y0))
            return 0;
    }
    /* by cell: (cell, index) pairs sorted, then both arrays permuted */
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

/* Flags the tiles holding an ambiguous cell and the tiles next to them. */
static int mark_near(wm_hidden *h, const wm_field *f)
{
    h->near = calloc((size_t)f->ntx * (size_t)f->nty + 1, 1);
    if (!h->near)
        return 0;
    for (size_t i = 0; i < h->ncell; i++)
    {
        const int64_t t = (int64_t)(h->cell[i] >> 32);
        const int32_t tx = (int32_t)(t % f->ntx), ty = (int32_t)(t / f->ntx);
        for (int32_t y = ty - 1; y <= ty + 1; y++)
            for (int32_t x = tx - 1; x <= tx + 1; x++)
                if (x >= 0 && y >= 0 && x < f->ntx && y < f->nty)
                    h->near[(size_t)y * (size_t)f->ntx + (size_t)x] = 1;
    }
    return 1;
}

wm_status wm_hidden_find(const wm_field *f, wm_probe *probe, wm_hidden *h,
                         const wm_ctx *ctx)
{
    const int32_t n = f->w - 1;
    memset(h, 0, sizeof *h);
    for (int32_t ty = 0; ty < f->nty; ty++)
        for (int32_t tx = 0; tx < f->ntx; tx++)
        {
            const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
            if (f->kind[t] != WM_TILE_MIXED)
                continue;
            const int32_t c0 = tx * WM_TILE, r0 = ty * WM_TILE;
            const int32_t c1 = c0 + WM_TILE < n ? c0 + WM_TILE : n;
            const int32_t r1 = r0 + WM_TILE < n ? r0 + WM_TILE : n;
            /* a tile searches its edges but those of its top row and right
             * column, which the tile beyond searches (it is mixed too: an
             * edge that cannot decide has no sample at the clamp band), or
             * which lie on the block square */
            const int32_t re = r1 == n ? r1 : r1 - 1;
            const int32_t ce = c1 == n ? c1 : c1 - 1;
            const float *v = f->val[t];
            const uint64_t hcols = (UINT64_C(1) << (c1 - c0)) - 1;
            const uint64_t vcols = (UINT64_C(1) << (ce - c0 + 1)) - 1;
            uint64_t near, water, near2 = 0, water2 = 0;
            row_bits(v, &near, &water);
            for (int32_t r = r0; r <= re; r++)
            {
                const float *row = v + (r - r0) * (WM_TILE + 1);
                if (r < r1)
                    row_bits(row + WM_TILE + 1, &near2, &water2);
                /* horizontal edges of row r, vertical ones up from it:
                 * both samples near, of one class */
                uint64_t hm =
                    near & (near >> 1) & ~(water ^ (water >> 1)) & hcols;
                uint64_t vm =
                    r < r1 ? near & near2 & ~(water ^ water2) & vcols : 0;
                while (hm)
                {
                    const int32_t q = __builtin_ctzll(hm);
                    hm &= hm - 1;
                    if (undecided(row + q, 1, WM_TILE + 1, r - r0, r1 - r) &&
                        !search_edge(h, f, probe, c0 + q, r, 0, row[q] <= 0))
                        goto nomem;
                }
                while (vm)
                {
                    const int32_t q = __builtin_ctzll(vm);
                    vm &= vm - 1;
                    if (undecided(row + q, WM_TILE + 1, 1, q, c1 - c0 - q) &&
                        !search_edge(h, f, probe, c0 + q, r, 1, row[q] <= 0))
                        goto nomem;
                }
                near = near2;
                water = water2;
            }
        }
    if (!add_seeds(h, f, probe) || !exact_sides(h, f, probe))
        goto nomem;
    if (h->ncell == 0)
        return WM_OK; /* nothing hidden (and no edge listed) */
    if (h->nedge > 1)
        qsort(h->edge, h->nedge, sizeof *h->edge, cmp_edge);
    qsort(h->cell, h->ncell, sizeof *h->cell, cmp_u64);
    if (!mark_near(h, f))
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
    free(h->near);
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
    const uint64_t key = cell_key(f, c, r);
    const size_t lo = lower_u64(h->cell, h->ncell, key);
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

/* A split position in [lo + 3, hi - 3], nearest the middle, on no crossing
 * of sides a and b; or -1. Parts at least 3 units wide: a part's side then
 * holds two crossings, those of a strip one unit wide. */
static int32_t split_at(const rect *q, int32_t lo, int32_t hi, int a, int b)
{
    const int32_t mid = lo + (hi - lo) / 2;
    for (int32_t d = 0; mid - d >= lo + 3 || mid + d <= hi - 3; d++)
        for (int sgn = 0; sgn < 2; sgn++)
        {
            const int32_t v = sgn ? mid + d : mid - d;
            if (v < lo + 3 || v > hi - 3)
                continue;
            if (!taken(q, a, v) && !taken(q, b, v))
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

/* Emits a -> b, or a -> (a point one unit inside) -> b when both are on
 * side s of q (the segment would run along the side). */
static int emit_pair(walker *w, const rect *q, const xing *a, const xing *b)
{
    if (a->side != b->side)
        return w->emit(w->user, a->p, b->p);
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
    return w->emit(w->user, a->p, m) && w->emit(w->user, m, b->p);
}

/* Pairs the crossings of a rectangle too small to divide: each out
 * crossing with the next in one counter-clockwise (the water corners
 * joined) or the previous (separated); the pairing with fewer pairs on one
 * side wins, the class of the centre decides a tie. */
static int pair_leaf(walker *w, const rect *q, const xing *x, int k)
{
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
    for (int i = 0; i < k; i++)
        if (x[i].out)
        {
            const int m = joined ? (i + 1) % k : (i + k - 1) % k;
            if (!emit_pair(w, q, &x[i], &x[m]))
                return 0;
        }
    return 1;
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
 * those of the sides it starts and ends on), and runs both parts. */
static int split(walker *w, const rect *q, int vertical, int32_t at, int depth)
{
    int32_t *mid = malloc(MAXCROSS * sizeof *mid);
    if (!mid)
        return 0;
    /* the sides the dividing segment starts and ends on, and the two
     * sides it cuts */
    const int s0 = vertical ? SB : SL, s1 = vertical ? ST : SR;
    const int c0 = class_at(q, s0, at);
    int c1 = class_at(q, s1, at);
    const wm_pt P = vertical ? (wm_pt){at, q->y0} : (wm_pt){q->x0, at};
    const int n = divide(
        w, P, vertical, vertical ? q->y1 - q->y0 : q->x1 - q->x0, c0, &c1, mid);
    int ok = n >= 0;
    rect part[2];
    for (int k = 0; k < 2 && ok; k++)
    {
        rect *a = &part[k];
        *a = *q;
        if (vertical)
        {
            /* k = 0: left of x = at, k = 1: right of it */
            if (k == 0)
                a->x1 = at;
            else
                a->x0 = at;
            a->cls[k ? 0 : 1] = c0;
            a->cls[k ? 3 : 2] = c1;
            sub_side(q, SB, k ? at : q->x0, k ? q->x1 : at, &a->side[SB],
                     &a->ns[SB]);
            sub_side(q, ST, k ? at : q->x0, k ? q->x1 : at, &a->side[ST],
                     &a->ns[ST]);
            a->side[k ? SL : SR] = mid;
            a->ns[k ? SL : SR] = n;
        }
        else
        {
            /* k = 0: below y = at, k = 1: above it */
            if (k == 0)
                a->y1 = at;
            else
                a->y0 = at;
            a->cls[k ? 0 : 3] = c0;
            a->cls[k ? 1 : 2] = c1;
            sub_side(q, SL, k ? at : q->y0, k ? q->y1 : at, &a->side[SL],
                     &a->ns[SL]);
            sub_side(q, SR, k ? at : q->y0, k ? q->y1 : at, &a->side[SR],
                     &a->ns[SR]);
            a->side[k ? SB : ST] = mid;
            a->ns[k ? SB : ST] = n;
        }
        ok = run_rect(w, a, depth + 1);
    }
    free(mid);
    return ok;
}

/* Divides q across its longer side (where a position is free of
 * crossings, the parts at least 3 units wide) and runs the parts; returns
 * 1, 0 when out of memory, or -1 when q cannot be divided. */
static int divide_rect(walker *w, const rect *q, int depth)
{
    if (depth >= MAXDEPTH)
        return -1;
    const int32_t sx =
        q->x1 - q->x0 >= 6 ? split_at(q, q->x0, q->x1, SB, ST) : -1;
    const int32_t sy =
        q->y1 - q->y0 >= 6 ? split_at(q, q->y0, q->y1, SL, SR) : -1;
    if (sx < 0 && sy < 0)
        return -1;
    const int vertical = sx > 0 && (sy < 0 || q->x1 - q->x0 >= q->y1 - q->y0);
    return split(w, q, vertical, vertical ? sx : sy, depth);
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

static int run_rect(walker *w, const rect *q, int depth)
{
    const int k = q->ns[0] + q->ns[1] + q->ns[2] + q->ns[3];
    if (k == 0)
    {
        /* nothing crosses the sides: an input smaller than the rectangle
         * may still lie inside; divide towards its seed */
        if (!has_seed(q))
            return 1;
        const int d = divide_rect(w, q, depth);
        return d < 0 ? 1 : d;
    }
    xing *x = malloc((size_t)k * sizeof *x);
    if (!x)
        return 0;
    boundary(q, x);
    int ok;
    if (k == 2 && x[0].side != x[1].side)
        ok = x[0].out ? w->emit(w->user, x[0].p, x[1].p)
                      : w->emit(w->user, x[1].p, x[0].p);
    else if ((ok = divide_rect(w, q, depth)) < 0)
        ok = pair_leaf(w, q, x, k);
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
    rect q = {X,
              Y,
              X + WM_Q,
              Y + WM_Q,
              {wm_field_at(f, c, r) <= 0, wm_field_at(f, c + 1, r) <= 0,
               wm_field_at(f, c + 1, r + 1) <= 0,
               wm_field_at(f, c, r + 1) <= 0},
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
    const uint64_t key = cell_key(f, c, r);
    size_t lo = lower_u64(h->seedcell, h->nseed, key);
    q.seed = h->seed + lo;
    while (lo < h->nseed && h->seedcell[lo] == key)
        lo++, q.nseed++;
    walker w = {probe, emit, user};
    const int ok = run_rect(&w, &q, 0);
    free(buf);
    return ok;
}

wm_status wm_hidden_cells(const wm_field *f, wm_probe *probe,
                          const wm_hidden *h, wm_segment_fn emit, void *user)
{
    for (size_t i = 0; i < h->ncell; i++)
    {
        int32_t c, r;
        cell_of(f, h->cell[i], &c, &r);
        if (!hidden_cell(f, probe, h, c, r, emit, user))
            return WM_ERR_NOMEM;
    }
    return WM_OK;
}
