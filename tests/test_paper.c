/* test_paper.c - the paper's extraction: classes and erosion on hand-made
 * grids, the heuristics (Fig. 5) and backtracking (Fig. 6) on small
 * patterns, pinches, thin features, and the wm_rings invariants, exact area
 * accounting and seams on random grids and scene fields. */
#include "field_check.h"
#include "paper.h"
#include "lattice.h"
#include "ring_check.h"
#include "scene_util.h"
#include "tap.h"

#include <stdlib.h>
#include <string.h>

/* A water mask from text rows given top row first ('#' water). */
static uint8_t *mask_from(const char *const *rows, int32_t h, int32_t *w)
{
    *w = (int32_t)strlen(rows[0]);
    uint8_t *m = calloc((size_t)(*w * h), 1);
    for (int32_t r = 0; r < h; r++)
        for (int32_t c = 0; c < *w; c++)
            m[r * *w + c] = rows[h - 1 - r][c] == '#';
    return m;
}

/* Classes of a mask (a copy, eroded). */
static uint8_t *classes_of(const uint8_t *m, int32_t w, int32_t h)
{
    uint8_t *c = malloc((size_t)(w * h));
    memcpy(c, m, (size_t)(w * h));
    wm_paper_erode(c, w, h);
    return c;
}

/* Twice the area of the water triangles of a mask, in pixels^2: a cell
 * with four water corners counts 2, with three 1. */
static long long region_area2(const uint8_t *m, int32_t w, int32_t h)
{
    long long a = 0;
    for (int32_t j = 0; j + 1 < h; j++)
        for (int32_t i = 0; i + 1 < w; i++)
        {
            const int n = (m[j * w + i] != 0) + (m[j * w + i + 1] != 0) +
                          (m[(j + 1) * w + i] != 0) +
                          (m[(j + 1) * w + i + 1] != 0);
            a += n == 4 ? 2 : n == 3 ? 1 : 0;
        }
    return a;
}

static int ring_has(const wm_rings *r, wm_pt p)
{
    for (size_t k = 0; k < r->npts; k++)
        if (wm_pt_eq(r->pts[k], p))
            return 1;
    return 0;
}

static int point_parity(const wm_rings *r, wm_pt p)
{
    int in = 0;
    for (size_t i = 0; i < r->nrings; i++)
    {
        const int k =
            wm_point_in_ring(r->pts + r->start[i], wm_rings_len(r, i), p);
        if (k < 0)
            return -1;
        in ^= k;
    }
    return in;
}

/*
 * Every check a result must pass, by brute force; returns the number of
 * violations:
 *  - wm_rings invariants: >= 3 vertices, no repeated consecutive vertex,
 *    simple and pairwise disjoint (ring_meetings), inside the block;
 *  - every vertex is a water sample, used once over all rings;
 *  - no land added: a point near a land corner of any cell is outside;
 *  - exact area: the signed areas (holes negative, so orientation counts)
 *    sum to the water triangles minus half a pixel per cut and shortcut;
 *  - when nothing was cut: every water sample on the block square that is
 *    a corner of a water triangle is a vertex.
 */
static int check_all(const wm_rings *r, const uint8_t *m, int32_t w, int32_t h,
                     const wm_paper_stats *st)
{
    int bad = 0;
    uint8_t *used = calloc((size_t)(w * h), 1);
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t n = wm_rings_len(r, i);
        const wm_pt *p = r->pts + r->start[i];
        bad += n < 3;
        for (size_t k = 0; k < n; k++)
        {
            bad += wm_pt_eq(p[k], p[(k + 1) % n]);
            if (p[k].x % WM_Q || p[k].y % WM_Q || p[k].x < 0 || p[k].y < 0 ||
                p[k].x > (w - 1) * WM_Q || p[k].y > (h - 1) * WM_Q)
            {
                bad++;
                continue;
            }
            const int32_t c = p[k].x / WM_Q, rr = p[k].y / WM_Q;
            bad += !m[rr * w + c];
            bad += used[rr * w + c]++ != 0;
        }
    }
    bad += ring_meetings(r);
    wm_i128 total = 0;
    for (size_t i = 0; i < r->nrings; i++)
        total += wm_ring_area2(r->pts + r->start[i], wm_rings_len(r, i));
    const long long want =
        region_area2(m, w, h) - (long long)st->cuts - (long long)st->shortcuts;
    bad += total != (wm_i128)want * WM_Q * WM_Q;
    for (int32_t j = 0; j + 1 < h; j++)
        for (int32_t i = 0; i + 1 < w; i++)
            for (int k = 0; k < 4; k++)
            {
                const int ox = k == 1 || k == 2, oy = k >= 2;
                if (m[(j + oy) * w + i + ox])
                    continue;
                const wm_pt q = {i * WM_Q + (ox ? 3 * WM_Q / 4 : WM_Q / 4),
                                 j * WM_Q + (oy ? 5 * WM_Q / 8 : 3 * WM_Q / 8)};
                bad += point_parity(r, q) != 0;
            }
    if (st->cuts == 0)
        for (int32_t rr = 0; rr < h; rr++)
            for (int32_t c = 0; c < w; c++)
            {
                if (!(c == 0 || rr == 0 || c == w - 1 || rr == h - 1) ||
                    !m[rr * w + c])
                    continue;
                int tri = 0; /* a corner of a cell with >= 3 water corners */
                for (int dj = -1; dj <= 0; dj++)
                    for (int di = -1; di <= 0; di++)
                    {
                        const int32_t i = c + di, j = rr + dj;
                        if (i < 0 || j < 0 || i + 1 >= w || j + 1 >= h)
                            continue;
                        tri |= (m[j * w + i] != 0) + (m[j * w + i + 1] != 0) +
                                   (m[(j + 1) * w + i] != 0) +
                                   (m[(j + 1) * w + i + 1] != 0) >=
                               3;
                    }
                bad += tri && !used[rr * w + c];
            }
    free(used);
    return bad;
}

