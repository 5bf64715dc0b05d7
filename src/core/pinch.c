/*
 * pinch.c - points where a block's boundary touches itself, opened.
 *
 * Method (pinch.h has the rule): every vertex strictly inside a cell of the
 * sample grid (no other may repeat, in_cell) goes into an open-addressing
 * table keyed by its lattice point; a point met twice is a pinch. Their
 * segments go into a grid of pixel cells (wm_cells) by their boxes; a
 * vertex inside one of them is a T. The passes through each such point
 * that may move are candidates, each with the lattice point it would move
 * to (the first one strictly inside its triangle along the wedge's
 * bisector) or none (then it would be cut); the regions they sweep are
 * checked empty by one pass over the vertices (a grid of the triangles'
 * boxes); all passes but one per pinch (the vertex of a T) are
 * chosen among those that passed and moved or cut. A move or cut next to
 * another waits for a next round on the new rings.
 *
 * Complexity: per round, O(n) for the filter, O(m log m) for the table
 * and the cell list of the m vertices inside cells and their segments
 * (a few per cent of a block's); where points are found, O(n log c) more
 * for c candidates. Rounds are few: a round stops only at neighbouring
 * passes.
 *
 * Robustness: exact integer orientation tests (lattice.h) decide; doubles
 * only propose the point a pass moves to.
 */
#include "pinch.h"
#include "lattice.h"
#include "scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FREE UINT32_MAX
#define MOVED 1 /* mark of a vertex moved or cut */
#define NEXT 2  /* mark of a neighbour of one */
#define MAX_ROUNDS 64
#define PINCH 1 /* a vertex at a pinch */
#define TEE 2   /* a vertex inside another segment */

/* A lattice point's slot table: slot[h] is the first vertex seen there. */
typedef struct
{
    uint32_t *slot;
    size_t mask;
} ptab;

/* A pass through a pinch that may move: vertex i (at P) of ring r, whose
 * ring neighbours a and b make the counter-clockwise triangle (a, P, b) on
 * the convex side of its turn, at a pinch of npass passes, to q (when
 * moves; else cut). */
typedef struct
{
    size_t i, a, b;
    size_t r, group, npass; /* group: its pinch's number */
    wm_pt q;
    int moves, ok; /* ok: the region it sweeps holds no vertex */
} pass;

/* A T: vertex v inside the segment from vertex a to vertex b. */
typedef struct
{
    size_t v, a, b;
} tee;

/* Items by grid cell over the block square (wm_cells), cells of cs
 * lattice units (a pixel, or more where the grid would pass 65535 cells a
 * side). */
typedef struct
{
    wm_cells g;
    int32_t cs;
} grid;

/* The first vertex at p's point (FREE when none yet); *h its slot. */
static uint32_t ptab_find(const ptab *t, const wm_pt *pts, wm_pt p, size_t *h)
{
    size_t k = wm_hash64(wm_pt_key(p), t->mask);
    while (t->slot[k] != FREE && !wm_pt_eq(pts[t->slot[k]], p))
        k = (k + 1) & t->mask;
    *h = k;
    return t->slot[k];
}

static int cmp_size(const void *x, const void *y)
{
    const size_t a = *(const size_t *)x, b = *(const size_t *)y;
    return (a > b) - (a < b);
}

/* Pairs of sizes, by the first, then the second: a total order, so that
 * the sort's result is one whatever the C library. */
static int cmp_pair(const void *x, const void *y)
{
    const size_t *a = x, *b = y;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0])
                        : (a[1] > b[1]) - (a[1] < b[1]);
}

