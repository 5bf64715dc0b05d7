/*
 * merge.c - vertex merging by distance, the last step of the paper's
 * pipeline ("mesh simplification with a vertex-vertex distance criterion",
 * Menegais et al. 2021, section 7), done on the rings before triangulation
 * so that the triangulation stays exact and conforming.
 *
 * Method. The rings become one doubly linked list per ring. A vertex closer
 * than `dist` to a ring neighbour, not on the block square, is removed
 * (merged into the neighbour) when that keeps the ring set valid:
 *   - the triangle (prev, v, next) it cuts off or adds contains no other
 *     vertex, closed (exact orientation tests);
 *   - the new edge (prev, next) meets no other edge, and does not fold back
 *     onto the edges before prev or after next;
 *   - the ring keeps >= 3 vertices and its signed area keeps its sign
 *     (tracked exactly in 128 bits).
 * With no vertex in the triangle and no edge crossing the new edge, no edge
 * passes through the triangle, so rings stay simple and disjoint and
 * nesting is unchanged. Passes in vertex order repeat until nothing merges.
 *
 * Cost: edges are registered in a uniform grid over the block (at most 256
 * x 256 cells); a removal test scans the cells of the triangle's bounding
 * box. Each removal is O(entries there); a pass is O(n x that).
 *
 * Robustness: every decision is an exact integer predicate; floating point
 * only compares squared lengths with dist^2.
 */
#include "merge.h"

#include "lattice.h"

#include <stdlib.h>
#include <string.h>

typedef struct
{
    size_t *v;
    size_t n, cap;
} cell;

typedef struct
{
    const wm_pt *p;
    size_t *nxt, *prv, *ring;
    uint8_t *alive;
    size_t *len;    /* per ring: vertices left */
    wm_i128 *area2; /* per ring: twice the signed area */
    int32_t size;   /* the block square's side */
    int shift;      /* cell side 2^shift lattice units */
    int32_t nc;     /* cells per side */
    cell *cells;
} state;

static int cell_push(cell *c, size_t i)
{
    if (c->n == c->cap)
    {
        const size_t cap = c->cap ? 2 * c->cap : 8;
        size_t *v = realloc(c->v, cap * sizeof *v);
        if (!v)
            return 0;
        c->v = v;
        c->cap = cap;
    }
    c->v[c->n++] = i;
    return 1;
}

static int32_t cell_of(const state *s, int32_t x)
{
    int32_t c = x >> s->shift;
    return c < 0 ? 0 : (c >= s->nc ? s->nc - 1 : c);
}

/* Registers edge i -> nxt[i] in the cells of its bounding box. */
static int add_edge(state *s, size_t i)
{
    const wm_pt a = s->p[i], b = s->p[s->nxt[i]];
    const int32_t cx0 = cell_of(s, a.x < b.x ? a.x : b.x),
                  cx1 = cell_of(s, a.x > b.x ? a.x : b.x),
                  cy0 = cell_of(s, a.y < b.y ? a.y : b.y),
                  cy1 = cell_of(s, a.y > b.y ? a.y : b.y);
    for (int32_t cy = cy0; cy <= cy1; cy++)
        for (int32_t cx = cx0; cx <= cx1; cx++)
            if (!cell_push(&s->cells[(size_t)cy * (size_t)s->nc + (size_t)cx],
                           i))
                return 0;
    return 1;
}

/* p in the closed triangle (a, b, c) of orientation o != 0. */
static int in_triangle(wm_pt a, wm_pt b, wm_pt c, int o, wm_pt p)
{
    return wm_orient(a, b, p) * o >= 0 && wm_orient(b, c, p) * o >= 0 &&
           wm_orient(c, a, p) * o >= 0;
}

/* Whether removing vertex v keeps the rings valid (see the file header). */
static int removable(const state *s, size_t v)
{
    const size_t a = s->prv[v], b = s->nxt[v], r = s->ring[v];
    if (s->len[r] <= 3)
        return 0;
    const wm_pt pa = s->p[a], pv = s->p[v], pb = s->p[b];
    /* never a new edge along a side of the block square: it would change
     * which piece of the side this block covers, not the neighbour */
    if ((pa.x == pb.x && (pa.x == 0 || pa.x == s->size)) ||
        (pa.y == pb.y && (pa.y == 0 || pa.y == s->size)))
        return 0;
    const wm_i128 area2 = s->area2[r] - (wm_i128)wm_orient_det(pa, pv, pb);
    if (area2 == 0 || (area2 > 0) != (s->area2[r] > 0))
        return 0;
    /* the new edge must not fold back onto its neighbours */
    if (wm_on_segment(pa, pb, s->p[s->prv[a]]) ||
        wm_on_segment(pa, pb, s->p[s->nxt[b]]) ||
        wm_on_segment(s->p[s->prv[a]], pa, pb) ||
        wm_on_segment(pb, s->p[s->nxt[b]], pa))
        return 0;
    const int o = wm_orient(pa, pv, pb);
    const int32_t xs[3] = {pa.x, pv.x, pb.x}, ys[3] = {pa.y, pv.y, pb.y};
    int32_t x0 = xs[0], x1 = xs[0], y0 = ys[0], y1 = ys[0];
    for (int k = 1; k < 3; k++)
    {
        x0 = xs[k] < x0 ? xs[k] : x0;
        x1 = xs[k] > x1 ? xs[k] : x1;
        y0 = ys[k] < y0 ? ys[k] : y0;
        y1 = ys[k] > y1 ? ys[k] : y1;
    }
    for (int32_t cy = cell_of(s, y0); cy <= cell_of(s, y1); cy++)
        for (int32_t cx = cell_of(s, x0); cx <= cell_of(s, x1); cx++)
        {
            const cell *c = &s->cells[(size_t)cy * (size_t)s->nc + (size_t)cx];
            for (size_t k = 0; k < c->n; k++)
            {
                const size_t e = c->v[k];
                if (!s->alive[e] || e == v || e == a)
                    continue;
                const wm_pt pe = s->p[e], pf = s->p[s->nxt[e]];
                /* a vertex in the closed triangle (collinear triangles: on
                 * the segment a-b, which contains v) */
                if (e != b)
                {
                    if (o != 0 ? in_triangle(pa, pv, pb, o, pe)
                               : wm_on_segment(pa, pb, pe))
                        return 0;
                }
                /* an edge meeting the new edge; the edges at a and b meet
                 * it at their shared end point only (checked above) */
                if (e != b && s->nxt[e] != a &&
                    wm_segments_meet(pa, pb, pe, pf))
                    return 0;
            }
        }
    return 1;
}

