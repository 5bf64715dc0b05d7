/*
 * corners.c - the candidate corners of a block's union boundary: where the
 * boundaries of two inputs cross.
 *
 * Boundary primitives of the inputs in reach: for a river segment its two
 * offset lines and two end circles (a circle two consecutive segments
 * share taken once), for a lake edge the edge. Their pairwise
 * intersections (primitives bucketed in a grid of 16-pixel cells; pairs
 * from the same input item, or with boxes apart, skipped) are kept when in
 * the block square (on it or within a unit of it: one unit inside it), not
 * strictly inside a river capsule where two short segments cross
 * (under_capsule()), and near the boundary (the nearest
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

/* The work of wm_corners_find. */
typedef struct
{
    wm_probe *in;
    const wm_ctx *ctx;
    double lo, hi; /* the block grown by 4 px, local lattice units */
    int32_t S;     /* the block's side */
    prim *pr;      /* primitives */
    size_t npr, prcap;
    wm_cells pg; /* primitives by cell */
    double *pb;  /* their boxes */
    int32_t *pc; /* the cells their boxes cover, clipped to the grown
                    block: x0, y0, x1, y1 (x0 > x1: none) */
    int64_t cmin;
    hit_pt *cand; /* primitive crossings, then the kept ones */
    size_t ncand, candcap;
} finder;

/* Cells of the candidates' grid. */
#define PC (16.0 * WM_Q)

/* Step 1a: each river segment's offset lines and end circles (a circle
 * two consecutive segments share taken once). */
static int river_prims(finder *cf)
{
    const wm_probe *in = cf->in;
    const wm_scene *s = in->s;
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
            cf->pr[cf->npr - 1].item = NO_ITEM;
        else
            p[np++] = river_prim(ax, ay, q->r, 0, 1, it, sl);
        if (l > 0)
            p[np++] = river_prim(bx2, by2, q->r, 0, 2, it, sl);
        for (int k = 0; k < np; k++)
            if (!wm_push((void **)&cf->pr, &cf->npr, &cf->prcap, &p[k],
                         sizeof *p))
                return 0;
    }
    return 1;
}

/* Step 1b: the lake edges whose box meets the grown block. */
static int lake_prims(finder *cf)
{
    const wm_probe *in = cf->in;
    const wm_scene *s = in->s;
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
            if (b[2] < cf->lo || b[0] > cf->hi || b[3] < cf->lo ||
                b[1] > cf->hi)
                continue;
            if (!wm_push((void **)&cf->pr, &cf->npr, &cf->prcap, &p, sizeof p))
                return 0;
        }
    }
    return 1;
}

/* Step 2a: the primitives' boxes, and the primitives by cell of the grid
 * over the grown block. */
static int bucket(finder *cf)
{
    const double lo = cf->lo, hi = cf->hi;
    cf->cmin = (int64_t)floor(lo / PC);
    const int64_t cside = (int64_t)floor(hi / PC) - cf->cmin + 1;
    wm_cells_reset(&cf->pg, (int32_t)cside);
    cf->pb = malloc((4 * cf->npr + 1) * sizeof *cf->pb);
    cf->pc = malloc((4 * cf->npr + 1) * sizeof *cf->pc);
    if (!cf->pb || !cf->pc)
        return 0;
    for (size_t i = 0; i < cf->npr; i++)
    {
        double *pb = cf->pb + 4 * i;
        int32_t *pc = cf->pc + 4 * i;
        prim_box(&cf->pr[i], pb);
        const double b[4] = {fmax(pb[0], lo), fmax(pb[1], lo), fmin(pb[2], hi),
                             fmin(pb[3], hi)};
        pc[0] = 1, pc[2] = 0;
        if (b[0] > b[2] || b[1] > b[3])
            continue;
        const int32_t x0 = (int32_t)((int64_t)floor(b[0] / PC) - cf->cmin);
        const int32_t x1 = (int32_t)((int64_t)floor(b[2] / PC) - cf->cmin);
        const int32_t y0 = (int32_t)((int64_t)floor(b[1] / PC) - cf->cmin);
        const int32_t y1 = (int32_t)((int64_t)floor(b[3] / PC) - cf->cmin);
        pc[0] = x0, pc[1] = y0, pc[2] = x1, pc[3] = y1;
        for (int32_t cy = y0; cy <= y1; cy++)
            for (int32_t cx = x0; cx <= x1; cx++)
                if (!wm_cells_add(&cf->pg, cx, cy, (uint32_t)i))
                    return 0;
    }
    return wm_cells_index(&cf->pg) == WM_OK;
}

/* Whether cell (cx, cy) of the grid (relative to cf->cmin) is one both
 * primitives' boxes cover. */
static int shared_cell(const finder *cf, uint32_t i, uint32_t j, int64_t cx,
                       int64_t cy)
{
    const int32_t *a = cf->pc + 4 * i, *b = cf->pc + 4 * j;
    return cx >= a[0] && cx <= a[2] && cy >= a[1] && cy <= a[3] && cx >= b[0] &&
           cx <= b[2] && cy >= b[1] && cy <= b[3];
}

