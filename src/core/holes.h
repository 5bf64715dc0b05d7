/*
 * holes.h - ring nesting: which ring immediately encloses each ring.
 */
#ifndef WM_HOLES_H
#define WM_HOLES_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Computes, for every ring of `rings`, the index of the smallest ring that
     * strictly encloses it, or -1 when none does.
     *
     * Contract: rings satisfy the wm_rings invariants (simple, pairwise
     * disjoint, water on the left). Because rings never cross, nesting
     * alternates: the enclosing ring of a hole (clockwise) is the outer ring it
     * belongs to, and the enclosing ring of an outer ring (if any) is a hole of
     * another polygon.
     *
     * Method: for each ring take its lowest-leftmost vertex q; the ring edge
     * first hit by the ray from q towards -x decides (that edge's ring S: if
     * the edge's direction puts q on S's interior side then S encloses the
     * ring, otherwise S's own enclosing ring does). Each edge looks up, in a
     * bitmap of the queries' rows, whether its y range holds a query, and
     * offers itself only to those; all comparisons are exact. O(n + rings log
     * rings + height / 64 + crossings) for n vertices.
     *
     * @param rings     the rings (borrowed)
     * @param enclosing out: rings->nrings entries, allocated by the caller
     * @param ctx       error sink, may be NULL
     * @return WM_OK, WM_ERR_NOMEM
     */
    wm_status wm_holes_nesting(const wm_rings *rings, int32_t *enclosing,
                               const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_HOLES_H */
