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

    /** Whether lake edge g crosses the ray from (X, Y) to +x: the field's
     *  even-odd rule (half-open in y, so a vertex on the ray counts once),
     *  exact in __int128. */
    static inline int wm_edge_crosses_ray(const wm_lake_edge *g, int64_t X,
                                          int64_t Y)
    {
        if ((g->ay <= Y) == (g->by <= Y))
            return 0;
        /* crossing x > X: (bx - ax)(Y - ay) > (X - ax)(by - ay), by > ay */
        const wm_i128 l = (wm_i128)(g->bx - g->ax) * (Y - g->ay);
        const wm_i128 r = (wm_i128)(X - g->ax) * (g->by - g->ay);
        return g->by > g->ay ? l > r : l < r;
    }

    /** An axis-aligned box in global lattice units, inclusive. */
    typedef struct
    {
        int64_t x0, y0, x1, y1;
    } wm_box;

/** Children per node of the reach R-tree. */
#define WM_RTREE_FANOUT 16
/** Levels the reach R-tree may have (16^15 leaves and more). */
#define WM_RTREE_LEVELS 16

    /** A static R-tree of boxes, packed in Hilbert order of their centres
     *  (as FlatGeobuf's index): level 0 holds the leaves, level l + 1 one
     *  node per WM_RTREE_FANOUT consecutive nodes of level l; the root is
     *  the one node of the top level. */
    typedef struct
    {
        wm_box *box;    /**< every level's boxes, leaves first (owned) */
        uint32_t *item; /**< per leaf: the item it holds (owned) */
        size_t level[WM_RTREE_LEVELS + 1]; /**< level l is box[level[l] ..
                                              level[l + 1] - 1] */
        int nlevels;                       /**< 0 when empty */
    } wm_rtree;

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
        wm_box water;     /**< box of the water (the capsules and polygons),
                             global lattice; valid when nbx > 0 */
        /** which blocks each item (river segments, then lake polygons)
         *  reaches, as a block range, in a packed R-tree: building and
         *  memory grow with the input, never with the grid's area */
        wm_rtree reach;

        size_t river_vertices; /**< input counts, for the vertex ratio V */
        size_t lake_vertices;
    } wm_scene;

    /** Builds the polygon boxes, the block range and the reach index from
     *  segs, edges, poly_start, npolys, n and band (the caller fills those;
     * every polygon has at least one edge). */
    wm_status wm_scene_index(wm_scene *s, const wm_ctx *ctx);

    /**
     * The items within reach of any block of `blocks` (block indices,
     * inclusive): ids[0 .. *nsegs - 1] are river segments, then *npolys lake
     * polygons, each part ascending and without repeats. *ids is the
     * caller's to free (NULL when there is none).
     */
    wm_status wm_scene_items(const wm_scene *s, wm_box blocks, uint32_t **ids,
                             size_t *nsegs, size_t *npolys);

    /**
     * The blocks of row `by`, from x0 to x1, that some item reaches, as
     * *nruns runs (first, last): ascending, disjoint and not adjacent.
     * *runs is the caller's to free (NULL when there is none).
     */
    wm_status wm_scene_row_runs(const wm_scene *s, int64_t by, int64_t x0,
                                int64_t x1, int64_t **runs, size_t *nruns);

    /** Frees everything the scene owns; s may be NULL. */
    void wm_scene_free(wm_scene *s);

    /**
     * How deep global point (X, Y) lies in the water of the given items
     * (river segments segs[], lake polygons polys[], indices into s): the
     * largest, over the items holding the point, of its distance to that
     * item's boundary (a capsule's r - |p - seg|, a polygon's distance to
     * its nearest edge where its even-odd parity is 1); 0 when none holds
     * it. Lattice units. No point of the union's boundary is nearer to
     * (X, Y) than this (a lower bound of the distance to the dissolved
     * shore). A pure function of the point and the items holding it, in
     * double arithmetic on exact lattice differences: two blocks passing
     * different supersets of those items get the same bits.
     */
    double wm_scene_depth(const wm_scene *s, const uint32_t *segs, size_t nsegs,
                          const uint32_t *polys, size_t npolys, int64_t X,
                          int64_t Y);

    /** Global lattice box of block (bx, by), samples included. */
    wm_box wm_scene_block_box(const wm_scene *s, int64_t bx, int64_t by);

#ifdef __cplusplus
}
#endif

#endif /* WM_SCENE_H */