static wm_status trace_mask(const uint8_t *m, int32_t w, int32_t h,
                            wm_heuristic heur, wm_rings *r, wm_paper_stats *st)
{
    uint8_t *c = classes_of(m, w, h);
    const wm_status s = wm_paper_trace(c, w, h, heur, r, st, NULL);
    free(c);
    return s;
}

static uint32_t rng_state = 2463534242u;
static uint32_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return rng_state;
}

static const char *const HNAME[4] = {"CLOSEST", "DIRECTIONAL_CW",
                                     "DIRECTIONAL_CCW", "LEAST_ANGLE"};

/* Whether b follows a in a ring (defined below). */
static int has_edge(const wm_rings *r, wm_pt a, wm_pt b);

static void test_classify(void)
{
    /* 7 x 5 field: values around the level 1/2 */
    enum
    {
        W = 7,
        H = 5
    };
    /* row 0 at the bottom */
    const float v[H * W] = {
        2.0f,  -2.0f, 0.5f,  0.51f, -1.0f, -1.0f, 2.0f,  /* r = 0 */
        -2.0f, -2.0f, -2.0f, -2.0f, -2.0f, -2.0f, -2.0f, /* r = 1 */
        -2.0f, -2.0f, -2.0f, 0.6f,  -2.0f, -2.0f, -2.0f, /* r = 2 */
        -2.0f, -2.0f, -2.0f, -2.0f, -2.0f, -2.0f, -2.0f, /* r = 3 */
        2.0f,  2.0f,  2.0f,  2.0f,  2.0f,  2.0f,  2.0f}; /* r = 4 */
    const uint8_t O = WM_PAPER_OUTSIDE, I = WM_PAPER_INSIDE,
                  B = WM_PAPER_BORDER;
    const uint8_t want[H * W] = {O, B, B, O, B, B, O, /* level: 0.5 water */
                                 B, I, I, B, I, I, B, /* land below */
                                 B, I, B, O, B, I, B, /* 0.6 is land */
                                 B, B, B, B, B, B, B, /* land above */
                                 O, O, O, O, O, O, O};
    wm_field f;
    uint8_t cls[H * W];
    fc_make_field(&f, W, H, v, 2.0f);
    TAP_EQ(wm_paper_classify(&f, cls, NULL), WM_OK, "classify a 7 x 5 field");
    int diff = 0;
    for (int i = 0; i < H * W; i++)
        diff += cls[i] != want[i];
    TAP_EQ(diff, 0, "classes: d <= 1/2 water, forced border, 4-neighbours");
    TAP_EQ(cls[2 * W + 2], WM_PAPER_BORDER, "a land 4-neighbour makes Border");
    TAP_EQ(cls[1 * W + 3], WM_PAPER_BORDER, "land below makes Border");
    TAP_EQ(cls[1 * W + 1], WM_PAPER_INSIDE,
           "a land diagonal neighbour does not (cross element)");
    wm_field_free(&f);

    /* the seam rules on the block square: an isolated water sample of a
     * side becomes land; a water sample of a side makes its inward
     * neighbour water */
    {
        const float u[H * W] = {
            2.0f, -1.0f, 2.0f, 2.0f, -1.0f, -1.0f, 2.0f, /* r = 0 */
            2.0f, 2.0f,  2.0f, 2.0f, 2.0f,  2.0f,  2.0f, /* r = 1 */
            2.0f, 2.0f,  2.0f, 2.0f, 2.0f,  2.0f,  2.0f, /* r = 2 */
            2.0f, 2.0f,  2.0f, 2.0f, 2.0f,  2.0f,  2.0f, /* r = 3 */
            2.0f, 2.0f,  2.0f, 2.0f, 2.0f,  2.0f,  2.0f};
        fc_make_field(&f, W, H, u, 2.0f);
        wm_paper_classify(&f, cls, NULL);
        TAP_EQ(cls[1], WM_PAPER_OUTSIDE,
               "an isolated water sample on the square becomes land");
        TAP_OK(cls[4] == WM_PAPER_BORDER && cls[5] == WM_PAPER_BORDER &&
                   cls[W + 4] == WM_PAPER_BORDER &&
                   cls[W + 5] == WM_PAPER_BORDER && cls[W + 1] == 0,
               "a pair on the square makes its inward neighbours water");
        wm_field_free(&f);
    }
    wm_field_free(&f);

    /* a pinch next to a corner of the square (two water bodies two pixels
     * apart): resolving it must not uncover the piece (0,0)-(1,0) of the
     * bottom side, which the block below covers too */
    {
        const float L = 2.0f, A = -1.0f;
        const float u[5 * 5] = {A, A, L, L, L,  /* r = 0 */
                                L, L, L, L, L,  /* r = 1: (1,1) forced */
                                A, A, A, L, L,  /* r = 2 */
                                A, L, L, L, L,  /* r = 3 */
                                L, L, L, L, L}; /* r = 4 */
        wm_rings rr;
        wm_paper_stats ps;
        memset(&rr, 0, sizeof rr);
        fc_make_field(&f, 5, 5, u, 2.0f);
        TAP_EQ(wm_paper_extract(&f, WM_HEUR_CLOSEST, &rr, &ps, NULL), WM_OK,
               "extract next to a corner pinch");
        TAP_OK(ps.pinches > 0 &&
                   (has_edge(&rr, (wm_pt){0, 0}, (wm_pt){WM_Q, 0}) ||
                    has_edge(&rr, (wm_pt){WM_Q, 0}, (wm_pt){0, 0})),
               "a pinch (%zu) keeps the side piece covered", ps.pinches);
        wm_rings_free(&rr);
        wm_field_free(&f);
    }

    fc_make_field(&f, W, H, v, 0.5f);
    TAP_EQ(wm_paper_classify(&f, cls, NULL), WM_ERR_INVALID,
           "a band of 1/2 pixel is refused");
    wm_field_free(&f);
}

