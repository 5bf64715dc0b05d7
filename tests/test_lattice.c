/* test_lattice.c - exact predicates and the ring container. */
#include "lattice.h"
#include "tap.h"

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
    return TAP_DONE();
}
