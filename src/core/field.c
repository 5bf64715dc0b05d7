/*
 * field.c - signed distance field of a window of the global sample grid
 * (the paper's "texture generation", C path).
 *
 * Method. The window is split into tiles of WM_TILE x WM_TILE cells. River
 * segments (capsules) and lake edges are binned into the tiles they may
 * reach (the segment clipped against the tile grown by radius + band: a
 * conservative superset, which is enough because anything farther than the
 * band is clamped away). A tile
 * with nothing in reach is uniform: one inside test decides water or land
 * (invariant 6). In the other tiles every sample takes
 *   min( min_rivers |p - seg| - r,  min_lakes (+/-) |p - lake boundary| )
 * clamped to [-band, band] pixels, the sign of a lake term being its
 * even-odd parity at p (invariant 5: union by minimum).
 *
 * Inside tests are exact: for every sample row and lake polygon, the
 * crossings of the polygon's edges with the row are located with __int128
 * arithmetic as "first sample column right of the crossing" (half-open
 * rule on y, so a vertex on the row counts once), giving a per-row toggle
 * list. Parity at (c, r) = toggles at columns <= c.
 *
 * Reproducibility (invariant 2): sample and input coordinates are lattice
 * integers; their differences are formed in int64 and converted to double
 * exactly (|diff| < 2^53); the rest is plain IEEE double arithmetic with
 * contraction off (-ffp-contract=off), min and sqrt, all exact functions of
 * the operands. So a sample's value depends only on its global index and
 * the input, never on the window or tile that computed it.
 *
 * Narrow band (C path). Within a tile, the evaluation skips the 4 x 4
 * sub-blocks that a bound at their centre proves to lie wholly at -band
 * (inside a river or lake by more than the band) or at +band (see
 * narrow_band): the values are the same bits, only fewer are computed
 * (about a quarter of the samples of mixed tiles on the synthetic L3).
 *
 * Cost: O(samples in mixed tiles x items in reach + rows x polygon edges
 * spanning them), the first term only over the narrow band. Memory:
 * (WM_TILE+1)^2 floats per mixed tile, plus crossing lists over each polygon's
 * own rows (its box), never polygons x rows.
 */
#include "field.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static int64_t floordiv128(wm_i128 a, wm_i128 b)
{
    wm_i128 q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0)))
        q--;
    return (int64_t)q;
}

