/*
 * test_refine.c - wm_refine_triangulate: on polygons with holes, thin
 * wedges, random stars and a block-square polygon, every result is a
 * triangulation of the polygon (orientation, exact area, every input
 * vertex used, ring edges kept or split), meets MIN_ANGLE except at input
 * angles (counted), meets MAX_EDGE, and cuts block-square edges only at
 * the global multiples of MAX_EDGE.
 */
#include "cdt.h"
#include "lattice.h"
#include "refine.h"
#include "scene.h"
#include "tap.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static void push(wm_rings *r, int x, int y)
{
    wm_pt p = {x, y};
    if (wm_rings_push(r, p) != WM_OK)
        abort();
}

/* Pushes the n points xy[0..2n) as one closed ring. */
static void ring(wm_rings *r, const int *xy, int n)
{
    for (int i = 0; i < n; i++)
        push(r, xy[2 * i], xy[2 * i + 1]);
    if (wm_rings_close(r) != WM_OK)
        abort();
}

/* A new set holding one ring. */
static wm_rings ring_of(const int *xy, int n)
{
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, xy, n);
    return r;
}

static double angle_min(wm_pt a, wm_pt b, wm_pt c)
{
    const wm_pt p[3] = {a, b, c};
    double best = 180;
    for (int i = 0; i < 3; i++)
    {
        const wm_pt o = p[i], u = p[(i + 1) % 3], v = p[(i + 2) % 3];
        const double ux = u.x - o.x, uy = u.y - o.y;
        const double vx = v.x - o.x, vy = v.y - o.y;
        const double cs = (ux * vx + uy * vy) /
                          sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy));
        const double deg = acos(cs > 1 ? 1 : (cs < -1 ? -1 : cs)) * 180 / PI;
        best = deg < best ? deg : best;
    }
    return best;
}

typedef struct
{
    int ok_orient, ok_area, ok_used, ok_edge;
    size_t below, ntris, nextra;
    double sharpest; /* the smallest angle, degrees */
    double area_in, area_out, worst_edge, perimeter;
    double drift; /* farthest added shore point from the input's rings */
    wm_refine_stats st;
} result;

static wm_pt at(const wm_rings *r, const wm_pt *extra, uint32_t i)
{
    return i < r->npts ? r->pts[i] : extra[i - r->npts];
}

