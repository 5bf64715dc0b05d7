/*
 * merge.h - the paper's final mesh simplification: vertices closer than a
 * distance are merged (MERGE_DISTANCE), without ever breaking validity or
 * a block seam.
 */
#ifndef WM_MERGE_H
#define WM_MERGE_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Merges, in place, every vertex closer than `dist` (lattice units) to
     * one of its ring neighbours into that neighbour (the vertex is
     * removed), unless
     *   - it lies on the block square (x or y is 0 or `size`): neighbouring
     *     blocks keep the same border vertices; nor when its neighbours lie
     *     on one side of the square (the new edge would run along it);
     *   - its ring would drop below 3 vertices or to zero area;
     *   - the edge joining its two neighbours would meet another edge, or
     *     the triangle it cuts off would contain another vertex (exact
     *     predicates), so rings stay simple, disjoint and keep their nesting
     *     and orientation.
     * Vertices are visited in ring order, repeatedly until nothing changes;
     * the result is deterministic. Ring indices are kept.
     *
     * @param r    rings satisfying the wm_rings invariants (modified)
     * @param size the block square's side, lattice units
     * @param dist merge distance, lattice units; <= 0 does nothing
     * @param merged optional: receives the number of vertices removed
     * @return WM_OK or WM_ERR_NOMEM (r unchanged then)
     */
    wm_status wm_merge_rings(wm_rings *r, int32_t size, double dist,
                             size_t *merged, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_MERGE_H */
