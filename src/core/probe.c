/*
 * probe.c - direct evaluation of the signed distance to the union of a
 * block's inputs at any point.
 *
 * Method: the minimum over the river segments within reach (from a grid of
 * 16-pixel cells over the block, 8 or 4 where the block has many items:
 * probe_cell) of |p - segment| - radius, and over the
 * block's lake polygons of +-|p - nearest edge| (negative inside, even-odd
 * by a ray crossing count), as the field defines a sample (field.c). The
 * lake edges are indexed twice: by that cell for the distances, and by
 * band of 4 sample rows for the ray (an edge in every band its half-open y
 * range meets; one band beyond each side of the block), so a query costs
 * the items near the point plus the edges its row crosses, never a whole
 * lake.
 * wm_probe_crossings finds the crossings of the union's boundary with an
 * axis-aligned segment exactly: the interval of the segment's line inside
 * each capsule near it (its two end discs and the rectangle between them),
 * and for each lake polygon the pieces between its edges' crossings, each
 * classed by the exact ray rule at a lattice point inside it; the union of
 * the water intervals gives the crossings. On a block side a lake edge
 * lying along it is water only where the points a unit across are, in both
 * blocks (side_rule), as a sample on a block line (field.c).
 * Cost: building the indexes is O(segments x cells they reach + lake edges
 * x bands they span); a query as above.
 * Robustness: a point with integer coordinates gets its ray test in exact
 * integer arithmetic, and every difference of coordinates is formed from
 * integers before floating point, so a query's result is a pure function
 * of the point's global position and the inputs, whichever block asks. The
 * distances choose (which corner to try, which way a saddle goes); validity
 * stays with the exact predicates of lattice.h.
 */
#include "probe.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct wm_probe_toggle
{
    double t;   /* where an edge of polygon k crosses the segment */
    uint32_t k; /* polygon slot */
};

/* Largest cell of the item indexes, and the reach they serve (queries ask
 * for at most DREACH); an item whose box touches more than WIDE cells of
 * DCELL (that area at smaller cells) is listed apart. */
#define DCELL (16 * WM_Q)
#define DREACH WM_PROBE_REACH
#define WIDE 1024
/* Two boundaries closer than WM_COINCIDE (scene.h) along a segment are
 * one; any farther apart bound a feature, kept at least a lattice unit wide
 * so that it stays whole to its tip. */

/* Height of a band of the ray index: 4 sample rows. */
#define RBAND (4 * WM_Q)

/* Index cell (clamped to the block) of the local coordinate v. */
static int32_t dcell(const wm_probe *in, double v)
{
    const double c = floor(v / in->cell);
    const int32_t side = in->cells.side;
    return c < 0 ? 0 : (c > side - 1 ? side - 1 : (int32_t)c);
}

/* Band (clamped) of the ray index holding local y; band 0 lies below the
 * block, and the last above it (side_rule asks a lattice unit outside). */
static int32_t rband(const wm_probe *in, double y)
{
    const double c = floor(y / RBAND) + 1;
    const int32_t side = in->lrows.side;
    return c < 0 ? 0 : (c > side - 1 ? side - 1 : (int32_t)c);
}

/* Local box of segment (a, b) grown by m. */
static void reach_box(const wm_probe *in, int64_t ax, int64_t ay, int64_t bx,
                      int64_t by, double m, double *b)
{
    b[0] = (double)((ax < bx ? ax : bx) - in->X0) - m;
    b[1] = (double)((ay < by ? ay : by) - in->Y0) - m;
    b[2] = (double)((ax > bx ? ax : bx) - in->X0) + m;
    b[3] = (double)((ay > by ? ay : by) - in->Y0) + m;
}

/* Registers item in the cells of g its local box b touches, or in wide[]
 * when that is more than WIDE cells. Returns 0 when out of memory. */
static int register_box(const wm_probe *in, wm_cells *g, const double *b,
                        int32_t S, uint32_t item, uint32_t *wide, size_t *nwide)
{
    if (b[2] < 0 || b[3] < 0 || b[0] > S || b[1] > S)
        return 1; /* never within reach of the block */
    const int32_t x0 = dcell(in, b[0]), x1 = dcell(in, b[2]);
    const int32_t y0 = dcell(in, b[1]), y1 = dcell(in, b[3]);
    const int64_t f = DCELL / in->cell;
    if ((int64_t)(x1 - x0 + 1) * (y1 - y0 + 1) > WIDE * f * f)
    {
        wide[(*nwide)++] = item;
        return 1;
    }
    for (int32_t cy = y0; cy <= y1; cy++)
        for (int32_t cx = x0; cx <= x1; cx++)
            if (!wm_cells_add(g, cx, cy, item))
                return 0;
    return 1;
}

static wm_status build_river_index(wm_probe *in, int32_t S)
{
    wm_cells_reset(&in->cells, S / in->cell + 1);
    in->wide = malloc((in->nsegs + 1) * sizeof *in->wide);
    if (!in->wide)
        return WM_ERR_NOMEM;
    for (size_t i = 0; i < in->nsegs; i++)
    {
        const wm_river_seg *g = &in->s->segs[in->segs[i]];
        double b[4];
        reach_box(in, g->ax, g->ay, g->bx, g->by, g->r + DREACH, b);
        if (!register_box(in, &in->cells, b, S, in->segs[i], in->wide,
                          &in->nwide))
            return WM_ERR_NOMEM;
    }
    return wm_cells_index(&in->cells);
}

