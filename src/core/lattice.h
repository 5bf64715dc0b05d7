/*
 * lattice.h - exact integer predicates on block-local lattice points.
 *
 * Every geometric decision after extraction (orientation, segment
 * intersection, point in ring, in-circle) is taken here, in integers:
 * coordinates are at most WM_LOCAL_MAX (2^24) in magnitude, offsets by a
 * few times that (CDT super-triangle) stay below 2^27, so
 *   - orientation: products of differences < 2^56, sums fit int64;
 *   - in-circle:   terms of degree 4 < 2^112, sums fit __int128.
 * No epsilon anywhere: a predicate is either exact or not used.
 */
#ifndef WM_LATTICE_H
#define WM_LATTICE_H

#include "wm_core.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /** Sign of the orientation of (a, b, c): +1 counter-clockwise (c left of
     *  a->b), -1 clockwise, 0 collinear. */
    static inline int wm_orient(wm_pt a, wm_pt b, wm_pt c)
    {
        const int64_t det = (int64_t)(b.x - a.x) * (int64_t)(c.y - a.y) -
                            (int64_t)(b.y - a.y) * (int64_t)(c.x - a.x);
        return (det > 0) - (det < 0);
    }

    /** Signed double area of (a, b, c), exact. */
    static inline int64_t wm_orient_det(wm_pt a, wm_pt b, wm_pt c)
    {
        return (int64_t)(b.x - a.x) * (int64_t)(c.y - a.y) -
               (int64_t)(b.y - a.y) * (int64_t)(c.x - a.x);
    }

    static inline int wm_pt_eq(wm_pt a, wm_pt b)
    {
        return a.x == b.x && a.y == b.y;
    }

    /** A point as one 64-bit key, x in the high half (equal keys, equal
     *  points). */
    static inline uint64_t wm_pt_key(wm_pt p)
    {
        return (uint64_t)(uint32_t)p.x << 32 | (uint32_t)p.y;
    }

    /** Key k mixed (MurmurHash3's finalizer, its first half) into a slot of
     *  an open-addressing table of mask + 1 slots (a power of two). */
    static inline size_t wm_hash64(uint64_t k, size_t mask)
    {
        k ^= k >> 33;
        k *= UINT64_C(0xff51afd7ed558ccd);
        k ^= k >> 33;
        return (size_t)k & mask;
    }

    /** Lexicographic order of points (x, then y): -1, 0 or 1. */
    static inline int wm_pt_cmp(wm_pt a, wm_pt b)
    {
        if (a.x != b.x)
            return a.x < b.x ? -1 : 1;
        return (a.y > b.y) - (a.y < b.y);
    }

    /** True when p lies on the closed segment [a, b] (p collinear with it and
     *  inside its bounding box). */
    static inline int wm_on_segment(wm_pt a, wm_pt b, wm_pt p)
    {
        if (wm_orient(a, b, p) != 0)
            return 0;
        return (p.x >= (a.x < b.x ? a.x : b.x)) &&
               (p.x <= (a.x > b.x ? a.x : b.x)) &&
               (p.y >= (a.y < b.y ? a.y : b.y)) &&
               (p.y <= (a.y > b.y ? a.y : b.y));
    }

    /** True when the closed segments [a, b] and [c, d] share at least one point
     *  (proper crossing, touching, or collinear overlap). */
    static inline int wm_segments_meet(wm_pt a, wm_pt b, wm_pt c, wm_pt d)
    {
        const int o1 = wm_orient(a, b, c), o2 = wm_orient(a, b, d);
        const int o3 = wm_orient(c, d, a), o4 = wm_orient(c, d, b);
        if (o1 != o2 && o3 != o4 && o1 * o2 <= 0 && o3 * o4 <= 0)
        {
            if (o1 != 0 || o2 != 0)
                return 1;
        }
        return wm_on_segment(a, b, c) || wm_on_segment(a, b, d) ||
               wm_on_segment(c, d, a) || wm_on_segment(c, d, b);
    }

    /** In-circle test: > 0 when d lies strictly inside the circle through the
     *  counter-clockwise triangle (a, b, c), < 0 outside, 0 on it. Exact for
     *  coordinates below 2^27 in magnitude. */
    static inline int wm_incircle(wm_pt a, wm_pt b, wm_pt c, wm_pt d)
    {
        const int64_t adx = (int64_t)a.x - d.x, ady = (int64_t)a.y - d.y;
        const int64_t bdx = (int64_t)b.x - d.x, bdy = (int64_t)b.y - d.y;
        const int64_t cdx = (int64_t)c.x - d.x, cdy = (int64_t)c.y - d.y;
        const wm_i128 alift = (wm_i128)(adx * adx + ady * ady);
        const wm_i128 blift = (wm_i128)(bdx * bdx + bdy * bdy);
        const wm_i128 clift = (wm_i128)(cdx * cdx + cdy * cdy);
        const wm_i128 det = alift * (wm_i128)(bdx * cdy - bdy * cdx) +
                            blift * (wm_i128)(cdx * ady - cdy * adx) +
                            clift * (wm_i128)(adx * bdy - ady * bdx);
        return (det > 0) - (det < 0);
    }

    /** Squared distance from p to the segment [a, b], compared exactly against
     *  a squared tolerance: returns 1 when dist(p, [a,b])^2 > tol2.
     *  Used by Douglas-Peucker; tol2 is in squared lattice units. */
    int wm_seg_dist2_exceeds(wm_pt a, wm_pt b, wm_pt p, wm_i128 tol2);

    /** Point in ring by crossing parity (even-odd), exact.
     *  Returns 1 inside, 0 outside, -1 when p lies on the ring's boundary. */
    int wm_point_in_ring(const wm_pt *ring, size_t n, wm_pt p);

#ifdef __cplusplus
}
#endif

#endif /* WM_LATTICE_H */
