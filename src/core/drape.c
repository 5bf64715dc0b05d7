/*
 * drape.c - heights of a block's mesh vertices from the levels of the
 * inputs (ELEVATION; the rule is in drape.h).
 *
 * Method. The block's items (wm_scene_items) go into two indexes over a
 * grid of CELL-wide cells of the block square: `near` holds each river
 * segment in the cells its capsule grown by WM_DRAPE_NEAR meets, row by row
 * (the segment clipped to the row's band), and each lake edge likewise;
 * `rows` holds every edge of the block's lake polygons by the cell rows its
 * half-open y range meets, for the even-odd ray cast to +x (edges beyond
 * the block count: a polygon's parity needs them all). A point's height is
 * then one ray cast over its row and one nearest-item search over its cell.
 *
 * Robustness: the ray cast is exact (integer differences, __int128
 * products); distances are double on exact integer differences, and ties
 * are broken by the item's global index, so the result does not depend on
 * the block or on the order of the index.
 *
 * Cost: O(items x cells they meet + lake edges x rows they span) to build,
 * O(items in the point's cell and row) per point.
 */
#include "drape.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Cell side, lattice units (32 pixels). */
#define CELL (32 * WM_Q)

typedef struct
{
    const wm_scene *s;
    const wm_drape *d;
    int64_t X0, Y0; /* block origin, global lattice */
    int64_t S;      /* block side, lattice units */
    int32_t side;   /* cells per side */
    uint32_t *ids;  /* the block's items: segments, then polygons */
    size_t nsegs, npolys;
    uint32_t *ledge; /* edges of the block's polygons (global indices) */
    uint32_t *lslot; /* per ledge: its polygon's slot in ids + nsegs */
    size_t nledge;
    wm_cells near, rows; /* near: k < nsegs a segment, else ledge k - nsegs */
    uint8_t *par;        /* per polygon slot: ray-cast parity (bit 0) and
                            listed in toggled (bit 1); 0 between queries */
    uint32_t *toggled;   /* the slots a query touched (scratch) */
} index_t;

static int32_t cell_of(const index_t *ix, double v)
{
    const double c = floor(v / CELL);
    return c < 0 ? 0 : (c >= ix->side ? ix->side - 1 : (int32_t)c);
}

/* The x range [*lo, *hi] of segment a -> b (local doubles) within the band
 * y0 <= y <= y1; 0 when it has none there. */
static int band_span(double ax, double ay, double bx, double by, double y0,
                     double y1, double *lo, double *hi)
{
    double t0 = 0, t1 = 1;
    const double dy = by - ay;
    if (dy == 0)
    {
        if (ay < y0 || ay > y1)
            return 0;
    }
    else
    {
        double ta = (y0 - ay) / dy, tb = (y1 - ay) / dy;
        if (ta > tb)
        {
            const double t = ta;
            ta = tb;
            tb = t;
        }
        t0 = ta > 0 ? ta : 0;
        t1 = tb < 1 ? tb : 1;
        if (t0 > t1)
            return 0;
    }
    const double xa = ax + t0 * (bx - ax), xb = ax + t1 * (bx - ax);
    *lo = xa < xb ? xa : xb;
    *hi = xa < xb ? xb : xa;
    return 1;
}

/* Registers item k (segment or edge a -> b, global) in the cells its
 * distance-g neighbourhood meets. */
