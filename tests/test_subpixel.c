/* test_subpixel.c - features narrower than a pixel, found from the inputs
 * where the samples cannot tell (probe.c, subpixel.c, contour.c). */
#include "contour.h"
#include "corners.h"
#include "field.h"
#include "probe.h"
#include "ring_check.h"
#include "scene_util.h"
#include "subpixel.h"
#include "tap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Rings of block (bx, by) of scene s (n x n cells), with the exact
 * search. */
static wm_status extract_block_at(const wm_scene *s, int bx, int by,
                                  wm_rings *r)
{
    wm_field f;
    wm_probe p;
    wm_status st = wm_field_compute(s, (int64_t)bx * s->n, (int64_t)by * s->n,
                                    s->n + 1, s->n + 1, NULL, &f, NULL);
    if (st != WM_OK)
        return st;
    st = wm_probe_init(&p, s, bx, by);
    if (st == WM_OK)
        st = wm_contour_extract_probed(&f, &p, r, NULL);
    wm_probe_free(&p);
    wm_field_free(&f);
    return st;
}

/* Rings of block (bx, 0) of scene s, with the exact search. */
static wm_status extract_block(const wm_scene *s, int bx, wm_rings *r)
{
    return extract_block_at(s, bx, 0, r);
}

/* Rings of block (0, 0) of scene s (n x n cells): without (probe == 0) or
 * with the exact search. */
static wm_status extract(const wm_scene *s, int probe, wm_rings *r)
{
    if (probe)
        return extract_block(s, 0, r);
    wm_field f;
    wm_status st =
        wm_field_compute(s, 0, 0, s->n + 1, s->n + 1, NULL, &f, NULL);
    if (st != WM_OK)
        return st;
    st = wm_contour_extract_probed(&f, NULL, r, NULL);
    wm_field_free(&f);
    return st;
}

static size_t count_sign(const wm_rings *r, int positive)
{
    size_t k = 0;
    for (size_t i = 0; i < r->nrings; i++)
        k += (wm_ring_area2(r->pts + r->start[i], wm_rings_len(r, i)) > 0) ==
             positive;
    return k;
}

/* Whether some ring vertex lies within d lattice units of (x, y). */
static int vertex_near(const wm_rings *r, double x, double y, double d)
{
    for (size_t k = 0; k < r->npts; k++)
        if (hypot(r->pts[k].x - x, r->pts[k].y - y) <= d)
            return 1;
    return 0;
}

/* Checks that both blocks sharing the side x = 32 px of scene s (blocks
 * of 32 px) find two crossings, at offsets lo and hi, on its segment from
 * y = 19 to 20 px, water at both ends; frees s. */
static void side_gap(wm_scene *s, int32_t lo, int32_t hi, const char *what)
{
    for (int bx = 0; bx < 2; bx++)
    {
        wm_probe p;
        TAP_EQ(wm_probe_init(&p, s, bx, 0), WM_OK, "probe of block (%d, 0)",
               bx);
        int32_t off[WM_Q];
        int cls1 = 1;
        const int k =
            wm_probe_crossings(&p, (wm_pt){(1 - bx) * 32 * WM_Q, 19 * WM_Q}, 1,
                               WM_Q, 1, &cls1, off, WM_Q);
        TAP_OK(k == 2 && off[0] == lo && off[1] == hi,
               "block (%d, 0): %s (%d, %d), got %d crossings %d %d", bx, what,
               lo, hi, k, k > 0 ? off[0] : -1, k > 1 ? off[1] : -1);
        wm_probe_free(&p);
    }
    wm_scene_free(s);
}

/* A block side along a lake's edge (lake A left of x = 32, blocks of 32
 * px), with land of the block across touching it between two lakes there
 * (C below y = 19.5, B above y = 20): the side's segment from y = 19 to 20
 * is water only where the points a unit across are both, so the land
 * stays a notch reaching the side, found alike by both blocks. */
static void block_side(void)
{
    wm_scene s;
    su_init(&s, 32);
    const double a[] = {20, 4, 32, 4, 32, 28, 20, 28};
    const double b[] = {32, 20, 44, 20, 44, 28, 32, 28};
    const double c[] = {32, 4, 44, 4, 44, 19.5, 32, 19.5};
    const int four[] = {4};
    su_lake(&s, a, four, 1);
    su_lake(&s, b, four, 1);
    su_lake(&s, c, four, 1);
    su_finish(&s);
    side_gap(&s, 128, WM_Q - 1,
             "the side's water ends at the gap and meets B a unit before its "
             "edge");
}

/* A river's bank along a block side (river V right of x = 32, blocks of
 * 32 px), a lake left of it below y = 19 and a river D across the side
 * above y = 20: the side between them is water only on V's bank, a line,
 * with land a unit across in block 0, so both blocks find the land gap's
 * two crossings there (grid seed 142216 at 3 m: a lake and a river joined
 * along a bank on the side). */
static void bank_on_side(void)
{
    wm_scene s;
    su_init(&s, 32);
    const double v[] = {33, -5, 33, 40}, d[] = {10, 20.5, 40, 20.5};
    const double lake[] = {20, 4, 32, 4, 32, 19, 20, 19};
    const int four = 4;
    su_river(&s, v, 2, 1.0);
    su_river(&s, d, 2, 0.5);
    su_lake(&s, lake, &four, 1);
    su_finish(&s);
    side_gap(&s, 1, WM_Q - 1, "land between the lake and D on the side");
}

