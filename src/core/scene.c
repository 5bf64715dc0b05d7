/*
 * scene.c - the global block grid and the index of which blocks each input
 * item reaches.
 *
 * A river segment reaches the blocks its capsule, grown by the clamp band,
 * may touch; a lake polygon those its bounding box, grown by the band,
 * touches (a polygon's inside test needs all its edges, so polygons are
 * indexed whole). Each item's reach is one box of block indices, and the
 * boxes go into a packed Hilbert R-tree: O(input log input) to build and
 * O(input) memory whatever the grid's area, so a 100 km wide river over
 * 13 m blocks costs what its one segment costs. A block asks the tree for
 * its items; a walk over the non-empty blocks asks it for a row's runs.
 */
#include "scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

wm_box wm_scene_block_box(const wm_scene *s, int64_t bx, int64_t by)
{
    const int64_t side = (int64_t)s->n * WM_Q;
    wm_box b = {bx * side, by * side, (bx + 1) * side, (by + 1) * side};
    return b;
}

/* Block index range touched by box grown by `grow` lattice units. */
static void block_range(const wm_scene *s, wm_box b, int64_t grow, int64_t *x0,
                        int64_t *y0, int64_t *x1, int64_t *y1)
{
    const int64_t side = (int64_t)s->n * WM_Q;
    *x0 = wm_floordiv(b.x0 - grow, side);
    *y0 = wm_floordiv(b.y0 - grow, side);
    *x1 = wm_floordiv(b.x1 + grow, side);
    *y1 = wm_floordiv(b.y1 + grow, side);
}

static wm_box seg_box(const wm_river_seg *g)
{
    wm_box b = {g->ax < g->bx ? g->ax : g->bx, g->ay < g->by ? g->ay : g->by,
                g->ax > g->bx ? g->ax : g->bx, g->ay > g->by ? g->ay : g->by};
    return b;
}

static int64_t seg_grow(const wm_scene *s, const wm_river_seg *g)
{
    return (int64_t)ceil(g->r) + (int64_t)s->band * WM_Q + 1;
}

/* Block range an item reaches: a river segment's capsule or a polygon's box,
 * grown by the clamp band. */
static wm_box item_reach(const wm_scene *s, size_t i)
{
    wm_box r;
    if (i < s->nsegs)
        block_range(s, seg_box(&s->segs[i]), seg_grow(s, &s->segs[i]), &r.x0,
                    &r.y0, &r.x1, &r.y1);
    else
        block_range(s, s->poly_box[i - s->nsegs], (int64_t)s->band * WM_Q + 1,
                    &r.x0, &r.y0, &r.x1, &r.y1);
    return r;
}

static int boxes_meet(const wm_box *a, const wm_box *b)
{
    return a->x0 <= b->x1 && b->x0 <= a->x1 && a->y0 <= b->y1 && b->y0 <= a->y1;
}

