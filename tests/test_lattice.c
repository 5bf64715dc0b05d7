/* test_lattice.c - exact predicates and the ring container. */
#include "lattice.h"
#include "tap.h"

#include <string.h>

/* wm_cells against a dense reference: n random (cell, item) pairs (items
 * in order of addition) in a side x side grid; every row run of a few
 * random column ranges must list exactly the dense cells' items, in order.
 * Returns the number of mismatching runs. */
static int cells_mismatches(wm_cells *g, int32_t side, size_t n, unsigned seed)
{
    uint32_t *cx = malloc((n + 1) * sizeof *cx);
    uint32_t *cy = malloc((n + 1) * sizeof *cy);
    uint32_t *ref = malloc((n + 1) * sizeof *ref);
    int bad = 0;
    wm_cells_reset(g, side);
    for (size_t i = 0; i < n; i++)
    {
        seed = seed * 1103515245u + 12345u;
        /* clustered: half the pairs in a small corner, as rings are */
        const uint32_t lim = (i & 1) ? (uint32_t)side : 3;
        cx[i] = (seed >> 8) % lim;
        seed = seed * 1103515245u + 12345u;
        cy[i] = (seed >> 8) % lim;
        if (!wm_cells_add(g, (int32_t)cx[i], (int32_t)cy[i], (uint32_t)i))
            bad++;
    }
    if (wm_cells_index(g) != WM_OK)
        bad++;
    for (int32_t y = 0; y < side && !bad; y++)
        for (int t = 0; t < 4; t++)
        {
            seed = seed * 1103515245u + 12345u;
            const int32_t x0 = (int32_t)((seed >> 8) % (uint32_t)side);
            const int32_t x1 = t == 0 ? side - 1 : x0 + (int32_t)(t * t);
            const int32_t x1c = x1 < side ? x1 : side - 1;
            size_t b, e, k = 0;
            wm_cells_row(g, y, x0, x1c, &b, &e);
            /* the reference run: the pairs of row y and columns x0..x1c,
             * by column, then in order of addition (insertion sort) */
            for (size_t i = 0; i < n; i++)
                if (cy[i] == (uint32_t)y && cx[i] >= (uint32_t)x0 &&
                    cx[i] <= (uint32_t)x1c)
                {
                    size_t j = k++;
                    for (; j > 0 && cx[ref[j - 1]] > cx[i]; j--)
                        ref[j] = ref[j - 1];
                    ref[j] = (uint32_t)i;
                }
            for (size_t j = 0; j < k; j++)
                if (b + j >= e || g->item[b + j] != ref[j])
                    bad++;
            if (b + k != e)
                bad++;
            if (bad)
                break;
        }
    free(ref);
    free(cx);
    free(cy);
    return bad;
}

/* Appends the axis-aligned square [x0, x1] x [y0, y1], counter-clockwise
 * (water inside) or clockwise (a hole). */
