/*
 * block.c - the per-block pipeline (DESIGN: field -> extract -> simplify ->
 * holes -> triangulate). Blocks are independent: a block reads only the
 * scene, so any number run in parallel, and its output depends only on the
 * scene and the block index (invariants 1, 2, 7). Extraction includes the
 * recovery of sharp corners (crease.c).
 */
#define _POSIX_C_SOURCE 200809L
#include "block.h"

#include "cdt.h"
#include "refine.h"
#include "contour.h"
#include "crease.h"
#include "field.h"
#include "holes.h"
#include "merge.h"
#include "paper.h"
#include "pinch.h"
#include "simplify.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

double wm_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void wm_block_result_free(wm_block_result *res)
{
    if (!res)
        return;
    wm_rings_free(&res->rings);
    free(res->poly_ring);
    free(res->poly_tri);
    free(res->tris);
    free(res->xpts);
    free(res->z);
    free(res->zgrad);
    free(res->poly_body);
    memset(res, 0, sizeof *res);
}

static wm_status copy_ring(const wm_rings *in, size_t i, wm_rings *out)
{
    for (size_t k = in->start[i]; k < in->start[i + 1]; k++)
        if (wm_rings_push(out, in->pts[k]) != WM_OK)
            return WM_ERR_NOMEM;
    return wm_rings_close(out);
}

/* Thinner than this (twice the area over the perimeter, lattice units) a
 * ring inside the block is a remnant of rounding, not a feature: the exact
 * search keeps a feature narrower than a unit one unit wide where it is
 * widest, so a real one is about half a unit thick on average at least
 * (a thin triangle one unit high has 2A/P just under 0.5, and would still
 * be dropped; an island of three river banks 0.03 x 0.007 m at 0.5 m
 * pixels, 2A/P = 0.87, was dropped at 1.0). An empirical bound: none of
 * 10,800 held-out adversarial scenes lost a feature or kept a speck at
 * 0.5. */
#define WM_THIN 0.5

/* Whether ring i of `in` lies inside the block square [0, S]^2 (no vertex
 * on it) and is thinner than WM_THIN: what is left where a feature narrows
 * below a lattice unit next to a sharp vertex of an input (its pieces
 * would be specks). */
static int thin_ring(const wm_rings *in, size_t i, int32_t S)
{
    const wm_pt *p = in->pts + in->start[i];
    const size_t n = wm_rings_len(in, i);
    int64_t l1 = 0; /* the perimeter in x and y: at least the perimeter */
    for (size_t k = 0; k < n; k++)
    {
        const wm_pt a = p[k], b = p[k + 1 < n ? k + 1 : 0];
        if (a.x == 0 || a.y == 0 || a.x == S || a.y == S)
            return 0;
        l1 += llabs((int64_t)b.x - a.x) + llabs((int64_t)b.y - a.y);
    }
    const wm_i128 a2 = wm_ring_area2(p, n);
    if ((a2 < 0 ? -a2 : a2) >= WM_THIN * (double)l1)
        return 0; /* most rings: no square root */
    double perim = 0;
    for (size_t k = 0; k < n; k++)
    {
        const wm_pt a = p[k], b = p[k + 1 < n ? k + 1 : 0];
        const double dx = (double)b.x - a.x, dy = (double)b.y - a.y;
        perim += sqrt(dx * dx + dy * dy);
    }
    return (double)(a2 < 0 ? -a2 : a2) < WM_THIN * perim;
}

/* drop[i] = 1 for the thin rings (thin_ring) and every ring nested in one
 * (enc: the enclosing ring, or -1), which goes with it. */
static void thin_rings(const wm_rings *in, const int32_t *enc, int32_t S,
                       uint8_t *drop)
{
    for (size_t i = 0; i < in->nrings; i++)
        drop[i] = (uint8_t)thin_ring(in, i, S);
    for (size_t i = 0; i < in->nrings; i++)
        for (int32_t j = enc[i]; j >= 0 && !drop[i]; j = enc[j])
            drop[i] = drop[j];
}

/* Whether ring i holds no lattice point inside it: then it can hold no
 * other ring. By Pick's theorem, twice its area is 2I + B - 2 for I points
 * inside and B on it (B: the gcd of each edge's steps, summed). */
