/*
 * cdt.h - constrained Delaunay triangulation of a polygon with holes.
 */
#ifndef WM_CDT_H
#define WM_CDT_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Triangulates one polygon: ring 0 of the input is the outer ring
     * (counter-clockwise), rings 1.. are its holes (clockwise), all simple,
     * pairwise disjoint, holes strictly inside the outer ring; coordinates in
     * [0, WM_LOCAL_MAX]. The result is the constrained Delaunay triangulation:
     * every ring edge is a triangle edge, no vertex is added, and every other
     * edge is locally Delaunay (exact in-circle test).
     *
     * @param pts        vertices, rings concatenated
     * @param ring_start nrings + 1 offsets into pts (as in wm_rings)
     * @param nrings     1 + number of holes
     * @param tris       out: 3 * *ntris vertex indices into pts, each triangle
     *                   counter-clockwise; caller frees with free()
     * @param ntris      out: npts + 2 * (nrings - 1) - 2 triangles
     * @return WM_OK, WM_ERR_NOMEM, WM_ERR_INVALID (contract broken, e.g.
     *         a constraint edge crossing another), WM_ERR_INTERNAL
     */
    wm_status wm_cdt_triangulate(const wm_pt *pts, const size_t *ring_start,
                                 size_t nrings, uint32_t **tris, size_t *ntris,
                                 const wm_ctx *ctx);

    /**
     * wm_cdt_triangulate with `nextra` more vertices after the rings'
     * (pts[ring_start[nrings] ..]), each strictly inside the polygon and
     * on no ring edge, distinct from every other vertex: the constrained
     * Delaunay triangulation of the polygon and those points (Steiner
     * points, refine.c). *ntris is then npts + 2 * (nrings - 1) - 2 +
     * 2 * nextra, and WM_ERR_INVALID also says an extra point is not
     * strictly inside.
     */
    wm_status wm_cdt_triangulate_ex(const wm_pt *pts, const size_t *ring_start,
                                    size_t nrings, size_t nextra,
                                    uint32_t **tris, size_t *ntris,
                                    const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_CDT_H */
