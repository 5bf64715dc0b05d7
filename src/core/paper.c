/*
 * paper.c - the paper's extraction (METHOD=PAPER): pixel classes, erosion,
 * and the walk over Border pixels with heuristics and backtracking.
 *
 * Reference: R. N. Menegais, F. P. Franzin, L. S. Kaufmann, C. T. Pozzer,
 * "A Raster-based Approach for Waterbodies Mesh Generation", GRAPP 2021,
 * section 4 (texture generation: classes, erosion, width compensation) and
 * section 5 (polygon extraction: walk, heuristics, backtracking).
 *
 * 1. Classes. The paper classifies pixels Inside (fully in water), Border
 * (meeting the shoreline) or Outside, and erodes the Inside set. Its width
 * compensation (rivers widened by 2 pixels, lake Border pixels one pixel
 * out) moves every shoreline one pixel towards land: d' = d - 1 for our
 * signed field d (pixels, negative in water). "Fully inside" for a pixel
 * of unit side centred on its sample is d' <= -1/2 (exact for a straight
 * shoreline along a pixel side). Hence the rule:
 *
 *     water  <=>  d <= WM_PAPER_LEVEL = +1/2 pixel.
 *
 * Why: the eroded border (below) is the set of water samples with a land
 * 4-neighbour. The field is 1-Lipschitz, so along a shoreline parallel to
 * the grid such a sample has d in (-1/2, +1/2], uniformly as the shoreline
 * slides across a pixel: mean 0, the vertices sit on the true shoreline
 * (at 45 degrees d is in (1/2 - 1/sqrt2, 1/2], mean +0.15). A level of 0
 * (sample inside) would put them half a pixel inside on average, +1 half a
 * pixel outside. A river at least one pixel wide always has two 4-adjacent
 * water samples across it, hence area. Stored float values are compared as
 * they are, so two blocks sharing a border column classify it identically.
 *
 * 1b. Seams (our addition; the paper forces Border pixels on the block
 * square and stops there). Which pieces of a block side the water covers
 * must not depend on the samples off the side, which the two blocks
 * sharing it do not share. So, on the water mask, before the erosion
 * (wm_paper_square_rules): a water sample of a side whose neighbours along
 * the side are land becomes land, and every water sample of a side (corners
 * of the square excepted) makes its inward neighbour water. Then the cell
 * between two consecutive water samples of a side always holds a water
 * triangle with that side, no sample of the square is a pinch (section 4),
 * and both blocks cover exactly the pieces between consecutive water
 * samples, with the same vertices: at most one pixel of water is added
 * along a side where the shore leaves it.
 *
 * 2. Erosion (Eq. 2). A is the water set, A' its part off the block
 * square, B the 3x3 cross: T = (A' eroded by B) XOR A' is the set of water
 * samples of A' with a land 4-neighbour; T is padded with A's border,
 * where every water sample is Border (the paper's forced Border pixels:
 * the ring runs along the block square through every water sample there,
 * the same samples in both blocks). Boundary condition: the cross at a
 * sample next to the square reads the square's samples from A; eroding A'
 * on its own would mark a second line of Border pixels along every block
 * edge, bounding no water.
 *
 * 3. The region. The rings bound an exact region R made of the "water
 * triangles" of the sample grid: a cell (the square between four samples)
 * whose four corners are water is water, a cell with three water corners
 * holds the triangle of those three, other cells hold nothing. R's
 * boundary runs along cell sides and diagonals (the paper's 8-neighbour
 * steps) through samples, and its vertices are exactly the Border samples
 * that are a corner of a water triangle: a water sample whose four
 * 4-neighbours are water is interior to R, one with a land 4-neighbour or
 * on the block square is not. Blocks own disjoint cells, so the regions of
 * two neighbouring blocks meet exactly along their shared column.
 * Border pixels that are a corner of no water triangle (an isolated
 * sample, a one-pixel thread, the tip of a one-pixel spur) bound no area:
 * the paper's walk would make zero-area out-and-back paths of them. They
 * are dropped (wm_paper_stats.dropped).
 *
 * 4. Pinches: the fix the paper needs (it only says that a revisited pixel
 * is "marked to not be chosen again"). Around a sample the water triangles
 * cover some of its 8 sectors of 45 degrees (sector k lies between the
 * directions k and k + 1: 0 = E, 1 = NE, ..., counter-clockwise). Where
 * they form two or more separate runs, R touches itself at that sample
 * (two blobs meeting diagonally, a hole touching the shore) and its
 * boundary would pass the sample twice: rings touching. Following the
 * paper's rule that a pixel belongs to one polygon, the run with the most
 * sectors keeps the sample (ties: the first counter-clockwise from E; but a
 * run holding a cell with a water piece of a block square side comes
 * first, so no cut uncovers a piece of a side: section 1b) and
 * the sample is cut out of the cells of the other runs: there it counts as
 * land, which removes exactly one half-pixel triangle per cell (a water
 * cell keeps the triangle of its other three corners, a triangle
 * vanishes). A cut can make a neighbour a boundary vertex (it becomes
 * Border) or a pinch, so the corners of cut cells are examined again, until
 * no sample is a pinch. A cut removes a (cell, corner) pair for good, so
 * this ends after at most 4 cuts per cell. Then every boundary sample has
 * one run: one incoming and one outgoing boundary edge. Cuts only remove
 * water and never change whether a sample is water, so both blocks still
 * classify a shared column alike. The cells of one sample holding a water
 * piece of a side always lie in one run (the side sample between them is
 * water), so that run can be kept. (Ring edges join 8-neighbours, so no
 * vertex of one block can lie inside an edge of the other.)
 *
 * 5. The walk. Start at the first unvisited Border pixel in row-major order
 * (bottom row first) with a virtual last segment heading E. Each node of
 * the path lists its candidate next pixels ranked by the heuristic; a
 * visited pixel is never chosen again, except the start; a dead end
 * backtracks to the last node with a candidate left (the paper's graph);
 * the ring closes when the start is the candidate taken (closing
 * threshold: one step, sqrt 2 pixel) and the path has >= 3 pixels and a
 * non-zero area (exact). The paper's candidates are all Border
 * 8-neighbours, which may jump across a thin river to the other bank;
 * here a Border 8-neighbour is a candidate only when it passes an exact
 * test, which is what makes the output valid:
 *   - the boundary step: the current pixel's outgoing boundary edge (along
 *     the first sector of its run: water on the left, land on the right);
 *   - the shortcut: the pixel after that one, skipping the boundary pixel v
 *     in between, when the boundary turns left at v (a convex corner of the
 *     water), both pixels are 8-neighbours, and v is neither the start nor
 *     on the block square. This is the corner-cutting path of the paper's
 *     Fig. 5; it removes the half-pixel triangle at v, and v is dropped.
 * The heuristics rank relative to the last segment: CLOSEST (4-neighbours
 * before diagonals, then the smaller turn, then left), DIRECTIONAL_CW (the
 * most clockwise turn first, a reversal last), DIRECTIONAL_CCW (the most
 * counter-clockwise first, a reversal last), LEAST_ANGLE (the smaller turn,
 * then left). A shortcut always turns left of the boundary step, so
 * DIRECTIONAL_CW never cuts (it traces R's boundary exactly) and
 * DIRECTIONAL_CCW cuts wherever it may; CLOSEST keeps a square corner
 * (boundary step to a 4-neighbour, shortcut to a diagonal) and cuts a
 * half-pixel tooth (boundary step diagonal, shortcut to a 4-neighbour),
 * the smaller turn deciding when both are 4-neighbours; LEAST_ANGLE cuts
 * where the shortcut turns less. A dead end (Fig. 6) happens when a
 * shortcut brings the walk back to the start after two pixels: it
 * backtracks to the branching node and takes the boundary step.
 *
 * Why the rings are valid. Boundary edges join 8-neighbours along cell
 * sides or diagonals, so two edges can only meet at samples, or cross as
 * the two diagonals of one cell; R's boundary holds at most one diagonal
 * per cell. After the pinch cuts each boundary sample has one incoming and
 * one outgoing edge, so the boundary is a set of disjoint simple closed
 * curves with water on the left (outer rings counter-clockwise, holes
 * clockwise; no orientation fix-up). A shortcut a -> b past v is a cell
 * side, or the diagonal of a water cell whose other diagonal would need v
 * on a ring; a and b have no other passage, and the new edge could only
 * coincide with an existing one if the ring were the triangle (a, v, b),
 * which the >= 3 pixels rule rejects. So rings stay simple and disjoint.
 * From an untouched start the walk follows its boundary curve back to the
 * start, so a walk fails only from a pixel skipped by a shortcut.
 *
 * Complexity: O(w * h) for the classes and the row-major scans, with one
 * byte per sample of work memory; O(boundary pixels + cuts) for the pinch
 * pass and the walk, which backtracks at most one step per start.
 *
 * Robustness: after the float comparison of stored values against 1/2,
 * everything is integer arithmetic on sample indices: no epsilon. A failed
 * invariant returns WM_ERR_INTERNAL.
 */