static int holds_no_point(const wm_rings *in, size_t i)
{
    const wm_pt *p = in->pts + in->start[i];
    const size_t n = wm_rings_len(in, i);
    int64_t on = 0;
    for (size_t k = 0; k < n; k++)
    {
        const wm_pt a = p[k], b = p[k + 1 < n ? k + 1 : 0];
        int64_t x = llabs((int64_t)b.x - a.x), y = llabs((int64_t)b.y - a.y);
        while (y)
        {
            const int64_t t = x % y;
            x = y;
            y = t;
        }
        on += x;
    }
    const wm_i128 a2 = wm_ring_area2(p, n);
    return (a2 < 0 ? -a2 : a2) == (wm_i128)on - 2;
}

/* Removes, in place, the thin rings (thin_ring) that hold no lattice
 * point (so no other ring) before simplification: such specks (a unit
 * across, left in a cell crowded with crossings) may cross another ring's
 * segment, which the simplifier takes for a fault (QA round 28);
 * thin_rings drops the others, and those simplification thins, after. */
static void drop_thin(wm_rings *r, int32_t S)
{
    size_t kept = 0, npts = 0;
    if (r->nrings == 0)
        return; /* no start[] yet */
    for (size_t i = 0; i < r->nrings; i++)
    {
        const wm_pt *p = r->pts + r->start[i];
        const size_t n = wm_rings_len(r, i);
        if (thin_ring(r, i, S) && holds_no_point(r, i))
            continue;
        memmove(r->pts + npts, p, n * sizeof *p);
        r->start[kept++] = npts;
        npts += n;
    }
    r->start[kept] = npts;
    r->nrings = kept;
    r->npts = npts;
}

/* Groups rings into polygons: each outer ring (in ring order) followed by
 * its holes (in ring order), copied into res->rings; rings with drop[i]
 * set are left out. */
static wm_status group(const wm_rings *in, const int32_t *enc,
                       const uint8_t *drop, wm_block_result *res,
                       const wm_ctx *ctx)
{
    const size_t nr = in->nrings;
    wm_status st = WM_OK;
    uint8_t *outer = malloc(nr + 1);
    size_t *hstart = calloc(nr + 1, sizeof *hstart), *cur = NULL;
    size_t *hole = NULL;
    size_t nouter = 0;
    if (!outer || !hstart)
        goto nomem;
    for (size_t i = 0; i < nr; i++)
        outer[i] =
            wm_ring_area2(in->pts + in->start[i], wm_rings_len(in, i)) > 0;
    /* nesting alternates: an outer ring lies in nothing or in a hole, a
     * hole in an outer ring */
    for (size_t i = 0; i < nr; i++)
    {
        if (drop[i])
            continue;
        if (outer[i] ? (enc[i] >= 0 && outer[enc[i]])
                     : (enc[i] < 0 || !outer[enc[i]]))
        {
            st = wm_fail(ctx, WM_ERR_INTERNAL,
                         "ring nesting does not alternate");
            goto cleanup;
        }
        if (outer[i])
            nouter++;
        else
            hstart[enc[i] + 1]++;
    }
    cur = wm_csr_begin(hstart, nr);
    hole = malloc((hstart[nr] + 1) * sizeof *hole);
    res->poly_ring = malloc((nouter + 1) * sizeof *res->poly_ring);
    if (!cur || !hole || !res->poly_ring)
        goto nomem;
    for (size_t i = 0; i < nr; i++)
        if (!outer[i] && !drop[i])
            hole[cur[enc[i]]++] = i;
    res->npolys = 0;
    for (size_t i = 0; i < nr; i++)
    {
        if (!outer[i] || drop[i])
            continue;
        res->poly_ring[res->npolys++] = res->rings.nrings;
        if (copy_ring(in, i, &res->rings) != WM_OK)
            goto nomem;
        for (size_t h = hstart[i]; h < hstart[i + 1]; h++)
            if (copy_ring(in, hole[h], &res->rings) != WM_OK)
                goto nomem;
    }
    res->poly_ring[res->npolys] = res->rings.nrings;
    goto cleanup;
nomem:
    st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory grouping polygons");
cleanup:
    free(outer);
    free(hstart);
    free(cur);
    free(hole);
    return st;
}