/* A river's round join whose bank crosses the block side x = 32 px by
 * 0.3 lattice unit between two samples (its vertex 456 units left of the
 * side, at y = 19.5 px, its radius 456.3 units), as rounding the inputs
 * to the lattice leaves a bank drawn a fraction of a unit short of a side
 * (Andorra with rivers 25 m wide at 7 m pixels and 1792 m blocks: the
 * block across kept a ring a unit wide, a speck). The side's segment from
 * y = 19 to 20 px is land in both blocks, the block across keeps no ring,
 * and this block's river stays one ring. */
static void bulge_across_side(void)
{
    wm_scene s;
    su_init(&s, 32);
    const double c = 32.0 - 456.0 / WM_Q; /* on the lattice */
    const double v[] = {c - 10, 9.5, c, 19.5, c - 10, 29.5};
    su_river(&s, v, 3, 456.3 / WM_Q);
    su_finish(&s);
    for (int bx = 0; bx < 2; bx++)
    {
        wm_probe p;
        TAP_EQ(wm_probe_init(&p, &s, bx, 0), WM_OK, "probe of block (%d, 0)",
               bx);
        int32_t off[WM_Q];
        int cls1 = 0;
        const int k =
            wm_probe_crossings(&p, (wm_pt){(1 - bx) * 32 * WM_Q, 19 * WM_Q}, 1,
                               WM_Q, 0, &cls1, off, WM_Q);
        TAP_EQ(k, 0,
               "block (%d, 0): a bank 0.3 unit across the side leaves it land",
               bx);
        wm_probe_free(&p);
    }
    wm_rings r0 = {0}, r1 = {0};
    TAP_EQ(extract_block(&s, 0, &r0), WM_OK, "the river's block extracts");
    TAP_EQ(extract_block(&s, 1, &r1), WM_OK, "the block across extracts");
    TAP_EQ(r0.nrings, 1, "the river is one ring");
    TAP_EQ(r1.nrings, 0, "the block across keeps no ring a unit wide");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);
}

/* Small lake rings in one cell that touch or nest: two lakes of 10 x 10
 * units sharing an edge, two touching at a vertex, a lake in another's
 * hole. Their rings as drawn are not the union's boundary; taken so, they
 * failed the block ("a chain ends inside the block", "ring nesting does
 * not alternate": held-out round 24). They are divided as before. */
static void lone_rings_touching(void)
{
    const double u = 1.0 / WM_Q, x = 10 + 100 * u, y = 10 + 100 * u;
    for (int c = 0; c < 3; c++)
    {
        wm_scene s;
        su_init(&s, 32);
        if (c < 2)
        {
            const double a[] = {x,          y,          x + 10 * u, y,
                                x + 10 * u, y + 10 * u, x,          y + 10 * u};
            const double d = c ? 10 * u : 0; /* the second: at a vertex */
            const double b[] = {x + 10 * u, y + d,         x + 20 * u,
                                y + d,      x + 20 * u,    y + d + 10 * u,
                                x + 10 * u, y + d + 10 * u};
            const int four = 4;
            su_lake(&s, a, &four, 1);
            su_lake(&s, b, &four, 1);
        }
        else
        {
            const double ring_hole[] = {
                x,          y,          x + 30 * u, y,
                x + 30 * u, y + 30 * u, x,          y + 30 * u,
                x + 5 * u,  y + 5 * u,  x + 5 * u,  y + 25 * u,
                x + 25 * u, y + 25 * u, x + 25 * u, y + 5 * u};
            const int counts[] = {4, 4};
            su_lake(&s, ring_hole, counts, 2);
            const double in[] = {x + 10 * u, y + 10 * u, x + 20 * u,
                                 y + 10 * u, x + 20 * u, y + 20 * u,
                                 x + 10 * u, y + 20 * u};
            const int four = 4;
            su_lake(&s, in, &four, 1);
        }
        su_finish(&s);
        wm_rings r = {0};
        TAP_EQ(extract_block(&s, 0, &r), WM_OK,
               "touching or nested rings %d: the block extracts", c);
        TAP_EQ(ring_meetings(&r), 0,
               "touching or nested rings %d: simple and disjoint", c);
        wm_rings_free(&r);
        wm_scene_free(&s);
    }
}

/* Four rectangular lakes, one in each block around the corner (32, 32)
 * px, their corners at (1, 1), (0, 0), (-1, -1) and (1, -1) units from
 * it: the corner sample lies on a lake's corner, and the four points a
 * unit diagonally from it are water, so it stayed water; each block kept
 * a triangle of half a square unit at its corner, and the two lakes whose
 * edges lie a unit apart across a block line a strip a unit wide along it
 * (held-out round 23). Each block holds its lake alone. */
