/*
 * corners.c - the candidate corners of a block's union boundary: where the
 * boundaries of two inputs cross.
 *
 * Boundary primitives of the inputs in reach: for a river segment its two
 * offset lines and two end circles (a circle two consecutive segments
 * share taken once), for a lake edge the edge. Their pairwise
 * intersections (primitives bucketed in a grid of 16-pixel cells; pairs
 * from the same input item, or with a circle and boxes apart, skipped) are
 * kept when strictly inside the block and near the boundary (the nearest
 * sample within 0.75 pixel of it: the field is 1-Lipschitz, so a point of
 * the boundary is within 0.71 pixel of a sample valued within 0.71 pixel
 * of 0; anything else is buried under another input).
 *
 * Users: crease.c puts the corners that sampling rounded off back into the
 * rings; subpixel.c seeds the cells whose four samples are of one class
 * and that hold a corner (an island smaller than a pixel between rivers).
 *
 * Floating point decides only which corners are candidates.
 */
#include "corners.h"

#include "lattice.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NO_ITEM UINT32_MAX

typedef struct
{
    double x0, y0, x1, y1; /* segment, or circle centre (x0,y0) radius x1 */
    int circle;    /* 0: an offset line; 1, 2: the circle at its segment's
                      first, second end */
    uint32_t item; /* its input item, or NO_ITEM: a circle two consecutive
                      segments share */
    uint32_t seg;  /* river primitives: the slot in probe->segs of their
                      segment (a shared circle: the earlier one's, whose
                      second end it is); lake edges: NO_ITEM */
    uint32_t poly; /* lake edges: their polygon; rivers: NO_ITEM */
} prim;

static prim river_prim(double x0, double y0, double x1, double y1, int circle,
                       uint32_t item, uint32_t slot)
{
    return (prim){x0, y0, x1, y1, circle, item, slot, NO_ITEM};
}

/* A crossing found: where, and whether it is joint (see joint()). */
typedef struct
{
    wm_pt p;
    int joint;
} hit_pt;

static int cmp_hit(const void *a, const void *b)
{
    return wm_pt_cmp(((const hit_pt *)a)->p, ((const hit_pt *)b)->p);
}

/* The lattice points primitive p ends at: a lake edge's or its river
 * segment's two ends for a line, its centre for a circle. */
static int prim_ends(const wm_probe *in, const prim *p, int64_t e[2][2])
{
    const wm_scene *s = in->s;
    int64_t a[2], b[2];
    if (p->seg != NO_ITEM)
    {
        const wm_river_seg *g = &s->segs[in->segs[p->seg]];
        a[0] = g->ax, a[1] = g->ay, b[0] = g->bx, b[1] = g->by;
    }
    else
    {
        const wm_lake_edge *g = &s->edges[p->item - s->nsegs];
        a[0] = g->ax, a[1] = g->ay, b[0] = g->bx, b[1] = g->by;
    }
    int n = 0;
    if (p->circle != 2)
        memcpy(e[n++], a, sizeof a);
    if (p->circle != 1)
        memcpy(e[n++], b, sizeof b);
    return n;
}

/* Whether primitives p and q come from one river segment, from two river
 * capsules sharing an end (the inside of a bend, lines meeting end to
 * end), or from two edges of one lake polygon sharing an end (its vertex):
 * a property of the coordinates, not of the order of the inputs, so a job
 * reading its features in another order finds the same. */
static int joint(const wm_probe *in, const prim *p, const prim *q)
{
    if ((p->seg == NO_ITEM) != (q->seg == NO_ITEM) ||
        (p->seg == NO_ITEM && p->poly != q->poly))
        return 0;
    if (p->seg != NO_ITEM && p->seg == q->seg)
        return 1;
    int64_t ep[2][2], eq[2][2];
    const int np = prim_ends(in, p, ep), nq = prim_ends(in, q, eq);
    for (int i = 0; i < np; i++)
        for (int j = 0; j < nq; j++)
            if (ep[i][0] == eq[j][0] && ep[i][1] == eq[j][1])
                return 1;
    return 0;
}

/* ---- candidate corners: intersections of primitives ------------------- */

/* How many scattered field reads ahead a loop prefetches. */
#define PREFETCH 8

/* The sample nearest to lattice coordinate v >= 0. */
static int32_t sample_of(int32_t v)
{
    return (v + WM_Q / 2) / WM_Q;
}