/* Appends polygon p's triangles t (nt, local indices: its ring points,
 * then its nx added points x) to res. */
static wm_status add_triangles(wm_block_result *res, size_t *cap, size_t p,
                               const uint32_t *t, size_t nt, size_t np,
                               const wm_pt *x, size_t nx)
{
    const size_t n = res->poly_tri[p],
                 base = res->rings.start[res->poly_ring[p]];
    const size_t xbase = res->rings.npts + res->nxpts;
    if (n + nt > *cap)
    {
        size_t nc = *cap ? *cap : 256;
        while (nc < n + nt)
            nc *= 2;
        uint32_t *q = realloc(res->tris, 3 * nc * sizeof *q);
        if (!q)
            return WM_ERR_NOMEM;
        res->tris = q;
        *cap = nc;
    }
    if (nx)
    {
        wm_pt *q = realloc(res->xpts, (res->nxpts + nx) * sizeof *q);
        if (!q)
            return WM_ERR_NOMEM;
        res->xpts = q;
        memcpy(res->xpts + res->nxpts, x, nx * sizeof *x);
        res->nxpts += nx;
    }
    for (size_t i = 0; i < 3 * nt; i++)
        res->tris[3 * n + i] =
            (uint32_t)(t[i] < np ? t[i] + base : t[i] - np + xbase);
    res->poly_tri[p + 1] = n + nt;
    return WM_OK;
}

/* The items that may hold a point of a block square's outline: the block's
 * river segments and lake polygons whose box (grown by the radius) meets
 * the outline. The room at a point of the outline is its depth in them
 * (wm_scene_depth), which the block across computes alike. */
typedef struct
{
    const wm_scene *s;
    uint32_t *ids; /* segs, then polys (owned) */
    size_t nsegs, npolys;
    wm_lake_bands lakes; /* of the polys */
} side_items;

static double side_room(void *user, int64_t X, int64_t Y, double cap)
{
    const side_items *si = user;
    return wm_scene_depth(si->s, si->ids, si->nsegs, &si->lakes, X, Y, cap);
}

/* Whether box b meets the outline of square q. */
static int meets_outline(wm_box b, wm_box q)
{
    return b.x0 <= q.x1 && b.x1 >= q.x0 && b.y0 <= q.y1 && b.y1 >= q.y0 &&
           !(b.x0 > q.x0 && b.x1 < q.x1 && b.y0 > q.y0 && b.y1 < q.y1);
}

static wm_status side_items_init(side_items *si, const wm_scene *s, int64_t bx,
                                 int64_t by)
{
    const wm_box q = wm_scene_block_box(s, bx, by);
    const wm_box blocks = {bx, by, bx, by};
    size_t nsegs, npolys, k = 0;
    memset(si, 0, sizeof *si);
    si->s = s;
    if (wm_scene_items(s, blocks, &si->ids, &nsegs, &npolys) != WM_OK)
        return WM_ERR_NOMEM;
    for (size_t i = 0; i < nsegs; i++)
    {
        const wm_river_seg *g = &s->segs[si->ids[i]];
        const int64_t r = (int64_t)ceil(g->r);
        const wm_box b = {(g->ax < g->bx ? g->ax : g->bx) - r,
                          (g->ay < g->by ? g->ay : g->by) - r,
                          (g->ax > g->bx ? g->ax : g->bx) + r,
                          (g->ay > g->by ? g->ay : g->by) + r};
        if (meets_outline(b, q))
            si->ids[k++] = si->ids[i];
    }
    si->nsegs = k;
    for (size_t i = nsegs; i < nsegs + npolys; i++)
        if (meets_outline(s->poly_box[si->ids[i]], q))
            si->ids[k++] = si->ids[i];
    si->npolys = k - si->nsegs;
    return wm_lake_bands_build(&si->lakes, s, si->ids + si->nsegs, si->npolys);
}

static void side_items_free(side_items *si)
{
    free(si->ids);
    wm_lake_bands_free(&si->lakes);
}

/* The refinement options of block (bx, by) (refine.h): what triangulate
 * refines by, and what simplify guards. */
