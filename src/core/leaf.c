/*
 * leaf.c - which water arcs of a small rectangle's boundary the union of
 * the inputs joins inside it.
 *
 * Why: subdivision (subpixel.c) divides an ambiguous cell until each piece
 * holds one boundary segment or is a few lattice units wide. Such a leaf
 * may keep four or more crossings, and which of them the boundary joins
 * is a question of the union inside the leaf, not of its sides: a rule on
 * the sides (join the water corners, or the class of the centre) fails
 * where the tip of a thin wedge or an island lies in the leaf, and the
 * output then joins what the exact union keeps apart (or cuts what it
 * joins).
 *
 * Method: the water inside the rectangle R is the union of the inputs'
 * pieces in R: each capsule's (convex, so one piece), and each lake
 * polygon's, cut by the chains of its boundary inside R (each entering R
 * and leaving it along consecutive edges; the pieces are the regions
 * between them, found as the walk around R's boundary finds them). Two
 * pieces are one component exactly when they meet in R. They meet when
 * their stretches of water along R's boundary overlap, or, where they do
 * not, inside R:
 *  - two capsules: their intersection is convex, so when it meets no side
 *    it lies wholly inside R or wholly outside; the point between their
 *    axes' closest points, at the ratio of the radii, is in it;
 *  - a capsule and a lake's piece: an edge of the piece's chains, clipped
 *    to R, within the radius of the capsule's axis; or the capsule, wholly
 *    inside R, in the lake (when the lake is one piece there);
 *  - pieces of two lakes: two of their chains' edges crossing inside R.
 * "Meet" means by more than WM_COINCIDE (the inputs' rounding): banks
 * that coincide keep the land between them joined, as the exact union's
 * computation does. Lakes are read on R grown by a fraction of a unit
 * (grown_side()), on whose sides no lake vertex lies: a lake's edge along
 * a side of R or through a corner, whose closed boundary is water as the
 * field has it, is read as the thin strip of lake beside it. The arcs then
 * take the labels of the pieces covering them: the water stretches of all
 * pieces along R's boundary, merged, are matched one to one with the
 * caller's arcs (whose crossings were rounded to the lattice, so within 2
 * units).
 *
 * Cost: O(items^2 + items x lake edges) per rectangle, on the few leaves
 * with four crossings or more.
 *
 * Robustness: every coordinate difference is formed in integers from the
 * global lattice before floating point, so the answer is a pure function
 * of the rectangle's global position and the inputs; which inputs meet is
 * decided in double precision (a choice of pairing: the pairing itself
 * stays one the caller can draw), and a configuration this reading does
 * not cover is handed back (return 0).
 */
#include "leaf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* water stretches along the boundary per input: a capsule meets each
 * side once; a lake's piece bounded by CHAINS chains touches as many arcs
 * of the boundary, one of them split at its first corner */
#define STRETCHES 8
/* how far (lattice units) a caller's arc may lie from the stretch it
 * matches: its crossings are rounded, and kept a unit apart */
#define ARC_SLACK 2.0
/* chains of one lake's boundary inside R read at most */
#define CHAINS 4
/* runs of edges of one lake piece's chains: one per chain, two for the one
 * through its ring's first vertex */
#define RUNS (CHAINS + 1)

typedef struct
{
    int lake;    /* 1: lake polygon slot id; 0: river segment id */
    uint32_t id; /* segment index, or polygon slot */
    double iv[2 * STRETCHES];
    int niv;
    /* a lake's piece, when its slot has several in R: the runs of edges
     * (first, last scene edge) of the chains bounding it; none: every edge
     * of the slot */
    int nrun;
    uint32_t run[2 * RUNS];
} item;

typedef struct
{
    wm_probe *p;
    int32_t x0, y0;    /* R's first corner, block-local */
    int64_t GX, GY;    /* the same, global */
    int32_t W, H;      /* R's size */
    double per;        /* R's perimeter */
    wm_probe_items le; /* lake edges near R */
    item it[WM_LEAF_ITEMS];
    int n;
    int up[WM_LEAF_ITEMS]; /* union-find parents */
} leaf;

/* Side s of R: its first point (global), direction and length. */
static void side_frame(const leaf *l, int s, int64_t *Gx, int64_t *Gy,
                       int *vertical, int32_t *L)
{
    *Gx = l->GX + (s == 1 ? l->W : 0);
    *Gy = l->GY + (s == 2 ? l->H : 0);
    *vertical = s & 1;
    *L = s & 1 ? l->H : l->W;
}

/* Position along R's boundary (counter-clockwise from its first corner)
 * of offset t along side s. */
static double to_pos(const leaf *l, int s, double t)
{
    switch (s)
    {
    case 0:
        return t;
    case 1:
        return l->W + t;
    case 2:
        return l->W + l->H + (l->W - t);
    default:
        return 2.0 * l->W + l->H + (l->H - t);
    }
}

