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
 * Acceleration: the non-horizontal edges are registered in a uniform grid
 * (CSR, square cells of a power-of-two side, one cell per one to four
 * edges) in every cell their segment passes through (row by row, exact
 * integer bounds, a superset of the cells). A query walks the cells of q's row
 * from q's column leftwards and stops as soon as the best crossing lies in the
 * cell just scanned. Building is O(n + total registrations); a query costs the
 * edges of the cells it visits: about O(n) overall for typical rings (many
 * short edges, rings spread over the block), no rings^2 term. Adversarial
 * layouts (many rays crossing long runs of crowded cells) cost more, up to
 * O(rings * n / cells); extraction output is not like that.
 *
 * Complexity: O(n) memory; time O(n + sum over queries of scanned cells).
 *
 * References: the half-open crossing rule of the even-odd test (E. Haines,
 * "Point in Polygon Strategies", Graphics Gems IV, 1994); symbolic
 * perturbation (Edelsbrunner & Muecke, "Simulation of Simplicity", ACM TOG
 * 9(1), 1990).
 */
#include "holes.h"
#include "lattice.h"

#include <math.h>
#include <stdlib.h>

#define H_NONE UINT32_MAX

/* ---- row-by-row cell walk of a segment ----------------------------------- */

typedef struct
{
    int64_t ax, ay, bx, by; /* endpoints, a has the lower (or equal) y */
    int64_t ox, oy, s;      /* grid origin and cell size (1 << k) */
    int k;
    int64_t colmin, colmax; /* columns of the segment's bounding box */
    int64_t row0, row, row_end, col, col_end;
} h_walk;

static int64_t h_floordiv(int64_t a, int64_t b)
{
    int64_t q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0)))
        q--;
    return q;
}

static int64_t h_ceildiv(int64_t a, int64_t b)
{
    return -h_floordiv(-a, b);
}

static void h_walk_row(h_walk *w)
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
    const int64_t lo = w->ax + h_floordiv(na < nb ? na : nb, dy);
    const int64_t hi = w->ax + h_ceildiv(na > nb ? na : nb, dy);
    w->col = (lo - w->ox) >> w->k; /* lo, hi >= ox */
    w->col_end = (hi - w->ox) >> w->k;
    if (w->col < w->colmin)
        w->col = w->colmin;
    if (w->col_end > w->colmax)
        w->col_end = w->colmax;
}

/* The cells of segment ab in the grid of cells of side 1 << k from
 * (ox, oy), both ends at or above and right of it. */
static void h_walk_init(h_walk *w, wm_pt a, wm_pt b, int64_t ox, int64_t oy,
                        int k)
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
    w->s = (int64_t)1 << k;
    w->k = k;
    w->colmin = ((int64_t)(a.x < b.x ? a.x : b.x) - ox) >> k;
    w->colmax = ((int64_t)(a.x > b.x ? a.x : b.x) - ox) >> k;
    w->row = ((int64_t)a.y - oy) >> k;
    w->row_end = ((int64_t)b.y - oy) >> k;
    w->row0 = w->row;
    h_walk_row(w);
}

/* Next cell (cx, cy) of the walk; 0 when done. */
static int h_walk_next(h_walk *w, int64_t *cx, int64_t *cy)
{
    while (w->col > w->col_end)
    {
        if (++w->row > w->row_end)
            return 0;
        h_walk_row(w);
    }
    *cx = w->col++;
    *cy = w->row;
    return 1;
}

/* ---- the nesting --------------------------------------------------------- */

static size_t h_next(const wm_rings *rs, const uint32_t *ring_of, size_t i)
{
    const size_t r = ring_of[i];
    return (i + 1 == rs->start[r + 1]) ? rs->start[r] : i + 1;
}

