/* test_field.c - the signed distance field: signs, union, clamping, and
 * the invariant that a sample's value depends only on its global index. */
#include "field.h"
#include "field_check.h"
#include "scene_util.h"
#include "tap.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* The field's definition evaluated directly at window sample (c, r), in
 * lattice units, clamped to [-bandl, bandl]: rivers by distance, lakes by
 * distance to all their edges and even-odd parity. */
static double reference(const wm_scene *s, const wm_field *f, int c, int r)
{
    const double bandl = (double)s->band * WM_Q;
    const double px = (double)((f->gx0 + c) * WM_Q),
                 py = (double)((f->gy0 + r) * WM_Q);
    double v = bandl;
    for (size_t i = 0; i < s->nsegs; i++)
    {
        const wm_river_seg *g = &s->segs[i];
        const double ax = (double)g->ax, ay = (double)g->ay;
        const double dx = (double)g->bx - ax, dy = (double)g->by - ay;
        const double l2 = dx * dx + dy * dy;
        double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        const double d = hypot(px - ax - t * dx, py - ay - t * dy) - g->r;
        v = d < v ? d : v;
    }
    for (size_t k = 0; k < s->npolys; k++)
    {
        int in = 0;
        double dmin = INFINITY;
        for (size_t e = s->poly_start[k]; e < s->poly_start[k + 1]; e++)
        {
            const wm_lake_edge *g = &s->edges[e];
            const double ax = (double)g->ax, ay = (double)g->ay;
            const double bx = (double)g->bx, by = (double)g->by;
            if ((ay > py) != (by > py) &&
                px < ax + (py - ay) * (bx - ax) / (by - ay))
                in = !in;
            const double dx = bx - ax, dy = by - ay;
            double t = ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy);
            t = t < 0 ? 0 : (t > 1 ? 1 : t);
            const double d = hypot(px - ax - t * dx, py - ay - t * dy);
            dmin = d < dmin ? d : dmin;
        }
        v = (in ? -dmin : dmin) < v ? (in ? -dmin : dmin) : v;
    }
    return v < -bandl ? -bandl : v;
}

/* Samples of f that disagree with the definition: where it is clamped by
 * a margin the sample must be exactly +/-band (the narrow band may skip
 * those), elsewhere within 1e-4 px. *deep counts the -band samples of
 * mixed tiles (the interiors the narrow band skips). */
static int definition_diff(const wm_scene *s, const wm_field *f, int *deep)
{
    const double bandl = (double)s->band * WM_Q;
    int bad = 0;
    *deep = 0;
    for (int r = 0; r < f->h; r++)
        for (int c = 0; c < f->w; c++)
        {
            const double ref = reference(s, f, c, r);
            const float v = wm_field_at(f, c, r);
            const int tx = c > 0 ? (c - 1) / WM_TILE : 0,
                      ty = r > 0 ? (r - 1) / WM_TILE : 0;
            if (v == -(float)s->band &&
                f->kind[ty * f->ntx + tx] == WM_TILE_MIXED)
                ++*deep;
            if (ref <= -bandl)
                bad += v != -(float)s->band;
            else if (ref >= bandl + 0.01)
                bad += v != (float)s->band;
            else
                bad += fabs(v - ref / WM_Q) > 1e-4;
        }
    return bad;
}

/* How many MIXED tiles of f its list or its rows' bits get wrong: the list
 * must be every MIXED tile, ascending; bit i of row j's water (near) word
 * must be v <= 0 (|v| < 1 pixel) at sample (i, j) of the tile. */
static size_t bits_diff(const wm_field *f)
{
    size_t bad = 0, k = 0;
    for (size_t t = 0; t < (size_t)f->ntx * (size_t)f->nty; t++)
    {
        if (f->kind[t] != WM_TILE_MIXED)
            continue;
        if (k >= f->mixed || f->mixed_tile[k] != t)
            return bad + 1;
        const uint64_t *b = wm_field_bits(f, k++);
        int ok = 1;
        for (int j = 0; j < WM_TS1; j++)
            for (int i = 0; i < WM_TS1; i++)
            {
                const float v = f->val[t][j * WM_TS1 + i];
                ok &= (int)(b[2 * j] >> i & 1) == (v <= 0);
                ok &= (int)(b[2 * j + 1] >> i & 1) == (fabsf(v) < 1.0f);
            }
        bad += !ok;
    }
    return bad + (k != f->mixed);
}