/* Adds the stretch [lo, hi] of side s (offsets, clipped to the side) to
 * item t; 0 when it holds too many. */
static int add_stretch(const leaf *l, item *t, int s, double lo, double hi)
{
    const double L = s & 1 ? l->H : l->W;
    lo = lo < 0 ? 0 : lo;
    hi = hi > L ? L : hi;
    if (!(lo <= hi))
        return 1;
    if (t->niv == STRETCHES)
        return 0;
    const double a = to_pos(l, s, lo), b = to_pos(l, s, hi);
    t->iv[2 * t->niv] = a < b ? a : b;
    t->iv[2 * t->niv + 1] = a < b ? b : a;
    t->niv++;
    return 1;
}

/* Whether global point (X, Y) lies in R, sides included. */
static int closed_in(const leaf *l, int64_t X, int64_t Y)
{
    return X >= l->GX && X <= l->GX + l->W && Y >= l->GY && Y <= l->GY + l->H;
}

/* Whether global point (X, Y) lies strictly inside R. */
static int strictly_in(const leaf *l, int64_t X, int64_t Y)
{
    return X > l->GX && X < l->GX + l->W && Y > l->GY && Y < l->GY + l->H;
}

/* Adds the capsules meeting R; 0 when there are too many. */
static int gather_rivers(leaf *l)
{
    const wm_scene *s = l->p->s;
    wm_probe_items r;
    wm_probe_rivers_near(l->p, l->x0 + l->W / 2.0, l->y0 + l->H / 2.0, &r);
    for (size_t i = 0; i < r.na + r.nb; i++)
    {
        const uint32_t id = i < r.na ? r.a[i] : r.b[i - r.na];
        const wm_river_seg *g = &s->segs[id];
        const double m = g->r;
        if ((double)((g->ax < g->bx ? g->ax : g->bx) - l->GX) - m > l->W ||
            (double)((g->ax > g->bx ? g->ax : g->bx) - l->GX) + m < 0 ||
            (double)((g->ay < g->by ? g->ay : g->by) - l->GY) - m > l->H ||
            (double)((g->ay > g->by ? g->ay : g->by) - l->GY) + m < 0)
            continue;
        item t = {0, id, {0}, 0, 0, {0}};
        for (int k = 0; k < 4; k++)
        {
            int64_t Gx, Gy;
            int vertical;
            int32_t L;
            double lo, hi;
            side_frame(l, k, &Gx, &Gy, &vertical, &L);
            if (wm_probe_capsule_interval(g, Gx, Gy, vertical, &lo, &hi) &&
                !add_stretch(l, &t, k, lo, hi))
                return 0;
        }
        if (t.niv == 0 && !strictly_in(l, g->ax, g->ay))
            continue; /* meets R's sides nowhere, nor lies inside R */
        if (l->n == WM_LEAF_ITEMS)
            return 0;
        l->it[l->n++] = t;
    }
    return 1;
}

/* Lake edge j of the near list. */
static const struct wm_probe_edge *near_edge(const leaf *l, size_t j)
{
    return &l->p->ledge[j < l->le.na ? l->le.a[j] : l->le.b[j - l->le.na]];
}

/* Where a lake's boundary crosses R's: at `pos` along R's boundary, on
 * scene edge e at fraction u of it, entering R or leaving it. */
typedef struct
{
    double pos, u;
    uint32_t e;
    int enter;
} toggle;

/* Lakes are read on R grown by a fraction of a unit, OUT_X = 16 / SCALE
 * across x and OUT_Y = 1 / SCALE across y: no lattice point (a lake's
 * vertex) lies on its sides, so every crossing of a lake's boundary with
 * them is a proper one, and a lake's edge along a side of R or through
 * one of its corners, where its closed boundary is water as the field has
 * it, is read as the thin strip of that lake beside R. Coordinates are
 * scaled by SCALE, exact in integers. */
#define SCALE 1024
#define OUT_X 16
#define OUT_Y 1

/* Side s of grown R, scaled from R's first corner: its line (w = c, w
 * the y coordinate for the bottom and top sides, x for the others), its
 * extent u0 -> u1 counter-clockwise along the other coordinate. */
static void grown_side(const leaf *l, int s, int64_t *c, int64_t *u0,
                       int64_t *u1)
{
    const int64_t X1 = (int64_t)l->W * SCALE + OUT_X;
    const int64_t Y1 = (int64_t)l->H * SCALE + OUT_Y;
    switch (s)
    {
    case 0:
        *c = -OUT_Y, *u0 = -OUT_X, *u1 = X1;
        break;
    case 1:
        *c = X1, *u0 = -OUT_Y, *u1 = Y1;
        break;
    case 2:
        *c = Y1, *u0 = X1, *u1 = -OUT_X;
        break;
    default:
        *c = -OUT_X, *u0 = Y1, *u1 = -OUT_Y;
        break;
    }
}