static int add_near(index_t *ix, uint32_t k, int64_t ax, int64_t ay, int64_t bx,
                    int64_t by, double g)
{
    const double lax = (double)(ax - ix->X0), lay = (double)(ay - ix->Y0);
    const double lbx = (double)(bx - ix->X0), lby = (double)(by - ix->Y0);
    const double ylo = (lay < lby ? lay : lby) - g;
    const double yhi = (lay < lby ? lby : lay) + g;
    if (yhi < 0 || ylo > (double)ix->S)
        return 1;
    const int32_t r0 = cell_of(ix, ylo), r1 = cell_of(ix, yhi);
    for (int32_t r = r0; r <= r1; r++)
    {
        double lo, hi;
        if (!band_span(lax, lay, lbx, lby, (double)r * CELL - g,
                       (double)(r + 1) * CELL + g, &lo, &hi))
            continue;
        if (hi + g < 0 || lo - g > (double)ix->S)
            continue;
        const int32_t c1 = cell_of(ix, hi + g);
        for (int32_t c = cell_of(ix, lo - g); c <= c1; c++)
            if (!wm_cells_add(&ix->near, c, r, k))
                return 0;
    }
    return 1;
}

static void index_free(index_t *ix)
{
    free(ix->ids);
    free(ix->ledge);
    free(ix->lslot);
    free(ix->par);
    free(ix->toggled);
    wm_cells_free(&ix->near);
    wm_cells_free(&ix->rows);
}

static wm_status index_build(index_t *ix, const wm_scene *s, const wm_drape *d,
                             int64_t bx, int64_t by)
{
    memset(ix, 0, sizeof *ix);
    ix->s = s;
    ix->d = d;
    ix->S = (int64_t)s->n * WM_Q;
    ix->X0 = bx * ix->S;
    ix->Y0 = by * ix->S;
    ix->side = (int32_t)(ix->S / CELL + 1);
    const wm_box blk = {bx, by, bx, by};
    if (wm_scene_items(s, blk, &ix->ids, &ix->nsegs, &ix->npolys) != WM_OK)
        return WM_ERR_NOMEM;
    for (size_t i = 0; i < ix->npolys; i++)
    {
        const uint32_t p = ix->ids[ix->nsegs + i];
        ix->nledge += s->poly_start[p + 1] - s->poly_start[p];
    }
    if (ix->nsegs + ix->nledge > UINT32_MAX)
        return WM_ERR_NOMEM;
    ix->ledge = malloc((ix->nledge + 1) * sizeof *ix->ledge);
    ix->lslot = malloc((ix->nledge + 1) * sizeof *ix->lslot);
    ix->par = calloc(ix->npolys + 1, 1);
    ix->toggled = malloc((ix->npolys + 1) * sizeof *ix->toggled);
    if (!ix->ledge || !ix->lslot || !ix->par || !ix->toggled)
        return WM_ERR_NOMEM;
    wm_cells_reset(&ix->near, ix->side);
    wm_cells_reset(&ix->rows, ix->side);
    for (size_t i = 0; i < ix->nsegs; i++)
    {
        const wm_river_seg *g = &s->segs[ix->ids[i]];
        if (!add_near(ix, (uint32_t)i, g->ax, g->ay, g->bx, g->by,
                      g->r + WM_DRAPE_NEAR))
            return WM_ERR_NOMEM;
    }
    size_t k = 0;
    for (size_t i = 0; i < ix->npolys; i++)
    {
        const uint32_t p = ix->ids[ix->nsegs + i];
        for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++, k++)
        {
            const wm_lake_edge *g = &s->edges[e];
            ix->ledge[k] = (uint32_t)e;
            ix->lslot[k] = (uint32_t)i;
            if (!add_near(ix, (uint32_t)(ix->nsegs + k), g->ax, g->ay, g->bx,
                          g->by, WM_DRAPE_NEAR))
                return WM_ERR_NOMEM;
            /* the rows of its half-open y range [min, max) */
            const int64_t y0 = (g->ay < g->by ? g->ay : g->by) - ix->Y0;
            const int64_t y1 = (g->ay < g->by ? g->by : g->ay) - ix->Y0;
            if (y0 == y1 || y1 <= 0 || y0 > ix->S)
                continue;
            const int32_t r1 = cell_of(ix, (double)(y1 - 1));
            for (int32_t r = cell_of(ix, (double)y0); r <= r1; r++)
                if (!wm_cells_add(&ix->rows, 0, r, (uint32_t)k))
                    return WM_ERR_NOMEM;
        }
    }
    if (wm_cells_index(&ix->near) != WM_OK ||
        wm_cells_index(&ix->rows) != WM_OK)
        return WM_ERR_NOMEM;
    return WM_OK;
}