static void test_erode(void)
{
    const char *const in[] = {"#########", /* top row: forced Border */
                              "#.#######", "#########", "####.####",
                              "###...###", "####.####", "#########"};
    const char *const want[] = {"BBBBBBBBB", "B.BIIIIIB", "BBIIBIIIB",
                                "BIIB.BIIB", "BIB...BIB", "BIIB.BIIB",
                                "BBBBBBBBB"};
    int32_t w;
    uint8_t *m = mask_from(in, 7, &w);
    wm_paper_erode(m, w, 7);
    int diff = 0;
    for (int32_t r = 0; r < 7; r++)
        for (int32_t c = 0; c < w; c++)
        {
            const char e = want[6 - r][c];
            const uint8_t x = e == 'B'   ? WM_PAPER_BORDER
                              : e == 'I' ? WM_PAPER_INSIDE
                                         : WM_PAPER_OUTSIDE;
            diff += m[r * w + c] != x;
        }
    TAP_EQ(diff, 0, "erosion: T = (A' - cross) XOR A', padded with A's border");
    uint8_t *again = malloc((size_t)(w * 7));
    memcpy(again, m, (size_t)(w * 7));
    wm_paper_erode(again, w, 7);
    TAP_OK(!memcmp(again, m, (size_t)(w * 7)), "erosion is idempotent");
    free(again);
    free(m);

    /* rows longer than the erosion's chunk, against the definition */
    enum
    {
        LW = 2500,
        LH = 5
    };
    static uint8_t big[LW * LH];
    for (int i = 0; i < LW * LH; i++)
        big[i] = rnd() % 4 != 0;
    uint8_t *e = classes_of(big, LW, LH);
    int wrong = 0;
    for (int r = 0; r < LH; r++)
        for (int c = 0; c < LW; c++)
        {
            const int i = r * LW + c;
            int x = 0;
            if (big[i])
                x = c == 0 || r == 0 || c == LW - 1 || r == LH - 1 ||
                            !big[i - 1] || !big[i + 1] || !big[i - LW] ||
                            !big[i + LW]
                        ? WM_PAPER_BORDER
                        : WM_PAPER_INSIDE;
            wrong += e[i] != x;
        }
    TAP_EQ(wrong, 0, "erosion of %d-sample rows matches the definition", LW);
    free(e);
}