/* Position of (x, y) on the Hilbert curve of a 2^21 square. */
static uint64_t hilbert(uint32_t x, uint32_t y)
{
    const uint32_t n = UINT32_C(1) << 21;
    uint64_t d = 0;
    for (uint32_t h = n / 2; h > 0; h /= 2)
    {
        const uint32_t rx = (x & h) != 0, ry = (y & h) != 0;
        d += (uint64_t)h * h * ((3 * rx) ^ ry);
        if (ry == 0)
        {
            if (rx == 1)
            {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            const uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

typedef struct
{
    uint64_t key;
    uint32_t item;
} hkey;

static int cmp_hkey(const void *a, const void *b)
{
    const hkey *p = a, *q = b;
    if (p->key != q->key)
        return (p->key > q->key) - (p->key < q->key);
    return (p->item > q->item) - (p->item < q->item);
}

static wm_box box_union(wm_box a, const wm_box *b)
{
    a.x0 = b->x0 < a.x0 ? b->x0 : a.x0;
    a.y0 = b->y0 < a.y0 ? b->y0 : a.y0;
    a.x1 = b->x1 > a.x1 ? b->x1 : a.x1;
    a.y1 = b->y1 > a.y1 ? b->y1 : a.y1;
    return a;
}

/* Level sizes of a tree of n leaves; returns the total box count. */
static size_t plan_levels(wm_rtree *t, size_t n)
{
    size_t total = 0, m = n;
    t->nlevels = 0;
    while (n > 0)
    {
        t->level[t->nlevels++] = total;
        total += m;
        if (m == 1)
            break;
        m = (m + WM_RTREE_FANOUT - 1) / WM_RTREE_FANOUT;
    }
    t->level[t->nlevels] = total;
    return total;
}

/* Packs every item's reach into s->reach: leaves in Hilbert order of their
 * centres (relative to the grid's first block, so keys fit 21 bits), ties
 * by item, then each level from the one below. */
static wm_status build_reach(wm_scene *s)
{
    wm_rtree *t = &s->reach;
    const size_t n = s->nsegs + s->npolys;
    free(t->box);
    free(t->item);
    memset(t, 0, sizeof *t);
    const size_t total = plan_levels(t, n);
    if (n == 0)
        return WM_OK;
    hkey *k = malloc(n * sizeof *k);
    t->box = malloc(total * sizeof *t->box);
    t->item = malloc(n * sizeof *t->item);
    if (!k || !t->box || !t->item)
    {
        free(k);
        return WM_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++)
    {
        const wm_box r = item_reach(s, i);
        k[i].key = hilbert((uint32_t)((r.x0 + r.x1) / 2 - s->bx0),
                           (uint32_t)((r.y0 + r.y1) / 2 - s->by0));
        k[i].item = (uint32_t)i;
    }
    qsort(k, n, sizeof *k, cmp_hkey);
    for (size_t i = 0; i < n; i++)
    {
        t->item[i] = k[i].item;
        t->box[i] = item_reach(s, k[i].item);
    }
    free(k);
    for (int l = 1; l < t->nlevels; l++)
        for (size_t j = t->level[l]; j < t->level[l + 1]; j++)
        {
            const size_t c0 =
                t->level[l - 1] + (j - t->level[l]) * WM_RTREE_FANOUT;
            const size_t c1 = c0 + WM_RTREE_FANOUT < t->level[l]
                                  ? c0 + WM_RTREE_FANOUT
                                  : t->level[l];
            wm_box b = t->box[c0];
            for (size_t c = c0 + 1; c < c1; c++)
                b = box_union(b, &t->box[c]);
            t->box[j] = b;
        }
    return WM_OK;
}

/* Appends the leaves of t whose box meets q to *out (n, cap): their slots,
 * depth first. */
static wm_status reach_query(const wm_rtree *t, const wm_box *q, size_t **out,
                             size_t *n, size_t *cap)
{
    size_t stack[WM_RTREE_LEVELS * WM_RTREE_FANOUT + 1];
    int sp = 0;
    if (t->nlevels == 0)
        return WM_OK;
    stack[sp++] = t->level[t->nlevels - 1];
    while (sp > 0)
    {
        const size_t j = stack[--sp];
        if (!boxes_meet(&t->box[j], q))
            continue;
        if (j < t->level[1])
        {
            if (!wm_push((void **)out, n, cap, &j, sizeof j))
                return WM_ERR_NOMEM;
            continue;
        }
        int l = 1;
        while (j >= t->level[l + 1])
            l++;
        const size_t c0 = t->level[l - 1] + (j - t->level[l]) * WM_RTREE_FANOUT;
        const size_t c1 = c0 + WM_RTREE_FANOUT < t->level[l]
                              ? c0 + WM_RTREE_FANOUT
                              : t->level[l];
        for (size_t c = c1; c-- > c0;)
            stack[sp++] = c;
    }
    return WM_OK;
}

static int cmp_u32(const void *a, const void *b)
{
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

wm_status wm_scene_items(const wm_scene *s, wm_box blocks, uint32_t **ids,
                         size_t *nsegs, size_t *npolys)
{
    size_t *leaf = NULL, n = 0, cap = 0;
    *ids = NULL;
    *nsegs = *npolys = 0;
    if (reach_query(&s->reach, &blocks, &leaf, &n, &cap) != WM_OK)
    {
        free(leaf);
        return WM_ERR_NOMEM;
    }
    if (n == 0)
        return WM_OK;
    uint32_t *v = malloc(n * sizeof *v);
    if (!v)
    {
        free(leaf);
        return WM_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++)
        v[i] = s->reach.item[leaf[i]];
    free(leaf);
    qsort(v, n, sizeof *v, cmp_u32);
    size_t k = 0;
    while (k < n && v[k] < s->nsegs)
        k++;
    for (size_t i = k; i < n; i++)
        v[i] -= (uint32_t)s->nsegs;
    *ids = v;
    *nsegs = k;
    *npolys = n - k;
    return WM_OK;
}

static int cmp_run(const void *a, const void *b)
{
    const int64_t *p = a, *q = b;
    if (p[0] != q[0])
        return (p[0] > q[0]) - (p[0] < q[0]);
    return (p[1] > q[1]) - (p[1] < q[1]);
}

wm_status wm_scene_row_runs(const wm_scene *s, int64_t by, int64_t x0,
                            int64_t x1, int64_t **runs, size_t *nruns)
{
    const wm_box q = {x0, by, x1, by};
    size_t *leaf = NULL, n = 0, cap = 0;
    *runs = NULL;
    *nruns = 0;
    if (reach_query(&s->reach, &q, &leaf, &n, &cap) != WM_OK)
    {
        free(leaf);
        return WM_ERR_NOMEM;
    }
    if (n == 0)
        return WM_OK;
    int64_t *r = malloc(2 * n * sizeof *r);
    if (!r)
    {
        free(leaf);
        return WM_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++)
    {
        const wm_box *b = &s->reach.box[leaf[i]];
        r[2 * i] = b->x0 > x0 ? b->x0 : x0;
        r[2 * i + 1] = b->x1 < x1 ? b->x1 : x1;
    }
    free(leaf);
    qsort(r, n, 2 * sizeof *r, cmp_run);
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (m > 0 && r[2 * i] <= r[2 * m - 1] + 1)
        {
            if (r[2 * i + 1] > r[2 * m - 1])
                r[2 * m - 1] = r[2 * i + 1];
        }
        else
        {
            r[2 * m] = r[2 * i];
            r[2 * m + 1] = r[2 * i + 1];
            m++;
        }
    *runs = r;
    *nruns = m;
    return WM_OK;
}

wm_status wm_scene_index(wm_scene *s, const wm_ctx *ctx)
{
    if (s->nsegs + s->npolys > UINT32_MAX)
        return wm_fail(ctx, WM_ERR_INVALID, "too many input segments");
    free(s->poly_box);
    s->poly_box = malloc((s->npolys ? s->npolys : 1) * sizeof *s->poly_box);
    if (!s->poly_box)
        return wm_fail(ctx, WM_ERR_NOMEM, "out of memory indexing the scene");
    for (size_t p = 0; p < s->npolys; p++)
    {
        wm_box b = {INT64_MAX, INT64_MAX, INT64_MIN, INT64_MIN};
        for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
        {
            const wm_lake_edge *g = &s->edges[e];
            const int64_t xs[2] = {g->ax, g->bx}, ys[2] = {g->ay, g->by};
            for (int k = 0; k < 2; k++)
            {
                if (xs[k] < b.x0)
                    b.x0 = xs[k];
                if (xs[k] > b.x1)
                    b.x1 = xs[k];
                if (ys[k] < b.y0)
                    b.y0 = ys[k];
                if (ys[k] > b.y1)
                    b.y1 = ys[k];
            }
        }
        s->poly_box[p] = b;
    }
    /* extent of everything, grown by reach; and of the water itself (each
     * capsule's box is its segment's grown by its radius) */
    int have = 0;
    wm_box all = {0, 0, 0, 0};
    s->max_r = 0;
    for (size_t i = 0; i < s->nsegs; i++)
        if (s->segs[i].r > s->max_r)
            s->max_r = s->segs[i].r;
    const int64_t grow = (int64_t)ceil(s->max_r) + (int64_t)s->band * WM_Q + 1;
    for (size_t i = 0; i < s->nsegs + s->npolys; i++)
    {
        const wm_box b =
            i < s->nsegs ? seg_box(&s->segs[i]) : s->poly_box[i - s->nsegs];
        const int64_t r = i < s->nsegs ? (int64_t)ceil(s->segs[i].r) : 0;
        const wm_box w = {b.x0 - r, b.y0 - r, b.x1 + r, b.y1 + r};
        all = have ? box_union(all, &b) : b;
        s->water = have ? box_union(s->water, &w) : w;
        have = 1;
    }
    if (!have)
    {
        s->nbx = s->nby = 0;
        s->bx0 = s->by0 = 0;
    }
    else
    {
        int64_t x0, y0, x1, y1;
        block_range(s, all, grow, &x0, &y0, &x1, &y1);
        s->bx0 = x0;
        s->by0 = y0;
        s->nbx = x1 - x0 + 1;
        s->nby = y1 - y0 + 1;
        if (s->nbx > (1 << 20) || s->nby > (1 << 20) ||
            s->nbx * s->nby > (INT64_C(1) << 39))
            return wm_fail(ctx, WM_ERR_INVALID,
                           "the scene spans %lld x %lld blocks: too many; "
                           "use a larger BLOCK_SIZE",
                           (long long)s->nbx, (long long)s->nby);
    }
    if (build_reach(s) != WM_OK)
        return wm_fail(ctx, WM_ERR_NOMEM, "out of memory indexing the scene");
    return WM_OK;
}

void wm_scene_free(wm_scene *s)
{
    if (!s)
        return;
    free(s->segs);
    free(s->edges);
    free(s->poly_start);
    free(s->poly_box);
    free(s->reach.box);
    free(s->reach.item);
    memset(s, 0, sizeof *s);
}

/* Squared distance from (X, Y) to segment [a, b], from exact lattice
 * differences. */
static double point_seg_d2(int64_t X, int64_t Y, int64_t ax, int64_t ay,
                           int64_t bx, int64_t by)
{
    const double px = (double)(X - ax), py = (double)(Y - ay);
    const double dx = (double)(bx - ax), dy = (double)(by - ay);
    const double len2 = dx * dx + dy * dy;
    double t = len2 > 0 ? (px * dx + py * dy) / len2 : 0.0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double ex = px - t * dx, ey = py - t * dy;
    return ex * ex + ey * ey;
}

/* Polygon k's index in s. */
static size_t lb_poly(const wm_lake_bands *lb, size_t k)
{
    return lb->poly ? lb->poly[k] : k;
}

size_t wm_lake_bands_of(const wm_lake_bands *lb, size_t k, int64_t y)
{
    const int64_t y0 = lb->s->poly_box[lb_poly(lb, k)].y0;
    const int64_t nb = (int64_t)(lb->band0[k + 1] - lb->band0[k]);
    int64_t b = y < y0 ? 0 : (y - y0) / lb->bh[k];
    b = b > nb - 1 ? nb - 1 : b;
    return lb->band0[k] + (size_t)b;
}

/* Bands of polygon p: about one per 8 edges, fewer while the edges would
 * be registered more than 16 times their number (long edges span many). */
static int64_t band_count(const wm_scene *s, size_t p)
{
    const size_t n = s->poly_start[p + 1] - s->poly_start[p];
    const int64_t h = s->poly_box[p].y1 - s->poly_box[p].y0 + 1;
    for (int64_t nb = (int64_t)(n / 8) + 1;; nb = nb / 2)
    {
        if (nb <= 1)
            return 1;
        const int64_t bh = (h + nb - 1) / nb;
        size_t spans = 0;
        for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
        {
            const wm_lake_edge *g = &s->edges[e];
            spans +=
                (size_t)((g->by > g->ay ? g->by - g->ay : g->ay - g->by) / bh +
                         2);
        }
        if (spans <= 16 * n)
            return nb;
    }
}

void wm_lake_bands_free(wm_lake_bands *lb)
{
    if (!lb)
        return;
    free(lb->band0);
    free(lb->bh);
    free(lb->start);
    free(lb->edge);
    memset(lb, 0, sizeof *lb);
}

wm_status wm_lake_bands_build(wm_lake_bands *lb, const wm_scene *s,
                              const uint32_t *poly, size_t npolys)
{
    memset(lb, 0, sizeof *lb);
    lb->s = s;
    lb->poly = poly;
    lb->npolys = poly ? npolys : s->npolys;
    const size_t np = lb->npolys;
    lb->band0 = malloc((np + 1) * sizeof *lb->band0);
    lb->bh = malloc((np + 1) * sizeof *lb->bh);
    size_t *cur = NULL;
    if (!lb->band0 || !lb->bh)
        goto nomem;
    lb->band0[0] = 0;
    for (size_t k = 0; k < np; k++)
    {
        const size_t p = lb_poly(lb, k);
        const int64_t nb = band_count(s, p);
        const int64_t h = s->poly_box[p].y1 - s->poly_box[p].y0 + 1;
        lb->bh[k] = (h + nb - 1) / nb;
        lb->band0[k + 1] = lb->band0[k] + (size_t)nb;
    }
    const size_t nbands = lb->band0[np];
    lb->start = calloc(nbands + 1, sizeof *lb->start);
    if (!lb->start)
        goto nomem;
    for (int pass = 0; pass < 2; pass++)
    {
        if (pass == 1)
        {
            cur = wm_csr_begin(lb->start, nbands);
            lb->edge = malloc((lb->start[nbands] + 1) * sizeof *lb->edge);
            if (!cur || !lb->edge)
                goto nomem;
        }
        for (size_t k = 0; k < np; k++)
        {
            const size_t p = lb_poly(lb, k);
            for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
            {
                const wm_lake_edge *g = &s->edges[e];
                const size_t b0 =
                    wm_lake_bands_of(lb, k, g->ay < g->by ? g->ay : g->by);
                const size_t b1 =
                    wm_lake_bands_of(lb, k, g->ay < g->by ? g->by : g->ay);
                for (size_t b = b0; b <= b1; b++)
                    if (pass == 0)
                        lb->start[b + 1]++;
                    else
                        lb->edge[cur[b]++] = e;
            }
        }
    }
    free(cur);
    return WM_OK;
nomem:
    free(cur);
    wm_lake_bands_free(lb);
    return WM_ERR_NOMEM;
}

int wm_lake_bands_inside(const wm_lake_bands *lb, size_t k, int64_t X,
                         int64_t Y)
{
    const wm_box *b = &lb->s->poly_box[lb_poly(lb, k)];
    if (X < b->x0 || X > b->x1 || Y < b->y0 || Y > b->y1)
        return 0;
    const size_t q = wm_lake_bands_of(lb, k, Y);
    int par = 0;
    for (size_t i = lb->start[q]; i < lb->start[q + 1]; i++)
        par ^= wm_edge_crosses_ray(&lb->s->edges[lb->edge[i]], X, Y);
    return par;
}

/* The distance from (X, Y) to polygon k's nearest edge, or cap when none
 * is nearer: its bands outward from the point's row, until a band's rows
 * are farther than the best found. */
static double lake_dist(const wm_lake_bands *lb, size_t k, int64_t X, int64_t Y,
                        double cap)
{
    const size_t b0 = lb->band0[k], b1 = lb->band0[k + 1];
    const size_t here = wm_lake_bands_of(lb, k, Y);
    const int64_t y0 = lb->s->poly_box[lb_poly(lb, k)].y0;
    double best2 = cap * cap;
    for (size_t step = 0;; step++)
    {
        int any = 0;
        for (int side = 0; side < (step ? 2 : 1); side++)
        {
            if (side == 0 ? here + step >= b1 : here < b0 + step)
                continue;
            const size_t b = side == 0 ? here + step : here - step;
            /* the band's rows: y0 + (b - b0) * bh .. + bh - 1 */
            const int64_t lo = y0 + (int64_t)(b - b0) * lb->bh[k];
            const int64_t hi = lo + lb->bh[k] - 1;
            /* no point of an edge in the band is nearer than its rows' gap
             * less one (the rows cover y up to hi + 1) */
            const int64_t gap = Y < lo ? lo - Y : (Y > hi ? Y - hi : 0);
            const double dy = gap > 1 ? (double)(gap - 1) : 0.0;
            if (dy * dy >= best2)
                continue;
            any = 1;
            for (size_t i = lb->start[b]; i < lb->start[b + 1]; i++)
            {
                const wm_lake_edge *g = &lb->s->edges[lb->edge[i]];
                const double q = point_seg_d2(X, Y, g->ax, g->ay, g->bx, g->by);
                best2 = q < best2 ? q : best2;
            }
        }
        if (!any && step > 0)
            break;
    }
    return sqrt(best2);
}

double wm_scene_depth(const wm_scene *s, const uint32_t *segs, size_t nsegs,
                      const wm_lake_bands *lakes, int64_t X, int64_t Y,
                      double cap)
{
    double depth = 0;
    for (size_t i = 0; i < nsegs && depth < cap; i++)
    {
        const wm_river_seg *g = &s->segs[segs[i]];
        const double d =
            g->r - sqrt(point_seg_d2(X, Y, g->ax, g->ay, g->bx, g->by));
        depth = d > depth ? d : depth;
    }
    for (size_t k = 0; lakes && k < lakes->npolys && depth < cap; k++)
        if (wm_lake_bands_inside(lakes, k, X, Y))
        {
            const double d = lake_dist(lakes, k, X, Y, cap);
            depth = d > depth ? d : depth;
        }
    return depth < cap ? depth : cap;
}
