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
     * Opens every pinch of the rings: a lattice point that two or more
     * passes of the boundary go through (one ring twice, or two rings).
     * Rounded to the lattice, two boundaries closer than a unit may meet
     * at one point (crossings on a dividing segment, contour.c
     * takes_before), where the rings touch without crossing: they break
     * the wm_rings invariants (simple, pairwise disjoint) that
     * simplification, nesting and the triangulation rely on.
     *
     * Rule: the contour links the passes at a pinch so that each bounds
     * its own water wedge there, the wedges disjoint, so all but at most
     * one pass turn left (their wedge is convex). All passes but one,
     * each a -> P -> b turning left, are cut to a -> b: the water triangle
     * (a, P, b) goes, the wedges no longer meet, and the change stays
     * within the triangle (under a lattice cell at SIMPLIFY=0). A cut is
     * made only where it is safe: no other vertex lies in the closed
     * triangle (then no segment crosses a -> b either: it would have to
     * end inside or cross a ring edge), the ring keeps three vertices, and
     * no two cuts are neighbours in a ring. A pinch it cannot open (passes
     * that do not turn left, as where rings made by hand overlap their
     * wedges) is left as it is.
     *
     * Cost: a hash of the vertices strictly inside cells of the sample
     * grid (on a sample row or column, the crossings of one cell side are
     * distinct points by construction); the checks only where a pinch is
     * found.
     *
     * @param r   the rings, changed in place
     * @param ctx error sink, may be NULL
     * @return WM_OK, WM_ERR_NOMEM
     */
    wm_status wm_rings_open_pinches(wm_rings *r, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_PINCH_H */
