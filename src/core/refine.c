/*
 * refine.c - Delaunay refinement of a polygon's constrained Delaunay
 * triangulation (MIN_ANGLE, MAX_EDGE).
 *
 * Method: Ruppert's algorithm (J. Ruppert, "A Delaunay refinement
 * algorithm for quality 2-dimensional mesh generation", J. Algorithms
 * 1995), in rounds. Each round triangulates the polygon with the points
 * added so far (cdt.c, wm_cdt_triangulate_ex), then looks at every
 * triangle: a bad one (smallest angle below min_angle, unless that angle
 * lies between two ring edges, an input angle no point can cure; or an
 * edge over max_edge) proposes its circumcentre. A walk through the
 * triangles from the bad one towards the circumcentre finds the triangle
 * holding it, or the ring edge that hides it; a ring edge crossed, or one
 * of the holding triangle's or its neighbours' ring edges whose diametral
 * circle holds the point, is split at its midpoint instead (Ruppert's
 * encroachment rule). The round's points and splits are then applied
 * together. Points are rounded to the lattice, so the CDT's predicates stay
 * exact; a shore edge is split at its middle projected on the input edge
 * it lies along, rounded to the nearest lattice point: every shore point
 * stays within 0.71 unit of the input's shore (split_point). Ring edges on the
 * block square are never split here (the block across could not know): they are
 * cut beforehand by rules of global data (cut_side: the global multiples of
 * max_edge, and with min_angle a grading by the water's depth along the side,
 * balanced so that no piece is more than four times as long as its neighbour).
 *
 * Cost: one CDT per round (O(n log n)), O(n) to rate the triangles and
 * O(walk) per bad one; rounds until nothing changes, at most MAX_ROUNDS.
 * Memory: O(n) for the points, the rings and two hash tables.
 *
 * Robustness: the triangulation's decisions are cdt.c's exact predicates;
 * angles and lengths, which only choose what to refine, are doubles. A
 * refined polygon the CDT refuses (a rounded midpoint too close to another
 * edge) ends the refinement with the last good triangulation.
 */
#include "refine.h"

#include "cdt.h"
#include "lattice.h"
#include "scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_ROUNDS 100
#define PI 3.14159265358979323846

/* A growable array of int32 (ring point indices, Steiner points). */
typedef struct
{
    int32_t *a;
    size_t n, cap;
} ibuf;

static int ibuf_push(ibuf *b, int32_t x)
{
    return wm_push((void **)&b->a, &b->n, &b->cap, &x, sizeof x);
}

/* Open-addressing map from nonzero 64-bit keys to int64 values. */
typedef struct
{
    uint64_t *k;
    int64_t *v;
    size_t cap; /* a power of two, or 0 */
} map64;

static uint64_t mix(uint64_t x)
{
    x ^= x >> 33;
    x *= UINT64_C(0xff51afd7ed558ccd);
    x ^= x >> 33;
    return x;
}

static int map_init(map64 *m, size_t n)
{
    size_t cap = 16;
    while (cap < 2 * n + 16)
        cap *= 2;
    free(m->k);
    free(m->v);
    m->k = calloc(cap, sizeof *m->k);
    m->v = malloc(cap * sizeof *m->v);
    m->cap = cap;
    return m->k && m->v;
}

static void map_put(map64 *m, uint64_t key, int64_t val)
{
    size_t i = mix(key) & (m->cap - 1);
    while (m->k[i] && m->k[i] != key)
        i = (i + 1) & (m->cap - 1);
    m->k[i] = key;
    m->v[i] = val;
}

static int64_t map_get(const map64 *m, uint64_t key)
{
    size_t i = mix(key) & (m->cap - 1);
    while (m->k[i])
    {
        if (m->k[i] == key)
            return m->v[i];
        i = (i + 1) & (m->cap - 1);
    }
    return -1;
}

static uint64_t pair_key(int32_t a, int32_t b)
{
    return ((uint64_t)(uint32_t)a << 32 | (uint32_t)b) + 1;
}

static uint64_t undirected(int32_t a, int32_t b)
{
    return a < b ? pair_key(a, b) : pair_key(b, a);
}

static uint64_t point_key(wm_pt p)
{
    return ((uint64_t)(uint32_t)p.x << 32 | (uint32_t)p.y) + 1;
}

typedef struct
{
    const wm_refine_opts *o;
    const wm_ctx *ctx;
    wm_pt *P; /* every point: the input's, then the added ones */
    size_t np, pcap;
    size_t nin;     /* the input's points: P[0 .. nin) */
    ibuf ring;      /* the rings' point indices, concatenated */
    size_t *rstart; /* nrings + 1 */
    size_t nrings;
    ibuf steiner; /* points strictly inside */
    map64 pts;    /* point -> index: no point twice */
    /* the current triangulation */
    uint32_t *tris;
    size_t ntris;
    /* the triangulation kept between rounds: the next one inserts the
     * round's Steiner points and ring splits into it */
    wm_cdt *live;     /* NULL: the next round triangulates from scratch */
    ibuf live_map;    /* its vertex numbers -> point indices */
    int32_t *live_of; /* point index -> its vertex number, or -1 (size
                         live_cap) */
    size_t live_cap;
    ibuf cuts;   /* the round's ring splits: (a, b, midpoint) point indices */
    int32_t *nb; /* per half-edge 3t + i of tris, its twin 3u + j, or -1
                    across a ring edge */
    map64 redge; /* ring edge {a, b} -> ring position (index into ring) */
    /* the round's changes */
    uint8_t *split;   /* per ring position: its edge splits (size ring.n) */
    uint8_t *touched; /* per triangle: near a change of this round */
    size_t nsplit, nnew;
    int nosplit;    /* a split broke the CDT once: split no more */
    double cos_min; /* cos(min_angle), or 2 (off) */
    double max2;    /* max_edge^2, or INFINITY */
} refiner;

static int add_point(refiner *r, wm_pt p, int32_t *idx)
{
    const int64_t have = map_get(&r->pts, point_key(p));
    if (have >= 0)
    {
        *idx = (int32_t)have;
        return 1;
    }
    if (!wm_push((void **)&r->P, &r->np, &r->pcap, &p, sizeof p))
        return 0;
    *idx = (int32_t)(r->np - 1);
    if (2 * r->np + 16 > r->pts.cap)
    {
        map64 m = {NULL, NULL, 0};
        if (!map_init(&m, 2 * r->np))
            return 0;
        for (size_t i = 0; i < r->np; i++)
            map_put(&m, point_key(r->P[i]), (int64_t)i);
        free(r->pts.k);
        free(r->pts.v);
        r->pts = m;
    }
    else
        map_put(&r->pts, point_key(p), *idx);
    return 1;
}

/* Whether point p lies on the block square's outline. */
static int on_square_pt(const refiner *r, wm_pt p)
{
    const int32_t S = r->o->side;
    return p.x == 0 || p.x == S || p.y == 0 || p.y == S;
}

/* Where ring position k's edge a-b is split: its middle, projected on the
 * input edge it lies along (between the input's vertices before and after
 * it on the ring) and rounded to the nearest lattice point, so that
 * however often a shore edge is halved its points stay within 0.71 unit
 * of the input's shore (rounding each middle of the pieces drifted: 2.3
 * units at MIN_ANGLE=20 and MAX_EDGE=6 px, held-out round 23). */
