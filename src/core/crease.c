/*
 * crease.c - recovery of the sharp corners of the union boundary.
 *
 * Why: marching squares on a sampled distance field rounds every corner of
 * the union off within about a pixel, but where two input boundaries cross
 * at a small angle (a river bank meeting a lake shore nearly tangentially,
 * two tributaries joining at a sharp angle, an acute lake vertex) the lost
 * tip is pixel / (2 tan(angle / 2)) long: several pixels for a 10 degree
 * wedge. The corners are known exactly from the input, so they are put
 * back (cf. Kobbelt et al. 2001, "Feature sensitive surface extraction from
 * volume data", which does the same per cell from normals).
 *
 * Method, per block:
 *   1-2. the candidate corners: crossings of two input boundaries strictly
 *      inside the block, near the boundary (corners.c, shared with the
 *      sub-pixel search);
 *   3. for each candidate C (lattice-snapped), the nearest ring edge; C is
 *      tried when it is 1/4 .. 16 pixels away (closer: nothing to
 *      recover), on that edge or, failing that, on a neighbouring one (a
 *      truncated tip ends in a vertex), never on an edge of the block
 *      square (seams stay exact, invariant 4);
 *   4. C is inserted when the two new edges meet no other ring edge and
 *      the triangle they add or cut contains no ring vertex (exact lattice
 *      predicates), so the rings stay simple, disjoint and keep their
 *      nesting (invariant 3); and when the new edges follow the union's
 *      boundary (C on it, the edges within half a pixel of it, by a direct
 *      distance evaluation), so a corner of an input that sampling missed
 *      altogether does not become a spike. At most one corner per edge and
 *      pass; up to four passes.
 * Floating point decides only which corners to try, never validity.
 *
 * Cost: finding the candidates, corners.c; every candidate
 * costs a local ring-grid search and, when it is more than 1/4 pixel away,
 * distance evaluations against the block's inputs (O(inputs in reach)).
 * Candidates that reach that point are few: one per corner of the union.
 */
#include "crease.h"

#include "corners.h"

#include "contour.h"
#include "field.h"
#include "probe.h"

#include "lattice.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint64_t ckey(int64_t cx, int64_t cy)
{
    return ((uint64_t)(uint32_t)(int32_t)cy << 32) | (uint32_t)(int32_t)cx;
}

typedef struct
{
    wm_pt p;
    size_t seg; /* insert after vertex seg (rings are contiguous: the
                   order of seg is the order along the rings) */
} insertion;

/* What the passes know of a candidate corner. A pass tries the open ones
 * (a later pass: those near a corner the previous one inserted). One found
 * within a quarter pixel of a ring edge has nothing to recover while that
 * edge stands: passes only split edges, so it is tried again only once its
 * witness edge is split (and the nearest edge search would skip it until
 * then). An inserted corner, or one off the union's boundary (which depends
 * on the inputs only), is settled. */
enum
{
    C_OPEN,
    C_CLOSE,
    C_DONE
};

typedef struct
{
    wm_pt c;
    wm_pt e0, e1; /* C_CLOSE: the witness edge */
    int state;
} corner;

static int cmp_ins(const void *a, const void *b)
{
    const insertion *x = a, *y = b;
    return (x->seg > y->seg) - (x->seg < y->seg);
}

/* How many scattered field reads ahead a loop prefetches. */
#define PREFETCH 8

/* Whether a point of the block within an eighth of a pixel of (x, y), in
 * one of eight directions, is of class `land` (1) or water (0): the new
 * edges a - c and c - b are chords of the union's boundary, which may bulge
 * across them (the round caps of two rivers ending side by side leave a
 * notch whose sides bulge into the triangle: a median point 0.01 pixel
 * inside a cap, seam seed 146366 at 0.9 m, left the notch's tip 0.54 pixel
 * off), while a spike along an edge two inputs share lies inside the union
 * far from either class's other side. Only points of the block count: its
 * rings hold its own square, and water just across a block side is the
 * next block's (a lake's edge on the side, a corner of it on the side 11
 * pixels from a stream leaving the lake: a spike along the side a unit
 * wide, held-out round 30). */