/* Global sample (x, y) of a field whose sample (0, 0) is org. */
static float at(const wm_field *f, const int *org, int x, int y)
{
    return wm_field_at(f, x - org[0], y - org[1]);
}

/* Samples on a block line (blocks of 32 pixels) that are exactly 0: water
 * where the water reaches into the blocks on both sides of the line, else
 * land (the smallest positive value), the same in every block holding them,
 * so that the block across a shore lying on its side keeps no strip. */
static void block_lines(void)
{
    wm_scene s;
    su_init(&s, 32);
    /* lake A on [32, 64] x [32, 64], its edges on block lines; lake B on
     * [64, 96] x [40, 56] shares a part of A's right edge (tiles) */
    const double a[] = {32, 32, 64, 32, 64, 64, 32, 64};
    const double b[] = {64, 40, 96, 40, 96, 56, 64, 56};
    /* lake C with an edge along column 10, not a block line */
    const double c[] = {10, 100, 20, 100, 20, 110, 10, 110};
    const int four[] = {4};
    su_lake(&s, a, four, 1);
    su_lake(&s, b, four, 1);
    su_lake(&s, c, four, 1);
    /* a river whose bank lies on row 96 (centre 100, radius 4) */
    const double r[] = {40, 100, 90, 100};
    su_river(&s, r, 2, 4);
    su_finish(&s);
    wm_field f[4]; /* blocks (0, 1), (1, 1), (1, 2), (2, 1) */
    const int org[4][2] = {{0, 32}, {32, 32}, {32, 64}, {64, 32}};
    for (int k = 0; k < 4; k++)
        TAP_EQ(wm_field_compute(&s, org[k][0], org[k][1], 33, 33, NULL, &f[k],
                                NULL),
               WM_OK, "block (%d, %d)", org[k][0] / 32, org[k][1] / 32);
    TAP_OK(at(&f[0], org[0], 32, 48) == FLT_MIN &&
               at(&f[1], org[1], 32, 48) == FLT_MIN,
           "a shore on a block side (water on one side): land in both blocks");
    TAP_OK(at(&f[1], org[1], 32, 32) == FLT_MIN &&
               at(&f[1], org[1], 48, 32) == FLT_MIN,
           "the lake's corner on a block corner and its bottom edge: land");
    TAP_OK(at(&f[1], org[1], 64, 48) == 0.0f &&
               at(&f[3], org[3], 64, 48) == 0.0f,
           "an edge two lakes share along a block side: water");
    TAP_OK(at(&f[1], org[1], 64, 36) == FLT_MIN &&
               at(&f[3], org[3], 64, 60) == FLT_MIN,
           "beyond the shared part of that side: land");
    TAP_OK(at(&f[1], org[1], 64, 40) == 0.0f &&
               at(&f[1], org[1], 64, 39) == FLT_MIN,
           "the shared part's end (B's corner) water, below it land");
    TAP_OK(at(&f[2], org[2], 50, 96) == FLT_MIN,
           "a river's bank along a block side (radius 4, centre 4 away): land");
    TAP_OK(at(&f[1], org[1], 50, 63) < 0 && at(&f[1], org[1], 63, 50) < 0,
           "the lake's samples beside its sides: water");
    wm_field g;
    TAP_EQ(wm_field_compute(&s, 0, 96, 33, 33, NULL, &g, NULL), WM_OK,
           "block (0, 3)");
    TAP_OK(wm_field_at(&g, 10, 5) == 0.0f,
           "a shore along a column inside a block stays water (0)");
    TAP_EQ(fc_shared_column_diff(&f[1], &f[3], 32), 0,
           "the shared side bit-identical in both blocks");
    wm_field_free(&g);
    for (int k = 0; k < 4; k++)
        wm_field_free(&f[k]);
    wm_scene_free(&s);
}

/* Two lakes touching along one edge at a block corner, a quadrant dry:
 * the corner sample is land, though the points a unit across both lines
 * are water (the edges are closed), so the dry block keeps no speck. */