static void test_basic(void)
{
    wm_rings r = {0};
    wm_paper_stats st;
    int32_t w;

    /* one interior 3 x 3 water square: 8 border pixels, one CCW ring */
    const char *const sq[] = {".......", ".......", "..###..", "..###..",
                              "..###..", ".......", "......."};
    uint8_t *m = mask_from(sq, 7, &w);
    for (int hh = 0; hh < 4; hh++)
    {
        TAP_EQ(trace_mask(m, w, 7, (wm_heuristic)hh, &r, &st), WM_OK,
               "square, %s", HNAME[hh]);
        TAP_EQ(r.nrings, 1, "one ring");
        TAP_OK(wm_ring_area2(r.pts, wm_rings_len(&r, 0)) > 0,
               "water on the left: counter-clockwise");
        TAP_EQ(check_all(&r, m, w, 7, &st), 0, "square rings valid");
        TAP_EQ(wm_rings_len(&r, 0) + st.shortcuts, 8,
               "8 border pixels, less the corners cut");
        TAP_OK(ring_has(&r, (wm_pt){2 * WM_Q, 2 * WM_Q}),
               "the start pixel is a vertex");
    }
    free(m);

    /* a lake with an island: outer CCW and hole CW */
    const char *const isl[] = {"..........", ".########.", ".########.",
                               ".###..###.", ".###..###.", ".########.",
                               ".########.", ".........."};
    m = mask_from(isl, 8, &w);
    TAP_EQ(trace_mask(m, w, 8, WM_HEUR_CLOSEST, &r, &st), WM_OK, "island");
    TAP_EQ(r.nrings, 2, "outer ring and hole");
    {
        int pos = 0, neg = 0;
        for (size_t i = 0; i < r.nrings; i++)
        {
            const wm_i128 a =
                wm_ring_area2(r.pts + r.start[i], wm_rings_len(&r, i));
            pos += a > 0;
            neg += a < 0;
        }
        TAP_OK(pos == 1 && neg == 1, "one CCW outer, one CW hole");
    }
    TAP_EQ(check_all(&r, m, w, 8, &st), 0, "island rings valid");
    TAP_EQ(point_parity(&r, (wm_pt){4 * WM_Q + 128, 4 * WM_Q + 100}), 0,
           "the island is land");
    free(m);

    /* all water: the block square through every sample on it */
    {
        enum
        {
            N = 16
        };
        uint8_t all[(N + 1) * (N + 1)];
        memset(all, 1, sizeof all);
        TAP_EQ(trace_mask(all, N + 1, N + 1, WM_HEUR_CLOSEST, &r, &st), WM_OK,
               "all water");
        TAP_EQ(r.nrings, 1, "one ring");
        TAP_EQ(r.npts, 4 * N, "every sample of the square is a vertex");
        TAP_EQ(check_all(&r, all, N + 1, N + 1, &st), 0, "square valid");
        memset(all, 0, sizeof all);
        TAP_EQ(trace_mask(all, N + 1, N + 1, WM_HEUR_CLOSEST, &r, &st), WM_OK,
               "all land");
        TAP_EQ(r.nrings, 0, "no ring");
    }

    /* water on the block border: the ring runs along the square */
    const char *const edge[] = {"........", "........", "###.....",
                                "####....", "#####...", "######.."};
    m = mask_from(edge, 6, &w);
    TAP_EQ(trace_mask(m, w, 6, WM_HEUR_DIRECTIONAL_CCW, &r, &st), WM_OK,
           "corner water");
    TAP_EQ(r.nrings, 1, "one ring");
    TAP_EQ(check_all(&r, m, w, 6, &st), 0,
           "valid, every border water sample a vertex (CCW never cuts them)");
    free(m);
    wm_rings_free(&r);
}

