/*
 * holes.c - ring nesting: the smallest ring strictly enclosing each ring.
 *
 * Method (ray shooting, i.e. point location by the first edge hit): for
 * every ring R take its lowest-leftmost vertex q (min y, then min x) and
 * shoot a ray from q towards -x. The first edge of another ring met by the
 * ray belongs to a ring S, and the point just right of the hit lies on the
 * same side of every ring other than R as q does. If that point is on S's
 * interior side (left of the edge for a counter-clockwise S, right for a
 * clockwise S), S is the innermost ring enclosing R; otherwise R's innermost
 * encloser is S's own encloser. The dependency R -> S always goes to a ring
 * whose q is smaller in (y, x) order, so the chain is acyclic for valid
 * input; it is resolved with an explicit stack and memo (cycles, possible
 * only for invalid input, resolve to -1).
 *
 * Robustness: exact integer arithmetic only, no epsilon. The ray is taken
 * at height q.y + eps (symbolic perturbation): an edge counts when
 * min(y) <= q.y < max(y) (the half-open rule, so a vertex on the ray is
 * counted once and horizontal edges never), crossings are compared as
 * rationals N / D with __int128 products, and two edges crossing at the
 * same point (adjacent edges of one ring at a vertex on the ray) are ordered
 * by their slope dx/dy, i.e. by where they are at q.y + eps. q itself is
 * never on another ring (rings are disjoint), so the perturbation changes no
 * containment.
 *
 * Acceleration: the queries sorted by y, and a bitmap of the lattice rows
 * holding one. Every non-horizontal edge looks up the rows of its y range
 * [min y, max y) in the bitmap (a few words for a contour edge) and, only
 * when one holds a query, offers itself to those queries (binary search
 * into the sorted ones). One pass over the edges, no per-edge allocation,
 * no grid; an edge meets only the queries whose ray it crosses.
 *
 * Complexity: O(n + rings log rings + (ymax - ymin) / 64 + edge-query
 * crossings) time, O(rings + (ymax - ymin) / 64) memory besides the input.
 *
 * References: the half-open crossing rule of the even-odd test (E. Haines,
 * "Point in Polygon Strategies", Graphics Gems IV, 1994); symbolic
 * perturbation (Edelsbrunner & Muecke, "Simulation of Simplicity", ACM TOG
 * 9(1), 1990).
 */
#include "holes.h"
#include "lattice.h"

#include <stdlib.h>

/* A query: ring r's lowest-leftmost vertex (x, y), and the edge its ray
 * first meets so far: crossing at x = N / D, slope dx / D, on ring S, going
 * up or down. */
typedef struct
{
    int32_t x, y;
    uint32_t r, S;
    int found, upward;
    int64_t N, D, dx;
} h_query;

static int cmp_query(const void *a, const void *b)
{
    const h_query *p = a, *q = b;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return (p->r > q->r) - (p->r < q->r);
}

/* Whether a bit of w[a .. b] (bit indices, a <= b) is set. */
static int h_any(const uint64_t *w, int64_t a, int64_t b)
{
    const int64_t wa = a >> 6, wb = b >> 6;
    const uint64_t ma = ~UINT64_C(0) << (a & 63);
    const uint64_t mb = ~UINT64_C(0) >> (63 - (b & 63));
    if (wa == wb)
        return (w[wa] & ma & mb) != 0;
    if (w[wa] & ma)
        return 1;
    for (int64_t k = wa + 1; k < wb; k++)
        if (w[k])
            return 1;
    return (w[wb] & mb) != 0;
}

/* Offers edge lo -> hi (lo.y <= q.y < hi.y, ring S, going up or not) to
 * query q: kept when it crosses the ray strictly left of q and right of
 * the best so far (a tie, two edges through one point, goes to the larger
 * dx / dy: it is further right at q.y + eps; equal slopes too means
 * overlapping edges, invalid rings, where the first edge offered stays). */
static void h_offer(h_query *q, wm_pt lo, wm_pt hi, uint32_t S, int upward)
{
    const int64_t D = (int64_t)hi.y - lo.y, dx = (int64_t)hi.x - lo.x;
    const int64_t N = (int64_t)lo.x * D + dx * ((int64_t)q->y - lo.y);
    if (N >= (int64_t)q->x * D)
        return; /* not strictly left of q */
    if (q->found)
    {
        const wm_i128 l = (wm_i128)N * q->D, rr = (wm_i128)q->N * D;
        if (l < rr || (l == rr && dx * q->D <= q->dx * D))
            return;
    }
    q->found = 1;
    q->N = N;
    q->D = D;
    q->dx = dx;
    q->S = S;
    q->upward = upward;
}

/* Step 1: per ring, its query (lowest-leftmost vertex) into qs (*nq; an
 * empty ring has none) and its orientation; hit and enclosing start at
 * -1. */
static void make_queries(const wm_rings *rings, h_query *qs, size_t *nq,
                         int32_t *hit, int32_t *enclosing, unsigned char *ccw)
{
    const wm_pt *P = rings->pts;
    *nq = 0;
    for (size_t r = 0; r < rings->nrings; r++)
    {
        const size_t b = rings->start[r], e = rings->start[r + 1];
        hit[r] = -1;
        enclosing[r] = -1;
        if (b == e)
            continue;
        size_t m = b;
        for (size_t i = b + 1; i < e; i++)
            if (P[i].y < P[m].y || (P[i].y == P[m].y && P[i].x < P[m].x))
                m = i;
        const h_query q = {P[m].x, P[m].y, (uint32_t)r, 0, 0, 0, 0, 0, 0};
        qs[(*nq)++] = q;
        ccw[r] = wm_ring_area2(P + b, e - b) > 0;
    }
}