static int cmp_i32(const void *a, const void *b)
{
    const int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Working state of one window computation. */
typedef struct
{
    const wm_scene *s;
    wm_field *f;
    int64_t X0, Y0;               /* lattice of window sample (0, 0) */
    int64_t tsq;                  /* tile side, lattice */
    uint32_t *ids;                /* the window's items (owned) */
    const uint32_t *segs, *polys; /* in ids */
    size_t nsegs, npolys;
    /* tile lists (CSR over ntx*nty) */
    size_t *tseg_start;
    uint32_t *tseg;
    size_t *tedge_start;
    uint32_t *tedge;      /* global edge index */
    uint32_t *tedge_poly; /* local polygon index */
    /* polygon rows: polygon k spans window rows row0[k] .. row0[k] +
     * nrows[k] - 1 (its box), whose crossing lists have keys
     * key0[k] .. key0[k] + nrows[k] - 1; memory grows with the polygons'
     * heights, not with polygons x window rows */
    int32_t *row0, *nrows;
    size_t *key0;
    /* polygons whose box touches each tile (CSR over tiles) */
    size_t *tpoly_start;
    uint32_t *tpoly;
    uint8_t *base;
    size_t *tog_start;
    int32_t *tog;
    wm_lake_bands lakes; /* the window's polygons by bands of rows, built
                            when a sample on a block line is 0 (lakes.s
                            NULL until then) */
} work;

/* Tile index range touched by the closed box [a, b] (lattice, x or y). */
static void tile_span(int64_t a, int64_t b, int64_t origin, int64_t tsq,
                      int32_t nt, int32_t *lo, int32_t *hi)
{
    int64_t l = wm_floordiv(a - origin - 1, tsq),
            h = wm_floordiv(b - origin, tsq);
    if (l < 0)
        l = 0;
    if (h > nt - 1)
        h = nt - 1;
    *lo = (int32_t)l;
    *hi = (int32_t)h;
}

/* True when segment [a, b] passes within `grow` (lattice units, a
 * square neighbourhood: a superset of the round one) of tile (tx, ty):
 * Liang-Barsky clipping against the tile's box grown by grow + 2 (the
 * extra two units absorb rounding, so no segment in reach is ever left
 * out; one out of reach may be kept, which costs time, never accuracy). */
static int seg_reaches_tile(const work *w, int32_t tx, int32_t ty, int64_t ax,
                            int64_t ay, int64_t bx, int64_t by, int64_t grow)
{
    const int64_t x0 = w->X0 + (int64_t)tx * w->tsq - grow - 2;
    const int64_t y0 = w->Y0 + (int64_t)ty * w->tsq - grow - 2;
    const double wx = (double)(w->tsq + 2 * (grow + 2));
    const double px = (double)(ax - x0), py = (double)(ay - y0);
    double t0, t1;
    return wm_clip_box(px, py, (double)(bx - ax), (double)(by - ay), wx, wx,
                       &t0, &t1);
}

static wm_status bin_items(work *w)
{
    const wm_scene *s = w->s;
    wm_field *f = w->f;
    const size_t nt = (size_t)f->ntx * (size_t)f->nty;
    const int64_t band = (int64_t)s->band * WM_Q + 1;
    w->tseg_start = calloc(nt + 1, sizeof(size_t));
    w->tedge_start = calloc(nt + 1, sizeof(size_t));
    if (!w->tseg_start || !w->tedge_start)
        return WM_ERR_NOMEM;
    for (int pass = 0; pass < 2; pass++)
    {
        size_t *cs = w->tseg_start + 1, *ce = w->tedge_start + 1;
        if (pass == 1)
        {
            cs = wm_csr_begin(w->tseg_start, nt);
            ce = wm_csr_begin(w->tedge_start, nt);
            w->tseg = malloc((w->tseg_start[nt] + 1) * sizeof *w->tseg);
            w->tedge = malloc((w->tedge_start[nt] + 1) * sizeof *w->tedge);
            w->tedge_poly =
                malloc((w->tedge_start[nt] + 1) * sizeof *w->tedge_poly);
            if (!cs || !ce || !w->tseg || !w->tedge || !w->tedge_poly)
            {
                free(cs);
                free(ce);
                return WM_ERR_NOMEM;
            }
        }
        for (size_t i = 0; i < w->nsegs; i++)
        {
            const wm_river_seg *g = &s->segs[w->segs[i]];
            const int64_t grow = (int64_t)ceil(g->r) + band;
            int32_t tx0, tx1, ty0, ty1;
            tile_span((g->ax < g->bx ? g->ax : g->bx) - grow,
                      (g->ax > g->bx ? g->ax : g->bx) + grow, w->X0, w->tsq,
                      f->ntx, &tx0, &tx1);
            tile_span((g->ay < g->by ? g->ay : g->by) - grow,
                      (g->ay > g->by ? g->ay : g->by) + grow, w->Y0, w->tsq,
                      f->nty, &ty0, &ty1);
            for (int32_t ty = ty0; ty <= ty1; ty++)
                for (int32_t tx = tx0; tx <= tx1; tx++)
                {
                    const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
                    if (!seg_reaches_tile(w, tx, ty, g->ax, g->ay, g->bx, g->by,
                                          grow))
                        continue;
                    if (pass == 0)
                        cs[t]++;
                    else
                        w->tseg[cs[t]++] = w->segs[i];
                }
        }
        for (size_t k = 0; k < w->npolys; k++)
        {
            const uint32_t p = w->polys[k];
            for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
            {
                const wm_lake_edge *g = &s->edges[e];
                int32_t tx0, tx1, ty0, ty1;
                tile_span((g->ax < g->bx ? g->ax : g->bx) - band,
                          (g->ax > g->bx ? g->ax : g->bx) + band, w->X0, w->tsq,
                          f->ntx, &tx0, &tx1);
                tile_span((g->ay < g->by ? g->ay : g->by) - band,
                          (g->ay > g->by ? g->ay : g->by) + band, w->Y0, w->tsq,
                          f->nty, &ty0, &ty1);
                for (int32_t ty = ty0; ty <= ty1; ty++)
                    for (int32_t tx = tx0; tx <= tx1; tx++)
                    {
                        const size_t t =
                            (size_t)ty * (size_t)f->ntx + (size_t)tx;
                        if (!seg_reaches_tile(w, tx, ty, g->ax, g->ay, g->bx,
                                              g->by, band))
                            continue;
                        if (pass == 0)
                            ce[t]++;
                        else
                        {
                            w->tedge[ce[t]] = (uint32_t)e;
                            w->tedge_poly[ce[t]++] = (uint32_t)k;
                        }
                    }
            }
        }
        if (pass == 1)
        {
            free(cs);
            free(ce);
        }
    }
    return WM_OK;
}

/* Polygons whose box touches each tile: the candidates of the one inside
 * test that makes a tile without edges in reach uniform water. */
static wm_status bin_polys(work *w)
{
    const wm_field *f = w->f;
    const size_t nt = (size_t)f->ntx * (size_t)f->nty;
    size_t *cur = NULL;
    w->tpoly_start = calloc(nt + 1, sizeof *w->tpoly_start);
    if (!w->tpoly_start)
        return WM_ERR_NOMEM;
    for (int pass = 0; pass < 2; pass++)
    {
        for (size_t k = 0; k < w->npolys; k++)
        {
            const wm_box b = w->s->poly_box[w->polys[k]];
            int32_t tx0, tx1, ty0, ty1;
            tile_span(b.x0, b.x1, w->X0, w->tsq, f->ntx, &tx0, &tx1);
            tile_span(b.y0, b.y1, w->Y0, w->tsq, f->nty, &ty0, &ty1);
            for (int32_t ty = ty0; ty <= ty1; ty++)
                for (int32_t tx = tx0; tx <= tx1; tx++)
                {
                    const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
                    if (pass == 0)
                        w->tpoly_start[t + 1]++;
                    else
                        w->tpoly[cur[t]++] = (uint32_t)k;
                }
        }
        if (pass == 0)
        {
            cur = wm_csr_begin(w->tpoly_start, nt);
            w->tpoly = malloc((w->tpoly_start[nt] + 1) * sizeof *w->tpoly);
            if (!w->tpoly || !cur)
            {
                free(cur);
                return WM_ERR_NOMEM;
            }
        }
    }
    free(cur);
    return WM_OK;
}

/* Row crossings of every gathered polygon: base parity (crossings left of
 * column 0) and sorted toggle columns in 1 .. w-1. */
static wm_status build_crossings(work *w)
{
    const wm_scene *s = w->s;
    const wm_field *f = w->f;
    w->row0 = malloc((w->npolys + 1) * sizeof *w->row0);
    w->nrows = malloc((w->npolys + 1) * sizeof *w->nrows);
    w->key0 = malloc((w->npolys + 1) * sizeof *w->key0);
    if (!w->row0 || !w->nrows || !w->key0)
        return WM_ERR_NOMEM;
    size_t nkeys = 0;
    for (size_t k = 0; k < w->npolys; k++)
    {
        const wm_box b = s->poly_box[w->polys[k]];
        int64_t r0 = -wm_floordiv(-b.y0, WM_Q) - f->gy0;
        int64_t r1 = wm_floordiv(b.y1, WM_Q) - f->gy0;
        if (r0 < 0)
            r0 = 0;
        if (r1 > f->h - 1)
            r1 = f->h - 1;
        w->row0[k] = (int32_t)r0;
        w->nrows[k] = r1 >= r0 ? (int32_t)(r1 - r0 + 1) : 0;
        w->key0[k] = nkeys;
        nkeys += (size_t)w->nrows[k];
    }
    w->base = calloc(nkeys + 1, 1);
    w->tog_start = calloc(nkeys + 1, sizeof(size_t));
    if (!w->base || !w->tog_start)
        return WM_ERR_NOMEM;
    size_t *cursor = NULL;
    for (int pass = 0; pass < 2; pass++)
    {
        if (pass == 1)
        {
            cursor = wm_csr_begin(w->tog_start, nkeys);
            w->tog = malloc((w->tog_start[nkeys] + 1) * sizeof *w->tog);
            if (!w->tog || !cursor)
            {
                free(cursor);
                return WM_ERR_NOMEM;
            }
        }
        for (size_t k = 0; k < w->npolys; k++)
        {
            const uint32_t p = w->polys[k];
            for (size_t e = s->poly_start[p]; e < s->poly_start[p + 1]; e++)
            {
                const wm_lake_edge *g = &s->edges[e];
                if (g->ay == g->by)
                    continue;
                int64_t xa = g->ax, ya = g->ay, xb = g->bx, yb = g->by;
                if (ya > yb)
                {
                    xa = g->bx;
                    ya = g->by;
                    xb = g->ax;
                    yb = g->ay;
                }
                /* rows with Y in [ya, yb) */
                int64_t r0 = -wm_floordiv(-ya, WM_Q) - f->gy0;
                int64_t r1 = -wm_floordiv(-yb, WM_Q) - 1 - f->gy0;
                if (r0 < 0)
                    r0 = 0;
                if (r1 > f->h - 1)
                    r1 = f->h - 1;
                const int64_t dy = yb - ya;
                for (int64_t r = r0; r <= r1; r++)
                {
                    const int64_t Y = (f->gy0 + r) * WM_Q;
                    const wm_i128 num = (wm_i128)(xa - w->X0) * dy +
                                        (wm_i128)(Y - ya) * (xb - xa);
                    const int64_t c = floordiv128(num, (wm_i128)dy * WM_Q) + 1;
                    const size_t key = w->key0[k] + (size_t)(r - w->row0[k]);
                    if (c <= 0)
                    {
                        if (pass == 0)
                            w->base[key] ^= 1;
                    }
                    else if (c < f->w)
                    {
                        if (pass == 0)
                            w->tog_start[key + 1]++;
                        else
                            w->tog[cursor[key]++] = (int32_t)c;
                    }
                }
            }
        }
    }
    free(cursor);
    for (size_t key = 0; key < nkeys; key++)
    {
        const size_t n = w->tog_start[key + 1] - w->tog_start[key];
        if (n > 1)
            qsort(w->tog + w->tog_start[key], n, sizeof *w->tog, cmp_i32);
    }
    return WM_OK;
}

/* Crossing-list key of polygon k on window row r, or SIZE_MAX when the
 * row is outside the polygon's box (no crossing, parity 0). */
static size_t row_key(const work *w, size_t k, int32_t r)
{
    if (r < w->row0[k] || r >= w->row0[k] + w->nrows[k])
        return SIZE_MAX;
    return w->key0[k] + (size_t)(r - w->row0[k]);
}

/* Parity bits of local polygon k along window row r, tile columns c0 ..
 * c0 + WM_TILE: bit q is the parity at column c0 + q. Rows outside the
 * polygon's box (and so outside the window) are all zero. */
static uint64_t parity_row(const work *w, size_t k, int32_t r, int32_t c0)
{
    const size_t key = row_key(w, k, r);
    if (key == SIZE_MAX)
        return 0;
    /* bit q: the base parity flipped by every crossing at or left of
     * c0 + q; those left of the tile found by bisection, each inside it
     * flips bits q and up */
    const uint64_t all = (UINT64_C(1) << WM_TS1) - 1;
    const size_t t0 = w->tog_start[key], te = w->tog_start[key + 1];
    size_t lo = t0, hi = te; /* first crossing > c0 */
    while (lo < hi)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (w->tog[mid] <= c0)
            lo = mid + 1;
        else
            hi = mid;
    }
    uint64_t m = (w->base[key] ^ ((lo - t0) & 1)) ? all : 0;
    for (size_t ti = lo; ti < te && w->tog[ti] <= c0 + WM_TILE; ti++)
        m ^= all & (all << (w->tog[ti] - c0));
    return m;
}