static wm_pt split_point(const refiner *r, int64_t k)
{
    const size_t q = wm_run_of(r->rstart, r->nrings, (size_t)k);
    const size_t b0 = r->rstart[q], len = r->rstart[q + 1] - b0;
    const size_t i0 = (size_t)k - b0, i1 = (i0 + 1) % len;
    size_t s = i0, e = i1;
    for (size_t n = 0; (size_t)r->ring.a[b0 + s] >= r->nin && n < len; n++)
        s = (s + len - 1) % len;
    for (size_t n = 0; (size_t)r->ring.a[b0 + e] >= r->nin && n < len; n++)
        e = (e + 1) % len;
    const wm_pt a = r->P[r->ring.a[b0 + i0]], b = r->P[r->ring.a[b0 + i1]];
    const wm_pt A = r->P[r->ring.a[b0 + s]], B = r->P[r->ring.a[b0 + e]];
    double mx = ((double)a.x + b.x) / 2, my = ((double)a.y + b.y) / 2;
    const double dx = (double)B.x - A.x, dy = (double)B.y - A.y;
    const double l2 = dx * dx + dy * dy;
    if (l2 > 0)
    {
        double t = ((mx - A.x) * dx + (my - A.y) * dy) / l2;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        mx = A.x + t * dx;
        my = A.y + t * dy;
    }
    return (wm_pt){(int32_t)floor(mx + 0.5), (int32_t)floor(my + 0.5)};
}

/* Whether edge a-b lies on the square of side S. */
static int on_side(int32_t S, wm_pt a, wm_pt b)
{
    return (a.x == b.x && (a.x == 0 || a.x == S)) ||
           (a.y == b.y && (a.y == 0 || a.y == S));
}

/* Whether ring edge a-b lies on the block square. */
static int on_square(const refiner *r, wm_pt a, wm_pt b)
{
    return on_side(r->o->side, a, b);
}

/* Appends to out the points cutting edge a -> b (not on the block
 * square) into equal pieces no longer than L, rounded to the lattice. */
static int cut_evenly(refiner *r, wm_pt a, wm_pt b, double L, ibuf *out)
{
    const double len = sqrt(((double)b.x - a.x) * ((double)b.x - a.x) +
                            ((double)b.y - a.y) * ((double)b.y - a.y));
    const double k = ceil(len / L);
    for (double m = 1; m < k; m++)
    {
        const wm_pt q = {(int32_t)llround(a.x + ((double)b.x - a.x) * m / k),
                         (int32_t)llround(a.y + ((double)b.y - a.y) * m / k)};
        int32_t iq;
        const size_t before = r->np;
        if (on_square_pt(r, q)) /* the block across would not have it */
            continue;
        if (!add_point(r, q, &iq))
            return 0;
        if (r->np > before && !ibuf_push(out, iq))
            return 0;
    }
    return 1;
}

/* A growable array of int64 (global positions along a side). */
typedef struct
{
    int64_t *a;
    size_t n, cap;
} lbuf;

/* The shortest side piece grading makes at an end of the side edge, where
 * the room always shrinks to nothing: 8 pixels (shorter ones added
 * triangles on the bundled extracts and synthetic scenes and cured no more
 * of them), at SIMPLIFY below a quarter pixel 32 times SIMPLIFY, down to a
 * pixel: the shore's edges next to the side are that much shorter (at
 * SIMPLIFY=0 one per cell; 8-pixel pieces left 66 triangles below 20
 * degrees in four blocks of the synthetic L1, 1-pixel ones 14, for as many
 * triangles) ... */
static int64_t grade_min(const wm_refine_opts *o)
{
    const double g = 32.0 * o->simplify;
    return g >= 8.0 * WM_Q ? 8 * (int64_t)WM_Q
           : g > WM_Q      ? (int64_t)g
                           : (int64_t)WM_Q;
}
/* ... and elsewhere: 1/16 pixel (a shore running along the side a
 * fraction of a pixel inside the block: pieces of a pixel left triangles
 * of 4-8 degrees there on the synthetic L3) */
#define GRADE_INNER ((int64_t)WM_Q / 16)
/* The longest piece grading leaves, whatever its room: 256 pixels.
 * Refinement checks a new point against the ring edges of the triangles
 * around it, not against a whole diametral circle; one of a piece of
 * hundreds of metres (a block side deep in a large lake) took interior
 * points, leaving triangles of 16-19 degrees on pieces of 160-590 m that
 * nothing could cure (synthetic L1 seed 4, S5). 512 pixels cured one of
 * the three; 64 added 1-2 % triangles; this adds under 0.1 %. */
#define GRADE_OUTER ((int64_t)256 * WM_Q)

static int lpush(lbuf *b, int64_t x)
{
    return wm_push((void **)&b->a, &b->n, &b->cap, &x, sizeof x);
}

/* A side edge's span e0 < e1 (global, along the side) and the shortest
 * piece grading makes at each end. */
typedef struct
{
    int64_t e0, e1, min0, min1;
} side_span;

/* The room (o->room) at position X along the side at F, capped. */
static double room_at(const wm_refine_opts *o, int vertical, int64_t F,
                      int64_t X, double cap)
{
    return vertical ? o->room(o->room_user, F, X, cap)
                    : o->room(o->room_user, X, F, cap);
}

/* Whether the room along piece (u, v) of a side edge rises from the end(s)
 * of the edge it touches (end0: e0 = u, end1: e1 = v) to its midpoint,
 * where it is `room`: read at its quarter points (capped at its length).
 * Where a shore leaves the side at an end, the room grows with the distance
 * from it (between two ends, a tent: concave, its peak anywhere); where it
 * falls, something nearer lies beside the piece (the tip of a land wedge
 * just off the side), whose vertex an end piece of 8 pixels would leave
 * inside its diametral circle (a triangle of 4 degrees on the synthetic
 * L3, seed 2). Three samples miss a tip within about 3/8 of the piece
 * from the end. */
static int room_rises(const wm_refine_opts *o, int vertical, int64_t F,
                      int64_t u, int64_t v, double room, int end0, int end1)
{
    const double len = (double)(v - u);
    const int64_t q1 = wm_floordiv(3 * u + v, 4),
                  q3 = wm_floordiv(u + 3 * v, 4);
    const double r1 = room_at(o, vertical, F, q1, len);
    const double r3 = room_at(o, vertical, F, q3, len);
    return end0 && end1 ? 2 * room >= r1 + r3 /* a tent, its peak anywhere */
           : end0       ? r1 <= room && room <= r3
                        : r3 <= room && room <= r1;
}

/* Appends to cut the points halving piece (u, v) of side edge e,
 * ascending: a piece is halved at its global midpoint while it is longer
 * than GRADE_OUTER, or than its room, o->room at that midpoint (no shore
 * is nearer), and than the end's shortest piece (e->min0, e->min1) at an
 * end of the side edge (unless the room does not rise from the end,
 * room_rises) or GRADE_INNER elsewhere (so a side edge makes at most 16
 * pieces per pixel, only where the shore runs that close to it, and one
 * room query per piece, three at an end, none over GRADE_OUTER; each query
 * reads the edges near the point, see wm_scene_depth; the recursion is as
 * deep as log2 of the side in pixels). A piece no longer
 * than its room has its diametral circle within half the room of its
 * midpoint, clear of the inputs' shore by half the room. Everything here
 * is a function of global positions and of the water along the side
 * only, so both blocks sharing the side find the same points. */