#include "paper.h"

#include <stdlib.h>
#include <string.h>

/* A work byte: bits 0-1 the class, bit 2 "seen" (on the path or a ring, or
 * given up), bits 4 + q: the sample is cut out of its quadrant-q cell. */
enum
{
    CLS = 3u,
    SEEN = 4u,
    CUT_SHIFT = 4
};

/* Directions, counter-clockwise from E (y up). */
static const int8_t DX[8] = {1, 1, 0, -1, -1, -1, 0, 1};
static const int8_t DY[8] = {0, 1, 1, 1, 0, -1, -1, -1};

/* Quadrant q of a sample (NE, NW, SW, SE) is the cell whose lower-left
 * sample is at this offset; the sample is that cell's corner q, corners
 * numbered 0 (i, j), 1 (i+1, j), 2 (i+1, j+1), 3 (i, j+1), i.e.
 * counter-clockwise, so corner q + 1 lies in direction 2q, corner q + 2 in
 * direction 2q + 1 and corner q + 3 in direction 2q + 2 from the sample. */
static const int8_t QX[4] = {0, -1, -1, 0};
static const int8_t QY[4] = {0, 0, -1, -1};
static const int8_t CX[4] = {0, 1, 1, 0};
static const int8_t CY[4] = {0, 0, 1, 1};

