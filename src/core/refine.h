/*
 * refine.h - quality triangulation of a block's polygon: Steiner points so
 * that triangles meet a minimum angle and a maximum edge length.
 */
#ifndef WM_REFINE_H
#define WM_REFINE_H

#include "simplify.h"
#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /** The ends of a block's water along its square: per side (bottom,
     *  right, top, left), the ends of the ring edges lying on it,
     *  block-local positions along the side, ascending (a position shared
     *  by two edges is kept twice). The blocks on both sides of a shared
     *  side hold the same water there, so the same ends. */
    typedef struct
    {
        uint64_t *at[4];
        size_t n[4];
    } wm_side_ends;

    /** Collects the ends of every ring (all of a block's polygons) on the
     *  square of side `side`. 0 when out of memory. */
    int wm_side_ends_build(wm_side_ends *e, const wm_rings *rings,
                           int32_t side);
    void wm_side_ends_free(wm_side_ends *e);

    /** What to refine to. */
    typedef struct
    {
        double min_angle; /**< degrees; 0: no angle criterion */
        double max_edge;  /**< lattice units; 0: no length criterion */
        int32_t side;     /**< the block square's side, lattice units */
        int64_t X0, Y0;   /**< the block's origin, global lattice */
        /** with min_angle: the room around global point (X, Y) of the
         *  block square, lattice units, or cap when it is larger; a pure
         *  function of the point and cap (so the blocks on both sides
         *  agree): no shore lies nearer. NULL: block-square edges are not
         *  graded (only max_edge cuts them) */
        double (*room)(void *user, int64_t X, int64_t Y, double cap);
        void *room_user;
        /** with room: the block's water along its square (every polygon's),
         *  which bounds the pieces at a side edge's end by the land gap to
         *  the next water along the side, or to the block corner; NULL: no
         *  such bound */
        const wm_side_ends *ends;
        /** with room: SIMPLIFY, lattice units (below a quarter pixel the
         *  pieces at a side edge's ends are graded shorter) */
        double simplify;
    } wm_refine_opts;

    /** What refining left undone (statistics, summed over polygons). */
    typedef struct
    {
        size_t steiner;     /**< points added (inside and on the shore) */
        size_t small_input; /**< triangles below min_angle at an angle
                                 between two ring edges (an input angle) */
        size_t left;        /**< other triangles still below min_angle or
                                 with an edge over max_edge */
        size_t at_side;     /**< of left: below min_angle with a vertex on
                                 the block square, whose edges refinement
                                 may not split */
    } wm_refine_stats;

    /**
     * The pieces every ring edge of `rings` on the block square is cut into
     * by the rule wm_refine_triangulate applies (below), with the same o
     * (o->ends built from rings with the same side edges: simplification
     * keeps every vertex on the square, so raw and simplified rings
     * qualify).
     * They are what refinement may not split; simplification keeps the
     * shore out of their diametral circles (wm_simplify_rings_guarded).
     * Returns 0 when out of memory; *out is free()d by the caller.
     */
    int wm_side_pieces(const wm_rings *rings, const wm_refine_opts *o,
                       wm_side_piece **out, size_t *n);

    /**
     * Triangulates one polygon as wm_cdt_triangulate does (same contract
     * for pts, ring_start, nrings), then refines it (Ruppert 1995, with
     * Shewchuk's "Delaunay refinement" rules): a triangle whose smallest
     * angle is below min_angle, or whose longest edge is over max_edge,
     * gets its circumcentre (rounded to the lattice) as a new vertex,
     * unless that point lies across a ring edge or inside the diametral
     * circle of one; then that ring edge is split at its midpoint (rounded
     * to the lattice, so the shore moves by at most half a lattice unit).
     * Ring edges on the block square are never split while refining: a
     * neighbour block could not know. They are cut beforehand by rules both
     * blocks sharing the side apply alike (so there is no T-junction): with
     * max_edge, at the global lattice multiples of max_edge along the side;
     * with min_angle and o->room, each piece is halved (at its global
     * midpoint, rounded down) while it is longer than 256 pixels, or than
     * its room at that midpoint and than 8 pixels at an end of the side
     * edge (32 times o->simplify when that is less, down to a pixel; half
     * the land gap to the next water along the side, or twice the land to
     * a block corner with no water beyond, where that is less, down to
     * 1/16 pixel: o->ends; at a block corner, the room at the
     * corner where that is less, down to 1/16 pixel; and no end limit
     * where the room does not rise from the end to the midpoint) or 1/16
     * pixel elsewhere: no point of the inputs' shore then lies within half
     * the room of its diametral circle, so refinement next to the side
     * seldom needs to split it (the extracted shore lies within about a
     * pixel and SIMPLIFY of the inputs'); then, while a piece is more than
     * four times as long as a neighbour (or, at a block corner, than 16
     * pixels: four times 4 pixels assumed beyond it, or the room at the
     * corner where that is less), it is halved too. Rounds of batch
     * insertion (into the triangulation kept from the round before:
     * wm_cdt_insert, wm_cdt_split) repeat until nothing is bad or a round
     * changes nothing; bounds on rounds and points stop a run that does not
     * converge (then `left` counts what remains).
     *
     * Guarantee (Ruppert, exact arithmetic): min_angle up to 20.7 degrees
     * is met when no input angle is below 60 degrees. Here triangles at an
     * input angle below min_angle are left (small_input), refinement near
     * input angles below 60 degrees (a shore meeting the block square at an
     * acute angle makes one) may cascade until the bounds on rounds and
     * points stop it, or leave triangles whose circumcentre would split a
     * block-square edge; `left` counts those, and what the lattice
     * rounding leaves.
     *
     * @param tris   out: 3 * *ntris indices into the input points followed
     *               by *extra (index npts + k is (*extra)[k]); free() it
     * @param extra  out: the added points (*nextra), block-local; free() it
     * @return WM_OK, WM_ERR_NOMEM, or wm_cdt_triangulate's errors for the
     *         input polygon (a refined polygon the CDT refuses ends the
     *         refinement with the last good triangulation)
     */
    wm_status wm_refine_triangulate(const wm_pt *pts, const size_t *ring_start,
                                    size_t nrings, const wm_refine_opts *o,
                                    uint32_t **tris, size_t *ntris,
                                    wm_pt **extra, size_t *nextra,
                                    wm_refine_stats *stats, const wm_ctx *ctx);

#ifdef __cplusplus
}
#endif

#endif /* WM_REFINE_H */