static int grade_side(const wm_refine_opts *o, int vertical, int64_t F,
                      int64_t u, int64_t v, const side_span *e, lbuf *cut)
{
    const int64_t at0 = u == e->e0 ? e->min0 : INT64_MAX;
    const int64_t at1 = v == e->e1 ? e->min1 : INT64_MAX;
    const int64_t least = at0 < at1 ? at0 : at1;
    if (v - u <= GRADE_INNER)
        return 1;
    const int64_t m = wm_floordiv(u + v, 2);
    if (v - u <= GRADE_OUTER)
    {
        const double len = (double)(v - u);
        const double room = room_at(o, vertical, F, m, len);
        if (len <= room || (least < INT64_MAX && v - u <= least &&
                            room_rises(o, vertical, F, u, v, room,
                                       at0 < INT64_MAX, at1 < INT64_MAX)))
            return 1;
    }
    return grade_side(o, vertical, F, u, m, e, cut) && lpush(cut, m) &&
           grade_side(o, vertical, F, m, v, e, cut);
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Side (bottom 0, right 1, top 2, left 3) of the block square holding
 * ring edge a-b, which lies on it. */
static int side_of(wm_pt a, wm_pt b)
{
    return a.x == b.x ? (a.x == 0 ? 3 : 1) : (a.y == 0 ? 0 : 2);
}

int wm_side_ends_build(wm_side_ends *e, const wm_rings *rings, int32_t S)
{
    size_t cap[4] = {0, 0, 0, 0};
    memset(e, 0, sizeof *e);
    for (size_t q = 0; q < rings->nrings; q++)
    {
        const size_t b0 = rings->start[q], len = rings->start[q + 1] - b0;
        for (size_t i = 0; i < len; i++)
        {
            const wm_pt a = rings->pts[b0 + i],
                        b = rings->pts[b0 + (i + 1) % len];
            if (!on_side(S, a, b))
                continue;
            const int s = side_of(a, b);
            const uint64_t two[2] = {(uint64_t)(s & 1 ? a.y : a.x),
                                     (uint64_t)(s & 1 ? b.y : b.x)};
            if (!wm_push((void **)&e->at[s], &e->n[s], &cap[s], &two[0],
                         sizeof two[0]) ||
                !wm_push((void **)&e->at[s], &e->n[s], &cap[s], &two[1],
                         sizeof two[1]))
            {
                wm_side_ends_free(e);
                return 0;
            }
        }
    }
    for (int s = 0; s < 4; s++)
        if (e->n[s] > 1)
            qsort(e->at[s], e->n[s], sizeof *e->at[s], cmp_u64);
    return 1;
}

void wm_side_ends_free(wm_side_ends *e)
{
    for (int s = 0; s < 4; s++)
        free(e->at[s]);
    memset(e, 0, sizeof *e);
}

/* The land along side s (of length S) from the end p of a side edge, dir
 * -1 (below p) or +1: to the next water beyond it, or (*corner set) to
 * the block corner where no water lies beyond; 0 where water touches p
 * there too (an end twice). */
static int64_t land_gap(const wm_side_ends *e, int s, int32_t p, int dir,
                        int32_t S, int *corner)
{
    const uint64_t *a = e->at[s];
    const size_t lo = wm_lower_u64(a, e->n[s], (uint64_t)p);
    const size_t hi = wm_lower_u64(a, e->n[s], (uint64_t)p + 1);
    *corner = dir < 0 ? lo == 0 : hi == e->n[s];
    if (hi - lo >= 2)
        return 0;
    if (dir < 0)
        return lo > 0 ? (int64_t)p - (int64_t)a[lo - 1] : p;
    return hi < e->n[s] ? (int64_t)a[hi] - p : (int64_t)S - p;
}

/* The shortest piece grading makes at an end of a side edge whose land
 * along the side runs `gap` (0: none) to the next water, or to a block
 * corner: most (grade_min), or half that gap, or twice that run to the
 * corner, where that is less, down to GRADE_INNER. A land notch a
 * fraction of a pixel wide at the side (a speck of land between two
 * water pieces reaching the side) has shore edges that short; a piece of
 * several pixels next to it, which refinement may not split, left
 * triangles of 2-7 degrees on the synthetic L1. A shore cutting a block
 * corner off leaves the side that near the corner, with an edge that
 * short to the other side: a piece of 8 pixels beside it left triangles
 * of 5-18 degrees (synthetic L1 at 2 m pixels and 512 m blocks; once the
 * run, not twice, added twice the triangles and cured no more). Both are
 * global: the water along a side is the same in both blocks. */
static int64_t end_min(int64_t most, int64_t gap, int corner)
{
    const int64_t h = corner ? 2 * gap : gap / 2;
    return gap <= 0 || h >= most ? most : h > GRADE_INNER ? h : GRADE_INNER;
}

/* The shortest piece grading makes at a block corner that ends a side
 * edge (global position C along the side at F): grade_min's `most`, or
 * the room at the corner where that is less, down to GRADE_INNER. A shore
 * passing the corner within `most` ends the water along the other side
 * that near it, and a piece of `most` here, which refinement may not
 * split, left a triangle of 5 degrees between the two (synthetic L3, seed
 * 2). The room is global, so the four blocks at the corner agree. */
static int64_t corner_min(const wm_refine_opts *o, int vertical, int64_t F,
                          int64_t C, int64_t most)
{
    const double room = room_at(o, vertical, F, C, (double)most);
    return room >= (double)most ? most
           : room > GRADE_INNER ? (int64_t)room
                                : GRADE_INNER;
}

/* Balances the pieces e0 < cut[0] < ... < e1 of a side edge: a piece
 * more than four times as long as a neighbour is halved at its global
 * midpoint, until none is. Ruppert's algorithm cannot split a side piece,
 * so a long piece next to a short one (grading halved a piece where the
 * shore comes near the side, not its neighbour) leaves a skinny triangle
 * on it. A piece ending at a block corner (lo or hi, the square's ends
 * along the side) is balanced against a piece of `out` assumed beyond
 * the corner (half of grade_min: what grading usually leaves at an end;
 * the side across the corner, which this side cannot see, is balanced
 * alike), so it is at most twice grade_min long (16 pixels at SIMPLIFY
 * of a quarter pixel or more). The result depends on the pieces and the
 * corners alone (passes in ascending global order), so both blocks sharing
 * the side find the same points. (A ratio of 2 cured no more triangles on the
 * synthetic L1 and L3 and added 4-6 % of them.) */
static int balance_side(lbuf *cut, int64_t e0, int64_t e1, int64_t lo,
                        int64_t hi, int64_t out_lo, int64_t out_hi)
{
    lbuf p = {NULL, 0, 0}, q = {NULL, 0, 0};
    int ok = lpush(&p, e0);
    for (size_t i = 0; ok && i < cut->n; i++)
        ok = lpush(&p, cut->a[i]);
    ok = ok && lpush(&p, e1);
    for (int changed = 1; ok && changed;)
    {
        changed = 0;
        q.n = 0;
        for (size_t i = 0; ok && i + 1 < p.n; i++)
        {
            const int64_t len = p.a[i + 1] - p.a[i];
            const int64_t l = i > 0          ? p.a[i] - p.a[i - 1]
                              : p.a[i] == lo ? out_lo
                                             : len;
            const int64_t rr = i + 2 < p.n        ? p.a[i + 2] - p.a[i + 1]
                               : p.a[i + 1] == hi ? out_hi
                                                  : len;
            ok = lpush(&q, p.a[i]);
            if (ok && (len > 4 * l || len > 4 * rr))
            {
                ok = lpush(&q, wm_floordiv(p.a[i] + p.a[i + 1], 2));
                changed = 1;
            }
        }
        ok = ok && lpush(&q, e1);
        const lbuf t = p;
        p = q;
        q = t;
    }
    if (ok)
    {
        cut->n = 0;
        for (size_t i = 1; ok && i + 1 < p.n; i++)
            ok = lpush(cut, p.a[i]);
    }
    free(p.a);
    free(q.a);
    return ok;
}

/* The global positions (along the side, ascending) cutting ring edge
 * a -> b on the block square into cut: when it is longer than max_edge, at
 * the global multiples of max_edge along the side, and, with min_angle and
 * a room callback, grading each piece (grade_side). Both blocks sharing the
 * side find the same exact lattice points. *o0 is the side's origin along
 * it (block-local = global - *o0). */
static int side_cut(const wm_refine_opts *o, wm_pt a, wm_pt b, lbuf *cut,
                    int64_t *o0)
{
    const int64_t L = (int64_t)floor(o->max_edge);
    const int vertical = a.x == b.x;
    *o0 = vertical ? o->Y0 : o->X0;
    const int64_t F = vertical ? o->X0 + a.x : o->Y0 + a.y;
    const int32_t pa = vertical ? a.y : a.x, pb = vertical ? b.y : b.x;
    const int32_t p0 = pa < pb ? pa : pb, p1 = pa < pb ? pb : pa;
    const int64_t e0 = *o0 + p0, e1 = *o0 + p1;
    const int grade = o->min_angle > 0 && o->room;
    const wm_side_ends *ends = o->ends;
    const int s = side_of(a, b);
    const int64_t most = grade_min(o);
    const int64_t c0 =
        grade && p0 == 0 ? corner_min(o, vertical, F, *o0, most) : most;
    const int64_t c1 = grade && p1 == o->side
                           ? corner_min(o, vertical, F, *o0 + o->side, most)
                           : most;
    int k0 = 0, k1 = 0;
    const int64_t l0 = ends ? land_gap(ends, s, p0, -1, o->side, &k0) : 0;
    const int64_t l1 = ends ? land_gap(ends, s, p1, +1, o->side, &k1) : 0;
    const int64_t g0 = end_min(most, l0, k0), g1 = end_min(most, l1, k1);
    const side_span e = {e0, e1, g0 < c0 ? g0 : c0, g1 < c1 ? g1 : c1};
    int ok = 1;
    for (int64_t u = e0; ok && u < e1;)
    {
        /* the next multiple of L past u when the edge is longer than L,
         * else the end */
        int64_t v = L >= 1 && e1 - e0 > L ? (wm_floordiv(u, L) + 1) * L : e1;
        v = v < e1 ? v : e1;
        ok = (!grade || grade_side(o, vertical, F, u, v, &e, cut)) &&
             (v == e1 || lpush(cut, v));
        u = v;
    }
    return ok && (!grade || balance_side(cut, e0, e1, *o0, *o0 + o->side,
                                         c0 < most / 2 ? c0 : most / 2,
                                         c1 < most / 2 ? c1 : most / 2));
}

/* Appends to out the points cutting ring edge a -> b on the block square
 * (side_cut), in the edge's direction. */
static int cut_side(refiner *r, wm_pt a, wm_pt b, ibuf *out)
{
    lbuf cut = {NULL, 0, 0};
    int64_t o;
    int ok = side_cut(r->o, a, b, &cut, &o);
    const int vertical = a.x == b.x;
    const int fwd = vertical ? a.y < b.y : a.x < b.x;
    for (size_t i = 0; ok && i < cut.n; i++)
    {
        const int64_t g = fwd ? cut.a[i] : cut.a[cut.n - 1 - i];
        const wm_pt m = vertical ? (wm_pt){a.x, (int32_t)(g - o)}
                                 : (wm_pt){(int32_t)(g - o), a.y};
        int32_t im;
        ok = add_point(r, m, &im) && ibuf_push(out, im);
    }
    free(cut.a);
    return ok;
}

int wm_side_pieces(const wm_rings *rings, const wm_refine_opts *o,
                   wm_side_piece **out, size_t *n)
{
    size_t cap = 0;
    lbuf cut = {NULL, 0, 0};
    int ok = 1;
    *out = NULL;
    *n = 0;
    for (size_t q = 0; ok && q < rings->nrings; q++)
    {
        const size_t b0 = rings->start[q], len = rings->start[q + 1] - b0;
        for (size_t i = 0; ok && i < len; i++)
        {
            const wm_pt a = rings->pts[b0 + i],
                        b = rings->pts[b0 + (i + 1) % len];
            if (!on_side(o->side, a, b))
                continue;
            int64_t org;
            cut.n = 0;
            ok = side_cut(o, a, b, &cut, &org);
            const int vertical = a.x == b.x;
            const int32_t p0 =
                vertical ? (a.y < b.y ? a.y : b.y) : (a.x < b.x ? a.x : b.x);
            const int32_t p1 =
                vertical ? (a.y < b.y ? b.y : a.y) : (a.x < b.x ? b.x : a.x);
            int32_t u = p0;
            for (size_t k = 0; ok && k <= cut.n; k++)
            {
                const int32_t v = k < cut.n ? (int32_t)(cut.a[k] - org) : p1;
                const wm_side_piece pc = {
                    vertical ? (wm_pt){a.x, u} : (wm_pt){u, a.y},
                    vertical ? (wm_pt){a.x, v} : (wm_pt){v, a.y}};
                ok = wm_push((void **)out, n, &cap, &pc, sizeof pc);
                u = v;
            }
        }
    }
    free(cut.a);
    if (!ok)
    {
        free(*out);
        *out = NULL;
        *n = 0;
    }
    return ok;
}

/* Cuts the ring edges on the block square (cut_side) and, with `shores`,
 * those longer than max_edge into equal pieces (points rounded to the
 * lattice), so that refinement does not halve them round after round. */
static int cut_long_edges(refiner *r, int shores)
{
    const int64_t L = (int64_t)floor(r->o->max_edge);
    if (L < 1 && r->o->min_angle <= 0)
        return 1;
    ibuf out = {NULL, 0, 0};
    size_t *ns = malloc((r->nrings + 1) * sizeof *ns);
    int ok = ns != NULL;
    for (size_t q = 0; ok && q < r->nrings; q++)
    {
        ns[q] = out.n;
        const size_t b0 = r->rstart[q], len = r->rstart[q + 1] - b0;
        for (size_t i = 0; ok && i < len; i++)
        {
            const int32_t ia = r->ring.a[b0 + i];
            const int32_t ib = r->ring.a[b0 + (i + 1) % len];
            ok = ibuf_push(&out, ia);
            const wm_pt a = r->P[ia], b = r->P[ib];
            if (ok && on_square(r, a, b))
                ok = cut_side(r, a, b, &out);
            else if (ok && shores && L >= 1)
                ok = cut_evenly(r, a, b, (double)L, &out);
        }
    }
    if (ok)
    {
        ns[r->nrings] = out.n;
        free(r->ring.a);
        free(r->rstart);
        r->ring = out;
        r->rstart = ns;
        return 1;
    }
    free(out.a);
    free(ns);
    return 0;
}

static double d2(wm_pt a, wm_pt b)
{
    const double dx = (double)a.x - b.x, dy = (double)a.y - b.y;
    return dx * dx + dy * dy;
}

/* With max_edge: seeds the points of a global triangular lattice of side
 * 0.9 max_edge that lie inside a triangle of the plain CDT (r->tris) with
 * an edge over max_edge, a third of the side or more from its edges (off
 * the ring edges, and apart from the seeds of the triangles beside), so
 * that most of the interior is meshed in the first round; refinement does
 * the rest. The lattice is global: the seeds do not depend on the block
 * or the thread. */
static int seed_grid(refiner *r)
{
    const double h = floor(0.9 * r->o->max_edge);
    const double hy = floor(h * 0.8660254037844386);
    if (h < 4 || hy < 4)
        return 1;
    const double X0 = (double)r->o->X0, Y0 = (double)r->o->Y0;
    for (size_t t = 0; t < r->ntris; t++)
    {
        const uint32_t *v = r->tris + 3 * t;
        const wm_pt p[3] = {r->P[v[0]], r->P[v[1]], r->P[v[2]]};
        double lmax = 0, len[3];
        for (int k = 0; k < 3; k++)
        {
            len[k] = sqrt(d2(p[k], p[(k + 1) % 3]));
            lmax = len[k] > lmax ? len[k] : lmax;
        }
        if (lmax * lmax <= r->max2)
            continue;
        double x0 = p[0].x, x1 = p[0].x, y0 = p[0].y, y1 = p[0].y;
        for (int k = 1; k < 3; k++)
        {
            x0 = p[k].x < x0 ? p[k].x : x0;
            x1 = p[k].x > x1 ? p[k].x : x1;
            y0 = p[k].y < y0 ? p[k].y : y0;
            y1 = p[k].y > y1 ? p[k].y : y1;
        }
        /* global rows j * hy, columns i * h (+ h / 2 on odd rows) */
        for (double j = ceil((y0 + Y0) / hy); j * hy - Y0 <= y1; j++)
        {
            const double shift = fmod(fabs(j), 2.0) == 1.0 ? h / 2 : 0;
            const double y = j * hy - Y0;
            /* the triangle's x range on this row (its edges crossing it) */
            double lo = x1, hi = x0;
            for (int k = 0; k < 3; k++)
            {
                const wm_pt a = p[k], b = p[(k + 1) % 3];
                if ((a.y > y) == (b.y > y) && a.y != y)
                    continue;
                const double x = a.y == b.y
                                     ? a.x
                                     : a.x + ((double)b.x - a.x) * (y - a.y) /
                                                 ((double)b.y - a.y);
                lo = x < lo ? x : lo;
                hi = x > hi ? x : hi;
                if (a.y == b.y)
                {
                    lo = b.x < lo ? b.x : lo;
                    hi = b.x > hi ? b.x : hi;
                }
            }
            for (double i = ceil((lo + X0 - shift) / h);
                 i * h + shift - X0 <= hi; i++)
            {
                const wm_pt q = {(int32_t)(i * h + shift - X0), (int32_t)y};
                int inside = 1;
                for (int k = 0; k < 3 && inside; k++)
                    inside = (double)wm_orient_det(p[k], p[(k + 1) % 3], q) >=
                             len[k] * h / 3;
                int32_t idx;
                const size_t before = r->np;
                if (!inside)
                    continue;
                if (!add_point(r, q, &idx))
                    return 0;
                if (r->np > before && !ibuf_push(&r->steiner, idx))
                    return 0;
            }
        }
    }
    return 1;
}

static wm_status index_tris(refiner *r);
static wm_status adopt(refiner *r, uint32_t *t, size_t nt, int32_t *nb);

/* The next round triangulates from scratch (the rings went back to an
 * earlier state, or the kept triangulation refused a change). */
static void drop_live(refiner *r)
{
    wm_cdt_free(r->live);
    r->live = NULL;
    r->cuts.n = 0;
}

/* Point index x is vertex number v of r->live. */
static int live_add(refiner *r, int32_t x, uint32_t v)
{
    return wm_map_set(&r->live_of, &r->live_cap, (size_t)x, (int32_t)v) &&
           r->live_map.n == v && ibuf_push(&r->live_map, x);
}

static int32_t live_vertex(const refiner *r, int32_t x)
{
    return (size_t)x < r->live_cap ? r->live_of[x] : -1;
}

/* Brings r->live up to the current rings and Steiner points: the round's
 * ring splits, then the Steiner points it lacks. WM_ERR_INVALID when there
 * is none or it refuses a change (then it is dropped, and the caller
 * triangulates from scratch, which reports the change as before). */
static wm_status update_live(refiner *r, const wm_ctx *quiet, uint32_t **t,
                             size_t *nt, int32_t **nb)
{
    if (!r->live)
        return WM_ERR_INVALID;
    wm_status st = WM_OK;
    for (size_t i = 0; i + 2 < r->cuts.n && st == WM_OK; i += 3)
    {
        const int32_t a = r->cuts.a[i], b = r->cuts.a[i + 1];
        const int32_t m = r->cuts.a[i + 2];
        const int32_t have = live_vertex(r, m);
        uint32_t q = have < 0 ? UINT32_MAX : (uint32_t)have;
        st = wm_cdt_split(r->live, (uint32_t)live_vertex(r, a),
                          (uint32_t)live_vertex(r, b), r->P[m], &q, quiet);
        if (st == WM_OK && have < 0 && !live_add(r, m, q))
            st = WM_ERR_NOMEM;
    }
    r->cuts.n = 0;
    wm_pt *in = NULL;
    size_t k = 0;
    if (st == WM_OK)
        in = malloc((r->steiner.n + 1) * sizeof *in);
    if (st == WM_OK && !in)
        st = WM_ERR_NOMEM;
    const uint32_t first = (uint32_t)r->live_map.n;
    for (size_t i = 0; st == WM_OK && i < r->steiner.n; i++)
    {
        const int32_t x = r->steiner.a[i];
        if (live_vertex(r, x) >= 0)
            continue;
        in[k] = r->P[x];
        if (!live_add(r, x, first + (uint32_t)k++))
            st = WM_ERR_NOMEM;
    }
    if (st == WM_OK)
        st = wm_cdt_insert(r->live, in, k, t, nt, nb, quiet);
    free(in);
    if (st != WM_OK)
        drop_live(r);
    return st == WM_ERR_NOMEM ? wm_fail(r->ctx, st, "refine: out of memory")
                              : st;
}

/* Triangulates the rings and the Steiner points; indexes the result. */
static wm_status triangulate(refiner *r)
{
    uint32_t *t = NULL;
    int32_t *nb = NULL;
    size_t nt = 0;
    const wm_ctx quiet = {NULL, NULL, r->ctx ? r->ctx->cancel : NULL};
    wm_status st = update_live(r, &quiet, &t, &nt, &nb);
    if (st == WM_OK)
        return adopt(r, t, nt, nb);
    if (st == WM_ERR_NOMEM)
        return st;
    const size_t nin = r->ring.n + r->steiner.n;
    wm_pt *in = malloc((nin + 1) * sizeof *in);
    if (!in)
        return wm_fail(r->ctx, WM_ERR_NOMEM, "refine: out of memory");
    for (size_t i = 0; i < r->ring.n; i++)
        in[i] = r->P[r->ring.a[i]];
    for (size_t i = 0; i < r->steiner.n; i++)
        in[r->ring.n + i] = r->P[r->steiner.a[i]];
    drop_live(r);
    st = wm_cdt_open(in, r->rstart, r->nrings, r->steiner.n, &r->live, &t, &nt,
                     &nb, &quiet);
    free(in);
    if (st != WM_OK)
        return st;
    for (size_t i = 0; i < r->live_cap; i++)
        r->live_of[i] = -1;
    r->live_map.n = 0;
    for (size_t i = 0; i < nin; i++)
        if (!live_add(
                r, i < r->ring.n ? r->ring.a[i] : r->steiner.a[i - r->ring.n],
                (uint32_t)i))
        {
            free(t);
            free(nb);
            return wm_fail(r->ctx, WM_ERR_NOMEM, "refine: out of memory");
        }
    return adopt(r, t, nt, nb);
}

/* Takes the triangles t (the live CDT's vertex numbers) and their
 * neighbours nb as the current triangulation; indexes the ring edges. */
static wm_status adopt(refiner *r, uint32_t *t, size_t nt, int32_t *nb)
{
    free(r->nb);
    r->nb = nb;
    for (size_t i = 0; i < 3 * nt; i++) /* to point indices */
        t[i] = (uint32_t)r->live_map.a[t[i]];
    free(r->tris);
    r->tris = t;
    r->ntris = nt;
    return index_tris(r);
}

/* Indexes the ring edges. */
static wm_status index_tris(refiner *r)
{
    if (!map_init(&r->redge, r->ring.n))
        return wm_fail(r->ctx, WM_ERR_NOMEM, "refine: out of memory");
    for (size_t q = 0; q < r->nrings; q++)
    {
        const size_t b0 = r->rstart[q], len = r->rstart[q + 1] - b0;
        for (size_t i = 0; i < len; i++)
            map_put(
                &r->redge,
                undirected(r->ring.a[b0 + i], r->ring.a[b0 + (i + 1) % len]),
                (int64_t)(b0 + i));
    }
    return WM_OK;
}

/* The cosine of the smallest angle of triangle p (larger is sharper), its
 * vertex *s (opposite the shortest edge), and l[i], the squared length of
 * the edge opposite vertex i. */
static double sharpest(const wm_pt p[3], double l[3], int *s)
{
    for (int i = 0; i < 3; i++)
        l[i] = d2(p[(i + 1) % 3], p[(i + 2) % 3]);
    *s = 0;
    for (int i = 1; i < 3; i++)
        *s = l[i] < l[*s] ? i : *s;
    const double b2 = l[(*s + 1) % 3], c2 = l[(*s + 2) % 3];
    return (b2 + c2 - l[*s]) / (2 * sqrt(b2 * c2));
}

/* Triangle t's badness: 0 fine, else LONG (an edge over max_edge) and/or
 * SHARP (an angle below min_angle, not an input angle); *input set when
 * its smallest angle lies between two ring edges. */
#define LONG 1
#define SHARP 2
static int bad(const refiner *r, size_t t, int *input)
{
    const uint32_t *v = r->tris + 3 * t;
    const wm_pt p[3] = {r->P[v[0]], r->P[v[1]], r->P[v[2]]};
    double l[3];
    int s;
    const double cosa = sharpest(p, l, &s);
    *input = 0;
    int is_bad = l[0] > r->max2 || l[1] > r->max2 || l[2] > r->max2 ? LONG : 0;
    if (cosa > r->cos_min)
    {
        /* the two edges at vertex s */
        const int32_t a = (int32_t)v[s], b = (int32_t)v[(s + 1) % 3];
        const int32_t c = (int32_t)v[(s + 2) % 3];
        *input = map_get(&r->redge, undirected(a, b)) >= 0 &&
                 map_get(&r->redge, undirected(a, c)) >= 0;
        is_bad |= *input ? 0 : SHARP;
    }
    return is_bad;
}

/* The circumcentre of triangle t, rounded to the lattice; 0 when it is
 * too far to matter (a nearly flat triangle: its longest edge is split
 * through the walk instead). */
static int circumcentre(const refiner *r, size_t t, wm_pt *c)
{
    const uint32_t *v = r->tris + 3 * t;
    const wm_pt a = r->P[v[0]], b = r->P[v[1]], q = r->P[v[2]];
    const double bx = (double)b.x - a.x, by = (double)b.y - a.y;
    const double cx = (double)q.x - a.x, cy = (double)q.y - a.y;
    const double d = 2 * (bx * cy - by * cx);
    if (d == 0)
        return 0;
    const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
    const double ux = a.x + (cy * b2 - by * c2) / d;
    const double uy = a.y + (bx * c2 - cx * b2) / d;
    const double lim = 2.0 * WM_LOCAL_MAX;
    if (!(fabs(ux) < lim && fabs(uy) < lim))
        return 0;
    c->x = (int32_t)llround(ux);
    c->y = (int32_t)llround(uy);
    return 1;
}

/* The ends of the ring edge at ring position k. */
static void ring_edge(const refiner *r, int64_t k, wm_pt *a, wm_pt *b)
{
    const size_t q0 = (size_t)k;
    const size_t q = wm_run_of(r->rstart, r->nrings, q0);
    const size_t len = r->rstart[q + 1] - r->rstart[q];
    *a = r->P[r->ring.a[q0]];
    *b = r->P[r->ring.a[r->rstart[q] + (q0 - r->rstart[q] + 1) % len]];
}

/* Marks ring position k's edge to be split; 0 when it may not be (on the
 * block square, or too short). */
static int want_split(refiner *r, int64_t k)
{
    wm_pt a, b;
    ring_edge(r, k, &a, &b);
    /* a split must add a vertex, and never one on the block square: the
     * block across would not have it */
    const wm_pt m = split_point(r, k);
    if (r->nosplit || on_square(r, a, b) || wm_pt_eq(m, a) || wm_pt_eq(m, b) ||
        on_square_pt(r, m))
        return 0;
    r->nsplit += !r->split[k];
    r->split[k] = 1;
    return 1;
}

/* The ring edge among the edges of triangle t and its neighbours whose
 * diametral circle holds c: its ring position, or -1. */
static int64_t encroached(const refiner *r, size_t t, wm_pt c)
{
    size_t tri[4] = {t, t, t, t};
    for (int i = 0; i < 3; i++)
    {
        const int32_t g = r->nb[3 * t + (size_t)i];
        if (g >= 0)
            tri[i + 1] = (size_t)g / 3;
    }
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 3; i++)
        {
            const uint32_t *v = r->tris + 3 * tri[k];
            const int32_t a = (int32_t)v[i], b = (int32_t)v[(i + 1) % 3];
            const int64_t pos = map_get(&r->redge, undirected(a, b));
            if (pos < 0)
                continue;
            const wm_pt pa = r->P[a], pb = r->P[b];
            const double dot = ((double)pa.x - c.x) * ((double)pb.x - c.x) +
                               ((double)pa.y - c.y) * ((double)pb.y - c.y);
            if (dot <= 0)
                return pos;
        }
    return -1;
}