static void push_square(wm_rings *r, int32_t x0, int32_t y0, int32_t x1,
                        int32_t y1, int cw)
{
    const wm_pt p[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    for (int k = 0; k < 4; k++)
        wm_rings_push(r, p[cw ? 3 - k : k]);
    wm_rings_close(r);
}

/* MIN_FEATURE_AREA on a block of side 100: rings inside the block below the
 * area go (with what they enclose), rings on the square stay. */
static void test_drop_small(void)
{
    wm_rings r;
    memset(&r, 0, sizeof r);
    push_square(&r, 0, 0, 3, 3, 0);     /* 9, on the square: kept */
    push_square(&r, 10, 10, 13, 13, 0); /* 9: dropped */
    push_square(&r, 20, 20, 60, 60, 0); /* 1600: kept */
    push_square(&r, 30, 30, 32, 32, 1); /* hole of 4: dropped */
    push_square(&r, 40, 40, 50, 50, 1); /* hole of 100: kept */
    push_square(&r, 44, 44, 46, 46, 0); /* island lake of 4 in it: dropped */
    TAP_EQ(wm_rings_drop_small(&r, 100, 0.0), 0, "drop_small: 0 is off");
    TAP_EQ(r.nrings, 6, "drop_small: off keeps all");
    TAP_EQ(wm_rings_drop_small(&r, 100, 10.0), 3, "drop_small: 3 dropped");
    TAP_EQ(r.nrings, 3, "drop_small: 3 kept");
    TAP_EQ(r.npts, 12, "drop_small: points compacted");
    TAP_EQ(r.pts[r.start[1]].x, 20, "drop_small: order kept");
    TAP_EQ(r.pts[r.start[2]].x, 40, "drop_small: the large hole kept");
    TAP_EQ(r.start[3], 12, "drop_small: ends consistent");
    wm_rings_free(&r);
}

int main(void)
{
    const wm_pt a = {0, 0}, b = {10, 0}, c = {5, 5}, d = {5, -5};
    TAP_EQ(wm_orient(a, b, c), 1, "orient: left is +1");
    TAP_EQ(wm_orient(a, b, d), -1, "orient: right is -1");
    TAP_EQ(wm_orient(a, b, (wm_pt){20, 0}), 0, "orient: collinear is 0");
    /* large coordinates: products beyond 2^48 stay exact */
    const wm_pt big0 = {0, 0}, big1 = {WM_LOCAL_MAX, WM_LOCAL_MAX - 1},
                big2 = {WM_LOCAL_MAX - 1, WM_LOCAL_MAX - 2};
    TAP_EQ(wm_orient(big0, big1, big2), -1, "orient exact near 2^24");

    TAP_OK(wm_segments_meet(a, b, c, d), "crossing segments meet");
    TAP_OK(wm_segments_meet(a, b, b, c), "segments sharing an end meet");
    TAP_OK(wm_segments_meet(a, b, (wm_pt){5, 0}, (wm_pt){5, 3}),
           "T contact meets");
    TAP_OK(wm_segments_meet(a, b, (wm_pt){3, 0}, (wm_pt){15, 0}),
           "collinear overlap meets");
    TAP_OK(!wm_segments_meet(a, b, (wm_pt){11, 0}, (wm_pt){15, 0}),
           "collinear disjoint do not meet");
    TAP_OK(!wm_segments_meet(a, b, (wm_pt){0, 1}, (wm_pt){10, 1}),
           "parallel do not meet");

    /* in-circle on the unit square's circle: cocircular gives 0 */
    const wm_pt s0 = {0, 0}, s1 = {4, 0}, s2 = {4, 4}, s3 = {0, 4};
    TAP_EQ(wm_incircle(s0, s1, s2, s3), 0, "incircle: cocircular is 0");
    TAP_EQ(wm_incircle(s0, s1, s2, (wm_pt){2, 2}), 1, "incircle: inside");
    TAP_EQ(wm_incircle(s0, s1, s2, (wm_pt){9, 9}), -1, "incircle: outside");
    const wm_pt L0 = {0, 0}, L1 = {1 << 26, 0}, L2 = {0, 1 << 26};
    TAP_EQ(wm_incircle(L0, L1, L2, (wm_pt){(1 << 26) - 1, (1 << 26) - 1}), 1,
           "incircle exact at 2^26");

    const wm_pt sq[4] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
    TAP_EQ(wm_point_in_ring(sq, 4, (wm_pt){5, 5}), 1, "point inside");
    TAP_EQ(wm_point_in_ring(sq, 4, (wm_pt){15, 5}), 0, "point outside");
    TAP_EQ(wm_point_in_ring(sq, 4, (wm_pt){10, 5}), -1, "point on edge");
    TAP_EQ(wm_point_in_ring(sq, 4, (wm_pt){-5, 10}), 0,
           "ray through a vertex counted once");
    TAP_EQ(wm_point_in_ring(sq, 4, (wm_pt){5, 0}), -1,
           "point on a horizontal edge");
    TAP_OK(wm_ring_area2(sq, 4) == 200, "area2 of CCW square is +200");

    TAP_OK(!wm_seg_dist2_exceeds(a, b, (wm_pt){5, 3}, 9), "dist 3 <= 3");
    TAP_OK(wm_seg_dist2_exceeds(a, b, (wm_pt){5, 4}, 9), "dist 4 > 3");
    TAP_OK(wm_seg_dist2_exceeds(a, b, (wm_pt){13, 1}, 9),
           "beyond the end: distance to the endpoint");

    wm_rings r = {0};
    for (int i = 0; i < 4; i++)
        wm_rings_push(&r, sq[i]);
    wm_rings_close(&r);
    wm_rings_push(&r, a);
    wm_rings_push(&r, b);
    wm_rings_push(&r, c);
    wm_rings_close(&r);
    TAP_EQ(r.nrings, 2, "two rings");
    TAP_EQ(wm_rings_len(&r, 0), 4, "ring 0 has 4 points");
    TAP_EQ(wm_rings_len(&r, 1), 3, "ring 1 has 3 points");
    wm_rings_free(&r);
    wm_rings_free(NULL);

    wm_cells g;
    memset(&g, 0, sizeof g);
    TAP_EQ(cells_mismatches(&g, 1, 5, 1), 0, "cells: 1 x 1 grid");
    TAP_EQ(cells_mismatches(&g, 40, 600, 2), 0,
           "cells: 40 x 40 grid (one radix pass), reused");
    TAP_EQ(cells_mismatches(&g, 300, 900, 3), 0,
           "cells: 300 x 300 grid (two radix passes)");
    TAP_EQ(cells_mismatches(&g, 2100, 300, 4), 0,
           "cells: 2100 x 2100 grid (three radix passes), sparse rows");
    TAP_EQ(cells_mismatches(&g, 7, 0, 5), 0, "cells: no items");
    wm_cells_free(&g);
    wm_cells_free(NULL);
    test_drop_small();
    return TAP_DONE();
}
