/*
 * scene.c - the global block grid and the per-block index of the input.
 *
 * Each river segment is registered in every block its capsule, grown by the
 * clamp band, may reach; each lake polygon in every block its bounding box,
 * grown by the band, touches (a polygon's inside test needs all its edges,
 * so polygons are indexed whole). Two passes (count, fill) into CSR arrays:
 * O(input + registrations), no per-item allocation.
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

/* Calls visit(block_linear_index) for every block an item reaches; returns
 * the count. Block ranges are clipped to the scene grid. */
typedef struct
{
    size_t *count;
    size_t *pos;
    uint32_t *out;
} fill_state;

static void visit_range(const wm_scene *s, int64_t x0, int64_t y0, int64_t x1,
                        int64_t y1, uint32_t item, fill_state *st)
{
    for (int64_t by = y0; by <= y1; by++)
        for (int64_t bx = x0; bx <= x1; bx++)
        {
            if (bx < s->bx0 || by < s->by0 || bx >= s->bx0 + s->nbx ||
                by >= s->by0 + s->nby)
                continue;
            const size_t k = (size_t)((by - s->by0) * s->nbx + (bx - s->bx0));
            if (st->out)
                st->out[st->pos[k]++] = item;
            else
                st->count[k]++;
        }
}

static wm_status build_csr(wm_scene *s, int polys, size_t **start_out,
                           uint32_t **items_out)
{
    const size_t nblk = (size_t)(s->nbx * s->nby);
    const int64_t band = (int64_t)s->band * WM_Q + 1;
    size_t *start = calloc(nblk + 1, sizeof *start);
    size_t *pos = NULL;
    uint32_t *items = NULL;
    fill_state st = {start + 1, NULL, NULL};
    const size_t nitems = polys ? s->npolys : s->nsegs;
    for (int pass = 0; pass < 2; pass++)
    {
        if (!start)
            goto nomem;
        for (size_t i = 0; i < nitems; i++)
        {
            int64_t x0, y0, x1, y1;
            if (polys)
                block_range(s, s->poly_box[i], band, &x0, &y0, &x1, &y1);
            else
                block_range(s, seg_box(&s->segs[i]), seg_grow(s, &s->segs[i]),
                            &x0, &y0, &x1, &y1);
            visit_range(s, x0, y0, x1, y1, (uint32_t)i, &st);
        }
        if (pass == 0)
        {
            pos = wm_csr_begin(start, nblk);
            items = malloc((start[nblk] ? start[nblk] : 1) * sizeof *items);
            if (!items || !pos)
                goto nomem;
            st.pos = pos;
            st.out = items;
        }
    }
    free(pos);
    *start_out = start;
    *items_out = items;
    return WM_OK;
nomem:
    free(start);
    free(pos);
    free(items);
    return WM_ERR_NOMEM;
}

wm_status wm_scene_index(wm_scene *s, const wm_ctx *ctx)
{
    if (s->nsegs > UINT32_MAX || s->npolys > UINT32_MAX)
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
    /* extent of everything, grown by reach */
    int have = 0;
    wm_box all = {0, 0, 0, 0};
    s->max_r = 0;
    for (size_t i = 0; i < s->nsegs; i++)
        if (s->segs[i].r > s->max_r)
            s->max_r = s->segs[i].r;
    const int64_t grow = (int64_t)ceil(s->max_r) + (int64_t)s->band * WM_Q + 1;
    for (size_t i = 0; i < s->nsegs + s->npolys; i++)
    {
        wm_box b =
            i < s->nsegs ? seg_box(&s->segs[i]) : s->poly_box[i - s->nsegs];
        if (!have)
            all = b;
        have = 1;
        if (b.x0 < all.x0)
            all.x0 = b.x0;
        if (b.y0 < all.y0)
            all.y0 = b.y0;
        if (b.x1 > all.x1)
            all.x1 = b.x1;
        if (b.y1 > all.y1)
            all.y1 = b.y1;
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
            s->nbx * s->nby > (INT64_C(1) << 26))
            return wm_fail(ctx, WM_ERR_INVALID,
                           "the scene spans %lld x %lld blocks: too many; "
                           "use a larger BLOCK_SIZE",
                           (long long)s->nbx, (long long)s->nby);
    }
    wm_status st = build_csr(s, 0, &s->blk_seg_start, &s->blk_seg);
    if (st == WM_OK)
        st = build_csr(s, 1, &s->blk_poly_start, &s->blk_poly);
    if (st != WM_OK)
        return wm_fail(ctx, st, "out of memory indexing the scene");
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
    free(s->blk_seg_start);
    free(s->blk_seg);
    free(s->blk_poly_start);
    free(s->blk_poly);
    memset(s, 0, sizeof *s);
}
