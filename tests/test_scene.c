/* test_scene.c - the reach index: per block and per row, the R-tree's
 * answers equal a brute-force scan over every item's reach, on random
 * scenes with tiny, long and huge items; wm_scene_depth in rivers, lakes,
 * holes and outside. */
#include "scene.h"
#include "scene_util.h"
#include "tap.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

static uint64_t rng = 88172645463325252u;

static double uniform(double lo, double hi)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return lo + (hi - lo) * (double)(rng >> 11) / 9007199254740992.0;
}

/* Does item i (segments, then polygons) reach block (bx, by)? The rule of
 * scene.c spelled out: the item's box grown by its reach. */
static int reaches(const wm_scene *s, size_t i, int64_t bx, int64_t by)
{
    const int64_t side = (int64_t)s->n * WM_Q;
    int64_t x0, y0, x1, y1, grow;
    if (i < s->nsegs)
    {
        const wm_river_seg *g = &s->segs[i];
        x0 = g->ax < g->bx ? g->ax : g->bx;
        x1 = g->ax > g->bx ? g->ax : g->bx;
        y0 = g->ay < g->by ? g->ay : g->by;
        y1 = g->ay > g->by ? g->ay : g->by;
        grow = (int64_t)ceil(g->r) + (int64_t)s->band * WM_Q + 1;
    }
    else
    {
        const wm_box b = s->poly_box[i - s->nsegs];
        x0 = b.x0;
        y0 = b.y0;
        x1 = b.x1;
        y1 = b.y1;
        grow = (int64_t)s->band * WM_Q + 1;
    }
    return wm_floordiv(x0 - grow, side) <= bx &&
           bx <= wm_floordiv(x1 + grow, side) &&
           wm_floordiv(y0 - grow, side) <= by &&
           by <= wm_floordiv(y1 + grow, side);
}

/* A random scene of n items in a square of `extent` pixels, blocks of 8
 * pixels: short segments, a few very long or very wide ones, small lakes. */
static void random_scene(wm_scene *s, int n, double extent)
{
    su_init(s, 8);
    for (int i = 0; i < n; i++)
    {
        const double x = uniform(-extent, extent), y = uniform(-extent, extent);
        const int kind = (int)uniform(0, 10);
        if (kind < 6)
        {
            const double xy[4] = {x, y, x + uniform(-5, 5), y + uniform(-5, 5)};
            su_river(s, xy, 2, uniform(0.1, 2));
        }
        else if (kind < 7)
        {
            const double xy[4] = {x, y, uniform(-extent, extent),
                                  uniform(-extent, extent)};
            su_river(s, xy, 2, kind == 6 && i % 2 ? extent / 3 : 0.5);
        }
        else
        {
            const double d = uniform(0.5, 20);
            const double xy[6] = {x, y, x + d, y, x, y + d};
            const int counts[1] = {3};
            su_lake(s, xy, counts, 1);
        }
    }
    su_finish(s);
}

static int check_blocks(const wm_scene *s)
{
    int bad = 0;
    for (int64_t by = s->by0 - 1; by <= s->by0 + s->nby && !bad; by++)
        for (int64_t bx = s->bx0 - 1; bx <= s->bx0 + s->nbx && !bad; bx++)
        {
            uint32_t *ids;
            size_t ns, np;
            const wm_box b = {bx, by, bx, by};
            if (wm_scene_items(s, b, &ids, &ns, &np) != WM_OK)
                return 1;
            size_t k = 0;
            for (size_t i = 0; i < s->nsegs + s->npolys && !bad; i++)
                if (reaches(s, i, bx, by))
                {
                    const size_t want = i < s->nsegs ? i : i - s->nsegs;
                    bad = k >= ns + np || ids[k] != want ||
                          (k < ns) != (i < s->nsegs);
                    k++;
                }
            bad |= k != ns + np;
            free(ids);
        }
    return bad;
}

static int check_rows(const wm_scene *s)
{
    int bad = 0;
    const int64_t x0 = s->bx0 + 1, x1 = s->bx0 + s->nbx - 2;
    for (int64_t by = s->by0 - 1; by <= s->by0 + s->nby && !bad; by++)
    {
        int64_t *runs;
        size_t nruns, r = 0;
        if (wm_scene_row_runs(s, by, x0, x1, &runs, &nruns) != WM_OK)
            return 1;
        for (int64_t bx = x0; bx <= x1 && !bad; bx++)
        {
            int any = 0;
            for (size_t i = 0; i < s->nsegs + s->npolys && !any; i++)
                any = reaches(s, i, bx, by);
            while (r < nruns && runs[2 * r + 1] < bx)
                r++;
            const int in = r < nruns && runs[2 * r] <= bx;
            bad = in != any;
        }
        for (size_t i = 0; i + 1 < nruns && !bad; i++)
            bad = runs[2 * i + 1] + 1 >= runs[2 * i + 2];
        free(runs);
    }
    return bad;
}

