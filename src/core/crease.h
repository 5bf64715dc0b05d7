/*
 * crease.h - sharp corners of the water boundary, recovered after sampling.
 */
#ifndef WM_CREASE_H
#define WM_CREASE_H

#include "field.h"
#include "probe.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Inserts the exact crease corners of block (bx, by) into its extracted
     * rings (block-local lattice units, as from wm_contour_extract on the
     * block's field `f`, which also serves to discard crossings buried under
     * other inputs).
     *
     * Where the boundaries of two inputs cross (a river bank meeting a lake
     * shore or another bank, the inner side of a sharp bend, a lake vertex)
     * the union's boundary has a corner. A sampled field loses the tip of a
     * sharp corner (by about pixel / (2 tan(angle / 2))); this puts it back:
     * each crossing point C of two input boundaries, strictly inside the block
     * and 1/4 to 16 pixels from the rings, is inserted into the nearest ring
     * edge (or a neighbour of it; never an edge on the block square) when the
     * two new edges meet no other edge, the triangle they add or cut contains
     * no ring vertex (exact predicates), and the new edges follow the union's
     * boundary within half a pixel. Otherwise it is skipped: the rings stay
     * valid, at worst unimproved.
     *
     * Deterministic: candidates are found in a fixed order and inserted in
     * lexicographic order of their lattice position.
     */
    wm_status wm_crease_recover(const wm_scene *s, const wm_field *f,
                                int64_t bx, int64_t by, wm_rings *rings,
                                const wm_ctx *ctx);

    /**
     * wm_crease_recover with the block's probe already set up (the block
     * is the probe's), after wm_contour_extract_probed made `rings` with
     * it: its probe->rebuilt tells the cells where the rings are not the
     * interpolated edges (an empty list, as after wm_probe_init, is right
     * only for rings from wm_contour_extract).
     */
    wm_status wm_crease_recover_probed(wm_probe *probe, const wm_field *f,
                                       wm_rings *rings, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_CREASE_H */