static wm_status build_lake_index(wm_probe *in, int32_t S)
{
    const wm_scene *s = in->s;
    size_t n = 0;
    for (size_t k = 0; k < in->npolys; k++)
        n += s->poly_start[in->polys[k] + 1] - s->poly_start[in->polys[k]];
    if (n >= UINT32_MAX)
        return WM_ERR_NOMEM; /* items are 32-bit */
    in->ledge = malloc((n + 1) * sizeof *in->ledge);
    in->lwide = malloc((n + 1) * sizeof *in->lwide);
    in->par = calloc(in->npolys + 1, 1);
    in->dmin = malloc((in->npolys + 1) * sizeof *in->dmin);
    in->touched = malloc((in->npolys + 1) * sizeof *in->touched);
    if (!in->ledge || !in->lwide || !in->par || !in->dmin || !in->touched)
        return WM_ERR_NOMEM;
    wm_cells_reset(&in->lcells, S / in->cell + 1);
    wm_cells_reset(&in->lrows, S / RBAND + 3);
    const int32_t nb = in->lrows.side;
    for (size_t k = 0; k < in->npolys; k++)
    {
        const uint32_t p = in->polys[k];
        for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
        {
            const wm_lake_edge *g = &s->edges[e];
            const uint32_t j = (uint32_t)in->nledge++;
            in->ledge[j] = (struct wm_probe_edge){(uint32_t)e, (uint32_t)k};
            double b[4];
            reach_box(in, g->ax, g->ay, g->bx, g->by, DREACH, b);
            if (!register_box(in, &in->lcells, b, S, j, in->lwide, &in->nlwide))
                return WM_ERR_NOMEM;
            if (g->ay == g->by)
                continue; /* never crosses a ray */
            /* bands met by the half-open range [y0, y1) */
            const int64_t y0 = (g->ay < g->by ? g->ay : g->by) - in->Y0;
            const int64_t y1 = (g->ay > g->by ? g->ay : g->by) - in->Y0;
            if (y1 <= -RBAND || y0 > S + RBAND)
                continue;
            int64_t b0 = wm_floordiv(y0, RBAND) + 1,
                    b1 = wm_floordiv(y1 - 1, RBAND) + 1;
            b0 = b0 < 0 ? 0 : b0;
            b1 = b1 > nb - 1 ? nb - 1 : b1;
            for (int64_t r = b0; r <= b1; r++)
                if (!wm_cells_add(&in->lrows, 0, (int32_t)r, j))
                    return WM_ERR_NOMEM;
        }
    }
    if (wm_cells_index(&in->lcells) != WM_OK)
        return WM_ERR_NOMEM;
    return wm_cells_index(&in->lrows);
}

double wm_probe_seg_dist(const wm_probe *in, int64_t ax, int64_t ay, int64_t bx,
                         int64_t by, double x, double y)
{
    const double px = x - (double)(ax - in->X0), py = y - (double)(ay - in->Y0);
    const double dx = (double)(bx - ax), dy = (double)(by - ay);
    const double l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? (px * dx + py * dy) / l2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double ex = px - t * dx, ey = py - t * dy;
    return sqrt(ex * ex + ey * ey);
}

/* Whether the ray from (x, y) towards +x crosses lake edge g (half-open
 * rule on y: vertices on the ray count once, horizontal edges never).
 * Exact when (x, y) is a lattice point. */
static int ray_crosses(const wm_probe *in, const wm_lake_edge *g, double x,
                       double y)
{
    if (x == floor(x) && y == floor(y) && fabs(x) < 0x1p52 && fabs(y) < 0x1p52)
    {
        const int64_t gx = (int64_t)x + in->X0, gy = (int64_t)y + in->Y0;
        if ((g->ay > gy) == (g->by > gy))
            return 0;
        const int64_t dy = g->by - g->ay;
        const wm_i128 lhs = (wm_i128)(gx - g->ax) * dy;
        const wm_i128 rhs = (wm_i128)(gy - g->ay) * (g->bx - g->ax);
        return dy > 0 ? lhs < rhs : lhs > rhs;
    }
    const double ay = (double)(g->ay - in->Y0), by = (double)(g->by - in->Y0);
    if ((ay > y) == (by > y))
        return 0;
    const double px = x - (double)(g->ax - in->X0);
    return px < (y - ay) * (double)(g->bx - g->ax) / (by - ay);
}

/* Marks polygon slot k touched by the current query. */
static void touch(wm_probe *in, uint32_t k, size_t *nt, double reach)
{
    if (in->par[k] & 2)
        return;
    in->par[k] = 2;
    in->dmin[k] = reach;
    in->touched[(*nt)++] = k;
}

/* Per polygon slot near (x, y): parity (bit 0 of par[]) by the ray index. */
static size_t lake_parities(wm_probe *in, double x, double y, double reach)
{
    size_t nt = 0, b, e;
    wm_cells_row(&in->lrows, rband(in, y), 0, 0, &b, &e);
    for (size_t i = b; i < e; i++)
    {
        const struct wm_probe_edge *le = &in->ledge[in->lrows.item[i]];
        if (ray_crosses(in, &in->s->edges[le->e], x, y))
        {
            touch(in, le->k, &nt, reach);
            in->par[le->k] ^= 1;
        }
    }
    return nt;
}

double wm_probe_distance(wm_probe *in, double x, double y, double reach)
{
    const wm_scene *s = in->s;
    double d = reach;
    const double gx = x + (double)in->X0, gy = y + (double)in->Y0;
    /* the segments within reach are in the point's cell, or wide */
    size_t c0, c1;
    const int32_t cx = dcell(in, x), cy = dcell(in, y);
    wm_cells_row(&in->cells, cy, cx, cx, &c0, &c1);
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
        const double v =
            wm_probe_seg_dist(in, g->ax, g->ay, g->bx, g->by, x, y) - g->r;
        d = v < d ? v : d;
    }
    if (in->nledge == 0)
        return d;
    size_t nt = lake_parities(in, x, y, reach);
    wm_cells_row(&in->lcells, cy, cx, cx, &c0, &c1);
    const size_t m0 = c1 - c0;
    for (size_t i = 0; i < m0 + in->nlwide; i++)
    {
        const struct wm_probe_edge *le =
            &in->ledge[i < m0 ? in->lcells.item[c0 + i] : in->lwide[i - m0]];
        const wm_lake_edge *g = &s->edges[le->e];
        if (gx < (double)(g->ax < g->bx ? g->ax : g->bx) - reach ||
            gx > (double)(g->ax > g->bx ? g->ax : g->bx) + reach ||
            gy < (double)(g->ay < g->by ? g->ay : g->by) - reach ||
            gy > (double)(g->ay > g->by ? g->ay : g->by) + reach)
            continue;
        touch(in, le->k, &nt, reach);
        const double v =
            wm_probe_seg_dist(in, g->ax, g->ay, g->bx, g->by, x, y);
        in->dmin[le->k] = v < in->dmin[le->k] ? v : in->dmin[le->k];
    }
    for (size_t i = 0; i < nt; i++)
    {
        const uint32_t k = in->touched[i];
        const double v = (in->par[k] & 1) ? -in->dmin[k] : in->dmin[k];
        d = v < d ? v : d;
        in->par[k] = 0;
    }
    return d;
}

