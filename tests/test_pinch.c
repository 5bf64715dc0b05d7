/*
 * test_pinch.c - wm_rings_open_pinches: hand-made pinches, and random
 * pixel images whose traced boundaries touch at every diagonal corner,
 * checked for simple, disjoint rings that nest and triangulate.
 */
#include "cdt.h"
#include "holes.h"
#include "lattice.h"
#include "pinch.h"
#include "tap.h"

#include <stdint.h>
#include <string.h>

/* The block square's side in these tests: far from every ring. */
#define SIDE (1 << 20)

/* Hand-made rings, moved by (O, O): off the sample grid's rows and
 * columns (multiples of WM_Q), where no vertex can repeat. */
#define O 100

static void ring(wm_rings *r, const int *xy, int n)
{
    for (int i = 0; i < n; i++)
    {
        wm_pt p;
        p.x = O + xy[2 * i];
        p.y = O + xy[2 * i + 1];
        if (wm_rings_push(r, p) != WM_OK)
            abort();
    }
    if (wm_rings_close(r) != WM_OK)
        abort();
}

static int repeats(const wm_rings *r)
{
    int n = 0;
    for (size_t i = 0; i < r->npts; i++)
        for (size_t j = i + 1; j < r->npts; j++)
            n += wm_pt_eq(r->pts[i], r->pts[j]);
    return n;
}

/* Segments of different rings, or of one ring and not consecutive, that
 * meet at all. */
static int meetings(const wm_rings *r)
{
    int n = 0;
    for (size_t a = 0; a < r->nrings; a++)
        for (size_t i = r->start[a]; i < r->start[a + 1]; i++)
        {
            const size_t la = wm_rings_len(r, a), s = r->start[a];
            const size_t i1 = s + (i - s + 1) % la;
            for (size_t b = a; b < r->nrings; b++)
                for (size_t j = b == a ? i + 1 : r->start[b];
                     j < r->start[b + 1]; j++)
                {
                    const size_t lb = wm_rings_len(r, b), t = r->start[b];
                    const size_t j1 = t + (j - t + 1) % lb;
                    if (a == b && (j == i1 || j1 == i))
                        continue;
                    n += wm_segments_meet(r->pts[i], r->pts[i1], r->pts[j],
                                          r->pts[j1]);
                }
        }
    return n;
}

static wm_i128 area2(const wm_rings *r)
{
    wm_i128 a = 0;
    for (size_t i = 0; i < r->nrings; i++)
        a += wm_ring_area2(r->pts + r->start[i], wm_rings_len(r, i));
    return a;
}

/* The contour's form of a land triangle touching the bottom of a square
 * of water at (10, 0): one ring through the point twice, each pass
 * turning left round its own water wedge. */
static const int touching[] = {0,  0, 10, 0, 5,  10, 15, 10,
                               10, 0, 20, 0, 20, 20, 0,  20};

static void hole_touching_shell(void)
{
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, touching, 8);
    TAP_EQ(repeats(&r), 1, "touching hole: one pinch before");
    const wm_i128 before = area2(&r);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK,
           "touching hole: opened");
    TAP_EQ(repeats(&r), 0, "touching hole: no pinch after");
    TAP_EQ(meetings(&r), 0, "touching hole: the ring is simple");
    TAP_EQ(r.npts, 8, "touching hole: one vertex moved, none cut");
    /* the second pass, 15,10 -> P -> 20,0, moves a unit along its wedge's
     * bisector: less than its triangle of 50 goes */
    TAP_OK(before - area2(&r) > 0 && before - area2(&r) < 100,
           "touching hole: a sliver of water less");
    wm_rings_free(&r);
}

