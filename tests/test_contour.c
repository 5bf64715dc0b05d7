/* test_contour.c - marching squares: case table, saddle rule, orientation,
 * closing along the block square, and the wm_rings invariants. */
#include "contour.h"
#include "field_check.h"
#include "lattice.h"
#include "ring_check.h"
#include "tap.h"

#include <stdlib.h>
#include <string.h>

/* Checks the wm_rings invariants by brute force; returns the number of
 * violations. */
static int check_rings(const wm_rings *r, int32_t S)
{
    int bad = 0;
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t n = wm_rings_len(r, i);
        const wm_pt *p = r->pts + r->start[i];
        bad += n < 3;
        for (size_t k = 0; k < n; k++)
        {
            bad += wm_pt_eq(p[k], p[(k + 1) % n]);
            bad += p[k].x < 0 || p[k].y < 0 || p[k].x > S || p[k].y > S;
        }
    }
    /* no two non-adjacent edges meet, anywhere */
    bad += ring_meetings(r);
    return bad;
}

static int sign_of_area(const wm_rings *r, size_t i)
{
    const wm_i128 a = wm_ring_area2(r->pts + r->start[i], wm_rings_len(r, i));
    return (a > 0) - (a < 0);
}

int main(void)
{
    enum
    {
        N = 8
    };
    const int32_t S = N * WM_Q;
    float v[(N + 1) * (N + 1)];
    wm_field f;
    wm_rings r = {0};

    /* one water sample in the middle: a CCW diamond of 4 crossings */
    for (int i = 0; i < (N + 1) * (N + 1); i++)
        v[i] = 1.0f;
    v[4 * (N + 1) + 4] = -1.0f;
    fc_make_field(&f, N + 1, N + 1, v, 2.0f);
    TAP_EQ(wm_contour_extract(&f, &r, NULL), WM_OK, "single water sample");
    TAP_EQ(r.nrings, 1, "one ring");
    TAP_EQ(wm_rings_len(&r, 0), 4, "four crossings");
    TAP_EQ(sign_of_area(&r, 0), 1, "water on the left: CCW");
    TAP_EQ(check_rings(&r, S), 0, "ring invariants");
    /* crossings at the midpoints (equal magnitudes) */
    TAP_OK(wm_point_in_ring(r.pts, 4, (wm_pt){4 * WM_Q, 4 * WM_Q}) == 1,
           "the water sample is inside its ring");
    wm_field_free(&f);

    /* all water: the block square itself */
    for (int i = 0; i < (N + 1) * (N + 1); i++)
        v[i] = -1.0f;
    v[4 * (N + 1) + 4] = 1.0f; /* one land sample: a hole */
    fc_make_field(&f, N + 1, N + 1, v, 2.0f);
    TAP_EQ(wm_contour_extract(&f, &r, NULL), WM_OK, "water block, one hole");
    TAP_EQ(r.nrings, 2, "square and hole");
    {
        int outer = -1, hole = -1;
        for (size_t i = 0; i < r.nrings; i++)
            if (sign_of_area(&r, i) > 0)
                outer = (int)i;
            else
                hole = (int)i;
        TAP_OK(outer >= 0 && hole >= 0, "one CCW outer, one CW hole");
        TAP_EQ(wm_rings_len(&r, (size_t)outer), 4,
               "the outer ring is the square's 4 corners");
    }
    TAP_EQ(check_rings(&r, S), 0, "ring invariants");
    wm_field_free(&f);

    /* saddles: diagonal water corners; the mean decides */
    for (int joined = 0; joined < 2; joined++)
    {
        for (int i = 0; i < (N + 1) * (N + 1); i++)
            v[i] = 1.0f;
        const float wv = joined ? -3.0f : -0.5f;
        v[3 * (N + 1) + 3] = wv; /* corner 0 of cell (3,3) */
        v[4 * (N + 1) + 4] = wv; /* corner 2 */
        fc_make_field(&f, N + 1, N + 1, v, 2.0f);
        TAP_EQ(wm_contour_extract(&f, &r, NULL), WM_OK, "saddle %d", joined);
        TAP_EQ(r.nrings, joined ? 1 : 2,
               joined ? "mean <= 0: water joined, one ring"
                      : "mean > 0: water separated, two rings");
        TAP_EQ(check_rings(&r, S), 0, "saddle rings valid");
        for (size_t i = 0; i < r.nrings; i++)
            TAP_EQ(sign_of_area(&r, i), 1, "saddle ring %zu is CCW", i);
        wm_field_free(&f);
    }

    /* water along the border: the ring closes along the square with the
     * corner it passes and no other vertex on the border */
    for (int rr = 0; rr <= N; rr++)
        for (int c = 0; c <= N; c++)
            v[rr * (N + 1) + c] = (c < 3 && rr < 3) ? -1.0f : 1.0f;
    fc_make_field(&f, N + 1, N + 1, v, 2.0f);
    TAP_EQ(wm_contour_extract(&f, &r, NULL), WM_OK, "corner water");
    TAP_EQ(r.nrings, 1, "one ring");
    TAP_EQ(sign_of_area(&r, 0), 1, "CCW");
    {
        int corner = 0, onborder = 0;
        for (size_t k = 0; k < r.npts; k++)
        {
            const wm_pt p = r.pts[k];
            corner += p.x == 0 && p.y == 0;
            onborder += p.x == 0 || p.y == 0 || p.x == S || p.y == S;
        }
        TAP_EQ(corner, 1, "the water corner (0,0) is a vertex");
        TAP_EQ(onborder, 3, "border vertices: 2 crossings + the corner");
    }
    TAP_EQ(check_rings(&r, S), 0, "ring invariants");
    wm_field_free(&f);

    /* checkerboard-ish noise: many saddles, still valid */
    {
        enum
        {
            M = 64
        };
        static float big[(M + 1) * (M + 1)];
        unsigned seed = 12345;
        for (int i = 0; i < (M + 1) * (M + 1); i++)
        {
            seed = seed * 1103515245u + 12345u;
            big[i] = (float)((int)((seed >> 16) % 2001) - 1000) / 500.0f;
            if (i % 7 == 0)
                big[i] = 0.0f; /* exact zeros count as water */
        }
        fc_make_field(&f, M + 1, M + 1, big, 2.0f);
        TAP_EQ(wm_contour_extract(&f, &r, NULL), WM_OK, "noise field");
        TAP_OK(r.nrings > 50, "noise gives many rings (%zu)", r.nrings);
        TAP_EQ(check_rings(&r, M * WM_Q), 0, "noise rings valid");
        /* every ring's orientation matches the class of the side it bounds:
         * total signed area equals the area of the water union, positive */
        wm_i128 total = 0;
        for (size_t i = 0; i < r.nrings; i++)
            total += wm_ring_area2(r.pts + r.start[i], wm_rings_len(&r, i));
        TAP_OK(total > 0, "net water area positive");
        wm_field_free(&f);
    }
    wm_rings_free(&r);
    return TAP_DONE();
}