/* Whether point h (block-local) lies strictly inside river capsule g
 * (its box first: most capsules of a cell are far). */
static int inside_capsule(const wm_probe *in, const wm_river_seg *g, dpt h)
{
    const double r = g->r - WM_COINCIDE;
    const double ex = h.x - (double)(g->ax - in->X0),
                 ey = h.y - (double)(g->ay - in->Y0);
    if (r <= 0 || fabs(ex) > r + fabs((double)(g->bx - g->ax)) ||
        fabs(ey) > r + fabs((double)(g->by - g->ay)))
        return 0;
    return wm_probe_seg_dist(in, g->ax, g->ay, g->bx, g->by, h.x, h.y) < r;
}

/* Whether river segment slot k of the block is shorter than its capsule
 * is wide. */
static int short_slot(const wm_probe *in, uint32_t k)
{
    const wm_river_seg *g = &in->s->segs[in->segs[k]];
    const double dx = (double)(g->bx - g->ax), dy = (double)(g->by - g->ay);
    return dx * dx + dy * dy < 4 * g->r * g->r;
}

/* Whether p is a river primitive of segments shorter than they are wide
 * (a circle two consecutive slots share: both of them, as its two copies
 * would be, read in another order): where buried crossings multiply.
 * Elsewhere they are few, and one that seeds a crowded cell (subpixel.c)
 * has it rebuilt exactly (testing every crossing changed 66 of L3's 1,430
 * features and made three held-out island scenes at 2 m slightly less
 * exact). */
static int short_seg(const wm_probe *in, const prim *p)
{
    if (p->seg == NO_ITEM)
        return 0;
    return short_slot(in, p->seg) &&
           (p->item != NO_ITEM || short_slot(in, p->seg + 1));
}

/* Segments between two crossing ones (by id) that under_capsule() tries
 * before the index. */
#define BURY_SPAN 64

/* Whether crossing h of river primitives p and q lies strictly inside a
 * river capsule of the block. Asked where their segments share no end
 * (joint() false) and are shorter than they are wide (short_seg()): an
 * end circle then crosses the next segment's sides inside its own
 * capsule, and on the inner side of a bend the offset lines of segments a
 * few apart cross a little inside those between (by k^2 l^2 / 8 R for k
 * segments of length l on a curve of radius R). None is a corner of the
 * union, though the field's test keeps it: a river network drawn with a
 * vertex every quarter pixel, 5 pixels wide, gave 4.6 M candidates, 91 %
 * of them such, whose cells the sub-pixel search seeded (18.9 s instead
 * of 1.4-1.5 s). The segments between theirs by id (the same line's, mostly)
 * are tried first, then those the probe's index holds near h: any capsule
 * holding h is among those, so the answer is geometric, as joint()'s is,
 * and a job reading the inputs in another order finds the same. */
static int under_capsule(const wm_probe *in, const prim *p, const prim *q,
                         dpt h)
{
    const wm_scene *s = in->s;
    const uint32_t a = in->segs[p->seg], b = in->segs[q->seg];
    const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    for (uint32_t m = lo; hi - lo <= BURY_SPAN && m <= hi; m++)
        if (inside_capsule(in, &s->segs[m], h))
            return 1;
    wm_probe_items it;
    wm_probe_rivers_near(in, h.x, h.y, &it);
    for (size_t i = 0; i < it.na + it.nb; i++)
        if (inside_capsule(in, &s->segs[i < it.na ? it.a[i] : it.b[i - it.na]],
                           h))
            return 1;
    return 0;
}

/* Step 2b: the crossings of primitives i and j, met in grid cell (cx, cy)
 * (relative to cf->cmin), that lie in a cell both their boxes cover and
 * strictly inside the block, added to the candidates. A pair is
 * intersected once, in the first cell it shares (the largest of their
 * first columns and rows); its other cells return at once. */