int main(void)
{
    const int sizes[] = {0, 1, 2, 17, 300, 2000};
    for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++)
    {
        wm_scene s;
        random_scene(&s, sizes[k], 200);
        TAP_OK(!check_blocks(&s),
               "%d items: each block's items are those "
               "whose reach holds it, ascending",
               sizes[k]);
        TAP_OK(!check_rows(&s), "%d items: row runs are the reached blocks",
               sizes[k]);
        if (sizes[k] > 0)
            TAP_OK(s.reach.nlevels >= 1 &&
                       s.reach.level[s.reach.nlevels] -
                               s.reach.level[s.reach.nlevels - 1] ==
                           1,
                   "%d items: one root", sizes[k]);
        wm_scene_free(&s);
    }

    /* the issue-13 case: one segment 100000 px wide over blocks of 13 px
     * reaches about 59 M blocks; the index holds one box */
    wm_scene s;
    su_init(&s, 13);
    const double xy[4] = {0, 0, 10, 0};
    su_river(&s, xy, 2, 50000);
    su_finish(&s);
    TAP_OK(s.nbx * s.nby > 50000000, "wide river: %lld blocks in the grid",
           (long long)(s.nbx * s.nby));
    TAP_EQ(s.reach.level[s.reach.nlevels], (size_t)1,
           "wide river: one box indexed");
    int64_t *runs;
    size_t nruns;
    TAP_EQ(wm_scene_row_runs(&s, 0, s.bx0, s.bx0 + s.nbx - 1, &runs, &nruns),
           WM_OK, "row runs");
    TAP_OK(nruns == 1 && runs[0] == s.bx0 && runs[1] == s.bx0 + s.nbx - 1,
           "wide river: row 0 is one run over the grid");
    free(runs);
    wm_scene_free(&s);

    /* wm_scene_depth: a river 20 px wide along y = 0 and a lake, the square
     * 100..200 with the hole 140..160 */
    su_init(&s, 64);
    const double river[4] = {0, 0, 300, 0};
    su_river(&s, river, 2, 10);
    const double lake[16] = {100, 100, 200, 100, 200, 200, 100, 200,
                             140, 140, 160, 140, 160, 160, 140, 160};
    const int counts[2] = {4, 4};
    su_lake(&s, lake, counts, 2);
    su_finish(&s);
    const uint32_t segs[1] = {0}, polys[1] = {0};
    wm_lake_bands lb;
    TAP_EQ(wm_lake_bands_build(&lb, &s, polys, 1), WM_OK, "lake bands");
    const double Q = WM_Q;
    TAP_OK(
        fabs(wm_scene_depth(&s, segs, 1, &lb, 50 * WM_Q, 4 * WM_Q, INFINITY) -
             6 * Q) < 1e-9,
        "depth in a river: r - distance to its axis");
    TAP_OK(fabs(wm_scene_depth(&s, segs, 1, &lb, 130 * WM_Q, 150 * WM_Q,
                               INFINITY) -
                10 * Q) < 1e-9,
           "depth in a lake: distance to its nearest edge, a hole's too");
    TAP_OK(wm_scene_depth(&s, segs, 1, &lb, 150 * WM_Q, 150 * WM_Q, INFINITY) ==
               0,
           "depth in a lake's hole: 0");
    TAP_OK(wm_scene_depth(&s, segs, 1, &lb, 50 * WM_Q, 50 * WM_Q, INFINITY) ==
               0,
           "depth outside every item: 0");
    TAP_OK(wm_scene_depth(&s, segs, 1, &lb, 100 * WM_Q, 150 * WM_Q, INFINITY) ==
               0,
           "depth on a lake's shore: 0");
    TAP_OK(wm_scene_depth(&s, segs, 1, NULL, 120 * WM_Q, 130 * WM_Q,
                          INFINITY) == 0,
           "depth counts only the items passed");
    TAP_OK(wm_scene_depth(&s, segs, 1, &lb, 130 * WM_Q, 150 * WM_Q, 4 * Q) ==
               4 * Q,
           "depth capped");
    /* the bands' distance equals a scan of every edge, around a wavy lake */
    {
        wm_scene w;
        su_init(&w, 64);
        double wavy[2 * 400];
        for (int i = 0; i < 400; i++)
        {
            const double a = 2 * 3.14159265358979 * i / 400;
            const double r = 100 * (1 + 0.3 * sin(7 * a));
            wavy[2 * i] = 200 + r * cos(a);
            wavy[2 * i + 1] = 200 + r * sin(a);
        }
        const int n400[1] = {400};
        su_lake(&w, wavy, n400, 1);
        su_finish(&w);
        wm_lake_bands wb;
        int bad = 0, inside = 0;
        TAP_EQ(wm_lake_bands_build(&wb, &w, NULL, 0), WM_OK, "wavy lake bands");
        for (int i = 0; i < 4000; i++)
        {
            const int64_t X = (int64_t)(uniform(60, 340) * WM_Q);
            const int64_t Y = (int64_t)(uniform(60, 340) * WM_Q);
            int par = 0;
            double d2 = INFINITY;
            for (size_t e = 0; e < w.nedges; e++)
            {
                const wm_lake_edge *g = &w.edges[e];
                par ^= wm_edge_crosses_ray(g, X, Y);
                const double px = (double)(X - g->ax), py = (double)(Y - g->ay);
                const double dx = (double)(g->bx - g->ax),
                             dy = (double)(g->by - g->ay);
                double t = (px * dx + py * dy) / (dx * dx + dy * dy);
                t = t < 0 ? 0 : (t > 1 ? 1 : t);
                const double ex = px - t * dx, ey = py - t * dy;
                d2 = ex * ex + ey * ey < d2 ? ex * ex + ey * ey : d2;
            }
            const double want = par ? sqrt(d2) : 0;
            inside += par;
            bad += wm_lake_bands_inside(&wb, 0, X, Y) != par ||
                   wm_scene_depth(&w, NULL, 0, &wb, X, Y, INFINITY) != want;
        }
        TAP_OK(inside > 1000 && bad == 0,
               "4000 points: parity and depth from the bands equal a full "
               "scan (%d inside, %d differ)",
               inside, bad);
        wm_lake_bands_free(&wb);
        wm_scene_free(&w);
    }
    wm_lake_bands_free(&lb);
    wm_scene_free(&s);
    return TAP_DONE();
}