/* ---- crossings of a segment ------------------------------------------- */

/* Appends [lo, hi] clipped to [0, L] to the pairs *v (*n of them, room
 * for *cap values); 0 when out of memory. */
static int push_interval(double **v, size_t *cap, size_t *n, double lo,
                         double hi, int32_t L)
{
    lo = lo < 0 ? 0 : lo;
    hi = hi > L ? L : hi;
    if (!(lo <= hi))
        return 1;
    if (!wm_grow((void **)v, cap, 2 * (*n + 1), sizeof **v))
        return 0;
    (*v)[2 * *n] = lo;
    (*v)[2 * *n + 1] = hi;
    (*n)++;
    return 1;
}

/* Appends the water interval [lo, hi] clipped to [0, L]. */
static int add_interval(wm_probe *in, size_t *n, double lo, double hi,
                        int32_t L)
{
    return push_interval(&in->iv, &in->ivcap, n, lo, hi, L);
}

/* The t-range where alpha * t + beta lies in [lo, hi] intersected with
 * [*t0, *t1]. */
static void clip_linear(double alpha, double beta, double lo, double hi,
                        double *t0, double *t1)
{
    if (alpha == 0)
    {
        if (beta < lo || beta > hi)
            *t1 = -INFINITY;
        return;
    }
    double a = (lo - beta) / alpha, b = (hi - beta) / alpha;
    if (a > b)
    {
        const double c = a;
        a = b;
        b = c;
    }
    *t0 = a > *t0 ? a : *t0;
    *t1 = b < *t1 ? b : *t1;
}

int wm_probe_capsule_interval(const wm_river_seg *g, int64_t Gx, int64_t Gy,
                              int vertical, double *lo, double *hi)
{
    /* coordinates relative to G, axis first */
    const double ax = (double)(vertical ? g->ay - Gy : g->ax - Gx);
    const double ay = (double)(vertical ? g->ax - Gx : g->ay - Gy);
    const double bx = (double)(vertical ? g->by - Gy : g->bx - Gx);
    const double by = (double)(vertical ? g->bx - Gx : g->by - Gy);
    const double r = g->r;
    *lo = INFINITY;
    *hi = -INFINITY;
    /* end discs: (t - ax)^2 + ay^2 <= r^2 */
    const double e[2][2] = {{ax, ay}, {bx, by}};
    for (int k = 0; k < 2; k++)
    {
        const double h2 = r * r - e[k][1] * e[k][1];
        if (h2 < 0)
            continue;
        const double h = sqrt(h2);
        *lo = fmin(*lo, e[k][0] - h);
        *hi = fmax(*hi, e[k][0] + h);
    }
    /* the rectangle: 0 <= (p - a).d <= |d|^2, |d x (p - a)| <= r |d| */
    const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
    if (l2 > 0)
    {
        double t0 = -INFINITY, t1 = INFINITY;
        /* p = (t, 0): (p - a).d = t dx - (ax dx + ay dy) */
        clip_linear(dx, -(ax * dx + ay * dy), 0, l2, &t0, &t1);
        /* d x (p - a) = dx (0 - ay) - dy (t - ax) */
        const double rl = r * sqrt(l2);
        clip_linear(-dy, -dx * ay + dy * ax, -rl, rl, &t0, &t1);
        if (t0 <= t1)
        {
            *lo = fmin(*lo, t0);
            *hi = fmax(*hi, t1);
        }
    }
    return *lo <= *hi;
}

static int cmp_toggle(const void *a, const void *b)
{
    const struct wm_probe_toggle *x = a, *y = b;
    if (x->k != y->k)
        return x->k < y->k ? -1 : 1;
    return (x->t > y->t) - (x->t < y->t);
}

