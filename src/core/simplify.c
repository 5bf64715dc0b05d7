/*
 * simplify.c - topology-preserving Douglas-Peucker on a block's rings.
 *
 * Method.
 *  1. Douglas-Peucker (Douglas & Peucker 1973) on every chain between fixed
 *     vertices, with the structure of PostGIS's ptarray_simplify_in_place:
 *     an explicit index stack and a "kept" bitmap, no recursion, no
 *     per-point allocation. Fixed vertices are the ones on the block square
 *     border (x or y equal to 0 or size); a ring without any is split at two
 *     deterministic anchors (its lowest-leftmost vertex and the first vertex
 *     farthest from it in index order). The distance is the distance to the
 *     segment (as PostGIS), a vertex is kept when its squared distance
 *     exceeds tol2 = floor(tol * tol) (squared lattice units, __int128):
 *     since a dropped vertex has squared distance <= floor(tol^2) <= tol^2,
 *     the rounding only keeps a few more vertices, never fewer, and every
 *     dropped input vertex stays within tol of the output segment spanning
 *     it (also after the repairs below, which re-run DP on the two halves
 *     of every refined span). A chain whose two fixed ends lie on one side
 *     of the square keeps its farthest vertex whatever the tolerance:
 *     straightened, it would run along the side and cover there, in this
 *     block only, a piece the neighbouring block leaves dry.
 *     With side pieces (wm_simplify_rings_guarded, MIN_ANGLE), a shortcut
 *     that enters the open diametral circle of a piece which refinement
 *     may not split, where none of the edges it replaces enters it and it
 *     does not end at an end of that piece, is split as one beyond the
 *     tolerance (the side guard; exact, in doubled lattice coordinates).
 *  2. Repairs, in the spirit of Saalfeld (1999). The output must have no
 *     two segments that cross or touch (consecutive segments of one ring
 *     share their vertex but may not fold back onto each other), every
 *     ring keeps >= 3 vertices and the sign of its area, and
 *     wm_holes_nesting must give the input's nesting. A violation
 *     "refines" the responsible output segments: the farthest input vertex
 *     of the span a segment replaces (the next DP split) is restored.
 *     Segment conflicts are found with a hash grid of cells over the output
 *     segments, filled incrementally; a worklist holds the segments not
 *     yet checked, so only what changed is re-checked. A nesting change of
 *     ring t with respect to ring S is located exactly: the crossing
 *     parities of t's vertex in the polygons (span + shortcut) of S add up
 *     to the change, so the spans with odd parity are refined; if that
 *     cannot be done, the rings involved are restored in full. Every round
 *     adds vertices, so the loop ends (in the limit with the valid input);
 *     it is bounded anyway and reports WM_ERR_INTERNAL on the bound.
 *
 * Complexity: DP is O(n log n) typical, O(n^2) worst (as PostGIS), plus,
 * with the side guard, one pass over a span per shortcut that comes near a
 * side (each edge reads the pieces near it by binary search); the
 * conflict check is O(m * k) for m output segments and k segments per
 * grid cell; nesting checks cost one wm_holes_nesting per round (usually
 * one or two rounds).
 *
 * Robustness: exact integer predicates only (lattice.h), no epsilon;
 * distances compared as __int128 rationals with a common denominator.
 * Doubles appear only to pick the grid's cell size (a heuristic) and to
 * skip, in the farthest-vertex scan, the vertices provably not the
 * farthest (s_far: its double values are within a relative 2^-52 of the
 * exact ones, so the exact comparison still decides).
 *
 * References: D. Douglas & T. Peucker, "Algorithms for the reduction of the
 * number of points required to represent a digitized line or its
 * caricature", The Canadian Cartographer 10(2), 1973; PostGIS
 * liblwgeom/ptarray.c, ptarray_simplify_in_place(); A. Saalfeld,
 * "Topologically consistent line simplification with the Douglas-Peucker
 * algorithm", Cartography and GIS 26(1), 1999.
 */
#include "simplify.h"
#include "holes.h"
#include "lattice.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define S_NONE UINT32_MAX
#define S_EMPTY UINT64_MAX
#define S_MAX_ROUNDS 100000

typedef struct
{
    uint32_t u, v; /* segment from kept vertex u to kept vertex v */
} s_seg;

typedef struct
{
    uint32_t u, v, next;
} s_ent;

typedef struct
{
    uint32_t S, t; /* "has t's containment by S changed?" */
} s_query;

typedef struct
{
    const wm_rings *in;
    const wm_pt *P;
    size_t n, nr;
    wm_i128 tol2;
    const wm_ctx *ctx;
    /* the side guard: pieces of the block square's edges per side (0: x =
     * 0, 1: x = size, 2: y = 0, 3: y = size), ascending along it, and the
     * longest per side; size 0 when off */
    wm_side_piece *by_side[4]; /* a before b along the side */
    uint32_t *mark[4];         /* s_guarded's, per piece */
    uint32_t tick;
    size_t nside[4];
    int64_t longest[4], size;
    uint32_t *ring_of; /* ring of each input vertex */
    unsigned char *kept;
    uint32_t *nk;    /* next kept vertex (valid for kept vertices) */
    uint32_t *stack; /* DP stack */
    double *approx;  /* s_far's scratch, one per input vertex */
    size_t *count;   /* kept vertices per ring */
    uint32_t *rep;   /* one kept vertex per ring (never dropped) */
    size_t added;    /* vertices restored by the repairs */
    /* worklist of segments to check */
    s_seg *work;
    size_t nwork, work_head, work_cap;
    /* hash grid: cell key -> chain of entries */
    uint64_t *keys;
    uint32_t *heads;
    size_t cap, used;
    unsigned bits;
    s_ent *ent;
    size_t nent, ent_cap;
    int64_t ox, oy, cs;
    /* per ring: the input's area sign and nesting, the output's nesting */
    signed char *sgn;
    int32_t *enc_in, *enc_out;
    s_query *qs; /* nesting queries of a repair round */
    size_t nq, q_cap;
} simp;

/* ---- small helpers ------------------------------------------------------- */

static uint32_t s_nxt(const simp *sp, uint32_t i)
{
    const size_t r = sp->ring_of[i];
    return (i + 1 == sp->in->start[r + 1]) ? (uint32_t)sp->in->start[r] : i + 1;
}

static int s_border(wm_pt p, int32_t size)
{
    return p.x == 0 || p.y == 0 || p.x == size || p.y == size;
}

/* Whether a and b lie on one side of the block square. */
static int s_same_side(wm_pt a, wm_pt b, int32_t size)
{
    return (a.x == b.x && (a.x == 0 || a.x == size)) ||
           (a.y == b.y && (a.y == 0 || a.y == size));
}