/* Where lake edge g (scene edge e) crosses side s of grown R, into *t (its
 * position mapped to R's boundary, side to side); 0 when it does not, -1
 * when it passes through a corner of grown R (left undecided). */
static int edge_toggle(const leaf *l, const wm_lake_edge *g, uint32_t e, int s,
                       toggle *t)
{
    int64_t c, u0, u1;
    grown_side(l, s, &c, &u0, &u1);
    const int vertical = s & 1; /* the side runs along y */
    const int64_t ax = (g->ax - l->GX) * SCALE, ay = (g->ay - l->GY) * SCALE;
    const int64_t bx = (g->bx - l->GX) * SCALE, by = (g->by - l->GY) * SCALE;
    const int64_t aw = (vertical ? ax : ay) - c, bw = (vertical ? bx : by) - c;
    const int64_t au = vertical ? ay : ax, bu = vertical ? by : bx;
    if ((aw > 0) == (bw > 0))
        return 0; /* aw, bw are never 0 */
    /* the crossing u = au + (0 - aw)(bu - au) / (bw - aw), against the
     * extent, as num / den with den > 0 */
    const wm_i128 den = bw > aw ? bw - aw : aw - bw;
    const wm_i128 num =
        ((wm_i128)au * (bw - aw) + (wm_i128)(0 - aw) * (bu - au)) *
        (bw > aw ? 1 : -1);
    const wm_i128 lo = (wm_i128)(u0 < u1 ? u0 : u1) * den;
    const wm_i128 hi = (wm_i128)(u0 < u1 ? u1 : u0) * den;
    if (num == lo || num == hi)
        return -1;
    if (num < lo || num > hi)
        return 0;
    const double f = ((double)num / (double)den - (double)u0) /
                     (double)(u1 - u0); /* 0 -> 1 counter-clockwise */
    const double L = vertical ? l->H : l->W;
    const double start = s == 0   ? 0
                         : s == 1 ? l->W
                         : s == 2 ? l->W + l->H
                                  : 2.0 * l->W + l->H;
    /* R lies on the side w > 0 of the bottom and left sides' lines */
    const int inward = s == 0 || s == 3;
    *t = (toggle){start + f * L, (double)(0 - aw) / (double)(bw - aw), e,
                  inward ? bw > 0 : bw < 0};
    return 1;
}

/* The even-odd class in polygon slot k of grown R's first corner, exact
 * (the ray rule; no vertex lies on its row). */
static int corner_in_lake(const leaf *l, uint32_t k)
{
    wm_probe_items ray;
    wm_probe_lake_edges_ray(l->p, (double)l->y0 - 1, &ray);
    const int64_t X = -OUT_X, Y = -OUT_Y;
    int odd = 0;
    for (size_t i = 0; i < ray.na; i++)
    {
        const struct wm_probe_edge *e = &l->p->ledge[ray.a[i]];
        if (e->k != k)
            continue;
        const wm_lake_edge *g = &l->p->s->edges[e->e];
        const int64_t ax = (g->ax - l->GX) * SCALE,
                      ay = (g->ay - l->GY) * SCALE;
        const int64_t bx = (g->bx - l->GX) * SCALE,
                      by = (g->by - l->GY) * SCALE;
        if ((ay > Y) == (by > Y))
            continue;
        /* crossing x > X: (ax - X)(by - ay) + (Y - ay)(bx - ax) has the
         * sign of by - ay */
        const wm_i128 v =
            (wm_i128)(ax - X) * (by - ay) + (wm_i128)(Y - ay) * (bx - ax);
        odd ^= by > ay ? v > 0 : v < 0;
    }
    return odd;
}

/* The even-odd class of global lattice point (X, Y) in polygon slot k,
 * exact; (X, Y) lies in the block's reach, on local row y. */
static int lake_holds(const leaf *l, uint32_t k, int64_t X, int64_t Y)
{
    wm_probe_items ray;
    wm_probe_lake_edges_ray(l->p, (double)(Y - l->p->Y0), &ray);
    int odd = 0;
    for (size_t i = 0; i < ray.na; i++)
    {
        const struct wm_probe_edge *e = &l->p->ledge[ray.a[i]];
        if (e->k == k && wm_edge_crosses_ray(&l->p->s->edges[e->e], X, Y))
            odd ^= 1;
    }
    return odd;
}

static int cmp_ring(const void *a, const void *b)
{
    const toggle *x = a, *y = b;
    if (x->e != y->e)
        return x->e < y->e ? -1 : 1;
    return (x->u > y->u) - (x->u < y->u);
}