static void test_heuristics(void)
{
    wm_rings r[4] = {{0}};
    wm_paper_stats st[4];
    int32_t w;

    /* Fig. 5: a convex corner (boundary step to a 4-neighbour, shortcut to
     * the diagonal) and a half-pixel tooth (boundary step diagonal,
     * shortcut to a 4-neighbour) at (3,5)-(4,4)-(3,4) */
    const char *const fig5[] = {"..........", "...#......", "...######.",
                                "...######.", "...######.", ".........."};
    uint8_t *m = mask_from(fig5, 6, &w);
    for (int hh = 0; hh < 4; hh++)
    {
        TAP_EQ(trace_mask(m, w, 6, (wm_heuristic)hh, &r[hh], &st[hh]), WM_OK,
               "Fig. 5 pattern, %s", HNAME[hh]);
        TAP_EQ(r[hh].nrings, 1, "one ring");
        TAP_EQ(check_all(&r[hh], m, w, 6, &st[hh]), 0, "valid");
    }
    const wm_pt tooth = {3 * WM_Q, 4 * WM_Q}, corner = {8 * WM_Q, 1 * WM_Q};
    TAP_EQ(st[WM_HEUR_DIRECTIONAL_CW].shortcuts, 0,
           "DIRECTIONAL_CW traces the exact boundary");
    TAP_OK(ring_has(&r[WM_HEUR_DIRECTIONAL_CW], tooth) &&
               ring_has(&r[WM_HEUR_DIRECTIONAL_CW], corner),
           "DIRECTIONAL_CW keeps the tooth and the corner");
    TAP_OK(!ring_has(&r[WM_HEUR_CLOSEST], tooth) &&
               ring_has(&r[WM_HEUR_CLOSEST], corner),
           "CLOSEST cuts the tooth (4-neighbour first), keeps the corner");
    TAP_OK(!ring_has(&r[WM_HEUR_DIRECTIONAL_CCW], corner),
           "DIRECTIONAL_CCW cuts the convex corner");
    TAP_OK(
        st[WM_HEUR_DIRECTIONAL_CCW].shortcuts > st[WM_HEUR_CLOSEST].shortcuts,
        "DIRECTIONAL_CCW cuts more than CLOSEST (%zu > %zu)",
        st[WM_HEUR_DIRECTIONAL_CCW].shortcuts, st[WM_HEUR_CLOSEST].shortcuts);
    TAP_OK(!ring_has(&r[WM_HEUR_LEAST_ANGLE], tooth) &&
               ring_has(&r[WM_HEUR_LEAST_ANGLE], corner),
           "LEAST_ANGLE: straight on past the tooth, keeps the corner");
    TAP_OK(st[WM_HEUR_CLOSEST].dropped == st[WM_HEUR_CLOSEST].shortcuts,
           "each pixel cut off is dropped");
    TAP_OK(st[WM_HEUR_CLOSEST].branches > 0, "branching nodes were met");
    free(m);

    /* Fig. 6: a lone triangle; DIRECTIONAL_CCW first takes the shortcut
     * from the start, comes back to the start after two pixels (no
     * polygon), backtracks to the branching node and takes the boundary */
    const char *const tri[] = {"......", "......", "..#...",
                               "..##..", "......", "......"};
    m = mask_from(tri, 6, &w);
    TAP_EQ(trace_mask(m, w, 6, WM_HEUR_DIRECTIONAL_CCW, &r[0], &st[0]), WM_OK,
           "Fig. 6 dead end");
    TAP_EQ(st[0].backtracks, 1, "one backtrack");
    TAP_EQ(r[0].nrings, 1, "the triangle is extracted");
    TAP_EQ(r[0].npts, 3, "with its three pixels");
    TAP_EQ(check_all(&r[0], m, w, 6, &st[0]), 0, "valid");
    TAP_EQ(trace_mask(m, w, 6, WM_HEUR_CLOSEST, &r[1], &st[1]), WM_OK,
           "same with CLOSEST");
    TAP_EQ(st[1].backtracks, 0, "no dead end");
    TAP_OK(rings_equal(&r[0], &r[1]), "same triangle");
    free(m);
    for (int i = 0; i < 4; i++)
        wm_rings_free(&r[i]);
}

static void test_thin_and_pinch(void)
{
    wm_rings r = {0};
    wm_paper_stats st;
    int32_t w;

    /* a one-pixel diagonal thread and an isolated sample: no area */
    const char *const thread[] = {"........", ".....#..", "....#...",
                                  "...#....", "..#.....", "........",
                                  "......#.", "........"};
    uint8_t *m = mask_from(thread, 8, &w);
    TAP_EQ(trace_mask(m, w, 8, WM_HEUR_CLOSEST, &r, &st), WM_OK, "threads");
    TAP_EQ(r.nrings, 0, "no area, no ring");
    TAP_EQ(st.dropped, 5, "all five Border pixels dropped");
    free(m);

    /* a two-pixel diagonal strip: one ring through every pixel */
    const char *const strip[] = {"........", ".....##.", "....##..", "...##...",
                                 "..##....", ".##.....", "........"};
    m = mask_from(strip, 7, &w);
    TAP_EQ(trace_mask(m, w, 7, WM_HEUR_DIRECTIONAL_CW, &r, &st), WM_OK,
           "strip");
    TAP_EQ(r.nrings, 1, "one ring");
    TAP_EQ(r.npts, 10, "DIRECTIONAL_CW: through all ten pixels");
    TAP_EQ(check_all(&r, m, w, 7, &st), 0, "valid");
    TAP_EQ(trace_mask(m, w, 7, WM_HEUR_CLOSEST, &r, &st), WM_OK, "strip");
    TAP_EQ(r.npts + st.shortcuts, 10, "CLOSEST: less the tooth at its end");
    TAP_EQ(st.shortcuts, 1, "one tooth");
    TAP_EQ(check_all(&r, m, w, 7, &st), 0, "valid");
    free(m);

    /* two water triangles touching at one pixel (4,4) */
    const char *const pinch[] = {"........", "........", "........",
                                 "....#...", "..###...", "..#.....",
                                 "........", "........"};
    m = mask_from(pinch, 8, &w);
    for (int hh = 0; hh < 4; hh++)
    {
        TAP_EQ(trace_mask(m, w, 8, (wm_heuristic)hh, &r, &st), WM_OK,
               "pinch, %s", HNAME[hh]);
        TAP_EQ(st.pinches, 1, "one pinch");
        TAP_EQ(st.cuts, 1, "one half pixel cut");
        TAP_EQ(r.nrings, 1, "one ring keeps the pixel");
        TAP_OK(ring_has(&r, (wm_pt){3 * WM_Q, 3 * WM_Q}),
               "the pinch pixel is its vertex");
        TAP_EQ(check_all(&r, m, w, 8, &st), 0, "valid: the rings do not touch");
    }
    free(m);

    /* a hole touching the shore at a pixel, and a pinch on the block
     * square */
    const char *const hole[] = {"#########", "#########", "##....###",
                                "##.....##", "##....#.#", "#####.###",
                                "#########", "#########"};
    m = mask_from(hole, 8, &w);
    for (int hh = 0; hh < 4; hh++)
    {
        TAP_EQ(trace_mask(m, w, 8, (wm_heuristic)hh, &r, &st), WM_OK,
               "hole touching the shore, %s", HNAME[hh]);
        TAP_EQ(check_all(&r, m, w, 8, &st), 0, "valid");
    }
    free(m);
    const char *const bpinch[] = {"......", "......", "##....",
                                  "#.....", "##....", "......"};
    m = mask_from(bpinch, 6, &w);
    TAP_EQ(trace_mask(m, w, 6, WM_HEUR_CLOSEST, &r, &st), WM_OK,
           "a pinch on the block square");
    TAP_EQ(st.pinches, 1, "one pinch");
    TAP_EQ(r.nrings, 1, "one ring");
    TAP_OK(ring_has(&r, (wm_pt){0, 2 * WM_Q}),
           "the block-square pinch pixel stays a vertex");
    TAP_EQ(check_all(&r, m, w, 6, &st), 0, "valid");
    free(m);
    wm_rings_free(&r);
}