static wm_status s_push_work(simp *sp, uint32_t u, uint32_t v)
{
    if (sp->work_head == sp->nwork)
        sp->work_head = sp->nwork = 0;
    if (!wm_grow((void **)&sp->work, &sp->work_cap, sp->nwork + 1,
                 sizeof *sp->work))
        return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
    sp->work[sp->nwork].u = u;
    sp->work[sp->nwork].v = v;
    sp->nwork++;
    return WM_OK;
}

/* Squared distance from p to segment [a, b] as a numerator over the common
 * denominator len2 (1 when a == b): exact, comparable within one span. */
static wm_i128 s_dnum(wm_pt a, wm_pt b, wm_pt p, int64_t len2)
{
    const int64_t abx = (int64_t)b.x - a.x, aby = (int64_t)b.y - a.y;
    const int64_t apx = (int64_t)p.x - a.x, apy = (int64_t)p.y - a.y;
    if (len2 == 0)
        return (wm_i128)(apx * apx + apy * apy);
    const int64_t dot = abx * apx + aby * apy;
    if (dot <= 0)
        return (wm_i128)(apx * apx + apy * apy) * len2;
    if (dot >= len2)
    {
        const int64_t bpx = (int64_t)p.x - b.x, bpy = (int64_t)p.y - b.y;
        return (wm_i128)(bpx * bpx + bpy * bpy) * len2;
    }
    const int64_t cross = abx * apy - aby * apx;
    return (wm_i128)cross * cross;
}

/* approx[i] = s_dnum(a, b, P[i]) in double, i = lo .. hi - 1, and returns
 * their maximum (or -1). Every difference, dot and cross product is exact
 * in double (coordinates below 2^24, products below 2^50), so the region is
 * s_dnum's and only the last product rounds: approx = exact (1 + d), |d| <=
 * 2^-53. */
WM_CLONES
static double s_approx(const wm_pt *P, uint32_t lo, uint32_t hi, wm_pt a,
                       wm_pt b, double *approx)
{
    const double ax = a.x, ay = a.y;
    const double abx = (double)b.x - ax, aby = (double)b.y - ay;
    const double len2 = abx * abx + aby * aby;
    const double scale = len2 > 0 ? len2 : 1; /* a point: the distance */
    for (uint32_t i = lo; i < hi; i++)
    { /* every branch computed: the selects vectorize */
        const double apx = P[i].x - ax, apy = P[i].y - ay;
        const double bpx = apx - abx, bpy = apy - aby;
        const double dot = abx * apx + aby * apy;
        const double cross = abx * apy - aby * apx;
        const double e0 = (apx * apx + apy * apy) * scale;
        const double e1 = (bpx * bpx + bpy * bpy) * scale;
        const double mid = dot >= len2 ? e1 : cross * cross;
        approx[i] = dot <= 0 ? e0 : mid;
    }
    double m[4] = {-1, -1, -1, -1}; /* four chains of maxsd */
    uint32_t i = lo;
    for (; i + 4 <= hi; i += 4)
        for (int k = 0; k < 4; k++)
            m[k] = approx[i + k] > m[k] ? approx[i + k] : m[k];
    for (; i < hi; i++)
        m[0] = approx[i] > m[0] ? approx[i] : m[0];
    m[0] = m[1] > m[0] ? m[1] : m[0];
    m[2] = m[3] > m[2] ? m[3] : m[2];
    return m[2] > m[0] ? m[2] : m[0];
}

/* Farthest vertex strictly between a and b (ring order, cyclic; a == b
 * means the whole ring but a); first one on ties. S_NONE when empty. The
 * approximations pick the few vertices within their rounding (a relative
 * 2^-52) of the largest: the exact comparison runs over those only. */
static uint32_t s_far(const simp *sp, uint32_t a, uint32_t b)
{
    const wm_pt pa = sp->P[a], pb = sp->P[b];
    const int64_t dx = (int64_t)pb.x - pa.x, dy = (int64_t)pb.y - pa.y;
    const int64_t len2 = dx * dx + dy * dy;
    uint32_t best = S_NONE;
    wm_i128 bestd = -1;
    /* the span in ring order as one or two index ranges */
    const size_t r = sp->ring_of[a];
    const uint32_t rs = (uint32_t)sp->in->start[r];
    const uint32_t re = (uint32_t)sp->in->start[r + 1];
    const uint32_t lo[2] = {a + 1, rs},
                   hi[2] = {a < b ? b : re, a < b ? rs : b};
    double m = -1;
    for (int k = 0; k < 2; k++)
    {
        const double mk = s_approx(sp->P, lo[k], hi[k], pa, pb, sp->approx);
        m = mk > m ? mk : m;
    }
    const double cut = m - m * 0x1p-50;
    for (int k = 0; k < 2; k++)
        for (uint32_t i = lo[k]; i < hi[k]; i++)
        {
            if (sp->approx[i] < cut)
                continue;
            const wm_i128 d = s_dnum(pa, pb, sp->P[i], len2);
            if (d > bestd)
            {
                bestd = d;
                best = i;
            }
        }
    return best;
}

/* ---- the side guard --------------------------------------------------- */

/* Distance of p to side k of the square, and its position along it. */
static int64_t s_side_dist(wm_pt p, int k, int64_t size)
{
    return k == 0 ? p.x : k == 1 ? size - p.x : k == 2 ? p.y : size - p.y;
}

static int64_t s_along(wm_pt p, int k)
{
    return k < 2 ? p.y : p.x;
}

/* Whether segment p-q enters the open diametral circle of piece c. In
 * doubled coordinates the circle's centre is c.a + c.b and its diameter
 * |c.b - c.a|, so everything stays on the integers. */
static int s_enters(wm_pt p, wm_pt q, const wm_side_piece *c)
{
    const wm_pt P = {2 * p.x, 2 * p.y}, Q = {2 * q.x, 2 * q.y};
    const wm_pt C = {c->a.x + c->b.x, c->a.y + c->b.y};
    const int64_t dx = (int64_t)Q.x - P.x, dy = (int64_t)Q.y - P.y;
    const int64_t len2 = dx * dx + dy * dy;
    const int64_t ex = (int64_t)c->b.x - c->a.x, ey = (int64_t)c->b.y - c->a.y;
    const wm_i128 r2 = (wm_i128)(ex * ex + ey * ey) * (len2 ? len2 : 1);
    return s_dnum(P, Q, C, len2) < r2;
}

static int s_same_pt(wm_pt a, wm_pt b)
{
    return a.x == b.x && a.y == b.y;
}

/* The pieces on side k whose circles segment p-q may enter, [*m0, *m1):
 * a circle is entered only where the segment comes nearer the side than
 * half the piece's length, and overlaps the piece along the side (pieces
 * on one side do not overlap). */
