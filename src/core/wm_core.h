/*
 * wm_core.h - the plain-C core of watermesh: status codes, error context,
 * ring containers and the stage entry points.
 *
 * The core never includes GDAL headers. It works on block-local integer
 * lattice coordinates (see lattice.h) and knows nothing of CRS or files.
 *
 * Orientation convention (used by every stage): water is on the LEFT of
 * every ring edge, in a y-up frame. Outer rings are therefore
 * counter-clockwise (positive signed area), holes clockwise.
 */
#ifndef WM_CORE_H
#define WM_CORE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C"
{
#endif

    /** Status returned by every fallible core function. */
    typedef enum
    {
        WM_OK = 0,
        WM_ERR_NOMEM,     /**< an allocation failed or a size overflowed */
        WM_ERR_INVALID,   /**< the input breaks the function's contract */
        WM_ERR_CANCELLED, /**< the progress callback asked to stop */
        WM_ERR_DEVICE,    /**< the OpenCL device failed or is missing (the C
                               path can take over) */
        WM_ERR_INTERNAL /**< an invariant failed: a bug, reported not hidden */
    } wm_status;

    /** Error sink. The GDAL side routes messages to CPLError; tests capture
     * them. A NULL handler drops messages. */
    typedef void (*wm_error_fn)(void *user, wm_status status, const char *msg);

    typedef struct wm_ctx
    {
        wm_error_fn error; /**< may be NULL */
        void *user;        /**< passed back to error() */
        /** set (non-zero, by another thread) to stop: the long loops check
         *  it every few milliseconds of work and return WM_ERR_CANCELLED;
         *  NULL: never */
        const int *cancel;
    } wm_ctx;

    /** Whether ctx asks to stop (wm_ctx.cancel). */
    static inline int wm_cancelled(const wm_ctx *ctx)
    {
        return ctx && ctx->cancel &&
               __atomic_load_n(ctx->cancel, __ATOMIC_RELAXED);
    }

    /** Reports a formatted message through ctx (may be NULL) and returns
     * status, so callers can write `return wm_fail(ctx, WM_ERR_NOMEM, "...")`.
     */
    wm_status wm_fail(const wm_ctx *ctx, wm_status status, const char *fmt, ...)
#if defined(__GNUC__)
        __attribute__((format(printf, 3, 4)))
#endif
        ;

    /** A block-local lattice point. Coordinates lie in [0, WM_LOCAL_MAX]. */
    typedef struct
    {
        int32_t x, y;
    } wm_pt;

/** Largest block-local lattice coordinate the core accepts (2^24): keeps
 *  orientation products in int64 and in-circle products in __int128. */
#define WM_LOCAL_MAX (INT32_C(1) << 24)

    /**
     * A set of rings in one block, vertices concatenated.
     *
     * Ring r owns pts[start[r]] .. pts[start[r+1]-1]; start has nrings+1
     * entries (start[0] == 0, start[nrings] == npts). Rings are implicitly
     * closed: the last vertex is not a repeat of the first. Invariants the
     * producers guarantee and the consumers may rely on: every ring has >= 3
     * vertices, no two consecutive vertices are equal, rings are simple and
     * pairwise disjoint (they neither cross nor touch), water is on the left.
     */
    typedef struct
    {
        wm_pt *pts;
        size_t npts, pts_cap;
        size_t *start; /**< nrings + 1 entries once a ring exists */
        size_t nrings, start_cap;
    } wm_rings;

    /** Empties the set, keeping its memory. */
    void wm_rings_clear(wm_rings *r);
    /** Frees the memory; r may be NULL. The struct itself is the caller's. */
    void wm_rings_free(wm_rings *r);
    /** wm_rings_push when the points' array is full: grows it, appends. */
    wm_status wm_rings_push_grow(wm_rings *r, wm_pt p);
    /** Appends a point to the ring being built. */
    static inline wm_status wm_rings_push(wm_rings *r, wm_pt p)
    {
        if (r->npts < r->pts_cap)
        {
            r->pts[r->npts++] = p;
            return WM_OK;
        }
        return wm_rings_push_grow(r, p);
    }
    /** Closes the ring being built (the points pushed since the last close). */
    wm_status wm_rings_close(wm_rings *r);
    /**
     * Compressed sparse rows built in two passes over the same items (the
     * pattern of every spatial index here): pass 1 counts, start[row + 1]++;
     * then wm_csr_begin turns the counts of start (nrows + 1 entries, start[0]
     * == 0) into offsets, start[nrows] being the total, and returns one fill
     * cursor per row; pass 2 writes items[cursor[row]++].
     *
     * @return the cursors (caller frees with free()), or NULL when out of
     *         memory
     */
    size_t *wm_csr_begin(size_t *start, size_t nrows);

    /**
     * Grows the array *buf (of elements of `elem` bytes, capacity *cap) to
     * hold at least `need`, doubling from 16; *buf and *cap are left as they
     * were when that fails.
     *
     * @return 1, or 0 when out of memory or the size overflows
     */
    int wm_grow(void **buf, size_t *cap, size_t need, size_t elem);

    /**
     * Appends the `elem` bytes at item to the array *buf of *n elements
     * (capacity *cap), growing it as wm_grow does.
     *
     * @return 1, or 0 when out of memory (the array is left as it was)
     */
    int wm_push(void **buf, size_t *n, size_t *cap, const void *item,
                size_t elem);

    /** The first index of ascending a[0 .. n) holding a value >= key (n
     *  when none). */
    size_t wm_lower_u64(const uint64_t *a, size_t n, uint64_t key);

    /**
     * Sets (*map)[i] = v in a map of capacity *cap whose unset entries are
     * -1, growing it as wm_grow does (the new entries unset).
     *
     * @return 1, or 0 when out of memory (the map is left as it was)
     */
    int wm_map_set(int32_t **map, size_t *cap, size_t i, int32_t v);

    /**
     * Items by cell of a side x side grid, only the occupied cells stored:
     * building and memory grow with the (cell, item) pairs, not with the
     * grid's area. Invariants once indexed: the occupied cells of row y are
     * row[y] .. row[y + 1] - 1, in ascending column col[]; the items of
     * occupied cell i are item[start[i] .. start[i + 1] - 1], in the order
     * they were added. So the items of the cells x0 .. x1 of a row are one
     * contiguous run (wm_cells_row).
     *
     * Use: memset to 0, wm_cells_reset(side) (also to reuse), wm_cells_add
     * for each pair, wm_cells_index, queries; wm_cells_free.
     */
    typedef struct
    {
        int32_t side;    /**< cells per side, at most 65535 */
        size_t *row;     /**< side + 1 */
        int32_t *col;    /**< nocc */
        size_t *start;   /**< nocc + 1 */
        uint32_t *item;  /**< npairs, grouped by cell */
        size_t nocc;     /**< occupied cells */
        uint64_t *pairs; /**< build buffer: cell << 32 | item, then the
                              sorted pairs */
        size_t npairs;
        size_t cap_pairs, cap_row, cap_col, cap_start, cap_item, cap_tmp;
        uint64_t *tmp; /**< radix sort scratch */
    } wm_cells;

    /** Empties g for a grid of side x side cells (keeps its memory). */
    void wm_cells_reset(wm_cells *g, int32_t side);

    /** The cell side (lattice units) for a grid over a square of side S
     *  holding n items: `largest`, halved down to `least` while there are
     *  more than 4 items per cell and the grid stays within 65535 cells a
     *  side. A query of such a grid reads whole cells: where the items are
     *  dense (coarse pixels), smaller cells read fewer. */
    int32_t wm_cells_fit(size_t n, int32_t S, int32_t largest, int32_t least);

    /** Adds `item` to cell (x, y), 0 <= x, y < side. Returns 0 when out of
     *  memory. */
    static inline int wm_cells_add(wm_cells *g, int32_t x, int32_t y,
                                   uint32_t item)
    {
        if (g->npairs == g->cap_pairs &&
            !wm_grow((void **)&g->pairs, &g->cap_pairs, g->npairs + 1,
                     sizeof *g->pairs))
            return 0;
        const uint64_t cell = (uint64_t)y * (uint64_t)g->side + (uint64_t)x;
        g->pairs[g->npairs++] = cell << 32 | item;
        return 1;
    }

    /** Sorts the pairs added since the reset into cells (stable: a cell's
     *  items keep their order of addition). Returns WM_ERR_NOMEM or WM_OK. */
    wm_status wm_cells_index(wm_cells *g);

    /** The run item[*b .. *e - 1] of the items of cells x0 .. x1 of row y
     *  (the caller clamps to the grid). */
    static inline void wm_cells_row(const wm_cells *g, int32_t y, int32_t x0,
                                    int32_t x1, size_t *b, size_t *e)
    {
        size_t lo = g->row[y], hi = g->row[y + 1];
        while (lo < hi) /* first cell at or right of x0 */
        {
            const size_t mid = lo + (hi - lo) / 2;
            if (g->col[mid] < x0)
                lo = mid + 1;
            else
                hi = mid;
        }
        hi = g->row[y + 1];
        size_t end = lo;
        while (end < hi && g->col[end] <= x1)
            end++;
        *b = g->start[lo];
        *e = g->start[end];
    }

    /** Frees what g owns (g may be NULL) and zeroes it. */
    void wm_cells_free(wm_cells *g);

    /** The run holding index x of offsets start[0 .. n] (ascending,
     *  start[0] <= x < start[n]): the last k < n with start[k] <= x. */
    static inline size_t wm_run_of(const size_t *start, size_t n, size_t x)
    {
        size_t lo = 0, hi = n;
        while (hi - lo > 1)
        {
            const size_t mid = lo + (hi - lo) / 2;
            if (start[mid] <= x)
                lo = mid;
            else
                hi = mid;
        }
        return lo;
    }

    /** Liang-Barsky clipping: the part [*t0, *t1] of the segment p + t d,
     *  0 <= t <= 1, inside the box [0, w] x [0, h] (p relative to the box's
     *  corner); returns 0 when the segment misses the box. */
    static inline int wm_clip_box(double px, double py, double dx, double dy,
                                  double w, double h, double *t0, double *t1)
    {
        const double p[4] = {-dx, dx, -dy, dy};
        const double q[4] = {px, w - px, py, h - py};
        *t0 = 0.0;
        *t1 = 1.0;
        for (int i = 0; i < 4; i++)
        {
            if (p[i] == 0.0)
            {
                if (q[i] < 0.0)
                    return 0;
                continue;
            }
            const double t = q[i] / p[i];
            if (p[i] < 0.0)
                *t0 = t > *t0 ? t : *t0;
            else
                *t1 = t < *t1 ? t : *t1;
            if (*t0 > *t1)
                return 0;
        }
        return 1;
    }

    /** Number of vertices of ring i. */
    static inline size_t wm_rings_len(const wm_rings *r, size_t i)
    {
        return r->start[i + 1] - r->start[i];
    }

/** Vector builds of hot loops: the same IEEE operations (no contraction,
 *  no fast-math) in wider lanes, so every clone gives the same bits
 *  (invariant 2). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define WM_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define WM_CLONES
#endif

    /** 128-bit integer for exact products (GCC/Clang extension, named once). */
    __extension__ typedef __int128 wm_i128;

    /** Twice the signed area of a ring of n points, exact (positive: CCW). */
    wm_i128 wm_ring_area2(const wm_pt *pts, size_t n);

    /**
     * Removes, in place, every ring that has no vertex on the block square
     * [0, S]^2 and whose area is below min_area (square lattice units):
     * MIN_FEATURE_AREA. A ring nested in a removed ring is inside the block
     * and smaller, so it goes too, and the rest keep their nesting. A ring
     * with a vertex on the square is a piece of a feature the neighbouring
     * block also holds: it is kept whatever its area, so both blocks decide
     * alike (seams stay exact). Returns how many rings were removed.
     */
    size_t wm_rings_drop_small(wm_rings *r, int32_t S, double min_area);

#ifdef __cplusplus
}
#endif

#endif /* WM_CORE_H */