static void test_contract(void)
{
    wm_rings r = {0};
    uint8_t c[9] = {0, 0, 0, 0, 1, 0, 0, 0, 0}; /* Inside where Border due */
    TAP_EQ(wm_paper_trace(c, 3, 3, WM_HEUR_CLOSEST, &r, NULL, NULL),
           WM_ERR_INVALID, "a grid that is not eroded is refused");
    c[4] = 3;
    TAP_EQ(wm_paper_trace(c, 3, 3, WM_HEUR_CLOSEST, &r, NULL, NULL),
           WM_ERR_INVALID, "an unknown class is refused");
    c[4] = WM_PAPER_BORDER;
    TAP_EQ(wm_paper_trace(c, 3, 3, (wm_heuristic)7, &r, NULL, NULL),
           WM_ERR_INVALID, "an unknown heuristic is refused");
    TAP_EQ(wm_paper_trace(c, 3, 3, WM_HEUR_CLOSEST, &r, NULL, NULL), WM_OK,
           "one isolated pixel");
    TAP_EQ(r.nrings, 0, "bounds nothing");
    TAP_EQ(wm_paper_trace(c, 0, 3, WM_HEUR_CLOSEST, &r, NULL, NULL),
           WM_ERR_INVALID, "an empty grid is refused");
    wm_rings_free(&r);
}

/* Random grids: smooth blobs (thresholded sums of bumps) and pure noise. */
static void test_random(void)
{
    enum
    {
        N = 48
    };
    static uint8_t m[N * N];
    wm_rings r = {0}, r2 = {0};
    wm_paper_stats st, st2;
    int bad[4] = {0}, det = 0, cw_exact = 0, tried = 0;
    size_t pinches = 0, rings = 0;
    for (int trial = 0; trial < 160; trial++)
    {
        const int noise = trial % 4 == 3;
        if (noise)
        {
            const uint32_t p = 30 + rnd() % 40; /* percent water */
            for (int i = 0; i < N * N; i++)
                m[i] = rnd() % 100 < p;
        }
        else
        {
            float v[N * N];
            for (int i = 0; i < N * N; i++)
                v[i] = 0;
            const int nb = 3 + (int)(rnd() % 10);
            for (int b = 0; b < nb; b++)
            {
                const float cx = (float)(rnd() % (N + 10)) - 5;
                const float cy = (float)(rnd() % (N + 10)) - 5;
                const float rad = 2 + (float)(rnd() % 90) / 10;
                for (int y = 0; y < N; y++)
                    for (int x = 0; x < N; x++)
                    {
                        const float dx = (float)x - cx, dy = (float)y - cy;
                        const float q = 1 - (dx * dx + dy * dy) / (rad * rad);
                        if (q > 0)
                            v[y * N + x] += q;
                    }
            }
            const float lvl = 0.1f + (float)(rnd() % 50) / 100;
            for (int i = 0; i < N * N; i++)
                m[i] = v[i] > lvl;
        }
        for (int hh = 0; hh < 4; hh++)
        {
            tried++;
            if (trace_mask(m, N, N, (wm_heuristic)hh, &r, &st) != WM_OK)
            {
                bad[hh]++;
                continue;
            }
            bad[hh] += check_all(&r, m, N, N, &st) != 0;
            pinches += st.pinches;
            rings += r.nrings;
            if (hh == WM_HEUR_DIRECTIONAL_CW)
                cw_exact += st.shortcuts == 0;
            trace_mask(m, N, N, (wm_heuristic)hh, &r2, &st2);
            det += !rings_equal(&r, &r2);
        }
    }
    for (int hh = 0; hh < 4; hh++)
        TAP_EQ(bad[hh], 0, "random grids valid with %s", HNAME[hh]);
    TAP_EQ(det, 0, "deterministic: the same rings twice");
    TAP_EQ(cw_exact, tried / 4, "DIRECTIONAL_CW never cuts a corner");
    TAP_OK(pinches > 0, "random grids exercised pinches (%zu)", pinches);
    TAP_OK(rings > 500, "and many rings (%zu)", rings);
    wm_rings_free(&r);
    wm_rings_free(&r2);
}