/* Step 2: every edge offers itself to the queries (sorted by y, their rows
 * set in the bitmap rows from y0 to y1) whose ray it crosses. */
static void offer_edges(const wm_rings *rings, h_query *qs, size_t nq,
                        const uint64_t *rows, int64_t y0, int64_t y1)
{
    const wm_pt *P = rings->pts;
    for (size_t r = 0; r < rings->nrings; r++)
    {
        const size_t b = rings->start[r], e = rings->start[r + 1];
        for (size_t i = b; i < e; i++)
        {
            const wm_pt p = P[i], q = P[i + 1 < e ? i + 1 : b];
            if (p.y == q.y)
                continue;
            const int upward = q.y > p.y;
            const wm_pt lo = upward ? p : q, hi = upward ? q : p;
            const int64_t a = lo.y > y0 ? lo.y : y0;
            const int64_t z = (int64_t)hi.y - 1 < y1 ? (int64_t)hi.y - 1 : y1;
            if (a > z || !h_any(rows, a - y0, z - y0))
                continue;
            size_t k0 = 0, k1 = nq; /* the first query at y >= a */
            while (k0 < k1)
            {
                const size_t mid = k0 + (k1 - k0) / 2;
                if (qs[mid].y < a)
                    k0 = mid + 1;
                else
                    k1 = mid;
            }
            for (size_t k = k0; k < nq && qs[k].y <= z; k++)
                if (qs[k].r != r)
                    h_offer(&qs[k], lo, hi, (uint32_t)r, upward);
        }
    }
}

/* Step 3: enc(r) = -1 | hit | enc(hit), iteratively with a memo. state: 0
 * unknown, 1 on the stack, 2 done. */
static void resolve(size_t nr, const int32_t *hit, const unsigned char *inside,
                    unsigned char *state, uint32_t *stack, int32_t *enclosing)
{
    for (size_t r0 = 0; r0 < nr; r0++)
    {
        size_t sp = 0;
        size_t cur = r0;
        while (state[cur] == 0)
        {
            state[cur] = 1;
            stack[sp++] = (uint32_t)cur;
            if (hit[cur] < 0 || inside[cur])
                break;
            cur = (size_t)hit[cur];
        }
        while (sp > 0)
        {
            const size_t x = stack[--sp];
            if (hit[x] < 0)
                enclosing[x] = -1;
            else if (inside[x])
                enclosing[x] = hit[x];
            else if (state[hit[x]] == 2)
                enclosing[x] = enclosing[hit[x]];
            else
                enclosing[x] = -1; /* a cycle: only for invalid input */
            state[x] = 2;
        }
    }
}

wm_status wm_holes_nesting(const wm_rings *rings, int32_t *enclosing,
                           const wm_ctx *ctx)
{
    const size_t nr = rings->nrings;
    if (nr == 0)
        return WM_OK;
    if (nr > (size_t)INT32_MAX || rings->npts >= (size_t)UINT32_MAX)
        return wm_fail(ctx, WM_ERR_NOMEM, "holes: too many rings or points");
    wm_status st = WM_OK;
    h_query *qs = malloc(nr * sizeof *qs);
    int32_t *hit = malloc(nr * sizeof *hit);
    unsigned char *inside = calloc(nr, 1), *ccw = calloc(nr, 1);
    unsigned char *state = calloc(nr, 1);
    uint32_t *stack = malloc(nr * sizeof *stack);
    uint64_t *rows = NULL;
    size_t nq = 0;
    if (!qs || !hit || !inside || !ccw || !state || !stack)
    {
        st = wm_fail(ctx, WM_ERR_NOMEM, "holes: out of memory");
        goto cleanup;
    }
    make_queries(rings, qs, &nq, hit, enclosing, ccw);
    if (nq == 0)
        goto cleanup;
    qsort(qs, nq, sizeof *qs, cmp_query);
    const int64_t y0 = qs[0].y, y1 = qs[nq - 1].y;
    rows = calloc((size_t)((y1 - y0) >> 6) + 1, sizeof *rows);
    if (!rows)
    {
        st = wm_fail(ctx, WM_ERR_NOMEM, "holes: out of memory (rows)");
        goto cleanup;
    }
    for (size_t k = 0; k < nq; k++)
        rows[(qs[k].y - y0) >> 6] |= UINT64_C(1) << ((qs[k].y - y0) & 63);
    offer_edges(rings, qs, nq, rows, y0, y1);
    for (size_t k = 0; k < nq; k++)
        if (qs[k].found)
        {
            /* q is on the +x side of the edge: its right side if the edge
             * goes up, its left side if it goes down; the interior of S is
             * on the left for a CCW ring, on the right for a CW ring. */
            hit[qs[k].r] = (int32_t)qs[k].S;
            inside[qs[k].r] = (unsigned char)(qs[k].upward == !ccw[qs[k].S]);
        }
    resolve(nr, hit, inside, state, stack, enclosing);
cleanup:
    free(qs);
    free(rows);
    free(stack);
    free(hit);
    free(inside);
    free(ccw);
    free(state);
    return st;
}