static int class_near(wm_probe *in, double x, double y, int land)
{
    const double d = WM_Q / 8.0, h = d * 0.70710678118654752;
    const double S = (double)in->s->n * WM_Q;
    static const double dir[8][2] = {{1, 0}, {0, 1},  {-1, 0},  {0, -1},
                                     {1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
    for (int k = 0; k < 8; k++)
    {
        const double s = k < 4 ? d : h;
        const double px = x + s * dir[k][0], py = y + s * dir[k][1];
        if (px < 0 || py < 0 || px > S || py > S)
            continue;
        if ((wm_probe_distance(in, px, py, 4.0 * WM_Q) > 0) == land)
            return 1;
    }
    return 0;
}

/* True when the new edges a - c - b (c on the union's boundary) stay within
 * half a pixel of that boundary.
 * Rejects corners of inputs the sampling missed altogether (a lake smaller
 * than a pixel), which would otherwise become spikes. */
static int follows_boundary(wm_probe *in, wm_pt a, wm_pt c, wm_pt b)
{
    const double reach = 4.0 * WM_Q;
    /* the triangle a c b changes class (water is left of a -> b: a corner
     * on the left moves the boundary into water, so the triangle becomes
     * land); its median from the middle of a b to c must be of that class,
     * at its quarter, third (the centroid), half and three quarters. Where
     * two inputs share a boundary inside the union (lakes with a common
     * edge) the distance is 0 along it, and this is what rejects a spike
     * along it: a thin one, along the line of such an edge that goes on as
     * a shore, has its centroid beside the shore, the rest of its median
     * inside the union (Andorra at 1 m pixels, 3.4 pixels). */
    const double mx = ((double)a.x + b.x) / 2.0, my = ((double)a.y + b.y) / 2.0;
    static const double along[] = {0.25, 1.0 / 3.0, 0.5, 0.75};
    const int land = wm_orient(a, b, c) > 0;
    for (int k = 0; k < 4; k++)
    {
        const double x = mx + along[k] * (c.x - mx),
                     y = my + along[k] * (c.y - my);
        if ((wm_probe_distance(in, x, y, reach) > 0) != land &&
            !class_near(in, x, y, land))
            return 0;
    }
    for (int e = 0; e < 2; e++)
    {
        const wm_pt p = e ? b : a;
        for (int k = 1; k < 4; k++)
        {
            const double t = k / 4.0;
            const double x = c.x + t * (p.x - c.x), y = c.y + t * (p.y - c.y);
            if (fabs(wm_probe_distance(in, x, y, reach)) > 0.5 * WM_Q)
                return 0;
        }
    }
    return 1;
}

/* ---- ring edges in a grid --------------------------------------------- */

/* Ring grid cells: 16 pixels, smaller where the rings are dense
 * (insert_pass). */
#define RCELL (16 * WM_Q)
/* Farthest a corner is looked for from the sampled rings: the tip of a
 * 5 degree wedge (pixel / (2 tan 2.5 deg) = 11.5 px) is within reach. */
#define WM_CREASE_REACH (16 * WM_Q)

/* The rings' edges by cell of a grid over the block. With an
 * `active` mask (of RCELL cells, each covering whole grid cells) only the
 * marked cells hold their edges: a later pass looks only near the corners
 * just inserted, and a query reaching an unmarked cell completes the grid
 * first (visit_edges), so a query never misses an edge. */
typedef struct
{
    const wm_rings *r;
    wm_cells cells;    /* edge k = from vertex k to its successor; its
                          side is the grid's */
    int32_t cell;      /* cell side, lattice units (RCELL >> k) */
    int32_t aside;     /* active's side: S / RCELL + 1 */
    uint32_t *ring_of; /* vertex -> ring */
    uint8_t *active;   /* aside^2, or NULL: every cell registered (owned) */
} ringgrid;

static size_t succ(const wm_rings *r, const uint32_t *ring_of, size_t k)
{
    const size_t ri = ring_of[k];
    return k + 1 == r->start[ri + 1] ? r->start[ri] : k + 1;
}

static size_t pred(const wm_rings *r, const uint32_t *ring_of, size_t k)
{
    const size_t ri = ring_of[k];
    return k == r->start[ri] ? r->start[ri + 1] - 1 : k - 1;
}

static int32_t cell_of(const ringgrid *g, int32_t v)
{
    if (v < 0)
        return 0;
    const int32_t c = v / g->cell; /* v >= 0: a shift */
    return c >= g->cells.side ? g->cells.side - 1 : c;
}

/* The cell of the active mask holding lattice coordinate v. */
static int32_t mask_of(const ringgrid *g, int32_t v)
{
    if (v < 0)
        return 0;
    const int32_t c = v / RCELL;
    return c >= g->aside ? g->aside - 1 : c;
}

/* Whether every cell (every = 1) or some cell (every = 0) of the mask over
 * [x0, x1] x [y0, y1] (lattice box) is marked. */
static int box_active(const ringgrid *g, int32_t x0, int32_t y0, int32_t x1,
                      int32_t y1, int every)
{
    if (!g->active)
        return 1;
    const int32_t cx0 = mask_of(g, x0), cx1 = mask_of(g, x1);
    const int32_t cy0 = mask_of(g, y0), cy1 = mask_of(g, y1);
    for (int32_t cy = cy0; cy <= cy1; cy++)
        for (int32_t cx = cx0; cx <= cx1; cx++)
        {
            const int marked =
                g->active[(size_t)cy * (size_t)g->aside + (size_t)cx] != 0;
            if (marked != every)
                return marked;
        }
    return every;
}

/* Cells cb = {x0, y0, x1, y1} of the box of edge a-b. */
static void edge_cells(const ringgrid *g, wm_pt a, wm_pt b, int32_t *cb)
{
    cb[0] = cell_of(g, a.x < b.x ? a.x : b.x);
    cb[1] = cell_of(g, a.y < b.y ? a.y : b.y);
    cb[2] = cell_of(g, a.x > b.x ? a.x : b.x);
    cb[3] = cell_of(g, a.y > b.y ? a.y : b.y);
}

/* fill_ringgrid registers the edges of g->r in the cells of g->active (or
 * all), looking at them in runs of CHUNK along a ring: a run whose box has
 * no registered cell is passed over whole. */
#define CHUNK 64

static wm_status fill_ringgrid(ringgrid *g)
{
    const wm_rings *r = g->r;
    wm_cells_reset(&g->cells, g->cells.side); /* the grid's side stays */
    for (size_t ri = 0; ri < r->nrings; ri++)
    {
        const size_t b0 = r->start[ri], e = r->start[ri + 1];
        for (size_t k0 = b0; k0 < e; k0 += CHUNK)
        {
            const size_t k1 = k0 + CHUNK < e ? k0 + CHUNK : e;
            if (g->active)
            { /* the run's box, its edges' ends */
                const wm_pt z = r->pts[k1 < e ? k1 : b0];
                int32_t x0 = z.x, y0 = z.y, x1 = z.x, y1 = z.y;
                for (size_t k = k0; k < k1; k++)
                {
                    const wm_pt p = r->pts[k];
                    x0 = p.x < x0 ? p.x : x0;
                    x1 = p.x > x1 ? p.x : x1;
                    y0 = p.y < y0 ? p.y : y0;
                    y1 = p.y > y1 ? p.y : y1;
                }
                if (!box_active(g, x0, y0, x1, y1, 0))
                    continue;
            }
            for (size_t k = k0; k < k1; k++)
            {
                int32_t cb[4];
                edge_cells(g, r->pts[k], r->pts[k + 1 < e ? k + 1 : b0], cb);
                for (int32_t cy = cb[1]; cy <= cb[3]; cy++)
                    for (int32_t cx = cb[0]; cx <= cb[2]; cx++)
                        if ((!g->active ||
                             g->active[(size_t)(cy * g->cell / RCELL) *
                                           (size_t)g->aside +
                                       (size_t)(cx * g->cell / RCELL)]) &&
                            !wm_cells_add(&g->cells, cx, cy, (uint32_t)k))
                            return WM_ERR_NOMEM;
            }
        }
    }
    return wm_cells_index(&g->cells);
}

/* The grid of rings r over a block of side S: every edge registered, or
 * (active != NULL, owned by the grid from here on) those in its cells. */
static wm_status build_ringgrid(ringgrid *g, const wm_rings *r, int32_t S,
                                int32_t cell, uint8_t *active)
{
    g->r = r;
    g->cell = cell;
    g->aside = S / RCELL + 1;
    wm_cells_reset(&g->cells, S / cell + 1);
    g->active = active;
    g->ring_of = malloc((r->npts + 1) * sizeof *g->ring_of);
    if (!g->ring_of || r->npts >= UINT32_MAX)
        return WM_ERR_NOMEM;
    for (size_t ri = 0; ri < r->nrings; ri++)
        for (size_t k = r->start[ri]; k < r->start[ri + 1]; k++)
            g->ring_of[k] = (uint32_t)ri;
    return fill_ringgrid(g);
}

static void free_ringgrid(ringgrid *g)
{
    wm_cells_free(&g->cells);
    free(g->ring_of);
    free(g->active);
}

/* Calls fn(edge k) for each edge registered in cells touching the box
 * [x0,x1]x[y0,y1] (an edge may be visited more than once), first
 * registering every edge if the box reaches a cell outside g->active.
 * Returns 0 as soon as fn does, -1 out of memory, else 1. */
static int visit_edges(ringgrid *g, int32_t x0, int32_t y0, int32_t x1,
                       int32_t y1, int (*fn)(void *, size_t), void *arg)
{
    if (!box_active(g, x0, y0, x1, y1, 1))
    {
        free(g->active);
        g->active = NULL;
        if (fill_ringgrid(g) != WM_OK)
            return -1;
    }
    const int32_t cx0 = cell_of(g, x0), cx1 = cell_of(g, x1);
    const int32_t cy0 = cell_of(g, y0), cy1 = cell_of(g, y1);
    for (int32_t cy = cy0; cy <= cy1; cy++)
    {
        size_t b, e;
        wm_cells_row(&g->cells, cy, cx0, cx1, &b, &e);
        for (size_t i = b; i < e; i++)
            if (!fn(arg, g->cells.item[i]))
                return 0;
    }
    return 1;
}

/* How many of the nearest edges a corner may split (with their
 * neighbours): the nearest may belong to another part of the rings (the
 * far bank of a narrow river beside a wedge's tip; at a hairpin's tip the
 * far banks of both arms, two edges each, were all nearer than the edge
 * that cut the tip). */
#define NEAREST 8
/* ... then the nearest edge of each of up to RINGS rings in reach: four
 * lake pieces pointing their tips at one point 0.5 pixel apart, the next
 * pieces' rings near one tip (lattice staircases of edges a few units
 * long) took all eight, and that tip stayed cut 0.52 pixel short (mosaic
 * seed 175119 at 3 m; a cap per ring instead lost a hairpin's tip, whose
 * far banks are of its own ring: wedge seed 101159 at 2 m) */
#define RINGS 4

/* nearest edges search state: best[0] <= best[1] <= ..., n of them; and
 * per ring (up to RINGS of them, the nearest rings), its nearest edge */
typedef struct
{
    const ringgrid *g;
    double x, y, best[NEAREST];
    size_t edge[NEAREST];
    int n;
    int32_t S; /* the block square's side: its edges are never split */
    double rbest[RINGS];
    size_t redge[RINGS];
    uint32_t ring[RINGS];
    int nr;
} nearest;

/* Whether edge a -> b lies on the block square [0, S]^2 (never split:
 * seams stay exact). */
static int on_square(wm_pt a, wm_pt b, int32_t S)
{
    return (a.x == b.x && (a.x == 0 || a.x == S)) ||
           (a.y == b.y && (a.y == 0 || a.y == S));
}

/* Distance from (x, y) to the ring edge a -> b. */
static double edge_dist(wm_pt a, wm_pt b, double x, double y)
{
    const double dx = b.x - a.x, dy = b.y - a.y, l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / l2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    const double ex = x - (a.x + t * dx), ey = y - (a.y + t * dy);
    return sqrt(ex * ex + ey * ey);
}

/* Keeps edge k, at distance d, as its ring's nearest when it is nearer
 * than that ring's (or the ring is new and one of the RINGS nearest). */
static void ring_nearest(nearest *n, size_t k, double d)
{
    const uint32_t ring = n->g->ring_of[k];
    int j = 0, far = 0;
    while (j < n->nr && n->ring[j] != ring)
        j++;
    if (j == n->nr && n->nr == RINGS)
    {
        for (int i = 1; i < n->nr; i++)
            far = n->rbest[i] > n->rbest[far] ? i : far;
        if (d >= n->rbest[far])
            return;
        j = far;
    }
    else if (j < n->nr &&
             (d > n->rbest[j] || (d == n->rbest[j] && k >= n->redge[j])))
        return;
    n->nr += j == n->nr;
    n->ring[j] = ring;
    n->rbest[j] = d;
    n->redge[j] = k;
}

/* Forgets the rings whose nearest edge is farther than R. */
static void drop_rings_beyond(nearest *n, double R)
{
    int m = 0;
    for (int r = 0; r < n->nr; r++)
        if (n->rbest[r] <= R)
        {
            n->rbest[m] = n->rbest[r];
            n->redge[m] = n->redge[r];
            n->ring[m++] = n->ring[r];
        }
    n->nr = m;
}

static int nearest_fn(void *arg, size_t k)
{
    nearest *n = arg;
    const wm_rings *r = n->g->r;
    const wm_pt a = r->pts[k], b = r->pts[succ(r, n->g->ring_of, k)];
    if (on_square(a, b, n->S))
        return 1;
    const double d = edge_dist(a, b, n->x, n->y);
    ring_nearest(n, k, d);
    int i = n->n;
    for (int j = 0; j < n->n; j++)
        if (n->edge[j] == k)
            return 1; /* met again (registered in several cells) */
    while (i > 0 &&
           (d < n->best[i - 1] || (d == n->best[i - 1] && k < n->edge[i - 1])))
        i--;
    if (i == NEAREST)
        return 1;
    const int last = n->n < NEAREST ? n->n : NEAREST - 1;
    for (int j = last; j > i; j--)
    {
        n->best[j] = n->best[j - 1];
        n->edge[j] = n->edge[j - 1];
    }
    n->best[i] = d;
    n->edge[i] = k;
    n->n = last + 1;
    return 1;
}

/* validity check state for inserting c into edge (pa, pb) */
typedef struct
{
    const ringgrid *g;
    size_t ka, kb; /* vertex indices of the edge's ends */
    wm_pt a, b, c;
    int ok;
} check;

static int check_fn(void *arg, size_t k)
{
    check *ck = arg;
    const wm_rings *r = ck->g->r;
    const size_t k2 = succ(r, ck->g->ring_of, k);
    const wm_pt p = r->pts[k], q = r->pts[k2];
    if (k == ck->ka)
        return 1; /* the edge being split */
    /* a ring vertex in the closed triangle (a, c, b), other than a, b */
    if (k != ck->kb)
    {
        const int o1 = wm_orient(ck->a, ck->c, p),
                  o2 = wm_orient(ck->c, ck->b, p);
        const int o3 = wm_orient(ck->b, ck->a, p);
        if ((o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0))
        {
            ck->ok = 0;
            return 0;
        }
    }
    /* the new edges a-c and c-b against edge p-q */
    const wm_pt ne[2][2] = {{ck->a, ck->c}, {ck->c, ck->b}};
    for (int e = 0; e < 2; e++)
    {
        const int shares_a = e == 0 && (k2 == ck->ka); /* q == a */
        const int shares_b = e == 1 && (k == ck->kb);  /* p == b */
        if (shares_a || shares_b)
        {
            /* adjacent edge: may share only the common vertex */
            const wm_pt other = shares_a ? p : q;
            const wm_pt common = shares_a ? ck->a : ck->b;
            if (wm_on_segment(common, ck->c, other) ||
                wm_on_segment(common, other, ck->c))
            {
                ck->ok = 0;
                return 0;
            }
            continue;
        }
        if (wm_segments_meet(ne[e][0], ne[e][1], p, q))
        {
            ck->ok = 0;
            return 0;
        }
    }
    return 1;
}

/* 1 when c may be inserted into edge ka (to its successor) of the current
 * rings (see the file comment, step 4), 0 when not, -1 out of memory. */
static int can_insert(wm_probe *in, ringgrid *g, size_t ka, wm_pt c, int32_t S,
                      const uint8_t *split, const insertion *ins, size_t nins)
{
    const wm_rings *rings = g->r;
    const size_t kb = succ(rings, g->ring_of, ka);
    const wm_pt a = rings->pts[ka], b = rings->pts[kb];
    if (split[ka] || wm_orient(a, b, c) == 0)
        return 0;
    if (on_square(a, b, S))
        return 0;
    check ck = {g, ka, kb, a, b, c, 1};
    const int32_t x0 = a.x < b.x ? a.x : b.x, x1 = a.x > b.x ? a.x : b.x;
    const int32_t y0 = a.y < b.y ? a.y : b.y, y1 = a.y > b.y ? a.y : b.y;
    if (visit_edges(g, (x0 < c.x ? x0 : c.x) - 1, (y0 < c.y ? y0 : c.y) - 1,
                    (x1 > c.x ? x1 : c.x) + 1, (y1 > c.y ? y1 : c.y) + 1,
                    check_fn, &ck) < 0)
        return -1;
    /* and against corners inserted earlier in this pass */
    for (size_t j = 0; ck.ok && j < nins; j++)
    {
        const insertion *o = &ins[j];
        const wm_pt oa = rings->pts[o->seg];
        const wm_pt ob = rings->pts[succ(rings, g->ring_of, o->seg)];
        const wm_pt ne[2][2] = {{a, c}, {c, b}};
        const wm_pt oe[2][2] = {{oa, o->p}, {o->p, ob}};
        for (int e = 0; ck.ok && e < 2; e++)
            for (int f = 0; ck.ok && f < 2; f++)
                if (wm_segments_meet(ne[e][0], ne[e][1], oe[f][0], oe[f][1]))
                    ck.ok = 0;
    }
    return ck.ok && follows_boundary(in, a, c, b);
}

/* Side of the cells that tell which candidates a later pass retries (64
 * pixels, in lattice units). A candidate's outcome depends on the rings
 * near it: its nearest edge is within 16 pixels, and the edges it may split
 * are that one and its neighbours, whose ends lie within 16 pixels plus
 * twice the longest edge (contour edges are under 1.5 pixels; an inserted
 * corner makes edges up to about 19). An insertion changes the rings only
 * inside the triangle it adds or cuts. So a candidate whose 3 x 3 cells
 * hold no corner inserted in the previous pass meets the same rings as
 * then, except where edges grew long over several passes; skipping it can
 * then only miss a corner, never break the rings (every insertion is
 * checked with exact predicates when it is made). On the test scenes and
 * L3 the output is byte-identical to retrying every candidate. */
#define HOT_CELL (64 * WM_Q)

static uint64_t hot_key(wm_pt p, int dx, int dy)
{
    return ckey(p.x / HOT_CELL + dx, p.y / HOT_CELL + dy);
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Whether p is in a cell of `hot` (sorted keys of the cells next to the
 * corners inserted by the previous pass). */
static int near_hot(const uint64_t *hot, size_t nhot, wm_pt p)
{
    const uint64_t k = hot_key(p, 0, 0);
    return bsearch(&k, hot, nhot, sizeof *hot, cmp_u64) != NULL;
}

/* Marks the ring grid cells [x0, x1] x [y0, y1] (clamped) in a. */
static void mark_cells(uint8_t *a, int32_t side, int32_t x0, int32_t y0,
                       int32_t x1, int32_t y1)
{
    x0 = x0 < 0 ? 0 : x0;
    y0 = y0 < 0 ? 0 : y0;
    x1 = x1 >= side ? side - 1 : x1;
    y1 = y1 >= side ? side - 1 : y1;
    for (int32_t cy = y0; cy <= y1; cy++)
        if (x0 <= x1)
            memset(a + (size_t)cy * (size_t)side + (size_t)x0, 1,
                   (size_t)(x1 - x0 + 1));
}

/* The ring grid's active mask a pass needs (owned by the caller): around
 * the corners cs[todo[0 .. ntodo)] it tries. Searches reach
 * WM_CREASE_REACH (one mask cell) around a candidate and the edges it may
 * split a little farther: two cells of margin cover that (a query beyond
 * them completes the grid). NULL when out of memory. */
static uint8_t *pass_cells(const corner *cs, const size_t *todo, size_t ntodo,
                           int32_t S)
{
    const int32_t side = S / RCELL + 1;
    uint8_t *a = calloc((size_t)side * (size_t)side, 1);
    if (!a)
        return NULL;
    for (size_t i = 0; i < ntodo; i++)
    {
        const wm_pt c = cs[todo[i]].c;
        const int32_t cx = c.x / RCELL, cy = c.y / RCELL;
        mark_cells(a, side, cx - 2, cy - 2, cx + 2, cy + 2);
    }
    return a;
}

/* An edge as a key: its ends, the lower first. */
typedef struct
{
    wm_pt lo, hi;
} edge_key;

static edge_key make_key(wm_pt a, wm_pt b)
{
    const int a_first = wm_pt_cmp(a, b) < 0;
    const edge_key k = {a_first ? a : b, a_first ? b : a};
    return k;
}

static int cmp_key(const void *a, const void *b)
{
    const edge_key *x = a, *y = b;
    const int c = wm_pt_cmp(x->lo, y->lo);
    return c ? c : wm_pt_cmp(x->hi, y->hi);
}

/* Edge k of the rings or a neighbour of it that may take corner c: 1 and
 * *ka set, 0 none, -1 out of memory. */
static int try_edge(wm_probe *in, ringgrid *g, size_t k, wm_pt c, int32_t S,
                    const uint8_t *split, const insertion *ins, size_t nins,
                    size_t *ka)
{
    const wm_rings *rings = g->r;
    const size_t tries[3] = {k, succ(rings, g->ring_of, k),
                             pred(rings, g->ring_of, k)};
    for (int t = 0; t < 3; t++)
    {
        const int ok = can_insert(in, g, tries[t], c, S, split, ins, nins);
        if (ok)
        {
            *ka = tries[t];
            return ok;
        }
    }
    return 0;
}

/* Sets *ka to the first of the nearest edges nr, then of the rings'
 * nearest (each, else one of its neighbours: a truncated tip ends in a
 * vertex, and either edge at it may be the one to split) into which c may
 * be inserted, or SIZE_MAX; returns -1 when out of memory, else 0. */
static int first_insertable(wm_probe *in, ringgrid *g, const nearest *nr,
                            wm_pt c, const uint8_t *split, const insertion *ins,
                            size_t nins, size_t *ka)
{
    *ka = SIZE_MAX;
    for (int e = 0; e < nr->n; e++)
    {
        const int ok =
            try_edge(in, g, nr->edge[e], c, nr->S, split, ins, nins, ka);
        if (ok)
            return ok < 0 ? -1 : 0;
    }
    /* then each ring's nearest, unless tried above */
    for (int r = 0; r < nr->nr; r++)
    {
        int seen = 0;
        for (int e = 0; e < nr->n; e++)
            seen |= nr->edge[e] == nr->redge[r];
        const int ok = seen ? 0
                            : try_edge(in, g, nr->redge[r], c, nr->S, split,
                                       ins, nins, ka);
        if (ok)
            return ok < 0 ? -1 : 0;
    }
    return 0;
}

/* The insertions of a pass, and the ring points they split. */
typedef struct
{
    insertion *ins;
    size_t n, cap;
    uint8_t *split; /* per ring point: its edge (or a neighbour's) taken */
} pass_ins;

/* Tries open corner cd against the rings in grid g: within a quarter pixel
 * of an edge it is close (that edge its witness); buried under another
 * input it is done; else it is inserted into the first nearest edge (within
 * a pixel, else WM_CREASE_REACH) that may take it, if any. -1 when out of
 * memory, else 0. */
static int place_corner(wm_probe *in, ringgrid *g, corner *cd, pass_ins *pi)
{
    const wm_rings *rings = g->r;
    const int32_t S = in->s->n * WM_Q;
    const wm_pt c = cd->c;
    /* nearest edges: within a quarter pixel first (most corners have
     * one; every edge that near is visited, so the nearest is the nearest
     * of all) */
    nearest nr = {g, c.x, c.y, {0}, {0}, 0, S, {0}, {0}, {0}, 0};
    int32_t R = WM_Q / 4;
    if (visit_edges(g, c.x - R, c.y - R, c.x + R, c.y + R, nearest_fn, &nr) < 0)
        return -1;
    if (nr.n > 0 && nr.best[0] <= WM_Q / 4.0)
    {
        cd->state = C_CLOSE;
        cd->e0 = rings->pts[nr.edge[0]];
        cd->e1 = rings->pts[succ(rings, g->ring_of, nr.edge[0])];
        return 0;
    }
    /* a corner of the union, not one buried under another input */
    if (fabs(wm_probe_distance(in, c.x, c.y, 4.0 * WM_Q)) > 1.0)
    {
        cd->state = C_DONE;
        return 0;
    }
    /* the nearest edges within a pixel, then (none taking the corner)
     * within WM_CREASE_REACH */
    R = WM_Q;
    nr.n = nr.nr = 0;
    if (visit_edges(g, c.x - R, c.y - R, c.x + R, c.y + R, nearest_fn, &nr) < 0)
        return -1;
    size_t ka = SIZE_MAX;
    for (int pass = nr.n ? 0 : 1; pass < 2 && ka == SIZE_MAX; pass++)
    {
        if (pass == 1)
        {
            R = WM_CREASE_REACH;
            nr.n = nr.nr = 0;
            if (visit_edges(g, c.x - R, c.y - R, c.x + R, c.y + R, nearest_fn,
                            &nr) < 0)
                return -1;
        }
        while (nr.n > 0 && nr.best[nr.n - 1] > R)
            nr.n--;
        drop_rings_beyond(&nr, R);
        if (first_insertable(in, g, &nr, c, pi->split, pi->ins, pi->n, &ka) < 0)
            return -1;
    }
    if (ka == SIZE_MAX)
        return 0;
    const insertion x = {c, ka};
    if (!wm_push((void **)&pi->ins, &pi->n, &pi->cap, &x, sizeof x))
        return -1;
    cd->state = C_DONE;
    pi->split[ka] = 1;
    pi->split[pred(rings, g->ring_of, ka)] = 1; /* neighbours stay as they */
    pi->split[succ(rings, g->ring_of, ka)] = 1; /* are: one corner per run */
    return 0;
}

/* The sorted, distinct keys of the 3 x 3 cells around each insertion, into
 * *hot (*nhot; caller frees); 0 when out of memory. */
static int hot_cells(const insertion *ins, size_t nins, uint64_t **hot,
                     size_t *nhot)
{
    *hot = malloc(9 * nins * sizeof **hot);
    if (!*hot)
        return 0;
    size_t nh = 0;
    for (size_t i = 0; i < nins; i++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++)
                (*hot)[nh++] = hot_key(ins[i].p, dx, dy);
    qsort(*hot, nh, sizeof **hot, cmp_u64);
    *nhot = 0;
    for (size_t i = 0; i < nh; i++)
        if (i == 0 || (*hot)[i] != (*hot)[i - 1])
            (*hot)[(*nhot)++] = (*hot)[i];
    return 1;
}

/* The close corners whose witness edge an insertion splits are open
 * again; 0 when out of memory. */
static int reopen_cut(const ringgrid *g, const insertion *ins, size_t nins,
                      corner *cs, size_t ncs)
{
    const wm_rings *rings = g->r;
    edge_key *cut = malloc(nins * sizeof *cut);
    if (!cut)
        return 0;
    for (size_t i = 0; i < nins; i++)
        cut[i] = make_key(rings->pts[ins[i].seg],
                          rings->pts[succ(rings, g->ring_of, ins[i].seg)]);
    qsort(cut, nins, sizeof *cut, cmp_key);
    for (size_t i = 0; i < ncs; i++)
    {
        if (cs[i].state != C_CLOSE)
            continue;
        const edge_key k = make_key(cs[i].e0, cs[i].e1);
        if (bsearch(&k, cut, nins, sizeof *cut, cmp_key))
            cs[i].state = C_OPEN;
    }
    free(cut);
    return 1;
}

/* Inserts the points in place (ins sorted here): new ring starts, then the
 * points moved up from the back; 0 when out of memory. */
static int insert_points(wm_rings *rings, insertion *ins, size_t nins)
{
    qsort(ins, nins, sizeof *ins, cmp_ins);
    if (!wm_grow((void **)&rings->pts, &rings->pts_cap, rings->npts + nins,
                 sizeof *rings->pts))
        return 0;
    for (size_t ri = 1, j = 0; ri <= rings->nrings; ri++)
    {
        while (j < nins && ins[j].seg < rings->start[ri])
            j++;
        rings->start[ri] += j;
    }
    for (size_t j = nins, src = rings->npts, dst = rings->npts + nins; j-- > 0;)
    {
        const size_t run = src - (ins[j].seg + 1);
        src -= run;
        dst -= run;
        memmove(rings->pts + dst, rings->pts + src, run * sizeof *rings->pts);
        rings->pts[--dst] = ins[j].p;
    }
    rings->npts += nins;
    return 1;
}

/* One pass: tries the open corners against the current rings (with hot,
 * the sorted keys of the hot cells next to the corners the previous pass
 * inserted, only those in them), updates their states and rebuilds the
 * rings with the accepted corners; *ninserted says how many. *newhot
 * receives this pass's hot cells (*nnewhot keys, caller frees). Returns
 * WM_ERR_CANCELLED when ctx asks to stop (checked every 256 corners). */
static wm_status insert_pass(wm_probe *in, wm_rings *rings, corner *cs,
                             size_t ncs, const uint64_t *hot, size_t nhot,
                             uint64_t **newhot, size_t *nnewhot,
                             size_t *ninserted, const wm_ctx *ctx)
{
    const int32_t S = in->s->n * WM_Q;
    *ninserted = 0;
    size_t ntodo = 0;
    size_t *todo = malloc((ncs + 1) * sizeof *todo);
    if (!todo)
        return WM_ERR_NOMEM;
    for (size_t i = 0; i < ncs; i++)
        if (cs[i].state == C_OPEN && (!hot || near_hot(hot, nhot, cs[i].c)))
            todo[ntodo++] = i;
    if (ntodo == 0)
    {
        free(todo);
        return WM_OK;
    }
    pass_ins pi = {NULL, 0, 0, NULL};
    ringgrid g;
    memset(&g, 0, sizeof g);
    /* cells down to an eighth of a pixel where the rings are dense: at
     * coarse pixels, where sub-pixel rivers give them many points per
     * pixel, 16-pixel cells made the nearest-edge searches the run's main
     * cost (Andorra at 50 m pixels); which edges a query reports does not
     * depend on the cell */
    const int32_t cell = wm_cells_fit(rings->npts, S, RCELL, WM_Q / 8);
    uint8_t *active = pass_cells(cs, todo, ntodo, S);
    /* the grid owns active */
    int ok = active && build_ringgrid(&g, rings, S, cell, active) == WM_OK &&
             (pi.split = calloc(rings->npts + 1, 1)) != NULL;
    int cancelled = 0;
    for (size_t q = 0; ok && q < ntodo; q++)
    {
        if (q % 256 == 0 && (cancelled = wm_cancelled(ctx)) != 0)
            break;
        ok = place_corner(in, &g, &cs[todo[q]], &pi) == 0;
    }
    if (ok && !cancelled && pi.n > 0)
    {
        ok = hot_cells(pi.ins, pi.n, newhot, nnewhot) &&
             reopen_cut(&g, pi.ins, pi.n, cs, ncs) &&
             insert_points(rings, pi.ins, pi.n);
        if (ok)
            *ninserted = pi.n;
    }
    free(pi.ins);
    free(pi.split);
    free(todo);
    free_ringgrid(&g);
    return cancelled ? WM_ERR_CANCELLED : ok ? WM_OK : WM_ERR_NOMEM;
}

wm_status wm_crease_recover(const wm_scene *s, const wm_field *f, int64_t bx,
                            int64_t by, wm_rings *rings, const wm_ctx *ctx)
{
    wm_probe in;
    if (wm_probe_init(&in, s, bx, by) != WM_OK)
        return wm_fail(ctx, WM_ERR_NOMEM, "out of memory recovering corners");
    const wm_status st = wm_crease_recover_probed(&in, f, rings, ctx);
    wm_probe_free(&in);
    return st;
}

wm_status wm_crease_recover_probed(wm_probe *probe, const wm_field *f,
                                   wm_rings *rings, const wm_ctx *ctx)
{
    wm_probe *in = probe;
    if (rings->nrings == 0)
        return WM_OK;
    wm_status st = wm_corners_find(in, f, ctx);
    if (st != WM_OK || in->ncorner == 0)
        return st;
    const wm_pt *cand = in->corner;
    const size_t ncand = in->ncorner;
    /* open unless within a quarter pixel of the contour edge of their own
     * cell (a ring edge: the nearest edge search would find it or a nearer
     * one and skip them); not where the contour may have taken exact
     * crossings or rebuilt the cell (probe->rebuilt), whose ring edge may
     * lie elsewhere (wedge tips were left 0.62 and 0.64 pixel from it so) */
    corner *cs = malloc(ncand * sizeof *cs);
    if (!cs)
        goto nomem;
    for (size_t i = 0; i < ncand; i++)
    {
        if (i + PREFETCH < ncand)
        {
            const wm_pt n = cand[i + PREFETCH];
            wm_field_prefetch(f, n.x / WM_Q, n.y / WM_Q);
            wm_field_prefetch(f, n.x / WM_Q, n.y / WM_Q + 1);
        }
        const wm_pt c = cand[i];
        wm_pt a, b;
        const int close =
            wm_contour_cell_edge(f, c.x / WM_Q, c.y / WM_Q, &a, &b) &&
            edge_dist(a, b, c.x, c.y) <= WM_Q / 4.0 &&
            !wm_probe_rebuilt(in, f, c.x / WM_Q, c.y / WM_Q);
        cs[i] =
            (corner){c, close ? a : c, close ? b : c, close ? C_CLOSE : C_OPEN};
    }

    /* 3-4. insertion passes: a corner next to one just inserted waits for
     * the next pass, which sees the new edges */
    uint64_t *hot = NULL;
    size_t nhot = 0;
    for (int pass = 0; pass < 4; pass++)
    {
        if (wm_cancelled(ctx))
        {
            free(hot);
            st = wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
            goto cleanup;
        }
        size_t n = 0, nnext = 0;
        uint64_t *next = NULL;
        st = insert_pass(in, rings, cs, ncand, pass ? hot : NULL, nhot, &next,
                         &nnext, &n, ctx);
        free(hot);
        hot = next;
        nhot = nnext;
        if (st != WM_OK)
        {
            free(hot);
            if (st == WM_ERR_CANCELLED)
            {
                st = wm_fail(ctx, st, "cancelled");
                goto cleanup;
            }
            goto nomem;
        }
        if (n == 0)
            break;
    }
    free(hot);
    goto cleanup;
nomem:
    st = wm_fail(ctx, WM_ERR_NOMEM, "out of memory recovering corners");
cleanup:
    free(cs);
    return st;
}