/* Reference classes of a field, sample by sample through wm_field_at. */
static int classify_matches(const wm_field *f)
{
    const size_t n = (size_t)f->w * (size_t)f->h;
    uint8_t *a = malloc(n), *b = malloc(n);
    wm_paper_classify(f, a, NULL);
    for (int32_t r = 0; r < f->h; r++)
        for (int32_t c = 0; c < f->w; c++)
            b[(size_t)r * (size_t)f->w + (size_t)c] =
                wm_field_at(f, c, r) <= WM_PAPER_LEVEL;
    wm_paper_square_rules(b, f->w, f->h);
    wm_paper_erode(b, f->w, f->h);
    const int same = !memcmp(a, b, n);
    free(a);
    free(b);
    return same;
}

/* The water mask of a field (for check_all). */
static uint8_t *mask_of(const wm_field *f)
{
    uint8_t *m = malloc((size_t)f->w * (size_t)f->h);
    for (int32_t r = 0; r < f->h; r++)
        for (int32_t c = 0; c < f->w; c++)
            m[(size_t)r * (size_t)f->w + (size_t)c] =
                wm_field_at(f, c, r) <= WM_PAPER_LEVEL;
    wm_paper_square_rules(m, f->w, f->h);
    return m;
}

static wm_i128 total_area2(const wm_rings *r)
{
    wm_i128 a = 0;
    for (size_t i = 0; i < r->nrings; i++)
        a += wm_ring_area2(r->pts + r->start[i], wm_rings_len(r, i));
    return a;
}

static int has_edge(const wm_rings *r, wm_pt a, wm_pt b)
{
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t n = wm_rings_len(r, i);
        const wm_pt *p = r->pts + r->start[i];
        for (size_t k = 0; k < n; k++)
            if (wm_pt_eq(p[k], a) && wm_pt_eq(p[(k + 1) % n], b))
                return 1;
    }
    return 0;
}

/* Vertices of `a` on the line x == xa that lie strictly inside an edge of
 * `b` (b shifted by dx): T-junctions. */
static int t_junctions(const wm_rings *a, int32_t xa, const wm_rings *b,
                       int32_t dx)
{
    int bad = 0;
    for (size_t k = 0; k < a->npts; k++)
    {
        if (a->pts[k].x != xa)
            continue;
        const wm_pt p = {a->pts[k].x - dx, a->pts[k].y};
        for (size_t i = 0; i < b->nrings; i++)
        {
            const size_t n = wm_rings_len(b, i);
            const wm_pt *q = b->pts + b->start[i];
            for (size_t e = 0; e < n; e++)
                bad += wm_on_segment(q[e], q[(e + 1) % n], p) &&
                       !wm_pt_eq(q[e], p) && !wm_pt_eq(q[(e + 1) % n], p);
        }
    }
    return bad;
}

/* The ring with a vertex in the box [x0, x1] x [y0, y1] (pixels), or -1. */
static int ring_near(const wm_rings *r, int x0, int x1, int y0, int y1)
{
    for (size_t i = 0; i < r->nrings; i++)
        for (size_t k = r->start[i]; k < r->start[i + 1]; k++)
        {
            const wm_pt p = r->pts[k];
            if (p.x >= x0 * WM_Q && p.x <= x1 * WM_Q && p.y >= y0 * WM_Q &&
                p.y <= y1 * WM_Q)
                return (int)i;
        }
    return -1;
}