static int pair_hits(finder *cf, uint32_t i, uint32_t j, int64_t cx, int64_t cy)
{
    const prim *p = &cf->pr[i], *q = &cf->pr[j];
    if (p->item == q->item && p->item != NO_ITEM)
        return 1;
    const int32_t *ci = cf->pc + 4 * i, *cj = cf->pc + 4 * j;
    if (cx != (ci[0] > cj[0] ? ci[0] : cj[0]) ||
        cy != (ci[1] > cj[1] ? ci[1] : cj[1]))
        return 1;
    /* boxes apart by more than any rounding give no hit (two nearly
     * collinear lines apart may give one, noise: an offset line of a
     * straight river drawn densely and the next but one's) */
    const double *bp = cf->pb + 4 * i, *bq = cf->pb + 4 * j;
    if (bp[0] > bq[2] + 4 || bq[0] > bp[2] + 4 || bp[1] > bq[3] + 4 ||
        bq[1] > bp[3] + 4)
        return 1;
    dpt hit[2];
    const int nh = intersect(p, q, hit);
    for (int h = 0; h < nh; h++)
    {
        /* the crossing lies in both boxes; rounding may put it a few ulps
         * out, into a cell the pair does not share, where it would never
         * be seen */
        hit[h].x = fmin(fmax(hit[h].x, fmax(bp[0], bq[0])), fmin(bp[2], bq[2]));
        hit[h].y = fmin(fmax(hit[h].y, fmax(bp[1], bq[1])), fmin(bp[3], bq[3]));
        if (!shared_cell(cf, i, j, (int64_t)floor(hit[h].x / PC) - cf->cmin,
                         (int64_t)floor(hit[h].y / PC) - cf->cmin))
            continue;
        if (!(hit[h].x >= 0 && hit[h].x <= cf->S && hit[h].y >= 0 &&
              hit[h].y <= cf->S))
            continue; /* in the block */
        const int jt = joint(cf->in, p, q);
        if (!jt && short_seg(cf->in, p) && short_seg(cf->in, q) &&
            under_capsule(cf->in, p, q, hit[h]))
            continue;
        /* one on the block square or within a unit of it is kept one unit
         * inside it (a wedge's tip 0.4 unit off the square is a corner of
         * this block alone; a lake's corner on a block corner is where the
         * block lines' land samples put it, field.c) */
        const double lo = 1, hi = cf->S - 1;
        const hit_pt c = {{round_pos(fmin(fmax(hit[h].x, lo), hi)),
                           round_pos(fmin(fmax(hit[h].y, lo), hi))},
                          jt};
        if (!wm_push((void **)&cf->cand, &cf->ncand, &cf->candcap, &c,
                     sizeof c))
            return 0;
    }
    return 1;
}

/* Step 2: every pair of primitives sharing a grid cell. */
static wm_status pairs(finder *cf)
{
    const wm_cells *pg = &cf->pg;
    for (int32_t row = 0; row < pg->side; row++)
        for (size_t cell = pg->row[row]; cell < pg->row[row + 1]; cell++)
        {
            const size_t a = pg->start[cell], z = pg->start[cell + 1];
            const int64_t cx = pg->col[cell], cy = row;
            for (size_t i = a; i < z; i++)
            {
                if (wm_cancelled(cf->ctx))
                    return wm_fail(cf->ctx, WM_ERR_CANCELLED, "cancelled");
                for (size_t j = i + 1; j < z; j++)
                    if (!pair_hits(cf, pg->item[i], pg->item[j], cx, cy))
                        return WM_ERR_NOMEM;
            }
        }
    return WM_OK;
}

/* Step 3: the candidates near the boundary, sorted and distinct, into
 * in->corner (joint where every crossing found there is). The field is
 * 1-Lipschitz: a point of the boundary is within 0.71 px of a sample
 * valued within 0.71 px of 0; anything else is buried under another
 * input. The samples are scattered over the block's field: fetched
 * PREFETCH hits ahead. */
static int keep_near(finder *cf, const wm_field *f)
{
    hit_pt *cand = cf->cand;
    size_t kept = 0;
    for (size_t i = 0; i < cf->ncand; i++)
    {
        if (i + PREFETCH < cf->ncand)
            wm_field_prefetch(f, sample_of(cand[i + PREFETCH].p.x),
                              sample_of(cand[i + PREFETCH].p.y));
        const wm_pt c = cand[i].p;
        if (fabsf(wm_field_at(f, sample_of(c.x), sample_of(c.y))) <= 0.75f)
            cand[kept++] = cand[i];
    }
    if (kept > 1)
        qsort(cand, kept, sizeof *cand, cmp_hit);
    wm_probe *in = cf->in;
    in->corner = malloc((kept + 1) * sizeof *in->corner);
    in->corner_joint = malloc(kept + 1);
    if (!in->corner || !in->corner_joint)
        return 0;
    size_t nu = 0;
    for (size_t i = 0; i < kept; i++)
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
    return 1;
}

wm_status wm_corners_find(wm_probe *probe, const wm_field *f, const wm_ctx *ctx)
{
    if (probe->corners_found)
        return WM_OK;
    probe->corners_found = 1;
    if (probe->nsegs + probe->npolys < 1)
        return WM_OK;
    finder cf;
    memset(&cf, 0, sizeof cf);
    cf.in = probe;
    cf.ctx = ctx;
    cf.S = probe->s->n * WM_Q;
    cf.lo = -4.0 * WM_Q;
    cf.hi = (double)cf.S + 4.0 * WM_Q;
    wm_status st = WM_OK;
    if (!river_prims(&cf) || !lake_prims(&cf))
        st = WM_ERR_NOMEM;
    else if (cf.npr >= NO_ITEM || probe->s->nsegs + probe->s->nedges >= NO_ITEM)
        st = WM_OK; /* items and primitives need 32 bits: none found */
    else if (!bucket(&cf))
        st = WM_ERR_NOMEM;
    else if ((st = pairs(&cf)) == WM_OK && !keep_near(&cf, f))
        st = WM_ERR_NOMEM;
    if (st == WM_ERR_NOMEM)
        st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory finding corners");
    free(cf.pr);
    wm_cells_free(&cf.pg);
    free(cf.pb);
    free(cf.pc);
    free(cf.cand);
    return st;
}
