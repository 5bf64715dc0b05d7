/*
 * corners.h - candidate corners of the union boundary: crossings of two
 * input boundaries.
 */
#ifndef WM_CORNERS_H
#define WM_CORNERS_H

#include "field.h"
#include "probe.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Finds once, into probe->corner, the candidate corners of the block's
     * union boundary: the crossings of two input boundaries (river banks
     * and end circles, lake edges) in the block square, whose nearest
     * sample of f is within 0.75 pixel of the boundary, snapped to the
     * lattice (and, within a unit of the block square, one unit inside
     * it), sorted and distinct; of two river segments sharing no end and
     * shorter than they are wide, none strictly inside a river capsule.
     * Some are buried under a third input.
     */
    wm_status wm_corners_find(wm_probe *probe, const wm_field *f,
                              const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_CORNERS_H */