/* Whether c lies on a ring edge of triangle t (exact): a point there
 * would break the CDT's contract. c lies in t's closure. */
static int on_ring_edge(const refiner *r, size_t t, wm_pt c)
{
    const uint32_t *v = r->tris + 3 * t;
    for (int i = 0; i < 3; i++)
    {
        const int32_t a = (int32_t)v[i], b = (int32_t)v[(i + 1) % 3];
        if (wm_orient(r->P[a], r->P[b], c) == 0 &&
            map_get(&r->redge, undirected(a, b)) >= 0)
            return 1;
    }
    return 0;
}

/* Walks from triangle t towards c: the triangle holding c (*hold), or the
 * ring edge crossed on the way (its position; *hold = SIZE_MAX). Returns
 * 0 when the walk fails (a step bound). */
static int walk(const refiner *r, size_t t, wm_pt c, size_t *hold,
                int64_t *crossed)
{
    for (size_t steps = 0; steps <= r->ntris; steps++)
    {
        const uint32_t *v = r->tris + 3 * t;
        int moved = 0;
        for (int i = 0; i < 3 && !moved; i++)
        {
            const int32_t a = (int32_t)v[i], b = (int32_t)v[(i + 1) % 3];
            if (wm_orient(r->P[a], r->P[b], c) >= 0)
                continue;
            const int64_t pos = map_get(&r->redge, undirected(a, b));
            if (pos >= 0)
            {
                *hold = SIZE_MAX;
                *crossed = pos;
                return 1;
            }
            const int32_t g = r->nb[3 * t + (size_t)i];
            if (g < 0)
                return 0;
            t = (size_t)g / 3;
            moved = 1;
        }
        if (!moved)
        {
            *hold = t;
            return 1;
        }
    }
    return 0;
}