/* Whether edges a .. b (scene indices, a <= b) run on one after another. */
static int consecutive(const wm_lake_edge *E, uint32_t a, uint32_t b)
{
    for (uint32_t j = a; j < b; j++)
        if (E[j].bx != E[j + 1].ax || E[j].by != E[j + 1].ay)
            return 0;
    return 1;
}

/* Pairs polygon slot k's toggles tg[0 .. n) (sorted along its rings) into
 * the chains of its boundary inside R, entering then leaving along one
 * run of consecutive edges: chain c is tg[2c] .. tg[2c + 1]. When the
 * first toggle leaves R (the ring's first vertex lies in R), the toggles
 * are turned by one, and the last chain runs from its entering edge to
 * the ring's last edge *re, then from its first edge *rs on (one ring
 * holding all of the slot's toggles); else *rs = *re = 0 and *wrap = 0.
 * 0 when they do not pair so. */
static int chains_of(const leaf *l, uint32_t k, toggle *tg, int n, int *wrap,
                     uint32_t *rs, uint32_t *re)
{
    const wm_scene *s = l->p->s;
    const wm_lake_edge *E = s->edges;
    *wrap = n > 0 && !tg[0].enter;
    *rs = *re = 0;
    if (*wrap)
    {
        const size_t p = l->p->polys[k];
        uint32_t a = tg[0].e, b = tg[n - 1].e;
        if (!consecutive(E, a, b))
            return 0;
        while (a > s->poly_start[p] && E[a - 1].bx == E[a].ax &&
               E[a - 1].by == E[a].ay)
            a--;
        while (b + 1 < s->poly_start[p + 1] && E[b].bx == E[b + 1].ax &&
               E[b].by == E[b + 1].ay)
            b++;
        if (E[b].bx != E[a].ax || E[b].by != E[a].ay)
            return 0; /* the ring does not close there */
        *rs = a;
        *re = b;
        const toggle first = tg[0];
        memmove(tg, tg + 1, (size_t)(n - 1) * sizeof *tg);
        tg[n - 1] = first;
    }
    for (int c = 0; c < n; c += 2)
    {
        if (!tg[c].enter || tg[c + 1].enter)
            return 0;
        if (!(*wrap && c == n - 2) && !consecutive(E, tg[c].e, tg[c + 1].e))
            return 0;
    }
    return 1;
}

/* The runs of edges (first, last scene edge) of chain c of tg[0 .. n)
 * (chains_of()) into r: one, or two for a wrapping chain (from its
 * entering edge to the ring's last edge re, from its first rs to its
 * leaving edge); returns how many. */
static int chain_runs(const toggle *tg, int n, int c, int wrap, uint32_t rs,
                      uint32_t re, uint32_t *r)
{
    r[0] = tg[c].e;
    if (!(wrap && c == n - 2))
    {
        r[1] = tg[c + 1].e;
        return 1;
    }
    r[1] = re;
    r[2] = rs;
    r[3] = tg[c + 1].e;
    return 2;
}

/* Whether some edge of polygon slot k with an end in R lies in no chain
 * of tg[0 .. n) (a ring of k inside R). */
static int stray_edges(const leaf *l, uint32_t k, const toggle *tg, int n,
                       int wrap, uint32_t rs, uint32_t re)
{
    const wm_scene *s = l->p->s;
    for (size_t j = 0; j < l->le.na + l->le.nb; j++)
    {
        const struct wm_probe_edge *e = near_edge(l, j);
        if (e->k != k)
            continue;
        const wm_lake_edge *g = &s->edges[e->e];
        if (!closed_in(l, g->ax, g->ay) && !closed_in(l, g->bx, g->by))
            continue;
        int held = 0;
        for (int c = 0; c < n && !held; c += 2)
        {
            uint32_t r[4];
            const int m = chain_runs(tg, n, c, wrap, rs, re, r);
            for (int i = 0; i < m; i++)
                held |= e->e >= r[2 * i] && e->e <= r[2 * i + 1];
        }
        if (!held)
            return 1;
    }
    return 0;
}

/* How a lake's boundary cuts R: its toggles in ring order, paired into
 * chains (chains_of()). */
typedef struct
{
    toggle tg[2 * CHAINS + 1];
    int n;
    int wrap;
    uint32_t rs, re;
} cut;

/* The cut of R by polygon slot k's boundary; 0 when beyond this reading
 * (more than CHAINS chains, an edge through a corner of grown R, see
 * chains_of() and stray_edges()). */
