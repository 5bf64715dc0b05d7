/* test_field.c - the signed distance field: signs, union, clamping, and
 * the invariant that a sample's value depends only on its global index. */
#include "field.h"
#include "field_check.h"
#include "scene_util.h"
#include "tap.h"

#include <math.h>
#include <string.h>

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
    wm_scene_free(&s);
    return TAP_DONE();
}
