/*
 * cdt.c - constrained Delaunay triangulation (CDT) of a polygon with holes.
 *
 * Algorithm
 *   1. Delaunay triangulation of all ring vertices by incremental insertion
 *      with Lawson flips (Lawson 1977; Guibas, Knuth, Sharir 1992), in a
 *      biased randomized insertion order (BRIO; Amenta, Choi, Rote 2003)
 *      whose rounds follow the Morton curve; each point is located by a
 *      stochastic visibility walk from the last triangle created
 *      (Devillers, Pion, Teillaud 2002). A point on an edge splits it.
 *      Everything lies inside one fixed super triangle.
 *   2. Each ring edge a-b becomes a constraint by cavity re-triangulation
 *      (Anglada 1997): walk from a to b through the triangles the segment
 *      crosses, remove them, and triangulate the pseudo-polygon on each
 *      side, giving each edge the vertex whose circle with it holds no
 *      other vertex of the polygon. This keeps the triangulation
 *      constrained Delaunay (Chew 1989). Flip-based insertion (Sloan 1993)
 *      was tried first and dropped: on a zigzag of crossed edges no flip
 *      removes a crossing, and Sloan's rule may then cycle. A cavity may
 *      touch itself (its boundary visits a vertex twice, around a dangling
 *      edge or a pocket); each visit is kept as its own polygon position,
 *      the right one is picked by its interior angle, and the two sides of
 *      a dangling edge are paired up.
 *   3. A flood fill from the super triangle, toggling inside/outside at
 *      each constraint, keeps the triangles of the polygon; a Lawson pass
 *      over their other edges certifies (and would restore) the local
 *      Delaunay property. Vertex numbers are the caller's throughout (the
 *      super vertices come last), so nothing needs renumbering.
 *
 * Data structure: half-edges in flat int32 arrays, three per triangle
 * (h = 3t + i): v[h] is the origin of h, tw[h] its twin (-1 on the super
 * triangle's border), con[h] marks ring edges; ve[x] is one half-edge
 * leaving vertex x. Flips and cavities rewrite triangles in place and the
 * triangle count is known in advance (2n + 1): no per-triangle malloc.
 *
 * Complexity: O(n) for the ordering (one radix sort); O(n log n) expected
 * for the Delaunay triangulation whatever the point distribution; a ring
 * edge crossing k triangle edges costs O(k) to walk and, to re-triangulate,
 * O(k log k) typically and O(k^2) at worst. k is small for real rings (the
 * sum of all k was under 10n in every test). Measured at -O2: 1e5 vertices
 * in 0.05 to 0.13 s, 1e6 in 0.6 to 2.1 s (a star with random radii).
 *
 * Robustness: every decision is an exact integer predicate from lattice.h
 * (wm_orient in int64, wm_incircle in __int128); no epsilon, no floating
 * point. The super triangle has finite vertices within |c| < 2^26, where
 * wm_incircle is still exact, and takes part in the predicates like any
 * point. It is too small for the exact Delaunay triangulation of the hull
 * in general, which does not matter here: the outer ring is forced in as
 * constraints, everything outside it is discarded, and no super vertex is
 * visible from inside the polygon, so the result inside is exactly the CDT
 * of the polygon. Each cavity step is certified: its new triangles form a
 * disk with the cavity's boundary, so when all are counter-clockwise they
 * tile the cavity exactly. Contract violations met on the way (duplicate
 * vertex, vertex on a ring edge, crossing ring edges, wrong orientation,
 * wrong nesting, caught by the triangle count) give WM_ERR_INVALID; every
 * loop has a bound whose excess, like a failed certificate, gives
 * WM_ERR_INTERNAL.
 */
#include "cdt.h"
#include "lattice.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The input is at most 2^24 wide; the super triangle (-M,-M), (3.5M,-M),
 * (-M,3.5M) with M = 2^24 contains [0,M]^2 strictly (its hypotenuse is
 * x + y = 2.5M > 2M) and keeps every coordinate below 2^26. */
#define SUPER_M ((int32_t)WM_LOCAL_MAX)

/* Largest vertex count: 3 * (2n + 1) half-edges must fit in int32. */
#define MAX_PTS ((size_t)(INT32_MAX / 6 - 8))

typedef struct
{
    int32_t *a;
    size_t n, cap;
} ivec;

/* One side of a cavity: a polygon P[0..k] counter-clockwise whose closing
 * edge P[k]->P[0] is the constraint. Edge j = P[j]->P[j+1] was half-edge
 * hc[j] of a cavity triangle; o[j] is its twin outside, fl[j] its
 * constraint flag, anten[j] is 1 when o[j] is inside the cavity too. */
typedef struct
{
    ivec v, hc, o, fl, anten;
    int rep; /* some vertex occurs twice on the polygon */
} chain;

typedef struct
{
    const wm_ctx *ctx;
    wm_pt *p;     /* nv + 3 points: the input, then the super triangle */
    int32_t *v;   /* origin vertex of each half-edge */
    int32_t *tw;  /* twin half-edge, -1 on the super triangle's border */
    uint8_t *con; /* 1 on both half-edges of a ring edge */
    int32_t *ve;  /* one half-edge leaving each vertex */
    int32_t nv;   /* input vertices */
    int32_t np;   /* all vertices: the input's, the super triangle's, then
                     those wm_cdt_insert added */
    int32_t ntri; /* triangles in use */
    int32_t maxtri;
    uint8_t *state; /* per triangle, once labelled (flood_fill): 1 outside,
                       2 inside; NULL before */
    int anywhere;   /* insert_point takes a point outside the polygon too */
    int32_t last;   /* triangle the next point location starts from */
    uint32_t rng;   /* xorshift state for the stochastic walk */
    ivec stack;     /* Lawson work stack */
    /* constraint insertion scratch */
    int32_t *tstamp; /* per triangle: id of the cavity it last belonged to */
    int32_t *vstamp; /* per vertex: 2 * cavity id + side, to see repeats */
    int32_t cid;     /* current cavity id */
    chain side[2];   /* 0: right of a->b, 1: left */
    ivec cav;        /* triangles crossed by a->b, reused for the new ones */
    ivec tstk;       /* (lo, hi, parent half-edge) triples */
    ivec pend;       /* (new half-edge, old half-edge, old twin) triples */
} mesh;

static wm_status cdt_nomem(const mesh *m)
{
    return wm_fail(m->ctx, WM_ERR_NOMEM, "cdt: out of memory");
}

/* The vertex number inside the mesh of the caller's vertex x, and the
 * caller's number of mesh vertex x (not a super vertex): the three super
 * vertices sit between the polygon's vertices and the points added. */
static int32_t internal(const mesh *m, uint32_t x)
{
    return x < (uint32_t)m->nv ? (int32_t)x : (int32_t)x + 3;
}

static uint32_t external(const mesh *m, int32_t x)
{
    return (uint32_t)(x < m->nv ? x : x - 3);
}

/* Whether p lies in the lattice range the predicates are exact over. */
static int in_range(wm_pt p)
{
    return p.x >= 0 && p.y >= 0 && p.x <= WM_LOCAL_MAX && p.y <= WM_LOCAL_MAX;
}

static int ivec_push(ivec *s, int32_t x)
{
    if (s->n == s->cap)
    {
        const size_t ncap = s->cap ? 2 * s->cap : 64;
        if (ncap > SIZE_MAX / sizeof *s->a)
            return 0;
        int32_t *na = realloc(s->a, ncap * sizeof *na);
        if (!na)
            return 0;
        s->a = na;
        s->cap = ncap;
    }
    s->a[s->n++] = x;
    return 1;
}