static int cut_by_lake(const leaf *l, uint32_t k, cut *c)
{
    const wm_scene *s = l->p->s;
    c->n = 0;
    for (size_t j = 0; j < l->le.na + l->le.nb; j++)
    {
        const struct wm_probe_edge *e = near_edge(l, j);
        if (e->k != k)
            continue;
        for (int side = 0; side < 4; side++)
        {
            const int got =
                edge_toggle(l, &s->edges[e->e], e->e, side, &c->tg[c->n]);
            if (got < 0 || (got && ++c->n > 2 * CHAINS))
                return 0;
        }
    }
    if (c->n % 2)
        return 0;
    qsort(c->tg, (size_t)c->n, sizeof *c->tg, cmp_ring);
    return chains_of(l, k, c->tg, c->n, &c->wrap, &c->rs, &c->re) &&
           !stray_edges(l, k, c->tg, c->n, c->wrap, c->rs, c->re);
}

/* Adds the pieces of polygon slot k that cut c (n > 0 toggles) leaves in R,
 * odd0 the slot's class at R's first corner: the regions between its
 * chains that are the lake's, each walked from arc to arc (along an arc,
 * then its end's chain to the chain's other end, whose arc follows); 0 when the
 * chains contradict the parity or there are too many. */
static int add_pieces(leaf *l, uint32_t k, const cut *c, int odd0)
{
    const int n = c->n;
    /* ring[i]: the toggle (ring order) i-th along R's boundary; at[]: its
     * inverse; mate[]: the other end of its chain, by position */
    int ring[2 * CHAINS], at[2 * CHAINS], mate[2 * CHAINS];
    for (int i = 0; i < n; i++)
    {
        int j = i;
        for (; j > 0 && c->tg[ring[j - 1]].pos > c->tg[i].pos; j--)
            ring[j] = ring[j - 1];
        ring[j] = i;
    }
    for (int i = 0; i < n; i++)
        at[ring[i]] = i;
    for (int j = 0; j < n; j += 2)
    {
        mate[at[j]] = at[j + 1];
        mate[at[j + 1]] = at[j];
    }
    /* arc i runs from toggle ring[i] to ring[i + 1] along R's boundary; the
     * one through the first corner (i = n - 1) is of class odd0 */
    unsigned seen = 0;
    for (int i0 = 0; i0 < n; i0++)
    {
        if ((seen >> i0 & 1) || (odd0 ^ ((i0 + 1) & 1)) == 0)
            continue;
        item t = {1, k, {0}, 0, 0, {0}};
        for (int i = i0; !(seen >> i & 1); i = mate[(i + 1) % n])
        {
            seen |= 1u << i;
            if ((odd0 ^ ((i + 1) & 1)) == 0 || t.niv + 2 > STRETCHES ||
                t.nrun + 2 > RUNS)
                return 0;
            const double a = c->tg[ring[i]].pos;
            const double b = c->tg[ring[(i + 1) % n]].pos;
            t.iv[2 * t.niv] = a;
            t.iv[2 * t.niv + 1] = i + 1 < n ? b : l->per;
            t.niv++;
            if (i + 1 == n)
            {
                t.iv[2 * t.niv] = 0;
                t.iv[2 * t.niv + 1] = b;
                t.niv++;
            }
            /* the chain from toggle ring[i + 1], by its entering toggle */
            const int j = ring[(i + 1) % n] & ~1;
            t.nrun += chain_runs(c->tg, n, j, c->wrap, c->rs, c->re,
                                 t.run + 2 * t.nrun);
        }
        if (l->n == WM_LEAF_ITEMS)
            return 0;
        l->it[l->n++] = t;
    }
    return 1;
}

/* Adds polygon slot k's pieces inside R: one item per component, with its
 * water stretches along R's boundary and its chains. 0 when beyond this
 * reading or too many. */
static int add_lake(leaf *l, uint32_t k)
{
    cut c;
    if (!cut_by_lake(l, k, &c))
        return 0;
    const int odd0 = corner_in_lake(l, k);
    if (c.n > 0)
        return add_pieces(l, k, &c, odd0);
    if (!odd0)
        return 1; /* misses R */
    if (l->n == WM_LEAF_ITEMS)
        return 0;
    l->it[l->n++] = (item){1, k, {0, l->per}, 1, 0, {0}};
    return 1;
}

/* Whether lake item t holds scene edge e: all of its slot's edges when it
 * is the slot's one piece, else those of its chains. */
static int holds_edge(const item *t, uint32_t e)
{
    if (t->nrun == 0)
        return 1;
    for (int c = 0; c < t->nrun; c++)
        if (e >= t->run[2 * c] && e <= t->run[2 * c + 1])
            return 1;
    return 0;
}

/* Adds the lake polygons meeting R; 0 when one is beyond this reading or
 * there are too many (or out of memory). Each polygon once: its edges
 * near R may be thousands (a dense shore), its polygons few, so they are
 * looked up among the polygons seen, not among the edges before. */
