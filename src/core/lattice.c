/*
 * lattice.c - the out-of-line exact predicates and the ring container.
 */
#include "lattice.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

wm_status wm_fail(const wm_ctx *ctx, wm_status status, const char *fmt, ...)
{
    if (ctx && ctx->error)
    {
        char msg[512];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, sizeof msg, fmt, ap);
        va_end(ap);
        ctx->error(ctx->user, status, msg);
    }
    return status;
}

size_t *wm_csr_begin(size_t *start, size_t nrows)
{
    for (size_t k = 0; k < nrows; k++)
        start[k + 1] += start[k];
    size_t *cursor = malloc((nrows + 1) * sizeof *cursor);
    if (cursor)
        memcpy(cursor, start, (nrows + 1) * sizeof *cursor);
    return cursor;
}

void wm_rings_clear(wm_rings *r)
{
    r->npts = 0;
    r->nrings = 0;
    if (r->start)
        r->start[0] = 0;
}

void wm_rings_free(wm_rings *r)
{
    if (!r)
        return;
    free(r->pts);
    free(r->start);
    memset(r, 0, sizeof *r);
}

int wm_grow(void **buf, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need)
    {
        if (ncap > SIZE_MAX / 2 / elem)
            return 0;
        ncap *= 2;
    }
    void *p = realloc(*buf, ncap * elem);
    if (!p)
        return 0;
    *buf = p;
    *cap = ncap;
    return 1;
}

int wm_map_set(int32_t **map, size_t *cap, size_t i, int32_t v)
{
    const size_t old = *cap;
    if (i == SIZE_MAX || !wm_grow((void **)map, cap, i + 1, sizeof **map))
        return 0;
    for (size_t k = old; k < *cap; k++)
        (*map)[k] = -1;
    (*map)[i] = v;
    return 1;
}

int wm_push(void **buf, size_t *n, size_t *cap, const void *item, size_t elem)
{
    if (!wm_grow(buf, cap, *n + 1, elem))
        return 0;
    memcpy((char *)*buf + *n * elem, item, elem);
    (*n)++;
    return 1;
}

