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

/** Two boundaries closer than this (lattice units) are one: two inputs
 *  sharing it, or the rounding of the inputs to the lattice (a bank on a
 *  block line at 0.3 m pixels lies 1e-13 pixel off it). probe.c merges
 *  such crossings along a segment; field.c settles samples so near a
 *  block line's boundary as on it. */
#define WM_COINCIDE 1e-6

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

    /** Whether global lattice point (X, Y) lies on lake edge g (exact in
     *  __int128): its distance is 0 there, and a lake's boundary is water. */
    static inline int wm_edge_holds(const wm_lake_edge *g, int64_t X, int64_t Y)
    {
        const wm_i128 ux = g->bx - g->ax, uy = g->by - g->ay;
        const wm_i128 px = X - g->ax, py = Y - g->ay;
        if (ux * py != uy * px)
            return 0;
        const wm_i128 dot = ux * px + uy * py;
        return dot >= 0 && dot <= ux * ux + uy * uy;
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
     * Lake polygons' edges by band of rows, per polygon: a point-in-polygon
     * test reads only the edges whose y range meets the point's band, a
     * distance query the bands near the point, a segment's crossings the
     * bands it spans. Polygon k of the index is s's polygon poly[k]. Band b
     * of polygon k (band0[k] <= b < band0[k + 1]) holds the edges
     * edge[start[b] .. start[b + 1] - 1] (indices into s->edges) whose
     * closed y range meets its rows; about 8 edges per band, fewer bands
     * where long edges would be registered more than 16 times their number.
     * A polygon's bands depend on its edges alone.
     */
    typedef struct
    {
        const wm_scene *s;
        const uint32_t *poly; /**< npolys polygon indices into s (borrowed),
                                   or NULL for every polygon of s */
        size_t npolys;
        size_t *band0; /**< npolys + 1 (owned) */
        int64_t *bh;   /**< band height per polygon, lattice (owned) */
        size_t *start; /**< bands + 1 (owned) */
        size_t *edge;  /**< (owned) */
    } wm_lake_bands;

    /** Builds the bands of polygons poly[0 .. npolys - 1] of s (poly NULL:
     *  all of s's polygons; npolys is then ignored). WM_ERR_NOMEM (lb freed)
     *  or WM_OK; free with wm_lake_bands_free(). */
    wm_status wm_lake_bands_build(wm_lake_bands *lb, const wm_scene *s,
                                  const uint32_t *poly, size_t npolys);

    /** Frees what lb owns; lb may be zeroed. */
    void wm_lake_bands_free(wm_lake_bands *lb);

    /** The band of polygon k holding row y (clamped to its bands). */
    size_t wm_lake_bands_of(const wm_lake_bands *lb, size_t k, int64_t y);

    /** Even-odd parity of global point (X, Y) in polygon k (the field's
     *  half-open ray rule, exact). */
    int wm_lake_bands_inside(const wm_lake_bands *lb, size_t k, int64_t X,
                             int64_t Y);

    /**
     * How deep global point (X, Y) lies in the water of river segments
     * segs[] and of the polygons of `lakes` (NULL: none), capped at `cap`:
     * the largest, over the items holding the point, of its distance to that
     * item's boundary (a capsule's r - |p - seg|, a polygon's distance to
     * its nearest edge where its parity is 1), or cap when that is larger;
     * 0 when none holds it. Lattice units. No point of the union's boundary
     * is nearer to (X, Y) (a lower bound of the distance to the dissolved
     * shore). Double arithmetic on exact lattice differences; a polygon's
     * distance reads its bands outward from the point's, so the cost grows
     * with the edges near the point. A pure function of the point, cap and
     * the items holding it: two blocks passing different supersets of
     * those items get the same bits.
     */
    double wm_scene_depth(const wm_scene *s, const uint32_t *segs, size_t nsegs,
                          const wm_lake_bands *lakes, int64_t X, int64_t Y,
                          double cap);

    /** Global lattice box of block (bx, by), samples included. */
    wm_box wm_scene_block_box(const wm_scene *s, int64_t bx, int64_t by);

#ifdef __cplusplus
}
#endif

#endif /* WM_SCENE_H */