/* The lowest body of the polygons containing global point (X, Y), even-odd
 * with the field's half-open rule; -1 when none does. */
static int32_t lake_body(index_t *ix, int64_t X, int64_t Y)
{
    if (!ix->npolys)
        return -1;
    size_t b, e, nt = 0;
    const int32_t r = cell_of(ix, (double)(Y - ix->Y0));
    wm_cells_row(&ix->rows, r, 0, 0, &b, &e);
    for (size_t i = b; i < e; i++)
    {
        const uint32_t k = ix->rows.item[i];
        if (!wm_edge_crosses_ray(&ix->s->edges[ix->ledge[k]], X, Y))
            continue;
        const uint32_t slot = ix->lslot[k];
        if (!ix->par[slot]) /* first toggle: remember the slot */
            ix->toggled[nt++] = slot;
        ix->par[slot] ^= 1;
        ix->par[slot] |= 2; /* bit 1: in toggled[] */
    }
    int32_t body = -1;
    for (size_t i = 0; i < nt; i++)
    {
        const uint32_t slot = ix->toggled[i];
        if (ix->par[slot] & 1)
        {
            const int32_t bi = ix->d->poly_body[ix->ids[ix->nsegs + slot]];
            body = body < 0 || bi < body ? bi : body;
        }
        ix->par[slot] = 0;
    }
    return body;
}

/* Squared distance from (px, py) to segment [(0, 0), (abx, aby)] and the
 * parameter of the projection, clamped to [0, 1]. */
static double seg_d2(double px, double py, double abx, double aby, double *t)
{
    const double len2 = abx * abx + aby * aby;
    double u = len2 > 0 ? (px * abx + py * aby) / len2 : 0;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    *t = u;
    const double dx = px - u * abx, dy = py - u * aby;
    return dx * dx + dy * dy;
}

/* A point's height, its gradient (per lattice unit) and its lake body. */
typedef struct
{
    double z, gx, gy;
    int32_t body;
} height_t;

/* Height of a point at parameter t of river segment g (index i): its
 * levels interpolated through the knee; the gradient runs along the axis
 * (level bank to bank), 0 beyond the ends (the caps). */
static height_t on_segment(const wm_drape *d, const wm_river_seg *g, uint32_t i,
                           double t)
{
    const double tk = d->tk[i], zk = d->zk[i];
    height_t h = {0, 0, 0, -1};
    double dzdt;
    if (t <= tk)
    {
        h.z = tk > 0 ? d->za[i] + t / tk * (zk - d->za[i]) : zk;
        dzdt = tk > 0 ? (zk - d->za[i]) / tk : 0;
    }
    else
    {
        h.z = zk + (t - tk) / (1 - tk) * (d->zb[i] - zk);
        dzdt = (d->zb[i] - zk) / (1 - tk);
    }
    const double abx = (double)(g->bx - g->ax), aby = (double)(g->by - g->ay);
    const double len2 = abx * abx + aby * aby;
    if (t > 0 && t < 1 && len2 > 0)
    {
        h.gx = dzdt * abx / len2;
        h.gy = dzdt * aby / len2;
    }
    return h;
}

/* The nearest item of the block to global (X, Y) among k in [b, e) of
 * `near` (all items when items is NULL) and the height it gives into *h.
 * Returns 0 when there is none. */