static wm_refine_opts refine_opts(const wm_scene *s, int64_t bx, int64_t by,
                                  const wm_block_opts *opts, side_items *si,
                                  const wm_side_ends *ends)
{
    const int64_t S = (int64_t)s->n * WM_Q;
    const wm_refine_opts ro = {
        opts->min_angle, opts->max_edge, (int32_t)S, bx * S,
        by * S,          side_room,      si,         ends,
        opts->simplify};
    return ro;
}

/* Simplifies raw into simp (simplify.h). With MIN_ANGLE the shore is kept
 * out of the diametral circles of the pieces that refinement will cut the
 * block square's edges into and may not split
 * (wm_simplify_rings_guarded). */
static wm_status simplify(const wm_rings *raw, const wm_scene *s, int64_t bx,
                          int64_t by, const wm_block_opts *opts, wm_rings *simp,
                          const wm_ctx *ctx)
{
    const int32_t S = s->n * WM_Q;
    if (!opts->triangulate || !(opts->min_angle > 0) || !(opts->simplify > 0))
        return wm_simplify_rings(raw, S, opts->simplify, simp, ctx);
    side_items si;
    wm_side_ends ends;
    wm_side_piece *pc = NULL;
    size_t n = 0;
    memset(&ends, 0, sizeof ends);
    wm_status st = side_items_init(&si, s, bx, by);
    const wm_refine_opts ro = refine_opts(s, bx, by, opts, &si, &ends);
    if (st != WM_OK || !wm_side_ends_build(&ends, raw, S) ||
        !wm_side_pieces(raw, &ro, &pc, &n))
        st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory simplifying");
    else
        st =
            wm_simplify_rings_guarded(raw, S, opts->simplify, pc, n, simp, ctx);
    free(pc);
    side_items_free(&si);
    wm_side_ends_free(&ends);
    return st;
}

/* The constrained Delaunay triangulation of every polygon, refined to
 * MIN_ANGLE and MAX_EDGE when asked (refine.h). */
static wm_status triangulate(wm_block_result *res, const wm_scene *s,
                             const wm_block_opts *opts, const wm_ctx *ctx)
{
    const int refine = opts->min_angle > 0 || opts->max_edge > 0;
    const int64_t S = (int64_t)s->n * WM_Q;
    side_items si;
    wm_side_ends ends;
    const wm_refine_opts ro =
        refine_opts(s, res->bx, res->by, opts, &si, &ends);
    wm_refine_stats rs = {0, 0, 0, 0};
    size_t cap = 0;
    wm_status st = WM_OK;
    memset(&si, 0, sizeof si);
    memset(&ends, 0, sizeof ends);
    res->poly_tri = calloc(res->npolys + 1, sizeof *res->poly_tri);
    if (!res->poly_tri ||
        (opts->min_angle > 0 &&
         (side_items_init(&si, s, res->bx, res->by) != WM_OK ||
          !wm_side_ends_build(&ends, &res->rings, (int32_t)S))))
        st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory triangulating");
    for (size_t p = 0; st == WM_OK && p < res->npolys; p++)
    {
        const size_t r0 = res->poly_ring[p], r1 = res->poly_ring[p + 1];
        const size_t base = res->rings.start[r0];
        size_t *rs_ = malloc((r1 - r0 + 1) * sizeof *rs_);
        uint32_t *t = NULL;
        wm_pt *x = NULL;
        size_t nt = 0, nx = 0;
        if (!rs_)
        {
            st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory triangulating");
            break;
        }
        for (size_t r = r0; r <= r1; r++)
            rs_[r - r0] = res->rings.start[r] - base;
        const size_t np = rs_[r1 - r0];
        st = refine ? wm_refine_triangulate(res->rings.pts + base, rs_, r1 - r0,
                                            &ro, &t, &nt, &x, &nx, &rs, ctx)
                    : wm_cdt_triangulate(res->rings.pts + base, rs_, r1 - r0,
                                         &t, &nt, ctx);
        free(rs_);
        if (st == WM_OK &&
            add_triangles(res, &cap, p, t, nt, np, x, nx) != WM_OK)
            st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory triangulating");
        free(t);
        free(x);
    }
    side_items_free(&si);
    wm_side_ends_free(&ends);
    res->steiner = rs.steiner;
    res->small_input = rs.small_input;
    res->left = rs.left;
    res->at_side = rs.at_side;
    return st;
}