static void *alloc_n(size_t n, size_t size)
{
    if (n == 0)
        n = 1;
    if (n > SIZE_MAX / size)
        return NULL;
    return malloc(n * size);
}

static inline int32_t nxt(int32_t h)
{
    return (h % 3 == 2) ? h - 2 : h + 1;
}

static inline int32_t prv(int32_t h)
{
    return (h % 3 == 0) ? h + 2 : h - 1;
}

static inline void pair_twins(mesh *m, int32_t a, int32_t b)
{
    m->tw[a] = b;
    if (b >= 0)
        m->tw[b] = a;
}

/* Writes triangle t = (a, b, c), counter-clockwise, whose first edge a->b
 * is a constraint when con_ab (the other two are new edges at an inserted
 * point); links are the caller's. */
static void set_tri(mesh *m, int32_t t, int32_t a, int32_t b, int32_t c,
                    uint8_t con_ab)
{
    const int32_t h = 3 * t;
    m->v[h] = a;
    m->v[h + 1] = b;
    m->v[h + 2] = c;
    m->con[h] = con_ab;
    m->con[h + 1] = m->con[h + 2] = 0;
    m->ve[a] = h;
    m->ve[b] = h + 1;
    m->ve[c] = h + 2;
}

/* Flips the edge of half-edge e. Before: e = a->b in (a, b, c), its twin
 * f = b->a in (b, a, d). After, in the same slots: (d, b, c) with e = d->b,
 * prv(e) = c->d; and (c, a, d) with f = c->a, prv(f) = d->c. The four outer
 * edges end up in slots e, nxt(e), f, nxt(f); the caller has checked that
 * the quad a, d, b, c is strictly convex. */
static void flip(mesh *m, int32_t e)
{
    const int32_t f = m->tw[e];
    const int32_t e1 = nxt(e), e2 = prv(e), f1 = nxt(f), f2 = prv(f);
    const int32_t a = m->v[e], b = m->v[e1], c = m->v[e2], d = m->v[f2];
    const int32_t te2 = m->tw[e2], tf2 = m->tw[f2];
    const uint8_t ce2 = m->con[e2], cf2 = m->con[f2];
    m->v[e] = d;
    m->v[f] = c;
    pair_twins(m, e, tf2);
    m->con[e] = cf2;
    pair_twins(m, f, te2);
    m->con[f] = ce2;
    pair_twins(m, e2, f2);
    m->con[e2] = m->con[f2] = 0;
    m->ve[a] = f1;
    m->ve[b] = e1;
    m->ve[c] = e2;
    m->ve[d] = f2;
}

/* True when the quad around half-edge h is strictly convex, i.e. h can be
 * flipped into two counter-clockwise triangles. */
static int flippable(const mesh *m, int32_t h)
{
    const int32_t g = m->tw[h];
    const wm_pt u = m->p[m->v[h]], w = m->p[m->v[nxt(h)]];
    const wm_pt c = m->p[m->v[prv(h)]], d = m->p[m->v[prv(g)]];
    return wm_orient(c, u, d) > 0 && wm_orient(d, w, c) > 0;
}

/* Lawson flips over the half-edges on m->stack until every edge seen is
 * locally Delaunay or a constraint. With `from_point`, the stack holds the
 * edges opposite a freshly inserted point, and only the two edges that face
 * it after a flip are pushed (the classic insertion step); otherwise all
 * four outer edges of a flipped quad are pushed. A slot on the stack may
 * hold another edge by the time it is popped: checking it is harmless, and
 * the edge it used to hold was pushed again by the flip that moved it. */
static wm_status lawson(mesh *m, int from_point, size_t budget)
{
    while (m->stack.n > 0)
    {
        const int32_t h = m->stack.a[--m->stack.n];
        const int32_t g = m->tw[h];
        if (g < 0 || m->con[h])
            continue;
        const wm_pt a = m->p[m->v[h]], b = m->p[m->v[nxt(h)]];
        const wm_pt c = m->p[m->v[prv(h)]], d = m->p[m->v[prv(g)]];
        if (wm_incircle(a, b, c, d) <= 0)
            continue;
        /* d inside the circle of (a, b, c) implies a convex quad; checking
         * costs two orientations and turns a corrupt mesh into an error */
        if (!flippable(m, h) || budget == 0)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: Lawson flip impossible or over budget");
        budget--;
        flip(m, h);
        if (!ivec_push(&m->stack, h) || !ivec_push(&m->stack, nxt(g)))
            return cdt_nomem(m);
        if (!from_point)
        {
            if (!ivec_push(&m->stack, nxt(h)) || !ivec_push(&m->stack, g))
                return cdt_nomem(m);
        }
    }
    return WM_OK;
}

/* Classifies p against triangle t: returns the first half-edge with p
 * strictly on its right (the walk goes there), or -1 when p is in the
 * closed triangle; then *zero is the half-edge p lies on (or -1) and *nz
 * the number of edges whose line holds p. */
static int32_t classify(const mesh *m, int32_t t, uint32_t r, wm_pt p,
                        int32_t *zero, int *nz)
{
    *zero = -1;
    *nz = 0;
    for (uint32_t k = 0; k < 3; k++)
    {
        const int32_t h = 3 * t + (int32_t)((r + k) % 3);
        const int o = wm_orient(m->p[m->v[h]], m->p[m->v[nxt(h)]], p);
        if (o < 0)
            return h;
        if (o == 0)
        {
            *zero = h;
            (*nz)++;
        }
    }
    return -1;
}

/* Finds the triangle holding point vi. *edge is the half-edge vi lies on,
 * or -1 when it is strictly inside. */
static wm_status locate(mesh *m, int32_t vi, int32_t *tri, int32_t *edge)
{
    const wm_pt p = m->p[vi];
    int32_t t = m->last, zero;
    int nz;
    /* A visibility walk cannot cycle in a Delaunay triangulation, and the
     * random first edge breaks ties; a walk longer than the mesh means a
     * bug, so fall back to a plain scan rather than loop. */
    const size_t limit = 2 * (size_t)m->ntri + 64;
    size_t steps = 0;
    for (;;)
    {
        m->rng ^= m->rng << 13;
        m->rng ^= m->rng >> 17;
        m->rng ^= m->rng << 5;
        const int32_t h = classify(m, t, m->rng, p, &zero, &nz);
        if (h < 0)
            break;
        const int32_t g = m->tw[h];
        if (g < 0 || ++steps > limit)
        {
            t = -1;
            break;
        }
        t = g / 3;
    }
    if (t < 0)
    {
        for (int32_t s = 0; s < m->ntri && t < 0; s++)
        {
            if (classify(m, s, 0, p, &zero, &nz) < 0)
                t = s;
        }
        if (t < 0)
            return wm_fail(m->ctx, WM_ERR_INTERNAL, "cdt: point %d not located",
                           (int)vi);
    }
    if (nz >= 2)
    {
        /* p lies on two edge lines of t: it is one of t's vertices */
        int32_t same = -1;
        for (int32_t h = 3 * t; h < 3 * t + 3; h++)
        {
            if (wm_pt_eq(m->p[m->v[h]], p))
                same = m->v[h];
        }
        return wm_fail(m->ctx, WM_ERR_INVALID,
                       "cdt: duplicate vertex %d and %d at (%d, %d)", (int)same,
                       (int)vi, (int)p.x, (int)p.y);
    }
    *tri = t;
    *edge = (nz == 1) ? zero : -1;
    return WM_OK;
}