wm_status wm_holes_nesting(const wm_rings *rings, int32_t *enclosing,
                           const wm_ctx *ctx)
{
    wm_status st = WM_OK;
    const size_t nr = rings->nrings, n = rings->npts;
    const wm_pt *P = rings->pts;
    uint32_t *ring_of = NULL, *ent = NULL, *qidx = NULL, *stack = NULL;
    size_t *cell = NULL;
    int32_t *hit = NULL;
    unsigned char *inside = NULL, *ccw = NULL, *state = NULL;
    size_t nedges = 0, ncells = 0, nent = 0;
    int64_t xmin = INT64_MAX, ymin = INT64_MAX, xmax = INT64_MIN,
            ymax = INT64_MIN, s = 1, cols = 1, rows = 1;
    int k = 0; /* cell side s = 1 << k */

    if (nr == 0)
        return WM_OK;
    if (nr > (size_t)INT32_MAX || n >= (size_t)UINT32_MAX)
        return wm_fail(ctx, WM_ERR_NOMEM, "holes: too many rings or points");

    ring_of = malloc((n ? n : 1) * sizeof *ring_of);
    qidx = malloc(nr * sizeof *qidx);
    hit = malloc(nr * sizeof *hit);
    inside = calloc(nr, 1);
    ccw = calloc(nr, 1);
    state = calloc(nr, 1);
    stack = malloc(nr * sizeof *stack);
    if (!ring_of || !qidx || !hit || !inside || !ccw || !state || !stack)
    {
        st = wm_fail(ctx, WM_ERR_NOMEM, "holes: out of memory");
        goto cleanup;
    }

    /* per ring: owner of each point, lowest-leftmost vertex, orientation */
    for (size_t r = 0; r < nr; r++)
    {
        const size_t b = rings->start[r], e = rings->start[r + 1];
        qidx[r] = H_NONE;
        hit[r] = -1;
        enclosing[r] = -1;
        for (size_t i = b; i < e; i++)
        {
            ring_of[i] = (uint32_t)r;
            if (qidx[r] == H_NONE || P[i].y < P[qidx[r]].y ||
                (P[i].y == P[qidx[r]].y && P[i].x < P[qidx[r]].x))
                qidx[r] = (uint32_t)i;
            if (P[i].x < xmin)
                xmin = P[i].x;
            if (P[i].x > xmax)
                xmax = P[i].x;
            if (P[i].y < ymin)
                ymin = P[i].y;
            if (P[i].y > ymax)
                ymax = P[i].y;
            if (e - b >= 2)
            {
                const size_t j = (i + 1 == e) ? b : i + 1;
                if (P[i].y != P[j].y)
                    nedges++;
            }
        }
        ccw[r] = wm_ring_area2(P + b, e - b) > 0;
    }
    if (nedges == 0)
        goto cleanup; /* no ring can enclose anything */

    /* grid: square cells, about one per 4 edges, at most 4 * nedges + 64 */
    {
        const double w = (double)(xmax - xmin + 1);
        const double h = (double)(ymax - ymin + 1);
        const double want = ceil(sqrt(w * h * 4.0 / (double)nedges));
        while ((double)((int64_t)1 << k) < want)
            k++; /* a power of two: cells by shifts */
        for (;;)
        {
            s = (int64_t)1 << k;
            cols = ((xmax - xmin) >> k) + 1;
            rows = ((ymax - ymin) >> k) + 1;
            if ((double)cols * (double)rows <= 4.0 * (double)nedges + 64.0)
                break;
            k++;
        }
        ncells = (size_t)cols * (size_t)rows;
    }
    cell = calloc(ncells + 1, sizeof *cell);
    if (!cell)
    {
        st = wm_fail(ctx, WM_ERR_NOMEM, "holes: out of memory (grid)");
        goto cleanup;
    }
    /* count, prefix, fill (CSR) */
    for (int pass = 0; pass < 2; pass++)
    {
        for (size_t i = 0; i < n; i++)
        {
            const size_t j = h_next(rings, ring_of, i);
            h_walk w;
            int64_t cx, cy;
            if (P[i].y == P[j].y)
                continue;
            h_walk_init(&w, P[i], P[j], xmin, ymin, k);
            while (h_walk_next(&w, &cx, &cy))
            {
                const size_t c = (size_t)(cy * cols + cx);
                if (pass == 0)
                    cell[c]++;
                else
                    ent[--cell[c]] = (uint32_t)i;
            }
        }
        if (pass == 0)
        {
            for (size_t c = 0; c < ncells; c++)
            {
                if (cell[c] > SIZE_MAX / sizeof *ent - nent)
                {
                    st = wm_fail(ctx, WM_ERR_NOMEM, "holes: grid too large");
                    goto cleanup;
                }
                nent += cell[c];
                cell[c] = nent; /* end of cell c; the fill decrements */
            }
            cell[ncells] = nent;
            ent = malloc((nent ? nent : 1) * sizeof *ent);
            if (!ent)
            {
                st = wm_fail(ctx, WM_ERR_NOMEM, "holes: out of memory (cells)");
                goto cleanup;
            }
        }
    }

    /* queries */
    for (size_t r = 0; r < nr; r++)
    {
        if (qidx[r] == H_NONE)
            continue;
        const wm_pt q = P[qidx[r]];
        const int64_t row = (q.y - ymin) >> k;
        int64_t bestN = 0, bestD = 0, bestdx = 0;
        size_t best = SIZE_MAX;
        for (int64_t c = (q.x - xmin) >> k; c >= 0; c--)
        {
            const size_t ci = (size_t)(row * cols + c);
            for (size_t e = cell[ci]; e < cell[ci + 1]; e++)
            {
                const size_t i = ent[e];
                if (ring_of[i] == r)
                    continue;
                const size_t j = h_next(rings, ring_of, i);
                wm_pt lo = P[i], hi = P[j];
                if (hi.y < lo.y)
                {
                    lo = P[j];
                    hi = P[i];
                }
                if (!(lo.y <= q.y && q.y < hi.y))
                    continue;
                const int64_t D = (int64_t)hi.y - lo.y;
                const int64_t dx = (int64_t)hi.x - lo.x;
                const int64_t N =
                    (int64_t)lo.x * D + dx * ((int64_t)q.y - lo.y);
                if (N >= (int64_t)q.x * D)
                    continue; /* not strictly left of q */
                if (best != SIZE_MAX)
                {
                    const wm_i128 l = (wm_i128)N * bestD;
                    const wm_i128 rr = (wm_i128)bestN * D;
                    if (l < rr)
                        continue;
                    /* tie: the larger dx/dy is further right at q.y + eps */
                    if (l == rr && dx * bestD <= bestdx * D)
                        continue;
                }
                best = i;
                bestN = N;
                bestD = D;
                bestdx = dx;
            }
            if (best != SIZE_MAX && bestN >= (xmin + c * s) * bestD)
                break; /* nothing further left can beat it */
        }
        if (best == SIZE_MAX)
            continue; /* hit[r] stays -1 */
        {
            const size_t j = h_next(rings, ring_of, best);
            const int upward = P[j].y > P[best].y;
            const uint32_t S = ring_of[best];
            /* q is on the +x side of the edge: its right side if the edge
             * goes up, its left side if it goes down; the interior of S is
             * on the left for a CCW ring, on the right for a CW ring. */
            hit[r] = (int32_t)S;
            inside[r] = (unsigned char)(upward == !ccw[S]);
        }
    }

    /* resolve: enc(r) = -1 | hit | enc(hit), iteratively with a memo.
     * state: 0 unknown, 1 on the stack, 2 done. */
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

cleanup:
    free(ring_of);
    free(ent);
    free(qidx);
    free(stack);
    free(cell);
    free(hit);
    free(inside);
    free(ccw);
    free(state);
    return st;
}