wm_status wm_block_field(const wm_scene *s, int64_t bx, int64_t by,
                         const wm_block_opts *opts, wm_field *f,
                         const wm_ctx *ctx)
{
    return wm_field_compute(s, bx * s->n, by * s->n, s->n + 1, s->n + 1,
                            opts->dev, f, ctx);
}

wm_status wm_block_run(const wm_scene *s, int64_t bx, int64_t by,
                       const wm_block_opts *opts, wm_block_result *res,
                       const wm_ctx *ctx)
{
    wm_field f;
    memset(res, 0, sizeof *res);
    const double t0 = wm_now();
    wm_status st = wm_block_field(s, bx, by, opts, &f, ctx);
    if (st != WM_OK)
        return st;
    const double t1 = wm_now();
    st = wm_block_finish(s, bx, by, &f, opts, res, ctx);
    res->seconds[WM_STAGE_FIELD] = t1 - t0;
    return st;
}

wm_status wm_block_finish(const wm_scene *s, int64_t bx, int64_t by,
                          wm_field *f, const wm_block_opts *opts,
                          wm_block_result *res, const wm_ctx *ctx)
{
    wm_status st;
    wm_rings raw, simp;
    int32_t *enc = NULL;
    uint8_t *drop = NULL;
    memset(res, 0, sizeof *res);
    memset(&raw, 0, sizeof raw);
    memset(&simp, 0, sizeof simp);
    res->bx = bx;
    res->by = by;
    res->mixed_tiles = f->mixed;
    res->samples = f->samples;
    res->pairs = f->pairs;

    const double t1 = wm_now();
    if (opts->method == WM_METHOD_PAPER)
    {
        st =
            wm_paper_extract(f, (wm_heuristic)opts->heuristic, &raw, NULL, ctx);
        res->contour_vertices = raw.npts;
    }
    else
    {
        wm_probe probe;
        st = wm_probe_init(&probe, s, bx, by);
        if (st != WM_OK)
            st = wm_fail(ctx, st, "out of memory extracting contours");
        if (st == WM_OK)
            st = wm_contour_extract_probed(f, &probe, &raw, ctx);
        res->contour_vertices = raw.npts;
        if (st == WM_OK)
            st = wm_crease_recover_probed(&probe, f, &raw, ctx);
        wm_probe_free(&probe);
    }
    wm_field_free(f);
    if (st == WM_OK)
        st = wm_rings_open_pinches(&raw, s->n * WM_Q, ctx);
    if (st == WM_OK)
    {
        wm_rings_drop_small(&raw, s->n * WM_Q, opts->min_area);
        drop_thin(&raw, s->n * WM_Q);
    }
    double t2 = wm_now();
    res->seconds[WM_STAGE_EXTRACT] = t2 - t1;
    if (st != WM_OK)
        goto cleanup;
    st = simplify(&raw, s, bx, by, opts, &simp, ctx);
    if (st == WM_OK && opts->merge > 0)
        st = wm_merge_rings(&simp, s->n * WM_Q, opts->merge, NULL, ctx);
    double t3 = wm_now();
    res->seconds[WM_STAGE_SIMPLIFY] = t3 - t2;
    if (st != WM_OK)
        goto cleanup;
    enc = malloc((simp.nrings + 1) * sizeof *enc);
    drop = malloc(simp.nrings + 1);
    if (!enc || !drop)
    {
        st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory");
        goto cleanup;
    }
    if (simp.nrings)
        st = wm_holes_nesting(&simp, enc, ctx);
    if (st == WM_OK)
    {
        thin_rings(&simp, enc, s->n * WM_Q, drop);
        st = group(&simp, enc, drop, res, ctx);
    }
    double t4 = wm_now();
    res->seconds[WM_STAGE_HOLES] = t4 - t3;
    if (st != WM_OK)
        goto cleanup;
    if (opts->triangulate)
        st = triangulate(res, s, opts, ctx);
    res->seconds[WM_STAGE_TRIANGULATE] = wm_now() - t4;
cleanup:
    free(enc);
    free(drop);
    wm_rings_free(&raw);
    wm_rings_free(&simp);
    if (st != WM_OK)
        wm_block_result_free(res);
    return st;
}
