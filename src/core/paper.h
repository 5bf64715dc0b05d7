/*
 * paper.h - the paper's own extraction (METHOD=PAPER): Inside / Outside /
 * Border classes with width compensation, erosion by a 3x3 cross, and the
 * walk over Border pixels with heuristics and backtracking (Menegais et
 * al., GRAPP 2021, sections 4 and 5). paper.c's header explains the method,
 * its exact rules and where it departs from the paper.
 */
#ifndef WM_PAPER_H
#define WM_PAPER_H

#include "field.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /** Pixel classes, one byte per sample (row-major, w * h, row 0 at the
     *  bottom). */
    enum
    {
        WM_PAPER_OUTSIDE = 0, /**< land */
        WM_PAPER_INSIDE = 1,  /**< water, not on the eroded border */
        WM_PAPER_BORDER = 2   /**< water on the eroded border or on the
                                   block square: a ring vertex candidate */
    };

/** Water level, pixels: a sample is water when its field value d <= this.
 *  The paper's width compensation (rivers widened by 2 pixels, lake border
 *  pixels one pixel out) applied to its "pixel fully inside" test (d <=
 *  -1/2); it puts the Border pixel centres at d in (-1/2, +1/2], centred on
 *  the true shoreline. See paper.c. */
#define WM_PAPER_LEVEL 0.5f

    /** How the walk ranks the Border neighbours of a pixel (paper, Fig. 5),
     *  relative to the last segment walked. */
    typedef enum
    {
        WM_HEUR_CLOSEST = 0,     /**< nearest first: 4-neighbours before
                                      diagonals (the paper's default) */
        WM_HEUR_DIRECTIONAL_CW,  /**< most clockwise turn first */
        WM_HEUR_DIRECTIONAL_CCW, /**< most counter-clockwise turn first */
        WM_HEUR_LEAST_ANGLE      /**< smallest turn first */
    } wm_heuristic;

    /** Counters of one extraction (statistics and tests). */
    typedef struct
    {
        size_t rings;      /**< rings emitted */
        size_t border;     /**< Border pixels when the walk starts */
        size_t dropped;    /**< Border pixels on no ring (they bound no
                                water triangle, or a heuristic cut them) */
        size_t pinches;    /**< pixels where the water touched itself */
        size_t cuts;       /**< half-pixel triangles removed at pinches */
        size_t shortcuts;  /**< corners cut by the heuristic's choice */
        size_t branches;   /**< walk nodes with two admissible steps */
        size_t backtracks; /**< walk steps undone after a dead end */
    } wm_paper_stats;

    /**
     * Classifies every sample of a block's field: water when d <=
     * WM_PAPER_LEVEL, then wm_paper_square_rules() and wm_paper_erode().
     *
     * @param f   the field (borrowed); f->band must exceed WM_PAPER_LEVEL
     * @param cls out: f->w * f->h classes, row-major, allocated by the caller
     * @param ctx error sink, may be NULL
     * @return WM_OK, or WM_ERR_INVALID for a band too small to tell land
     */
    wm_status wm_paper_classify(const wm_field *f, uint8_t *cls,
                                const wm_ctx *ctx);

    /**
     * The seam rules, in place, on a water mask (non-zero: water) of w * h
     * samples, before the erosion: along each side of the block square, a
     * water sample (not a corner of the square) whose two neighbours along
     * the side are land becomes land, and every water sample (not a corner)
     * makes its inward neighbour water. They make two blocks sharing a side
     * cover the same pieces of it and have the same vertices on it (see
     * paper.c). wm_paper_classify applies them.
     */
    void wm_paper_square_rules(uint8_t *mask, int32_t w, int32_t h);

    /**
     * The paper's erosion, in place: every non-zero entry of `cls` is water
     * (the foreground A); a water sample becomes WM_PAPER_BORDER when it lies
     * on the block square (first or last row or column: the paper's forced
     * Border pixels) or when one of its four 4-neighbours is land, and
     * WM_PAPER_INSIDE otherwise; land stays WM_PAPER_OUTSIDE. This is
     * T = (A' eroded by the 3x3 cross) XOR A' on the interior A', padded
     * with A's border as Border (see paper.c for the boundary condition).
     * Idempotent.
     */
    void wm_paper_erode(uint8_t *cls, int32_t w, int32_t h);

    /**
     * Traces the water boundary through the Border pixel centres: sample
     * (c, r) becomes the lattice point (c * WM_Q, r * WM_Q).
     *
     * Contract: w, h >= 1, (max(w, h) - 1) * WM_Q <= WM_LOCAL_MAX, and `cls`
     * is an eroded class grid (what wm_paper_erode() leaves), else
     * WM_ERR_INVALID.
     *
     * Guarantees: the wm_rings invariants (>= 3 vertices, no repeated
     * consecutive vertex, rings simple and pairwise disjoint, water on the
     * left: outer rings counter-clockwise, holes clockwise). Every vertex is
     * a water sample. Water samples on the block square are never skipped
     * by a heuristic; each one that is a corner of a water triangle of the
     * region after pinch cuts (see paper.c) is a vertex. Deterministic.
     *
     * @param cls   the classes (borrowed; copied to a work grid of w * h
     *              bytes)
     * @param heur  ranking of candidate pixels
     * @param out   cleared first; caller frees with wm_rings_free()
     * @param stats optional counters (may be NULL), overwritten
     * @param ctx   error sink, may be NULL
     * @return WM_OK, WM_ERR_INVALID, WM_ERR_NOMEM, or WM_ERR_INTERNAL when an
     *         invariant fails (a bug, reported not hidden)
     */
    wm_status wm_paper_trace(const uint8_t *cls, int32_t w, int32_t h,
                             wm_heuristic heur, wm_rings *out,
                             wm_paper_stats *stats, const wm_ctx *ctx);

    /**
     * wm_paper_classify() then wm_paper_trace() on a block's field (the
     * replacement of contour + crease when METHOD=PAPER). Uses one byte per
     * sample of work memory.
     *
     * @param f     the field (borrowed), f->w, f->h >= 1
     * @param out   cleared first; caller frees with wm_rings_free()
     * @param stats optional counters (may be NULL)
     * @return as wm_paper_classify() and wm_paper_trace()
     */
    wm_status wm_paper_extract(const wm_field *f, wm_heuristic heur,
                               wm_rings *out, wm_paper_stats *stats,
                               const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_PAPER_H */