wm_status wm_merge_rings(wm_rings *r, int32_t size, double dist, size_t *merged,
                         const wm_ctx *ctx)
{
    wm_status st = WM_OK;
    state s;
    size_t removed = 0;
    memset(&s, 0, sizeof s);
    if (merged)
        *merged = 0;
    if (!(dist > 0) || r->npts == 0)
        return WM_OK;
    const size_t n = r->npts;
    s.p = r->pts;
    s.size = size;
    s.nxt = malloc(n * sizeof *s.nxt);
    s.prv = malloc(n * sizeof *s.prv);
    s.ring = malloc(n * sizeof *s.ring);
    s.alive = malloc(n);
    s.len = malloc(r->nrings * sizeof *s.len);
    s.area2 = malloc(r->nrings * sizeof *s.area2);
    s.shift = 4;
    while (((int64_t)size >> s.shift) >= 256)
        s.shift++;
    s.nc = (int32_t)((int64_t)size >> s.shift) + 1;
    s.cells = calloc((size_t)s.nc * (size_t)s.nc, sizeof *s.cells);
    if (!s.nxt || !s.prv || !s.ring || !s.alive || !s.len || !s.area2 ||
        !s.cells)
        goto nomem;
    memset(s.alive, 1, n);
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t a = r->start[i], m = wm_rings_len(r, i);
        s.len[i] = m;
        s.area2[i] = wm_ring_area2(r->pts + a, m);
        for (size_t k = 0; k < m; k++)
        {
            s.nxt[a + k] = a + (k + 1) % m;
            s.prv[a + k] = a + (k + m - 1) % m;
            s.ring[a + k] = i;
        }
    }
    for (size_t i = 0; i < n; i++)
        if (!add_edge(&s, i))
            goto nomem;

    const double d2 = dist * dist;
    for (int changed = 1; changed;)
    {
        changed = 0;
        for (size_t v = 0; v < n; v++)
        {
            const wm_pt p = r->pts[v];
            if (!s.alive[v] || p.x == 0 || p.y == 0 || p.x == size ||
                p.y == size)
                continue;
            const wm_pt q = r->pts[s.prv[v]], t = r->pts[s.nxt[v]];
            const int64_t dq = (int64_t)(p.x - q.x) * (p.x - q.x) +
                               (int64_t)(p.y - q.y) * (p.y - q.y);
            const int64_t dt = (int64_t)(p.x - t.x) * (p.x - t.x) +
                               (int64_t)(p.y - t.y) * (p.y - t.y);
            if (!((double)dq < d2 || (double)dt < d2) || !removable(&s, v))
                continue;
            const size_t a = s.prv[v], b = s.nxt[v];
            s.area2[s.ring[v]] -= (wm_i128)wm_orient_det(q, p, t);
            s.len[s.ring[v]]--;
            s.alive[v] = 0;
            s.nxt[a] = b;
            s.prv[b] = a;
            if (!add_edge(&s, a))
                goto nomem;
            removed++;
            changed = 1;
        }
    }
    /* compact in place: the survivors of each ring, in order */
    size_t w = 0, first = 0;
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t a = r->start[i], b = r->start[i + 1];
        r->start[i] = first;
        for (size_t k = a; k < b; k++)
            if (s.alive[k])
                r->pts[w++] = r->pts[k];
        first = w;
    }
    r->start[r->nrings] = w;
    r->npts = w;
    if (merged)
        *merged = removed;
    goto cleanup;
nomem:
    st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory merging vertices");
cleanup:
    if (s.cells)
        for (size_t c = 0; c < (size_t)s.nc * (size_t)s.nc; c++)
            free(s.cells[c].v);
    free(s.cells);
    free(s.nxt);
    free(s.prv);
    free(s.ring);
    free(s.alive);
    free(s.len);
    free(s.area2);
    return st;
}