static wm_status insert_point(mesh *m, int32_t pi)
{
    int32_t t = -1, h = -1;
    wm_status st = locate(m, pi, &t, &h);
    if (st != WM_OK)
        return st;
    if (m->ntri + 2 > m->maxtri)
        return wm_fail(m->ctx, WM_ERR_INTERNAL, "cdt: triangle overflow");
    if (m->state && !m->anywhere && m->state[t] != 2)
        return wm_fail(m->ctx, WM_ERR_INVALID,
                       "cdt: point %d not strictly inside", (int)pi);
    m->stack.n = 0;
    if (h < 0)
    {
        /* split (a, b, c) into (a, b, p), (b, c, p), (c, a, p) */
        const int32_t h0 = 3 * t;
        const int32_t a = m->v[h0], b = m->v[h0 + 1], c = m->v[h0 + 2];
        const int32_t oab = m->tw[h0], obc = m->tw[h0 + 1];
        const int32_t oca = m->tw[h0 + 2];
        const uint8_t cab = m->con[h0], cbc = m->con[h0 + 1];
        const uint8_t cca = m->con[h0 + 2];
        const int32_t t1 = m->ntri++, t2 = m->ntri++;
        set_tri(m, t, a, b, pi, cab);
        set_tri(m, t1, b, c, pi, cbc);
        set_tri(m, t2, c, a, pi, cca);
        if (m->state)
            m->state[t1] = m->state[t2] = m->state[t];
        pair_twins(m, 3 * t, oab);
        pair_twins(m, 3 * t1, obc);
        pair_twins(m, 3 * t2, oca);
        pair_twins(m, 3 * t + 1, 3 * t1 + 2);
        pair_twins(m, 3 * t1 + 1, 3 * t2 + 2);
        pair_twins(m, 3 * t2 + 1, 3 * t + 2);
        if (!ivec_push(&m->stack, 3 * t) || !ivec_push(&m->stack, 3 * t1) ||
            !ivec_push(&m->stack, 3 * t2))
            return cdt_nomem(m);
    }
    else
    {
        /* p on edge u->v of (u, v, w), twin in (v, u, z): four triangles
         * (w, u, p), (v, w, p), (z, v, p), (u, z, p) */
        const int32_t g = m->tw[h];
        if (g < 0)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: point on the super triangle");
        if (m->con[h])
            return wm_fail(m->ctx, WM_ERR_INVALID,
                           "cdt: point %d on a ring edge", (int)pi);
        const int32_t u = m->v[h], v = m->v[nxt(h)], w = m->v[prv(h)];
        const int32_t z = m->v[prv(g)];
        const int32_t owu = m->tw[prv(h)], ovw = m->tw[nxt(h)];
        const int32_t ozv = m->tw[prv(g)], ouz = m->tw[nxt(g)];
        const uint8_t cwu = m->con[prv(h)], cvw = m->con[nxt(h)];
        const uint8_t czv = m->con[prv(g)], cuz = m->con[nxt(g)];
        const int32_t ta = h / 3, tc = g / 3;
        const int32_t tb = m->ntri++, td = m->ntri++;
        set_tri(m, ta, w, u, pi, cwu);
        set_tri(m, tb, v, w, pi, cvw);
        set_tri(m, tc, z, v, pi, czv);
        set_tri(m, td, u, z, pi, cuz);
        if (m->state)
        {
            m->state[tb] = m->state[ta];
            m->state[td] = m->state[tc];
        }
        pair_twins(m, 3 * ta, owu);
        pair_twins(m, 3 * tb, ovw);
        pair_twins(m, 3 * tc, ozv);
        pair_twins(m, 3 * td, ouz);
        pair_twins(m, 3 * ta + 1, 3 * td + 2);
        pair_twins(m, 3 * ta + 2, 3 * tb + 1);
        pair_twins(m, 3 * tb + 2, 3 * tc + 1);
        pair_twins(m, 3 * tc + 2, 3 * td + 1);
        if (!ivec_push(&m->stack, 3 * ta) || !ivec_push(&m->stack, 3 * tb) ||
            !ivec_push(&m->stack, 3 * tc) || !ivec_push(&m->stack, 3 * td))
            return cdt_nomem(m);
    }
    m->last = t;
    /* each flip adds one edge at p, so p's degree bounds the flips */
    return lawson(m, 1, (size_t)m->np + 8);
}

static void mark(mesh *m, int32_t h)
{
    m->con[h] = 1;
    if (m->tw[h] >= 0)
        m->con[m->tw[h]] = 1;
}

/* Dot product of q->r and q->d; exact (differences below 2^28). */
static int64_t dot(wm_pt q, wm_pt r, wm_pt d)
{
    return (int64_t)(r.x - q.x) * (d.x - q.x) +
           (int64_t)(r.y - q.y) * (d.y - q.y);
}

/* 0 when direction q->d is at an angle in [0, 180) counter-clockwise from
 * direction q->r, 1 when in [180, 360). */
static int half_turn(wm_pt q, wm_pt r, wm_pt d)
{
    const int o = wm_orient(q, r, d);
    if (o != 0)
        return o < 0;
    return dot(q, r, d) <= 0;
}

/* True when the counter-clockwise angle from q->r to q->d1 is at most the
 * one from q->r to q->d2 (angles in [0, 360)). */
static int angle_le(wm_pt q, wm_pt r, wm_pt d1, wm_pt d2)
{
    const int h1 = half_turn(q, r, d1), h2 = half_turn(q, r, d2);
    if (h1 != h2)
        return h1 < h2;
    return wm_orient(q, d1, d2) >= 0;
}

/* Whether triangle (P[hi], P[lo], P[x]) fits in the polygon's interior
 * angle at position x: from P[x+1] counter-clockwise to P[x-1], the
 * directions to P[hi] then P[lo] must come in that order. Only needed
 * where a vertex occurs twice on the polygon, to pick the right copy. */
static int wedge_ok(const mesh *m, const chain *c, size_t x, size_t lo,
                    size_t hi)
{
    const wm_pt q = m->p[c->v.a[x]];
    const wm_pt pn = m->p[c->v.a[x + 1]], pp = m->p[c->v.a[x - 1]];
    const wm_pt ph = m->p[c->v.a[hi]], pl = m->p[c->v.a[lo]];
    if (wm_pt_eq(ph, q) || wm_pt_eq(pl, q) || !angle_le(q, pn, ph, pl))
        return 0;
    /* P[x-1] in the direction of P[x+1]: the tip of a dangling edge, whose
     * interior angle is the full turn */
    if (wm_orient(q, pn, pp) == 0 && dot(q, pn, pp) > 0)
        return 1;
    return angle_le(q, pn, pl, pp);
}

/* Triangulates one side of the cavity (Anglada 1997): the triangle on the
 * edge P[hi]->P[lo] takes the vertex between them whose circle with that
 * edge holds no other one, then both sub-polygons are done the same way
 * (explicit stack, no recursion). The freed cavity triangles are reused.
 * `parent` is the half-edge the closing edge must be linked to (-1 for
 * none); *top receives the closing edge's new half-edge. */