static const uint8_t POP4[16] = {0, 1, 1, 2, 1, 2, 2, 3,
                                 1, 2, 2, 3, 2, 3, 3, 4};

typedef struct
{
    uint8_t *g;
    int32_t w, h;
} grid;

static size_t at(const grid *G, int32_t c, int32_t r)
{
    return (size_t)r * (size_t)G->w + (size_t)c;
}

static int on_square(const grid *G, int32_t c, int32_t r)
{
    return c == 0 || r == 0 || c == G->w - 1 || r == G->h - 1;
}

/* The first sample at or after u whose class is Border (the only class
 * with bit 1 set), or n; skips eight bytes at a time. */
static size_t next_border(const uint8_t *g, size_t u, size_t n)
{
    const uint64_t ones = UINT64_C(0x0202020202020202);
    for (; u + 8 <= n; u += 8)
    {
        uint64_t x;
        memcpy(&x, g + u, sizeof x);
        if (x & ones)
            break;
    }
    while (u < n && !(g[u] & WM_PAPER_BORDER))
        u++;
    return u;
}

/* Corners of cell (i, j) that count as water: water samples not cut out of
 * this cell. Bit k for corner k. */
static unsigned cell_water(const grid *G, int32_t i, int32_t j)
{
    unsigned e = 0;
    for (unsigned k = 0; k < 4; k++)
    {
        const uint8_t v = G->g[at(G, i + CX[k], j + CY[k])];
        if ((v & CLS) != WM_PAPER_OUTSIDE && !((v >> (CUT_SHIFT + k)) & 1u))
            e |= 1u << k;
    }
    return e;
}

/* The sectors of sample (c, r) covered by water triangles: bit k for the
 * sector between directions k and k + 1. */
static unsigned sectors(const grid *G, int32_t c, int32_t r)
{
    unsigned m = 0;
    for (unsigned q = 0; q < 4; q++)
    {
        const int32_t i = c + QX[q], j = r + QY[q];
        if (i < 0 || j < 0 || i >= G->w - 1 || j >= G->h - 1)
            continue;
        const unsigned e = cell_water(G, i, j);
        if (!((e >> q) & 1u) || POP4[e] < 3)
            continue;
        unsigned s = 3u; /* full cell, or the diagonal corner missing */
        if (POP4[e] == 3)
        {
            const unsigned miss = ~e & 15u;
            if (miss == 1u << ((q + 1) & 3u))
                s = 2u; /* triangle (sample, diagonal, corner q + 3) */
            else if (miss == 1u << ((q + 3) & 3u))
                s = 1u; /* triangle (sample, corner q + 1, diagonal) */
        }
        m |= s << (2 * q);
    }
    return m;
}

/* The runs of a sector mask other than 0 and 0xFF: first sector and length
 * of each, counter-clockwise from E. Returns their number (<= 4). */
static unsigned runs(unsigned m, unsigned *first, unsigned *len)
{
    unsigned n = 0;
    for (unsigned s = 0; s < 8; s++)
        if (((m >> s) & 1u) && !((m >> ((s + 7) & 7u)) & 1u))
        {
            unsigned l = 0;
            while (l < 8 && ((m >> ((s + l) & 7u)) & 1u))
                l++;
            first[n] = s;
            len[n] = l;
            n++;
        }
    return n;
}

typedef struct
{
    size_t *a;
    size_t n, cap;
} stack;