/* Distance from p to the nearest edge of rings r. */
static double to_rings(const wm_rings *r, wm_pt p)
{
    double best = INFINITY;
    for (size_t q = 0; q < r->nrings; q++)
        for (size_t i = r->start[q]; i < r->start[q + 1]; i++)
        {
            const wm_pt a = r->pts[i];
            const wm_pt b =
                r->pts[i + 1 < r->start[q + 1] ? i + 1 : r->start[q]];
            const double dx = b.x - a.x, dy = b.y - a.y;
            const double l2 = dx * dx + dy * dy;
            double t = l2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2 : 0;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            const double d = hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
            best = d < best ? d : best;
        }
    return best;
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* The farthest from rings r of the added points (index >= r->npts) on the
 * outline of triangles tris (nt): the edges no other triangle has
 * reversed. */
static double shore_drift(const wm_rings *r, const wm_pt *extra,
                          const uint32_t *tris, size_t nt)
{
    uint64_t *e = malloc((3 * nt + 1) * sizeof *e);
    for (size_t i = 0; i < 3 * nt; i++)
        e[i] = (uint64_t)tris[i] << 32 | tris[i - i % 3 + (i % 3 + 1) % 3];
    qsort(e, 3 * nt, sizeof *e, cmp_u64);
    double worst = 0;
    for (size_t i = 0; i < 3 * nt; i++)
    {
        const uint32_t u = (uint32_t)(e[i] >> 32), v = (uint32_t)e[i];
        const uint64_t rev = (uint64_t)v << 32 | u;
        if (bsearch(&rev, e, 3 * nt, sizeof *e, cmp_u64))
            continue;
        for (int k = 0; k < 2; k++)
        {
            const uint32_t w = k ? v : u;
            if (w < r->npts)
                continue;
            const double d = to_rings(r, extra[w - r->npts]);
            worst = d > worst ? d : worst;
        }
    }
    free(e);
    return worst;
}

/* Refines rings r (ring 0 outer) and checks the result. */
static result run(const wm_rings *r, const wm_refine_opts *o)
{
    result res;
    memset(&res, 0, sizeof res);
    uint32_t *tris = NULL;
    wm_pt *extra = NULL;
    size_t nt = 0, nx = 0;
    const wm_status st = wm_refine_triangulate(
        r->pts, r->start, r->nrings, o, &tris, &nt, &extra, &nx, &res.st, NULL);
    if (st != WM_OK)
        return res;
    res.ntris = nt;
    res.nextra = nx;
    res.ok_orient = res.ok_used = res.ok_edge = 1;
    wm_i128 a2 = 0, in2 = 0;
    for (size_t q = 0; q < r->nrings; q++)
        in2 += wm_ring_area2(r->pts + r->start[q], wm_rings_len(r, q));
    for (size_t q = 0; q < r->nrings; q++)
        for (size_t i = r->start[q]; i < r->start[q + 1]; i++)
        {
            const wm_pt a = r->pts[i];
            const wm_pt b =
                r->pts[i + 1 < r->start[q + 1] ? i + 1 : r->start[q]];
            res.perimeter += hypot(a.x - b.x, a.y - b.y);
        }
    uint8_t *used = calloc(r->npts + 1, 1);
    for (size_t t = 0; t < nt; t++)
    {
        const wm_pt a = at(r, extra, tris[3 * t]);
        const wm_pt b = at(r, extra, tris[3 * t + 1]);
        const wm_pt c = at(r, extra, tris[3 * t + 2]);
        const int64_t d = wm_orient_det(a, b, c);
        res.ok_orient &= d > 0;
        a2 += d;
        for (int k = 0; k < 3; k++)
        {
            if (tris[3 * t + k] < r->npts)
                used[tris[3 * t + k]] = 1;
            const wm_pt u = at(r, extra, tris[3 * t + k]);
            const wm_pt v = at(r, extra, tris[3 * t + (k + 1) % 3]);
            const double len = hypot(u.x - v.x, u.y - v.y);
            res.worst_edge = len > res.worst_edge ? len : res.worst_edge;
        }
        const double am = angle_min(a, b, c);
        if (o->min_angle > 0 && am < o->min_angle - 1e-9)
            res.below++;
        res.sharpest = t == 0 || am < res.sharpest ? am : res.sharpest;
    }
    for (size_t i = 0; i < r->npts; i++)
        res.ok_used &= used[i];
    res.area_in = (double)in2;
    res.area_out = (double)a2;
    res.drift = shore_drift(r, extra, tris, nt);
    free(used);
    free(tris);
    free(extra);
    return res;
}

/* (away from the block square's lines x, y = 0) */
static void square_with_hole(wm_rings *r, int S)
{
    const int outer[] = {10, 10, S, 10, S, S, 10, S};
    const int hole[] = {S / 3,         S / 3,          S / 3,     2 * S / 3,
                        2 * S / 3 + 7, 2 * S / 3 - 11, 2 * S / 3, S / 3};
    ring(r, outer, 4);
    ring(r, hole, 4);
}

/* Shore segments in global lattice units; the room of a point is its
 * distance to the nearest, a function of global points. */
typedef struct
{
    int n;
    double seg[4][4];
} shores;

static double room_of_shores(void *user, int64_t X, int64_t Y, double cap)
{
    const shores *sh = user;
    double best = INFINITY;
    for (int i = 0; i < sh->n; i++)
    {
        const double *g = sh->seg[i];
        const double dx = g[2] - g[0], dy = g[3] - g[1];
        double t = (((double)X - g[0]) * dx + ((double)Y - g[1]) * dy) /
                   (dx * dx + dy * dy);
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        const double ex = (double)X - g[0] - t * dx;
        const double ey = (double)Y - g[1] - t * dy;
        const double d = sqrt(ex * ex + ey * ey);
        best = d < best ? d : best;
    }
    return best < cap ? best : cap;
}

/* Refines rings r and writes the y of its Steiner points on the line
 * x = side, ascending (at most max); their count, or -1 on failure. */
static int side_points(const wm_rings *r, const wm_refine_opts *o, int side,
                       int32_t *y, int max, wm_refine_stats *st)
{
    uint32_t *tris = NULL;
    wm_pt *extra = NULL;
    size_t nt = 0, nx = 0;
    int n = 0;
    if (wm_refine_triangulate(r->pts, r->start, r->nrings, o, &tris, &nt,
                              &extra, &nx, st, NULL) != WM_OK)
        return -1;
    for (size_t i = 0; i < nx; i++)
        if (extra[i].x == side && n < max)
        {
            int k = n++;
            for (; k > 0 && y[k - 1] > extra[i].y; k--)
                y[k] = y[k - 1];
            y[k] = extra[i].y;
        }
    free(tris);
    free(extra);
    return n;
}

/* Refines ra (the block at the origin, square side S) and rb (the block
 * across its side x = S) with MIN_ANGLE 20, SIMPLIFY of a pixel, the room
 * of sh and the blocks' water along their squares ea and eb (NULL: none):
 * the Steiner points on the shared side, from ra, into ya (ascending, *na
 * of them, at most 510; -1 on failure), and whether rb's differ. */
static int shared_side_of(const wm_rings *ra, const wm_rings *rb, int S,
                          const shores *sh, const wm_side_ends *ea,
                          const wm_side_ends *eb, int32_t *ya, int *na,
                          wm_refine_stats *sa, wm_refine_stats *sb)
{
    const wm_refine_opts oa = {20,         0,  S,   0, 0, room_of_shores,
                               (void *)sh, ea, WM_Q};
    const wm_refine_opts ob = {20,         0,  S,   S, 0, room_of_shores,
                               (void *)sh, eb, WM_Q};
    int32_t yb[512];
    *na = side_points(ra, &oa, S, ya, 510, sa);
    const int nb = side_points(rb, &ob, 0, yb, 510, sb);
    int differ = *na != nb;
    for (int i = 0; !differ && i < *na; i++)
        differ = ya[i] != yb[i];
    return differ;
}

/* shared_side_of() without the water along the squares. */
static int shared_side(const wm_rings *ra, const wm_rings *rb, int S,
                       const shores *sh, int32_t *ya, int *na,
                       wm_refine_stats *sa)
{
    wm_refine_stats sb = {0, 0, 0, 0};
    return shared_side_of(ra, rb, S, sh, NULL, NULL, ya, na, sa, &sb);
}

/* shared_side_of() without and with the blocks' water along their squares
 * (wm_side_ends of ra and rb): the side points with it (ya, *na), whether
 * the blocks cut the side differently with it (*differ), and the sharp
 * triangles both leave without (left[0]) and with it (left[1]). 0 on
 * failure. */
static int with_side_ends(const wm_rings *ra, const wm_rings *rb, int S,
                          const shores *sh, int32_t *ya, int *na, int *differ,
                          size_t left[2])
{
    wm_side_ends ea, eb;
    memset(&eb, 0, sizeof eb);
    int ok = wm_side_ends_build(&ea, ra, S) && wm_side_ends_build(&eb, rb, S);
    for (int with = 0; ok && with < 2; with++)
    {
        wm_refine_stats sa = {0, 0, 0, 0}, sb = {0, 0, 0, 0};
        *differ = shared_side_of(ra, rb, S, sh, with ? &ea : NULL,
                                 with ? &eb : NULL, ya, na, &sa, &sb);
        ok = *na >= 0 && *na < 510;
        left[with] = sa.left + sb.left;
    }
    wm_side_ends_free(&ea);
    wm_side_ends_free(&eb);
    return ok;
}

int main(void)
{
    /* a square with a hole, a long river-like strip, MIN_ANGLE 20 */
    {
        wm_rings r;
        memset(&r, 0, sizeof r);
        square_with_hole(&r, 30000);
        wm_refine_opts o = {20, 0, 1 << 20, 0, 0, NULL, NULL, NULL, 0};
        result x = run(&r, &o);
        TAP_OK(x.ntris > 0 && x.ok_orient && x.ok_used,
               "square with hole: %zu triangles, %zu points added", x.ntris,
               x.nextra);
        TAP_OK(x.area_in == x.area_out,
               "square with hole: area kept exactly (%.0f)", x.area_in);
        TAP_EQ(x.below, x.st.small_input + x.st.left,
               "square with hole: every triangle below 20 degrees is counted");
        TAP_EQ(x.below, 0, "square with hole: none below 20 degrees");
        wm_rings_free(&r);
    }
    {
        wm_rings r;
        memset(&r, 0, sizeof r);
        /* a strip 100 wide and 20000 long, with a bend */
        static const int strip[] = {10,    10,  10000, 300, 20000, 10,
                                    20000, 110, 10000, 400, 10,    110};
        ring(&r, strip, 6);
        wm_refine_opts o = {20, 0, 1 << 20, 0, 0, NULL, NULL, NULL, 0};
        result x = run(&r, &o);
        TAP_OK(x.ntris > 0 && x.ok_orient && x.ok_used,
               "strip: %zu triangles, %zu points added", x.ntris, x.nextra);
        TAP_OK(fabs(x.area_out - x.area_in) <= 0.5 * x.perimeter,
               "strip: area within the rounding of split midpoints (half a "
               "lattice unit along the shore) "
               "(%.0f vs %.0f)",
               x.area_out, x.area_in);
        TAP_EQ(x.below, x.st.small_input + x.st.left,
               "strip: every triangle below 20 degrees is counted");
        TAP_OK(x.below <= x.st.small_input + 2,
               "strip: below 20 degrees only at input angles (%zu, %zu input)",
               x.below, x.st.small_input);
        TAP_OK(x.drift <= 0.7072,
               "strip: shore points within 0.71 unit of the input (%.3f)",
               x.drift);
        wm_rings_free(&r);
    }
    /* a thin wedge: its tip is an input angle of about 1 degree */
    {
        wm_rings r;
        memset(&r, 0, sizeof r);
        static const int wedge[] = {10, 10, 50000, 400, 50000, 1400};
        ring(&r, wedge, 3);
        wm_refine_opts o = {20, 3000, 1 << 20, 0, 0, NULL, NULL, NULL, 0};
        result x = run(&r, &o);
        TAP_OK(x.ntris > 0 && x.ok_orient && x.ok_used,
               "wedge: %zu triangles, %zu points", x.ntris, x.nextra);
        TAP_OK(x.st.small_input >= 1,
               "wedge: the 1-degree tip is reported "
               "(%zu)",
               x.st.small_input);
        TAP_OK(x.worst_edge <= 3000 + 1e-9 || x.st.left > 0,
               "wedge: MAX_EDGE 3000 met (longest %.1f) or counted",
               x.worst_edge);
        TAP_OK(x.worst_edge <= 3000 + 1e-9, "wedge: longest edge %.1f <= 3000",
               x.worst_edge);
        TAP_OK(x.drift <= 0.7072,
               "wedge: shore points within 0.71 unit of the input (%.3f)",
               x.drift);
        wm_rings_free(&r);
    }
    /* random stars with a hole, angle and length */
    {
        uint64_t s = 7;
        size_t bad = 0, badlen = 0, fail = 0, area = 0, left = 0, below = 0;
        for (int k = 0; k < 40; k++)
        {
            wm_rings r;
            memset(&r, 0, sizeof r);
            const int n = 12 + k % 20;
            for (int i = 0; i < n; i++)
            {
                s = s * 6364136223846793005ULL + 1442695040888963407ULL;
                const double rad =
                    20000 + (double)(s >> 40) / (1 << 24) * 20000;
                const double th = 2 * PI * i / n;
                push(&r, 50000 + (int)(rad * cos(th)),
                     50000 + (int)(rad * sin(th)));
            }
            wm_rings_close(&r);
            push(&r, 48000, 48000);
            push(&r, 48000, 52000);
            push(&r, 52000, 52000);
            push(&r, 52000, 48000);
            wm_rings_close(&r);
            wm_refine_opts o = {20.7, 4000, 1 << 20, 0, 0, NULL, NULL, NULL, 0};
            result x = run(&r, &o);
            fail += !(x.ntris > 0 && x.ok_orient && x.ok_used);
            bad += x.below > x.st.small_input + x.st.left;
            left += x.st.left;
            below += x.below;
            badlen += x.worst_edge > 4000 + 1e-9;
            area += fabs(x.area_out - x.area_in) > 0.5 * x.perimeter;
            wm_rings_free(&r);
        }
        TAP_EQ(fail, 0, "40 random stars: valid triangulations");
        TAP_EQ(bad, 0,
               "40 random stars: every triangle below 20.7 degrees "
               "is counted");
        TAP_EQ(badlen, 0, "40 random stars: MAX_EDGE 4000 met");
        TAP_EQ(left, 0,
               "40 random stars: nothing left unrefined (%zu below "
               "20.7 degrees, all at input angles)",
               below);
        TAP_EQ(area, 0, "40 random stars: area kept");
    }
    /* a polygon filling the block square: its sides are cut only at the
     * global multiples of MAX_EDGE (here the block's origin is 7 * S) */
    {
        const int S = 10000;
        wm_rings r;
        memset(&r, 0, sizeof r);
        const int sq[] = {0, 0, S, 0, S, S, 0, S};
        ring(&r, sq, 4);
        wm_refine_opts o = {20,   1500, S, 7 * (int64_t)S, 3 * (int64_t)S, NULL,
                            NULL, NULL, 0};
        uint32_t *tris = NULL;
        wm_pt *extra = NULL;
        size_t nt = 0, nx = 0;
        wm_refine_stats st = {0, 0, 0, 0};
        const wm_status rc = wm_refine_triangulate(r.pts, r.start, 1, &o, &tris,
                                                   &nt, &extra, &nx, &st, NULL);
        size_t side = 0, off = 0;
        for (size_t i = 0; i < nx; i++)
        {
            const wm_pt p = extra[i];
            const int on = p.x == 0 || p.x == S || p.y == 0 || p.y == S;
            const int64_t g = p.x == 0 || p.x == S ? 3 * (int64_t)S + p.y
                                                   : 7 * (int64_t)S + p.x;
            side += on;
            off += on && g % 1500 != 0;
        }
        TAP_OK(rc == WM_OK && nt > 0, "block square: %zu triangles", nt);
        TAP_EQ(off, 0,
               "block square: %zu side points, all at global "
               "multiples of 1500",
               side);
        /* x from 70000 to 80000: 70500 .. 79500, 7 points on each of the
         * two sides along x; y from 30000 to 40000: 31500 .. 39000, 6 */
        TAP_EQ(side, 2 * 7 + 2 * 6, "block square: the sides' multiples");
        free(tris);
        free(extra);
        wm_rings_free(&r);
    }
    /* shore edges ending on the block square (x = 0): refinement never puts
     * a point on the square but the global multiples of MAX_EDGE */
    {
        uint64_t s = 11;
        size_t bad_side = 0, fail = 0;
        for (int k = 0; k < 300; k++)
        {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            const int W = 2000 + (int)((s >> 33) % 20000);
            const int H = 3000 + (int)((s >> 13) % 20000);
            const int y0 = 1 + (int)((s >> 43) % (uint64_t)(H - 2));
            const int dx = 1 + k % 3;
            wm_rings r;
            memset(&r, 0, sizeof r);
            const int xy[] = {0, 0, W, 0, W, H, dx, H, 0, y0};
            ring(&r, xy, 5);
            const wm_refine_opts o = {
                20, k % 2 ? 900.0 : 0.0, 1 << 20, 0, 0, NULL, NULL, NULL, 0};
            uint32_t *tris = NULL;
            wm_pt *extra = NULL;
            size_t nt = 0, nx = 0;
            fail += wm_refine_triangulate(r.pts, r.start, 1, &o, &tris, &nt,
                                          &extra, &nx, NULL, NULL) != WM_OK;
            for (size_t i = 0; i < nx; i++)
            {
                const wm_pt p = extra[i];
                const int32_t v = p.x == 0 ? p.y : (p.y == 0 ? p.x : -1);
                if (v >= 0 && (o.max_edge == 0 || v % 900 != 0))
                    bad_side++;
            }
            free(tris);
            free(extra);
            wm_rings_free(&r);
        }
        TAP_EQ(fail, 0, "300 polygons touching the square: refined");
        TAP_EQ(bad_side, 0,
               "300 polygons touching the square: no point on "
               "it but the multiples of MAX_EDGE");
    }
    /* water across the side x = S between two blocks, with a shore vertex
     * of the left block close to the side edge: with a room callback (the
     * distance to the shores of both blocks, a function of global points)
     * both blocks grade their side edge into the same points, and fewer
     * triangles stay sharp than with the side edge kept whole */
    {
        const int S = 51200;
        const int a[] = {S,     10000,     S,     30000,   S - 20000,
                         30000, S - 20000, 12000, S - 800, 10400};
        const int b[] = {0, 10000, 20000, 11000, 20000, 30000, 0, 30000};
        wm_rings ra = ring_of(a, 5), rb = ring_of(b, 4);
        const shores sh = {4,
                           {{S - 20000, 12000, S - 800, 10400},
                            {S - 800, 10400, S, 10000},
                            {S, 10000, 2 * S, 11000},
                            {S - 20000, 30000, S + 20000, 30000}}};
        size_t left[2] = {0, 0}, graded = 0, differ = 0, fail = 0;
        for (int with = 0; with < 2; with++)
        {
            const wm_refine_opts oa = {
                20,          0,    S,   0, 0, with ? room_of_shores : NULL,
                (void *)&sh, NULL, WM_Q};
            const wm_refine_opts ob = {
                20,          0,    S,   S, 0, with ? room_of_shores : NULL,
                (void *)&sh, NULL, WM_Q};
            int32_t ya[64], yb[64];
            wm_refine_stats sa = {0, 0, 0, 0}, sb = {0, 0, 0, 0};
            const int na = side_points(&ra, &oa, S, ya, 64, &sa);
            const int nb = side_points(&rb, &ob, 0, yb, 64, &sb);
            fail += na < 0 || nb < 0;
            left[with] = sa.left + sb.left;
            if (with)
            {
                graded = (size_t)(na > 0 ? na : 0);
                differ = na != nb;
                for (int i = 0; !differ && i < na; i++)
                    differ = ya[i] != yb[i];
            }
        }
        TAP_EQ(fail, 0, "water across a side: refined in both blocks");
        TAP_OK(graded >= 2, "water across a side: %zu graded side points",
               graded);
        TAP_EQ(differ, 0, "water across a side: both blocks cut it alike");
        TAP_OK(graded < 64, "water across a side: every side point compared");
        TAP_OK(left[1] < left[0],
               "water across a side: %zu sharp triangles left, %zu with the "
               "side edge whole",
               left[1], left[0]);
        wm_rings_free(&ra);
        wm_rings_free(&rb);
    }
    /* a land notch 17 units wide at the side x = S between two blocks (6
     * units deep in the left block, 40 in the right one), water along the
     * side on both sides of it: with the blocks' water along the side
     * (wm_side_ends, the same in both), the side pieces next to the notch
     * are graded down to about half its width, both blocks cut the side
     * alike, and no triangle is left sharp; without, the pieces next to
     * the notch stay 8 pixels long and leave sharp triangles on it */
    {
        const int S = 51200;
        const int a[] = {S - 20000, 5000, S,     5000, S,     20000,     S - 6,
                         20008,     S,    20017, S,    35000, S - 20000, 35000};
        const int b[] = {0,     5000, 20000, 5000, 20000, 35000, 0,
                         35000, 0,    20017, 40,   20008, 0,     20000};
        wm_rings ra = ring_of(a, 7), rb = ring_of(b, 7);
        const shores sh = {4,
                           {{S - 20000, 5000, S + 20000, 5000},
                            {S - 20000, 35000, S + 20000, 35000},
                            {S, 20000, S - 6, 20008},
                            {S, 20000, S + 40, 20008}}};
        int32_t ya[512], near = 0;
        int na = 0, differ = 0;
        size_t left[2] = {0, 0};
        const int fail =
            !with_side_ends(&ra, &rb, S, &sh, ya, &na, &differ, left);
        /* the side points nearest the notch, below and above it */
        int32_t below = 0, above = 35000;
        for (int i = 0; i < na; i++)
        {
            below = ya[i] < 20000 && ya[i] > below ? ya[i] : below;
            above = ya[i] > 20017 && ya[i] < above ? ya[i] : above;
        }
        near = 20000 - below > above - 20017 ? 20000 - below : above - 20017;
        TAP_EQ(fail, 0, "a notch at a side: refined in both blocks");
        TAP_EQ(differ, 0, "a notch at a side: both blocks cut it alike");
        TAP_OK(near > 0 && near <= 16,
               "a notch at a side: the pieces next to it %d units long",
               (int)near);
        TAP_OK(left[1] == 0 && left[0] > 0,
               "a notch at a side: %zu sharp triangles left, %zu without "
               "the water along the side",
               left[1], left[0]);
        wm_rings_free(&ra);
        wm_rings_free(&rb);
    }
    /* a river 20000 units wide across the side x = S, its shores square to
     * it: the side pieces at the shores are graded down to 8 pixels at
     * SIMPLIFY of a pixel, and to one pixel at SIMPLIFY=0, whose shore
     * edges are that short */
    {
        const int S = 51200;
        const int a[] = {S - 20000, 10000, S,         10000,
                         S,         30000, S - 20000, 30000};
        wm_rings ra = ring_of(a, 4);
        const shores sh = {2,
                           {{S - 20000, 10000, S + 20000, 10000},
                            {S - 20000, 30000, S + 20000, 30000}}};
        int32_t first[2] = {0, 0};
        int fail = 0;
        for (int k = 0; k < 2; k++)
        {
            const wm_refine_opts o = {20,          0,    S,
                                      0,           0,    room_of_shores,
                                      (void *)&sh, NULL, k ? 0.0 : WM_Q};
            int32_t y[512];
            wm_refine_stats st = {0, 0, 0, 0};
            const int n = side_points(&ra, &o, S, y, 512, &st);
            fail += n <= 0 || n >= 512;
            first[k] = n > 0 ? y[0] - 10000 : 0;
        }
        TAP_EQ(fail, 0, "a river across a side: refined");
        TAP_OK(first[0] > 4 * WM_Q && first[0] <= 8 * WM_Q,
               "a river across a side: end piece %d units at SIMPLIFY of a "
               "pixel",
               (int)first[0]);
        TAP_OK(first[1] > 0 && first[1] <= WM_Q,
               "a river across a side: end piece %d units at SIMPLIFY=0",
               (int)first[1]);
        wm_rings_free(&ra);
    }
    /* a shore 30 units from the side x = S near y = 20000 only: the side
     * edge from the block corner (S, 0) to (S, 40000) is graded finely
     * there and coarsely elsewhere, with no piece more than four times as
     * long as its neighbour (Ruppert cannot split a side piece, so a long
     * one next to a short one leaves a skinny triangle on it), the piece at
     * the corner no longer than 16 pixels (four times the 4 pixels beyond
     * the corner that the side across it is graded against), and both
     * blocks cut it alike */
    {
        const int S = 51200, H = 40000;
        const int a[] = {S - 20000, 0, S, 0, S, H, S - 20000, H};
        const int b[] = {0, 0, 20000, 0, 20000, H, 0, H};
        wm_rings ra, rb;
        memset(&ra, 0, sizeof ra);
        memset(&rb, 0, sizeof rb);
        ring(&ra, a, 4);
        ring(&rb, b, 4);
        const shores sh = {1, {{S - 30, 19000, S - 30, 21000}}};
        int32_t ya[512];
        int na, ratio = 0;
        wm_refine_stats sa = {0, 0, 0, 0};
        const int differ = shared_side(&ra, &rb, S, &sh, ya, &na, &sa);
        int32_t y[514], shortest = H;
        int n = 0;
        y[n++] = 0;
        for (int i = 0; i < na && na < 510; i++)
            y[n++] = ya[i];
        y[n++] = H;
        for (int i = 0; i + 1 < n; i++)
        {
            const int32_t len = y[i + 1] - y[i];
            shortest = len < shortest ? len : shortest;
            if (i + 2 < n && (len > 4 * (y[i + 2] - y[i + 1]) ||
                              y[i + 2] - y[i + 1] > 4 * len))
                ratio++;
        }
        TAP_OK(na > 0 && na < 510, "side graded near a shore: %d side points",
               na);
        TAP_EQ(differ, 0, "side graded near a shore: both blocks alike");
        TAP_OK(shortest <= 32,
               "side graded near a shore: shortest piece %d units (room 30)",
               (int)shortest);
        TAP_EQ(ratio, 0,
               "side graded near a shore: neighbouring pieces within 4x");
        TAP_OK(na > 0 && ya[0] <= 16 * 256,
               "side graded near a shore: the corner's piece %d <= 16 pixels",
               na > 0 ? (int)ya[0] : -1);
        wm_rings_free(&ra);
        wm_rings_free(&rb);
    }
    /* a shore passing the block corner (S, S) 86 units off: the water
     * along the side y = S ends 100 units from the corner, so the piece of
     * the side x = S at the corner is graded down to the room there (78
     * units; 8 pixels before, which left a triangle of 3 degrees between
     * the two), and the block across the side cuts it alike */
    {
        const int S = 51200;
        const int a[] = {S - 12100, S - 20000, S, S - 20000, S, S, S - 100, S};
        const int b[] = {0, S - 20000, 3000, S - 20000, 3000, S - 5000, 0, S};
        wm_rings ra = ring_of(a, 4), rb = ring_of(b, 4);
        const shores sh = {2,
                           {{S - 12100, S - 20000, S + 5900, S + 10000},
                            {S - 12100, S - 20000, S + 20000, S - 20000}}};
        int32_t ya[512];
        int na;
        wm_refine_stats sa = {0, 0, 0, 0};
        const int differ = shared_side(&ra, &rb, S, &sh, ya, &na, &sa);
        TAP_OK(na > 0 && S - ya[na - 1] <= 86,
               "a shore past a corner: the corner's piece %d units",
               na > 0 ? (int)(S - ya[na - 1]) : -1);
        TAP_EQ(differ, 0, "a shore past a corner: both blocks cut it alike");
        TAP_EQ(sa.left, 0, "a shore past a corner: no sharp triangle left");
        wm_rings_free(&ra);
        wm_rings_free(&rb);
    }
    /* a shore cutting the block corner (S, S) off 60 units below it on the
     * side x = S and 116 units left of it on the side y = S: the water
     * along x = S ends 60 units from the corner, with land up to it. With
     * the blocks' water along the side (wm_side_ends, the same in both),
     * the piece at that end is graded down to twice that (the corner is
     * the nearest feature of the block square, as the next water is for a
     * notch), both blocks cut the side alike and no triangle is left
     * sharp; without, the end piece stays 8 pixels long beside the shore's
     * edge of 131 units (2 sharp triangles; 7 in one block of the
     * synthetic L1, seed 7, at 2 m pixels and 512 m blocks) */
    {
        const int S = 51200;
        const int a[] = {S - 20000, S - 20000, S, S - 20000, S,
                         S - 60,    S - 116,   S, S - 20000, S};
        const int b[] = {0,     S - 20000, 20000, S - 20000,
                         20000, S - 10405, 0,     S - 60};
        wm_rings ra = ring_of(a, 5), rb = ring_of(b, 4);
        const shores sh = {2,
                           {{S + 20000, S - 10405, S - 2049, S + 1000},
                            {S - 20000, S - 20000, S + 20000, S - 20000}}};
        int32_t ya[512];
        int na = 0, differ = 0;
        size_t left[2] = {0, 0};
        const int fail =
            !with_side_ends(&ra, &rb, S, &sh, ya, &na, &differ, left) ||
            na == 0;
        const int32_t end = fail ? 0 : S - 60 - ya[na - 1];
        TAP_EQ(fail, 0, "a corner cut off: refined in both blocks");
        TAP_EQ(differ, 0, "a corner cut off: both blocks cut it alike");
        TAP_OK(end > 0 && end <= 120,
               "a corner cut off: the end piece %d units long", (int)end);
        TAP_OK(left[1] == 0 && left[0] > 0,
               "a corner cut off: %zu sharp triangles left, %zu without the "
               "water along the side",
               left[1], left[0]);
        wm_rings_free(&ra);
        wm_rings_free(&rb);
    }
    /* a shore leaving a side piece that may not be split (no room
     * callback: not graded) with its first vertex near the crossing: the
     * triangle on the piece has 17.6 degrees, and its circumcentre lies
     * inside the piece's diametral circle, where it would make one of 5
     * degrees; it is not taken */
    {
        const int S = 51200;
        const int a[] = {S, 10000, S, 13375, S - 5000, 13375, S - 1000, 10220};
        wm_rings ra = ring_of(a, 4);
        const wm_refine_opts o = {20, 0, S, 0, 0, NULL, NULL, NULL, WM_Q};
        const result res = run(&ra, &o);
        TAP_OK(res.ntris > 0 && res.sharpest > 17.5,
               "a circumcentre by a kept side piece: sharpest angle %.1f",
               res.sharpest);
        TAP_OK(res.st.at_side == res.below && res.below > 0 &&
                   res.st.left >= res.st.at_side,
               "a circumcentre by a kept side piece: %zu sharp triangles "
               "counted at the side, of %zu",
               res.st.at_side, res.below);
        wm_rings_free(&ra);
    }
    /* the tip of a land wedge 20 units off the side x = S, 900 units from
     * where the shore leaves it, inside the piece that ends the side edge
     * (8 pixels at most): the room there falls where it should rise from
     * the end, so that piece is graded too, and no sharp triangle is left
     * (1 when the end piece stays whole) */
    {
        const int S = 51200;
        const int a[] = {S - 20000, 10000,     S,         10000,     S,
                         30000,     S - 20000, 30000,     S - 20000, 11000,
                         S - 20,    10900,     S - 20000, 10800};
        wm_rings ra = ring_of(a, 7);
        const shores sh = {3,
                           {{S - 20000, 10000, S + 20000, 10000},
                            {S - 20000, 11000, S - 20, 10900},
                            {S - 20, 10900, S - 20000, 10800}}};
        const wm_refine_opts o = {20,          0,    S,   0, 0, room_of_shores,
                                  (void *)&sh, NULL, WM_Q};
        const result res = run(&ra, &o);
        TAP_OK(res.ntris > 0 && res.st.left == 0,
               "a land tip by an end piece: %zu sharp triangles left",
               res.st.left);
        wm_rings_free(&ra);
    }
    /* a block wholly inside a lake: whatever the room, its sides are cut
     * into pieces of at most 256 pixels (refinement took points inside
     * the diametral circles of longer ones, which it cannot cure) */
    {
        const int S = 2048 * WM_Q;
        const int a[] = {0, 0, S, 0, S, S, 0, S};
        wm_rings ra = ring_of(a, 4);
        const shores sh = {1, {{-1e7, -1e7, -1e7 + 1, -1e7}}};
        const wm_refine_opts o = {20,          0,    S,   0, 0, room_of_shores,
                                  (void *)&sh, NULL, WM_Q};
        int32_t y[512];
        wm_refine_stats st = {0, 0, 0, 0};
        const int n = side_points(&ra, &o, S, y, 510, &st);
        int32_t longest = 0, prev = 0;
        for (int i = 0; i <= n && n < 510; i++)
        {
            const int32_t cur = i < n ? y[i] : S;
            longest = cur - prev > longest ? cur - prev : longest;
            prev = cur;
        }
        TAP_OK(n > 0 && n < 510 && longest <= 256 * WM_Q,
               "a block inside a lake: %d side points, longest piece %d "
               "units",
               n, (int)longest);
        wm_rings_free(&ra);
    }
    /* invalid input is the CDT's error */
    {
        wm_rings r;
        memset(&r, 0, sizeof r);
        static const int cw[] = {0, 0, 0, 100, 100, 0};
        ring(&r, cw, 3);
        wm_refine_opts o = {20, 0, 1 << 20, 0, 0, NULL, NULL, NULL, 0};
        uint32_t *tris = NULL;
        wm_pt *extra = NULL;
        size_t nt = 0, nx = 0;
        const wm_status rc = wm_refine_triangulate(
            r.pts, r.start, 1, &o, &tris, &nt, &extra, &nx, NULL, NULL);
        TAP_OK(rc == WM_ERR_INVALID && !tris && !extra,
               "a clockwise outer ring is refused");
        wm_rings_free(&r);
    }
    return TAP_DONE();
}