/* Marks triangle t and its neighbours as changed by this round: their
 * bad ones wait for the next (inserting points whose cavities overlap in
 * one batch would crowd them: Ruppert's algorithm inserts one at a time). */
static void touch(refiner *r, size_t t)
{
    r->touched[t] = 1;
    for (int i = 0; i < 3; i++)
    {
        const int32_t g = r->nb[3 * t + (size_t)i];
        if (g >= 0)
            r->touched[g / 3] = 1;
    }
}

/* The midpoint of triangle t's longest edge that is not a ring edge,
 * rounded: where a point goes when t's circumcentre would split a ring
 * edge that may not be split (on the block square, or too short). 0 when
 * every edge of t is a ring edge. */
static int interior_midpoint(const refiner *r, size_t t, wm_pt *m)
{
    const uint32_t *v = r->tris + 3 * t;
    double best = -1;
    for (int i = 0; i < 3; i++)
    {
        const int32_t a = (int32_t)v[i], b = (int32_t)v[(i + 1) % 3];
        const double l = d2(r->P[a], r->P[b]);
        if (l <= best || map_get(&r->redge, undirected(a, b)) >= 0)
            continue;
        best = l;
        m->x = (int32_t)(((int64_t)r->P[a].x + r->P[b].x) >> 1);
        m->y = (int32_t)(((int64_t)r->P[a].y + r->P[b].y) >> 1);
    }
    return best >= 4;
}