static void two_lobes(void)
{
    /* two rings meeting at (10, 10), each turning left there */
    const int a[] = {0, 0, 10, 10, 0, 20, -10, 10};
    const int b[] = {10, 10, 20, 0, 30, 10, 20, 20};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, a, 4);
    ring(&r, b, 4);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "two lobes: opened");
    TAP_EQ(repeats(&r), 0, "two lobes: no pinch after");
    TAP_EQ(meetings(&r), 0, "two lobes: rings disjoint");
    TAP_EQ(r.npts, 8, "two lobes: one vertex moved");
    int32_t enc[2];
    TAP_EQ(wm_holes_nesting(&r, enc, NULL), WM_OK, "two lobes: nesting");
    TAP_OK(enc[0] == -1 && enc[1] == -1, "two lobes: neither encloses");
    wm_rings_free(&r);
}

static void vertex_in_sweep(void)
{
    /* two lobes, where the second would move to (11, 10) a small land
     * ring has a vertex: the first lobe moves instead */
    const int a[] = {0, 0, 10, 10, 0, 20, -10, 10};
    const int b[] = {10, 10, 20, 0, 30, 10, 20, 20};
    const int small[] = {11, 10, 13, 11, 13, 9};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, a, 4);
    ring(&r, b, 4);
    ring(&r, small, 3);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK,
           "vertex in sweep: runs");
    TAP_EQ(repeats(&r), 0, "vertex in sweep: no pinch after");
    TAP_OK(r.pts[4].x == O + 10 && r.pts[4].y == O + 10 &&
               !(r.pts[1].x == O + 10 && r.pts[1].y == O + 10),
           "vertex in sweep: the other lobe moved");
    TAP_EQ(meetings(&r), 0, "vertex in sweep: disjoint");
    wm_rings_free(&r);
}

static void no_room_to_move(void)
{
    /* two lobes whose corners at (10, 10) hold no lattice point: one is
     * cut */
    const int a[] = {10, 10, 11, 10, 14, 14, 10, 11};
    const int b[] = {10, 10, 9, 10, 6, 6, 10, 9};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, a, 4);
    ring(&r, b, 4);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "no room: runs");
    TAP_EQ(repeats(&r), 0, "no room: no pinch after");
    TAP_EQ(r.npts, 7, "no room: one vertex cut");
    TAP_EQ(meetings(&r), 0, "no room: disjoint");
    wm_rings_free(&r);
}

static void hole_at_straight_side(void)
{
    /* a hole ring touching a straight side at a vertex of both, as OGC
     * draws it: the shell goes straight through, the hole turns right;
     * the hole's vertex moves into its land */
    const int shell[] = {0, 0, 10, 0, 20, 0, 20, 20, 0, 20};
    const int hole[] = {10, 0, 5, 10, 15, 10};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, shell, 5);
    ring(&r, hole, 3);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "hole at side: runs");
    TAP_EQ(repeats(&r), 0, "hole at side: no pinch after");
    TAP_EQ(meetings(&r), 0, "hole at side: disjoint");
    TAP_OK(r.pts[1].y == O && r.pts[5].y > O,
           "hole at side: the hole's vertex moved off the side");
    wm_rings_free(&r);
}

static void hole_on_edge(void)
{
    /* a T: the hole's vertex lies inside the shell's bottom edge */
    const int shell[] = {0, 0, 20, 0, 20, 20, 0, 20};
    const int hole[] = {10, 0, 5, 10, 15, 10};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, shell, 4);
    ring(&r, hole, 3);
    TAP_EQ(meetings(&r), 2, "T: the rings meet before");
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "T: runs");
    TAP_EQ(meetings(&r), 0, "T: disjoint after");
    TAP_OK(r.npts == 7 && r.pts[4].y > O, "T: the hole's vertex moved up");
    int32_t enc[2];
    TAP_EQ(wm_holes_nesting(&r, enc, NULL), WM_OK, "T: nesting");
    TAP_EQ(enc[1], 0, "T: the hole is in the shell");
    wm_rings_free(&r);
}