static int stack_push(stack *s, size_t v)
{
    if (s->n == s->cap)
    {
        const size_t nc = s->cap ? 2 * s->cap : 256;
        size_t *p = realloc(s->a, nc * sizeof *p);
        if (!p)
            return 0;
        s->a = p;
        s->cap = nc;
    }
    s->a[s->n++] = v;
    return 1;
}

/* Whether quadrant q of sample (c, r) is a cell with a side on the block
 * square whose two corners are water: the cell's triangle covers that piece
 * of the side, which the neighbouring block covers too. */
static int seam_cell(const grid *G, int32_t c, int32_t r, unsigned q)
{
    const int32_t i = c + QX[q], j = r + QY[q];
    if (i < 0 || j < 0 || i >= G->w - 1 || j >= G->h - 1)
        return 0;
    const unsigned e = cell_water(G, i, j);
    return (j == 0 && (e & 3u) == 3u) || (j == G->h - 2 && (e & 12u) == 12u) ||
           (i == 0 && (e & 9u) == 9u) || (i == G->w - 2 && (e & 6u) == 6u);
}

/* Examines sample u: promotes it to Border when it is a boundary vertex,
 * and resolves it when it is a pinch (section 4 of the header), pushing the
 * corners of the cells cut. Returns 0 when out of memory. */
static int settle(grid *G, size_t u, stack *todo, wm_paper_stats *st)
{
    uint8_t *const v = &G->g[u];
    if ((*v & CLS) == WM_PAPER_OUTSIDE)
        return 1;
    const int32_t c = (int32_t)(u % (size_t)G->w);
    const int32_t r = (int32_t)(u / (size_t)G->w);
    const unsigned m = sectors(G, c, r);
    if (m == 0 || m == 0xFFu)
        return 1;
    if ((*v & CLS) == WM_PAPER_INSIDE)
        *v = (uint8_t)((*v & ~CLS) | WM_PAPER_BORDER);
    unsigned first[4], len[4];
    const unsigned n = runs(m, first, len);
    if (n < 2)
        return 1;
    /* the run to keep: one holding a cell whose side on the block square is
     * water at both ends (cutting it would uncover that piece of the side
     * in this block only, section 1b); else the longest */
    unsigned keep = 0;
    int keep_seam = 0;
    for (unsigned k = 0; k < n; k++)
    {
        int seam = 0;
        for (unsigned l = 0; l < len[k]; l++)
            seam |= seam_cell(G, c, r, ((first[k] + l) & 7u) >> 1);
        if (k == 0 || (seam && !keep_seam) ||
            (seam == keep_seam && len[k] > len[keep]))
        {
            keep = k;
            keep_seam = seam;
        }
    }
    st->pinches++;
    for (unsigned k = 0; k < n; k++)
    {
        if (k == keep)
            continue;
        for (unsigned l = 0; l < len[k]; l++)
        {
            const unsigned q = ((first[k] + l) & 7u) >> 1;
            if ((*v >> (CUT_SHIFT + q)) & 1u)
                continue;
            *v = (uint8_t)(*v | (1u << (CUT_SHIFT + q)));
            st->cuts++;
            const int32_t i = c + QX[q], j = r + QY[q];
            for (unsigned k2 = 0; k2 < 4; k2++)
                if (k2 != q && !stack_push(todo, at(G, i + CX[k2], j + CY[k2])))
                    return 0;
        }
    }
    return 1;
}

/* Cuts every pinch; afterwards each boundary sample has one run. */
static wm_status resolve_pinches(grid *G, wm_paper_stats *st, const wm_ctx *ctx)
{
    wm_status status = WM_OK;
    stack todo = {0};
    const size_t n = (size_t)G->w * (size_t)G->h;
    for (size_t u = next_border(G->g, 0, n); u < n;
         u = next_border(G->g, u + 1, n))
    {
        if (!settle(G, u, &todo, st))
            goto nomem;
        while (todo.n)
            if (!settle(G, todo.a[--todo.n], &todo, st))
                goto nomem;
    }
    goto cleanup;
nomem:
    status = wm_fail(ctx, WM_ERR_NOMEM, "paper: out of memory (pinches)");
cleanup:
    free(todo.a);
    return status;
}

/* The outgoing boundary edge of boundary sample (c, r): the direction of
 * the first sector of its only run, or -1 when it has not exactly one. */
static int out_dir(const grid *G, int32_t c, int32_t r)
{
    const unsigned m = sectors(G, c, r);
    unsigned first[4], len[4];
    if (m == 0 || m == 0xFFu || runs(m, first, len) != 1)
        return -1;
    return (int)first[0];
}

