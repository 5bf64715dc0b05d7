/*
 * block.h - one block through the whole pipeline: field, extraction,
 * simplification, holes, triangulation.
 */
#ifndef WM_BLOCK_H
#define WM_BLOCK_H

#include "field.h"
#include "scene.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /** Stage indices of the timing table (the paper's Table 2 columns). */
    enum
    {
        WM_STAGE_FIELD = 0,
        WM_STAGE_EXTRACT,
        WM_STAGE_SIMPLIFY,
        WM_STAGE_HOLES,
        WM_STAGE_TRIANGULATE,
        WM_STAGE_COUNT
    };

    /** Boundary extraction. */
    typedef enum
    {
        WM_METHOD_CONTOUR = 0, /**< marching squares + crease recovery */
        WM_METHOD_PAPER        /**< the paper's classes and Border walk */
    } wm_method;

    /** Options of the block pipeline. */
    typedef struct
    {
        double simplify; /**< Douglas-Peucker tolerance, lattice units; 0 off */
        int triangulate; /**< 0: polygons only */
        const wm_field_device *dev; /**< evaluates the field; NULL: C path */
        wm_method method;
        int heuristic;    /**< a wm_heuristic (paper.h), METHOD=PAPER */
        double merge;     /**< vertex merge distance, lattice units; 0 off */
        double min_area;  /**< MIN_FEATURE_AREA, square lattice units; 0 off */
        double min_angle; /**< MIN_ANGLE, degrees; 0 off (refine.h) */
        double max_edge;  /**< MAX_EDGE, lattice units; 0 off */
    } wm_block_opts;

    /**
     * A block's result, in block-local lattice units.
     *
     * Polygon p is rings poly_ring[p] .. poly_ring[p+1]-1 of `rings`, the first
     * its outer ring (CCW), the others its holes (CW), in a deterministic
     * order. Its triangles are tris[3*poly_tri[p] .. 3*poly_tri[p+1]-1],
     * counter-clockwise, indices into rings.pts followed by xpts (the
     * Steiner points of MIN_ANGLE and MAX_EDGE): wm_block_point.
     */
    typedef struct
    {
        int64_t bx, by;
        wm_rings rings;
        size_t npolys;
        size_t *poly_ring; /**< npolys + 1 (owned) */
        size_t *poly_tri;  /**< npolys + 1 (owned) */
        uint32_t *tris;    /**< (owned) */
        wm_pt *xpts;       /**< the mesh's added points (owned; NULL: none) */
        size_t nxpts;
        size_t steiner, small_input, left, at_side; /**< refinement
                                                      (refine.h) */
        double *z;          /**< per point of rings, then of xpts: its
                                 height, or NULL
                                 without ELEVATION (owned; drape.h) */
        double *zgrad;      /**< per point: the height's gradient (dz/dx, dz/dy
                                 per lattice unit), or NULL (owned) */
        int32_t *poly_body; /**< per polygon: a lake body it holds, or -1;
                                 NULL without ELEVATION (owned) */
        double seconds[WM_STAGE_COUNT];
        size_t mixed_tiles;
        uint64_t samples, pairs;
        uint64_t contour_vertices; /**< of the extracted rings, before
                                      corners are put back: about the cells
                                      the boundary crosses (statistics) */
    } wm_block_result;

    /** Runs block (bx, by); `res` is overwritten (free with
     *  wm_block_result_free()). Same as wm_block_field + wm_block_finish. */
    wm_status wm_block_run(const wm_scene *s, int64_t bx, int64_t by,
                           const wm_block_opts *opts, wm_block_result *res,
                           const wm_ctx *ctx);

    /** The first stage alone: the field of block (bx, by) (free it with
     *  wm_field_free(), or hand it to wm_block_finish). A runner computes
     *  the next block's field on a device while the CPU finishes this one. */
    wm_status wm_block_field(const wm_scene *s, int64_t bx, int64_t by,
                             const wm_block_opts *opts, wm_field *f,
                             const wm_ctx *ctx);

    /** The other stages of block (bx, by) from its field, which it frees.
     *  `res` is overwritten; its field time is left 0 for the caller. */
    wm_status wm_block_finish(const wm_scene *s, int64_t bx, int64_t by,
                              wm_field *f, const wm_block_opts *opts,
                              wm_block_result *res, const wm_ctx *ctx);

    void wm_block_result_free(wm_block_result *res);

    /** Point i of a result's mesh: rings.pts, then xpts. */
    static inline wm_pt wm_block_point(const wm_block_result *r, size_t i)
    {
        return i < r->rings.npts ? r->rings.pts[i] : r->xpts[i - r->rings.npts];
    }

    /** Points a result's triangles index: rings.npts + nxpts. */
    static inline size_t wm_block_npoints(const wm_block_result *r)
    {
        return r->rings.npts + r->nxpts;
    }

    /** Monotonic clock in seconds. */
    double wm_now(void);

#ifdef __cplusplus
}
#endif

#endif /* WM_BLOCK_H */