static wm_status fill_side(mesh *m, chain *c, int32_t parent, size_t *used,
                           int32_t *top)
{
    const size_t k = c->v.n - 1;
    m->tstk.n = 0;
    if (!ivec_push(&m->tstk, 0) || !ivec_push(&m->tstk, (int32_t)k) ||
        !ivec_push(&m->tstk, parent))
        return cdt_nomem(m);
    *top = -1;
    while (m->tstk.n > 0)
    {
        m->tstk.n -= 3;
        const size_t lo = (size_t)m->tstk.a[m->tstk.n];
        const size_t hi = (size_t)m->tstk.a[m->tstk.n + 1];
        const int32_t par = m->tstk.a[m->tstk.n + 2];
        if (hi == lo + 1)
        {
            /* a polygon edge: the new half-edge par replaces hc[lo] */
            m->con[par] = (uint8_t)c->fl.a[lo];
            if (c->anten.a[lo])
            {
                /* both sides of this edge are in the cavity: pair it with
                 * its other occurrence once everything is built */
                m->tw[par] = -1;
                if (!ivec_push(&m->pend, par) ||
                    !ivec_push(&m->pend, c->hc.a[lo]) ||
                    !ivec_push(&m->pend, c->o.a[lo]))
                    return cdt_nomem(m);
            }
            else
                pair_twins(m, par, c->o.a[lo]);
            continue;
        }
        const int32_t vl = c->v.a[lo], vh = c->v.a[hi];
        const wm_pt pl = m->p[vl], ph = m->p[vh];
        size_t best = 0;
        for (size_t x = lo + 1; x < hi; x++)
        {
            const int32_t vx = c->v.a[x];
            if (vx == vl || vx == vh || wm_orient(ph, pl, m->p[vx]) <= 0)
                continue;
            if (best == 0 ||
                wm_incircle(ph, pl, m->p[c->v.a[best]], m->p[vx]) > 0)
                best = x;
        }
        if (best == 0)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: empty pseudo-polygon %d-%d", (int)vl, (int)vh);
        if (c->rep)
        {
            for (size_t x = lo + 1; x < hi; x++)
            {
                if (c->v.a[x] == c->v.a[best] && wedge_ok(m, c, x, lo, hi))
                {
                    best = x;
                    break;
                }
            }
        }
        const int32_t vb = c->v.a[best];
        if (*used >= m->cav.n)
            return wm_fail(m->ctx, WM_ERR_INTERNAL, "cdt: cavity overflow");
        const int32_t t = m->cav.a[(*used)++], h = 3 * t;
        m->v[h] = vh;
        m->v[h + 1] = vl;
        m->v[h + 2] = vb;
        m->con[h] = m->con[h + 1] = m->con[h + 2] = 0;
        m->ve[vh] = h;
        m->ve[vl] = h + 1;
        m->ve[vb] = h + 2;
        if (par >= 0)
            pair_twins(m, h, par);
        else
            m->tw[h] = -1;
        if (lo == 0 && hi == k)
            *top = h;
        if (!ivec_push(&m->tstk, (int32_t)lo) ||
            !ivec_push(&m->tstk, (int32_t)best) ||
            !ivec_push(&m->tstk, h + 1) ||
            !ivec_push(&m->tstk, (int32_t)best) ||
            !ivec_push(&m->tstk, (int32_t)hi) || !ivec_push(&m->tstk, h + 2))
            return cdt_nomem(m);
    }
    return WM_OK;
}

/* Appends vertex w (and the half-edge hc of the cavity edge ending or
 * starting there) to side s; notes a repeated vertex. */
static int chain_push(mesh *m, int s, int32_t w, int32_t hc)
{
    chain *c = &m->side[s];
    const int32_t st = 2 * m->cid + s;
    if (m->vstamp[w] == st)
        c->rep = 1;
    m->vstamp[w] = st;
    return ivec_push(&c->v, w) && ivec_push(&c->hc, hc);
}

static void ivec_reverse(ivec *s)
{
    for (size_t i = 0, j = s->n; i + 1 < j; i++, j--)
    {
        const int32_t t = s->a[i];
        s->a[i] = s->a[j - 1];
        s->a[j - 1] = t;
    }
}

/* Step 1 of insert_constraint: around a, the edge a-b (marked: *start
 * stays -1) or the half-edge h of the triangle (a, v1, v2) whose open wedge
 * at a holds the direction to b (*start = h). */
static wm_status find_wedge(mesh *m, int32_t a, int32_t b, int32_t *start)
{
    const wm_pt pa = m->p[a], pb = m->p[b];
    const int32_t h0 = m->ve[a];
    int32_t h = h0;
    size_t guard = 0;
    *start = -1;
    do
    {
        const int32_t v1 = m->v[nxt(h)], v2 = m->v[prv(h)];
        if (v1 == b)
        {
            mark(m, h);
            return WM_OK;
        }
        const int o1 = wm_orient(pa, m->p[v1], pb);
        if (o1 == 0 && dot(pa, m->p[v1], pb) > 0)
            return wm_fail(m->ctx, WM_ERR_INVALID,
                           "cdt: vertex %d lies on ring edge %d-%d", (int)v1,
                           (int)a, (int)b);
        if (o1 > 0 && wm_orient(pa, m->p[v2], pb) < 0)
        {
            *start = h;
            return WM_OK;
        }
        h = m->tw[prv(h)];
        if (h < 0 || ++guard > 3 * (size_t)m->ntri)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: broken vertex star at %d", (int)a);
    } while (h != h0);
    return wm_fail(m->ctx, WM_ERR_INTERNAL, "cdt: no triangle at %d towards %d",
                   (int)a, (int)b);
}

/* Step 2: walks along a->b from half-edge start through the triangles it
 * crosses (the cavity), collecting the polygons on its right and left. The
 * edge we leave a triangle by runs from the right side to the left one; g
 * is its twin in the next triangle, whose third vertex w is new. */
static wm_status walk_cavity(mesh *m, int32_t a, int32_t b, int32_t start)
{
    const wm_pt pa = m->p[a], pb = m->p[b];
    m->cid++;
    for (int s = 0; s < 2; s++)
    {
        m->side[s].v.n = m->side[s].hc.n = 0;
        m->side[s].rep = 0;
    }
    m->cav.n = 0;
    m->pend.n = 0;
    if (!ivec_push(&m->cav, start / 3) || !chain_push(m, 0, a, start) ||
        !chain_push(m, 1, a, prv(start)) ||
        !ivec_push(&m->side[0].v, m->v[nxt(start)]) ||
        !ivec_push(&m->side[1].v, m->v[prv(start)]))
        return cdt_nomem(m);
    m->tstamp[start / 3] = m->cid;
    m->vstamp[m->v[nxt(start)]] = 2 * m->cid;
    m->vstamp[m->v[prv(start)]] = 2 * m->cid + 1;
    for (int32_t cur = nxt(start);;)
    {
        const int32_t g = m->tw[cur];
        if (g < 0 || m->cav.n > (size_t)m->ntri)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: walk from %d to %d left the mesh", (int)a,
                           (int)b);
        if (m->con[g])
            return wm_fail(m->ctx, WM_ERR_INVALID,
                           "cdt: ring edge %d-%d crosses ring edge %d-%d",
                           (int)a, (int)b, (int)m->v[g], (int)m->v[nxt(g)]);
        if (!ivec_push(&m->cav, g / 3))
            return cdt_nomem(m);
        m->tstamp[g / 3] = m->cid;
        const int32_t w = m->v[prv(g)];
        if (w == b)
            return ivec_push(&m->side[0].hc, nxt(g)) &&
                           ivec_push(&m->side[0].v, b) &&
                           ivec_push(&m->side[1].hc, prv(g)) &&
                           ivec_push(&m->side[1].v, b)
                       ? WM_OK
                       : cdt_nomem(m);
        const int o = wm_orient(pa, pb, m->p[w]);
        if (o == 0)
            return wm_fail(m->ctx, WM_ERR_INVALID,
                           "cdt: vertex %d lies on ring edge %d-%d", (int)w,
                           (int)a, (int)b);
        /* chain_push stores the vertex and the edge reaching it */
        const int ok =
            o > 0 ? chain_push(m, 1, w, prv(g)) : chain_push(m, 0, w, nxt(g));
        if (!ok)
            return cdt_nomem(m);
        cur = o > 0 ? nxt(g) : prv(g);
    }
}