static void block_corner(void)
{
    wm_scene s;
    su_init(&s, 32);
    const double below[] = {20, 10, 44, 10, 44, 32, 20, 32};
    const double left[] = {20, 32, 32, 32, 32, 40, 20, 40};
    const int four[] = {4};
    su_lake(&s, below, four, 1);
    su_lake(&s, left, four, 1);
    su_finish(&s);
    wm_field f;
    TAP_EQ(wm_field_compute(&s, 32, 32, 33, 33, NULL, &f, NULL), WM_OK,
           "block (1, 1)");
    TAP_OK(wm_field_at(&f, 0, 0) == FLT_MIN,
           "a block corner two lakes touch with the block dry: land");
    TAP_OK(wm_field_at(&f, 5, 0) == FLT_MIN && wm_field_at(&f, 0, 5) == FLT_MIN,
           "the lakes' edges along its sides: land");
    wm_field_free(&f);
    wm_scene_free(&s);
}

int main(void)
{
    wm_scene s;
    su_init(&s, 64);
    /* a river crossing blocks (0,0) and (1,0), far from the origin */
    const double river[] = {3.3, 20.7, 60.1, 35.2, 64.0, 35.9, 120.4, 50.3};
    su_river(&s, river, 4, 3.1);
    /* a lake with an island, straddling the two blocks */
    const double lake[] = {40, 60, 100, 62,  98, 120, 42, 118,
                           60, 80, 60,  100, 80, 100, 80, 80};
    const int counts[] = {4, 4};
    su_lake(&s, lake, counts, 2);
    /* a bowtie lake: both lobes filled (even-odd) */
    const double bow[] = {5, 70, 25, 100, 25, 70, 5, 100};
    const int bc[] = {4};
    su_lake(&s, bow, bc, 1);
    su_finish(&s);

    wm_field a, b, w;
    TAP_EQ(wm_field_compute(&s, 0, 0, 65, 129, NULL, &a, NULL), WM_OK,
           "field of block column 0");
    TAP_EQ(wm_field_compute(&s, 64, 0, 65, 129, NULL, &b, NULL), WM_OK,
           "field of block column 1");
    TAP_OK(a.mixed > 0 && bits_diff(&a) == 0 && bits_diff(&b) == 0,
           "the MIXED tiles listed, their rows' water and near bits right");
    int diff = fc_shared_column_diff(&a, &b, 64);
    TAP_EQ(diff, 0, "shared border column bit-identical in both blocks");

    /* an odd window: every sample equal to the block's value */
    TAP_EQ(wm_field_compute(&s, 37, 11, 53, 77, NULL, &w, NULL), WM_OK,
           "odd window");
    diff = fc_window_diff(&w, 37, 11, &a, &b, 64);
    TAP_EQ(diff, 0, "window samples bit-identical to block samples");

    TAP_OK(wm_field_at(&a, 3, 21) < -2.0f + 1e-6f || wm_field_at(&a, 3, 21) < 0,
           "river centre is water");
    TAP_OK(wm_field_at(&a, 30, 5) == 2.0f, "far from everything: +band");
    TAP_OK(wm_field_at(&a, 50, 70) < 0, "inside the lake: water");
    TAP_OK(wm_field_at(&b, 70 - 64, 90) > 0, "inside the island: land");
    TAP_OK(wm_field_at(&a, 8, 85) < 0 && wm_field_at(&a, 22, 85) < 0,
           "bowtie: both lobes water");
    TAP_OK(wm_field_at(&a, 15, 72) > 0 && wm_field_at(&a, 15, 98) > 0,
           "bowtie: the notches between the lobes are land");
    float lo = 0, hi = 0;
    for (int r = 0; r < 129; r++)
        for (int c = 0; c < 65; c++)
        {
            const float v = wm_field_at(&a, c, r);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    TAP_OK(lo >= -2.0f && hi <= 2.0f, "values clamped to the band [%g, %g]",
           (double)lo, (double)hi);
    /* a cell's four samples in one lookup, as wm_field_at gives them */
    size_t celldiff = 0;
    for (int r = 0; r < 128; r++)
        for (int c = 0; c < 64; c++)
        {
            float v[4];
            wm_field_cell(&a, c, r, v);
            celldiff += v[0] != wm_field_at(&a, c, r) ||
                        v[1] != wm_field_at(&a, c + 1, r) ||
                        v[2] != wm_field_at(&a, c + 1, r + 1) ||
                        v[3] != wm_field_at(&a, c, r + 1);
        }
    TAP_EQ(celldiff, 0, "wm_field_cell: the four samples of every cell");
    /* exact distance away from junctions: |d| = dist - r on the river */
    {
        /* sample (30, 26): distance to the first segment */
        const double ax = 3.3, ay = 20.7, bx = 60.1, by = 35.2;
        const double px = 30, py = 26;
        const double t = ((px - ax) * (bx - ax) + (py - ay) * (by - ay)) /
                         ((bx - ax) * (bx - ax) + (by - ay) * (by - ay));
        const double dx = px - (ax + t * (bx - ax)),
                     dy = py - (ay + t * (by - ay));
        const double ref = sqrt(dx * dx + dy * dy) - 3.1;
        TAP_OK(fabs(wm_field_at(&a, 30, 26) - ref) < 0.01,
               "river distance %g vs %g", (double)wm_field_at(&a, 30, 26), ref);
    }
    {
        wm_field g;
        wm_field_compute(&s, 0, 0, 257, 257, NULL, &g, NULL);
        TAP_OK(g.mixed > 0 && g.mixed < (size_t)g.ntx * (size_t)g.nty,
               "tiles away from the shore are uniform (%zu of %d mixed)",
               g.mixed, g.ntx * g.nty);
        wm_field_free(&g);
    }
    wm_field_free(&a);
    wm_field_free(&b);
    wm_field_free(&w);

    /* a block deep inside a big lake: every tile uniform water */
    wm_scene big;
    su_init(&big, 256);
    const double sq[] = {-1000, -1000, 2000, -1000, 2000, 2000, -1000, 2000};
    su_lake(&big, sq, bc, 1);
    su_finish(&big);
    wm_field f;
    TAP_EQ(wm_field_compute(&big, 0, 0, 257, 257, NULL, &f, NULL), WM_OK,
           "deep lake block");
    TAP_EQ(f.mixed, 0, "deep inside a lake: no mixed tile");
    TAP_OK(wm_field_at(&f, 100, 100) == -2.0f, "deep inside: -band");
    wm_field_free(&f);
    wm_scene_free(&big);

    /* every sample as the definition says, in tiles where wide rivers and
     * a lake leave deep water and land next to the shore (what the narrow
     * band skips) */
    {
        wm_scene n;
        su_init(&n, 192);
        const double wide[] = {-20.3, 30.7, 90.6, 100.2, 210.3, 120.9};
        su_river(&n, wide, 3, 14.2);
        const double thin[] = {10.3, 180.4, 150.7, 140.6};
        su_river(&n, thin, 2, 1.6);
        const double dot[] = {40.3, 150.6, 40.3, 150.6};
        su_river(&n, dot, 2, 9.4); /* a point: a disc */
        const double lk[] = {100.3, 10.6,  185.7, 20.2,  180.4, 95.3,  105.6,
                             80.7,  130.2, 40.4,  150.8, 45.1,  145.3, 60.7};
        const int lc[] = {4, 3};
        su_lake(&n, lk, lc, 2);
        su_finish(&n);
        wm_field g;
        int deep = 0;
        TAP_EQ(wm_field_compute(&n, -5, 3, 190, 185, NULL, &g, NULL), WM_OK,
               "field of wide rivers and a lake");
        TAP_EQ(definition_diff(&n, &g, &deep), 0,
               "every sample as the definition says");
        TAP_OK(deep > 1000, "mixed tiles hold deep water (%d samples)", deep);
        /* the statistics count what the narrow band evaluated, not the
         * mixed tiles' every sample */
        const uint64_t all = (uint64_t)g.mixed * WM_TS1 * WM_TS1;
        TAP_OK(g.samples > 0 && 2 * g.samples < all,
               "samples evaluated: %llu of the mixed tiles' %llu",
               (unsigned long long)g.samples, (unsigned long long)all);
        TAP_OK(g.pairs > 0 && g.pairs <= 11 * g.samples,
               "sample-item distances: %llu, at most one per sample and "
               "item (11 items)",
               (unsigned long long)g.pairs);
        wm_field_free(&g);
        wm_scene_free(&n);
    }
    block_lines();
    block_corner();
    wm_scene_free(&s);
    return TAP_DONE();
}
