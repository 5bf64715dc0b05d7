/*
 * probe.c - direct evaluation of the signed distance to the union of a
 * block's inputs at any point.
 *
 * Method: the minimum over the river segments within reach (from a grid of
 * 16-pixel cells over the block) of |p - segment| - radius, and over the
 * block's lake polygons of +-|p - nearest edge| (negative inside, even-odd
 * by a ray crossing count), as the field defines a sample (field.c).
 * Cost: the segments of the point's cell plus every edge of the lake
 * polygons whose box is within reach; building the index is O(segments x
 * cells they reach).
 * Robustness: double precision from block-local coordinates; the result
 * chooses (which corner to try, which way a saddle goes), it never decides
 * validity, which stays with the exact predicates of lattice.h.
 */
#include "probe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Cells of the river index, and the reach it serves (union_distance is
 * always asked for at most DREACH). */
#define DCELL (16 * WM_Q)
#define DREACH WM_PROBE_REACH
#define WIDE 1024

/* Index cell (clamped to the block) of the local coordinate v. */
static int32_t dcell(const wm_probe *in, double v)
{
    const double c = floor(v / DCELL);
    const int32_t side = in->cells.side;
    return c < 0 ? 0 : (c > side - 1 ? side - 1 : (int32_t)c);
}

/* Local box of river segment g grown by its radius + DREACH. */
static void seg_reach_box(const wm_probe *in, const wm_river_seg *g, double *b)
{
    const double m = g->r + DREACH;
    b[0] = (double)((g->ax < g->bx ? g->ax : g->bx) - in->X0) - m;
    b[1] = (double)((g->ay < g->by ? g->ay : g->by) - in->Y0) - m;
    b[2] = (double)((g->ax > g->bx ? g->ax : g->bx) - in->X0) + m;
    b[3] = (double)((g->ay > g->by ? g->ay : g->by) - in->Y0) + m;
}

static wm_status build_river_index(wm_probe *in, int32_t S)
{
    wm_cells_reset(&in->cells, S / DCELL + 1);
    in->wide = malloc((in->nsegs + 1) * sizeof *in->wide);
    if (!in->wide)
        return WM_ERR_NOMEM;
    in->nwide = 0;
    for (size_t i = 0; i < in->nsegs; i++)
    {
        double b[4];
        int32_t x0, x1, y0, y1;
        seg_reach_box(in, &in->s->segs[in->segs[i]], b);
        if (b[2] < 0 || b[3] < 0 || b[0] > S || b[1] > S)
            continue; /* never within reach of the block */
        x0 = dcell(in, b[0]);
        x1 = dcell(in, b[2]);
        y0 = dcell(in, b[1]);
        y1 = dcell(in, b[3]);
        if ((int64_t)(x1 - x0 + 1) * (y1 - y0 + 1) > WIDE)
        {
            in->wide[in->nwide++] = in->segs[i];
            continue;
        }
        for (int32_t cy = y0; cy <= y1; cy++)
            for (int32_t cx = x0; cx <= x1; cx++)
                if (!wm_cells_add(&in->cells, cx, cy, in->segs[i]))
                    return WM_ERR_NOMEM;
    }
    return wm_cells_index(&in->cells);
}

/* Distance from (x, y) (block-local, double) to segment (global ends). */
static double seg_dist(const wm_probe *in, int64_t ax, int64_t ay, int64_t bx,
                       int64_t by, double x, double y)
{
    const double x0 = (double)(ax - in->X0), y0 = (double)(ay - in->Y0);
    const double dx = (double)(bx - ax), dy = (double)(by - ay);
    const double l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((x - x0) * dx + (y - y0) * dy) / l2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double ex = x - (x0 + t * dx), ey = y - (y0 + t * dy);
    return sqrt(ex * ex + ey * ey);
}

/* Signed distance (lattice units, negative in water) from (x, y) to the
 * union of the block's inputs, in double precision; inputs farther than
 * `reach` (<= DREACH) are ignored (the result is then +reach or more).
 * (x, y) lies in the block square. */
double wm_probe_distance(const wm_probe *in, double x, double y, double reach)
{
    const wm_scene *s = in->s;
    double d = reach;
    const double gx = x + (double)in->X0, gy = y + (double)in->Y0;
    /* the segments within reach are in the point's cell, or wide */
    size_t c0, c1;
    const int32_t cx = dcell(in, x);
    wm_cells_row(&in->cells, dcell(in, y), cx, cx, &c0, &c1);
    const size_t n0 = c1 - c0;
    for (size_t i = 0; i < n0 + in->nwide; i++)
    {
        const wm_river_seg *g =
            &s->segs[i < n0 ? in->cells.item[c0 + i] : in->wide[i - n0]];
        const double m = g->r + reach;
        if (gx < (double)(g->ax < g->bx ? g->ax : g->bx) - m ||
            gx > (double)(g->ax > g->bx ? g->ax : g->bx) + m ||
            gy < (double)(g->ay < g->by ? g->ay : g->by) - m ||
            gy > (double)(g->ay > g->by ? g->ay : g->by) + m)
            continue;
        const double v = seg_dist(in, g->ax, g->ay, g->bx, g->by, x, y) - g->r;
        d = v < d ? v : d;
    }
    for (size_t k = 0; k < in->npolys; k++)
    {
        const uint32_t p = in->polys[k];
        const wm_box b = s->poly_box[p];
        if (gx < (double)b.x0 - reach || gx > (double)b.x1 + reach ||
            gy < (double)b.y0 - reach || gy > (double)b.y1 + reach)
            continue;
        int inside = 0;
        double dmin = INFINITY;
        for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
        {
            const wm_lake_edge *g = &s->edges[e];
            const double ay = (double)(g->ay - in->Y0);
            const double by = (double)(g->by - in->Y0);
            if ((ay > y) != (by > y))
            {
                const double ax = (double)(g->ax - in->X0);
                const double bxx = (double)(g->bx - in->X0);
                if (x < ax + (y - ay) * (bxx - ax) / (by - ay))
                    inside = !inside;
            }
            const double v = seg_dist(in, g->ax, g->ay, g->bx, g->by, x, y);
            dmin = v < dmin ? v : dmin;
        }
        const double v = inside ? -dmin : dmin;
        d = v < d ? v : d;
    }
    return d;
}

wm_status wm_probe_init(wm_probe *p, const wm_scene *s, int64_t bx, int64_t by)
{
    memset(p, 0, sizeof *p);
    p->s = s;
    if (s->nbx == 0 || bx < s->bx0 || by < s->by0 || bx >= s->bx0 + s->nbx ||
        by >= s->by0 + s->nby)
        return WM_OK;
    const int32_t S = s->n * WM_Q;
    const size_t blk = (size_t)((by - s->by0) * s->nbx + (bx - s->bx0));
    p->X0 = bx * (int64_t)S;
    p->Y0 = by * (int64_t)S;
    p->segs = s->blk_seg + s->blk_seg_start[blk];
    p->nsegs = s->blk_seg_start[blk + 1] - s->blk_seg_start[blk];
    p->polys = s->blk_poly + s->blk_poly_start[blk];
    p->npolys = s->blk_poly_start[blk + 1] - s->blk_poly_start[blk];
    if (build_river_index(p, S) != WM_OK)
    {
        wm_probe_free(p);
        return WM_ERR_NOMEM;
    }
    return WM_OK;
}

void wm_probe_free(wm_probe *p)
{
    if (!p)
        return;
    wm_cells_free(&p->cells);
    free(p->wide);
    p->wide = NULL;
    p->nwide = 0;
}
