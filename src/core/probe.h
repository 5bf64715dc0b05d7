/*
 * probe.h - the signed distance to the union of a block's inputs at any
 * point, evaluated directly from the inputs (not from the sampled field).
 */
#ifndef WM_PROBE_H
#define WM_PROBE_H

#include "field.h"
#include "scene.h"

#ifdef __cplusplus
extern "C"
{
#endif

/** The farthest reach a probe serves, lattice units (4 pixels). */
#define WM_PROBE_REACH (4.0 * WM_Q)

    /**
     * The inputs in reach of one block, with an index of its river segments
     * by cell (16 pixels, or 8 or 4 in a block of many items). The inputs
     * and indexes are read-only after wm_probe_init; what the block's
     * stages find once and share (corners, rebuilt cells) and the query
     * scratch are written later.
     */
    /** A lake edge of a probe: scene edge e of polygon slot k (an index
     *  into the probe's polys). */
    struct wm_probe_edge
    {
        uint32_t e;
        uint32_t k;
    };
    struct wm_probe_toggle;

    typedef struct
    {
        const wm_scene *s;
        int64_t X0, Y0;       /**< block origin, global lattice */
        uint32_t *ids;        /**< the block's items (owned): segs, polys */
        const uint32_t *segs; /**< the block's river segments, in ids */
        size_t nsegs;
        const uint32_t *polys; /**< the block's lake polygons, in ids */
        size_t npolys;
        /** river segments by cell of the block, each registered in the
         *  cells its box grown by radius + WM_PROBE_REACH touches; segments
         *  touching too many cells are in `wide` instead (owned) */
        wm_cells cells;
        int32_t cell; /**< the indexes' cell side, lattice units */
        uint32_t *wide;
        size_t nwide;
        /* lake edges of the block's polygons, built by wm_probe_init:
         * `ledge` (owned) lists them as (edge, polygon slot k);
         * `lcells` by cell as the rivers (within reach), `lwide` those
         * touching too many cells, `lrows` by band of 4 sample rows (those
         * whose half-open y range meets the band: the ray crossings) */
        struct wm_probe_edge *ledge;
        size_t nledge;
        wm_cells lcells, lrows;
        uint32_t *lwide;
        size_t nlwide;
        /** the exact crossings of two input boundaries strictly inside the
         *  block, near the boundary, lattice-snapped, sorted, distinct
         *  (owned; found once by wm_corners_find) */
        wm_pt *corner;
        /* per corner: 1 when every crossing found there is of one segment
         *  or two sharing an end (a bend, lines meeting end to end), 0
         *  when not (owned, as `corner`) */
        uint8_t *corner_joint;
        size_t ncorner;
        int corners_found;
        /** the cells whose ring edges may come from exact crossings (the
         *  ambiguous cells, their neighbours, and both cells of each edge
         *  listed with one crossing), as sorted wm_field_cell_key()s:
         *  there the ring may not be what wm_contour_cell_edge()
         *  interpolates (owned; set by wm_contour_extract_probed, read by
         *  crease.c) */
        uint64_t *rebuilt;
        size_t nrebuilt;
        /* scratch of a query (owned): per polygon slot, and growable lists */
        uint8_t *par;
        double *dmin;
        uint32_t *touched;
        double *iv; /* water intervals, pairs */
        size_t ivcap;
        double *dv; /* lake edges along the query's segment, pairs */
        size_t ndv, dvcap;
        struct wm_probe_toggle *tg;
        size_t tgcap;
    } wm_probe;

    /** Whether cell (c, r) of block field f is in p->rebuilt. */
    int wm_probe_rebuilt(const wm_probe *p, const wm_field *f, int32_t c,
                         int32_t r);

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
    double wm_probe_distance(wm_probe *p, double x, double y, double reach);

    /** Distance (lattice units) from the block-local point (x, y) to the
     *  segment with global lattice ends a, b; the differences of
     *  coordinates are formed before any rounding. */
    double wm_probe_seg_dist(const wm_probe *p, int64_t ax, int64_t ay,
                             int64_t bx, int64_t by, double x, double y);

    /**
     * The crossings of the union's boundary with the open axis-aligned
     * lattice segment from block-local P, of length L > 0 lattice units,
     * along +x (vertical == 0) or +y, computed exactly from the inputs: the
     * water intervals of the river capsules and of the lake polygons (even-
     * odd, the half-open ray rule of the field) are merged. The class at P
     * is taken as cls0 and at the far end as *cls1 (1: water), the classes
     * the caller already gave those points (the field's, or a neighbouring
     * segment's): a crossing the rounding puts on an end, or that disagrees
     * with them, is dropped, and so is a pair of crossings closer than a
     * lattice unit (a feature the lattice does not resolve). With *cls1 < 0
     * the far end's class is the inputs', and is written to *cls1.
     * Writes to off[] the crossings' offsets from P, strictly increasing in
     * 1 .. L - 1, at most `max` (beyond that the list is cut to an even or
     * odd count matching the classes), and returns how many; their count is
     * odd exactly when cls0 != *cls1. Uses only global integer differences
     * before floating point, so the result is a pure function of the
     * segment's global position and the inputs: the two blocks sharing a
     * segment of their square find the same crossings. Returns -1 when out
     * of memory.
     */
    int wm_probe_crossings(wm_probe *p, wm_pt P, int vertical, int32_t L,
                           int cls0, int *cls1, int32_t *off, int max);

    /**
     * The interval [*lo, *hi] of the line through global lattice point
     * (Gx, Gy) along +x (vertical == 0) or +y, as offsets from it, inside
     * the capsule of g (double precision); returns 0 when the line misses
     * it.
     */
    int wm_probe_capsule_interval(const wm_river_seg *g, int64_t Gx, int64_t Gy,
                                  int vertical, double *lo, double *hi);

    /** Items of a probe's index: a[0 .. na) then b[0 .. nb). */
    typedef struct
    {
        const uint32_t *a;
        size_t na;
        const uint32_t *b;
        size_t nb;
    } wm_probe_items;

    /** The river segments (indices into the scene's segs) that may come
     *  within WM_PROBE_REACH of block-local point (x, y), and others. */
    void wm_probe_rivers_near(const wm_probe *p, double x, double y,
                              wm_probe_items *it);

    /** The lake edges (indices into p->ledge) that may come within
     *  WM_PROBE_REACH of block-local point (x, y), and others. */
    void wm_probe_lake_edges_near(const wm_probe *p, double x, double y,
                                  wm_probe_items *it);

    /** The lake edges (indices into p->ledge) that the ray from any point
     *  of local row y towards +x may cross (wm_edge_crosses_ray), and
     *  others. */
    void wm_probe_lake_edges_ray(const wm_probe *p, double y,
                                 wm_probe_items *it);

    /**
     * The least radius (lattice units) of the river capsules that may come
     * within reach of the block-local box [x0, x1] x [y0, y1] (inside the
     * block square), or, with lakes set, 0 when a lake edge may (a lake's
     * corners are sharp); INFINITY when nothing does. Read from the
     * indexes, which register an item in every cell its reach touches: a
     * lower bound, never more than the true least radius.
     */
    double wm_probe_min_radius(const wm_probe *p, int32_t x0, int32_t y0,
                               int32_t x1, int32_t y1, int lakes);

#ifdef __cplusplus
}
#endif

#endif /* WM_PROBE_H */
