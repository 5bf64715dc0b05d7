/*
 * probe.h - the signed distance to the union of a block's inputs at any
 * point, evaluated directly from the inputs (not from the sampled field).
 */
#ifndef WM_PROBE_H
#define WM_PROBE_H

#include "scene.h"

#ifdef __cplusplus
extern "C"
{
#endif

/** The farthest reach a probe serves, lattice units (4 pixels). */
#define WM_PROBE_REACH (4.0 * WM_Q)

    /**
     * The inputs in reach of one block, with an index of its river segments
     * by 16-pixel cell. Fields are read-only after wm_probe_init.
     */
    typedef struct
    {
        const wm_scene *s;
        int64_t X0, Y0;       /**< block origin, global lattice */
        const uint32_t *segs; /**< the block's river segments (borrowed) */
        size_t nsegs;
        const uint32_t *polys; /**< the block's lake polygons (borrowed) */
        size_t npolys;
        /** river segments by cell of the block, each registered in the
         *  cells its box grown by radius + WM_PROBE_REACH touches; segments
         *  touching too many cells are in `wide` instead (owned) */
        wm_cells cells;
        uint32_t *wide;
        size_t nwide;
    } wm_probe;

    /**
     * Sets up the probe of block (bx, by) of scene s (which must outlive
     * it). A block outside the grid gets an empty probe. Returns
     * WM_ERR_NOMEM on allocation failure (p is then freed). Caller frees
     * with wm_probe_free().
     */
    wm_status wm_probe_init(wm_probe *p, const wm_scene *s, int64_t bx,
                            int64_t by);

    /** Frees what p owns; p may be NULL or zeroed. */
    void wm_probe_free(wm_probe *p);

    /**
     * Signed distance (lattice units, negative in water) from the
     * block-local point (x, y), which lies in the block square, to the
     * union of the block's inputs, in double precision; inputs farther than
     * `reach` (<= WM_PROBE_REACH) are ignored (the result is then +reach or
     * more). Floating point: use it to choose, never to decide validity.
     */
    double wm_probe_distance(const wm_probe *p, double x, double y,
                             double reach);

#ifdef __cplusplus
}
#endif

#endif /* WM_PROBE_H */
