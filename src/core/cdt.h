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

    /** A constrained Delaunay triangulation kept for more points. */
    typedef struct wm_cdt wm_cdt;

    /**
     * wm_cdt_triangulate_ex that also keeps the triangulation in *cdt (when
     * cdt is not NULL; free it with wm_cdt_free) for wm_cdt_insert, and
     * gives (when nb is not NULL) the neighbours: (*nb)[3t + i] is the
     * half-edge 3u + j of the triangle u across edge i (from vertex i to
     * i + 1) of triangle t, or -1 across a ring edge; free() it.
     */
    wm_status wm_cdt_open(const wm_pt *pts, const size_t *ring_start,
                          size_t nrings, size_t nextra, wm_cdt **cdt,
                          uint32_t **tris, size_t *ntris, int32_t **nb,
                          const wm_ctx *ctx);

    /**
     * Inserts n more points, each strictly inside the polygon, on no ring
     * edge and distinct from every vertex (Lawson flips keep it constrained
     * Delaunay), numbered after the vertices so far, and gives all the
     * triangles (and neighbours) as wm_cdt_open does. The result is the CDT of
     * the same point set wm_cdt_triangulate_ex would triangulate, but
     * where four points are cocircular it may pick the other diagonal.
     * On an error (WM_ERR_INVALID: a point breaks the contract) the
     * triangulation is unusable: free it.
     */
    wm_status wm_cdt_insert(wm_cdt *cdt, const wm_pt *pts, size_t n,
                            uint32_t **tris, size_t *ntris, int32_t **nb,
                            const wm_ctx *ctx);

    /**
     * Replaces ring edge a-b of cdt (a then b along their ring) by a-q-b,
     * where q is a point strictly inside already (*q its number) or, with
     * *q == UINT32_MAX, point p, inserted and numbered next (set in *q).
     * p may lie off the edge (a midpoint rounded to the lattice) on either
     * side, but the new edges must cross no ring edge. The next
     * wm_cdt_insert labels the triangles inside the new rings. Errors as
     * wm_cdt_insert's.
     */
    wm_status wm_cdt_split(wm_cdt *cdt, uint32_t a, uint32_t b, wm_pt p,
                           uint32_t *q, const wm_ctx *ctx);

    void wm_cdt_free(wm_cdt *cdt);

#ifdef __cplusplus
}
#endif

#endif /* WM_CDT_H */
