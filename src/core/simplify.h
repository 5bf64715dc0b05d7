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

    /** A piece of a ring edge on the block square, from a to b
     *  (block-local): what Delaunay refinement may not split (refine.h,
     *  wm_side_pieces). */
    typedef struct
    {
        wm_pt a, b;
    } wm_side_piece;

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

    /**
     * wm_simplify_rings, where in addition no simplified edge enters the
     * diametral circle of one of the npieces `pieces` (of ring edges on the
     * block square) unless the input edges it replaces enter it too, or it
     * ends at an end of that piece. Refinement (MIN_ANGLE) cannot split
     * those pieces: a shore carried into their circle would leave skinny
     * triangles on them (a shore running along a block side, straightened
     * towards it). Vertices are kept as Douglas-Peucker keeps them (the
     * farthest of the span first).
     *
     * @param pieces  npieces segments on the block square's sides (x == 0,
     *                x == size, y == 0 or y == size), those on one side not
     *                overlapping (they may share ends); NULL when npieces
     *                is 0 (then this is wm_simplify_rings)
     * @return as wm_simplify_rings
     */
    wm_status wm_simplify_rings_guarded(const wm_rings *in, int32_t size,
                                        double tol, const wm_side_piece *pieces,
                                        size_t npieces, wm_rings *out,
                                        const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_SIMPLIFY_H */