/* Ranking key of a step in direction k after a segment heading hin; the
 * smaller key is tried first. */
static int rank_key(wm_heuristic heur, unsigned hin, unsigned k)
{
    int t = (int)((k + 8 - hin) & 7u); /* turn in 45 degree steps */
    if (t > 4)
        t -= 8; /* -3 .. 4: positive turns left, 4 reverses */
    const int a = t < 0 ? -t : t;
    switch (heur)
    {
    case WM_HEUR_CLOSEST:
        return (int)(k & 1u) * 100 + a * 10 + (t < 0);
    case WM_HEUR_DIRECTIONAL_CW:
        return t == 4 ? 100 : t + 3;
    case WM_HEUR_DIRECTIONAL_CCW:
        return t == 4 ? 100 : 3 - t;
    default: /* WM_HEUR_LEAST_ANGLE */
        return a * 10 + (t < 0);
    }
}

static unsigned dir_of(int dx, int dy)
{
    static const uint8_t D[9] = {5, 6, 7, 4, 0, 0, 3, 2, 1};
    return D[(dy + 1) * 3 + (dx + 1)];
}

/* A node of the walk's path. */
typedef struct
{
    size_t px;       /* pixel */
    size_t to[2];    /* admissible next pixels, in ranked order */
    uint8_t dir[2];  /* their directions */
    uint8_t cut[2];  /* 1: a shortcut past the boundary step's pixel */
    uint8_t n, next; /* candidates, and the next one to try */
    uint8_t hin;     /* heading of the segment that reached px */
    uint8_t by_cut;  /* px was reached by a shortcut */
} node;

typedef struct
{
    node *a;
    size_t n, cap;
} path;

/* Fills the candidates of node t (see "The walk" in the header). Returns 0
 * when px has no single outgoing edge (an invariant failure). */
static int candidates(const grid *G, node *t, size_t start, wm_heuristic heur,
                      wm_paper_stats *st)
{
    const int32_t c = (int32_t)(t->px % (size_t)G->w);
    const int32_t r = (int32_t)(t->px / (size_t)G->w);
    t->n = t->next = 0;
    const int d = out_dir(G, c, r);
    if (d < 0)
        return 0;
    const int32_t vc = c + DX[d], vr = r + DY[d];
    const size_t v = at(G, vc, vr);
    if (v == start || !(G->g[v] & SEEN))
    {
        t->to[t->n] = v;
        t->dir[t->n] = (uint8_t)d;
        t->cut[t->n++] = 0;
    }
    if (v != start && !(G->g[v] & SEEN) && !on_square(G, vc, vr))
    {
        const int e = out_dir(G, vc, vr);
        if (e < 0)
            return 0;
        const int32_t bc = vc + DX[e], br = vr + DY[e];
        const int dx = bc - c, dy = br - r;
        const size_t b = at(G, bc, br);
        /* left turn at v: cross product of (v - p) and (b - v) */
        const int turn = DX[d] * DY[e] - DY[d] * DX[e];
        if (dx >= -1 && dx <= 1 && dy >= -1 && dy <= 1 && (dx || dy) &&
            turn > 0 && (b == start || !(G->g[b] & SEEN)))
        {
            t->to[t->n] = b;
            t->dir[t->n] = (uint8_t)dir_of(dx, dy);
            t->cut[t->n++] = 1;
        }
    }
    if (t->n == 2)
    {
        st->branches++;
        if (rank_key(heur, t->hin, t->dir[1]) <
            rank_key(heur, t->hin, t->dir[0]))
        {
            const size_t to = t->to[0];
            const uint8_t dd = t->dir[0], cc = t->cut[0];
            t->to[0] = t->to[1];
            t->dir[0] = t->dir[1];
            t->cut[0] = t->cut[1];
            t->to[1] = to;
            t->dir[1] = dd;
            t->cut[1] = cc;
        }
    }
    return 1;
}

/* Emits the path as a ring if its area is not zero (closing_cut: the step
 * back to the start is a shortcut); returns 1 if emitted, 0 if not, -1 when
 * out of memory. */
static int emit(const grid *G, const path *P, int closing_cut, wm_rings *out,
                wm_paper_stats *st)
{
    const size_t base = out->npts;
    size_t cuts = (size_t)closing_cut;
    for (size_t i = 0; i < P->n; i++)
    {
        const size_t px = P->a[i].px;
        const wm_pt p = {(int32_t)(px % (size_t)G->w) * WM_Q,
                         (int32_t)(px / (size_t)G->w) * WM_Q};
        if (wm_rings_push(out, p) != WM_OK)
            return -1;
        cuts += P->a[i].by_cut;
    }
    if (wm_ring_area2(out->pts + base, P->n) == 0)
    {
        out->npts = base;
        return 0;
    }
    if (wm_rings_close(out) != WM_OK)
        return -1;
    st->rings++;
    st->shortcuts += cuts;
    return 1;
}