static void four_lakes_at_a_corner(void)
{
    static const int corner[4][2] = {{1, 1}, {0, 0}, {-1, -1}, {1, -1}};
    static const int dir[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
    wm_scene s;
    su_init(&s, 32);
    for (int k = 0; k < 4; k++)
    {
        const double x0 = 32 + corner[k][0] / (double)WM_Q;
        const double y0 = 32 + corner[k][1] / (double)WM_Q;
        const double x1 = x0 + 10 * dir[k][0], y1 = y0 + 8 * dir[k][1];
        const double v[] = {x0, y0, x1, y0, x1, y1, x0, y1};
        const int count = 4;
        su_lake(&s, v, &count, 1);
    }
    su_finish(&s);
    for (int b = 0; b < 4; b++)
    {
        wm_rings r = {0};
        TAP_EQ(extract_block_at(&s, b & 1, b >> 1, &r), WM_OK,
               "block (%d, %d) extracts", b & 1, b >> 1);
        TAP_EQ(r.nrings, 1, "block (%d, %d) holds its lake alone", b & 1,
               b >> 1);
        wm_rings_free(&r);
    }
    wm_scene_free(&s);
}

/* An island of 1.5 square units (a triangle 2 x 2 units) in a lake, and
 * a lake as small on land: each lies inside one cell, seeded; dividing the
 * cell rounded the crossings of a segment through the island a unit
 * inward, and the ring left, a unit thinner, was dropped as a rounding
 * remnant (held-out lakes seed 193000 at 2.5 m: 16.8 px). A rectangle of
 * the subdivision that holds such a ring whole, and nothing else, takes it
 * as it is. */
static void lone_rings_kept(void)
{
    wm_scene s;
    su_init(&s, 32);
    const double u = 1.0 / WM_Q;
    const double lake[] = {2,           2,           20,          2,
                           20,          20,          2,           20,
                           10 + 10 * u, 10 + 20 * u, 10 + 12 * u, 10 + 21 * u,
                           10 + 11 * u, 10 + 22 * u};
    const int counts[] = {4, 3};
    su_lake(&s, lake, counts, 2);
    const double pond[] = {25 + 7 * u, 25 + 3 * u, 25 + 9 * u,
                           25 + 4 * u, 25 + 8 * u, 25 + 5 * u};
    const int three = 3;
    su_lake(&s, pond, &three, 1);
    su_finish(&s);
    wm_rings r = {0};
    TAP_EQ(extract_block(&s, 0, &r), WM_OK, "the block extracts");
    TAP_EQ(r.nrings, 3, "the lake, its island and the pond");
    TAP_EQ(ring_meetings(&r), 0, "the rings are simple and disjoint");
    int island = 0, pond_ring = 0;
    for (size_t i = 0; i < r.nrings; i++)
    {
        const size_t n = wm_rings_len(&r, i);
        const wm_i128 a2 = wm_ring_area2(r.pts + r.start[i], n);
        island += n == 3 && a2 == -3; /* clockwise: land inside */
        pond_ring += n == 3 && a2 == 3;
    }
    TAP_EQ(island, 1, "the island is the input's triangle, a hole");
    TAP_EQ(pond_ring, 1, "the pond is the input's triangle, water");
    wm_rings_free(&r);
    wm_scene_free(&s);
}

/* A lake's edge along the side of blocks 0 and 1 (x = 32 px), a river in
 * block 1 whose bank runs 0.9 unit off the side: the side's samples are
 * water (the points a unit across are), and the land between the side and
 * the bank, less than a unit wide, was rounded to a unit with a unit of the
 * lake's water before it, which block 1 kept as a ring a unit wide along
 * its side (held-out mixed seed 196131 at 4 m: a speck at a corner). */
static void shore_on_side(void)
{
    wm_scene s;
    su_init(&s, 32);
    const double lake[] = {20, 5, 32, 5, 32, 25, 20, 25};
    const int count = 4;
    su_lake(&s, lake, &count, 1);
    const double river[] = {34, 2, 34, 28};
    su_river(&s, river, 2, (2 * WM_Q - 0.9) / WM_Q);
    su_finish(&s);
    wm_rings r = {0};
    TAP_EQ(extract_block(&s, 1, &r), WM_OK, "the river's block extracts");
    TAP_EQ(r.nrings, 1, "the river is one ring, the lake none in its block");
    wm_rings_free(&r);
    wm_scene_free(&s);
}

/* Three lakes touching pairwise at a vertex each, around a land sliver
 * 0.2 unit thick, a land wedge's tip at one of those vertices: a pinch
 * point where four pieces meet. A leaf there kept six crossings; its
 * pairing by the class of its centre left a bump of land a unit deep
 * under the other pairing's chord, the rings crossed, and the block failed
 * ("ring nesting does not alternate"; held-out lakes seed 198031 at
 * 0.5 m). The other pairing draws apart. */
static void pinch_of_three_lakes(void)
{
    static const double L0[] = {1918, 16326, 588,  15709,
                                2722, 11107, 4053, 11724};
    static const double L1[] = {1349, 14066, 709,  13769,
                                2082, 10810, 2722, 11107};
    static const double L2[] = {4053, 11724, 2082, 10810, 3954, 9355};
    const double *lake[3] = {L0, L1, L2};
    const int count[3] = {4, 4, 3};
    wm_scene s;
    su_init(&s, 128);
    for (int k = 0; k < 3; k++)
    {
        double v[8];
        for (int i = 0; i < 2 * count[k]; i++)
            v[i] = lake[k][i] / WM_Q; /* lattice units to pixels, exact */
        su_lake(&s, v, &count[k], 1);
    }
    su_finish(&s);
    wm_rings r = {0};
    TAP_EQ(extract_block(&s, 0, &r), WM_OK, "the pinch point's block extracts");
    TAP_EQ(ring_meetings(&r), 0, "its rings are simple and disjoint");
    wm_rings_free(&r);
    wm_scene_free(&s);
}

/* A river 5 px wide drawn along an arc of radius 40 px with a vertex
 * every quarter pixel: the union's corners are the inner bends' (one per
 * vertex), and the candidates include where each bank's side meets the
 * outer round join (a tangent). The offset lines of segments a few apart cross
 * too, and an end circle crosses the next segment's sides, all inside the
 * capsules: not corners (4.6 M of them made a real river network drawn that
 * densely 170 times slower). */
static void dense_bend(void)
{
    wm_scene s;
    su_init(&s, 128);
    enum
    {
        NV = 201
    };
    static double xy[2 * NV];
    for (int i = 0; i < NV; i++)
    {
        const double t = 0.25 * i / 40.0; /* a quarter pixel of arc */
        xy[2 * i] = 64 + 40 * cos(t);
        xy[2 * i + 1] = 20 + 40 * sin(t);
    }
    su_river(&s, xy, NV, 2.5);
    su_finish(&s);
    wm_field f;
    wm_probe p;
    TAP_EQ(wm_field_compute(&s, 0, 0, s.n + 1, s.n + 1, NULL, &f, NULL), WM_OK,
           "field");
    TAP_EQ(wm_probe_init(&p, &s, 0, 0), WM_OK, "probe");
    TAP_EQ(wm_corners_find(&p, &f, NULL), WM_OK, "corners");
    size_t apart = 0; /* corners of segments sharing no end */
    for (size_t i = 0; i < p.ncorner; i++)
        apart += !p.corner_joint[i];
    TAP_EQ(apart, 0, "no crossing of segments apart is a corner");
    TAP_OK(p.ncorner <= 3 * NV,
           "about a corner per bend on each bank: %zu for %d vertices (5681 "
           "before)",
           p.ncorner, NV);
    wm_probe_free(&p);
    wm_field_free(&f);
    wm_rings r = {0};
    TAP_EQ(extract(&s, 1, &r), WM_OK, "extract with the exact search");
    TAP_EQ(r.nrings, 1, "one ring");
    TAP_EQ(ring_meetings(&r), 0, "rings simple and disjoint");
    wm_rings_free(&r);
    wm_scene_free(&s);
}

/* The corners wm_corners_find gives for block (0, 0) of s, into *c (the
 * caller frees); how many. */
static size_t corners_of(const wm_scene *s, wm_pt **c)
{
    wm_field f;
    wm_probe p;
    *c = NULL;
    if (wm_field_compute(s, 0, 0, s->n + 1, s->n + 1, NULL, &f, NULL) != WM_OK)
        return 0;
    size_t n = 0;
    if (wm_probe_init(&p, s, 0, 0) == WM_OK &&
        wm_corners_find(&p, &f, NULL) == WM_OK)
    {
        n = p.ncorner;
        *c = malloc((n + 1) * sizeof **c);
        if (*c)
            memcpy(*c, p.corner, n * sizeof **c);
    }
    wm_probe_free(&p);
    wm_field_free(&f);
    return n;
}

/* A stream 0.33 px wide along y = 100.87 (banks at 100.705 and 101.035)
 * between the sample rows 100 and 101: the row above is water by the
 * stream's near bank only (0.035 px), so the interpolated crossing of the
 * edges from row 100 sat 0.25 px short of the far bank, within the loose
 * bound: the stream came out 0.08 px wide. Such a stream (y = 36.87) with
 * a second one 0.3 px wide above it, rising to y = 37.28 over 8 px, leaves
 * a land island 3.9 x 0.1 px between them, hidden on the edges from row 37
 * (water) to 38 (land): three crossings, the middle ones a river crossing
 * them twice (river_may_hide; held-out round 26, at 0.3 m pixels). */
static void thin_streams_between_rows(void)
{
    wm_scene s;
    wm_rings r = {0};
    su_init(&s, 256);
    const double a[] = {20, 100.87, 230, 100.87};
    su_river(&s, a, 2, 0.165);
    su_finish(&s);
    TAP_EQ(extract(&s, 1, &r), WM_OK, "the stream's block extracts");
    TAP_OK(vertex_near(&r, 150 * WM_Q, 100.705 * WM_Q, 1.0) &&
               vertex_near(&r, 150 * WM_Q, 101.035 * WM_Q, 1.0),
           "both banks exactly on the sample column x = 150");
    TAP_EQ(ring_meetings(&r), 0, "rings simple and disjoint");
    wm_rings_free(&r);
    wm_scene_free(&s);

    su_init(&s, 64);
    const double a2[] = {20.67, 36.8667, 46.67, 36.8667};
    const double b[] = {25.67, 36.8667, 33.67, 37.2833, 41.67, 36.8667};
    su_river(&s, a2, 2, 0.165);
    su_river(&s, b, 3, 0.15);
    su_finish(&s);
    TAP_EQ(extract(&s, 1, &r), WM_OK, "the two streams' block extracts");
    TAP_EQ(count_sign(&r, 1), 1, "one water ring");
    TAP_EQ(count_sign(&r, 0), 1, "the island between the streams kept");
    TAP_EQ(ring_meetings(&r), 0, "rings simple and disjoint");
    wm_rings_free(&r);
    wm_scene_free(&s);
}

/* Edges the exact search listed in block (0, 0) of s. */
static size_t listed_edges(const wm_scene *s)
{
    wm_field f;
    wm_probe p;
    wm_hidden h;
    size_t n = (size_t)-1;
    if (wm_field_compute(s, 0, 0, s->n + 1, s->n + 1, NULL, &f, NULL) != WM_OK)
        return n;
    if (wm_probe_init(&p, s, 0, 0) == WM_OK &&
        wm_hidden_find(&f, &p, &h, NULL) == WM_OK)
    {
        n = h.nedge;
        wm_hidden_free(&h);
    }
    wm_probe_free(&p);
    wm_field_free(&f);
    return n;
}

/* An island 0.1 px high in a lake, 0.3 px above the sample row y = 40,
 * the shore 0.5 px above it: the edges up from the row (water, 0.3 px
 * from the island) to the shore's land (0.5 px) hold three crossings, the
 * island's two sides and the shore, where marching squares draws one; the
 * values sum past the loose bound and no river is near. The lake's edges
 * meet those edges at two places (lake_twice): searched, the island kept
 * (joined to the shore before, 9878593). A twin of the lake meets every
 * edge where the lake does and adds no search. */
static void island_near_shore(void)
{
    wm_scene s;
    wm_rings r = {0};
    const double lake[] = {2,    10,   60,   10,   60,   40.5, 2,    40.5,
                           10.3, 40.3, 30.7, 40.3, 30.7, 40.4, 10.3, 40.4};
    const int counts[] = {4, 4};
    su_init(&s, 64);
    su_lake(&s, lake, counts, 2);
    su_finish(&s);
    TAP_EQ(extract(&s, 1, &r), WM_OK, "the lake's block extracts");
    TAP_EQ(count_sign(&r, 1), 1, "one water ring");
    TAP_EQ(count_sign(&r, 0), 1, "the island kept");
    TAP_OK(vertex_near(&r, 20 * WM_Q, 40.3 * WM_Q, 1.0) &&
               vertex_near(&r, 20 * WM_Q, 40.4 * WM_Q, 1.0),
           "both its sides exactly on the sample column x = 20");
    TAP_EQ(ring_meetings(&r), 0, "rings simple and disjoint");
    wm_rings_free(&r);
    wm_scene_free(&s);

    const double shore[] = {2, 10, 60, 10, 60, 40.5, 2, 40.5};
    su_init(&s, 64);
    su_lake(&s, shore, counts, 1);
    su_finish(&s);
    const size_t one = listed_edges(&s);
    wm_scene_free(&s);
    su_init(&s, 64);
    su_lake(&s, shore, counts, 1);
    su_lake(&s, shore, counts, 1);
    su_finish(&s);
    TAP_EQ(listed_edges(&s), one, "a twin lake adds no search (%zu)", one);
    wm_scene_free(&s);
}

static int count_segment(void *user, wm_pt a, wm_pt b)
{
    (void)a;
    (void)b;
    (*(size_t *)user)++;
    return 1;
}

/* The subdivision of the ambiguous cells stops when asked (a dense shore
 * gives a block thousands of them, each subdivided deep: a saw-toothed lake
 * of 60,000 vertices ran on for a minute after SIGINT). */
static void hidden_cells_cancel(void)
{
    wm_scene s;
    su_init(&s, 256);
    const double a[] = {20, 100.87, 230, 100.87};
    const double b[] = {120, 100.87, 150, 101.3, 180, 100.87};
    su_river(&s, a, 2, 0.165);
    su_river(&s, b, 3, 0.15);
    su_finish(&s);
    wm_field f;
    wm_probe p;
    wm_hidden h;
    int cancel = 0;
    const wm_ctx ctx = {NULL, NULL, &cancel};
    TAP_EQ(wm_field_compute(&s, 0, 0, s.n + 1, s.n + 1, NULL, &f, NULL), WM_OK,
           "field");
    TAP_EQ(wm_probe_init(&p, &s, 0, 0), WM_OK, "probe");
    TAP_EQ(wm_hidden_find(&f, &p, &h, &ctx), WM_OK, "hidden crossings");
    TAP_OK(h.ncell > 0, "ambiguous cells: %zu", h.ncell);
    size_t nseg = 0;
    TAP_EQ(wm_hidden_cells(&f, &p, &h, count_segment, &nseg, &ctx), WM_OK,
           "subdivided");
    TAP_OK(nseg > 0, "segments: %zu", nseg);
    cancel = 1;
    nseg = 0;
    TAP_EQ(wm_hidden_cells(&f, &p, &h, count_segment, &nseg, &ctx),
           WM_ERR_CANCELLED, "asked to stop: cancelled");
    TAP_EQ(nseg, 0, "before any cell");
    wm_hidden_free(&h);
    wm_probe_free(&p);
    wm_field_free(&f);
    wm_scene_free(&s);
}

/* Whether a corner of c lies within 2 units of (x, y) (pixels). */
static int has_corner(const wm_pt *c, size_t n, double x, double y)
{
    for (size_t i = 0; i < n; i++)
        if (fabs(c[i].x - x * WM_Q) <= 2 && fabs(c[i].y - y * WM_Q) <= 2)
            return 1;
    return 0;
}

/* Two rivers 4 px wide drawn with a vertex every quarter pixel cross at
 * (60.1, 60.1); a third, 10 px wide, covers their banks' crossing
 * (62.1, 62.1) 0.7 px deep (within the field's 0.75 px of the boundary),
 * away from their vertices (where each bank touches its own end circles,
 * joint crossings, which stay). That crossing
 * is no corner of the union; the capsule burying it is found through the
 * probe's index (the two segments' ids are 320 apart). Read in either
 * order, a line of short segments and one long segment meeting end to end
 * give the same corners (their shared end circle is short only where both
 * are). */
static void buried_crossings(void)
{
    enum
    {
        NL = 321
    };
    static double h[2 * NL], v[2 * NL];
    for (int i = 0; i < NL; i++)
    {
        h[2 * i] = v[2 * i + 1] = 20 + 0.25 * i;
        h[2 * i + 1] = v[2 * i] = 60.1;
    }
    const double w[] = {55, 66.4, 70, 66.4};
    wm_scene s;
    su_init(&s, 128);
    su_river(&s, h, NL, 2.0);
    su_river(&s, v, NL, 2.0);
    su_river(&s, w, 2, 5.0);
    su_finish(&s);
    wm_pt *c;
    size_t n = corners_of(&s, &c);
    TAP_OK(has_corner(c, n, 58.1, 58.1),
           "the banks' crossing (58.1, 58.1) a corner");
    TAP_OK(!has_corner(c, n, 62.1, 62.1),
           "the banks' crossing (62.1, 62.1) under the third river is none");
    free(c);
    wm_scene_free(&s);

    /* a dense arc ending where a long segment starts, read both ways */
    enum
    {
        NA = 81
    };
    static double arc[2 * NA];
    for (int i = 0; i < NA; i++)
    {
        const double t = 0.25 * i / 30.0;
        arc[2 * i] = 40 + 30 * cos(t);
        arc[2 * i + 1] = 20 + 30 * sin(t);
    }
    const double tail[] = {arc[2 * NA - 2], arc[2 * NA - 1], 20, 90};
    wm_pt *c2;
    su_init(&s, 128);
    su_river(&s, arc, NA, 2.5);
    su_river(&s, tail, 2, 2.5);
    su_finish(&s);
    n = corners_of(&s, &c);
    wm_scene_free(&s);
    su_init(&s, 128);
    su_river(&s, tail, 2, 2.5);
    su_river(&s, arc, NA, 2.5);
    su_finish(&s);
    const size_t n2 = corners_of(&s, &c2);
    wm_scene_free(&s);
    TAP_OK(n > 0 && n == n2 && c && c2 && !memcmp(c, c2, n * sizeof *c),
           "the same corners in either order (%zu, %zu)", n, n2);
    free(c);
    free(c2);
}

int main(void)
{
    /* Two rivers 10 px wide, their banks 0.2 px apart between two sample
     * rows (y = 100.3 and 100.5): every sample beside the strip of land is
     * water. */
    wm_scene s;
    su_init(&s, 256);
    const double a[] = {20, 95.3, 200, 95.3}, b[] = {20, 105.5, 200, 105.5};
    su_river(&s, a, 2, 5.0);
    su_river(&s, b, 2, 5.0);
    su_finish(&s);

    /* the exact search of one edge across the strip */
    wm_probe p;
    TAP_EQ(wm_probe_init(&p, &s, 0, 0), WM_OK, "probe");
    int32_t off[WM_Q];
    int cls1 = 1;
    const int k = wm_probe_crossings(&p, (wm_pt){100 * WM_Q, 100 * WM_Q}, 1,
                                     WM_Q, 1, &cls1, off, WM_Q);
    TAP_EQ(k, 2, "two crossings on the edge across the strip");
    /* the banks on the lattice: su_river truncates 95.3 px to 24396 units */
    TAP_OK(k == 2 && off[0] == 76 && off[1] == 128,
           "at the banks: 0.3 and 0.5 px (76 and 128 units), got %d %d",
           k > 0 ? off[0] : -1, k > 1 ? off[1] : -1);
    /* the edge beside it, inside river A only: none */
    cls1 = 1;
    TAP_EQ(wm_probe_crossings(&p, (wm_pt){100 * WM_Q, 99 * WM_Q}, 1, WM_Q, 1,
                              &cls1, off, WM_Q),
           0, "no crossing inside one river");
    /* a free end class is found: from land into river A's bank */
    cls1 = -1;
    TAP_EQ(wm_probe_crossings(&p, (wm_pt){100 * WM_Q, 90 * WM_Q}, 1, WM_Q, 0,
                              &cls1, off, WM_Q),
           1, "one crossing into the river");
    TAP_EQ(cls1, 1, "the far end's class is water");
    TAP_EQ(off[0], 76, "at the bank, 90.3 px");
    wm_probe_free(&p);

    wm_rings r0 = {0}, r1 = {0};
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_EQ(count_sign(&r0, 1), 1, "samples alone: one merged water ring");
    TAP_EQ(count_sign(&r1, 1), 2, "exact search: the two rivers apart");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    TAP_OK(vertex_near(&r1, 100.5 * WM_Q, 100.3 * WM_Q, 1.0) &&
               vertex_near(&r1, 100.5 * WM_Q, 100.5 * WM_Q, 1.0),
           "vertices on both sides of the strip, exactly");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);

    /* A pond of 0.3 px inside one cell in open land, and an island of
     * 0.4 px inside one cell of a lake: the samples see neither; the
     * seeded cells find both. */
    su_init(&s, 64);
    const double pond[] = {10.3, 10.3, 10.6, 10.3, 10.45, 10.6};
    const double lake[] = {20,   20,   40,   20,   40,   40,   20,   40,
                           30.3, 30.3, 30.3, 30.7, 30.7, 30.7, 30.7, 30.3};
    const int npond = 3, nlake[] = {4, 4};
    su_lake(&s, pond, &npond, 1);
    su_lake(&s, lake, nlake, 2);
    su_finish(&s);
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_EQ(r0.nrings, 1, "samples alone: the lake only");
    TAP_EQ(count_sign(&r1, 1), 2, "exact search: the lake and the pond");
    TAP_EQ(count_sign(&r1, 0), 1, "exact search: the island");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    TAP_OK(vertex_near(&r1, 10.45 * WM_Q, 10.6 * WM_Q, 8.0),
           "the pond's apex within 1/32 px");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);

    /* A stream 0.72 px wide (x 99.30 .. 100.02) covering the sample column
     * x = 100 by 0.02 px: its far bank is 0.64 px from the interpolated
     * crossing of the edges from x = 99 (a loose edge): exact with the
     * search. */
    su_init(&s, 256);
    const double stream[] = {99.66, 20, 99.66, 200};
    su_river(&s, stream, 2, 0.36);
    su_finish(&s);
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_OK(!vertex_near(&r0, 99.30 * WM_Q, 100 * WM_Q, 0.1 * WM_Q),
           "samples alone: the far bank a fraction of a pixel off");
    TAP_OK(vertex_near(&r1, 99.30 * WM_Q, 100 * WM_Q, 1.0),
           "loose edge: the far bank exactly");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);

    /* A stream 0.1 px wide through the samples (100, 100) and (101, 101)
     * of a saddle cell, bending a quarter pixel off the cell's centre: the
     * centre is land, yet the stream is one piece. */
    su_init(&s, 256);
    const double bend[] = {80, 80, 100, 100, 100.8, 100.4, 101, 101, 120, 120};
    su_river(&s, bend, 5, 0.05);
    su_finish(&s);
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_OK(count_sign(&r0, 1) > 1, "samples alone: the stream dashed");
    TAP_EQ(count_sign(&r1, 1), 1, "saddle cell: the stream in one piece");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);

    /* A stream 0.3 px wide ending at x = 100.5 (its tip at 100.65): inside
     * the cell whose sample (100, 100) it covers; the tip is seeded. */
    su_init(&s, 256);
    const double ends[] = {50, 100.1, 100.5, 100.1};
    su_river(&s, ends, 2, 0.15);
    su_finish(&s);
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_OK(vertex_near(&r1, 100.65 * WM_Q, 100.1 * WM_Q, 8.0),
           "the stream's tip within 1/32 px");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r1);
    wm_scene_free(&s);

    /* An island of 0.4 px that three rivers enclose (y > 100.3, x > 100.3,
     * x + y < 201) inside a cell whose four samples are water: no single
     * input marks it; its corners seed the cell. */
    su_init(&s, 256);
    const double ra[] = {80, 97.3, 120, 97.3}, rb[] = {97.3, 80, 97.3, 120},
                 rc[] = {85, 120.243, 120.243, 85};
    su_river(&s, ra, 2, 3.0);
    su_river(&s, rb, 2, 3.0);
    su_river(&s, rc, 2, 3.0);
    su_finish(&s);
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_EQ(count_sign(&r0, 0), 0, "samples alone: no island");
    TAP_EQ(count_sign(&r1, 0), 1, "exact search: the island");
    TAP_OK(vertex_near(&r1, 100.3 * WM_Q, 100.3 * WM_Q, 4.0),
           "the island's corner within 1/64 px");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);
    /* A lake whose top edge runs along the sample row y = 60 and a river
     * whose bank runs 0.2 px above it: the samples on the edge are water
     * (distance 0), those above it in the river too. The land strip
     * between is found next to the edge's samples, though the ray rule
     * puts those samples outside the lake; along the edge itself nothing
     * is found (the lake's boundary is water). */
    su_init(&s, 128);
    const double rect[] = {40, 40, 80, 40, 80, 60, 40, 60};
    const int nrect = 4;
    const double bank[] = {20, 62.2, 100, 62.2};
    su_lake(&s, rect, &nrect, 1);
    su_river(&s, bank, 2, 2.0);
    su_finish(&s);
    TAP_EQ(wm_probe_init(&p, &s, 0, 0), WM_OK, "probe");
    cls1 = 1;
    const int kr = wm_probe_crossings(&p, (wm_pt){60 * WM_Q, 60 * WM_Q}, 1,
                                      WM_Q, 1, &cls1, off, WM_Q);
    TAP_OK(kr == 2 && off[0] == 1 && abs(off[1] - 51) <= 1,
           "from a sample on the lake's edge: land at once, then the bank "
           "at 0.2 px (got %d: %d %d)",
           kr, kr > 0 ? off[0] : -1, kr > 1 ? off[1] : -1);
    cls1 = 1;
    TAP_EQ(wm_probe_crossings(&p, (wm_pt){60 * WM_Q, 60 * WM_Q}, 0, WM_Q, 1,
                              &cls1, off, WM_Q),
           0, "along the lake's edge: water all the way");
    cls1 = 1;
    TAP_EQ(wm_probe_crossings(&p, (wm_pt){60 * WM_Q, 59 * WM_Q}, 1, WM_Q, 1,
                              &cls1, off, WM_Q),
           0, "from inside up to the edge: water all the way");
    wm_probe_free(&p);
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_EQ(count_sign(&r0, 1), 1, "samples alone: lake and river merged");
    TAP_EQ(count_sign(&r1, 1), 2, "exact search: the lake and the river apart");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    TAP_OK(vertex_near(&r1, 60 * WM_Q, 60 * WM_Q, 1.0) &&
               vertex_near(&r1, 80 * WM_Q, 60 * WM_Q, 1.0),
           "the lake's top edge kept, corner included");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);
    /* Two rivers 2 px wide whose banks lie on the sample rows y = 61 and
     * y = 62: every sample is water (the banks' at distance 0), the strip
     * of land between them is exactly one pixel. */
    su_init(&s, 128);
    const double low[] = {20, 60, 100, 60}, high[] = {20, 63, 100, 63};
    su_river(&s, low, 2, 1.0);
    su_river(&s, high, 2, 1.0);
    su_finish(&s);
    TAP_EQ(wm_probe_init(&p, &s, 0, 0), WM_OK, "probe");
    cls1 = 1;
    const int kb = wm_probe_crossings(&p, (wm_pt){50 * WM_Q, 61 * WM_Q}, 1,
                                      WM_Q, 1, &cls1, off, WM_Q);
    TAP_OK(kb == 2 && off[0] == 1 && off[1] == WM_Q - 1,
           "between banks through both samples: the whole pixel is land "
           "(got %d: %d %d)",
           kb, kb > 0 ? off[0] : -1, kb > 1 ? off[1] : -1);
    wm_probe_free(&p);
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_EQ(count_sign(&r1, 1), 2, "the two rivers apart");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r1);
    wm_scene_free(&s);
    /* An L-shaped lake whose inner corner is the sample (60, 60), and a
     * river 0.94 px wide that cuts off a land triangle of legs 0.15 and
     * 0.30 px at that corner: the triangle touches the corner's cell only
     * along the lake's edges, which are water, and the cell's samples give
     * a segment 0.5 px from it, too far for the crease recovery. Its
     * corners, off the cell's contour, make the cell ambiguous. */
    su_init(&s, 128);
    const double ell[] = {40, 40, 80, 40, 80, 60, 60, 60, 60, 80, 40, 80};
    const int nell = 6;
    su_lake(&s, ell, &nell, 1);
    const double ux = 2.4 / hypot(2.4, 1.2), uy = -1.2 / hypot(2.4, 1.2);
    const double r = 0.47; /* half-width: the upper bank through (60,
                            * 61.2) and (62.4, 60) */
    const double cut[] = {60 - 20 * ux + uy * r, 61.2 - 20 * uy - ux * r,
                          60 + 24 * ux + uy * r, 61.2 + 24 * uy - ux * r};
    su_river(&s, cut, 2, r);
    su_finish(&s);
    TAP_EQ(extract(&s, 0, &r0), WM_OK, "extract from the samples alone");
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_EQ(count_sign(&r0, 0), 0, "samples alone: the land triangle lost");
    TAP_EQ(count_sign(&r1, 0), 1, "exact search: the land triangle kept");
    const double lx = 62.4 - 2 * r / -uy, ly = 61.2 - 2 * r / ux;
    TAP_OK(vertex_near(&r1, 60 * WM_Q, ly * WM_Q, 4.0) &&
               vertex_near(&r1, lx * WM_Q, 60 * WM_Q, 4.0),
           "its corners on the lake's edges within 1/64 px (%.3f, %.3f)", lx,
           ly);
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r0);
    wm_rings_free(&r1);
    wm_scene_free(&s);
    /* An island 0.15 px across between three rivers (2.2, 5.3 and 1.0 m
     * wide at 2 m pixels: adversarial seam seed 9019), in a cell whose
     * samples give a segment within a quarter pixel of the island's
     * corners: off_contour leaves them to the crease recovery, which
     * cannot make a hole. Its three corners in one cell make the cell
     * ambiguous. */
    su_init(&s, 128);
    const double ia[] = {57.0625, 67.125, 48.93359375, 76.02734375};
    const double ib[] = {55.0, 75.12890625, 48.41796875, 71.6171875};
    const double ic[] = {47.83203125, 71.375, 56.2734375, 71.98046875};
    su_river(&s, ia, 2, 0.555109790257489);
    su_river(&s, ib, 2, 1.3256807709745995);
    su_river(&s, ic, 2, 0.2512326676842075);
    su_finish(&s);
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract the three rivers");
    size_t near = 0;
    for (size_t i = 0; i < r1.nrings; i++)
    {
        const size_t m = wm_rings_len(&r1, i);
        const wm_pt *q = r1.pts + r1.start[i];
        if (wm_ring_area2(q, m) >= 0)
            continue;
        int in = 1;
        for (size_t v = 0; v < m; v++)
            in &= hypot(q[v].x - 51.85 * WM_Q, q[v].y - 71.94 * WM_Q) <
                  0.25 * WM_Q;
        near += in;
    }
    TAP_EQ(near, 1, "the island kept: one hole within 1/4 px of it");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r1);
    wm_scene_free(&s);
    /* A river 6 px wide whose round end dips 1/32 px below the sample row
     * y = 10, between the samples (10, 10) and (11, 10): both are land,
     * 0.013 px from the cap, and the cap crosses their edge twice, 0.86 px
     * apart. The least radius in reach (3 px) must not rule the edge out;
     * a lake elsewhere makes its cells' least radius 0, nothing in reach
     * none at all. */
    su_init(&s, 128);
    const double cap[] = {10.5, 12.96875, 10.5, 40};
    const double pool[] = {80, 80, 90, 80, 90, 90, 80, 90};
    const int npool = 4;
    su_river(&s, cap, 2, 3.0);
    su_lake(&s, pool, &npool, 1);
    su_finish(&s);
    TAP_EQ(wm_probe_init(&p, &s, 0, 0), WM_OK, "probe");
    TAP_OK(wm_probe_min_radius(&p, 0, 0, 12 * WM_Q, 12 * WM_Q, 1) == 3.0 * WM_Q,
           "least radius near the cap: 3 px");
    TAP_OK(wm_probe_min_radius(&p, 84 * WM_Q, 84 * WM_Q, 86 * WM_Q, 86 * WM_Q,
                               1) == 0,
           "least radius near the lake: 0");
    TAP_OK(isinf(wm_probe_min_radius(&p, 40 * WM_Q, 100 * WM_Q, 60 * WM_Q,
                                     120 * WM_Q, 1)),
           "nothing in reach: infinite");
    TAP_OK(isinf(wm_probe_min_radius(&p, 84 * WM_Q, 84 * WM_Q, 86 * WM_Q,
                                     86 * WM_Q, 0)),
           "least river radius near the lake, no river in reach: infinite");
    wm_probe_free(&p);
    TAP_EQ(extract(&s, 1, &r1), WM_OK, "extract with the exact search");
    TAP_OK(vertex_near(&r1, 10.0681 * WM_Q, 10 * WM_Q, 1.0) &&
               vertex_near(&r1, 10.9319 * WM_Q, 10 * WM_Q, 1.0),
           "the cap's two crossings of the land edge, exactly");
    TAP_EQ(ring_meetings(&r1), 0, "rings simple and disjoint");
    wm_rings_free(&r1);
    wm_scene_free(&s);
    block_side();
    bank_on_side();
    bulge_across_side();
    pinch_of_three_lakes();
    shore_on_side();
    lone_rings_kept();
    four_lakes_at_a_corner();
    lone_rings_touching();
    dense_bend();
    buried_crossings();
    thin_streams_between_rows();
    island_near_shore();
    hidden_cells_cancel();
    return TAP_DONE();
}