/* Adds Steiner point c, held by triangle hold, for bad triangle t: 1
 * added, 0 not (a point already there), -1 out of memory. */
static int add_steiner(refiner *r, size_t t, size_t hold, wm_pt c)
{
    const size_t before = r->np;
    int32_t idx;
    if (!add_point(r, c, &idx))
        return -1;
    if (r->np == before)
        return 0;
    if (!ibuf_push(&r->steiner, idx))
        return -1;
    r->nnew++;
    touch(r, t);
    touch(r, hold);
    return 1;
}

/* Whether point c, with ring edge pos (on the block square, kept) as its
 * base, would make a sharper triangle than t. */
static int kept_worse(const refiner *r, size_t t, int64_t pos, wm_pt c)
{
    wm_pt a, b;
    ring_edge(r, pos, &a, &b);
    if (!on_square(r, a, b))
        return 0;
    const uint32_t *v = r->tris + 3 * t;
    const wm_pt now[3] = {r->P[v[0]], r->P[v[1]], r->P[v[2]]};
    const wm_pt then[3] = {a, b, c};
    double l[3];
    int s;
    return sharpest(then, l, &s) > sharpest(now, l, &s);
}

/* What bad triangle t does this round: splits a ring edge or adds its
 * circumcentre (1), waits for a neighbour's change (2), can do nothing
 * (0), or runs out of memory (-1). */