static int cmp_interval(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* A query's lists hold a few entries: sorted by insertion below this
 * many (qsort's call costs more there), by qsort above. */
#define SMALL_SORT 16

_Static_assert(sizeof(struct wm_probe_toggle) <= 16 && 2 * sizeof(double) <= 16,
               "sort_small swaps through 16 bytes");

/* Sorts n elements of `size` (<= 16) bytes at base by cmp (stable). */
static void sort_small(void *base, size_t n, size_t size,
                       int (*cmp)(const void *, const void *))
{
    if (n > SMALL_SORT)
    {
        qsort(base, n, size, cmp);
        return;
    }
    unsigned char *b = base, tmp[16];
    for (size_t i = 1; i < n; i++)
        for (size_t q = i; q > 0 && cmp(b + (q - 1) * size, b + q * size) > 0;
             q--)
        {
            memcpy(tmp, b + q * size, size);
            memcpy(b + q * size, b + (q - 1) * size, size);
            memcpy(b + (q - 1) * size, tmp, size);
        }
}

/* Lake edge g in the segment's frame: along the axis u, across it w (the
 * segment's line is w == 0), from G. */
static void edge_frame(const wm_lake_edge *g, int64_t Gx, int64_t Gy,
                       int vertical, int64_t *au, int64_t *aw, int64_t *bu,
                       int64_t *bw)
{
    *au = vertical ? g->ay - Gy : g->ax - Gx;
    *aw = vertical ? g->ax - Gx : g->ay - Gy;
    *bu = vertical ? g->by - Gy : g->bx - Gx;
    *bw = vertical ? g->bx - Gx : g->by - Gy;
}

/* Where lake edge g crosses the segment's line (the half-open rule across
 * the line), as t; returns 0 when it does not. */
static int edge_toggle(const wm_lake_edge *g, int64_t Gx, int64_t Gy,
                       int vertical, double *t)
{
    int64_t au, aw, bu, bw;
    edge_frame(g, Gx, Gy, vertical, &au, &aw, &bu, &bw);
    if ((aw > 0) == (bw > 0))
        return 0;
    const wm_i128 num = (wm_i128)(0 - aw) * (bu - au);
    *t = (double)au + (double)num / (double)(bw - aw);
    return 1;
}

/* The part of the segment [0, L] that lake edge g covers (closed), as a
 * water interval: a lake's boundary is water, as the field has it (its
 * distance is 0 there), whatever the ray rule says of its points. Only an
 * edge along the segment's line or through one of its ends gives one
 * (where it crosses inside, its toggle does the work). Returns whether g
 * passes through the segment's start P, or -1 when out of memory. */
static int edge_cover(wm_probe *in, const wm_lake_edge *g, int64_t Gx,
                      int64_t Gy, int vertical, int32_t L, size_t *niv)
{
    int64_t au, aw, bu, bw;
    edge_frame(g, Gx, Gy, vertical, &au, &aw, &bu, &bw);
    if ((aw > 0 && bw > 0) || (aw < 0 && bw < 0) || (au > L && bu > L) ||
        (au < 0 && bu < 0))
        return 0;
    if (aw == 0 && bw == 0) /* along the line */
    {
        const double lo = (double)(au < bu ? au : bu);
        const double hi = (double)(au > bu ? au : bu);
        /* noted apart too: on a block side, side_rule decides it */
        if (!add_interval(in, niv, lo, hi, L) ||
            !push_interval(&in->dv, &in->dvcap, &in->ndv, lo, hi, L))
            return -1;
        return (au <= 0 && bu >= 0) || (bu <= 0 && au >= 0);
    }
    int at_p = 0;
    for (int64_t t = 0; t <= L; t += L) /* through an end */
        if ((wm_i128)(bu - au) * (0 - aw) == (wm_i128)(bw - aw) * (t - au))
        {
            if (!add_interval(in, niv, (double)t, (double)t, L))
                return -1;
            at_p |= t == 0;
        }
    return at_p;
}

/* Gathers into in->tg where the lake edges near the segment cross it
 * (inside it), and into in->iv (*niv) the parts of it they cover (see
 * edge_cover); returns how many toggles, or -1 when out of memory. */
static long lake_toggles(wm_probe *in, int64_t Gx, int64_t Gy, wm_pt P,
                         int vertical, int32_t L, size_t *niv)
{
    const wm_scene *s = in->s;
    const double mx = P.x + (vertical ? 0 : L / 2.0);
    const double my = P.y + (vertical ? L / 2.0 : 0);
    size_t c0, c1, ntg = 0;
    const int32_t cx = dcell(in, mx), cy = dcell(in, my);
    wm_cells_row(&in->lcells, cy, cx, cx, &c0, &c1);
    const size_t m0 = c1 - c0;
    for (size_t i = 0; i < m0 + in->nlwide; i++)
    {
        const struct wm_probe_edge *le =
            &in->ledge[i < m0 ? in->lcells.item[c0 + i] : in->lwide[i - m0]];
        const wm_lake_edge *g = &s->edges[le->e];
        const int at_p = edge_cover(in, g, Gx, Gy, vertical, L, niv);
        if (at_p < 0)
            return -1;
        /* an edge through P toggles there: the ray rule's class of P, a
         * boundary point, is not that of the piece after it, which is
         * then classed at a point inside */
        double t = 0;
        if (!at_p &&
            (!edge_toggle(g, Gx, Gy, vertical, &t) || !(t > 0 && t < L)))
            continue;
        if (!wm_grow((void **)&in->tg, &in->tgcap, ntg + 1, sizeof *in->tg))
            return -1;
        in->tg[ntg++] = (struct wm_probe_toggle){t, le->k};
    }
    return (long)ntg;
}

/* Appends the water intervals of the lake polygons along the segment,
 * given their ntg toggles in in->tg. */
static int lake_intervals(wm_probe *in, wm_pt P, int vertical, int32_t L,
                          size_t ntg, size_t *niv)
{
    const wm_scene *s = in->s;
    if (ntg > 1)
        sort_small(in->tg, ntg, sizeof *in->tg, cmp_toggle);
    /* every polygon odd at P (the ray) or toggling inside: its pieces */
    size_t nt = lake_parities(in, P.x, P.y, 0);
    for (size_t i = 0; i < ntg; i++)
        touch(in, in->tg[i].k, &nt, 0);
    /* in slot order, as the toggles */
    for (size_t i = 1; i < nt; i++)
        for (size_t q = i; q > 0 && in->touched[q - 1] > in->touched[q]; q--)
        {
            const uint32_t x = in->touched[q];
            in->touched[q] = in->touched[q - 1];
            in->touched[q - 1] = x;
        }
    size_t j = 0;
    for (size_t q = 0; q < nt; q++)
    {
        const uint32_t k = in->touched[q];
        /* polygon k's toggles: tg[j0 .. j1) (sorted by slot) */
        while (j < ntg && in->tg[j].k < k)
            j++;
        size_t j1 = j;
        while (j1 < ntg && in->tg[j1].k == k)
            j1++;
        double from = 0;
        int odd = in->par[k] & 1;
        for (size_t i = j; i <= j1; i++)
        {
            const double to = i < j1 ? in->tg[i].t : L;
            if (i > j)
            {
                /* the piece's class by the exact ray rule at a lattice
                 * point inside it, not at a toggle (an edge through a
                 * lattice point toggles there, and the rule's class of a
                 * point of an edge may be either: an island 0.1 pixel wide
                 * in a lake was lost so); the last piece's may be the
                 * segment's end; a piece with none, narrower than a unit,
                 * takes the other class than the piece before it, across
                 * the edge crossing the segment there (a lake cut into
                 * pieces meeting at a point at a small angle: the thin tip
                 * of one between the others was land), but after an edge
                 * through P (t = 0), where the class of P may be either,
                 * keeps it */
                double c = ceil(from), f = floor(to);
                c += c == from; /* from is a toggle */
                f -= i < j1 && f == to;
                if (!(c <= f && c >= 0 && f <= L))
                    odd ^= from > 0;
                else
                {
                    const double t = floor((c + f) / 2);
                    const double x = P.x + (vertical ? 0 : t);
                    const double y = P.y + (vertical ? t : 0);
                    odd = 0;
                    size_t b, e;
                    wm_cells_row(&in->lrows, rband(in, y), 0, 0, &b, &e);
                    for (size_t r = b; r < e; r++)
                    {
                        const struct wm_probe_edge *le =
                            &in->ledge[in->lrows.item[r]];
                        if (le->k == k &&
                            ray_crosses(in, &s->edges[le->e], x, y))
                            odd ^= 1;
                    }
                }
            }
            if (odd && !add_interval(in, niv, from, to, L))
                return 0;
            from = to;
        }
        j = j1;
        in->par[k] = 0;
    }
    return 1;
}

/* The crossings of the sorted water intervals iv[0 .. niv) (pairs) with
 * the open segment (0, L), rounded to the lattice into off[] (see
 * wm_probe_crossings), the classes at the ends being cls0 and *cls1 (< 0:
 * found and written). Returns how many. */
static int round_crossings(const double *iv, size_t niv, int32_t L, int cls0,
                           int *cls1, int32_t *off, int max)
{
    /* the union's boundaries, rounded, normalized against the ends'
     * classes: a boundary that does not change the class (rounding at an
     * end) is skipped, two on one lattice point cancel */
    int n = 0, cur = cls0;
    double reach = -INFINITY; /* right end of the union so far */
    double last = 0;          /* unrounded position of off[n - 1] */
    for (size_t i = 0; i <= niv; i++)
    {
        /* boundaries: the end of the union so far when the next interval
         * starts beyond it, and that start */
        const double lo = i < niv ? iv[2 * i] : INFINITY;
        const double hi = i < niv ? iv[2 * i + 1] : INFINITY;
        double b[2];
        int nb = 0;
        if (lo > reach)
        {
            if (reach > -INFINITY)
                b[nb++] = reach; /* water -> land */
            if (lo < INFINITY)
                b[nb++] = lo; /* land -> water */
        }
        reach = fmax(reach, hi);
        for (int k = 0; k < nb; k++)
        {
            const int after = (nb == 2 && k == 1) || (nb == 1 && b[0] == lo);
            /* water is closed: a boundary through an end sample is a
             * crossing only when the water is on the other side of it,
             * then next to the sample, where interpolation puts it; so is
             * one through an end given as land that the water beyond it
             * meets (field.c settles such a sample of a block line to
             * land: a lake crossing the side there, seam seed 161017 at
             * 3 m, lost its half in one block) */
            const int at0 = b[k] == 0 && after && cur == 0;
            const int atL = b[k] == L && !after && *cls1 == 0;
            if (!(after ? b[k] > 0 && b[k] <= L : b[k] >= 0 && b[k] < L) &&
                !at0 && !atL)
                continue;
            if (after == cur)
                continue;
            /* rounded, kept off the ends */
            double o = floor(b[k] + 0.5);
            o = o < 1 ? 1 : (o > L - 1 ? L - 1 : o);
            if (n > 0 && o <= off[n - 1])
            {
                /* a feature narrower than a lattice unit: kept one unit
                 * wide (a thin strip stays whole to its tip), unless its
                 * two boundaries coincide (two inputs sharing one) */
                o = off[n - 1] + 1;
                if (o > L - 1 && off[n - 1] - 1 > (n > 1 ? off[n - 2] : 0))
                {
                    off[n - 1]--; /* room below: the pair moves down */
                    o = L - 1;
                }
                if (b[k] - last < WM_COINCIDE || o > L - 1)
                {
                    n--;
                    cur = after;
                    continue;
                }
            }
            if (n == max)
                continue;
            off[n++] = (int32_t)o;
            last = b[k];
            cur = after;
        }
    }
    if (*cls1 < 0)
        *cls1 = cur;
    else if (cur != *cls1)
    {
        if (n > 0)
            n--;
        else if (L >= 2 && max > 0) /* the ends' given classes differ
                                       where the inputs find no boundary
                                       between them: one midway */
            off[n++] = L / 2;
    }
    return n;
}

/* Whether capsule g's bank lies along the line through global (Gx, Gy)
 * along x or y (vertical), within WM_COINCIDE: its axis parallel to the
 * line, at the radius from it. */
static int bank_along(const wm_river_seg *g, int64_t Gx, int64_t Gy,
                      int vertical)
{
    if (vertical ? g->ax != g->bx : g->ay != g->by)
        return 0;
    const double w = (double)(vertical ? g->ax - Gx : g->ay - Gy);
    return fabs(fabs(w) - g->r) < WM_COINCIDE;
}

/* Appends to in->iv (*niv) the intervals of the river capsules meeting
 * the segment (those of its midpoint's cell: any capsule meeting it is
 * within half of it from the midpoint, so registered); *inside is set
 * when a bank meets the segment, ends included. On a block side (along),
 * a capsule whose bank lies along the segment is noted in in->dv too, as
 * a lake's edge along it: side_rule() decides that water (a bank on the
 * side is the side's water only where the points a unit across are).
 * Returns 0 when the segment lies in one capsule and cls0 (water) and
 * *cls1 agree (the crossings are known: none), -1 when out of memory,
 * else 1. */
static int river_intervals(wm_probe *in, int64_t Gx, int64_t Gy, wm_pt P,
                           int vertical, int32_t L, int cls0, int cls1,
                           size_t *niv, int *inside, int along)
{
    const wm_scene *s = in->s;
    const double mx = P.x + (vertical ? 0 : L / 2.0);
    const double my = P.y + (vertical ? L / 2.0 : 0);
    size_t c0, c1;
    const int32_t cx = dcell(in, mx), cy = dcell(in, my);
    wm_cells_row(&in->cells, cy, cx, cx, &c0, &c1);
    const size_t n0 = c1 - c0;
    for (size_t i = 0; i < n0 + in->nwide; i++)
    {
        const wm_river_seg *g =
            &s->segs[i < n0 ? in->cells.item[c0 + i] : in->wide[i - n0]];
        double lo, hi;
        /* the capsule's box against the segment's */
        const double m = g->r;
        if ((double)((g->ax < g->bx ? g->ax : g->bx) - Gx) - m >
                (vertical ? 0 : L) ||
            (double)((g->ax > g->bx ? g->ax : g->bx) - Gx) + m < 0 ||
            (double)((g->ay < g->by ? g->ay : g->by) - Gy) - m >
                (vertical ? L : 0) ||
            (double)((g->ay > g->by ? g->ay : g->by) - Gy) + m < 0)
            continue;
        if (!wm_probe_capsule_interval(g, Gx, Gy, vertical, &lo, &hi))
            continue;
        const int bank = along && bank_along(g, Gx, Gy, vertical);
        if (!bank && lo <= 0 && hi >= L && cls0 && cls1 == cls0)
            return 0; /* water ends, the segment inside one capsule */
        if (bank && !push_interval(&in->dv, &in->dvcap, &in->ndv, lo, hi, L))
            return -1;
        /* a bank through an end sample counts: the end's class may be
         * water only by that bank (distance 0), the land beside it found
         * below (two rivers whose banks lie on sample rows) */
        *inside |= (lo >= 0 && lo <= L) || (hi >= 0 && hi <= L);
        if (!add_interval(in, niv, lo, hi, L))
            return -1;
    }
    return 1;
}

/* The water intervals of the segment, every input's, sorted into in->iv
 * (*niv); 0 when out of memory. */
static int seg_water(wm_probe *in, wm_pt P, int vertical, int32_t L,
                     size_t *niv)
{
    const int64_t Gx = (int64_t)P.x + in->X0, Gy = (int64_t)P.y + in->Y0;
    int inside = 0;
    *niv = 0;
    if (river_intervals(in, Gx, Gy, P, vertical, L, 0, 0, niv, &inside, 0) < 0)
        return 0;
    const long ntg =
        in->nledge ? lake_toggles(in, Gx, Gy, P, vertical, L, niv) : 0;
    if (ntg < 0 ||
        (in->nledge && !lake_intervals(in, P, vertical, L, (size_t)ntg, niv)))
        return 0;
    if (*niv > 1)
        sort_small(in->iv, *niv, 2 * sizeof *in->iv, cmp_interval);
    return 1;
}

/* Sorted intervals a[0 .. n) (pairs) merged in place; returns how many. */
static size_t merge_iv(double *a, size_t n)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
    {
        if (m > 0 && a[2 * i] <= a[2 * m - 1])
        {
            a[2 * m - 1] = fmax(a[2 * m - 1], a[2 * i + 1]);
            continue;
        }
        a[2 * m] = a[2 * i];
        a[2 * m + 1] = a[2 * i + 1];
        m++;
    }
    return m;
}

/* The pieces of positive length common to merged a and b, into out;
 * returns how many (at most na + nb). */
static size_t meet_iv(const double *a, size_t na, const double *b, size_t nb,
                      double *out)
{
    size_t n = 0;
    for (size_t i = 0, j = 0; i < na && j < nb;)
    {
        const double lo = fmax(a[2 * i], b[2 * j]);
        const double hi = fmin(a[2 * i + 1], b[2 * j + 1]);
        if (lo < hi)
        {
            out[2 * n] = lo;
            out[2 * n + 1] = hi;
            n++;
        }
        if (a[2 * i + 1] < b[2 * j + 1])
            i++;
        else
            j++;
    }
    return n;
}

/* Merged a less the open pieces of merged b (a piece of a that b does not
 * overlap is kept whole, a point too; what b cuts keeps positive length),
 * into out; returns how many (at most na + nb). */
static size_t cut_iv(const double *a, size_t na, const double *b, size_t nb,
                     double *out)
{
    size_t n = 0, j = 0;
    for (size_t i = 0; i < na; i++)
    {
        double cur = a[2 * i];
        const double hi = a[2 * i + 1];
        int cut = 0;
        while (j < nb && b[2 * j + 1] <= cur)
            j++;
        for (size_t k = j; k < nb && b[2 * k] < hi; k++)
        {
            if (!(b[2 * k + 1] > cur && b[2 * k] < hi))
                continue;
            if (b[2 * k] > cur)
            {
                out[2 * n] = cur;
                out[2 * n + 1] = b[2 * k];
                n++;
            }
            cur = fmax(cur, b[2 * k + 1]);
            cut = 1;
        }
        if (!cut || cur < hi)
        {
            out[2 * n] = cur;
            out[2 * n + 1] = hi;
            n++;
        }
    }
    return n;
}

/* A merged copy of the niv water intervals in in->iv (*nw pairs; owned by
 * the caller), or NULL when out of memory. */
static double *merged_water(const wm_probe *in, size_t niv, size_t *nw)
{
    double *w = malloc((2 * niv + 2) * sizeof *w);
    if (w)
        *nw = merge_iv(memcpy(w, in->iv, 2 * niv * sizeof *w), niv);
    return w;
}

/* The water a lattice unit across a block side's segment (P, vertical,
 * L), on each side of it (k = 0 before, 1 beyond), merged, into a[k] (na[k]
 * pairs; owned by the caller, NULL on failure). Overwrites in->iv; 0 when
 * out of memory. */
static int water_across(wm_probe *in, wm_pt P, int vertical, int32_t L,
                        double *a[2], size_t na[2])
{
    for (int k = 0; k < 2; k++)
    {
        const wm_pt Q = {P.x + (vertical ? 2 * k - 1 : 0),
                         P.y + (vertical ? 0 : 2 * k - 1)};
        if (!seg_water(in, Q, vertical, L, &na[k]) ||
            !(a[k] = merged_water(in, na[k], &na[k])))
            return 0;
    }
    return 1;
}

/* A block side's segment along which lake edges lie (in->dv): there the
 * water is the lake's boundary alone, and it stays water only where the
 * points a lattice unit across the side, in both blocks, are water (as a
 * sample exactly 0 on a block line, field.c): a shore on the side moves a
 * unit into its block, and the land of the block across that touches the
 * side there stays a notch in it, not a hole a unit off it. Rewrites the
 * sorted in->iv (*niv); 0 when out of memory. Both blocks find the same:
 * the points across are a pure function of the global position. */
static int side_rule(wm_probe *in, wm_pt P, int vertical, int32_t L, int cls0,
                     int cls1, size_t *niv)
{
    /* w: the side's water, merged; d: the lake edges along it; a[k]: the
     * water a unit across on each side; m: where both are water; x: the
     * edges' parts where they are not */
    const size_t nd = in->ndv;
    size_t nw = 0;
    double *w = merged_water(in, *niv, &nw);
    double *d = malloc((2 * nd + 2) * sizeof *d), *a[2] = {NULL, NULL};
    double *m = NULL, *x = NULL;
    size_t na[2] = {0, 0};
    int ok = w && d;
    if (ok)
        memcpy(d, in->dv, 2 * nd * sizeof *d);
    ok = ok && water_across(in, P, vertical, L, a, na);
    if (ok)
        ok = (m = malloc((2 * (na[0] + na[1]) + 2) * sizeof *m)) != NULL &&
             (x = malloc((2 * (nd + na[0] + na[1]) + 2) * sizeof *x)) != NULL &&
             wm_grow((void **)&in->iv, &in->ivcap,
                     2 * (nw + nd + na[0] + na[1]) + 6, sizeof *in->iv);
    if (ok)
    {
        sort_small(d, nd, 2 * sizeof *d, cmp_interval);
        const size_t nm = meet_iv(a[0], na[0], a[1], na[1], m);
        const size_t nx = cut_iv(d, merge_iv(d, nd), m, nm, x);
        *niv = cut_iv(w, nw, x, nx, in->iv);
        /* the ends keep their samples' classes, which the same rule gave */
        for (int k = 0; k < 2; k++)
            if ((k ? cls1 : cls0) == 1)
            {
                in->iv[2 * *niv] = in->iv[2 * *niv + 1] = k ? L : 0;
                ++*niv;
            }
        sort_small(in->iv, *niv, 2 * sizeof *in->iv, cmp_interval);
    }
    free(w);
    free(d);
    free(a[0]);
    free(a[1]);
    free(m);
    free(x);
    return ok;
}

/* Whether merged intervals a (na) overlap (lo, hi) with positive length. */
static int meets(const double *a, size_t na, double lo, double hi)
{
    for (size_t i = 0; i < na; i++)
        if (fmin(a[2 * i + 1], hi) > fmax(a[2 * i], lo))
            return 1;
    return 0;
}

/* A block side's segment: a water run strictly inside it (both its ends
 * land) that does not reach a lattice unit into both blocks, across the
 * side, is taken for land. Rounding the inputs to the lattice leaves such
 * runs where a bank passes within a unit of a block line: one crossing
 * the side by a fraction of a unit made the block across keep a ring a
 * unit wide along it (a speck that the inputs as drawn do not have), as a
 * sample on a block line is settled by the points a unit across
 * (field.c). Land needs no such rule: a land run that barely reaches into
 * a block leaves a notch a unit deep in its water's ring, not a ring, and
 * one that reaches into one block only is the tip of a land wedge there.
 * Not where an input's edge lies along the side (side_rule settles those).
 * Both blocks find the same: the points across are a pure function of the
 * global position. Rewrites the sorted in->iv (*niv); 0 when out of
 * memory. */
static int thin_runs(wm_probe *in, wm_pt P, int vertical, int32_t L,
                     size_t *niv)
{
    size_t na[2] = {0, 0}, nw = 0;
    double *w = merged_water(in, *niv, &nw), *a[2] = {NULL, NULL};
    int ok = w != NULL, inner = 0;
    for (size_t i = 0; i < nw; i++)
        inner |= w[2 * i] > 0 && w[2 * i + 1] < L;
    ok = ok && (!inner || water_across(in, P, vertical, L, a, na));
    if (ok && inner)
    {
        size_t m = 0;
        for (size_t i = 0; i < nw; i++)
        {
            const double lo = w[2 * i], hi = w[2 * i + 1];
            if (lo > 0 && hi < L &&
                !(meets(a[0], na[0], lo, hi) && meets(a[1], na[1], lo, hi)))
                continue;
            in->iv[2 * m] = lo;
            in->iv[2 * m + 1] = hi;
            m++;
        }
        *niv = m;
    }
    free(w);
    free(a[0]);
    free(a[1]);
    return ok;
}

/* A segment perpendicular to a block side at an end (at0, at1) on it,
 * whose class there is water: such an end is a sample of the side settled
 * water (field.c settle_lines: the points a lattice unit across are water)
 * or a point of the side that side_rule leaves water alike, so a land run
 * from that end of at most a unit (the point a unit across, on a closed
 * shore, is water) is the rest of a shore lying along the side (a lake's
 * edge on it, a bank or another lake's edge within a unit across): it is
 * water, as the end is. Rounded, it left a strip of water a unit wide
 * along the side, the lake's, which has none in this block, and the block
 * kept it as its own ring (a speck at a block corner: held-out mixed seed
 * 196131 at 4 m; two lakes a unit apart across a block line, round 23).
 * Adds the run to the sorted in->iv (*niv) as water; 0 when out of
 * memory. */
static int settled_ends(wm_probe *in, int32_t L, int at0, int at1, size_t *niv)
{
    size_t nw = 0;
    double *w = merged_water(in, *niv, &nw);
    if (!w)
        return 0;
    double fill[4];
    size_t nf = 0;
    if (at0 && nw > 1 && fabs(w[1]) < WM_COINCIDE && w[2] <= 1.0 + WM_COINCIDE)
    {
        fill[2 * nf] = w[1];
        fill[2 * nf++ + 1] = w[2];
    }
    if (at1 && nw > 1 && fabs(w[2 * nw - 2] - L) < WM_COINCIDE &&
        w[2 * nw - 3] >= L - 1.0 - WM_COINCIDE)
    {
        fill[2 * nf] = w[2 * nw - 3];
        fill[2 * nf++ + 1] = w[2 * nw - 2];
    }
    free(w);
    if (nf == 0)
        return 1;
    if (!wm_grow((void **)&in->iv, &in->ivcap, 2 * (*niv + nf), sizeof *in->iv))
        return 0;
    memcpy(in->iv + 2 * *niv, fill, 2 * nf * sizeof *fill);
    *niv += nf;
    sort_small(in->iv, *niv, 2 * sizeof *in->iv, cmp_interval);
    return 1;
}

int wm_probe_crossings(wm_probe *in, wm_pt P, int vertical, int32_t L, int cls0,
                       int *cls1, int32_t *off, int max)
{
    const int64_t Gx = (int64_t)P.x + in->X0, Gy = (int64_t)P.y + in->Y0;
    const int32_t S = in->s->n * WM_Q;
    const int on_side = vertical ? P.x == 0 || P.x == S : P.y == 0 || P.y == S;
    size_t niv = 0;
    int inside = 0; /* an input's boundary meets the segment, ends included */
    in->ndv = 0;
    const int r = river_intervals(in, Gx, Gy, P, vertical, L, cls0, *cls1, &niv,
                                  &inside, on_side);
    if (r <= 0)
        return r;
    const size_t nriver = niv;
    const long ntg =
        in->nledge ? lake_toggles(in, Gx, Gy, P, vertical, L, &niv) : 0;
    if (ntg < 0)
        return -1;
    inside |= niv > nriver; /* a lake's edge along the segment or at an end */
    if (!inside && ntg == 0 && in->ndv == 0 && (*cls1 < 0 || *cls1 == cls0))
    {
        /* every input's membership is constant along the segment */
        if (*cls1 < 0)
            *cls1 = cls0;
        return 0;
    }
    if (ntg || in->nledge)
        if (!lake_intervals(in, P, vertical, L, (size_t)ntg, &niv))
            return -1;
    if (niv > 1)
        sort_small(in->iv, niv, 2 * sizeof *in->iv, cmp_interval);
    if (on_side && in->ndv && !side_rule(in, P, vertical, L, cls0, *cls1, &niv))
        return -1;
    if (on_side && niv && !in->ndv && !thin_runs(in, P, vertical, L, &niv))
        return -1;
    const int32_t a = vertical ? P.y : P.x; /* along the segment */
    const int at0 = cls0 == 1 && (a == 0 || a == S);
    const int at1 = *cls1 == 1 && (a + L == 0 || a + L == S);
    if ((at0 || at1) && niv && !settled_ends(in, L, at0, at1, &niv))
        return -1;
    return round_crossings(in->iv, niv, L, cls0, cls1, off, max);
}

void wm_probe_rivers_near(const wm_probe *p, double x, double y,
                          wm_probe_items *it)
{
    size_t c0, c1;
    wm_cells_row(&p->cells, dcell(p, y), dcell(p, x), dcell(p, x), &c0, &c1);
    *it = (wm_probe_items){p->cells.item + c0, c1 - c0, p->wide, p->nwide};
}

void wm_probe_lake_edges_near(const wm_probe *p, double x, double y,
                              wm_probe_items *it)
{
    if (p->nledge == 0)
    {
        *it = (wm_probe_items){NULL, 0, NULL, 0};
        return;
    }
    size_t c0, c1;
    wm_cells_row(&p->lcells, dcell(p, y), dcell(p, x), dcell(p, x), &c0, &c1);
    *it = (wm_probe_items){p->lcells.item + c0, c1 - c0, p->lwide, p->nlwide};
}

void wm_probe_lake_edges_ray(const wm_probe *p, double y, wm_probe_items *it)
{
    if (p->nledge == 0)
    {
        *it = (wm_probe_items){NULL, 0, NULL, 0};
        return;
    }
    size_t b, e;
    wm_cells_row(&p->lrows, rband(p, y), 0, 0, &b, &e);
    *it = (wm_probe_items){p->lrows.item + b, e - b, NULL, 0};
}

double wm_probe_min_radius(const wm_probe *p, int32_t x0, int32_t y0,
                           int32_t x1, int32_t y1, int lakes)
{
    if (p->nsegs == 0 && (p->npolys == 0 || !lakes))
        return INFINITY;
    const int32_t cx0 = dcell(p, x0), cx1 = dcell(p, x1);
    const int32_t cy0 = dcell(p, y0), cy1 = dcell(p, y1);
    if (lakes && p->nledge)
    {
        if (p->nlwide)
            return 0;
        for (int32_t cy = cy0; cy <= cy1; cy++)
        {
            size_t b, e;
            wm_cells_row(&p->lcells, cy, cx0, cx1, &b, &e);
            if (b < e)
                return 0;
        }
    }
    double r = INFINITY;
    for (size_t i = 0; i < p->nwide; i++)
    {
        const double ri = p->s->segs[p->wide[i]].r;
        r = ri < r ? ri : r;
    }
    for (int32_t cy = cy0; cy <= cy1; cy++)
    {
        size_t b, e;
        wm_cells_row(&p->cells, cy, cx0, cx1, &b, &e);
        for (size_t i = b; i < e; i++)
        {
            const double ri = p->s->segs[p->cells.item[i]].r;
            r = ri < r ? ri : r;
        }
    }
    return r;
}

/* The indexes' cell for probe p (its items listed) over a block of side
 * S: DCELL, down to 4 pixels (the reach every item is grown by) where the
 * block has many river segments and lake edges (wm_cells_fit). A query
 * reads the items of one cell: at coarse pixels, where dense rivers put
 * hundreds of segments in a 16-pixel cell, 4-pixel cells made Andorra at
 * 50 m pixels 6-12 % faster. Which items a query finds within its reach
 * does not depend on the cell (wm_probe_min_radius reads the items
 * registered in the cells over a box, a superset of those in reach:
 * smaller cells only tighten its bound). */
static int32_t probe_cell(const wm_scene *s, const wm_probe *p, int32_t S)
{
    size_t nitems = p->nsegs;
    for (size_t k = 0; k < p->npolys; k++)
        nitems += s->poly_start[p->polys[k] + 1] - s->poly_start[p->polys[k]];
    return wm_cells_fit(nitems, S, DCELL, 4 * WM_Q);
}

wm_status wm_probe_init(wm_probe *p, const wm_scene *s, int64_t bx, int64_t by)
{
    memset(p, 0, sizeof *p);
    p->s = s;
    if (s->nbx == 0 || bx < s->bx0 || by < s->by0 || bx >= s->bx0 + s->nbx ||
        by >= s->by0 + s->nby)
        return WM_OK;
    const int32_t S = s->n * WM_Q;
    const wm_box blk = {bx, by, bx, by};
    p->X0 = bx * (int64_t)S;
    p->Y0 = by * (int64_t)S;
    if (wm_scene_items(s, blk, &p->ids, &p->nsegs, &p->npolys) != WM_OK)
        return WM_ERR_NOMEM;
    p->segs = p->ids;
    p->polys = p->ids ? p->ids + p->nsegs : NULL;
    p->cell = probe_cell(s, p, S);
    if (build_river_index(p, S) != WM_OK ||
        (p->npolys && build_lake_index(p, S) != WM_OK))
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
    free(p->ids);
    wm_cells_free(&p->cells);
    wm_cells_free(&p->lcells);
    wm_cells_free(&p->lrows);
    free(p->wide);
    free(p->ledge);
    free(p->lwide);
    free(p->par);
    free(p->dmin);
    free(p->touched);
    free(p->iv);
    free(p->dv);
    free(p->tg);
    free(p->corner);
    free(p->corner_joint);
    free(p->rebuilt);
    const wm_scene *s = p->s;
    memset(p, 0, sizeof *p);
    p->s = s;
}

int wm_probe_rebuilt(const wm_probe *p, const wm_field *f, int32_t c, int32_t r)
{
    const uint64_t key = wm_field_cell_key(f, c, r);
    const size_t lo = wm_lower_u64(p->rebuilt, p->nrebuilt, key);
    return lo < p->nrebuilt && p->rebuilt[lo] == key;
}