#define TS1 WM_TS1

/* The tile loops below run over full tiles: samples beyond the window are
 * computed too (fixed trip counts vectorize) and never read. (X, Y) is the
 * lattice position of tile sample (0, 0). */

/* Squared distance from p to segment [0, ab] (p relative to a); inv =
 * 1 / |ab|^2, or 0 for a point. Inlined into each vector clone. */
static inline double seg_d2(double px, double py, double abx, double aby,
                            double inv)
{
    double t = (px * abx + py * aby) * inv;
    t = t < 0.0 ? 0.0 : t;
    t = t > 1.0 ? 1.0 : t;
    const double dx = px - t * abx, dy = py - t * aby;
    return dx * dx + dy * dy;
}

/* Rows [*j0, *j1] of a tile whose sample (0, 0) is at lattice y Y that lie
 * within `reach` (lattice units, plus one for rounding) of the y-extent of
 * [a, b]; every other row is farther than reach from the segment in y
 * alone, so a term clamped at reach cannot lower its samples' values. */
static void row_span(int64_t Y, int64_t ay, int64_t by, double reach,
                     int32_t *j0, int32_t *j1)
{
    const int64_t y0 = ay < by ? ay : by, y1 = ay > by ? ay : by;
    const double lo = ceil(((double)(y0 - Y) - reach - 1.0) / WM_Q);
    const double hi = floor(((double)(y1 - Y) + reach + 1.0) / WM_Q);
    *j0 = lo < 0 ? 0 : (lo > TS1 ? TS1 : (int32_t)lo);
    *j1 = hi < -1 ? -1 : (hi > TS1 - 1 ? TS1 - 1 : (int32_t)hi);
}

/* Sub-blocks: the tile's samples in NSB x NSB blocks of SB x SB, the last
 * row and column of blocks one sample larger (they hold sample WM_TILE).
 * Sample (i, j) is in block (sb_of(i), sb_of(j)). */
#define SB 4
#define NSB (WM_TILE / SB)

static inline int32_t sb_of(int32_t i)
{
    return i / SB < NSB ? i / SB : NSB - 1;
}

/* Last sample of sub-block b along an axis (its first is b * SB). */
static inline int32_t sb_last(int32_t b)
{
    return b < NSB - 1 ? b * SB + SB - 1 : WM_TILE;
}

/* The samples of a tile a batch evaluates: per row of sub-blocks, the
 * columns lo .. hi (lo > hi: none) spanning its active blocks. */
typedef struct
{
    int32_t lo[NSB], hi[NSB];
} span;

/* v = min(v, |p - seg| - r) over the spanned samples of a tile, v <= bandl:
 * rows farther than r + bandl from the segment are left alone (the term
 * exceeds v). */
WM_CLONES
static uint64_t river_min(const wm_river_seg *g, int64_t X, int64_t Y,
                          double *v, double bandl, const span *sp)
{
    const double abx = (double)(g->bx - g->ax), aby = (double)(g->by - g->ay);
    const double len2 = abx * abx + aby * aby;
    const double inv = len2 > 0 ? 1.0 / len2 : 0.0;
    const double ox = (double)(X - g->ax), oy = (double)(Y - g->ay);
    const double r = g->r;
    int32_t j0, j1, i0, i1;
    row_span(Y, g->ay, g->by, r + bandl, &j0, &j1);
    row_span(X, g->ax, g->bx, r + bandl, &i0, &i1); /* columns alike */
    uint64_t n = 0;
    for (int32_t j = j0; j <= j1; j++)
    {
        const double py = oy + (double)j * WM_Q;
        double *row = v + j * TS1;
        const int32_t lo = sp->lo[sb_of(j)] > i0 ? sp->lo[sb_of(j)] : i0;
        const int32_t hi = sp->hi[sb_of(j)] < i1 ? sp->hi[sb_of(j)] : i1;
        for (int32_t i = lo; i <= hi; i++)
        {
            const double d =
                sqrt(seg_d2(ox + (double)i * WM_Q, py, abx, aby, inv)) - r;
            const double cur = row[i];
            row[i] = d < cur ? d : cur;
        }
        n += (uint64_t)(hi >= lo ? hi - lo + 1 : 0);
    }
    return n;
}

/* du2 = min(du2, d^2 to edge) over the spanned samples of a tile; rows
 * farther than bandl from the edge are left alone (as if the edge were out
 * of reach: the distance only matters up to the clamp). */
WM_CLONES
static uint64_t edge_min2(const wm_lake_edge *g, int64_t X, int64_t Y,
                          double *du2, double bandl, const span *sp)
{
    const double abx = (double)(g->bx - g->ax), aby = (double)(g->by - g->ay);
    const double len2 = abx * abx + aby * aby;
    const double inv = len2 > 0 ? 1.0 / len2 : 0.0;
    const double ox = (double)(X - g->ax), oy = (double)(Y - g->ay);
    int32_t j0, j1, i0, i1;
    row_span(Y, g->ay, g->by, bandl, &j0, &j1);
    row_span(X, g->ax, g->bx, bandl, &i0, &i1);
    uint64_t n = 0;
    for (int32_t j = j0; j <= j1; j++)
    {
        const double py = oy + (double)j * WM_Q;
        double *row = du2 + j * TS1;
        const int32_t lo = sp->lo[sb_of(j)] > i0 ? sp->lo[sb_of(j)] : i0;
        const int32_t hi = sp->hi[sb_of(j)] < i1 ? sp->hi[sb_of(j)] : i1;
        for (int32_t i = lo; i <= hi; i++)
        {
            const double px = ox + (double)i * WM_Q;
            /* a sample on the edge is exactly 0 away, so water (the
             * closed rule; the projection's rounding would leave it a few
             * ulps off, either side of the shore by its parity): the
             * cross product of lattice differences is exact in double
             * below 2^53 (beyond, the OpenCL kernel rounds it alike); an
             * edge of no length is a point */
            const double dot = px * abx + py * aby;
            const double d2 =
                len2 > 0 && px * aby == py * abx && dot >= 0 && dot <= len2
                    ? 0.0
                    : seg_d2(px, py, abx, aby, inv);
            const double cur = row[i];
            row[i] = d2 < cur ? d2 : cur;
        }
        n += (uint64_t)(hi >= lo ? hi - lo + 1 : 0);
    }
    return n;
}

