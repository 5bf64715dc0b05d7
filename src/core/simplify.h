/*
 * simplify.h - topology-preserving Douglas-Peucker on a block's rings.
 */
#ifndef WM_SIMPLIFY_H
#define WM_SIMPLIFY_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Simplifies every ring of `in` with Douglas-Peucker, tolerance `tol`
     * (lattice units), into `out` (cleared first; caller frees with
     * wm_rings_free()).
     *
     * Fixed vertices: every vertex on the block square's border (x == 0,
     * x == size, y == 0 or y == size) is kept, so neighbouring blocks keep the
     * same border vertices. Each chain between consecutive fixed vertices is
     * simplified on its own; a ring without fixed vertices is split at two
     * deterministic anchors (its lowest-leftmost vertex and the vertex farthest
     * from it).
     *
     * Guarantees on `out` (given `in` satisfies the wm_rings invariants):
     * vertices are a subset of the input's, in order; every ring keeps >= 3
     * vertices and its orientation; rings stay simple and pairwise disjoint (no
     * crossing, no touching); ring nesting (wm_holes_nesting) is unchanged; the
     * rings keep their indices (ring i of out comes from ring i of in). Where a
     * simplification would break one of these, vertices are restored until none
     * is broken (in the limit the input itself, which is valid).
     *
     * tol <= 0 copies the input.
     */
    wm_status wm_simplify_rings(const wm_rings *in, int32_t size, double tol,
                                wm_rings *out, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_SIMPLIFY_H */