static void blocked_wedge(void)
{
    /* a land hole turning right at (10, 10), an island inside it touching
     * it there: the hole's convex side holds the island's segments, so
     * only the island moves (into its water) */
    const int a[] = {0, 0, 10, 10, 20, 0, 20, -10, 0, -10};
    const int b[] = {10, 10, 8, 4, 12, 4};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, a, 5);
    ring(&r, b, 3);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "blocked: runs");
    TAP_OK(r.pts[1].x == O + 10 && r.pts[1].y == O + 10,
           "blocked: the hole's pass stays");
    TAP_OK(r.pts[5].y < O + 10, "blocked: the island's pass moves");
    TAP_EQ(meetings(&r), 0, "blocked: disjoint");
    wm_rings_free(&r);
}

static void three_lobes(void)
{
    /* three water lobes around (50, 50), three rings */
    const int a[] = {50, 50, 90, 40, 95, 50, 90, 60};
    const int b[] = {50, 50, 40, 90, 30, 95, 20, 90};
    const int c[] = {50, 50, 10, 20, 15, 15, 20, 10};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, a, 4);
    ring(&r, b, 4);
    ring(&r, c, 4);
    TAP_EQ(repeats(&r), 3, "three lobes: three pairs at one point");
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "three lobes: opened");
    TAP_EQ(repeats(&r), 0, "three lobes: none after");
    TAP_EQ(r.npts, 12, "three lobes: two passes moved");
    TAP_EQ(meetings(&r), 0, "three lobes: disjoint");
    wm_rings_free(&r);
}

/* Whether two segments of different rings, or non-adjacent segments of
 * one ring, lie along each other (overlap in more than a point). */
static int overlaps(const wm_rings *r)
{
    int n = 0;
    for (size_t a = 0; a < r->nrings; a++)
        for (size_t i = r->start[a]; i < r->start[a + 1]; i++)
        {
            const size_t i1 = i + 1 < r->start[a + 1] ? i + 1 : r->start[a];
            for (size_t b = 0; b < r->nrings; b++)
                for (size_t j = r->start[b]; j < r->start[b + 1]; j++)
                {
                    const size_t j1 =
                        j + 1 < r->start[b + 1] ? j + 1 : r->start[b];
                    if (i == j)
                        continue;
                    const wm_pt p = r->pts[i], q = r->pts[i1];
                    const wm_pt u = r->pts[j], v = r->pts[j1];
                    if (wm_orient(p, q, u) == 0 && wm_orient(p, q, v) == 0 &&
                        ((wm_on_segment(p, q, u) && !wm_pt_eq(u, p) &&
                          !wm_pt_eq(u, q)) ||
                         (wm_on_segment(p, q, v) && !wm_pt_eq(v, p) &&
                          !wm_pt_eq(v, q))))
                        n++;
                }
        }
    return n;
}

/* Cases a reviewing helper found, where a cut laid its chord along a
 * neighbouring segment or a block side, or a one-unit side kept a pass
 * from moving. */