/* v = min(v, +/- sqrt(du2)) over the spanned samples of a tile, the sign
 * - where the polygon's parity bit is set (multiplying by +/-1 is exact). */
WM_CLONES
static void lake_min(const double *du2, const uint64_t *mask, double *v,
                     const span *sp)
{
    for (int32_t j = 0; j < TS1; j++)
    {
        const uint64_t m = mask[j];
        const int32_t lo = sp->lo[sb_of(j)], hi = sp->hi[sb_of(j)];
        for (int32_t q = lo; q <= hi; q++)
        {
            const double sign = 1.0 - 2.0 * (double)((m >> q) & 1);
            const double d = sign * sqrt(du2[j * TS1 + q]);
            v[j * TS1 + q] = d < v[j * TS1 + q] ? d : v[j * TS1 + q];
        }
    }
}

/* Centre and half-extent, in samples, of sub-block b along an axis. */
static inline double sb_centre(int32_t b)
{
    return (b * SB + sb_last(b)) / 2.0;
}

static inline double sb_half(int32_t b)
{
    return (sb_last(b) - b * SB) / 2.0;
}

/* d2 = squared distances from the sub-block centres of a tile (sample
 * (0, 0) at lattice (X, Y)) to segment [a, b]. */
WM_CLONES
static void centre_d2(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t X,
                      int64_t Y, double *d2)
{
    const double abx = (double)(bx - ax), aby = (double)(by - ay);
    const double len2 = abx * abx + aby * aby;
    const double inv = len2 > 0 ? 1.0 / len2 : 0.0;
    const double ox = (double)(X - ax), oy = (double)(Y - ay);
    for (int32_t b = 0; b < NSB; b++)
        for (int32_t a = 0; a < NSB; a++)
            d2[b * NSB + a] = seg_d2(ox + sb_centre(a) * WM_Q,
                                     oy + sb_centre(b) * WM_Q, abx, aby, inv);
}

/* The narrow band of batch tile k (sample (0, 0) at lattice (X, Y)): sets
 * v to its starting values and *sp to the samples to evaluate.
 *
 * A sub-block of half-diagonal h (lattice) whose centre c has
 *   - a river term |c - seg| - r <= -tol, tol = bandl + h + 1, has that
 *     term below -bandl - 1 at each of its samples (the term is
 *     1-Lipschitz), so every sample there ends at -band: "deep";
 *   - a lake polygon's edges in reach all >= tol from c, so none crosses
 *     the block and its parity is the same at every sample (the mask's,
 *     at the block's first sample), and its term at each sample is at
 *     least bandl + 1 in magnitude: with parity 1 the block is deep;
 *   - every river term >= tol and every lake as above with parity 0: every
 *     term is at least bandl + 1 at each sample, which ends at +band: "far".
 * Deep samples start at -bandl, the others at +bandl; the evaluation then
 * leaves them where they are (a min can only keep a deep sample at or below
 * -bandl, and no term goes below bandl at a far one), so it may skip them:
 * the values are those of the whole tile's evaluation, bit for bit. The
 * margin of one lattice unit dwarfs the rounding of double arithmetic on
 * coordinates below 2^40. */
WM_CLONES
static void narrow_band(const wm_field_batch *bt, size_t k, int64_t X,
                        int64_t Y, double bandl, double *v, span *sp)
{
    const wm_scene *s = bt->s;
    double cm[NSB * NSB], ce2[NSB * NSB], tol[NSB * NSB], d2[NSB * NSB];
    uint8_t deep[NSB * NSB], far[NSB * NSB];
    for (int32_t b = 0; b < NSB; b++)
        for (int32_t a = 0; a < NSB; a++)
        {
            const double ha = sb_half(a), hb = sb_half(b);
            tol[b * NSB + a] = bandl + 1.0 + sqrt(ha * ha + hb * hb) * WM_Q;
            cm[b * NSB + a] = INFINITY;
        }
    for (size_t i = bt->seg_start[k]; i < bt->seg_start[k + 1]; i++)
    {
        const wm_river_seg *g = &s->segs[bt->seg[i]];
        centre_d2(g->ax, g->ay, g->bx, g->by, X, Y, d2);
        for (int32_t q = 0; q < NSB * NSB; q++)
        {
            const double d = sqrt(d2[q]) - g->r;
            cm[q] = d < cm[q] ? d : cm[q];
        }
    }
    for (int32_t q = 0; q < NSB * NSB; q++)
    {
        deep[q] = cm[q] <= -tol[q];
        far[q] = cm[q] >= tol[q];
    }
    for (size_t g = bt->grp_start[k]; g < bt->grp_start[k + 1]; g++)
    {
        for (int32_t q = 0; q < NSB * NSB; q++)
            ce2[q] = INFINITY;
        for (size_t i = bt->edge_start[g]; i < bt->edge_start[g + 1]; i++)
        {
            const wm_lake_edge *e = &s->edges[bt->edge[i]];
            centre_d2(e->ax, e->ay, e->bx, e->by, X, Y, d2);
            for (int32_t q = 0; q < NSB * NSB; q++)
                ce2[q] = d2[q] < ce2[q] ? d2[q] : ce2[q];
        }
        for (int32_t b = 0; b < NSB; b++)
            for (int32_t a = 0; a < NSB; a++)
            {
                const int32_t q = b * NSB + a;
                if (ce2[q] < tol[q] * tol[q])
                    far[q] = 0;
                else if ((bt->mask[g * TS1 + (size_t)(b * SB)] >> (a * SB)) & 1)
                    deep[q] = 1;
            }
    }
    for (int32_t q = 0; q < TS1 * TS1; q++)
        v[q] = bandl;
    for (int32_t b = 0; b < NSB; b++)
        for (int32_t a = 0; a < NSB; a++)
            if (deep[b * NSB + a])
                for (int32_t j = b * SB; j <= sb_last(b); j++)
                    for (int32_t i = a * SB; i <= sb_last(a); i++)
                        v[j * TS1 + i] = -bandl;
    for (int32_t b = 0; b < NSB; b++)
    {
        sp->lo[b] = TS1;
        sp->hi[b] = -1;
        for (int32_t a = 0; a < NSB; a++)
            if (!deep[b * NSB + a] && !far[b * NSB + a])
            {
                sp->lo[b] = sp->lo[b] < a * SB ? sp->lo[b] : a * SB;
                sp->hi[b] = sb_last(a);
            }
    }
}

