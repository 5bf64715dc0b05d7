/*
 * leaf.h - which water arcs of a small rectangle's boundary the union of
 * the inputs joins inside it, read from the inputs themselves.
 */
#ifndef WM_LEAF_H
#define WM_LEAF_H

#include "probe.h"

#ifdef __cplusplus
extern "C"
{
#endif

/** The longest side of a rectangle wm_leaf_join reads (lattice units). */
#define WM_LEAF_SIDE 64
/** The most water arcs and inputs it reads in one rectangle. */
#define WM_LEAF_ARCS 32
#define WM_LEAF_ITEMS 64

    /**
     * Labels the water arcs of the boundary of the block-local rectangle
     * [x0, x1] x [y0, y1] by the component of the union's water inside it
     * that holds them: label[i] == label[j] exactly when the water of the
     * inputs joins arcs i and j without leaving the rectangle. The arcs are
     * given as narc pairs arc[2i], arc[2i + 1] of positions along the
     * boundary, counter-clockwise from (x0, y0) (the second may exceed the
     * perimeter when the arc wraps past that corner), in order, as the
     * caller's crossings bound them.
     *
     * Two inputs join when they overlap inside the rectangle by more than
     * WM_COINCIDE (banks that coincide do not join), or when both cover one
     * stretch of its boundary. Returns 1 when labelled; -1 when out of
     * memory; 0 when the inputs there are beyond this reading (a lake's
     * boundary entering the rectangle more than four times, or across two
     * of its rings, or holding a ring inside it; more than WM_LEAF_ITEMS
     * inputs; a side over WM_LEAF_SIDE), or when the inputs' stretches of
     * water along the boundary do not match the caller's arcs one to one,
     * each end within 2 units: the caller decides.
     */
    int wm_leaf_join(wm_probe *p, int32_t x0, int32_t y0, int32_t x1,
                     int32_t y1, int narc, const int64_t *arc, int *label);

#ifdef __cplusplus
}
#endif

#endif /* WM_LEAF_H */
