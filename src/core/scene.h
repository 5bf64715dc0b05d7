/*
 * scene.h - the core's view of the input: river segments and lake edges on
 * the global integer lattice, and the global block grid.
 *
 * Lattice (DESIGN invariant 2): every input coordinate is quantized once to
 * int64 units of PIXEL_SIZE / Q (Q = WM_Q = 256, a power of two so that the
 * sample spacing is an exact integer and sub-pixel crossings have 8 bits).
 * Sample (gx, gy) of the global grid sits at lattice (gx * Q, gy * Q); block
 * (bx, by) owns samples bx*N .. (bx+1)*N inclusive in x (likewise y), so
 * neighbours share their border samples (invariant 1).
 *
 * The GDAL side fills a wm_scene (scene ingestion) and the core only reads it.
 */
#ifndef WM_SCENE_H
#define WM_SCENE_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

/** Lattice units per pixel. Why 256: sub-pixel crossings keep 8 bits, and
 *  a 65536-pixel block stays within 2^24 local units (see lattice.h). */
#define WM_Q 256

    /** Floor division (rounds towards -infinity), b > 0. Block and tile
     *  indices of negative coordinates need it. */
    static inline int64_t wm_floordiv(int64_t a, int64_t b)
    {
        const int64_t q = a / b;
        return (a % b != 0 && a < 0) ? q - 1 : q;
    }

    /** A river segment: a capsule of radius r around [a, b]. */
    typedef struct
    {
        int64_t ax, ay, bx, by; /**< global lattice */
        double r;               /**< radius in lattice units (width / 2) */
    } wm_river_seg;

    /** A lake edge; edges of one polygon are contiguous in wm_scene.edges. */
    typedef struct
    {
        int64_t ax, ay, bx, by; /**< global lattice */
    } wm_lake_edge;

    /** An axis-aligned box in global lattice units, inclusive. */
    typedef struct
    {
        int64_t x0, y0, x1, y1;
    } wm_box;

    /**
     * The scene. Lake polygons are filled even-odd over all their rings (outer
     * and holes alike, so ring orientation in the input does not matter and a
     * bowtie fills both lobes); polygons union with each other and with the
     * rivers by taking the minimum of signed distances (invariant 5).
     */
    typedef struct
    {
        wm_river_seg *segs; /**< river segments (owned) */
        size_t nsegs;
        wm_lake_edge *edges; /**< lake edges, grouped by polygon (owned) */
        size_t nedges;
        size_t *poly_start; /**< npolys + 1 offsets into edges (owned) */
        wm_box *poly_box;   /**< per polygon: bbox of its edges (owned; set
                               by wm_scene_index) */
        size_t npolys;

        int32_t n;    /**< samples per block side minus one: BLOCK/PIXEL */
        int32_t band; /**< clamp band in pixels: |field| <= band */
        double max_r; /**< largest river radius, lattice units */

        /* block grid covering everything within reach of the input */
        int64_t bx0, by0; /**< first block index */
        int64_t nbx, nby; /**< number of blocks */
        /* per block (row-major, by * nbx + bx): river segments and polygons
         * within reach, as CSR arrays (owned) */
        size_t *blk_seg_start;
        uint32_t *blk_seg;
        size_t *blk_poly_start;
        uint32_t *blk_poly;

        size_t river_vertices; /**< input counts, for the vertex ratio V */
        size_t lake_vertices;
    } wm_scene;

    /** Builds the polygon boxes, the block range and the per-block index from
     *  segs, edges, poly_start, npolys, n and band (the caller fills those;
     * every polygon has at least one edge). */
    wm_status wm_scene_index(wm_scene *s, const wm_ctx *ctx);

    /** Frees everything the scene owns; s may be NULL. */
    void wm_scene_free(wm_scene *s);

    /** Global lattice box of block (bx, by), samples included. */
    wm_box wm_scene_block_box(const wm_scene *s, int64_t bx, int64_t by);

#ifdef __cplusplus
}
#endif

#endif /* WM_SCENE_H */