/* out = v clamped below at -bandl, in pixels. */
WM_CLONES
static void clamp_out(const double *v, double bandl, float *out)
{
    for (int32_t j = 0; j < TS1 * TS1; j++)
    {
        const double d = v[j] < -bandl ? -bandl : v[j];
        out[j] = (float)(d / WM_Q);
    }
}

wm_status wm_field_eval_c(void *user, const wm_field_batch *b,
                          const wm_ctx *ctx)
{
    (void)user;
    (void)ctx;
    const wm_scene *s = b->s;
    const double bandl = (double)s->band * WM_Q;
    double v[TS1 * TS1], du2[TS1 * TS1];
    uint64_t samples = 0, pairs = 0;
    for (size_t k = 0; k < b->ntiles; k++)
    {
        const int64_t X = b->org[2 * k], Y = b->org[2 * k + 1];
        span sp;
        narrow_band(b, k, X, Y, bandl, v, &sp);
        for (int32_t j = 0; j < TS1; j++)
            samples += (uint64_t)(sp.hi[sb_of(j)] >= sp.lo[sb_of(j)]
                                      ? sp.hi[sb_of(j)] - sp.lo[sb_of(j)] + 1
                                      : 0);
        for (size_t i = b->seg_start[k]; i < b->seg_start[k + 1]; i++)
            pairs += river_min(&s->segs[b->seg[i]], X, Y, v, bandl, &sp);
        for (size_t g = b->grp_start[k]; g < b->grp_start[k + 1]; g++)
        {
            for (int32_t j = 0; j < TS1; j++) /* what edge_min2 may set */
                for (int32_t i = sp.lo[sb_of(j)]; i <= sp.hi[sb_of(j)]; i++)
                    du2[j * TS1 + i] = INFINITY;
            for (size_t i = b->edge_start[g]; i < b->edge_start[g + 1]; i++)
                pairs +=
                    edge_min2(&s->edges[b->edge[i]], X, Y, du2, bandl, &sp);
            lake_min(du2, b->mask + g * TS1, v, &sp);
        }
        clamp_out(v, bandl, b->val + k * TS1 * TS1);
    }
    if (b->samples)
        *b->samples += samples;
    if (b->pairs)
        *b->pairs += pairs;
    return WM_OK;
}

/* Tile (tx, ty) is uniform when nothing is in reach, or when a gathered
 * polygon without edges in reach contains it: then its kind is set and 1
 * returned. Otherwise its samples need evaluating: 0. */
static int uniform_tile(work *w, int32_t tx, int32_t ty, uint8_t *haspoly)
{
    const wm_scene *s = w->s;
    wm_field *f = w->f;
    const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
    const size_t e0 = w->tedge_start[t], e1 = w->tedge_start[t + 1];
    for (size_t i = e0; i < e1; i++)
        haspoly[w->tedge_poly[i]] = 1;
    int water = 0;
    const int32_t c0 = tx * WM_TILE, r0 = ty * WM_TILE;
    const int64_t X = w->X0 + (int64_t)c0 * WM_Q,
                  Y = w->Y0 + (int64_t)r0 * WM_Q;
    for (size_t i = w->tpoly_start[t]; i < w->tpoly_start[t + 1] && !water; i++)
    {
        const size_t k = w->tpoly[i];
        const wm_box b = s->poly_box[w->polys[k]];
        if (!haspoly[k] && X >= b.x0 && X <= b.x1 && Y >= b.y0 && Y <= b.y1 &&
            (parity_row(w, k, r0, c0) & 1))
            water = 1;
    }
    for (size_t i = e0; i < e1; i++)
        haspoly[w->tedge_poly[i]] = 0;
    if (water || (w->tseg_start[t] == w->tseg_start[t + 1] && e0 == e1))
    {
        f->kind[t] = (uint8_t)(water ? WM_TILE_WATER : WM_TILE_LAND);
        return 1;
    }
    return 0;
}

/* A batch under assembly: the arrays behind a wm_field_batch, reused from
 * one batch to the next. */
typedef struct
{
    int64_t *org;
    size_t *seg_start, *grp_start, *edge_start;
    uint32_t *seg, *edge;
    uint64_t *mask;
    size_t cap_seg, cap_edge, cap_mask, cap_grp;
} batch_buf;

static void batch_buf_free(batch_buf *bb)
{
    free(bb->org);
    free(bb->seg_start);
    free(bb->grp_start);
    free(bb->edge_start);
    free(bb->seg);
    free(bb->edge);
    free(bb->mask);
}

/* Fills the batch of window tiles tiles[0 .. n-1]. */
static wm_status build_batch(const work *w, const size_t *tiles, size_t n,
                             batch_buf *bb, wm_field_batch *b)
{
    const wm_field *f = w->f;
    size_t nseg = 0, ngrp = 0, nedge = 0;
    if (!wm_grow((void **)&bb->edge_start, &bb->cap_grp, 1,
                 sizeof *bb->edge_start))
        return WM_ERR_NOMEM;
    bb->seg_start[0] = bb->grp_start[0] = bb->edge_start[0] = 0;
    for (size_t k = 0; k < n; k++)
    {
        const size_t t = tiles[k];
        const int32_t c0 = (int32_t)(t % (size_t)f->ntx) * WM_TILE;
        const int32_t r0 = (int32_t)(t / (size_t)f->ntx) * WM_TILE;
        bb->org[2 * k] = w->X0 + (int64_t)c0 * WM_Q;
        bb->org[2 * k + 1] = w->Y0 + (int64_t)r0 * WM_Q;
        const size_t s0 = w->tseg_start[t], s1 = w->tseg_start[t + 1];
        if (!wm_grow((void **)&bb->seg, &bb->cap_seg, nseg + (s1 - s0) + 1,
                     sizeof *bb->seg))
            return WM_ERR_NOMEM;
        memcpy(bb->seg + nseg, w->tseg + s0, (s1 - s0) * sizeof *bb->seg);
        nseg += s1 - s0;
        bb->seg_start[k + 1] = nseg;
        /* the tile's edges come grouped by polygon (bin_items appends them
         * polygon by polygon) */
        const size_t e1 = w->tedge_start[t + 1];
        for (size_t i = w->tedge_start[t]; i < e1;)
        {
            const uint32_t p = w->tedge_poly[i];
            const size_t i0 = i;
            while (i < e1 && w->tedge_poly[i] == p)
                i++;
            if (!wm_grow((void **)&bb->edge, &bb->cap_edge,
                         nedge + (i - i0) + 1, sizeof *bb->edge) ||
                !wm_grow((void **)&bb->mask, &bb->cap_mask, (ngrp + 1) * TS1,
                         sizeof *bb->mask) ||
                !wm_grow((void **)&bb->edge_start, &bb->cap_grp, ngrp + 2,
                         sizeof *bb->edge_start))
                return WM_ERR_NOMEM;
            memcpy(bb->edge + nedge, w->tedge + i0,
                   (i - i0) * sizeof *bb->edge);
            nedge += i - i0;
            for (int32_t j = 0; j < TS1; j++)
                bb->mask[ngrp * TS1 + (size_t)j] = parity_row(w, p, r0 + j, c0);
            ngrp++;
            bb->edge_start[ngrp] = nedge;
        }
        bb->grp_start[k + 1] = ngrp;
    }
    b->s = w->s;
    b->ntiles = n;
    b->org = bb->org;
    b->seg_start = bb->seg_start;
    b->seg = bb->seg;
    b->grp_start = bb->grp_start;
    b->ngroups = ngrp;
    b->edge_start = bb->edge_start;
    b->edge = bb->edge;
    b->mask = bb->mask;
    b->val = NULL; /* the caller's */
    return WM_OK;
}