static void s_near(const simp *sp, wm_pt p, wm_pt q, int k, size_t *m0,
                   size_t *m1)
{
    const int64_t dp = s_side_dist(p, k, sp->size);
    const int64_t dq = s_side_dist(q, k, sp->size);
    *m0 = *m1 = 0;
    if (sp->nside[k] == 0 || 2 * (dp < dq ? dp : dq) >= sp->longest[k])
        return;
    const int64_t up = s_along(p, k), uq = s_along(q, k);
    const int64_t lo = up < uq ? up : uq, hi = up < uq ? uq : up;
    const wm_side_piece *c = sp->by_side[k];
    size_t l = 0, h = sp->nside[k]; /* the first piece ending past lo */
    while (l < h)
    {
        const size_t m = l + (h - l) / 2;
        if (s_along(c[m].b, k) <= lo)
            l = m + 1;
        else
            h = m;
    }
    *m0 = *m1 = l;
    while (*m1 < sp->nside[k] && s_along(c[*m1].a, k) < hi)
        (*m1)++;
}

/* Whether the shortcut a-b enters the circle of a piece that does not end
 * where it does, and none of the input edges from a to b enters that
 * circle. The pieces it enters are marked first, the input edges clear
 * their marks in one pass, and a mark left objects (work linear in the
 * span and in the pieces near it). */
static int s_guarded(simp *sp, uint32_t a, uint32_t b)
{
    const wm_pt pa = sp->P[a], pb = sp->P[b];
    if (++sp->tick == 0) /* wrapped: no mark may look current */
    {
        for (int k = 0; k < 4; k++)
            memset(sp->mark[k], 0, sp->nside[k] * sizeof *sp->mark[k]);
        sp->tick = 1;
    }
    int any = 0;
    size_t m0, m1;
    for (int k = 0; k < 4; k++)
    {
        s_near(sp, pa, pb, k, &m0, &m1);
        for (size_t m = m0; m < m1; m++)
        {
            const wm_side_piece *c = &sp->by_side[k][m];
            if (!s_same_pt(pa, c->a) && !s_same_pt(pa, c->b) &&
                !s_same_pt(pb, c->a) && !s_same_pt(pb, c->b) &&
                s_enters(pa, pb, c))
            {
                sp->mark[k][m] = sp->tick;
                any = 1;
            }
        }
    }
    for (uint32_t i = a, j = s_nxt(sp, a); any; i = j, j = s_nxt(sp, j))
    {
        for (int k = 0; k < 4; k++)
        {
            s_near(sp, sp->P[i], sp->P[j], k, &m0, &m1);
            for (size_t m = m0; m < m1; m++)
                if (sp->mark[k][m] == sp->tick &&
                    s_enters(sp->P[i], sp->P[j], &sp->by_side[k][m]))
                    sp->mark[k][m] = 0;
        }
        if (j == b)
            break;
    }
    for (int k = 0; any && k < 4; k++)
    {
        s_near(sp, pa, pb, k, &m0, &m1);
        for (size_t m = m0; m < m1; m++)
            if (sp->mark[k][m] == sp->tick)
                return 1;
    }
    return 0;
}

static int s_piece_cmp(const void *x, const void *y)
{
    /* on one side either x or y is constant */
    const wm_side_piece *c = x, *d = y;
    const int64_t u = (int64_t)c->a.x + c->a.y, v = (int64_t)d->a.x + d->a.y;
    return (u > v) - (u < v);
}

/* The side guard's pieces, per side, ascending along it. */
static wm_status s_guard_setup(simp *sp, const wm_side_piece *pc, size_t n,
                               int32_t size)
{
    size_t cap[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < n; i++)
    {
        const wm_side_piece c = pc[i];
        const int k =
            c.a.x == c.b.x ? (c.a.x == 0 ? 0 : 1) : (c.a.y == 0 ? 2 : 3);
        const int fwd = s_along(c.a, k) < s_along(c.b, k);
        const wm_side_piece o = {fwd ? c.a : c.b, fwd ? c.b : c.a};
        const int64_t len = s_along(o.b, k) - s_along(o.a, k);
        sp->longest[k] = len > sp->longest[k] ? len : sp->longest[k];
        if (!wm_push((void **)&sp->by_side[k], &sp->nside[k], &cap[k], &o,
                     sizeof o))
            return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
    }
    for (int k = 0; k < 4; k++)
    {
        if (sp->nside[k] > 1)
            qsort(sp->by_side[k], sp->nside[k], sizeof *sp->by_side[k],
                  s_piece_cmp);
        sp->mark[k] =
            calloc(sp->nside[k] ? sp->nside[k] : 1, sizeof *sp->mark[k]);
        if (!sp->mark[k])
            return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
    }
    sp->size = n ? size : 0;
    return WM_OK;
}

/* Douglas-Peucker on the span a..b (PostGIS ptarray_simplify_in_place
 * structure): marks the kept vertices strictly between a and b. Returns 0
 * when cancelled (checked before each search: one scans at most the ring,
 * some milliseconds for the 7 M vertices of a block-long river). */
static int s_dp(simp *sp, uint32_t a, uint32_t b)
{
    size_t top = 0;
    uint32_t i1 = a;
    sp->stack[top++] = b;
    while (top > 0)
    {
        if (wm_cancelled(sp->ctx))
            return 0;
        const uint32_t i2 = sp->stack[top - 1];
        const uint32_t split = s_far(sp, i1, i2);
        if (split != S_NONE && (wm_seg_dist2_exceeds(sp->P[i1], sp->P[i2],
                                                     sp->P[split], sp->tol2) ||
                                (sp->size && s_guarded(sp, i1, i2))))
        {
            sp->kept[split] = 1;
            sp->stack[top++] = split; /* depth <= ring length */
        }
        else
        {
            i1 = i2;
            top--;
        }
    }
    return 1;
}

/* Re-links the kept vertices from u to v (u, v kept, nothing between them
 * linked yet) and queues the new segments. */
static wm_status s_link_span(simp *sp, uint32_t u, uint32_t v)
{
    uint32_t prev = u, i = u;
    const size_t r = sp->ring_of[u];
    for (;;)
    {
        i = s_nxt(sp, i);
        if (!sp->kept[i])
            continue;
        sp->nk[prev] = i;
        const wm_status st = s_push_work(sp, prev, i);
        if (st != WM_OK)
            return st;
        if (i == v)
            return WM_OK;
        sp->count[r]++;
        sp->added++;
        prev = i;
    }
}

/* Refines the output segment starting at kept vertex u: restores the
 * farthest vertex of its span, then re-runs DP on both halves. *did is 0
 * when the segment is an input edge (nothing to restore). */
