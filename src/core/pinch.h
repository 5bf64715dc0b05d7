/*
 * pinch.h - points where a block's boundary touches itself, opened.
 */
#ifndef WM_PINCH_H
#define WM_PINCH_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Opens the points where the rings touch: a lattice point strictly
     * inside a cell of the sample grid that two or more passes of the
     * boundary go through (one ring twice, or two rings: a pinch), or
     * such a vertex inside another ring's segment (a T).
     * Rounded to the lattice, two boundaries closer than a unit may meet
     * there (crossings on a dividing segment, contour.c takes_before;
     * the pieces of a crowded cell), where the rings touch without
     * crossing: they break the wm_rings invariants (simple, pairwise
     * disjoint) that simplification, nesting and the triangulation rely
     * on.
     *
     * Rule: a pass a -> P -> b that turns at P is moved into the convex
     * side of its turn (its water wedge where it turns left, its land
     * wedge where it turns right), to the first lattice point strictly
     * inside the triangle (a, P, b) along the wedge's bisector (a unit or
     * two), or cut to a -> b where there is none. All passes through a
     * pinch but one move, the vertex of a T moves; a pass moves only where
     * no other segment at P leaves into its wedge (then the passes no
     * longer meet), no other vertex lies in the region it sweeps (then no
     * segment crosses its new edges either: it would have to end there or
     * cross a ring edge), a cut ring keeps three vertices, and no two
     * moved vertices are neighbours in a ring (the next round takes the
     * second, on the new rings). The contour links the passes at a pinch
     * so that each bounds its own water wedge, the wedges disjoint: all
     * but one turn left and may move. A point no pass may leave, and one
     * that is both a pinch and a T, is left as it is (the CDT or the
     * simplifier then reports it). A cut is made only where neither end of
     * the chord is a pinch or a T, the chord continues neither neighbouring
     * segment, and it does not run along a side of the block square.
     *
     * Cost: a hash of the vertices strictly inside cells of the sample
     * grid (on a sample row or column, the crossings of one cell side are
     * distinct points by construction), and a grid of their segments; the
     * checks only where a point is found.
     *
     * @param r   the rings, changed in place
     * @param S   the block square's side (lattice units): no cut runs
     *            along it
     * @param ctx error sink, may be NULL
     * @return WM_OK, WM_ERR_NOMEM
     */
    wm_status wm_rings_open_pinches(wm_rings *r, int32_t S, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_PINCH_H */