/* The compare and the shift by the lane's index vectorize (a compare, a
 * variable shift, an OR reduction), where bytes gathered one by one did
 * not; the row's last sample goes apart (WM_TILE bits fill a word). */
_Static_assert(WM_TILE <= 32, "a tile row's bits are built in 32 bits");

WM_CLONES static void row_bits(const float *row, uint64_t *b)
{
    uint32_t w = 0, nr = 0;
    for (uint32_t i = 0; i < WM_TILE; i++)
    {
        w |= (uint32_t)(row[i] <= 0) << i;
        nr |= (uint32_t)(fabsf(row[i]) < 1.0f) << i;
    }
    b[0] = w | (uint64_t)(row[WM_TILE] <= 0) << WM_TILE;
    b[1] = nr | (uint64_t)(fabsf(row[WM_TILE]) < 1.0f) << WM_TILE;
}

/* Appends tile t, MIXED, to f's list and its rows' bits; the caller has
 * made room for it. */
static void index_tile(wm_field *f, size_t t)
{
    f->mixed_tile[f->mixed] = (uint32_t)t;
    for (int32_t j = 0; j < TS1; j++)
        row_bits(f->val[t] + j * TS1, f->bits + (f->mixed * TS1 + j) * 2);
    f->mixed++;
}

/* Room in f's list of MIXED tiles and their bits for n more. */
static int index_room(wm_field *f, size_t n, size_t *cap)
{
    if (f->mixed + n <= *cap)
        return 1;
    size_t c = *cap;
    if (!wm_grow((void **)&f->mixed_tile, &c, f->mixed + n,
                 sizeof *f->mixed_tile))
        return 0;
    uint64_t *b = realloc(f->bits, (c * 2 * TS1 + 1) * sizeof *b);
    if (!b)
        return 0;
    f->bits = b;
    *cap = c;
    return 1;
}

/* Window tile t's first sample (c0, r0) and how many of its samples lie
 * inside the window, nx x ny. */
static void tile_extent(const wm_field *f, size_t t, int32_t *c0, int32_t *r0,
                        int32_t *nx, int32_t *ny)
{
    *c0 = (int32_t)(t % (size_t)f->ntx) * WM_TILE;
    *r0 = (int32_t)(t / (size_t)f->ntx) * WM_TILE;
    *nx = (*c0 + WM_TILE < f->w - 1 ? WM_TILE : f->w - 1 - *c0) + 1;
    *ny = (*r0 + WM_TILE < f->h - 1 ? WM_TILE : f->h - 1 - *r0) + 1;
}

/* Keeps the evaluated tile k of a batch as window tile t: uniform when
 * every sample inside the window is +band or -band, else its values, moved
 * to *dst (the next free tile of the slab; advanced). */
static void store_tile(work *w, size_t t, float *val, float **dst)
{
    wm_field *f = w->f;
    const float band = (float)w->s->band;
    int32_t c0, r0, nx, ny;
    tile_extent(f, t, &c0, &r0, &nx, &ny);
    int all_land = 1, all_water = 1;
    for (int32_t j = 0; j < ny && (all_land || all_water); j++)
        for (int32_t q = 0; q < nx; q++)
        {
            const float d = val[j * TS1 + q];
            all_land &= d == band;
            all_water &= d == -band;
        }
    if (all_land || all_water)
    {
        f->kind[t] = (uint8_t)(all_water ? WM_TILE_WATER : WM_TILE_LAND);
        return;
    }
    if (*dst != val)
        memmove(*dst, val, sizeof(float) * TS1 * TS1);
    f->val[t] = *dst;
    *dst += TS1 * TS1;
    f->kind[t] = WM_TILE_MIXED;
    index_tile(f, t);
}

/* Tiles per slab of values (at least a batch): about 1 MB. */
#define SLAB_TILES 256

static wm_status field_nomem(const wm_ctx *ctx)
{
    return wm_fail(ctx, WM_ERR_NOMEM, "out of memory computing the field");
}

/* The items (river segments, lake polygons) of the scene's blocks that
 * cover the window, clipped to the scene's grid, into wk->ids. */
static wm_status gather_items(work *wk)
{
    const wm_scene *s = wk->s;
    const wm_field *f = wk->f;
    if (s->nbx <= 0)
        return WM_OK;
    const int64_t side = (int64_t)s->n * WM_Q;
    int64_t bx0 = wm_floordiv(wk->X0, side), by0 = wm_floordiv(wk->Y0, side);
    int64_t bx1 = wm_floordiv(wk->X0 + (int64_t)(f->w - 1) * WM_Q, side);
    int64_t by1 = wm_floordiv(wk->Y0 + (int64_t)(f->h - 1) * WM_Q, side);
    if (bx0 < s->bx0)
        bx0 = s->bx0;
    if (by0 < s->by0)
        by0 = s->by0;
    if (bx1 > s->bx0 + s->nbx - 1)
        bx1 = s->bx0 + s->nbx - 1;
    if (by1 > s->by0 + s->nby - 1)
        by1 = s->by0 + s->nby - 1;
    if (bx0 > bx1 || by0 > by1)
        return WM_OK;
    const wm_box blocks = {bx0, by0, bx1, by1};
    if (wm_scene_items(s, blocks, &wk->ids, &wk->nsegs, &wk->npolys) != WM_OK)
        return WM_ERR_NOMEM;
    wk->segs = wk->ids;
    wk->polys = wk->ids ? wk->ids + wk->nsegs : NULL;
    return WM_OK;
}

/* The tiles whose samples need evaluating, in order, into cand; the
 * others get their uniform kind. Returns how many. */
static size_t candidates(work *wk, uint8_t *haspoly, size_t *cand)
{
    const wm_field *f = wk->f;
    size_t ncand = 0;
    for (int32_t ty = 0; ty < f->nty; ty++)
        for (int32_t tx = 0; tx < f->ntx; tx++)
        {
            const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
            /* most tiles of a sparse block: nothing in reach and no lake's
             * box, land as they are (kind 0) */
            if (wk->tseg_start[t] == wk->tseg_start[t + 1] &&
                wk->tedge_start[t] == wk->tedge_start[t + 1] &&
                wk->tpoly_start[t] == wk->tpoly_start[t + 1])
                continue;
            if (!uniform_tile(wk, tx, ty, haspoly))
                cand[ncand++] = t;
        }
    return ncand;
}

/* Whether global lattice point (X, Y), within a lattice unit of a sample
 * of window tile t, is water in the closed union: in a capsule (the
 * field's |p - seg| - r <= 0), on a lake edge, or inside a lake by the
 * ray rule (exact). Every item holding it is in the tile's lists, and no
 * polygon without an edge there holds it (the tile would be uniform). */