/* Step 3: both sides as counter-clockwise polygons closed by the
 * constraint: right = a .. b, left = b .. a. Records what lies outside
 * each edge before the cavity triangles are overwritten. */
static wm_status close_sides(mesh *m, int32_t a, int32_t b)
{
    ivec_reverse(&m->side[1].v);
    ivec_reverse(&m->side[1].hc);
    size_t need = 0;
    for (int s = 0; s < 2; s++)
    {
        chain *c = &m->side[s];
        c->o.n = c->fl.n = c->anten.n = 0;
        for (size_t j = 0; j < c->hc.n; j++)
        {
            const int32_t hc = c->hc.a[j], o = m->tw[hc];
            if (!ivec_push(&c->o, o) || !ivec_push(&c->fl, m->con[hc]) ||
                !ivec_push(&c->anten, o >= 0 && m->tstamp[o / 3] == m->cid))
                return cdt_nomem(m);
        }
        need += c->v.n - 2; /* a polygon of n vertices: n - 2 triangles */
    }
    if (need != m->cav.n)
        return wm_fail(m->ctx, WM_ERR_INTERNAL,
                       "cdt: cavity of %d-%d has %zu triangles, needs %zu",
                       (int)a, (int)b, m->cav.n, need);
    return WM_OK;
}

/* Step 4: re-triangulates both sides and links the two halves of a-b. */
static wm_status refill(mesh *m)
{
    size_t used = 0;
    int32_t top_r, top_l;
    wm_status st = fill_side(m, &m->side[0], -1, &used, &top_r);
    if (st == WM_OK)
        st = fill_side(m, &m->side[1], top_r, &used, &top_l);
    if (st != WM_OK)
        return st;
    if (top_r < 0 || top_l < 0 || m->tw[top_r] != top_l)
        return wm_fail(m->ctx, WM_ERR_INTERNAL, "cdt: cavity not closed");
    mark(m, top_r);
    /* edges with the cavity on both sides: old half-edge h had twin o, so
     * the new half-edge replacing h pairs with the one replacing o */
    for (size_t i = 0; i < m->pend.n; i += 3)
    {
        size_t j = 0;
        while (j < m->pend.n && m->pend.a[j + 1] != m->pend.a[i + 2])
            j += 3;
        if (j >= m->pend.n)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: unpaired dangling edge");
        pair_twins(m, m->pend.a[i], m->pend.a[j]);
    }
    return WM_OK;
}

/* Step 5: the new triangles must all be counter-clockwise. Since they form
 * a disk whose boundary is the cavity's, every point is then covered as
 * many times as the cavity boundary winds around it: once inside, never
 * outside. This certifies the step, whatever the subtleties of repeated
 * vertices. */
static wm_status check_cavity(mesh *m, int32_t a, int32_t b)
{
    for (size_t i = 0; i < m->cav.n; i++)
    {
        const int32_t t = m->cav.a[i];
        if (wm_orient(m->p[m->v[3 * t]], m->p[m->v[3 * t + 1]],
                      m->p[m->v[3 * t + 2]]) <= 0)
            return wm_fail(m->ctx, WM_ERR_INTERNAL,
                           "cdt: inverted triangle inserting %d-%d", (int)a,
                           (int)b);
    }
    return WM_OK;
}

/* Inserts ring edge a-b as a constraint. */
static wm_status insert_constraint(mesh *m, int32_t a, int32_t b)
{
    int32_t start;
    wm_status st = find_wedge(m, a, b, &start);
    if (st != WM_OK || start < 0)
        return st; /* an error, or a-b an edge already (marked) */
    if ((st = walk_cavity(m, a, b, start)) == WM_OK &&
        (st = close_sides(m, a, b)) == WM_OK && (st = refill(m)) == WM_OK)
        st = check_cavity(m, a, b);
    return st;
}

/* Spreads the low 25 bits of v to the even bit positions. */
static uint64_t spread_bits(uint32_t v)
{
    uint64_t x = v;
    x = (x | x << 16) & UINT64_C(0x0000FFFF0000FFFF);
    x = (x | x << 8) & UINT64_C(0x00FF00FF00FF00FF);
    x = (x | x << 4) & UINT64_C(0x0F0F0F0F0F0F0F0F);
    x = (x | x << 2) & UINT64_C(0x3333333333333333);
    x = (x | x << 1) & UINT64_C(0x5555555555555555);
    return x;
}

typedef struct
{
    uint64_t key;
    int32_t idx;
} skey;

#define RADIX_BITS 14
#define RADIX_SIZE (1u << RADIX_BITS)

/* LSD radix sort on 56-bit keys, 4 passes of 14 bits; an even number of
 * passes leaves the result in a. */