static wm_status s_refine(simp *sp, uint32_t u, int *did)
{
    const uint32_t v = sp->nk[u];
    const uint32_t w = s_far(sp, u, v);
    *did = 0;
    if (w == S_NONE)
        return WM_OK;
    sp->kept[w] = 1;
    s_dp(sp, u, w);
    s_dp(sp, w, v);
    *did = 1;
    return s_link_span(sp, u, v);
}

/* Refines every output segment of ring r. */
static wm_status s_refine_ring(simp *sp, size_t r, int *did)
{
    const uint32_t first = sp->rep[r];
    uint32_t u = first;
    *did = 0;
    do
    {
        const uint32_t v = sp->nk[u];
        int d;
        const wm_status st = s_refine(sp, u, &d);
        if (st != WM_OK)
            return st;
        *did |= d;
        u = v;
    } while (u != first);
    return WM_OK;
}

/* Restores ring r completely. */
static wm_status s_restore_ring(simp *sp, size_t r)
{
    const uint32_t first = sp->rep[r];
    uint32_t u = first;
    do
    {
        const uint32_t v = sp->nk[u];
        if (s_nxt(sp, u) != v)
        {
            for (uint32_t i = s_nxt(sp, u); i != v; i = s_nxt(sp, i))
                sp->kept[i] = 1;
            const wm_status st = s_link_span(sp, u, v);
            if (st != WM_OK)
                return st;
        }
        u = v;
    } while (u != first);
    return WM_OK;
}

/* ---- the hash grid of output segments ------------------------------------ */

typedef struct
{
    int64_t ax, ay, bx, by; /* endpoints, a has the lower (or equal) y */
    int64_t ox, oy, s;      /* grid origin and cell size */
    int64_t colmin, colmax; /* columns of the segment's bounding box */
    int64_t row0, row, row_end, col, col_end;
} s_walk;

static int64_t s_floordiv(int64_t a, int64_t b)
{
    int64_t q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0)))
        q--;
    return q;
}

static int64_t s_ceildiv(int64_t a, int64_t b)
{
    return -s_floordiv(-a, b);
}

static void s_walk_row(s_walk *w)
{
    if (w->colmin == w->colmax || w->row_end == w->row0)
    {
        /* one column, or one row holding the whole segment */
        w->col = w->colmin;
        w->col_end = w->colmax;
        return;
    }
    /* the part of the segment with y in the row's closed y range; its x
     * range, rounded outwards, exactly (dy > 0 here) */
    int64_t ylo = w->oy + w->row * w->s, yhi = ylo + w->s;
    if (ylo < w->ay)
        ylo = w->ay;
    if (yhi > w->by)
        yhi = w->by;
    const int64_t dx = w->bx - w->ax, dy = w->by - w->ay;
    const int64_t na = dx * (ylo - w->ay), nb = dx * (yhi - w->ay);
    const int64_t lo = w->ax + s_floordiv(na < nb ? na : nb, dy);
    const int64_t hi = w->ax + s_ceildiv(na > nb ? na : nb, dy);
    w->col = s_floordiv(lo - w->ox, w->s);
    w->col_end = s_floordiv(hi - w->ox, w->s);
    if (w->col < w->colmin)
        w->col = w->colmin;
    if (w->col_end > w->colmax)
        w->col_end = w->colmax;
}

/* Walks, row by row, a superset of the cells the closed segment [a, b]
 * meets: two segments that meet share at least one walked cell. */
static void s_walk_init(s_walk *w, wm_pt a, wm_pt b, int64_t ox, int64_t oy,
                        int64_t s)
{
    if (b.y < a.y)
    {
        const wm_pt t = a;
        a = b;
        b = t;
    }
    w->ax = a.x;
    w->ay = a.y;
    w->bx = b.x;
    w->by = b.y;
    w->ox = ox;
    w->oy = oy;
    w->s = s;
    w->colmin = s_floordiv((int64_t)(a.x < b.x ? a.x : b.x) - ox, s);
    w->colmax = s_floordiv((int64_t)(a.x > b.x ? a.x : b.x) - ox, s);
    w->row = s_floordiv((int64_t)a.y - oy, s);
    w->row_end = s_floordiv((int64_t)b.y - oy, s);
    w->row0 = w->row;
    s_walk_row(w);
}

static int s_walk_next(s_walk *w, int64_t *cx, int64_t *cy)
{
    while (w->col > w->col_end)
    {
        if (++w->row > w->row_end)
            return 0;
        s_walk_row(w);
    }
    *cx = w->col++;
    *cy = w->row;
    return 1;
}

static size_t s_hash(const simp *sp, uint64_t key)
{
    return (size_t)((key * UINT64_C(0x9E3779B97F4A7C15)) >> (64 - sp->bits));
}

/* Slot of key, or SIZE_MAX when absent. */
static size_t s_find(const simp *sp, uint64_t key)
{
    size_t h = s_hash(sp, key);
    for (;;)
    {
        if (sp->keys[h] == key)
            return h;
        if (sp->keys[h] == S_EMPTY)
            return SIZE_MAX;
        h = (h + 1) & (sp->cap - 1);
    }
}

static wm_status s_table_alloc(simp *sp, unsigned bits)
{
    const size_t cap = (size_t)1 << bits;
    sp->keys = malloc(cap * sizeof *sp->keys);
    sp->heads = malloc(cap * sizeof *sp->heads);
    if (!sp->keys || !sp->heads)
        return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory (grid)");
    for (size_t i = 0; i < cap; i++)
    {
        sp->keys[i] = S_EMPTY;
        sp->heads[i] = S_NONE;
    }
    sp->cap = cap;
    sp->bits = bits;
    sp->used = 0;
    return WM_OK;
}

/* Slot of key, inserted when absent (grows the table at load 1/2). */
static wm_status s_insert(simp *sp, uint64_t key, size_t *slot)
{
    size_t h = s_find(sp, key);
    if (h != SIZE_MAX)
    {
        *slot = h;
        return WM_OK;
    }
    if (2 * (sp->used + 1) > sp->cap)
    {
        uint64_t *okeys = sp->keys;
        uint32_t *oheads = sp->heads;
        const size_t ocap = sp->cap;
        if (sp->bits >= 8 * sizeof(size_t) - 2)
            return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: grid too large");
        sp->keys = NULL;
        sp->heads = NULL;
        const wm_status st = s_table_alloc(sp, sp->bits + 1);
        if (st != WM_OK)
        {
            free(sp->keys);
            free(sp->heads);
            sp->keys = okeys;
            sp->heads = oheads;
            sp->cap = ocap;
            return st;
        }
        for (size_t i = 0; i < ocap; i++)
            if (okeys[i] != S_EMPTY)
            {
                size_t k = s_hash(sp, okeys[i]);
                while (sp->keys[k] != S_EMPTY)
                    k = (k + 1) & (sp->cap - 1);
                sp->keys[k] = okeys[i];
                sp->heads[k] = oheads[i];
                sp->used++;
            }
        free(okeys);
        free(oheads);
    }
    h = s_hash(sp, key);
    while (sp->keys[h] != S_EMPTY)
        h = (h + 1) & (sp->cap - 1);
    sp->keys[h] = key;
    sp->heads[h] = S_NONE;
    sp->used++;
    *slot = h;
    return WM_OK;
}