static int gather_lakes(leaf *l)
{
    wm_probe_lake_edges_near(l->p, l->x0 + l->W / 2.0, l->y0 + l->H / 2.0,
                             &l->le);
    uint32_t *seen = NULL;
    size_t nseen = 0, cap = 0;
    int ok = 1;
    for (size_t j = 0; ok && j < l->le.na + l->le.nb; j++)
    {
        const uint32_t k = near_edge(l, j)->k;
        size_t i = 0;
        while (i < nseen && seen[i] != k)
            i++;
        if (i < nseen)
            continue;
        ok = wm_push((void **)&seen, &nseen, &cap, &k, sizeof k) &&
             add_lake(l, k);
    }
    free(seen);
    return ok;
}

static int find(leaf *l, int i)
{
    while (l->up[i] != i)
        i = l->up[i] = l->up[l->up[i]];
    return i;
}

static void join(leaf *l, int a, int b)
{
    a = find(l, a);
    b = find(l, b);
    if (a != b)
        l->up[a < b ? b : a] = a < b ? a : b;
}

/* Whether items a and b share a stretch of R's boundary longer than
 * WM_COINCIDE. */
static int share_boundary(const item *a, const item *b)
{
    for (int i = 0; i < a->niv; i++)
        for (int j = 0; j < b->niv; j++)
            if (fmin(a->iv[2 * i + 1], b->iv[2 * j + 1]) -
                    fmax(a->iv[2 * i], b->iv[2 * j]) >
                WM_COINCIDE)
                return 1;
    return 0;
}

typedef struct
{
    double x, y;
} dpt;

/* Global lattice point (X, Y) relative to R's first corner. */
static dpt local(const leaf *l, int64_t X, int64_t Y)
{
    return (dpt){(double)(X - l->GX), (double)(Y - l->GY)};
}

/* The point of segment [a, b] nearest p. */
static dpt nearest_on(dpt a, dpt b, dpt p)
{
    const double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    return (dpt){a.x + t * dx, a.y + t * dy};
}

static double dist(dpt a, dpt b)
{
    return hypot(a.x - b.x, a.y - b.y);
}

/* Sign of the orientation of (a, b, c), global lattice points, exact. */
static int orient(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t cx,
                  int64_t cy)
{
    const wm_i128 d =
        (wm_i128)(bx - ax) * (cy - ay) - (wm_i128)(by - ay) * (cx - ax);
    return (d > 0) - (d < 0);
}

/* Whether segments [a, b] and [c, d] (global) cross at one point interior
 * to both (exact), written to *x relative to R. */
static int proper_cross(const leaf *l, const int64_t *a, const int64_t *b,
                        const int64_t *c, const int64_t *d, dpt *x)
{
    const int o1 = orient(a[0], a[1], b[0], b[1], c[0], c[1]);
    const int o2 = orient(a[0], a[1], b[0], b[1], d[0], d[1]);
    const int o3 = orient(c[0], c[1], d[0], d[1], a[0], a[1]);
    const int o4 = orient(c[0], c[1], d[0], d[1], b[0], b[1]);
    if (!(o1 * o2 < 0 && o3 * o4 < 0))
        return 0;
    const dpt A = local(l, a[0], a[1]), B = local(l, b[0], b[1]);
    const dpt C = local(l, c[0], c[1]), D = local(l, d[0], d[1]);
    const double den = (B.x - A.x) * (D.y - C.y) - (B.y - A.y) * (D.x - C.x);
    const double t =
        ((C.x - A.x) * (D.y - C.y) - (C.y - A.y) * (D.x - C.x)) / den;
    *x = (dpt){A.x + t * (B.x - A.x), A.y + t * (B.y - A.y)};
    return 1;
}

/* The closest points *pa, *pb of segments [a0, a1] and [b0, b1] (global,
 * as x, y pairs); returns their distance. */
static double closest(const leaf *l, const int64_t *a0, const int64_t *a1,
                      const int64_t *b0, const int64_t *b1, dpt *pa, dpt *pb)
{
    dpt x;
    if (proper_cross(l, a0, a1, b0, b1, &x))
    {
        *pa = *pb = x;
        return 0;
    }
    const dpt A0 = local(l, a0[0], a0[1]), A1 = local(l, a1[0], a1[1]);
    const dpt B0 = local(l, b0[0], b0[1]), B1 = local(l, b1[0], b1[1]);
    const dpt cand[4][2] = {{A0, nearest_on(B0, B1, A0)},
                            {A1, nearest_on(B0, B1, A1)},
                            {nearest_on(A0, A1, B0), B0},
                            {nearest_on(A0, A1, B1), B1}};
    double best = INFINITY;
    for (int i = 0; i < 4; i++)
    {
        const double d = dist(cand[i][0], cand[i][1]);
        if (d < best)
        {
            best = d;
            *pa = cand[i][0];
            *pb = cand[i][1];
        }
    }
    return best;
}

/* Whether point p (relative to R) lies strictly inside R. */
static int dpt_in(const leaf *l, dpt p)
{
    return p.x > 0 && p.x < l->W && p.y > 0 && p.y < l->H;
}