/* Walks from boundary pixel s; *closed tells whether a ring came out. */
static wm_status walk(grid *G, size_t s, wm_heuristic heur, path *P,
                      size_t budget, wm_rings *out, wm_paper_stats *st,
                      int *closed, const wm_ctx *ctx)
{
    wm_status status = WM_OK;
    *closed = 0;
    P->n = 0;
    if (!P->cap)
    {
        P->a = malloc(256 * sizeof *P->a);
        if (!P->a)
            goto nomem;
        P->cap = 256;
    }
    memset(&P->a[0], 0, sizeof P->a[0]);
    P->a[0].px = s;
    P->a[0].hin = 0; /* virtual last segment heading E */
    if (!candidates(G, &P->a[0], s, heur, st))
        goto internal;
    G->g[s] |= SEEN;
    P->n = 1;
    for (size_t steps = 0; P->n; steps++)
    {
        if (steps > budget)
            goto internal;
        node *t = &P->a[P->n - 1];
        if (t->next == t->n)
        {
            if (P->n == 1)
                goto cleanup;              /* s starts no ring; it stays seen */
            G->g[t->px] &= (uint8_t)~SEEN; /* dead end: back one node */
            P->n--;
            st->backtracks++;
            continue;
        }
        const unsigned k = t->next++;
        const size_t q = t->to[k];
        if (q == s)
        {
            if (P->n < 3)
                continue; /* closing with two pixels: not a ring */
            const int e = emit(G, P, t->cut[k], out, st);
            if (e < 0)
                goto nomem;
            if (e > 0)
            {
                *closed = 1;
                goto cleanup;
            }
            continue;
        }
        node nd;
        memset(&nd, 0, sizeof nd);
        nd.px = q;
        nd.hin = t->dir[k];
        nd.by_cut = t->cut[k];
        if (!candidates(G, &nd, s, heur, st))
            goto internal;
        if (P->n == P->cap)
        {
            node *a = realloc(P->a, 2 * P->cap * sizeof *a);
            if (!a)
                goto nomem;
            P->a = a;
            P->cap *= 2;
        }
        P->a[P->n++] = nd;
        G->g[q] |= SEEN;
    }
internal:
    status = wm_fail(ctx, WM_ERR_INTERNAL,
                     "paper: walk from sample (%d, %d) lost the boundary",
                     (int)(s % (size_t)G->w), (int)(s / (size_t)G->w));
    goto cleanup;
nomem:
    status = wm_fail(ctx, WM_ERR_NOMEM, "paper: out of memory (walk)");
cleanup:
    return status;
}

/* Pinch pass and walk on a work grid (modified). */
static wm_status trace_grid(uint8_t *g, int32_t w, int32_t h, wm_heuristic heur,
                            wm_rings *out, wm_paper_stats *st,
                            const wm_ctx *ctx)
{
    grid G = {g, w, h};
    path P = {0};
    wm_status status = resolve_pinches(&G, st, ctx);
    if (status != WM_OK)
        goto cleanup;
    const size_t n = (size_t)w * (size_t)h;
    const size_t budget = 4 * n + 16; /* a walk never comes near it */
    for (size_t u = next_border(g, 0, n); u < n; u = next_border(g, u + 1, n))
    {
        st->border++;
        if (g[u] & SEEN)
            continue;
        const int32_t c = (int32_t)(u % (size_t)w),
                      r = (int32_t)(u / (size_t)w);
        if (sectors(&G, c, r) == 0)
        {
            g[u] |= SEEN; /* a corner of no water triangle */
            st->dropped++;
            continue;
        }
        int closed;
        status = walk(&G, u, heur, &P, budget, out, st, &closed, ctx);
        if (status != WM_OK)
            goto cleanup;
        st->dropped += !closed;
    }
cleanup:
    free(P.a);
    return status;
}

static wm_status check_size(int32_t w, int32_t h, const wm_ctx *ctx)
{
    if (w < 1 || h < 1 || (int64_t)(w - 1) * WM_Q > WM_LOCAL_MAX ||
        (int64_t)(h - 1) * WM_Q > WM_LOCAL_MAX)
        return wm_fail(ctx, WM_ERR_INVALID,
                       "paper: a grid of %d x %d samples is out of range",
                       (int)w, (int)h);
    return WM_OK;
}