static int cure(refiner *r, size_t t, int why)
{
    if (r->touched[t])
        return 2;
    wm_pt c;
    size_t hold;
    int64_t pos = -1;
    if (!circumcentre(r, t, &c) || !walk(r, t, c, &hold, &pos))
        return 0;
    if (hold != SIZE_MAX)
    {
        if (r->touched[hold])
            return 2;
        pos = encroached(r, hold, c);
    }
    if (pos < 0)
        return add_steiner(r, t, hold, c);
    if (want_split(r, pos))
    {
        touch(r, t);
        return 1;
    }
    /* a ring edge that stays (on the block square, too short, or after a
     * split broke the CDT): a sharp triangle whose circumcentre lies inside
     * takes it anyway (that empties its circumcircle; only the edge kept is
     * encroached), unless the edge kept is a side piece it would make a
     * sharper triangle on (kept_worse); a long one takes the middle of its
     * longest inner edge (edges halve: this ends) */
    if (!(why & LONG) && kept_worse(r, t, pos, c))
        return 0;
    if (!(why & LONG))
        return hold == SIZE_MAX || on_ring_edge(r, hold, c)
                   ? 0
                   : add_steiner(r, t, hold, c);
    if (!interior_midpoint(r, t, &c) || !walk(r, t, c, &hold, &pos) ||
        hold == SIZE_MAX)
        return 0;
    if (r->touched[hold])
        return 2;
    return on_ring_edge(r, hold, c) ? 0 : add_steiner(r, t, hold, c);
}

/* One round: rates every triangle, collects circumcentres and splits. */
static int rate(refiner *r, size_t *left, size_t *small_input, size_t *pending)
{
    *left = *small_input = *pending = 0;
    for (size_t t = 0; t < r->ntris; t++)
    {
        int input;
        const int why = bad(r, t, &input);
        *small_input += input;
        if (!why)
            continue;
        const int c = cure(r, t, why);
        if (c < 0)
            return 0;
        *left += c == 0;
        *pending += c != 0; /* being cured, or waiting for the next round */
    }
    return 1;
}

/* Applies the round's splits: midpoints rounded to the lattice. */
static int apply_splits(refiner *r)
{
    ibuf out = {NULL, 0, 0};
    size_t *ns = malloc((r->nrings + 1) * sizeof *ns);
    const size_t np0 = r->np;
    uint8_t *was = calloc(np0 + 1, 1); /* ring points before the splits */
    int ok = ns != NULL && was != NULL;
    for (size_t i = 0; ok && i < r->ring.n; i++)
        was[r->ring.a[i]] = 1;
    for (size_t q = 0; ok && q < r->nrings; q++)
    {
        ns[q] = out.n;
        const size_t b0 = r->rstart[q], len = r->rstart[q + 1] - b0;
        for (size_t i = 0; ok && i < len; i++)
        {
            ok = ibuf_push(&out, r->ring.a[b0 + i]);
            if (!ok || !r->split[b0 + i])
                continue;
            const wm_pt m = split_point(r, (int64_t)(b0 + i));
            int32_t im;
            const size_t before = r->np;
            ok = add_point(r, m, &im);
            /* a new point, or a Steiner point the rounding met; never a
             * ring's vertex */
            if (ok && (r->np > before || ((size_t)im < np0 && !was[im])))
                ok = ibuf_push(&out, im) &&
                     ibuf_push(&r->cuts, r->ring.a[b0 + i]) &&
                     ibuf_push(&r->cuts, r->ring.a[b0 + (i + 1) % len]) &&
                     ibuf_push(&r->cuts, im);
        }
    }
    free(was);
    if (!ok)
    {
        free(out.a);
        free(ns);
        return 0;
    }
    ns[r->nrings] = out.n;
    free(r->ring.a);
    free(r->rstart);
    r->ring = out;
    r->rstart = ns;
    /* a Steiner point the rounding of a midpoint met is a ring point now */
    uint8_t *on = calloc(r->np + 1, 1);
    if (!on)
        return 0;
    for (size_t i = 0; i < r->ring.n; i++)
        on[r->ring.a[i]] = 1;
    size_t k = 0;
    for (size_t i = 0; i < r->steiner.n; i++)
        if (!on[r->steiner.a[i]])
            r->steiner.a[k++] = r->steiner.a[i];
    r->steiner.n = k;
    free(on);
    return 1;
}

static void refiner_free(refiner *r)
{
    drop_live(r);
    free(r->live_map.a);
    free(r->live_of);
    free(r->cuts.a);
    free(r->P);
    free(r->ring.a);
    free(r->rstart);
    free(r->steiner.a);
    free(r->pts.k);
    free(r->pts.v);
    free(r->tris);
    free(r->nb);
    free(r->redge.k);
    free(r->redge.v);
    free(r->split);
    free(r->touched);
}

/* Copies the current triangulation and the added points it uses into the
 * result (a good triangulation: the result so far), the points renumbered
 * in their order. 0: out of memory. */
static int snapshot(const refiner *r, size_t n, uint32_t **tris, size_t *ntris,
                    wm_pt **extra, size_t *nextra)
{
    free(*tris);
    free(*extra);
    *tris = malloc((3 * r->ntris + 1) * sizeof **tris);
    *extra = malloc((r->np - n + 1) * sizeof **extra);
    uint32_t *to = calloc(r->np - n + 1, sizeof *to); /* 0: unused */
    if (!*tris || !*extra || !to)
    {
        free(to);
        return 0;
    }
    for (size_t i = 0; i < 3 * r->ntris; i++)
        if (r->tris[i] >= n)
            to[r->tris[i] - n] = 1;
    size_t k = 0;
    for (size_t i = 0; i < r->np - n; i++)
        if (to[i])
        {
            (*extra)[k] = r->P[n + i];
            to[i] = (uint32_t)(n + k++);
        }
    for (size_t i = 0; i < 3 * r->ntris; i++)
        (*tris)[i] = r->tris[i] < n ? r->tris[i] : to[r->tris[i] - n];
    *ntris = r->ntris;
    *nextra = k;
    free(to);
    return 1;
}

/* The rings and the Steiner count before a round's changes. */
typedef struct
{
    ibuf ring;
    size_t *rstart;
    size_t nsteiner;
} saved;

static int save(const refiner *r, saved *s)
{
    s->ring.n = 0;
    for (size_t i = 0; i < r->ring.n; i++)
        if (!ibuf_push(&s->ring, r->ring.a[i]))
            return 0;
    free(s->rstart);
    s->rstart = malloc((r->nrings + 1) * sizeof *s->rstart);
    if (!s->rstart)
        return 0;
    memcpy(s->rstart, r->rstart, (r->nrings + 1) * sizeof *s->rstart);
    s->nsteiner = r->steiner.n;
    return 1;
}

/* Puts the saved rings back (and the Steiner points too with all). */
static int restore(refiner *r, const saved *s, int all)
{
    drop_live(r);
    r->ring.n = 0;
    for (size_t i = 0; i < s->ring.n; i++)
        if (!ibuf_push(&r->ring, s->ring.a[i]))
            return 0;
    memcpy(r->rstart, s->rstart, (r->nrings + 1) * sizeof *r->rstart);
    if (all)
        r->steiner.n = s->nsteiner;
    return 1;
}

