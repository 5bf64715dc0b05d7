/* test_block.c - property tests of the whole per-block pipeline on random
 * scenes: valid rings, polygons with their holes, exact triangle coverage,
 * identical vertices on shared block edges, deterministic results. */
#include "block.h"
#include "lattice.h"
#include "ring_check.h"
#include "scene_util.h"
#include "tap.h"

#include <math.h>
#include <string.h>

static unsigned rng_state;
static double rnd(double lo, double hi)
{
    rng_state = rng_state * 1103515245u + 12345u;
    return lo + (hi - lo) * (double)((rng_state >> 8) & 0xffffff) / 16777216.0;
}

/* A random scene in pixels over [0, 3n] x [0, 3n]: meandering rivers, some
 * sharing a start vertex, random-radius lakes (some self-intersecting). */
static void random_scene(wm_scene *s, int32_t n, unsigned seed)
{
    rng_state = seed;
    su_init(s, n);
    const double ext = 3.0 * n;
    double xy[2 * 40];
    double jx = rnd(0, ext), jy = rnd(0, ext);
    for (int r = 0; r < 6; r++)
    {
        int np = 3 + (int)rnd(0, 20);
        double x = r < 3 ? jx : rnd(0, ext), y = r < 3 ? jy : rnd(0, ext);
        double h = rnd(0, 6.283);
        for (int i = 0; i < np; i++)
        {
            xy[2 * i] = x;
            xy[2 * i + 1] = y;
            h += rnd(-0.9, 0.9);
            const double step = rnd(2, 15);
            x += step * (h < 3.14 ? 1 : -1) * (0.3 + rnd(0, 0.7));
            y += step * (rnd(0, 1) < 0.5 ? 1 : -1) * rnd(0, 1);
        }
        su_river(s, xy, np, rnd(0.3, 8));
    }
    for (int l = 0; l < 3; l++)
    {
        const int np = 5 + (int)rnd(0, 30);
        const double cx = rnd(0, ext), cy = rnd(0, ext), R = rnd(3, n / 2.0);
        const int twist = l == 2; /* self-intersecting star */
        for (int i = 0; i < np; i++)
        {
            const double a = 6.2831853 * i * (twist ? 3 : 1) / np;
            const double rr = R * rnd(0.4, 1.0);
            xy[2 * i] = cx + rr * cos(a);
            xy[2 * i + 1] = cy + rr * sin(a);
        }
        const int cnt[1] = {np};
        su_lake(s, xy, cnt, 1);
    }
    su_finish(s);
}

static int check_block(const wm_block_result *r)
{
    int bad = ring_meetings(&r->rings);
    for (size_t p = 0; p < r->npolys; p++)
    {
        wm_i128 area = 0;
        for (size_t ri = r->poly_ring[p]; ri < r->poly_ring[p + 1]; ri++)
        {
            const wm_i128 a = wm_ring_area2(r->rings.pts + r->rings.start[ri],
                                            wm_rings_len(&r->rings, ri));
            bad += ri == r->poly_ring[p] ? a <= 0 : a >= 0;
            area += a;
        }
        wm_i128 tri = 0;
        for (size_t t = r->poly_tri[p]; t < r->poly_tri[p + 1]; t++)
        {
            const wm_pt *q = r->rings.pts;
            const int64_t a =
                wm_orient_det(q[r->tris[3 * t]], q[r->tris[3 * t + 1]],
                              q[r->tris[3 * t + 2]]);
            bad += a <= 0;
            tri += a;
        }
        bad += tri != area;
    }
    return bad;
}

/* Sorted positions of the vertices of r on its block's edge `side`
 * (0: x == 0, 1: x == S); returns the count. */
static size_t edge_vertices(const wm_block_result *r, int32_t S, int side,
                            int32_t *out, size_t cap)
{
    size_t n = 0;
    for (size_t k = 0; k < r->rings.npts && n < cap; k++)
        if (r->rings.pts[k].x == (side ? S : 0))
            out[n++] = r->rings.pts[k].y;
    for (size_t i = 1; i < n; i++) /* insertion sort */
        for (size_t j = i; j > 0 && out[j - 1] > out[j]; j--)
        {
            const int32_t t = out[j];
            out[j] = out[j - 1];
            out[j - 1] = t;
        }
    return n;
}

int main(void)
{
    const wm_block_opts opts[2] = {{.simplify = 0.0, .triangulate = 1},
                                   {.simplify = WM_Q, .triangulate = 1}};
    for (unsigned seed = 1; seed <= 40; seed++)
    {
        wm_scene s;
        random_scene(&s, 64, seed);
        int bad = 0, seams = 0, polys = 0, fails = 0, det = 0;
        for (int o = 0; o < 2; o++)
            for (int64_t by = 0; by < 3; by++)
                for (int64_t bx = 0; bx < 3; bx++)
                {
                    wm_block_result r, r2, right;
                    if (wm_block_run(&s, bx, by, &opts[o], &r, NULL) != WM_OK)
                    {
                        fails++;
                        continue;
                    }
                    bad += check_block(&r);
                    polys += (int)r.npolys;
                    /* the same block twice: the same rings */
                    if (wm_block_run(&s, bx, by, &opts[o], &r2, NULL) == WM_OK)
                    {
                        det += r2.rings.npts != r.rings.npts ||
                               (r.rings.npts > 0 &&
                                memcmp(r2.rings.pts, r.rings.pts,
                                       r.rings.npts * sizeof(wm_pt)) != 0);
                        wm_block_result_free(&r2);
                    }
                    /* the shared edge with the right neighbour */
                    if (bx < 2 && wm_block_run(&s, bx + 1, by, &opts[o], &right,
                                               NULL) == WM_OK)
                    {
                        static int32_t a[4096], b[4096];
                        const int32_t S = 64 * WM_Q;
                        const size_t na = edge_vertices(&r, S, 1, a, 4096);
                        const size_t nb = edge_vertices(&right, S, 0, b, 4096);
                        seams += na != nb || memcmp(a, b, na * sizeof *a) != 0;
                        wm_block_result_free(&right);
                    }
                    wm_block_result_free(&r);
                }
        TAP_EQ(fails, 0, "seed %u: every block runs", seed);
        TAP_EQ(bad, 0,
               "seed %u: %d polygons valid, holes CW, triangles cover them "
               "exactly",
               seed, polys);
        TAP_EQ(seams, 0, "seed %u: shared block edges carry the same vertices",
               seed);
        TAP_EQ(det, 0, "seed %u: a block computed twice is identical", seed);
        wm_scene_free(&s);
    }
    return TAP_DONE();
}