static int water_at(const work *w, size_t t, int64_t X, int64_t Y)
{
    const wm_scene *s = w->s;
    for (size_t i = w->tseg_start[t]; i < w->tseg_start[t + 1]; i++)
    {
        const wm_river_seg *g = &s->segs[w->tseg[i]];
        const double abx = (double)(g->bx - g->ax),
                     aby = (double)(g->by - g->ay);
        const double len2 = abx * abx + aby * aby;
        const double d2 = seg_d2((double)(X - g->ax), (double)(Y - g->ay), abx,
                                 aby, len2 > 0 ? 1.0 / len2 : 0.0);
        if (sqrt(d2) - g->r <= 0)
            return 1;
    }
    /* the tile's edges come polygon by polygon (bin_items): each
     * polygon's inside test once, at its first edge */
    const size_t e0 = w->tedge_start[t], e1 = w->tedge_start[t + 1];
    for (size_t i = e0; i < e1; i++)
        if (wm_edge_holds(&s->edges[w->tedge[i]], X, Y) ||
            ((i == e0 || w->tedge_poly[i] != w->tedge_poly[i - 1]) &&
             wm_lake_bands_inside(&w->lakes, w->tedge_poly[i], X, Y)))
            return 1;
    return 0;
}

/* Whether the water at sample (X, Y) of a block line (vertical: a side
 * between blocks left and right of it; horizontal: below and above),
 * whose value settle_lines takes for 0, reaches into every block holding
 * the sample: the points a lattice unit across the line are water, or at a
 * block corner (both) the four a unit diagonally into the four blocks (two
 * lakes touching there along one edge leave the axis points all water and
 * a quadrant dry) and the four a unit along the lines (four lakes' corners
 * a unit diagonally off it, one on it, leave the diagonal points water and
 * land along the lines: each block kept a triangle of half a square unit
 * at its corner, held-out round 23). */
static int water_across(const work *w, size_t t, int64_t X, int64_t Y,
                        int vertical, int horizontal)
{
    if (vertical && horizontal)
        return water_at(w, t, X - 1, Y - 1) && water_at(w, t, X + 1, Y - 1) &&
               water_at(w, t, X - 1, Y + 1) && water_at(w, t, X + 1, Y + 1) &&
               water_at(w, t, X - 1, Y) && water_at(w, t, X + 1, Y) &&
               water_at(w, t, X, Y - 1) && water_at(w, t, X, Y + 1);
    if (vertical)
        return water_at(w, t, X - 1, Y) && water_at(w, t, X + 1, Y);
    return water_at(w, t, X, Y - 1) && water_at(w, t, X, Y + 1);
}

/* First index i >= 0 with (g0 + i) a multiple of n. */
static int32_t first_line(int64_t g0, int32_t n)
{
    return (int32_t)((n - g0 % n) % n);
}

/* Samples on a block line (a global row or column that is a multiple of
 * the block's n) valued 0, or below it by no more than WM_COINCIDE (the
 * inputs' rounding to the lattice: a bank on the line at 0.3 m pixels is
 * 1e-13 pixel off it), lie on a lake edge or a bank.
 * Water is closed, so such a sample is water, which is right inside a
 * block (a boundary through samples moves by a lattice unit) but not on a
 * block side where the water lies on one side only: the block across
 * would keep a strip one unit thick along its side (a speck at a corner)
 * that the union does not have. Such a sample is land: the smallest
 * positive value, for every block that holds it (a pure function of the
 * global data, invariant 2), so the water's own block stops a unit short
 * of the side and the block across has none; the two still agree on the
 * side. Where water lies on both sides (two lake polygons sharing an edge
 * along the side), it stays water and the union stays seamless
 * (water_across; probe.c's side_rule does the same between samples). */
#define SETTLE ((float)(WM_COINCIDE / WM_Q)) /* pixels */

static wm_status settle_lines(work *w, size_t t, float *val)
{
    const wm_field *f = w->f;
    const int32_t n = w->s->n;
    int32_t c0, r0, nx, ny;
    tile_extent(f, t, &c0, &r0, &nx, &ny);
    const int64_t gx = f->gx0 + c0, gy = f->gy0 + r0;
    /* the columns on vertical lines (every row), then the rows on
     * horizontal ones (the other columns) */
    for (int pass = 0; pass < 2; pass++)
        for (int32_t l = first_line(pass ? gy : gx, n); l < (pass ? ny : nx);
             l += n)
            for (int32_t k = 0; k < (pass ? nx : ny); k++)
            {
                const int32_t i = pass ? k : l, j = pass ? l : k;
                const int vertical = (gx + i) % n == 0;
                const int horizontal = (gy + j) % n == 0;
                float *v = &val[j * TS1 + i];
                if (!(*v <= 0.0f && *v > -SETTLE) || (pass && vertical))
                    continue;
                if (!w->lakes.s && w->npolys &&
                    wm_lake_bands_build(&w->lakes, w->s, w->polys, w->npolys) !=
                        WM_OK)
                    return WM_ERR_NOMEM;
                if (!water_across(w, t, (gx + i) * WM_Q, (gy + j) * WM_Q,
                                  vertical, horizontal))
                    *v = FLT_MIN;
            }
    return WM_OK;
}

/* Evaluates the candidate tiles in batches (on dev, or the C path)
 * straight into the field's slabs, keeping the mixed ones (store_tile packs
 * them down over the uniform ones). */
static wm_status eval_batches(work *wk, const wm_field_device *dev,
                              const size_t *cand, size_t ncand,
                              const wm_ctx *ctx)
{
    wm_field *f = wk->f;
    /* the C path gains nothing from large batches: small ones stay in the
     * cache */
    const size_t batch = dev ? WM_FIELD_BATCH : 16;
    const size_t nb = ncand < batch ? ncand : batch;
    batch_buf bb;
    memset(&bb, 0, sizeof bb);
    bb.org = malloc((2 * nb + 1) * sizeof *bb.org);
    bb.seg_start = malloc((nb + 1) * sizeof *bb.seg_start);
    bb.grp_start = malloc((nb + 1) * sizeof *bb.grp_start);
    wm_status st =
        bb.org && bb.seg_start && bb.grp_start ? WM_OK : field_nomem(ctx);
    float *top = NULL;
    size_t room = 0, slabcap = 0; /* tiles left in the current slab */
    size_t mixcap = 0;            /* room in f->mixed_tile and f->bits */
    for (size_t c0 = 0; st == WM_OK && c0 < ncand; c0 += batch)
    {
        const size_t n = ncand - c0 < batch ? ncand - c0 : batch;
        if (wm_cancelled(ctx))
        {
            st = wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
            break;
        }
        if (n > room)
        {
            const size_t cap = SLAB_TILES > batch ? SLAB_TILES : batch;
            if (!wm_grow((void **)&f->slab, &slabcap, f->nslab + 1,
                         sizeof *f->slab) ||
                !(top = malloc(cap * TS1 * TS1 * sizeof *top)))
            {
                st = field_nomem(ctx);
                break;
            }
            f->slab[f->nslab++] = top;
            room = cap;
        }
        wm_field_batch b;
        if (build_batch(wk, cand + c0, n, &bb, &b) != WM_OK ||
            !index_room(f, n, &mixcap))
        {
            st = field_nomem(ctx);
            break;
        }
        b.val = top;
        b.samples = &f->samples;
        b.pairs = &f->pairs;
        st = dev ? dev->eval(dev->user, &b, ctx)
                 : wm_field_eval_c(NULL, &b, ctx);
        if (st != WM_OK)
            break;
        for (size_t k = 0; st == WM_OK && k < n; k++)
            if (settle_lines(wk, cand[c0 + k], top + k * TS1 * TS1) != WM_OK)
                st = field_nomem(ctx);
        if (st != WM_OK)
            break;
        float *next = top;
        for (size_t k = 0; k < n; k++)
            store_tile(wk, cand[c0 + k], top + k * TS1 * TS1, &next);
        room -= (size_t)(next - top) / (TS1 * TS1);
        top = next;
    }
    batch_buf_free(&bb);
    return st;
}