static int nearest(const index_t *ix, int64_t X, int64_t Y,
                   const uint32_t *items, size_t n, height_t *h)
{
    const wm_scene *s = ix->s;
    double best = INFINITY, bt = 0;
    int found = 0, blake = 0;
    uint32_t bglob = 0;
    for (size_t i = 0; i < n; i++)
    {
        const uint32_t k = items ? items[i] : (uint32_t)i;
        const int lake = k >= ix->nsegs;
        const uint32_t glob = lake ? ix->ledge[k - ix->nsegs] : ix->ids[k];
        int64_t ax, ay, bx, by;
        double r = 0;
        if (lake)
        {
            const wm_lake_edge *g = &s->edges[glob];
            ax = g->ax, ay = g->ay, bx = g->bx, by = g->by;
        }
        else
        {
            const wm_river_seg *g = &s->segs[glob];
            ax = g->ax, ay = g->ay, bx = g->bx, by = g->by, r = g->r;
        }
        double t;
        const double d =
            sqrt(seg_d2((double)(X - ax), (double)(Y - ay), (double)(bx - ax),
                        (double)(by - ay), &t)) -
            r;
        const int better =
            !found || d < best ||
            (d == best && (lake > blake || (lake == blake && glob < bglob)));
        if (!better)
            continue;
        found = 1;
        best = d;
        bt = t;
        blake = lake;
        bglob = glob;
    }
    if (!found)
        return 0;
    if (blake)
    {
        /* the polygon holding edge bglob */
        const size_t p = wm_run_of(ix->s->poly_start, ix->s->npolys, bglob);
        h->body = ix->d->poly_body[p];
        h->z = ix->d->body_level[h->body];
        h->gx = h->gy = 0;
    }
    else
        *h = on_segment(ix->d, &s->segs[bglob], bglob, bt);
    return 1;
}

/* Height, gradient and body of block-local point p. */
static height_t height(index_t *ix, wm_pt p)
{
    const int64_t X = ix->X0 + p.x, Y = ix->Y0 + p.y;
    height_t h = {0, 0, 0, lake_body(ix, X, Y)};
    if (h.body >= 0)
    {
        h.z = ix->d->body_level[h.body]; /* flat */
        return h;
    }
    size_t b = 0, e = 0;
    const int32_t c = cell_of(ix, (double)p.x), r = cell_of(ix, (double)p.y);
    if (ix->near.nocc)
        wm_cells_row(&ix->near, r, c, c, &b, &e);
    if (!nearest(ix, X, Y, ix->near.item + b, e - b, &h))
        nearest(ix, X, Y, NULL, ix->nsegs + ix->nledge, &h);
    return h; /* (no item at all: an empty block has no vertex) */
}

wm_status wm_drape_block(const wm_scene *s, const wm_drape *d,
                         wm_block_result *res)
{
    index_t ix;
    memset(&ix, 0, sizeof ix);
    const size_t np = wm_block_npoints(res);
    double *z = calloc(np + 1, sizeof *z);
    double *g = calloc(2 * np + 1, sizeof *g);
    int32_t *pb = malloc((res->npolys + 1) * sizeof *pb);
    wm_status st = WM_ERR_NOMEM;
    if (!z || !g || !pb || index_build(&ix, s, d, res->bx, res->by) != WM_OK)
        goto done;
    for (size_t p = 0; p < res->npolys; p++)
        pb[p] = -1;
    for (size_t k = 0; k < np; k++) /* ring points, then Steiner points */
    {
        const height_t h = height(&ix, wm_block_point(res, k));
        z[k] = h.z;
        g[2 * k] = h.gx;
        g[2 * k + 1] = h.gy;
        if (h.body < 0 || k >= res->rings.npts)
            continue;
        const size_t p = wm_run_of(res->rings.start, res->rings.nrings, k);
        const size_t poly = wm_run_of(res->poly_ring, res->npolys, p);
        pb[poly] = pb[poly] < 0 || h.body < pb[poly] ? h.body : pb[poly];
    }
    free(res->z);
    free(res->zgrad);
    free(res->poly_body);
    res->z = z;
    res->zgrad = g;
    res->poly_body = pb;
    z = g = NULL;
    pb = NULL;
    st = WM_OK;
done:
    index_free(&ix);
    free(z);
    free(g);
    free(pb);
    return st;
}