static uint64_t s_key(int64_t cx, int64_t cy)
{
    return ((uint64_t)(uint32_t)cx << 32) | (uint64_t)(uint32_t)cy;
}

static int s_valid(const simp *sp, uint32_t u, uint32_t v)
{
    return sp->kept[u] && sp->nk[u] == v;
}

/* Do output segments (u, v) and (x, y) conflict? */
static int s_conflict(const simp *sp, uint32_t u, uint32_t v, uint32_t x,
                      uint32_t y)
{
    const wm_pt a = sp->P[u], b = sp->P[v], c = sp->P[x], d = sp->P[y];
    if (sp->ring_of[u] == sp->ring_of[x])
    {
        if (v == x && y == u)
            return 1; /* a ring reduced to two vertices */
        if (v == x)   /* (a, b) then (b, d): may only share b */
            return wm_on_segment(a, b, d) || wm_on_segment(c, d, a);
        if (y == u) /* (c, a) then (a, b): may only share a */
            return wm_on_segment(c, d, b) || wm_on_segment(a, b, c);
    }
    return wm_segments_meet(a, b, c, d);
}

/* Checks every queued segment against the registered ones, refining the
 * conflicting pairs, and registers the segments that survive. */
static wm_status s_resolve(simp *sp)
{
    wm_status st = WM_OK;
    while (sp->work_head < sp->nwork)
    {
        const s_seg A = sp->work[sp->work_head++];
        if (!s_valid(sp, A.u, A.v))
            continue;
        int alive = 1;
        int64_t cx, cy;
        s_walk w;
        s_walk_init(&w, sp->P[A.u], sp->P[A.v], sp->ox, sp->oy, sp->cs);
        while (alive && s_walk_next(&w, &cx, &cy))
        {
            const size_t slot = s_find(sp, s_key(cx, cy));
            if (slot == SIZE_MAX)
                continue;
            uint32_t *link = &sp->heads[slot];
            while (*link != S_NONE)
            {
                const s_ent e = sp->ent[*link];
                if (!s_valid(sp, e.u, e.v))
                {
                    *link = e.next; /* stale: unlink lazily */
                    continue;
                }
                if (e.u != A.u && s_conflict(sp, A.u, A.v, e.u, e.v))
                {
                    int ra, rb;
                    if ((st = s_refine(sp, A.u, &ra)) != WM_OK ||
                        (st = s_refine(sp, e.u, &rb)) != WM_OK)
                        return st;
                    if (!ra && !rb)
                        return wm_fail(sp->ctx, WM_ERR_INVALID,
                                       "simplify: input rings cross or touch "
                                       "near (%d, %d)",
                                       (int)sp->P[A.u].x, (int)sp->P[A.u].y);
                    if (ra)
                    {
                        alive = 0;
                        break;
                    }
                    *link = e.next; /* e was refined: now stale */
                    continue;
                }
                link = &sp->ent[*link].next;
            }
        }
        if (!alive)
            continue;
        s_walk_init(&w, sp->P[A.u], sp->P[A.v], sp->ox, sp->oy, sp->cs);
        while (s_walk_next(&w, &cx, &cy))
        {
            size_t slot = 0;
            if ((st = s_insert(sp, s_key(cx, cy), &slot)) != WM_OK)
                return st;
            if (sp->nent >= (size_t)S_NONE ||
                !wm_grow((void **)&sp->ent, &sp->ent_cap, sp->nent + 1,
                         sizeof *sp->ent))
                return wm_fail(sp->ctx, WM_ERR_NOMEM,
                               "simplify: out of memory (grid entries)");
            sp->ent[sp->nent].u = A.u;
            sp->ent[sp->nent].v = A.v;
            sp->ent[sp->nent].next = sp->heads[slot];
            sp->heads[slot] = (uint32_t)sp->nent++;
        }
    }
    return st;
}

/* ---- nesting repair ------------------------------------------------------ */