/* Counts the bad triangles of the current triangulation: at input angles
 * and others. */
static void count_bad(const refiner *r, size_t *left, size_t *small_input)
{
    *left = *small_input = 0;
    for (size_t t = 0; t < r->ntris; t++)
    {
        int input;
        *left += bad(r, t, &input) != 0;
        *small_input += input;
    }
}

/* The triangles of the current triangulation below min_angle, not at an
 * input angle, with a vertex on the block square. */
static size_t count_at_side(const refiner *r)
{
    size_t n = 0;
    for (size_t t = 0; t < r->ntris; t++)
    {
        int input;
        const uint32_t *v = r->tris + 3 * t;
        n += (bad(r, t, &input) & SHARP) &&
             (on_square_pt(r, r->P[v[0]]) || on_square_pt(r, r->P[v[1]]) ||
              on_square_pt(r, r->P[v[2]]));
    }
    return n;
}

/* Refinement rounds from the current rings and Steiner points. WM_OK with
 * the result set; WM_ERR_INVALID when the CDT refuses the first round
 * (nothing set); WM_ERR_NOMEM. When a later round's changes break the CDT,
 * the round is retried without its splits (and splits stop), then the last
 * good triangulation is kept. *left counts the bad triangles of the result
 * but those at input angles (*small_input). */
static wm_status rounds(refiner *r, size_t n, double cap, uint32_t **tris,
                        size_t *ntris, wm_pt **extra, size_t *nextra,
                        size_t *left, size_t *small_input)
{
    saved sv;
    memset(&sv, 0, sizeof sv);
    wm_status st = WM_OK;
    int retried = 0;
    for (int round = 0; round < MAX_ROUNDS; round++)
    {
        st = triangulate(r);
        if (st != WM_OK && st != WM_ERR_NOMEM && round > 0)
        {
            /* the round's splits first (they move the shore), then all */
            const int all = retried || r->nosplit;
            if (!restore(r, &sv, all))
                st = WM_ERR_NOMEM;
            else if (!all)
            {
                r->nosplit = retried = 1;
                round--;
                continue;
            }
            else /* the last good triangulation and its maps stay */
            {
                count_bad(r, left, small_input);
                st = WM_OK;
                break;
            }
        }
        if (st != WM_OK)
            break;
        retried = 0;
        if (!save(r, &sv))
        {
            st = WM_ERR_NOMEM;
            break;
        }
        free(r->split);
        free(r->touched);
        r->split = calloc(r->ring.n + 1, 1);
        r->touched = calloc(r->ntris + 1, 1);
        r->nsplit = r->nnew = 0;
        size_t pending = 0;
        if (!r->split || !r->touched || !rate(r, left, small_input, &pending))
        {
            st = WM_ERR_NOMEM;
            break;
        }
        if (r->nsplit == 0 && r->nnew == 0)
            break;
        if ((double)r->np > cap || round == MAX_ROUNDS - 1 ||
            wm_cancelled(r->ctx))
        {
            *left += pending; /* stopped with these still bad */
            break;
        }
        if (r->nsplit && !apply_splits(r))
        {
            st = WM_ERR_NOMEM;
            break;
        }
    }
    /* r->tris: the last triangulation the CDT accepted */
    if (st == WM_OK && !snapshot(r, n, tris, ntris, extra, nextra))
        st = WM_ERR_NOMEM;
    free(sv.ring.a);
    free(sv.rstart);
    return st;
}

/* Starts again from the input rings, without Steiner points. */
static int reset(refiner *r, const size_t *ring_start, size_t n)
{
    drop_live(r);
    r->ring.n = 0;
    for (size_t i = 0; i < n; i++)
        if (!ibuf_push(&r->ring, (int32_t)i))
            return 0;
    memcpy(r->rstart, ring_start, (r->nrings + 1) * sizeof *r->rstart);
    r->steiner.n = 0;
    r->nosplit = 0;
    return 1;
}

wm_status wm_refine_triangulate(const wm_pt *pts, const size_t *ring_start,
                                size_t nrings, const wm_refine_opts *o,
                                uint32_t **tris, size_t *ntris, wm_pt **extra,
                                size_t *nextra, wm_refine_stats *stats,
                                const wm_ctx *ctx)
{
    refiner r;
    memset(&r, 0, sizeof r);
    r.o = o;
    r.ctx = ctx;
    *tris = NULL;
    *extra = NULL;
    *ntris = *nextra = 0;
    const size_t n = ring_start[nrings];
    r.cos_min = o->min_angle > 0 ? cos(o->min_angle * PI / 180.0) : 2.0;
    r.max2 = o->max_edge > 0 ? o->max_edge * o->max_edge : INFINITY;
    /* the input triangulation first: its errors are the caller's */
    wm_status st =
        wm_cdt_triangulate(pts, ring_start, nrings, &r.tris, &r.ntris, ctx);
    if (st != WM_OK)
        return st;
    r.nrings = nrings;
    r.rstart = malloc((nrings + 1) * sizeof *r.rstart);
    r.P = malloc((n + 1) * sizeof *r.P);
    if (!r.rstart || !r.P || !map_init(&r.pts, 2 * n))
        goto nomem;
    r.pcap = n + 1;
    r.nin = n;
    memcpy(r.rstart, ring_start, (nrings + 1) * sizeof *r.rstart);
    for (size_t i = 0; i < n; i++)
    {
        r.P[r.np++] = pts[i];
        map_put(&r.pts, point_key(pts[i]), (int64_t)i);
        if (!ibuf_push(&r.ring, (int32_t)i))
            goto nomem;
    }
    /* the most points: 16 per ring vertex (input or cut) and, with
     * max_edge, 8 per max_edge^2 of area (an equilateral mesh needs about
     * 2.3) */
    double area2 = 0;
    for (size_t q = 0; q < nrings; q++)
        area2 += (double)wm_ring_area2(pts + ring_start[q],
                                       ring_start[q + 1] - ring_start[q]);
    const double cap =
        16.0 * (double)n + 4096 + (o->max_edge > 0 ? 4 * area2 / r.max2 : 0);
    size_t left = 0, small_input = 0;
    /* with MAX_EDGE, long edges cut and the interior seeded first; if the
     * CDT refuses that (a rounded cut too close to another edge), the exact
     * cuts of the block square's edges alone, which the block across makes
     * too; if even that fails, the plain CDT */
    for (int prep = o->max_edge > 0 ? 2 : 1; prep >= 0; prep--)
    {
        if (prep < 2 && !reset(&r, ring_start, n))
            goto nomem;
        if ((prep == 2 && (!cut_long_edges(&r, 1) || !seed_grid(&r))) ||
            (prep == 1 && !cut_long_edges(&r, 0)))
            goto nomem;
        if (prep == 0) /* the plain CDT: r.tris is still the first one */
        {
            if (!reset(&r, ring_start, n) || index_tris(&r) != WM_OK ||
                !snapshot(&r, n, tris, ntris, extra, nextra))
                goto nomem;
            count_bad(&r, &left, &small_input);
            break;
        }
        /* the cuts made ring points: 16 more each */
        st = rounds(&r, n, cap + 16.0 * (double)(r.ring.n - n), tris, ntris,
                    extra, nextra, &left, &small_input);
        if (st == WM_ERR_NOMEM)
            goto nomem;
        if (st == WM_OK)
            break;
    }
    st = WM_OK;
    if (stats)
    {
        stats->steiner += *nextra;
        stats->small_input += small_input;
        stats->left += left;
        stats->at_side += o->min_angle > 0 ? count_at_side(&r) : 0;
    }
    goto done;
nomem:
    st = wm_fail(ctx, WM_ERR_NOMEM, "refine: out of memory");
done:
    if (st != WM_OK)
    {
        free(*tris);
        free(*extra);
        *tris = NULL;
        *extra = NULL;
        *ntris = *nextra = 0;
    }
    refiner_free(&r);
    return st;
}