static void radix_sort(skey *a, skey *tmp, size_t n, size_t *cnt)
{
    for (unsigned shift = 0; shift < 4 * RADIX_BITS; shift += RADIX_BITS)
    {
        memset(cnt, 0, RADIX_SIZE * sizeof *cnt);
        for (size_t i = 0; i < n; i++)
            cnt[(a[i].key >> shift) & (RADIX_SIZE - 1)]++;
        size_t sum = 0;
        for (size_t d = 0; d < RADIX_SIZE; d++)
        {
            const size_t c = cnt[d];
            cnt[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            tmp[cnt[(a[i].key >> shift) & (RADIX_SIZE - 1)]++] = a[i];
        skey *s = a;
        a = tmp;
        tmp = s;
    }
}

/* Checks the rings: sizes, coordinates, orientation. */
static wm_status check_input(const wm_pt *pts, const size_t *rs, size_t nrings,
                             size_t nextra, const wm_ctx *ctx)
{
    if (rs[0] != 0)
        return wm_fail(ctx, WM_ERR_INVALID, "cdt: ring_start[0] is not 0");
    for (size_t r = 0; r < nrings; r++)
    {
        if (rs[r + 1] < rs[r] || rs[r + 1] - rs[r] < 3)
            return wm_fail(ctx, WM_ERR_INVALID,
                           "cdt: ring %zu has fewer than 3 vertices", r);
    }
    const size_t n = rs[nrings] + nextra;
    if (n > MAX_PTS || nextra > MAX_PTS)
        return wm_fail(ctx, WM_ERR_NOMEM, "cdt: too many vertices (%zu)", n);
    for (size_t i = 0; i < n; i++)
    {
        if (!in_range(pts[i]))
            return wm_fail(ctx, WM_ERR_INVALID,
                           "cdt: vertex %zu (%d, %d) out of range", i,
                           (int)pts[i].x, (int)pts[i].y);
    }
    for (size_t r = 0; r < nrings; r++)
    {
        const wm_i128 a2 = wm_ring_area2(pts + rs[r], rs[r + 1] - rs[r]);
        if (r == 0 ? a2 <= 0 : a2 >= 0)
            return wm_fail(ctx, WM_ERR_INVALID,
                           "cdt: ring %zu has the wrong orientation", r);
    }
    return WM_OK;
}

/* Inserts every point (rings and extra) in a biased randomized insertion
 * order (BRIO, Amenta, Choi, Rote 2003): each point draws a round, the last
 * one with probability 1/2, the one before with 1/4, and so on; rounds go
 * in order and each is sorted along the Morton curve, by one radix sort on
 * (round << 50 | Morton key). The randomness keeps the expected number of
 * flips per point constant whatever the input (a pure curve order is
 * quadratic on, e.g., a square's dense border: each new point on one side
 * flips a whole fan to the opposite side); the curve keeps the walks
 * short. The generator is fixed: the output is deterministic. */
static wm_status insert_points(mesh *m, const wm_pt *pts, size_t n)
{
    skey *keys = alloc_n(n, sizeof *keys), *ktmp = alloc_n(n, sizeof *ktmp);
    size_t *cnt = alloc_n(RADIX_SIZE, sizeof *cnt);
    wm_status st = WM_OK;
    if (!keys || !ktmp || !cnt)
    {
        st = wm_fail(m->ctx, WM_ERR_NOMEM, "cdt: out of memory (%zu vertices)",
                     n);
        goto cleanup;
    }
    uint32_t rounds = 0, seed = 0x9e3779b9u;
    while (rounds < 26 && (n >> (rounds + 6)) > 0)
        rounds++;
    for (size_t i = 0; i < n; i++)
    {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        uint32_t z = 0, u = seed;
        while (z < rounds && (u & 1u) == 0)
        {
            u >>= 1;
            z++;
        }
        keys[i].idx = (int32_t)i;
        keys[i].key = (uint64_t)(rounds - z) << 50 |
                      spread_bits((uint32_t)pts[i].x) |
                      spread_bits((uint32_t)pts[i].y) << 1;
    }
    radix_sort(keys, ktmp, n, cnt);
    for (size_t i = 0; i < n && st == WM_OK; i++)
        st = insert_point(m, keys[i].idx);
cleanup:
    free(keys);
    free(ktmp);
    free(cnt);
    return st;
}

/* Labels the triangles by a flood fill from the super triangle, toggling
 * at each constraint: state[t] 1 outside, 2 inside. */
static wm_status flood_fill(const mesh *m, uint8_t *state, int32_t *queue)
{
    const size_t nt = (size_t)m->ntri;
    size_t qh = 0, qt = 0;
    const int32_t t0 = m->ve[m->nv] / 3; /* a triangle of the super vertex */
    queue[qt++] = t0;
    state[t0] = 1;
    while (qh < qt)
    {
        const int32_t t = queue[qh++];
        for (int32_t h = 3 * t; h < 3 * t + 3; h++)
        {
            const int32_t g = m->tw[h];
            if (g < 0)
                continue;
            const uint8_t s = (uint8_t)(((state[t] - 1) ^ m->con[h]) + 1);
            if (state[g / 3] == 0)
            {
                state[g / 3] = s;
                queue[qt++] = g / 3;
            }
            else if (state[g / 3] != s)
                return wm_fail(m->ctx, WM_ERR_INTERNAL,
                               "cdt: inconsistent inside/outside labels");
        }
    }
    if (qt != nt)
        return wm_fail(m->ctx, WM_ERR_INTERNAL, "cdt: mesh not connected");
    return WM_OK;
}

/* Counts the inside triangles into *inside and checks them: no super
 * vertex, and Euler's count: a polygon with h holes and k vertices inside
 * it has n + 2h - 2 + 2k triangles; anything else means holes outside the
 * outer ring, nested holes, or extra points not strictly inside. */
static wm_status check_inside(const mesh *m, const uint8_t *state, size_t nring,
                              size_t nrings, size_t nextra, size_t *inside)
{
    *inside = 0;
    for (size_t t = 0; t < (size_t)m->ntri; t++)
    {
        if (state[t] != 2)
            continue;
        (*inside)++;
        for (size_t i = 0; i < 3; i++)
            if (m->v[3 * t + i] >= m->nv && m->v[3 * t + i] < m->nv + 3)
                return wm_fail(m->ctx, WM_ERR_INVALID,
                               "cdt: rings are not a polygon with holes");
    }
    const size_t expect = nring + 2 * (nrings - 1) - 2 + 2 * nextra;
    if (*inside != expect)
        return wm_fail(m->ctx, WM_ERR_INVALID,
                       "cdt: %zu triangles instead of %zu: holes not strictly "
                       "inside the outer ring, nested, or extra points not "
                       "strictly inside",
                       *inside, expect);
    return WM_OK;
}

/* Lawson pass over the interior edges. Anglada's construction keeps the
 * triangulation constrained Delaunay, so this flips nothing (none in any
 * test); it certifies the result. Flips inside stay inside: both triangles
 * are. The budget only stops a runaway: far more than a repair of a nearly
 * Delaunay mesh could need. */
static wm_status certify(mesh *m, const uint8_t *state, size_t n)
{
    m->stack.n = 0;
    for (size_t t = 0; t < (size_t)m->ntri; t++)
    {
        if (state[t] != 2)
            continue;
        for (int32_t h = 3 * (int32_t)t; h < 3 * (int32_t)t + 3; h++)
            if (!m->con[h] && m->tw[h] > h && !ivec_push(&m->stack, h))
                return cdt_nomem(m);
    }
    return lawson(m, 0, 32 * n + 1024);
}

static void mesh_free(mesh *m)
{
    free(m->p);
    free(m->v);
    free(m->tw);
    free(m->con);
    free(m->ve);
    free(m->tstamp);
    free(m->vstamp);
    free(m->stack.a);
    for (int s = 0; s < 2; s++)
    {
        free(m->side[s].v.a);
        free(m->side[s].hc.a);
        free(m->side[s].o.a);
        free(m->side[s].fl.a);
        free(m->side[s].anten.a);
    }
    free(m->cav.a);
    free(m->tstk.a);
    free(m->pend.a);
    free(m->state);
}

/* Builds the CDT of the rings and the nextra points after them into m
 * (m->state labels its triangles); *inside: how many are inside. */
static wm_status build(mesh *m, const wm_pt *pts, const size_t *ring_start,
                       size_t nrings, size_t nextra, size_t *inside)
{
    wm_status st = check_input(pts, ring_start, nrings, nextra, m->ctx);
    if (st != WM_OK)
        return st;
    const size_t nring = ring_start[nrings], n = nring + nextra;
    const size_t nall = n + 3;
    const size_t maxtri = 2 * nall - 5; /* hull of 3: 2V - 2 - 3 */
    m->nv = (int32_t)n;
    m->np = (int32_t)nall;
    m->maxtri = (int32_t)maxtri;
    m->rng = 2463534242u;
    m->p = alloc_n(nall, sizeof *m->p);
    m->v = alloc_n(3 * maxtri, sizeof *m->v);
    m->tw = alloc_n(3 * maxtri, sizeof *m->tw);
    m->con = alloc_n(3 * maxtri, sizeof *m->con);
    m->ve = alloc_n(nall, sizeof *m->ve);
    m->tstamp = calloc(maxtri, sizeof *m->tstamp);
    m->vstamp = calloc(nall, sizeof *m->vstamp);
    if (!m->p || !m->v || !m->tw || !m->con || !m->ve || !m->tstamp ||
        !m->vstamp)
        return wm_fail(m->ctx, WM_ERR_NOMEM,
                       "cdt: out of memory (%zu vertices)", n);

    /* points, super triangle, first triangle */
    memcpy(m->p, pts, n * sizeof *pts);
    const int32_t s0 = (int32_t)n, s1 = s0 + 1, s2 = s0 + 2;
    m->p[s0].x = -SUPER_M;
    m->p[s0].y = -SUPER_M;
    m->p[s1].x = SUPER_M * 3 + SUPER_M / 2;
    m->p[s1].y = -SUPER_M;
    m->p[s2].x = -SUPER_M;
    m->p[s2].y = SUPER_M * 3 + SUPER_M / 2;
    m->ntri = 1;
    set_tri(m, 0, s0, s1, s2, 0);
    m->tw[0] = m->tw[1] = m->tw[2] = -1;
    st = insert_points(m, pts, n);
    if (st != WM_OK)
        return st;

    /* constraints, ring by ring */
    for (size_t r = 0; r < nrings; r++)
    {
        const size_t b0 = ring_start[r], len = ring_start[r + 1] - b0;
        for (size_t i = 0; i < len; i++)
        {
            st = insert_constraint(m, (int32_t)(b0 + i),
                                   (int32_t)(b0 + (i + 1) % len));
            if (st != WM_OK)
                return st;
        }
    }

    const size_t nt = (size_t)m->ntri;
    uint8_t *state = calloc(maxtri, 1);
    int32_t *queue = alloc_n(nt, sizeof *queue);
    if (!state || !queue)
    {
        free(state);
        free(queue);
        return cdt_nomem(m);
    }
    st = flood_fill(m, state, queue);
    free(queue);
    if (st == WM_OK)
        st = check_inside(m, state, nring, nrings, nextra, inside);
    if (st == WM_OK)
        st = certify(m, state, n);
    if (st != WM_OK)
    {
        free(state);
        return st;
    }
    m->state = state;
    return WM_OK;
}

/* The inside triangles of m (*ntris of them), in the caller's vertex
 * numbers: the input's, then those wm_cdt_insert added; with nb, the twin
 * of each of their half-edges (as in wm_cdt_open). */
static wm_status export_tris(const mesh *m, size_t inside, uint32_t **tris,
                             size_t *ntris, int32_t **nb)
{
    uint32_t *out = alloc_n(3 * inside, sizeof *out);
    int32_t *at = nb ? alloc_n((size_t)m->ntri, sizeof *at) : NULL;
    int32_t *tw = nb ? alloc_n(3 * inside, sizeof *tw) : NULL;
    if (!out || (nb && (!at || !tw)))
    {
        free(out);
        free(at);
        free(tw);
        return cdt_nomem(m);
    }
    size_t k = 0;
    for (size_t t = 0; t < (size_t)m->ntri; t++)
    {
        if (m->state[t] != 2)
            continue;
        if (at)
            at[t] = (int32_t)(k / 3);
        for (size_t i = 0; i < 3; i++)
        {
            const int32_t x = m->v[3 * t + i]; /* never a super vertex */
            out[k++] = external(m, x);
        }
    }
    for (size_t t = 0, e = 0; nb && t < (size_t)m->ntri; t++)
    {
        if (m->state[t] != 2)
            continue;
        for (int32_t i = 0; i < 3; i++, e++)
        {
            const int32_t g = m->tw[3 * (int32_t)t + i];
            tw[e] = g >= 0 && m->state[g / 3] == 2 ? 3 * at[g / 3] + g % 3 : -1;
        }
    }
    free(at);
    if (nb)
        *nb = tw;
    *tris = out;
    *ntris = inside;
    return WM_OK;
}

struct wm_cdt
{
    mesh m;
    size_t inside; /* inside triangles */
    /* for Euler's count: ring vertices, rings, points strictly inside */
    size_t nring, nrings, nextra;
    int stale; /* a ring edge was split since the triangles were labelled */
    /* a split must keep its ring's orientation: twice each ring's signed
     * area, and the ring of each vertex (caller numbers; -1 off the rings,
     * ring_cap entries) */
    wm_i128 *area2;
    int32_t *ring_of;
    size_t ring_cap;
};

wm_status wm_cdt_triangulate(const wm_pt *pts, const size_t *ring_start,
                             size_t nrings, uint32_t **tris, size_t *ntris,
                             const wm_ctx *ctx)
{
    return wm_cdt_triangulate_ex(pts, ring_start, nrings, 0, tris, ntris, ctx);
}

wm_status wm_cdt_triangulate_ex(const wm_pt *pts, const size_t *ring_start,
                                size_t nrings, size_t nextra, uint32_t **tris,
                                size_t *ntris, const wm_ctx *ctx)
{
    return wm_cdt_open(pts, ring_start, nrings, nextra, NULL, tris, ntris, NULL,
                       ctx);
}

wm_status wm_cdt_open(const wm_pt *pts, const size_t *ring_start, size_t nrings,
                      size_t nextra, wm_cdt **cdt, uint32_t **tris,
                      size_t *ntris, int32_t **nb, const wm_ctx *ctx)
{
    if (nb)
        *nb = NULL;
    if (cdt)
        *cdt = NULL;
    if (tris)
        *tris = NULL;
    if (ntris)
        *ntris = 0;
    if (!pts || !ring_start || !tris || !ntris || nrings == 0)
        return wm_fail(ctx, WM_ERR_INVALID, "cdt: missing argument");
    wm_cdt *c = calloc(1, sizeof *c);
    if (!c)
        return wm_fail(ctx, WM_ERR_NOMEM, "cdt: out of memory");
    c->m.ctx = ctx;
    wm_status st = build(&c->m, pts, ring_start, nrings, nextra, &c->inside);
    c->nring = ring_start[nrings];
    c->nrings = nrings;
    c->nextra = nextra;
    if (st == WM_OK && cdt)
    {
        c->area2 = malloc(nrings * sizeof *c->area2);
        c->ring_cap = ring_start[nrings] + nextra + 1;
        c->ring_of = malloc(c->ring_cap * sizeof *c->ring_of);
        if (!c->area2 || !c->ring_of)
            st = wm_fail(ctx, WM_ERR_NOMEM, "cdt: out of memory");
        for (size_t i = 0; st == WM_OK && i < c->ring_cap; i++)
            c->ring_of[i] = -1;
        for (size_t k = 0; st == WM_OK && k < nrings; k++)
        {
            const size_t b0 = ring_start[k], len = ring_start[k + 1] - b0;
            c->area2[k] = wm_ring_area2(pts + b0, len);
            for (size_t i = b0; i < b0 + len; i++)
                c->ring_of[i] = (int32_t)k;
        }
    }
    if (st == WM_OK)
        st = export_tris(&c->m, c->inside, tris, ntris, nb);
    if (st != WM_OK || !cdt)
        wm_cdt_free(c);
    else
        *cdt = c;
    return st;
}

/* Room for `add` more vertices and their 2 * add triangles. */
static int grow(mesh *m, size_t add)
{
    const size_t np = (size_t)m->np + add;
    const size_t nt = (size_t)m->maxtri + 2 * add;
    if (np > MAX_PTS + 3 || nt > (size_t)INT32_MAX / 3)
        return 0;
    void *p = realloc(m->p, np * sizeof *m->p);
    if (p)
        m->p = p;
    void *ve = realloc(m->ve, np * sizeof *m->ve);
    if (ve)
        m->ve = ve;
    void *vs = realloc(m->vstamp, np * sizeof *m->vstamp);
    if (vs)
        m->vstamp = vs;
    void *v = realloc(m->v, 3 * nt * sizeof *m->v);
    if (v)
        m->v = v;
    void *tw = realloc(m->tw, 3 * nt * sizeof *m->tw);
    if (tw)
        m->tw = tw;
    void *con = realloc(m->con, 3 * nt * sizeof *m->con);
    if (con)
        m->con = con;
    void *ts = realloc(m->tstamp, nt * sizeof *m->tstamp);
    if (ts)
        m->tstamp = ts;
    void *state = realloc(m->state, nt);
    if (state)
        m->state = state;
    if (!p || !ve || !vs || !v || !tw || !con || !ts || !state)
        return 0;
    memset(m->vstamp + m->np, 0, add * sizeof *m->vstamp);
    memset(m->tstamp + m->maxtri, 0, 2 * add * sizeof *m->tstamp);
    m->maxtri = (int32_t)nt;
    return 1;
}

/* The half-edge a->b, or -1. */
static int32_t find_half(const mesh *m, int32_t a, int32_t b)
{
    const int32_t h0 = m->ve[a];
    int32_t h = h0;
    size_t guard = 0;
    do
    {
        if (m->v[nxt(h)] == b)
            return h;
        h = m->tw[prv(h)];
    } while (h >= 0 && h != h0 && ++guard <= 3 * (size_t)m->ntri);
    return -1;
}

/* Whether vertex x is on a ring: a constraint leaves it. */
static int on_ring(const mesh *m, int32_t x)
{
    const int32_t h0 = m->ve[x];
    int32_t h = h0;
    size_t guard = 0;
    do
    {
        if (m->con[h] || m->con[prv(h)])
            return 1;
        h = m->tw[prv(h)];
    } while (h >= 0 && h != h0 && ++guard <= 3 * (size_t)m->ntri);
    return 0;
}

/* Labels the triangles inside and outside again and checks their count
 * (after ring edges were split). */
static wm_status relabel(wm_cdt *c)
{
    mesh *m = &c->m;
    int32_t *queue = alloc_n((size_t)m->ntri, sizeof *queue);
    if (!queue)
        return cdt_nomem(m);
    memset(m->state, 0, (size_t)m->ntri);
    wm_status st = flood_fill(m, m->state, queue);
    free(queue);
    if (st == WM_OK)
        st = check_inside(m, m->state, c->nring, c->nrings, c->nextra,
                          &c->inside);
    c->stale = st != WM_OK;
    return st;
}

wm_status wm_cdt_split(wm_cdt *cdt, uint32_t a, uint32_t b, wm_pt p,
                       uint32_t *q, const wm_ctx *ctx)
{
    mesh *m = &cdt->m;
    m->ctx = ctx;
    const uint32_t nvert = (uint32_t)m->np - 3; /* caller numbers below */
    const int32_t ia = a < nvert ? internal(m, a) : -1;
    const int32_t ib = b < nvert ? internal(m, b) : -1;
    const int32_t h = ia >= 0 && ib >= 0 ? find_half(m, ia, ib) : -1;
    if (h < 0 || !m->con[h] || a >= cdt->ring_cap || cdt->ring_of[a] < 0)
        return wm_fail(ctx, WM_ERR_INVALID, "cdt: %u-%u is not a ring edge",
                       (unsigned)a, (unsigned)b);
    if (*q != UINT32_MAX && *q >= nvert)
        return wm_fail(ctx, WM_ERR_INVALID, "cdt: no vertex %u", (unsigned)*q);
    /* a-q-b instead of a-b adds triangle (a, q, b) to the ring's area: it
     * must keep its sign (a thin ring whose vertices lie between a-b and q
     * would turn inside out, which no other test sees) */
    const int32_t ring = cdt->ring_of[a];
    const wm_pt pq = *q == UINT32_MAX ? p : m->p[internal(m, *q)];
    const wm_i128 after =
        cdt->area2[ring] + (wm_i128)wm_orient_det(m->p[ia], pq, m->p[ib]);
    if (after == 0 || (after > 0) != (cdt->area2[ring] > 0))
        return wm_fail(ctx, WM_ERR_INVALID,
                       "cdt: splitting %u-%u turns its ring inside out",
                       (unsigned)a, (unsigned)b);
    m->con[h] = 0;
    if (m->tw[h] >= 0)
        m->con[m->tw[h]] = 0;
    cdt->stale = 1;
    int32_t iq;
    if (*q == UINT32_MAX)
    {
        if (!in_range(p))
            return wm_fail(ctx, WM_ERR_INVALID,
                           "cdt: point (%d, %d) outside the lattice range",
                           (int)p.x, (int)p.y);
        if (!grow(m, 1))
            return wm_fail(ctx, WM_ERR_NOMEM, "cdt: out of memory");
        iq = m->np++;
        m->p[iq] = p;
        m->anywhere = 1;
        const wm_status st = insert_point(m, iq);
        m->anywhere = 0;
        if (st != WM_OK)
            return st;
        *q = external(m, iq);
    }
    else
    {
        iq = internal(m, *q);
        if ((iq >= m->nv && iq < m->nv + 3) || iq >= m->np ||
            cdt->nextra == 0 || on_ring(m, iq))
            return wm_fail(ctx, WM_ERR_INVALID, "cdt: %u is not a point inside",
                           (unsigned)*q);
        cdt->nextra--;
    }
    if (!wm_map_set(&cdt->ring_of, &cdt->ring_cap, external(m, iq), ring))
        return wm_fail(ctx, WM_ERR_NOMEM, "cdt: out of memory");
    cdt->area2[ring] = after;
    cdt->nring++;
    wm_status st = insert_constraint(m, ia, iq);
    if (st == WM_OK)
        st = insert_constraint(m, iq, ib);
    /* a-b, no longer a constraint, may still be an edge that q's insertion
     * never tested (q was not in a triangle beside it): Lawson from it */
    const int32_t hab = st == WM_OK ? find_half(m, ia, ib) : -1;
    if (hab >= 0 && !m->con[hab])
    {
        m->stack.n = 0;
        if (!ivec_push(&m->stack, hab))
            return wm_fail(ctx, WM_ERR_NOMEM, "cdt: out of memory");
        st = lawson(m, 0, 32 * (size_t)m->np + 1024);
    }
    return st;
}

wm_status wm_cdt_insert(wm_cdt *cdt, const wm_pt *pts, size_t n,
                        uint32_t **tris, size_t *ntris, int32_t **nb,
                        const wm_ctx *ctx)
{
    mesh *m = &cdt->m;
    m->ctx = ctx;
    *tris = NULL;
    *ntris = 0;
    if (nb)
        *nb = NULL;
    if (cdt->stale)
    {
        const wm_status st = relabel(cdt);
        if (st != WM_OK)
            return st;
    }
    for (size_t i = 0; i < n; i++)
        if (!in_range(pts[i]))
            return wm_fail(ctx, WM_ERR_INVALID,
                           "cdt: point (%d, %d) outside the lattice range",
                           (int)pts[i].x, (int)pts[i].y);
    if (!grow(m, n))
        return wm_fail(ctx, WM_ERR_NOMEM, "cdt: out of memory");
    for (size_t i = 0; i < n; i++)
    {
        const int32_t pi = m->np++;
        m->p[pi] = pts[i];
        const wm_status st = insert_point(m, pi);
        if (st != WM_OK)
            return st;
        cdt->inside += 2;
        cdt->nextra++;
    }
    return export_tris(m, cdt->inside, tris, ntris, nb);
}

void wm_cdt_free(wm_cdt *cdt)
{
    if (!cdt)
        return;
    mesh_free(&cdt->m);
    free(cdt->area2);
    free(cdt->ring_of);
    free(cdt);
}
