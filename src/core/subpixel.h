/*
 * subpixel.h - what the samples of a block's field cannot see: boundary
 * crossings hidden between two samples of one class, and the cells they
 * make ambiguous, resolved from the exact inputs.
 */
#ifndef WM_SUBPIXEL_H
#define WM_SUBPIXEL_H

#include "field.h"
#include "probe.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /** One cell edge with hidden crossings. */
    typedef struct
    {
        uint64_t id;    /**< edge id, as contour.c numbers edges */
        uint32_t first; /**< its crossings: off[first .. first + n - 1] */
        uint32_t n;     /**< even, >= 2 */
    } wm_hidden_edge;

    /**
     * The hidden crossings of a block and its ambiguous cells.
     * Edge id: horizontal edge from sample (c, r) to (c + 1, r) is
     * 2 * (r * (n + 1) + c), vertical from (c, r) to (c, r + 1) that + 1.
     * A cell is keyed by wm_field_cell_key(), so the cells of a tile are
     * one sorted run.
     */
    typedef struct
    {
        wm_hidden_edge *edge; /**< sorted by id (owned) */
        size_t nedge, edgecap;
        int32_t *off; /**< crossing offsets from the edge's first sample,
                           increasing, in 1 .. WM_Q - 1 (owned) */
        size_t noff, offcap;
        uint64_t *cell; /**< ambiguous cells, sorted, distinct (owned) */
        size_t ncell, cellcap;
        uint64_t *link; /**< cells whose segments take listed crossings:
                             those next to an ambiguous cell, and the two of
                             each edge with one listed crossing (sorted,
                             distinct; owned) */
        size_t nlink, linkcap;
        wm_pt *seed; /**< points of features that may lie inside one
                          cell (a point of an input smaller than two
                          pixels, a thin cap's tip, a corner in a cell of
                          one class), by cell: seed[i] is in cell
                          seedcell[i], sorted (owned) */
        uint64_t *seedcell;
        size_t nseed, seedcap, seedcellcap;
    } wm_hidden;

    /**
     * Finds where the samples of the block field f (the block's: f->w ==
     * f->h == n + 1) cannot decide the boundary (subpixel.c has the rule):
     * every edge of a mixed tile whose two samples are of one class and
     * whose feasible part (what the samples' balls leave) is not empty, and
     * every edge whose samples differ and whose interpolated crossing may
     * stray more than LOOSE pixel or that lies on the block square, gets
     * the exact crossings of the union's boundary with it
     * (wm_probe_crossings) and is listed. The cells of an
     * edge of one class with crossings, of a loose edge with three or more,
     * saddle cells, and the cells of seeds (small inputs, thin caps'
     * tips, corners in cells of one class) are ambiguous; a corner in
     * another cell only steers that cell's subdivision, if it is
     * ambiguous. Then every side
     * of an ambiguous cell whose samples differ in class, but those on the
     * block square, gets its crossings exactly too (listed, even when it has
     * one); three or more make the cell across ambiguous as well, and so on.
     * What is listed on the block square is a pure function of the
     * samples on the square and the inputs, so the two blocks sharing it
     * agree on it. Caller frees h with wm_hidden_free().
     */
    wm_status wm_hidden_find(const wm_field *f, wm_probe *probe, wm_hidden *h,
                             const wm_ctx *ctx);

    /** Frees what h owns; h may be NULL or zeroed. */
    void wm_hidden_free(wm_hidden *h);

    /** Whether cell (c, r) of block field f is ambiguous. */
    int wm_hidden_is_cell(const wm_hidden *h, const wm_field *f, int32_t c,
                          int32_t r);

    /**
     * The exact crossing on side `side` (0 bottom, 1 right, 2 top, 3 left)
     * of cell (c, r), when that side is listed with one crossing (a loose
     * edge, or a side of an ambiguous cell whose samples differ in class):
     * then *p is it and 1 is returned (marching squares must use it there,
     * not its interpolated one, so that both cells of the side agree);
     * else 0.
     */
    int wm_hidden_side_crossing(const wm_hidden *h, const wm_field *f,
                                int32_t c, int32_t r, int side, wm_pt *p);

    /** Receives a directed boundary segment (water on its left). Returns 0
     *  to stop (out of memory). */
    typedef int (*wm_segment_fn)(void *user, wm_pt a, wm_pt b);

    /**
     * The boundary inside every ambiguous cell of h: its sides' crossings (the
     * sampled one of a side whose samples differ in class, computed as
     * contour.c does; the hidden ones otherwise) are joined by subdividing
     * the cell, each new dividing segment's crossings found exactly, until
     * every piece holds one boundary segment between two of its sides and
     * no seed, or is 3-5 lattice units wide.
     * Segments end on crossings (shared with the neighbouring cells) or on
     * points inside the cell; they are simple and meet only at their ends.
     * Returns WM_OK, WM_ERR_NOMEM, or WM_ERR_CANCELLED (ctx asked to stop;
     * checked before each cell).
     */
    wm_status wm_hidden_cells(const wm_field *f, wm_probe *probe,
                              const wm_hidden *h, wm_segment_fn emit,
                              void *user, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_SUBPIXEL_H */