static void review_cases(void)
{
    wm_rings r;
    /* a T in ring 0 at (0, 5) and a pinch with ring 1 at (1, 1): cutting
     * (1, 1) left 0,0 -> 0,5 folded back along 0,10 -> 0,0 */
    memset(&r, 0, sizeof r);
    ring(&r, (const int[]){0, 10, 0, 0, 1, 1, 0, 5, 1, 6}, 5);
    ring(&r, (const int[]){1, 1, 3, 0, 3, 2}, 3);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "fold: runs");
    TAP_EQ(overlaps(&r), 0, "fold: no segment along another");
    wm_rings_free(&r);
    /* ring 1's vertices (0, 0) and (8, 0) on ring 0's edge: a cut of
     * (4, 1) laid 0,0 -> 8,0 on it */
    memset(&r, 0, sizeof r);
    ring(&r, (const int[]){16, 0, -8, 0, 0, -8}, 3);
    ring(&r, (const int[]){0, 0, 4, 1, 8, 0, 8, 6, 0, 6}, 5);
    ring(&r, (const int[]){4, 1, 3, 3, 5, 3}, 3);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "along: runs");
    TAP_EQ(overlaps(&r), 0, "along: no segment along another");
    TAP_EQ(meetings(&r), 0, "along: rings apart");
    wm_rings_free(&r);
    /* a pass whose side is one unit long moves to (1, 1) */
    memset(&r, 0, sizeof r);
    ring(&r, (const int[]){3, 10, 0, 0, 1, 0, 4, 11}, 4);
    ring(&r, (const int[]){0, 0, -5, 2, -3, -4}, 3);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "one unit: runs");
    TAP_OK(r.npts == 7 && r.pts[1].x == O + 1 && r.pts[1].y == O + 1,
           "one unit: moved, not cut");
    wm_rings_free(&r);
    /* a notch on the block side x = 0 touching a hole at (1, 11): a cut
     * would run along the side */
    memset(&r, 0, sizeof r);
    const int notch[] = {0, 12, 1, 11, 0, 10, 0, 2, 10, 2, 10, 20, 0, 20};
    for (int i = 0; i < 7; i++)
    {
        const wm_pt p = {notch[2 * i], 300 + notch[2 * i + 1]};
        if (wm_rings_push(&r, p) != WM_OK)
            abort();
    }
    if (wm_rings_close(&r) != WM_OK)
        abort();
    const int hole[] = {1, 11, 4, 13, 4, 9};
    for (int i = 0; i < 3; i++)
    {
        const wm_pt p = {hole[2 * i], 300 + hole[2 * i + 1]};
        if (wm_rings_push(&r, p) != WM_OK)
            abort();
    }
    if (wm_rings_close(&r) != WM_OK)
        abort();
    TAP_EQ(wm_rings_open_pinches(&r, 256, NULL), WM_OK, "side: runs");
    TAP_OK(r.npts == 10 && r.pts[1].x == 1, "side: the notch stays");
    TAP_EQ(meetings(&r), 0, "side: rings apart");
    wm_rings_free(&r);
}

/* Random images: pixel (i, j) water with probability 1/2, the border
 * land; the boundary traced with water on the left, each edge followed by
 * the next edge of its own pixel at a diagonal corner (the rings touch
 * there). Coordinates times 8. */
enum
{
    W = 12,
    H = 12
};

static uint64_t lcg_state = 2024;

static uint32_t lcg(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (uint32_t)(lcg_state >> 33);
}

typedef struct
{
    int x0, y0, x1, y1, pix, used;
} edge;

static int water(const uint8_t *img, int i, int j)
{
    return i >= 0 && j >= 0 && i < W && j < H && img[j * W + i];
}

static int trace(const uint8_t *img, int K, wm_rings *r)
{
    edge e[4 * W * H];
    int n = 0;
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++)
        {
            if (!water(img, i, j))
                continue;
            const int p = j * W + i;
            if (!water(img, i, j - 1))
                e[n++] = (edge){i, j, i + 1, j, p, 0};
            if (!water(img, i + 1, j))
                e[n++] = (edge){i + 1, j, i + 1, j + 1, p, 0};
            if (!water(img, i, j + 1))
                e[n++] = (edge){i + 1, j + 1, i, j + 1, p, 0};
            if (!water(img, i - 1, j))
                e[n++] = (edge){i, j + 1, i, j, p, 0};
        }
    for (int s = 0; s < n; s++)
    {
        if (e[s].used)
            continue;
        int c = s;
        do
        {
            e[c].used = 1;
            wm_pt q;
            q.x = K * e[c].x0 + 3;
            q.y = K * e[c].y0 + 3;
            if (wm_rings_push(r, q) != WM_OK)
                abort();
            int next = -1;
            for (int k = 0; k < n; k++)
                if (e[k].x0 == e[c].x1 && e[k].y0 == e[c].y1 &&
                    (next < 0 || e[k].pix == e[c].pix))
                    next = k;
            c = next;
        } while (c != s && c >= 0 && !e[c].used);
        if (c != s || wm_rings_close(r) != WM_OK)
            return 0;
    }
    return 1;
}

