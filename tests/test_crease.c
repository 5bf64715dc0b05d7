/* test_crease.c - sharp corners of the union are put back after sampling,
 * and the rings stay valid. */
#include "contour.h"
#include "crease.h"
#include "field.h"
#include "lattice.h"
#include "ring_check.h"
#include "scene_util.h"
#include "tap.h"

#include <math.h>

/* distance (lattice units) from p to the nearest ring vertex */
static double nearest_vertex(const wm_rings *r, double x, double y)
{
    double best = INFINITY;
    for (size_t k = 0; k < r->npts; k++)
    {
        const double dx = r->pts[k].x - x, dy = r->pts[k].y - y;
        const double d = sqrt(dx * dx + dy * dy);
        best = d < best ? d : best;
    }
    return best;
}

/* distance from p to the nearest ring edge */
static double nearest_edge(const wm_rings *r, double x, double y)
{
    double best = INFINITY;
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t n = wm_rings_len(r, i);
        const wm_pt *p = r->pts + r->start[i];
        for (size_t k = 0; k < n; k++)
        {
            const wm_pt a = p[k], b = p[(k + 1) % n];
            const double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
            double t = l2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / l2 : 0;
            t = t < 0 ? 0 : (t > 1 ? 1 : t);
            const double ex = x - (a.x + t * dx), ey = y - (a.y + t * dy);
            const double d = sqrt(ex * ex + ey * ey);
            best = d < best ? d : best;
        }
    }
    return best;
}

typedef double (*dist_fn)(const wm_rings *, double, double);

/* Samples block (0, 0) of s, extracts its rings into r and recovers their
 * corners (checked: message what). *before: the distance in pixels from
 * (cx, cy) to the extracted rings, by `dist`, before the recovery. */
static void extract_recover(const wm_scene *s, double cx, double cy,
                            dist_fn dist, wm_rings *r, double *before,
                            const char *what)
{
    wm_field f;
    wm_field_compute(s, 0, 0, s->n + 1, s->n + 1, NULL, &f, NULL);
    TAP_EQ(wm_contour_extract(&f, r, NULL), WM_OK, "extract: %s", what);
    *before = dist(r, cx, cy) / WM_Q;
    TAP_EQ(wm_crease_recover(s, &f, 0, 0, r, NULL), WM_OK, "recover: %s", what);
    wm_field_free(&f);
}

static void wedge(double angle_deg, double *cx, double *cy, wm_scene *s)
{
    const double th = angle_deg * 3.14159265358979323846 / 180.0, r = 5.0;
    su_init(s, 256);
    const double r1[] = {60, 100, 250, 100};
    const double r2[] = {60, 100, 60 + 190 * cos(th), 100 + 190 * sin(th)};
    su_river(s, r1, 2, r);
    su_river(s, r2, 2, r);
    su_finish(s);
    /* the land wedge's tip: river 1's upper bank meets river 2's lower */
    *cx = (60 + r * (1 + cos(th)) / sin(th)) * WM_Q;
    *cy = (100 + r) * WM_Q;
}