static void test_scene(void)
{
    enum
    {
        N = 64
    };
    const int32_t S = N * WM_Q;
    wm_scene s;
    su_init(&s, N);
    const double river[] = {3.3, 20.7, 60.1, 35.2, 64.0, 35.9, 120.4, 50.3};
    su_river(&s, river, 4, 3.1);
    /* one pixel wide: shallow across both blocks, and at 45 degrees */
    const double thin[] = {-5, 12.3, 135, 4.6};
    su_river(&s, thin, 2, 0.5);
    const double diag[] = {-5, 60, 35, 100};
    su_river(&s, diag, 2, 0.5);
    const double lake[] = {40, 60, 100, 62,  98, 120, 42, 118,
                           60, 80, 60,  100, 80, 100, 80, 80};
    const int counts[] = {4, 4};
    su_lake(&s, lake, counts, 2);
    su_finish(&s);

    wm_field fa, fb, fab;
    wm_rings ra = {0}, rb = {0}, rab = {0};
    wm_paper_stats sa, sb, sab;
    TAP_EQ(wm_field_compute(&s, 0, 0, N + 1, 2 * N + 1, NULL, &fa, NULL), WM_OK,
           "field of blocks (0,0)-(0,1)");
    TAP_EQ(wm_field_compute(&s, N, 0, N + 1, 2 * N + 1, NULL, &fb, NULL), WM_OK,
           "field of blocks (1,0)-(1,1)");
    TAP_EQ(wm_field_compute(&s, 0, 0, 2 * N + 1, 2 * N + 1, NULL, &fab, NULL),
           WM_OK, "field of both");
    TAP_OK(classify_matches(&fa) && classify_matches(&fb) &&
               classify_matches(&fab),
           "tile-wise classes equal sample-wise classes");
    uint8_t *ma = mask_of(&fa), *mb = mask_of(&fb), *mab = mask_of(&fab);

    for (int hh = 0; hh < 4; hh++)
    {
        const wm_heuristic h = (wm_heuristic)hh;
        TAP_EQ(wm_paper_extract(&fa, h, &ra, &sa, NULL), WM_OK, "extract A, %s",
               HNAME[hh]);
        TAP_EQ(wm_paper_extract(&fb, h, &rb, &sb, NULL), WM_OK, "extract B");
        TAP_EQ(wm_paper_extract(&fab, h, &rab, &sab, NULL), WM_OK,
               "extract A+B");
        TAP_EQ(check_all(&ra, ma, fa.w, fa.h, &sa) +
                   check_all(&rb, mb, fb.w, fb.h, &sb) +
                   check_all(&rab, mab, fab.w, fab.h, &sab),
               0, "scene rings valid, border water samples are vertices");
        TAP_EQ(sa.cuts + sb.cuts + sab.cuts, 0, "no pinch in this scene");
        int shared = 0;
        for (size_t k = 0; k < ra.npts; k++)
            shared += ra.pts[k].x == S;
        TAP_OK(shared > 10 && t_junctions(&ra, S, &rb, -S) == 0 &&
                   t_junctions(&rb, 0, &ra, S) == 0,
               "shared column: %d vertices, no T-junction", shared);
        /* one-pixel rivers stay one polygon */
        const int l = ring_near(&rab, 0, 0, 9, 15);
        TAP_OK(l >= 0 && l == ring_near(&rab, 2 * N, 2 * N, 2, 8),
               "a shallow one-pixel river crosses both blocks in one piece");
        const int d = ring_near(&rab, 0, 0, 62, 68);
        TAP_OK(d >= 0 && d == ring_near(&rab, 33, 37, 98, 102),
               "a diagonal one-pixel river is one polygon to its end");
        if (h != WM_HEUR_DIRECTIONAL_CW)
            continue;
        /* the exact boundary: water adds up, column edges match */
        TAP_OK(total_area2(&ra) + total_area2(&rb) == total_area2(&rab),
               "the two blocks' water adds up to the water of both");
        int bad = 0;
        for (int32_t r = 0; r + 1 < fa.h; r++)
        {
            const wm_pt p = {S, r * WM_Q}, q = {S, (r + 1) * WM_Q};
            const int ea = has_edge(&ra, p, q);
            const int eb = has_edge(&rb, (wm_pt){0, q.y}, (wm_pt){0, p.y});
            bad += has_edge(&rab, p, q) != (ea && !eb);
            bad += has_edge(&rab, q, p) != (eb && !ea);
        }
        TAP_EQ(bad, 0,
               "a column edge in one block only is a shoreline of "
               "both, one in both is interior");
    }
    free(ma);
    free(mb);
    free(mab);
    wm_field_free(&fa);
    wm_field_free(&fb);
    wm_field_free(&fab);
    wm_rings_free(&ra);
    wm_rings_free(&rb);
    wm_rings_free(&rab);
    wm_scene_free(&s);
}

int main(void)
{
    test_classify();
    test_erode();
    test_basic();
    test_heuristics();
    test_thin_and_pinch();
    test_contract();
    test_random();
    test_scene();
    return TAP_DONE();
}