/* Triangulates every shell with its holes; 0 on any failure. */
static int triangulates(const wm_rings *r, const int32_t *enc)
{
    for (size_t s = 0; s < r->nrings; s++)
    {
        if (wm_ring_area2(r->pts + r->start[s], wm_rings_len(r, s)) <= 0)
            continue;
        wm_pt pts[8 * W * H * 4];
        size_t rs[W * H + 2], nr = 0, np = 0;
        rs[nr++] = 0; /* the shell, then its holes */
        for (size_t k = 0; k < wm_rings_len(r, s); k++)
            pts[np++] = r->pts[r->start[s] + k];
        rs[nr] = np;
        for (size_t h = 0; h < r->nrings; h++)
        {
            if (enc[h] != (int32_t)s)
                continue;
            for (size_t k = 0; k < wm_rings_len(r, h); k++)
                pts[np++] = r->pts[r->start[h] + k];
            rs[++nr] = np;
        }
        uint32_t *t = NULL;
        size_t nt = 0;
        const wm_status st = wm_cdt_triangulate(pts, rs, nr, &t, &nt, NULL);
        free(t);
        if (st != WM_OK)
            return 0;
    }
    return 1;
}

static void random_images(int K)
{
    int bad_trace = 0, pinched = 0, left = 0, crossing = 0, nest = 0, cdt = 0,
        lost = 0;
    for (int it = 0; it < 300; it++)
    {
        uint8_t img[W * H];
        for (int k = 0; k < W * H; k++)
            img[k] = (uint8_t)(lcg() % 2);
        wm_rings r;
        memset(&r, 0, sizeof r);
        if (!trace(img, K, &r))
        {
            bad_trace++;
            wm_rings_free(&r);
            continue;
        }
        pinched += repeats(&r) > 0;
        const wm_i128 before = area2(&r);
        const size_t nrings = r.nrings;
        if (wm_rings_open_pinches(&r, SIDE, NULL) != WM_OK)
            abort();
        left += repeats(&r) > 0;
        crossing += meetings(&r) > 0;
        /* each move or cut takes water of at most half a pixel */
        const wm_i128 d = before - area2(&r);
        lost += r.nrings != nrings || d < 0 || d > (wm_i128)K * K * W * H;
        int32_t enc[W * H + 1];
        if (wm_holes_nesting(&r, enc, NULL) != WM_OK)
            nest++;
        else if (!triangulates(&r, enc))
            cdt++;
        wm_rings_free(&r);
    }
    TAP_EQ(bad_trace, 0, "random images: every boundary traced");
    TAP_OK(pinched > 100, "random images: %d of 300 have pinches", pinched);
    TAP_EQ(left, 0, "random images: no pinch left");
    TAP_EQ(crossing, 0, "random images: rings simple and disjoint");
    TAP_EQ(lost, 0, "random images: only water triangles cut, no ring lost");
    TAP_EQ(nest, 0, "random images: nesting succeeds");
    TAP_EQ(cdt, 0, "random images: every polygon triangulates");
}

static void no_pinch_unchanged(void)
{
    const int a[] = {0, 0, 30, 0, 30, 30, 0, 30};
    const int b[] = {10, 10, 10, 20, 20, 20, 20, 10};
    wm_rings r;
    memset(&r, 0, sizeof r);
    ring(&r, a, 4);
    ring(&r, b, 4);
    wm_pt copy[8];
    memcpy(copy, r.pts, sizeof copy);
    TAP_EQ(wm_rings_open_pinches(&r, SIDE, NULL), WM_OK, "no pinch: runs");
    TAP_OK(r.npts == 8 && r.nrings == 2 &&
               memcmp(copy, r.pts, sizeof copy) == 0,
           "no pinch: rings unchanged");
    wm_rings_free(&r);
}

int main(void)
{
    hole_touching_shell();
    two_lobes();
    vertex_in_sweep();
    no_room_to_move();
    hole_at_straight_side();
    hole_on_edge();
    blocked_wedge();
    three_lobes();
    no_pinch_unchanged();
    review_cases();
    random_images(8);
    random_images(3);
    return TAP_DONE();
}