static wm_status check_args(int32_t w, int32_t h, wm_heuristic heur,
                            const wm_ctx *ctx)
{
    if ((unsigned)heur > (unsigned)WM_HEUR_LEAST_ANGLE)
        return wm_fail(ctx, WM_ERR_INVALID, "paper: unknown heuristic %d",
                       (int)heur);
    return check_size(w, h, ctx);
}

/* One interior row of the erosion: out[k] for samples 1 + k of `row`. The
 * restrict-qualified operands let the compiler vectorize without runtime
 * alias checks. */
static void erode_row(uint8_t *restrict out, const uint8_t *restrict dn,
                      const uint8_t *restrict row, const uint8_t *restrict up,
                      int32_t n)
{
    for (int32_t k = 0; k < n; k++)
    {
        const int32_t c = k + 1;
        const unsigned land =
            (row[c - 1] == 0) | (row[c + 1] == 0) | (dn[c] == 0) | (up[c] == 0);
        out[k] = (uint8_t)((row[c] != 0) * (1u + land));
    }
}

void wm_paper_erode(uint8_t *cls, int32_t w, int32_t h)
{
    /* Row r is computed into buf from rows r - 1 (already rewritten, but a
     * rewrite keeps zero and non-zero apart), r and r + 1, then copied
     * back. */
    uint8_t buf[1024];
    for (int32_t r = 0; r < h; r++)
    {
        uint8_t *const row = cls + (size_t)r * (size_t)w;
        if (r == 0 || r == h - 1 || w < 3)
        {
            for (int32_t c = 0; c < w; c++)
                row[c] = row[c] ? WM_PAPER_BORDER : WM_PAPER_OUTSIDE;
            continue;
        }
        const uint8_t *const dn = row - w, *const up = row + w;
        for (int32_t c0 = 1; c0 < w - 1; c0 += (int32_t)sizeof buf)
        {
            const int32_t n = w - 1 - c0 < (int32_t)sizeof buf
                                  ? w - 1 - c0
                                  : (int32_t)sizeof buf;
            erode_row(buf, dn + c0 - 1, row + c0 - 1, up + c0 - 1, n);
            memcpy(row + c0, buf, (size_t)n);
        }
        row[0] = row[0] ? WM_PAPER_BORDER : WM_PAPER_OUTSIDE;
        row[w - 1] = row[w - 1] ? WM_PAPER_BORDER : WM_PAPER_OUTSIDE;
    }
}

/* The seam rules (see the file header, 1b), on the water mask before the
 * erosion. Along each side of the block square, for every sample other
 * than the square's corners:
 *   - a water sample whose two neighbours along the side are land becomes
 *     land (it could bound water in one block and none in the other);
 *   - a water sample makes its inward neighbour (off the square) water.
 * The first rule reads only the side's samples, which both blocks sharing
 * the side hold identically; the second changes only samples off the
 * square. Then the cell between two consecutive water samples of a side
 * holds a water triangle with that side (the corners' pairs too: the other
 * sample's inward neighbour is water), and no square sample is a pinch, so
 * both blocks cover exactly the pieces of the side between consecutive
 * water samples and have the same vertices on it. */
void wm_paper_square_rules(uint8_t *cls, int32_t w, int32_t h)
{
    if (w < 3 || h < 3)
        return;
    /* the four sides: first sample, step along, step inward, length */
    const struct
    {
        size_t first;
        ptrdiff_t along, in;
        int32_t n;
    } side[4] = {
        {0, 1, w, w},                                       /* bottom */
        {(size_t)(h - 1) * (size_t)w, 1, -(ptrdiff_t)w, w}, /* top */
        {0, w, 1, h},                                       /* left */
        {(size_t)(w - 1), w, -1, h},                        /* right */
    };
    for (int k = 0; k < 4; k++)
    {
        uint8_t *const p = cls + side[k].first;
        const ptrdiff_t a = side[k].along;
        for (int32_t i = 1; i < side[k].n - 1; i++)
            if (p[i * a] && !p[(i - 1) * a] && !p[(i + 1) * a])
                p[i * a] = WM_PAPER_OUTSIDE;
    }
    for (int k = 0; k < 4; k++)
    {
        uint8_t *const p = cls + side[k].first;
        const ptrdiff_t a = side[k].along, in = side[k].in;
        for (int32_t i = 1; i < side[k].n - 1; i++)
            if (p[i * a])
                p[i * a + in] = WM_PAPER_INSIDE;
    }
}