int main(void)
{
    const double angles[] = {10, 20, 40};
    for (int k = 0; k < 3; k++)
    {
        wm_scene s;
        double cx, cy;
        wedge(angles[k], &cx, &cy, &s);
        wm_rings r = {0};
        double before;
        extract_recover(&s, cx, cy, nearest_edge, &r, &before, "wedge");
        const double after = nearest_vertex(&r, cx, cy) / WM_Q;
        TAP_OK(after < 0.01,
               "%g deg wedge: tip %.3f px from the sampled rings, %.4f px "
               "after recovery",
               angles[k], before, after);
        TAP_OK(ring_meetings(&r) == 0, "rings still simple and disjoint");
        for (size_t i = 0; i < r.nrings; i++)
            TAP_OK(wm_ring_area2(r.pts + r.start[i], wm_rings_len(&r, i)) != 0,
                   "ring %zu keeps a non-zero area", i);
        wm_rings_free(&r);
        wm_scene_free(&s);
    }
    /* the same wedge against the bank of a river 1200 px wide (its reach
     * box spans thousands of index cells: crease.c keeps it in the list of
     * wide segments checked everywhere) */
    {
        const double th = 20 * 3.14159265358979323846 / 180.0;
        wm_scene s;
        su_init(&s, 1024);
        const double r1[] = {-500, 700, 1500, 700};
        const double r2[] = {60, 100, 60 + 190 * cos(th), 100 - 190 * sin(th)};
        su_river(&s, r1, 2, 600.0);
        su_river(&s, r2, 2, 5.0);
        su_finish(&s);
        /* the tip: river 1's lower bank (y = 100) meets river 2's upper */
        const double cx = (60 + 5.0 / sin(th)) * WM_Q, cy = 100.0 * WM_Q;
        wm_rings r = {0};
        double before;
        extract_recover(&s, cx, cy, nearest_edge, &r, &before,
                        "next to a wide river");
        const double after = nearest_vertex(&r, cx, cy) / WM_Q;
        TAP_OK(after < 0.01 && before > 1,
               "wedge at a 1200 px river: tip %.3f px away, %.4f px after",
               before, after);
        TAP_OK(ring_meetings(&r) == 0, "rings still simple and disjoint");
        wm_rings_free(&r);
        wm_scene_free(&s);
    }
    /* a corner next to the block square is left alone: seams stay exact */
    {
        wm_scene s;
        su_init(&s, 64);
        const double r1[] = {-50, 0.3, 100, 0.3};
        const double r2[] = {-50, 0.3, 100, 30};
        su_river(&s, r1, 2, 2.0);
        su_river(&s, r2, 2, 2.0);
        su_finish(&s);
        wm_field f;
        wm_rings r = {0}, r0 = {0};
        wm_field_compute(&s, 0, 0, 65, 65, NULL, &f, NULL);
        wm_contour_extract(&f, &r, NULL);
        wm_contour_extract(&f, &r0, NULL);
        wm_crease_recover(&s, &f, 0, 0, &r, NULL);
        size_t border = 0, border0 = 0;
        const int32_t S = 64 * WM_Q;
        for (size_t k = 0; k < r.npts; k++)
            border += r.pts[k].x == 0 || r.pts[k].y == 0 || r.pts[k].x == S ||
                      r.pts[k].y == S;
        for (size_t k = 0; k < r0.npts; k++)
            border0 += r0.pts[k].x == 0 || r0.pts[k].y == 0 ||
                       r0.pts[k].x == S || r0.pts[k].y == S;
        TAP_EQ(border, border0, "block-square vertices unchanged");
        TAP_OK(ring_meetings(&r) == 0, "rings valid");
        wm_field_free(&f);
        wm_rings_free(&r);
        wm_rings_free(&r0);
        wm_scene_free(&s);
    }
    /* a 10 degree wedge between a river 3.3 px wide and one 0.5 px wide:
     * the tip lies nearer the wide river's far bank than the cut the
     * samples make, so the nearest ring edge does not take the corner; a
     * farther one does */
    {
        wm_scene s;
        su_init(&s, 128);
        const double v[2] = {31.359375, 47.0390625};
        const double ra = 1.633184 * 2, rb = 0.247268 * 2;
        const double a[] = {v[0], v[1], 95.7265625, 98.96875};
        const double b[] = {v[0], v[1], 85.78125, 109.31640625};
        su_river(&s, a, 2, ra);
        su_river(&s, b, 2, rb);
        su_finish(&s);
        /* the tip: a's left bank meets b's right bank */
        const double la = hypot(a[2] - a[0], a[3] - a[1]);
        const double lb = hypot(b[2] - b[0], b[3] - b[1]);
        const double ua[2] = {(a[2] - a[0]) / la, (a[3] - a[1]) / la};
        const double ub[2] = {(b[2] - b[0]) / lb, (b[3] - b[1]) / lb};
        /* v + s ua + ra (-ua.y, ua.x) = v + t ub + rb (ub.y, -ub.x) */
        const double rx = rb * ub[1] + ra * ua[1],
                     ry = -rb * ub[0] - ra * ua[0];
        const double det = ua[0] * -ub[1] + ub[0] * ua[1];
        const double sa = (rx * -ub[1] + ub[0] * ry) / det;
        const double cx = (v[0] + sa * ua[0] - ra * ua[1]) * WM_Q;
        const double cy = (v[1] + sa * ua[1] + ra * ua[0]) * WM_Q;
        wm_rings r = {0};
        double before;
        extract_recover(&s, cx, cy, nearest_vertex, &r, &before,
                        "beside a narrow river");
        const double after = nearest_vertex(&r, cx, cy) / WM_Q;
        TAP_OK(after < 0.01 && before > 0.5,
               "wedge beside a narrow river: tip %.3f px from a vertex, "
               "%.4f px after",
               before, after);
        TAP_OK(ring_meetings(&r) == 0, "rings still simple and disjoint");
        wm_rings_free(&r);
        wm_scene_free(&s);
    }
    /* a narrow river leaving a lake through its edge on x = 64 px, a line
     * of the 16-pixel grid corners.c buckets primitives in: the crossing
     * of the bank and the edge computed from the bank may fall a few ulps
     * into the cell on the left, which the edge does not reach; the
     * corner was then never a candidate and stayed cut by 0.6 px (the
     * twolakes scene of issue 12, 0.25 m pixels). Eight offsets of the
     * river. */
    for (int k = 0; k < 8; k++)
    {
        wm_scene s;
        su_init(&s, 128);
        const double dy = k / 8.0;
        const double lake[] = {-8, 20, 64, 20, 64, 54, -8, 54};
        const int cnt[] = {4};
        const double rv[] = {-68.97150951, 12.34909 + dy, 170.54016,
                             27.65094 + dy};
        const double rr = 0.41774839;
        su_lake(&s, lake, cnt, 1);
        su_river(&s, rv, 2, rr);
        su_finish(&s);
        /* the corner: the river's upper bank at x = 64 */
        const double m = (rv[3] - rv[1]) / (rv[2] - rv[0]);
        const double cx = 64.0 * WM_Q,
                     cy = (rv[1] + (64 - rv[0]) * m + rr * sqrt(1 + m * m)) *
                          WM_Q;
        wm_rings r = {0};
        double before;
        extract_recover(&s, cx, cy, nearest_edge, &r, &before,
                        "a lake edge on a grid line");
        const double after = nearest_edge(&r, cx, cy) / WM_Q;
        TAP_OK(after < 0.25,
               "bank leaving a lake edge on x = 64 px (+%g px): corner %.3f "
               "px from the sampled rings, %.4f px after",
               dy, before, after);
        TAP_OK(ring_meetings(&r) == 0, "rings still simple and disjoint");
        wm_rings_free(&r);
        wm_scene_free(&s);
    }
    return TAP_DONE();
}