/* Clips segment [a, b] (relative to R) to R; 0 when it misses R. */
static int clip(const leaf *l, dpt *a, dpt *b)
{
    const double dx = b->x - a->x, dy = b->y - a->y;
    double t0, t1;
    if (!wm_clip_box(a->x, a->y, dx, dy, l->W, l->H, &t0, &t1))
        return 0;
    const dpt A = *a;
    *a = (dpt){A.x + t0 * dx, A.y + t0 * dy};
    *b = (dpt){A.x + t1 * dx, A.y + t1 * dy};
    return 1;
}

static void seg_ends(const wm_river_seg *g, int64_t *a, int64_t *b)
{
    a[0] = g->ax;
    a[1] = g->ay;
    b[0] = g->bx;
    b[1] = g->by;
}

static void edge_ends(const wm_lake_edge *g, int64_t *a, int64_t *b)
{
    a[0] = g->ax;
    a[1] = g->ay;
    b[0] = g->bx;
    b[1] = g->by;
}

/* Whether two capsules meet inside R, away from its boundary. */
static int capsules_meet(const leaf *l, const wm_river_seg *g,
                         const wm_river_seg *h)
{
    int64_t a0[2], a1[2], b0[2], b1[2];
    seg_ends(g, a0, a1);
    seg_ends(h, b0, b1);
    dpt pa = {0, 0}, pb = {0, 0};
    const double d = closest(l, a0, a1, b0, b1, &pa, &pb);
    if (!(d < g->r + h->r - WM_COINCIDE))
        return 0;
    const double t = d > 0 ? g->r / (g->r + h->r) : 0;
    return dpt_in(l, (dpt){pa.x + t * (pb.x - pa.x), pa.y + t * (pb.y - pa.y)});
}

/* Whether capsule item c meets lake item t inside R, away from its
 * boundary; -1 when this reading cannot tell (a capsule wholly inside R,
 * in a lake with several pieces there). */
static int capsule_meets_lake(const leaf *l, const item *c, const item *t)
{
    const wm_scene *s = l->p->s;
    const wm_river_seg *g = &s->segs[c->id];
    if (c->niv == 0 && lake_holds(l, t->id, g->ax, g->ay))
        return t->nrun ? -1 : 1; /* wholly inside R, in the lake */
    const dpt A = local(l, g->ax, g->ay), B = local(l, g->bx, g->by);
    for (size_t j = 0; j < l->le.na + l->le.nb; j++)
    {
        const struct wm_probe_edge *e = near_edge(l, j);
        if (e->k != t->id || !holds_edge(t, e->e))
            continue;
        const wm_lake_edge *h = &s->edges[e->e];
        dpt a = local(l, h->ax, h->ay), b = local(l, h->bx, h->by);
        if (!clip(l, &a, &b))
            continue;
        /* the clipped edge's nearest approach to the axis */
        const dpt pa = nearest_on(A, B, a), pb = nearest_on(A, B, b);
        const dpt qa = nearest_on(a, b, A), qb = nearest_on(a, b, B);
        double d = fmin(fmin(dist(a, pa), dist(b, pb)),
                        fmin(dist(qa, A), dist(qb, B)));
        int64_t a0[2], a1[2], b0[2], b1[2];
        seg_ends(g, a0, a1);
        edge_ends(h, b0, b1);
        dpt x;
        if (proper_cross(l, a0, a1, b0, b1, &x) && dpt_in(l, x))
            d = 0;
        if (d < g->r - WM_COINCIDE)
            return 1;
    }
    return 0;
}

/* Whether lake items a and b, of two polygons, have edges crossing inside
 * R (pieces of one polygon are apart by construction). */
static int lakes_meet(const leaf *l, const item *a, const item *b)
{
    const wm_scene *s = l->p->s;
    if (a->id == b->id)
        return 0;
    for (size_t i = 0; i < l->le.na + l->le.nb; i++)
    {
        const struct wm_probe_edge *e = near_edge(l, i);
        if (e->k != a->id || !holds_edge(a, e->e))
            continue;
        for (size_t j = 0; j < l->le.na + l->le.nb; j++)
        {
            const struct wm_probe_edge *f = near_edge(l, j);
            if (f->k != b->id || !holds_edge(b, f->e))
                continue;
            int64_t a0[2], a1[2], b0[2], b1[2];
            edge_ends(&s->edges[e->e], a0, a1);
            edge_ends(&s->edges[f->e], b0, b1);
            dpt x;
            if (proper_cross(l, a0, a1, b0, b1, &x) && dpt_in(l, x))
                return 1;
        }
    }
    return 0;
}

/* Whether items a and b meet inside R, away from its boundary; -1 when
 * this reading cannot tell. */