wm_status wm_paper_classify(const wm_field *f, uint8_t *cls, const wm_ctx *ctx)
{
    const wm_status st = check_size(f->w, f->h, ctx);
    if (st != WM_OK)
        return st;
    if (!(f->band > WM_PAPER_LEVEL))
        return wm_fail(ctx, WM_ERR_INVALID,
                       "paper: a clamp band of %g pixel cannot tell land "
                       "from the water level %g",
                       (double)f->band, (double)WM_PAPER_LEVEL);
    /* tile by tile, with wm_field_at's choice of tile for shared samples:
     * uniform tiles need no value */
    for (int32_t r = 0; r < f->h; r++)
    {
        int32_t ty = r > 0 ? (r - 1) / WM_TILE : 0;
        if (ty >= f->nty)
            ty = f->nty - 1;
        uint8_t *const row = cls + (size_t)r * (size_t)f->w;
        for (int32_t tx = 0; tx < f->ntx; tx++)
        {
            const int32_t c0 = tx == 0 ? 0 : tx * WM_TILE + 1;
            const int32_t c1 = tx == f->ntx - 1 ? f->w - 1 : (tx + 1) * WM_TILE;
            if (c0 > c1)
                continue;
            const uint8_t kind =
                f->kind[(size_t)ty * (size_t)f->ntx + (size_t)tx];
            if (kind == WM_TILE_MIXED)
            {
                for (int32_t c = c0; c <= c1; c++)
                    row[c] = wm_field_at(f, c, r) <= WM_PAPER_LEVEL
                                 ? WM_PAPER_INSIDE
                                 : WM_PAPER_OUTSIDE;
            }
            else
                memset(row + c0,
                       kind == WM_TILE_WATER ? WM_PAPER_INSIDE
                                             : WM_PAPER_OUTSIDE,
                       (size_t)(c1 - c0 + 1));
        }
    }
    wm_paper_square_rules(cls, f->w, f->h);
    wm_paper_erode(cls, f->w, f->h);
    return WM_OK;
}

wm_status wm_paper_trace(const uint8_t *cls, int32_t w, int32_t h,
                         wm_heuristic heur, wm_rings *out,
                         wm_paper_stats *stats, const wm_ctx *ctx)
{
    wm_paper_stats local = {0};
    wm_paper_stats *const st = stats ? stats : &local;
    uint8_t *g = NULL;
    memset(st, 0, sizeof *st);
    wm_rings_clear(out);
    wm_status status = check_args(w, h, heur, ctx);
    if (status != WM_OK)
        goto cleanup;
    const size_t n = (size_t)w * (size_t)h;
    g = malloc(n);
    if (!g)
    {
        status =
            wm_fail(ctx, WM_ERR_NOMEM, "paper: out of memory (%zu bytes)", n);
        goto cleanup;
    }
    for (size_t u = 0; u < n; u++)
    {
        if (cls[u] > WM_PAPER_BORDER)
        {
            status = wm_fail(ctx, WM_ERR_INVALID,
                             "paper: class %d at sample (%d, %d)", cls[u],
                             (int)(u % (size_t)w), (int)(u / (size_t)w));
            goto cleanup;
        }
        g[u] = cls[u] ? WM_PAPER_INSIDE : WM_PAPER_OUTSIDE;
    }
    wm_paper_erode(g, w, h);
    if (memcmp(g, cls, n) != 0)
    {
        size_t u = 0;
        while (g[u] == cls[u])
            u++;
        status = wm_fail(ctx, WM_ERR_INVALID,
                         "paper: class grid not eroded at sample (%d, %d)",
                         (int)(u % (size_t)w), (int)(u / (size_t)w));
        goto cleanup;
    }
    status = trace_grid(g, w, h, heur, out, st, ctx);
cleanup:
    free(g);
    return status;
}

wm_status wm_paper_extract(const wm_field *f, wm_heuristic heur, wm_rings *out,
                           wm_paper_stats *stats, const wm_ctx *ctx)
{
    wm_paper_stats local = {0};
    wm_paper_stats *const st = stats ? stats : &local;
    uint8_t *g = NULL;
    memset(st, 0, sizeof *st);
    wm_rings_clear(out);
    wm_status status = check_args(f->w, f->h, heur, ctx);
    if (status != WM_OK)
        goto cleanup;
    const size_t n = (size_t)f->w * (size_t)f->h;
    g = malloc(n);
    if (!g)
    {
        status =
            wm_fail(ctx, WM_ERR_NOMEM, "paper: out of memory (%zu bytes)", n);
        goto cleanup;
    }
    status = wm_paper_classify(f, g, ctx);
    if (status == WM_OK)
        status = trace_grid(g, f->w, f->h, heur, out, st, ctx);
cleanup:
    free(g);
    return status;
}