size_t wm_lower_u64(const uint64_t *a, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi)
    {
        const size_t mid = lo + (hi - lo) / 2;
        if (a[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

wm_status wm_rings_push_grow(wm_rings *r, wm_pt p)
{
    if (!wm_grow((void **)&r->pts, &r->pts_cap, r->npts + 1, sizeof *r->pts))
        return WM_ERR_NOMEM;
    r->pts[r->npts++] = p;
    return WM_OK;
}

wm_status wm_rings_close(wm_rings *r)
{
    if (!wm_grow((void **)&r->start, &r->start_cap, r->nrings + 2,
                 sizeof *r->start))
        return WM_ERR_NOMEM;
    if (r->nrings == 0)
        r->start[0] = 0;
    r->start[++r->nrings] = r->npts;
    return WM_OK;
}

wm_i128 wm_ring_area2(const wm_pt *pts, size_t n)
{
    wm_i128 a = 0;
    for (size_t i = 0; i < n; i++)
    {
        const wm_pt p = pts[i], q = pts[i + 1 < n ? i + 1 : 0];
        a += (wm_i128)((int64_t)p.x * q.y - (int64_t)q.x * p.y);
    }
    return a;
}

static int on_square(const wm_pt *pts, size_t n, int32_t S)
{
    for (size_t i = 0; i < n; i++)
        if (pts[i].x == 0 || pts[i].y == 0 || pts[i].x == S || pts[i].y == S)
            return 1;
    return 0;
}

size_t wm_rings_drop_small(wm_rings *r, int32_t S, double min_area)
{
    size_t kept = 0, npts = 0;
    if (!(min_area > 0) || r->nrings == 0)
        return 0;
    for (size_t i = 0; i < r->nrings; i++)
    {
        const wm_pt *p = r->pts + r->start[i];
        const size_t n = wm_rings_len(r, i);
        const wm_i128 a2 = wm_ring_area2(p, n);
        const double area = (double)(a2 < 0 ? -a2 : a2) / 2.0;
        if (!on_square(p, n, S) && area < min_area)
            continue;
        memmove(r->pts + npts, p, n * sizeof *p);
        r->start[kept] = npts;
        npts += n;
        kept++;
    }
    const size_t dropped = r->nrings - kept;
    r->start[kept] = npts;
    r->nrings = kept;
    r->npts = npts;
    return dropped;
}

int wm_seg_dist2_exceeds(wm_pt a, wm_pt b, wm_pt p, wm_i128 tol2)
{
    const int64_t abx = (int64_t)b.x - a.x, aby = (int64_t)b.y - a.y;
    const int64_t apx = (int64_t)p.x - a.x, apy = (int64_t)p.y - a.y;
    const int64_t len2 = abx * abx + aby * aby;
    const int64_t dot = abx * apx + aby * apy;
    if (len2 == 0 || dot <= 0)
        return (wm_i128)(apx * apx + apy * apy) > tol2;
    if (dot >= len2)
    {
        const int64_t bpx = (int64_t)p.x - b.x, bpy = (int64_t)p.y - b.y;
        return (wm_i128)(bpx * bpx + bpy * bpy) > tol2;
    }
    /* perpendicular: cross^2 / len2 > tol2  <=>  cross^2 > tol2 * len2 */
    const wm_i128 cross = (wm_i128)(abx * apy - aby * apx);
    return cross * cross > tol2 * (wm_i128)len2;
}

int wm_point_in_ring(const wm_pt *ring, size_t n, wm_pt p)
{
    int inside = 0;
    for (size_t i = 0, j = n - 1; i < n; j = i++)
    {
        const wm_pt a = ring[j], b = ring[i];
        if (wm_on_segment(a, b, p))
            return -1;
        /* half-open rule on y: the edge counts when p.y is in [min, max) */
        if ((a.y > p.y) != (b.y > p.y))
        {
            /* crossing x > p.x  <=>  orientation sign matches edge direction */
            const int o = wm_orient(a, b, p);
            if ((b.y > a.y) ? (o > 0) : (o < 0))
                inside = !inside;
        }
    }
    return inside;
}

void wm_cells_reset(wm_cells *g, int32_t side)
{
    g->side = side;
    g->npairs = 0;
    g->nocc = 0;
}

int32_t wm_cells_fit(size_t n, int32_t S, int32_t largest, int32_t least)
{
    int32_t cell = largest;
    while (cell > least && S / (cell / 2) + 1 <= 65535)
    {
        const double side = (double)(S / cell + 1);
        if ((double)n <= 4.0 * side * side)
            break;
        cell /= 2;
    }
    return cell;
}

/* Bits of a radix digit: 2^11 counters stay in the L1 cache. */
#define CELL_DIGIT 11

wm_status wm_cells_index(wm_cells *g)
{
    const size_t side = (size_t)g->side, n = g->npairs;
    if (!wm_grow((void **)&g->row, &g->cap_row, side + 1, sizeof *g->row) ||
        !wm_grow((void **)&g->tmp, &g->cap_tmp, n + 1, sizeof *g->tmp))
        return WM_ERR_NOMEM;
    /* stable LSD radix sort on the cell (bits 32 and up) */
    const uint64_t maxcell = side * side;
    for (int shift = 32; shift < 64 && (maxcell >> (shift - 32)) > 0;
         shift += CELL_DIGIT)
    {
        size_t count[1 << CELL_DIGIT] = {0};
        const uint64_t mask = (1u << CELL_DIGIT) - 1;
        for (size_t i = 0; i < n; i++)
            count[(g->pairs[i] >> shift) & mask]++;
        for (size_t d = 0, sum = 0; d < (1u << CELL_DIGIT); d++)
        {
            const size_t c = count[d];
            count[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            g->tmp[count[(g->pairs[i] >> shift) & mask]++] = g->pairs[i];
        uint64_t *t = g->pairs;
        g->pairs = g->tmp;
        g->tmp = t;
        const size_t c = g->cap_pairs;
        g->cap_pairs = g->cap_tmp;
        g->cap_tmp = c;
    }
    /* occupied cells */
    size_t nocc = 0;
    for (size_t i = 0; i < n; i++)
        nocc += i == 0 || (g->pairs[i] >> 32) != (g->pairs[i - 1] >> 32);
    if (!wm_grow((void **)&g->col, &g->cap_col, nocc + 1, sizeof *g->col) ||
        !wm_grow((void **)&g->start, &g->cap_start, nocc + 1,
                 sizeof *g->start) ||
        !wm_grow((void **)&g->item, &g->cap_item, n + 1, sizeof *g->item))
        return WM_ERR_NOMEM;
    size_t o = 0, y = 0;
    g->row[0] = 0;
    for (size_t i = 0; i < n; i++)
    {
        const uint64_t cell = g->pairs[i] >> 32;
        if (i == 0 || cell != g->pairs[i - 1] >> 32)
        {
            const size_t cy = (size_t)(cell / side);
            while (y < cy)
                g->row[++y] = o;
            g->col[o] = (int32_t)(cell - cy * side);
            g->start[o++] = i;
        }
        g->item[i] = (uint32_t)g->pairs[i];
    }
    while (y < side)
        g->row[++y] = o;
    g->start[o] = n;
    g->nocc = o;
    return WM_OK;
}

void wm_cells_free(wm_cells *g)
{
    if (!g)
        return;
    free(g->row);
    free(g->col);
    free(g->start);
    free(g->item);
    free(g->pairs);
    free(g->tmp);
    memset(g, 0, sizeof *g);
}