static int meet_inside(const leaf *l, const item *a, const item *b)
{
    const wm_scene *s = l->p->s;
    if (!a->lake && !b->lake)
        return capsules_meet(l, &s->segs[a->id], &s->segs[b->id]);
    if (a->lake && b->lake)
        return lakes_meet(l, a, b);
    return a->lake ? capsule_meets_lake(l, b, a) : capsule_meets_lake(l, a, b);
}

typedef struct
{
    double lo, hi;
    int item;
} stretch;

static int cmp_stretch(const void *a, const void *b)
{
    const stretch *x = a, *y = b;
    return (x->lo > y->lo) - (x->lo < y->lo);
}

/* Distance along the boundary (perimeter per) from position v to the
 * stretch [lo, hi] (lo may be negative: wrapping past the first corner). */
static double cyc_dist(double v, double lo, double hi, double per)
{
    double best = INFINITY;
    for (int k = -1; k <= 1; k++)
    {
        const double w = v + k * per;
        const double d = w < lo ? lo - w : (w > hi ? w - hi : 0);
        best = d < best ? d : best;
    }
    return best;
}

/* Merges the items' water stretches along R's boundary into pieces
 * (joining the items of each), matches them to the caller's arcs and
 * labels those; 0 when they do not match one to one. */
static int label_arcs(leaf *l, int narc, const int64_t *arc, int *label)
{
    stretch st[WM_LEAF_ITEMS * STRETCHES];
    int ns = 0;
    for (int i = 0; i < l->n; i++)
        for (int j = 0; j < l->it[i].niv; j++)
            st[ns++] = (stretch){l->it[i].iv[2 * j], l->it[i].iv[2 * j + 1], i};
    qsort(st, (size_t)ns, sizeof *st, cmp_stretch);
    stretch piece[WM_LEAF_ARCS + 1];
    int np = 0;
    for (int i = 0; i < ns; i++)
    {
        if (np > 0 && st[i].lo <= piece[np - 1].hi + WM_COINCIDE)
        {
            piece[np - 1].hi = fmax(piece[np - 1].hi, st[i].hi);
            join(l, piece[np - 1].item, st[i].item);
            continue;
        }
        if (np == WM_LEAF_ARCS + 1)
            return 0;
        piece[np++] = st[i];
    }
    /* a piece through the first corner */
    if (np > 1 && piece[0].lo <= WM_COINCIDE &&
        piece[np - 1].hi >= l->per - WM_COINCIDE)
    {
        join(l, piece[0].item, piece[np - 1].item);
        piece[0].lo = piece[np - 1].lo - l->per;
        np--;
    }
    if (np != narc || narc == 0)
        return 0;
    /* the piece nearest arc 0's middle, then in order */
    int first = 0;
    double best = INFINITY;
    for (int j = 0; j < np; j++)
    {
        const double d = cyc_dist((double)(arc[0] + arc[1]) / 2.0, piece[j].lo,
                                  piece[j].hi, l->per);
        if (d < best)
        {
            best = d;
            first = j;
        }
    }
    for (int i = 0; i < narc; i++)
    {
        const stretch *pc = &piece[(first + i) % np];
        if (cyc_dist((double)arc[2 * i], pc->lo, pc->lo, l->per) > ARC_SLACK ||
            cyc_dist((double)arc[2 * i + 1], pc->hi, pc->hi, l->per) >
                ARC_SLACK)
            return 0;
        label[i] = find(l, pc->item);
    }
    return 1;
}

int wm_leaf_join(wm_probe *p, int32_t x0, int32_t y0, int32_t x1, int32_t y1,
                 int narc, const int64_t *arc, int *label)
{
    if (x1 - x0 > WM_LEAF_SIDE || y1 - y0 > WM_LEAF_SIDE ||
        narc > WM_LEAF_ARCS || narc < 1)
        return 0;
    leaf *l = malloc(sizeof *l);
    if (!l)
        return -1;
    l->p = p;
    l->x0 = x0;
    l->y0 = y0;
    l->GX = p->X0 + x0;
    l->GY = p->Y0 + y0;
    l->W = x1 - x0;
    l->H = y1 - y0;
    l->per = 2.0 * (l->W + l->H);
    l->n = 0;
    int ok = gather_rivers(l) && gather_lakes(l);
    for (int i = 0; ok && i < l->n; i++)
        l->up[i] = i;
    for (int i = 0; ok && i < l->n; i++)
        for (int j = i + 1; ok && j < l->n; j++)
        {
            if (find(l, i) == find(l, j))
                continue;
            const int m = share_boundary(&l->it[i], &l->it[j])
                              ? 1
                              : meet_inside(l, &l->it[i], &l->it[j]);
            if (m > 0)
                join(l, i, j);
            ok = m >= 0;
        }
    ok = ok && label_arcs(l, narc, arc, label);
    free(l);
    return ok;
}