static void work_free(work *wk)
{
    free(wk->ids);
    free(wk->tseg_start);
    free(wk->tseg);
    free(wk->tedge_start);
    free(wk->tedge);
    free(wk->tedge_poly);
    free(wk->row0);
    free(wk->nrows);
    free(wk->key0);
    free(wk->tpoly_start);
    free(wk->tpoly);
    free(wk->base);
    free(wk->tog_start);
    free(wk->tog);
    wm_lake_bands_free(&wk->lakes);
}

wm_status wm_field_compute(const wm_scene *s, int64_t gx0, int64_t gy0,
                           int32_t w, int32_t h, const wm_field_device *dev,
                           wm_field *f, const wm_ctx *ctx)
{
    memset(f, 0, sizeof *f);
    if (w < 1 || h < 1)
        return wm_fail(ctx, WM_ERR_INVALID, "empty field window");
    f->gx0 = gx0;
    f->gy0 = gy0;
    f->w = w;
    f->h = h;
    f->band = (float)s->band;
    f->ntx = w > 1 ? (w - 2) / WM_TILE + 1 : 1;
    f->nty = h > 1 ? (h - 2) / WM_TILE + 1 : 1;
    const size_t nt = (size_t)f->ntx * (size_t)f->nty;
    if (nt > UINT32_MAX) /* tiles are numbered in 32 bits */
        return wm_fail(ctx, WM_ERR_INVALID, "field window too large");
    work wk;
    memset(&wk, 0, sizeof wk);
    wk.s = s;
    wk.f = f;
    wk.X0 = gx0 * WM_Q;
    wk.Y0 = gy0 * WM_Q;
    wk.tsq = (int64_t)WM_TILE * WM_Q;
    f->kind = calloc(nt, 1);
    f->val = calloc(nt, sizeof *f->val);
    uint8_t *haspoly = NULL;
    size_t *cand = NULL;
    wm_status st;
    if (!f->kind || !f->val || gather_items(&wk) != WM_OK ||
        !(haspoly = calloc(wk.npolys + 1, 1)) ||
        !(cand = malloc(nt * sizeof *cand)) || bin_items(&wk) != WM_OK ||
        bin_polys(&wk) != WM_OK || build_crossings(&wk) != WM_OK)
        st = field_nomem(ctx);
    else
        st = eval_batches(&wk, dev, cand, candidates(&wk, haspoly, cand), ctx);
    if (st != WM_OK)
        wm_field_free(f);
    free(cand);
    free(haspoly);
    work_free(&wk);
    return st;
}

/* The tile holding window sample (c, r) (a sample on a tile border is read
 * from the tile below or left of it) and the sample's offset in it. */
static size_t tile_of(const wm_field *f, int32_t c, int32_t r, int32_t *off)
{
    int32_t tx = c > 0 ? (c - 1) / WM_TILE : 0;
    int32_t ty = r > 0 ? (r - 1) / WM_TILE : 0;
    if (tx >= f->ntx)
        tx = f->ntx - 1;
    if (ty >= f->nty)
        ty = f->nty - 1;
    *off = (r - ty * WM_TILE) * TS1 + (c - tx * WM_TILE);
    return (size_t)ty * (size_t)f->ntx + (size_t)tx;
}

float wm_field_at(const wm_field *f, int32_t c, int32_t r)
{
    int32_t off;
    const size_t t = tile_of(f, c, r, &off);
    switch (f->kind[t])
    {
    case WM_TILE_WATER:
        return -f->band;
    case WM_TILE_LAND:
        return f->band;
    default:
        return f->val[t][off];
    }
}

wm_status wm_field_index(wm_field *f)
{
    const size_t nt = (size_t)f->ntx * (size_t)f->nty;
    if (nt > UINT32_MAX)
        return WM_ERR_NOMEM; /* tiles are numbered in 32 bits */
    size_t cap = 0;
    f->mixed = 0;
    free(f->mixed_tile);
    free(f->bits);
    f->mixed_tile = NULL;
    f->bits = NULL;
    for (size_t t = 0; t < nt; t++)
        if (f->kind[t] == WM_TILE_MIXED)
        {
            if (!index_room(f, 1, &cap))
                return WM_ERR_NOMEM;
            index_tile(f, t);
        }
    return WM_OK;
}

void wm_field_cell(const wm_field *f, int32_t c, int32_t r, float v[4])
{
    const int32_t tx = c / WM_TILE < f->ntx ? c / WM_TILE : f->ntx - 1;
    const int32_t ty = r / WM_TILE < f->nty ? r / WM_TILE : f->nty - 1;
    const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
    if (f->kind[t] != WM_TILE_MIXED)
    {
        const float u = f->kind[t] == WM_TILE_WATER ? -f->band : f->band;
        v[0] = v[1] = v[2] = v[3] = u;
        return;
    }
    const float *p = f->val[t] + (r - ty * WM_TILE) * TS1 + (c - tx * WM_TILE);
    v[0] = p[0];
    v[1] = p[1];
    v[2] = p[TS1 + 1];
    v[3] = p[TS1];
}

void wm_field_prefetch(const wm_field *f, int32_t c, int32_t r)
{
    int32_t off;
    const size_t t = tile_of(f, c, r, &off);
    if (f->val[t]) /* NULL for a uniform tile */
        __builtin_prefetch(f->val[t] + off);
}

void wm_field_prefetch_tile(const wm_field *f, size_t k)
{
    if (k >= f->mixed)
        return;
    const float *v = f->val[f->mixed_tile[k]];
    const uint64_t *b = wm_field_bits(f, k);
    for (int32_t j = 0; j < TS1; j++)
    {
        /* the near samples of rows j - 1 .. j + 1 */
        const uint64_t m = b[2 * j + 1] | (j > 0 ? b[2 * j - 1] : 0) |
                           (j + 1 < TS1 ? b[2 * j + 3] : 0);
        if (!m)
            continue;
        const float *row = v + (ptrdiff_t)j * TS1;
        const char *p = (const char *)(row + __builtin_ctzll(m));
        const char *last = (const char *)(row + 63 - __builtin_clzll(m));
        for (; p < last; p += 64)
            __builtin_prefetch(p);
        __builtin_prefetch(last);
    }
}

void wm_field_free(wm_field *f)
{
    if (!f)
        return;
    for (size_t i = 0; i < f->nslab; i++)
        free(f->slab[i]);
    free(f->slab);
    free(f->val);
    free(f->kind);
    free(f->mixed_tile);
    free(f->bits);
    memset(f, 0, sizeof *f);
}