/* The ring holding vertex i. */
static size_t ring_of(const wm_rings *r, size_t i)
{
    size_t lo = 0, hi = r->nrings; /* start[lo] <= i < start[hi] */
    while (hi - lo > 1)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (r->start[mid] <= i)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Whether q lies in the closed counter-clockwise triangle (a, p, b), and
 * strictly inside it. */
static int in_triangle(wm_pt a, wm_pt p, wm_pt b, wm_pt q)
{
    return wm_orient(a, p, q) >= 0 && wm_orient(p, b, q) >= 0 &&
           wm_orient(b, a, q) >= 0;
}

static int inside_triangle(wm_pt a, wm_pt p, wm_pt b, wm_pt q)
{
    return wm_orient(a, p, q) > 0 && wm_orient(p, b, q) > 0 &&
           wm_orient(b, a, q) > 0;
}

/* The lattice point nearest p, along the bisector of the left turn
 * a -> p -> b, strictly inside triangle (a, p, b), into *q; 0 when steps
 * of 1, 2, 3 and 4 units, then half as long again each time, up to the
 * longer side find none (the bisector leaves the triangle before it). */
static int move_to(wm_pt a, wm_pt p, wm_pt b, wm_pt *q)
{
    const double ax = (double)a.x - p.x, ay = (double)a.y - p.y;
    const double bx = (double)b.x - p.x, by = (double)b.y - p.y;
    const double la = hypot(ax, ay), lb = hypot(bx, by);
    double ux = ax / la + bx / lb, uy = ay / la + by / lb;
    const double lu = hypot(ux, uy);
    if (!(lu > 0))
        return 0;
    ux /= lu;
    uy /= lu;
    const double reach = la > lb ? la : lb;
    for (double k = 1; k <= reach; k = k < 4 ? k + 1 : k * 1.5)
    {
        q->x = p.x + (int32_t)lround(k * ux);
        q->y = p.y + (int32_t)lround(k * uy);
        if (inside_triangle(a, p, b, *q))
            return 1;
    }
    return 0;
}

/* Whether p lies strictly inside a cell of the sample grid. A vertex on a
 * sample row or column is a crossing of a cell's side, and the crossings
 * of one side are distinct lattice points (marching squares puts one
 * there; subpixel.c rounds more apart, probe.c round_crossings); only a
 * vertex inside a cell (subdivision, leaves, corners) may repeat. */
static int in_cell(wm_pt p)
{
    return (p.x & (WM_Q - 1)) != 0 && (p.y & (WM_Q - 1)) != 0;
}

/* Step 1: the vertices inside cells into in[0 .. *nin) (the caller frees
 * it) and a table of them; those met at a point already taken go to
 * rep[0 .. *nrep) (a pinch each). Returns 0 when out of memory. */
static int find_repeats(const wm_rings *r, ptab *t, uint32_t **in, size_t *nin,
                        size_t **rep, size_t *nrep)
{
    size_t cap = 16, rcap = 0;
    *nin = 0;
    if (!(*in = malloc(r->npts * sizeof **in)))
        return 0;
    for (size_t i = 0; i < r->npts; i++)
    {
        (*in)[*nin] = (uint32_t)i; /* kept only where it is in a cell */
        *nin += (size_t)in_cell(r->pts[i]);
    }
    while (cap < 2 * *nin)
        cap *= 2;
    t->mask = cap - 1;
    if (!(t->slot = malloc(cap * sizeof *t->slot)))
        return 0;
    memset(t->slot, 0xff, cap * sizeof *t->slot);
    for (size_t k = 0; k < *nin; k++)
    {
        const uint32_t i = (*in)[k];
        size_t h;
        if (ptab_find(t, r->pts, r->pts[i], &h) == FREE)
        {
            t->slot[h] = i;
            continue;
        }
        const size_t at = i;
        if (!wm_push((void **)rep, nrep, &rcap, &at, sizeof at))
            return 0;
    }
    return 1;
}

/* The vertex after i in its ring (ring ri). */
static size_t next_of(const wm_rings *r, size_t ri, size_t i)
{
    return i + 1 < r->start[ri + 1] ? i + 1 : r->start[ri];
}

static void grid_init(grid *G, int32_t S)
{
    memset(G, 0, sizeof *G);
    G->cs = WM_Q;
    while (S / G->cs + 1 > 65535)
        G->cs *= 2;
    wm_cells_reset(&G->g, S / G->cs + 1);
}

/* The cell holding coordinate x, clamped to the grid. */
static int32_t grid_cell(const grid *G, int32_t x)
{
    const int32_t c = x < 0 ? 0 : x / G->cs;
    return c < G->g.side ? c : G->g.side - 1;
}

/* Adds item to every cell the box of a and b covers; 0 when out of
 * memory. */
static int grid_add(grid *G, wm_pt a, wm_pt b, uint32_t item)
{
    const int32_t x0 = grid_cell(G, a.x < b.x ? a.x : b.x);
    const int32_t x1 = grid_cell(G, a.x < b.x ? b.x : a.x);
    const int32_t y0 = grid_cell(G, a.y < b.y ? a.y : b.y);
    const int32_t y1 = grid_cell(G, a.y < b.y ? b.y : a.y);
    for (int32_t cy = y0; cy <= y1; cy++)
        for (int32_t cx = x0; cx <= x1; cx++)
            if (!wm_cells_add(&G->g, cx, cy, item))
                return 0;
    return 1;
}

/* The items of the cell holding p: G->g.item[*b .. *e). */
static void grid_at(const grid *G, wm_pt p, size_t *b, size_t *e)
{
    const int32_t cx = grid_cell(G, p.x);
    wm_cells_row(&G->g, grid_cell(G, p.y), cx, cx, b, e);
}

/* Step 1b: the vertices inside cells (in[0 .. nin)) that lie inside a
 * segment with an end inside a cell (a T: the boundary touches itself
 * there too), each with the segment's two vertices, into (*tees)[0 ..
 * *ntee). A segment through a vertex inside a
 * cell has such an end: marching squares' segments cross cells that hold
 * no other boundary. Returns 0 when out of memory. */
static int find_tees(const wm_rings *r, int32_t S, const uint32_t *in,
                     size_t nin, tee **tees, size_t *ntee)
{
    grid G;
    size_t *seg = NULL, nseg = 0, scap = 0, tcap = 0; /* pairs a, b */
    int ok = 0;
    if (nin < 2)
        return 1; /* a T needs a segment with an end inside a cell too */
    grid_init(&G, S);
    for (size_t k = 0, ri = 0; k < nin; k++)
    {
        const size_t i = in[k]; /* ascending: so are the rings */
        while (r->start[ri + 1] <= i)
            ri++;
        const size_t j = next_of(r, ri, i);
        const size_t h = i > r->start[ri] ? i - 1 : r->start[ri + 1] - 1;
        /* segments i -> j, and h -> i unless h lists it */
        const size_t ends[4] = {i, j, h, i};
        for (int e = 0; e < (in_cell(r->pts[h]) ? 2 : 4); e += 2)
            if (!wm_push((void **)&seg, &nseg, &scap, &ends[e], sizeof *ends) ||
                !wm_push((void **)&seg, &nseg, &scap, &ends[e + 1],
                         sizeof *ends) ||
                !grid_add(&G, r->pts[ends[e]], r->pts[ends[e + 1]],
                          (uint32_t)(nseg / 2 - 1)))
                goto cleanup;
    }
    if (wm_cells_index(&G.g) != WM_OK)
        goto cleanup;
    for (size_t k = 0; k < nin; k++)
    {
        const wm_pt v = r->pts[in[k]];
        size_t b, e;
        grid_at(&G, v, &b, &e);
        for (; b < e; b++)
        {
            const size_t *sg = seg + 2 * G.g.item[b];
            const wm_pt pa = r->pts[sg[0]], pb = r->pts[sg[1]];
            if (wm_pt_eq(v, pa) || wm_pt_eq(v, pb) || !wm_on_segment(pa, pb, v))
                continue;
            const tee t = {in[k], sg[0], sg[1]};
            if (!wm_push((void **)tees, ntee, &tcap, &t, sizeof t))
                goto cleanup;
            break;
        }
    }
    ok = 1;
cleanup:
    free(seg);
    wm_cells_free(&G.g);
    return ok;
}

/* The neighbours of vertex i in its ring: *a before it, *b after it. */
static void neighbours(const wm_rings *r, size_t i, size_t *a, size_t *b)
{
    const size_t ri = ring_of(r, i), s = r->start[ri];
    const size_t len = wm_rings_len(r, ri);
    *a = s + (i - s + len - 1) % len;
    *b = s + (i - s + 1) % len;
}

/* Whether e lies in the closed wedge at p of the counter-clockwise
 * triangle (u, p, w). */
static int in_wedge(wm_pt u, wm_pt p, wm_pt w, wm_pt e)
{
    return wm_orient(u, p, e) >= 0 && wm_orient(p, w, e) >= 0;
}

/* One round's state: the rings, the block square's side S, what each
 * vertex is (seen: PINCH, TEE), and the candidates so far. */
typedef struct
{
    wm_rings *r;
    int32_t S;
    uint8_t *seen;
    pass *ps;
    size_t nps, cap, group;
} round_state;

static int on_one_side(wm_pt a, wm_pt b, int32_t S)
{
    return (a.x == b.x && (a.x == 0 || a.x == S)) ||
           (a.y == b.y && (a.y == 0 || a.y == S));
}

/* Whether the pass at vertex i (between ring neighbours a before and b
 * after) may be cut to a -> b: neither end is a pinch or a T (where other
 * segments meet it), the chord continues neither neighbouring segment
 * (it would fold back onto one, or run along it), and it does not lie
 * along a side of the block square (where the block across would not
 * cover the same piece). */
static int may_cut(const round_state *R, size_t a, size_t b)
{
    const wm_rings *r = R->r;
    size_t aa, ab, ba, bb;
    neighbours(r, a, &aa, &ab);
    neighbours(r, b, &ba, &bb);
    return !R->seen[a] && !R->seen[b] &&
           wm_orient(r->pts[aa], r->pts[a], r->pts[b]) != 0 &&
           wm_orient(r->pts[a], r->pts[b], r->pts[bb]) != 0 &&
           !on_one_side(r->pts[a], r->pts[b], R->S);
}

/* Step 2: the candidates among the passes through one point P, at[0 ..
 * n), npass passes there in all (the segment through a T, from t0 to t1,
 * counts as one that does not move): each pass that turns at P, to move
 * into the convex side of its turn (its water wedge where it turns left,
 * its land wedge where it turns right), where no other segment at P leaves
 * into that wedge, with the point it would move to, or to be cut where
 * there is none and may_cut allows. Returns 0 when out of memory. */
static int candidates(round_state *R, const size_t *at, size_t n,
                      const wm_pt *t, size_t npass)
{
    const wm_rings *r = R->r;
    const size_t group = R->group++;
    for (size_t k = 0; k < n; k++)
    {
        const size_t i = at[k];
        size_t a, b;
        neighbours(r, i, &a, &b);
        const int o = wm_orient(r->pts[a], r->pts[i], r->pts[b]);
        if (o == 0)
            continue;
        const size_t u = o > 0 ? a : b, w = o > 0 ? b : a;
        const wm_pt pu = r->pts[u], p = r->pts[i], pw = r->pts[w];
        int clear =
            !t || (!in_wedge(pu, p, pw, t[0]) && !in_wedge(pu, p, pw, t[1]));
        for (size_t j = 0; clear && j < n; j++)
        {
            size_t x, y;
            neighbours(r, at[j], &x, &y);
            clear = j == k || (!in_wedge(pu, p, pw, r->pts[x]) &&
                               !in_wedge(pu, p, pw, r->pts[y]));
        }
        pass c = {i, u, w, ring_of(r, i), group, npass, p, 0, 1};
        c.moves = move_to(pu, p, pw, &c.q);
        if (!clear || (!c.moves && !may_cut(R, a, b)))
            continue;
        if (!wm_push((void **)&R->ps, &R->nps, &R->cap, &c, sizeof c))
            return 0;
    }
    return 1;
}

/* Step 3: every candidate that sweeps a vertex other than its own three
 * points is given up: a move sweeps its closed triangle less the open one
 * (a, q, b) and the open chord a -> b, a cut the closed triangle. Returns
 * 0 when out of memory. */
static int check_empty(const wm_rings *r, int32_t S, pass *ps, size_t nps)
{
    grid G;
    int ok = 0;
    grid_init(&G, S);
    for (size_t c = 0; c < nps; c++)
    {
        const wm_pt a = r->pts[ps[c].a], p = r->pts[ps[c].i];
        const wm_pt b = r->pts[ps[c].b];
        const wm_pt lo = {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y};
        const wm_pt hi = {a.x < b.x ? b.x : a.x, a.y < b.y ? b.y : a.y};
        const wm_pt lo3 = {lo.x < p.x ? lo.x : p.x, lo.y < p.y ? lo.y : p.y};
        const wm_pt hi3 = {hi.x > p.x ? hi.x : p.x, hi.y > p.y ? hi.y : p.y};
        if (!grid_add(&G, lo3, hi3, (uint32_t)c))
            goto cleanup;
    }
    if (wm_cells_index(&G.g) != WM_OK)
        goto cleanup;
    for (size_t q = 0; q < r->npts; q++)
    {
        const wm_pt v = r->pts[q];
        size_t k, e;
        grid_at(&G, v, &k, &e);
        for (; k < e; k++)
        {
            pass *c = &ps[G.g.item[k]];
            const wm_pt a = r->pts[c->a], p = r->pts[c->i], b = r->pts[c->b];
            if (c->ok && !wm_pt_eq(v, a) && !wm_pt_eq(v, p) &&
                !wm_pt_eq(v, b) && in_triangle(a, p, b, v) &&
                !(c->moves &&
                  (inside_triangle(a, c->q, b, v) || wm_on_segment(a, b, v))))
                c->ok = 0;
        }
    }
    ok = 1;
cleanup:
    wm_cells_free(&G.g);
    return ok;
}

/* Step 4: of the candidates of each pinch (consecutive in ps[]) that
 * sweep no vertex, all passes but one moved or cut, a cut only in a ring
 * that keeps three vertices (left[]: vertices still in each ring), no two
 * next to each other in a ring (mark[]: MOVED, or NEXT to one); the moves
 * made, the vertices to remove into gone[0 .. return). */
static size_t apply_passes(wm_rings *r, const pass *ps, size_t nps,
                           size_t *left, uint8_t *mark, size_t *gone,
                           size_t *nmoved)
{
    size_t ngone = 0;
    for (size_t lo = 0, hi; lo < nps; lo = hi)
    {
        size_t made = 0;
        for (hi = lo + 1; hi < nps && ps[hi].group == ps[lo].group; hi++)
            ;
        for (size_t k = lo; k < hi && made + 1 < ps[lo].npass; k++)
        {
            const pass *c = &ps[k];
            if (!c->ok || (!c->moves && left[c->r] <= 3) || mark[c->i] ||
                mark[c->a] == MOVED || mark[c->b] == MOVED)
                continue;
            mark[c->i] = MOVED;
            mark[c->a] = mark[c->b] = NEXT;
            if (c->moves)
            {
                r->pts[c->i] = c->q;
                (*nmoved)++;
            }
            else
            {
                left[c->r]--;
                gone[ngone++] = c->i;
            }
            made++;
        }
    }
    return ngone;
}

/* Step 5: the cut vertices (sorted gone[0 .. n)) removed from their
 * rings. */
static void remove_vertices(wm_rings *r, const size_t *gone, size_t n)
{
    size_t w = 0, g = 0;
    for (size_t ri = 0; ri < r->nrings; ri++)
    {
        const size_t s = r->start[ri], e = r->start[ri + 1];
        r->start[ri] = w;
        for (size_t i = s; i < e; i++)
        {
            if (g < n && gone[g] == i)
            {
                g++;
                continue;
            }
            r->pts[w++] = r->pts[i];
        }
    }
    r->start[r->nrings] = w;
    r->npts = w;
}

/* Step 2 for every point found: the passes through each pinch (its first
 * vertex, then its repeats, sorted by that first vertex), and the vertex
 * of each T. A point that is both a pinch and a T waits (no candidate
 * weighs both). Returns 0 when out of memory. */
static int all_candidates(round_state *R, const ptab *t, const size_t *rep,
                          size_t nrep, const tee *tees, size_t ntee)
{
    const wm_rings *r = R->r;
    size_t *key = malloc((3 * nrep + 1) * sizeof *key);
    if (!key)
        return 0;
    for (size_t k = 0; k < nrep; k++)
    {
        size_t h;
        key[2 * k] = ptab_find(t, r->pts, r->pts[rep[k]], &h);
        key[2 * k + 1] = rep[k];
        R->seen[key[2 * k]] = R->seen[rep[k]] = PINCH;
    }
    for (size_t k = 0; k < ntee; k++)
        R->seen[tees[k].v] |= TEE;
    qsort(key, nrep, 2 * sizeof *key, cmp_pair);
    int ok = 1;
    for (size_t lo = 0, hi; ok && lo < nrep; lo = hi)
    {
        size_t *at = key + 2 * nrep, n = 0;
        int both = 0;
        at[n++] = key[2 * lo];
        for (hi = lo; hi < nrep && key[2 * hi] == key[2 * lo]; hi++)
            at[n++] = key[2 * hi + 1];
        for (size_t k = 0; k < n; k++)
            both |= R->seen[at[k]] & TEE;
        ok = both || candidates(R, at, n, NULL, n);
    }
    free(key);
    for (size_t k = 0; ok && k < ntee; k++)
    {
        const wm_pt seg[2] = {r->pts[tees[k].a], r->pts[tees[k].b]};
        ok = (R->seen[tees[k].v] & PINCH) ||
             candidates(R, &tees[k].v, 1, seg, 2);
    }
    return ok;
}

/* One round: the points where the rings touch found, and the passes that
 * may be moved or cut there moved or cut; *nchanged: how many. Returns 0
 * when out of memory. */
static int open_round(wm_rings *r, int32_t S, size_t *nchanged)
{
    ptab t = {NULL, 0};
    uint32_t *in = NULL;
    size_t *rep = NULL, *left = NULL, *gone = NULL;
    tee *tees = NULL;
    size_t nin = 0, nrep = 0, ntee = 0;
    uint8_t *mark = NULL;
    round_state R = {r, S, NULL, NULL, 0, 0, 0};
    int ok = 0;
    *nchanged = 0;
    if (!find_repeats(r, &t, &in, &nin, &rep, &nrep) ||
        !find_tees(r, S, in, nin, &tees, &ntee))
        goto cleanup;
    if ((nrep || ntee) && (!(R.seen = calloc(r->npts, 1)) ||
                           !all_candidates(&R, &t, rep, nrep, tees, ntee)))
        goto cleanup;
    if (R.nps)
    {
        left = malloc(r->nrings * sizeof *left);
        mark = calloc(r->npts, 1);
        gone = malloc(R.nps * sizeof *gone);
        if (!left || !mark || !gone || !check_empty(r, S, R.ps, R.nps))
            goto cleanup;
        for (size_t ri = 0; ri < r->nrings; ri++)
            left[ri] = wm_rings_len(r, ri);
        size_t nmoved = 0;
        const size_t ngone =
            apply_passes(r, R.ps, R.nps, left, mark, gone, &nmoved);
        qsort(gone, ngone, sizeof *gone, cmp_size);
        remove_vertices(r, gone, ngone);
        *nchanged = ngone + nmoved;
    }
    ok = 1;
cleanup:
    free(t.slot);
    free(in);
    free(rep);
    free(tees);
    free(left);
    free(mark);
    free(R.seen);
    free(R.ps);
    free(gone);
    return ok;
}

wm_status wm_rings_open_pinches(wm_rings *r, int32_t S, const wm_ctx *ctx)
{
    if (r->npts >= FREE)
        return wm_fail(ctx, WM_ERR_NOMEM, "pinch: too many vertices");
    /* a pass next to one moved or cut waits for the next round, on the
     * new rings; each round that changes a pass opens a pinch */
    size_t nchanged = 1;
    for (int round = 0; round < MAX_ROUNDS && nchanged > 0 && r->npts; round++)
        if (!open_round(r, S, &nchanged))
            return wm_fail(ctx, WM_ERR_NOMEM,
                           "out of memory opening pinch points");
    return WM_OK;
}