static int s_query_cmp(const void *pa, const void *pb)
{
    const s_query *a = pa, *b = pb;
    if (a->S != b->S)
        return a->S < b->S ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

static int s_u32_cmp(const void *pa, const void *pb)
{
    const uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}

/* Crossing parity of q in the closed polygon u -> ... -> v -> u (input
 * vertices of the span, closed by the shortcut); half-open rule on y. */
static int s_span_parity(const simp *sp, uint32_t u, uint32_t v, wm_pt q)
{
    int in = 0;
    uint32_t i = u;
    do
    {
        const uint32_t j = (i == v) ? u : s_nxt(sp, i);
        const wm_pt a = sp->P[i], b = sp->P[j];
        if ((a.y > q.y) != (b.y > q.y))
        {
            const int o = wm_orient(a, b, q);
            if ((b.y > a.y) ? (o > 0) : (o < 0))
                in = !in;
        }
        i = j;
    } while (i != u);
    return in;
}

typedef struct
{
    int32_t x, y; /* the query's point */
    uint32_t k;   /* index of the query */
} s_qpt;

static int s_qpt_cmp(const void *pa, const void *pb)
{
    const s_qpt *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    return (a->k > b->k) - (a->k < b->k);
}

/* The work of s_fix_queries: query points of one S sorted by x, their
 * parities, and the (query, span) pairs found and the spans to refine. */
typedef struct
{
    s_qpt *pts;
    size_t np;
    unsigned char *par; /* per query of the group */
    s_seg *hits;        /* (query index, span start) */
    size_t nhit, hit_cap;
    uint32_t *marks;
    size_t nmark, mark_cap;
} s_fixer;

/* Bounding box of the input vertices of the span from kept vertex u to v. */
static void s_span_box(const simp *sp, uint32_t u, uint32_t v, int32_t *x0,
                       int32_t *y0, int32_t *x1, int32_t *y1)
{
    *x0 = *x1 = sp->P[u].x;
    *y0 = *y1 = sp->P[u].y;
    for (uint32_t i = s_nxt(sp, u);; i = s_nxt(sp, i))
    {
        const wm_pt p = sp->P[i];
        *x0 = p.x < *x0 ? p.x : *x0;
        *x1 = p.x > *x1 ? p.x : *x1;
        *y0 = p.y < *y0 ? p.y : *y0;
        *y1 = p.y > *y1 ? p.y : *y1;
        if (i == v)
            break;
    }
}

/* Toggles the parity of every query point (index base g) inside the span
 * polygon from u to v and records the pair; 0 when out of memory. */
static int s_span_hits(const simp *sp, s_fixer *fx, size_t g, uint32_t u,
                       uint32_t v)
{
    int32_t x0, y0, x1, y1;
    s_span_box(sp, u, v, &x0, &y0, &x1, &y1);
    size_t lo = 0, hi = fx->np; /* first point with x >= x0 */
    while (lo < hi)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (fx->pts[mid].x < x0)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (size_t m = lo; m < fx->np && fx->pts[m].x <= x1; m++)
    {
        const wm_pt q = {fx->pts[m].x, fx->pts[m].y};
        if (q.y < y0 || q.y > y1 || !s_span_parity(sp, u, v, q))
            continue;
        fx->par[fx->pts[m].k - g] ^= 1;
        if (!wm_grow((void **)&fx->hits, &fx->hit_cap, fx->nhit + 1,
                     sizeof *fx->hits))
            return 0;
        fx->hits[fx->nhit++] = (s_seg){fx->pts[m].k, u};
    }
    return 1;
}

/* fx->marks: the spans of S (sorted, maybe repeated) holding a query point
 * of the group (index base g) whose parity is odd; 0 when out of memory. */
static int s_odd_spans(const simp *sp, s_fixer *fx, size_t g, uint32_t S)
{
    const uint32_t first = sp->rep[S];
    uint32_t u = first;
    fx->nhit = fx->nmark = 0;
    memset(fx->par, 0, fx->np);
    do
    {
        const uint32_t v = sp->nk[u];
        if (s_nxt(sp, u) != v && !s_span_hits(sp, fx, g, u, v))
            return 0;
        u = v;
    } while (u != first);
    for (size_t h = 0; h < fx->nhit; h++)
        if (fx->par[fx->hits[h].u - g])
        {
            if (!wm_grow((void **)&fx->marks, &fx->mark_cap, fx->nmark + 1,
                         sizeof *fx->marks))
                return 0;
            fx->marks[fx->nmark++] = fx->hits[h].v;
        }
    if (fx->nmark > 1)
        qsort(fx->marks, fx->nmark, sizeof *fx->marks, s_u32_cmp);
    return 1;
}

/* Repeats on ring S (its queries qs[g .. g + fx->np)) until every query is
 * answered as in the input: each pass refines the spans with an odd
 * parity (an odd span is never an input edge: each pass restores). */
static wm_status s_fix_ring(simp *sp, s_fixer *fx, const s_query *qs, size_t g,
                            int *did)
{
    const uint32_t S = qs[g].S;
    for (size_t k = g; k < g + fx->np; k++)
    {
        const wm_pt q = sp->P[sp->rep[qs[k].t]];
        fx->pts[k - g] = (s_qpt){q.x, q.y, (uint32_t)k};
    }
    qsort(fx->pts, fx->np, sizeof *fx->pts, s_qpt_cmp);
    for (;;)
    {
        if (!s_odd_spans(sp, fx, g, S))
            return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
        if (fx->nmark == 0)
            return WM_OK; /* every query of S answered as in the input */
        for (size_t m = 0; m < fx->nmark; m++)
        {
            int d;
            if (m > 0 && fx->marks[m] == fx->marks[m - 1])
                continue;
            const wm_status st = s_refine(sp, fx->marks[m], &d);
            if (st != WM_OK)
                return st;
            *did |= d;
        }
    }
}

/* For every query (S, t) whose answer changed, refines the spans of S whose
 * span polygon holds t's representative vertex an odd number of times
 * (their parities add up to the change), and repeats on S until every
 * query of S is answered as in the input. Queries are grouped by S; the
 * spans are matched to the query points by bounding box (points sorted by
 * x). *did is set when a vertex was restored. */
static wm_status s_fix_queries(simp *sp, s_query *qs, size_t nq, int *did)
{
    wm_status st = WM_OK;
    s_fixer fx;
    memset(&fx, 0, sizeof fx);
    *did = 0;
    fx.par = calloc(nq ? nq : 1, 1);
    fx.pts = malloc((nq ? nq : 1) * sizeof *fx.pts);
    if (!fx.par || !fx.pts)
        st = wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
    else
        qsort(qs, nq, sizeof *qs, s_query_cmp);
    for (size_t g = 0; st == WM_OK && g < nq; g += fx.np)
    {
        size_t ge = g;
        while (ge < nq && qs[ge].S == qs[g].S)
            ge++;
        fx.np = ge - g;
        st = s_fix_ring(sp, &fx, qs, g, did);
    }
    free(fx.par);
    free(fx.hits);
    free(fx.pts);
    free(fx.marks);
    return st;
}

/* ---- driver -------------------------------------------------------------- */

static wm_status s_copy(const wm_rings *in, wm_rings *out, const wm_ctx *ctx)
{
    for (size_t r = 0; r < in->nrings; r++)
    {
        for (size_t i = in->start[r]; i < in->start[r + 1]; i++)
            if (wm_rings_push(out, in->pts[i]) != WM_OK)
                return wm_fail(ctx, WM_ERR_NOMEM, "simplify: out of memory");
        if (wm_rings_close(out) != WM_OK)
            return wm_fail(ctx, WM_ERR_NOMEM, "simplify: out of memory");
    }
    return WM_OK;
}

static wm_status s_emit(const simp *sp, wm_rings *out)
{
    wm_rings_clear(out);
    for (size_t r = 0; r < sp->nr; r++)
    {
        for (size_t i = sp->in->start[r]; i < sp->in->start[r + 1]; i++)
            if (sp->kept[i] && wm_rings_push(out, sp->P[i]) != WM_OK)
                return wm_fail(sp->ctx, WM_ERR_NOMEM,
                               "simplify: out of memory");
        if (wm_rings_close(out) != WM_OK)
            return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
    }
    return WM_OK;
}

/* Twice the signed area of ring r's output. */
static wm_i128 s_area2(const simp *sp, size_t r)
{
    const uint32_t first = sp->rep[r];
    uint32_t u = first;
    wm_i128 a = 0;
    do
    {
        const uint32_t v = sp->nk[u];
        const wm_pt p = sp->P[u], q = sp->P[v];
        a += (wm_i128)((int64_t)p.x * q.y - (int64_t)q.x * p.y);
        u = v;
    } while (u != first);
    return a;
}

static int s_sign(wm_i128 a)
{
    return (a > 0) - (a < 0);
}

/* Step 0: sp's arrays for input `in`, each vertex's ring and each ring's
 * sign, and the input's nesting (sp->enc_in). */
static wm_status s_setup(simp *sp, const wm_rings *in, double tol,
                         const wm_ctx *ctx)
{
    const size_t n = in->npts, nr = in->nrings;
    sp->in = in;
    sp->P = in->pts;
    sp->n = n;
    sp->nr = nr;
    sp->ctx = ctx;
    /* tol2 = floor(tol^2), capped far above any lattice distance^2 (2^50)
     * so that tol2 * len2 cannot overflow */
    const double t2 = tol * tol;
    sp->tol2 = t2 >= 0x1p60 ? (wm_i128)1 << 60 : (wm_i128)floor(t2);
    sp->ring_of = malloc((n ? n : 1) * sizeof *sp->ring_of);
    sp->kept = calloc(n ? n : 1, 1);
    sp->nk = malloc((n ? n : 1) * sizeof *sp->nk);
    sp->stack = malloc((n + 1) * sizeof *sp->stack);
    sp->approx = malloc((n + 1) * sizeof *sp->approx);
    sp->count = calloc(nr, sizeof *sp->count);
    sp->rep = malloc(nr * sizeof *sp->rep);
    sp->sgn = malloc(nr);
    sp->enc_in = malloc(nr * sizeof *sp->enc_in);
    sp->enc_out = malloc(nr * sizeof *sp->enc_out);
    if (!sp->ring_of || !sp->kept || !sp->nk || !sp->stack || !sp->approx ||
        !sp->count || !sp->rep || !sp->sgn || !sp->enc_in || !sp->enc_out)
        return wm_fail(ctx, WM_ERR_NOMEM, "simplify: out of memory");
    for (size_t r = 0; r < nr; r++)
    {
        const size_t b = in->start[r], e = in->start[r + 1];
        for (size_t i = b; i < e; i++)
            sp->ring_of[i] = (uint32_t)r;
        sp->sgn[r] = (signed char)s_sign(wm_ring_area2(in->pts + b, e - b));
    }
    return wm_holes_nesting(in, sp->enc_in, ctx);
}

/* Step 1 for a ring with no vertex on the block's sides: Douglas-Peucker
 * between its lowest vertex and the vertex farthest from it, both kept.
 * Returns 0 when cancelled. */
static int s_dp_free_ring(simp *sp, size_t b, size_t e, size_t r)
{
    const wm_pt *P = sp->P;
    uint32_t a0 = (uint32_t)b, a1 = S_NONE;
    int64_t best = -1;
    for (size_t i = b + 1; i < e; i++)
        if (P[i].y < P[a0].y || (P[i].y == P[a0].y && P[i].x < P[a0].x))
            a0 = (uint32_t)i;
    for (size_t i = b; i < e; i++)
    {
        const int64_t dx = (int64_t)P[i].x - P[a0].x;
        const int64_t dy = (int64_t)P[i].y - P[a0].y;
        if (dx * dx + dy * dy > best)
        {
            best = dx * dx + dy * dy;
            a1 = (uint32_t)i;
        }
    }
    sp->kept[a0] = sp->kept[a1] = 1;
    sp->rep[r] = a0;
    return s_dp(sp, a0, a1) && s_dp(sp, a1, a0);
}

/* Step 1 for a ring whose vertices on the block's sides (kept, f0 the
 * first) cut it into chains: Douglas-Peucker per chain. Returns 0 when
 * cancelled. */
static int s_dp_fixed_ring(simp *sp, uint32_t f0, int32_t size, size_t r)
{
    const wm_pt *P = sp->P;
    uint32_t cur = f0;
    do
    {
        uint32_t j = s_nxt(sp, cur);
        while (!s_border(P[j], size))
            j = s_nxt(sp, j);
        if (s_nxt(sp, cur) != j && s_same_side(P[cur], P[j], size))
        {
            /* the chain leaves the side between two of its vertices:
             * straightening it would lay an edge along the side, covering
             * in this block a piece of it that the neighbouring block does
             * not; keep its farthest vertex whatever the tolerance */
            const uint32_t m = s_far(sp, cur, j);
            sp->kept[m] = 1;
            if (!s_dp(sp, cur, m) || !s_dp(sp, m, j))
                return 0;
        }
        else if (!s_dp(sp, cur, j))
            return 0;
        cur = j;
    } while (cur != f0);
    sp->rep[r] = f0;
    return 1;
}

/* Step 1: Douglas-Peucker per chain between fixed vertices (the block's
 * sides) or anchors; rings of fewer than 3 vertices pass unchanged.
 * Returns 0 when cancelled. */
static int s_dp_rings(simp *sp, int32_t size)
{
    const wm_rings *in = sp->in;
    for (size_t r = 0; r < sp->nr; r++)
    {
        const size_t b = in->start[r], e = in->start[r + 1];
        if (e - b < 3)
        {
            for (size_t i = b; i < e; i++)
                sp->kept[i] = 1;
            sp->rep[r] = (uint32_t)b;
            continue;
        }
        uint32_t f0 = S_NONE;
        for (size_t i = b; i < e; i++)
            if (s_border(sp->P[i], size))
            {
                sp->kept[i] = 1;
                if (f0 == S_NONE)
                    f0 = (uint32_t)i;
            }
        if (!(f0 == S_NONE ? s_dp_free_ring(sp, b, e, r)
                           : s_dp_fixed_ring(sp, f0, size, r)))
            return 0;
    }
    return 1;
}

/* Step 2: the kept vertices linked in ring order, counted per ring. */
static void s_link(simp *sp)
{
    const wm_rings *in = sp->in;
    for (size_t r = 0; r < sp->nr; r++)
    {
        const size_t b = in->start[r], e = in->start[r + 1];
        uint32_t first = S_NONE, prev = S_NONE;
        for (size_t i = b; i < e; i++)
            if (sp->kept[i])
            {
                if (first == S_NONE)
                    first = (uint32_t)i;
                else
                    sp->nk[prev] = (uint32_t)i;
                prev = (uint32_t)i;
                sp->count[r]++;
            }
        if (first != S_NONE)
            sp->nk[prev] = first;
    }
}

/* Step 3: at least three vertices per ring that had them. */
static wm_status s_three_each(simp *sp)
{
    for (size_t r = 0; r < sp->nr; r++)
        while (wm_rings_len(sp->in, r) >= 3 && sp->count[r] < 3)
        {
            int did;
            const wm_status st = s_refine_ring(sp, r, &did);
            if (st != WM_OK)
                return st;
            if (!did)
                return wm_fail(sp->ctx, WM_ERR_INTERNAL,
                               "simplify: ring %zu cannot reach 3 vertices", r);
        }
    return WM_OK;
}

/* Step 4: the grid (cells twice the mean output segment), every segment
 * queued for checking. */
static wm_status s_grid(simp *sp)
{
    const wm_pt *P = sp->P;
    double sum = 0.0;
    size_t nseg = 0;
    int64_t xmin = INT64_MAX, ymin = INT64_MAX;
    for (size_t i = 0; i < sp->n; i++)
    {
        xmin = P[i].x < xmin ? P[i].x : xmin;
        ymin = P[i].y < ymin ? P[i].y : ymin;
    }
    sp->nwork = sp->work_head = 0;
    for (size_t i = 0; i < sp->n; i++)
        if (sp->kept[i])
        {
            const wm_pt a = P[i], b = P[sp->nk[i]];
            sum += hypot((double)b.x - a.x, (double)b.y - a.y);
            nseg++;
            const wm_status st = s_push_work(sp, (uint32_t)i, sp->nk[i]);
            if (st != WM_OK)
                return st;
        }
    sp->ox = xmin;
    sp->oy = ymin;
    sp->cs = nseg ? (int64_t)ceil(2.0 * sum / (double)nseg) : 1;
    if (sp->cs < 1)
        sp->cs = 1;
    unsigned bits = 10;
    while (bits < 40 && ((size_t)1 << bits) < 4 * nseg)
        bits++;
    return s_table_alloc(sp, bits);
}

/* Step 5a: every ring of 3 or more input vertices and nonzero area gets 3
 * or more and its input's sign back; *changed when one needed it. */
static wm_status s_fix_rings(simp *sp, int *changed)
{
    *changed = 0;
    for (size_t r = 0; r < sp->nr; r++)
    {
        if (wm_rings_len(sp->in, r) < 3 || sp->sgn[r] == 0)
            continue;
        if (sp->count[r] >= 3 && s_sign(s_area2(sp, r)) == sp->sgn[r])
            continue;
        int did;
        const wm_status st = s_refine_ring(sp, r, &did);
        if (st != WM_OK)
            return st;
        *changed = 1;
    }
    return WM_OK;
}

/* Step 5b: the rings whose nesting changed (enc_in against enc_out), as
 * containment queries in sp->qs (sp->nq of them). */
static wm_status s_nesting_queries(simp *sp)
{
    sp->nq = 0;
    for (size_t r = 0; r < sp->nr; r++)
    {
        const int32_t p = sp->enc_in[r], p2 = sp->enc_out[r];
        s_query cand[4];
        size_t nc = 0;
        if (p == p2)
            continue;
        if (p >= 0)
            cand[nc++] = (s_query){(uint32_t)p, (uint32_t)r};
        if (p2 >= 0)
            cand[nc++] = (s_query){(uint32_t)p2, (uint32_t)r};
        if (p >= 0 && p2 >= 0)
        {
            cand[nc++] = (s_query){(uint32_t)p2, (uint32_t)p};
            cand[nc++] = (s_query){(uint32_t)p, (uint32_t)p2};
        }
        if (!wm_grow((void **)&sp->qs, &sp->q_cap, sp->nq + nc, sizeof *sp->qs))
            return wm_fail(sp->ctx, WM_ERR_NOMEM, "simplify: out of memory");
        memcpy(sp->qs + sp->nq, cand, nc * sizeof *cand);
        sp->nq += nc;
    }
    return WM_OK;
}

/* Step 5c: the queries answered by restoring vertices, or else every ring
 * involved restored whole. */
static wm_status s_fix_nesting(simp *sp)
{
    int did;
    wm_status st = s_fix_queries(sp, sp->qs, sp->nq, &did);
    for (size_t k = 0; st == WM_OK && !did && k < sp->nq; k++)
        if ((st = s_restore_ring(sp, sp->qs[k].S)) == WM_OK)
            st = s_restore_ring(sp, sp->qs[k].t);
    return st;
}

/* Step 5: repair rounds until the output is valid and nested as the input
 * (written to out), each restoring vertices. */
static wm_status s_repair(simp *sp, wm_rings *out)
{
    for (int round = 0;; round++)
    {
        const size_t added0 = sp->added;
        int changed;
        wm_status st;
        if (round >= S_MAX_ROUNDS)
            return wm_fail(sp->ctx, WM_ERR_INTERNAL,
                           "simplify: repair did not converge");
        if ((st = s_resolve(sp)) != WM_OK ||
            (st = s_fix_rings(sp, &changed)) != WM_OK)
            return st;
        if (changed)
        {
            if (sp->added == added0)
                return wm_fail(sp->ctx, WM_ERR_INTERNAL,
                               "simplify: a ring cannot be repaired");
            continue;
        }
        if ((st = s_emit(sp, out)) != WM_OK ||
            (st = wm_holes_nesting(out, sp->enc_out, sp->ctx)) != WM_OK ||
            (st = s_nesting_queries(sp)) != WM_OK)
            return st;
        if (sp->nq == 0)
            return WM_OK; /* clean */
        if ((st = s_fix_nesting(sp)) != WM_OK)
            return st;
        if (sp->added == added0)
            return wm_fail(sp->ctx, WM_ERR_INTERNAL,
                           "simplify: nesting cannot be repaired");
    }
}

static void s_free(simp *sp)
{
    free(sp->ring_of);
    free(sp->kept);
    free(sp->nk);
    free(sp->stack);
    free(sp->approx);
    free(sp->count);
    free(sp->rep);
    free(sp->work);
    free(sp->keys);
    free(sp->heads);
    free(sp->ent);
    free(sp->sgn);
    free(sp->enc_in);
    free(sp->enc_out);
    free(sp->qs);
    for (int k = 0; k < 4; k++)
    {
        free(sp->by_side[k]);
        free(sp->mark[k]);
    }
}

wm_status wm_simplify_rings(const wm_rings *in, int32_t size, double tol,
                            wm_rings *out, const wm_ctx *ctx)
{
    return wm_simplify_rings_guarded(in, size, tol, NULL, 0, out, ctx);
}

wm_status wm_simplify_rings_guarded(const wm_rings *in, int32_t size,
                                    double tol, const wm_side_piece *pieces,
                                    size_t npieces, wm_rings *out,
                                    const wm_ctx *ctx)
{
    wm_rings_clear(out);
    if (!(tol > 0.0) || in->nrings == 0)
        return s_copy(in, out, ctx);
    if (in->npts >= (size_t)UINT32_MAX - 1 || in->nrings > (size_t)INT32_MAX)
        return wm_fail(ctx, WM_ERR_NOMEM, "simplify: too many points");
    simp sp;
    memset(&sp, 0, sizeof sp);
    wm_status st = s_setup(&sp, in, tol, ctx);
    if (st == WM_OK)
        st = s_guard_setup(&sp, pieces, npieces, size);
    if (st == WM_OK && !s_dp_rings(&sp, size))
        st = wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
    if (st == WM_OK)
    {
        s_link(&sp);
        st = s_three_each(&sp);
    }
    if (st == WM_OK)
        st = s_grid(&sp);
    if (st == WM_OK)
        st = s_repair(&sp, out);
    if (st != WM_OK)
        wm_rings_clear(out);
    s_free(&sp);
    return st;
}