typedef struct
{
    double x, y;
} dpt;

static int seg_seg(const prim *a, const prim *b, dpt *out)
{
    const double rx = a->x1 - a->x0, ry = a->y1 - a->y0;
    const double sx = b->x1 - b->x0, sy = b->y1 - b->y0;
    const double den = rx * sy - ry * sx;
    if (den == 0)
        return 0;
    const double qx = b->x0 - a->x0, qy = b->y0 - a->y0;
    const double t = (qx * sy - qy * sx) / den, u = (qx * ry - qy * rx) / den;
    if (t < 0 || t > 1 || u < 0 || u > 1)
        return 0;
    out[0].x = a->x0 + t * rx;
    out[0].y = a->y0 + t * ry;
    return 1;
}

static int seg_circle(const prim *a, const prim *c, dpt *out)
{
    const double dx = a->x1 - a->x0, dy = a->y1 - a->y0;
    const double fx = a->x0 - c->x0, fy = a->y0 - c->y0, r = c->x1;
    const double A = dx * dx + dy * dy, B = 2 * (fx * dx + fy * dy);
    const double C = fx * fx + fy * fy - r * r;
    const double disc = B * B - 4 * A * C;
    if (A == 0 || disc < 0)
        return 0;
    const double sq = sqrt(disc);
    int n = 0;
    for (int k = -1; k <= 1; k += 2)
    {
        const double t = (-B + k * sq) / (2 * A);
        if (t >= 0 && t <= 1)
        {
            out[n].x = a->x0 + t * dx;
            out[n].y = a->y0 + t * dy;
            n++;
        }
    }
    return n;
}

static int circle_circle(const prim *a, const prim *b, dpt *out)
{
    const double dx = b->x0 - a->x0, dy = b->y0 - a->y0;
    const double d2 = dx * dx + dy * dy, d = sqrt(d2);
    const double r0 = a->x1, r1 = b->x1;
    if (d == 0 || d > r0 + r1 || d < fabs(r0 - r1))
        return 0;
    const double l = (r0 * r0 - r1 * r1 + d2) / (2 * d);
    const double h2 = r0 * r0 - l * l, h = h2 > 0 ? sqrt(h2) : 0;
    const double mx = a->x0 + l * dx / d, my = a->y0 + l * dy / d;
    out[0].x = mx + h * dy / d;
    out[0].y = my - h * dx / d;
    out[1].x = mx - h * dy / d;
    out[1].y = my + h * dx / d;
    return 2;
}

static int intersect(const prim *a, const prim *b, dpt *out)
{
    if (!a->circle && !b->circle)
        return seg_seg(a, b, out);
    if (a->circle && b->circle)
        return circle_circle(a, b, out);
    return a->circle ? seg_circle(b, a, out) : seg_circle(a, b, out);
}

/* llround of a positive x (the hits lie inside the block), exactly. */
static int32_t round_pos(double x)
{
    const int32_t r = (int32_t)x; /* truncation: floor for x >= 0 */
    return r + (x - r >= 0.5);    /* x - r is exact */
}

static void prim_box(const prim *p, double *b)
{
    if (p->circle)
    {
        b[0] = p->x0 - p->x1;
        b[1] = p->y0 - p->x1;
        b[2] = p->x0 + p->x1;
        b[3] = p->y0 + p->x1;
        return;
    }
    b[0] = fmin(p->x0, p->x1);
    b[1] = fmin(p->y0, p->y1);
    b[2] = fmax(p->x0, p->x1);
    b[3] = fmax(p->y0, p->y1);
}

