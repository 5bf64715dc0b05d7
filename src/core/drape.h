/*
 * drape.h - the water surface's height at every vertex of a block's mesh,
 * from levels given per river segment end and per lake water body.
 */
#ifndef WM_DRAPE_H
#define WM_DRAPE_H

#include "block.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Levels of the scene's inputs (the GDAL side computes them from an
     * elevation model, wm_drape.c). Borrowed, read-only.
     */
    typedef struct
    {
        const double *za, *zb;    /**< per river segment: the level at its
                                       a and b ends */
        const double *tk, *zk;    /**< per river segment: a knee, the
                                       level zk at parameter tk (where it
                                       crosses a lake's shore; tk = 1,
                                       zk = zb where it crosses none) */
        const int32_t *poly_body; /**< per lake polygon: its water body */
        const double *body_level; /**< per body: its one level */
    } wm_drape;

    /**
     * Sets res->z (one height per point of res->rings, then of res->xpts,
     * owned by res), res->zgrad (its gradient: 0 in a lake, along the axis
     * in a river, so a pure function of position too) and
     * res->poly_body (per polygon: the lowest body whose level one of its
     * points took, or -1).
     *
     * Rule, a pure function of the point's global position and the scene,
     * so both blocks sharing a side give its vertices the same height:
     *  - a point inside a lake polygon (even-odd) takes the level of its
     *    body (the lowest body index where several contain it): lakes are
     *    flat to the bit;
     *  - any other point takes the level of the item nearest in the field's
     *    terms (|p - seg| - r for a river segment, the distance to a lake
     *    edge), ties to lakes, then to the lower index: a lake's body
     *    level, or the segment's levels interpolated (through its knee)
     *    at the projection of the point on its axis, so a river is level
     *    bank to bank.
     * Items are searched within WM_DRAPE_NEAR of their capsule or edge (then
     * among all the block's items), which holds every output vertex: they
     * lie in water or within SIMPLIFY of the boundary.
     *
     * @return WM_OK, or WM_ERR_NOMEM (res is then unchanged)
     */
    wm_status wm_drape_block(const wm_scene *s, const wm_drape *d,
                             wm_block_result *res);

/** How far beyond a capsule or lake edge the nearest-item search looks,
 *  lattice units (2 pixels). */
#define WM_DRAPE_NEAR (2 * WM_Q)

#ifdef __cplusplus
}
#endif

#endif /* WM_DRAPE_H */