wm_status wm_corners_find(wm_probe *probe, const wm_field *f, const wm_ctx *ctx)
{
    wm_status st = WM_OK;
    prim *pr = NULL;
    size_t npr = 0, prcap = 0;
    wm_cells pg;       /* primitives by cell */
    double *pb = NULL; /* their boxes */
    memset(&pg, 0, sizeof pg);
    hit_pt *cand = NULL; /* primitive crossings, then the kept ones */
    size_t ncand = 0, candcap = 0, nkept = 0;
    wm_probe *in = probe;
    const wm_scene *s = in->s;

    if (in->corners_found)
        return WM_OK;
    in->corners_found = 1;
    if (in->nsegs + in->npolys < 1)
        return WM_OK;
    const int32_t S = s->n * WM_Q;

    /* 1. primitives, local doubles */
    const double lo = -4.0 * WM_Q, hi = (double)S + 4.0 * WM_Q;
    for (size_t i = 0; i < in->nsegs; i++)
    {
        const wm_river_seg *q = &s->segs[in->segs[i]];
        const double ax = (double)(q->ax - in->X0),
                     ay = (double)(q->ay - in->Y0);
        const double bx2 = (double)(q->bx - in->X0),
                     by2 = (double)(q->by - in->Y0);
        const double dx = bx2 - ax, dy = by2 - ay, l = sqrt(dx * dx + dy * dy);
        const uint32_t it = in->segs[i], sl = (uint32_t)i;
        prim p[4];
        int np = 0;
        if (l > 0)
        {
            const double nx = -dy / l * q->r, ny = dx / l * q->r;
            p[np++] =
                river_prim(ax + nx, ay + ny, bx2 + nx, by2 + ny, 0, it, sl);
            p[np++] =
                river_prim(ax - nx, ay - ny, bx2 - nx, by2 - ny, 0, it, sl);
        }
        /* end circles, each once: the start circle of a segment that
         * continues the previous one (same vertex, same radius) is that
         * one's end circle, which then belongs to neither (it pairs with
         * the primitives of both, as the two copies did) */
        const wm_river_seg *prev = i > 0 ? &s->segs[in->segs[i - 1]] : NULL;
        if (prev && prev->bx == q->ax && prev->by == q->ay && prev->r == q->r)
            pr[npr - 1].item = NO_ITEM;
        else
            p[np++] = river_prim(ax, ay, q->r, 0, 1, it, sl);
        if (l > 0)
            p[np++] = river_prim(bx2, by2, q->r, 0, 2, it, sl);
        for (int k = 0; k < np; k++)
            if (!wm_push((void **)&pr, &npr, &prcap, &p[k], sizeof *p))
                goto nomem;
    }
    for (size_t k = 0; k < in->npolys; k++)
    {
        const uint32_t pidx = in->polys[k];
        for (size_t e = s->poly_start[pidx]; e < s->poly_start[pidx + 1]; e++)
        {
            const wm_lake_edge *q = &s->edges[e];
            prim p = {(double)(q->ax - in->X0),
                      (double)(q->ay - in->Y0),
                      (double)(q->bx - in->X0),
                      (double)(q->by - in->Y0),
                      0,
                      (uint32_t)(s->nsegs + e),
                      NO_ITEM,
                      pidx};
            double b[4];
            prim_box(&p, b);
            if (b[2] < lo || b[0] > hi || b[3] < lo || b[1] > hi)
                continue;
            if (!wm_push((void **)&pr, &npr, &prcap, &p, sizeof p))
                goto nomem;
        }
    }
    if (npr >= NO_ITEM || s->nsegs + s->nedges >= NO_ITEM)
        goto cleanup; /* items and primitives need 32 bits */

    /* 2. candidates: pairs sharing a grid cell (cells over the block grown
     * by 4 px), found once (in the cell holding the intersection) */
    const double PC = 16.0 * WM_Q;
    const int64_t cmin = (int64_t)floor(lo / PC);
    const int64_t cside = (int64_t)floor(hi / PC) - cmin + 1;
    wm_cells_reset(&pg, (int32_t)cside);
    pb = malloc((4 * npr + 1) * sizeof *pb);
    if (!pb)
        goto nomem;
    for (size_t i = 0; i < npr; i++)
    {
        prim_box(&pr[i], pb + 4 * i);
        double b[4];
        b[0] = fmax(pb[4 * i], lo);
        b[1] = fmax(pb[4 * i + 1], lo);
        b[2] = fmin(pb[4 * i + 2], hi);
        b[3] = fmin(pb[4 * i + 3], hi);
        if (b[0] > b[2] || b[1] > b[3])
            continue;
        const int32_t x0 = (int32_t)((int64_t)floor(b[0] / PC) - cmin);
        const int32_t x1 = (int32_t)((int64_t)floor(b[2] / PC) - cmin);
        const int32_t y0 = (int32_t)((int64_t)floor(b[1] / PC) - cmin);
        const int32_t y1 = (int32_t)((int64_t)floor(b[3] / PC) - cmin);
        for (int32_t cy = y0; cy <= y1; cy++)
            for (int32_t cx = x0; cx <= x1; cx++)
                if (!wm_cells_add(&pg, cx, cy, (uint32_t)i))
                    goto nomem;
    }
    if (wm_cells_index(&pg) != WM_OK)
        goto nomem;
    for (int32_t row = 0; row < pg.side; row++)
        for (size_t cell = pg.row[row]; cell < pg.row[row + 1]; cell++)
        {
            const size_t a = pg.start[cell], z = pg.start[cell + 1];
            const int64_t cx = pg.col[cell] + cmin, cy = row + cmin;
            for (size_t i = a; i < z; i++)
            {
                if (wm_cancelled(ctx))
                {
                    st = wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
                    goto cleanup;
                }
                for (size_t j = i + 1; j < z; j++)
                {
                    const prim *p = &pr[pg.item[i]], *q = &pr[pg.item[j]];
                    if (p->item == q->item && p->item != NO_ITEM)
                        continue;
                    /* with a circle, boxes apart by more than any rounding
                     * give no hit; two nearly parallel lines may (their
                     * crossing is noise, far off), and are kept as they
                     * were */
                    const double *bp = pb + 4 * pg.item[i],
                                 *bq = pb + 4 * pg.item[j];
                    if ((p->circle || q->circle) &&
                        (bp[0] > bq[2] + 4 || bq[0] > bp[2] + 4 ||
                         bp[1] > bq[3] + 4 || bq[1] > bp[3] + 4))
                        continue;
                    dpt hit[2];
                    const int nh = intersect(p, q, hit);
                    for (int h = 0; h < nh; h++)
                    {
                        /* the crossing lies in both boxes; rounding may
                         * put it a few ulps out, into a cell the pair
                         * does not share, where it would never be seen */
                        hit[h].x = fmin(fmax(hit[h].x, fmax(bp[0], bq[0])),
                                        fmin(bp[2], bq[2]));
                        hit[h].y = fmin(fmax(hit[h].y, fmax(bp[1], bq[1])),
                                        fmin(bp[3], bq[3]));
                        if (floor(hit[h].x / PC) != (double)cx ||
                            floor(hit[h].y / PC) != (double)cy)
                            continue;
                        if (!(hit[h].x >= 1 && hit[h].x <= S - 1 &&
                              hit[h].y >= 1 && hit[h].y <= S - 1))
                            continue; /* strictly inside the block */
                        const hit_pt c = {
                            {round_pos(hit[h].x), round_pos(hit[h].y)},
                            joint(in, p, q)};
                        if (!wm_push((void **)&cand, &ncand, &candcap, &c,
                                     sizeof c))
                            goto nomem;
                    }
                }
            }
        }
    /* the field is 1-Lipschitz: a point of the boundary is within 0.71 px
     * of a sample valued within 0.71 px of 0; anything else is buried under
     * another input. The samples are scattered over the block's field:
     * fetched PREFETCH hits ahead. The kept ones are packed in place. */
    for (size_t i = 0; i < ncand; i++)
    {
        if (i + PREFETCH < ncand)
            wm_field_prefetch(f, sample_of(cand[i + PREFETCH].p.x),
                              sample_of(cand[i + PREFETCH].p.y));
        const wm_pt c = cand[i].p;
        if (fabsf(wm_field_at(f, sample_of(c.x), sample_of(c.y))) <= 0.75f)
            cand[nkept++] = cand[i];
    }
    ncand = nkept;
    if (ncand > 1)
        qsort(cand, ncand, sizeof *cand, cmp_hit);
    in->corner = malloc((ncand + 1) * sizeof *in->corner);
    in->corner_joint = malloc(ncand + 1);
    if (!in->corner || !in->corner_joint)
        goto nomem;
    size_t nu = 0;
    for (size_t i = 0; i < ncand; i++)
    {
        if (nu > 0 && wm_pt_eq(cand[i].p, in->corner[nu - 1]))
        {
            in->corner_joint[nu - 1] &= (uint8_t)cand[i].joint;
            continue;
        }
        in->corner[nu] = cand[i].p;
        in->corner_joint[nu++] = (uint8_t)cand[i].joint;
    }
    in->ncorner = nu;
    goto cleanup;
nomem:
    st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory finding corners");
cleanup:
    free(pr);
    wm_cells_free(&pg);
    free(pb);
    free(cand);
    return st;
}
