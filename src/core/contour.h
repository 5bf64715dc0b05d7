/*
 * contour.h - water boundary of a block by marching squares.
 */
#ifndef WM_CONTOUR_H
#define WM_CONTOUR_H

#include "field.h"
#include "probe.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /**
     * Extracts the boundary of the water region {d <= 0} of a block's field,
     * clipped exactly to the block square, as rings in block-local lattice
     * units (sample (c, r) of the block at (c * WM_Q, r * WM_Q)).
     *
     * The field must cover the block's (n+1) x (n+1) samples (f->w == f->h ==
     * n + 1). `out` is cleared first; caller frees with wm_rings_free().
     *
     * Guarantees: the wm_rings invariants (simple, disjoint, >= 3 vertices,
     * water on the left). The only vertices on the block square are the
     * crossings of the boundary with it and the square's corners that are
     * water; crossing positions depend only on the two samples of their cell
     * edge, so both blocks sharing an edge produce the same vertices there.
     */
    wm_status wm_contour_extract(const wm_field *f, wm_rings *out,
                                 const wm_ctx *ctx);

    /**
     * wm_contour_extract with the block's inputs at hand (`probe`; NULL: as
     * wm_contour_extract): where the samples cannot decide (subpixel.h:
     * hidden and loose crossings, saddle cells, features inside one cell)
     * the boundary is rebuilt exactly from the inputs. The cells so
     * rebuilt are left in probe->rebuilt for crease.c.
     */
    wm_status wm_contour_extract_probed(const wm_field *f, wm_probe *probe,
                                        wm_rings *out, const wm_ctx *ctx);

    /**
     * The crossing contour.c puts on the cell edge from the sample at
     * lattice (x, y) (value va) to the next one along x (vertical == 0) or y
     * (value vb), which differ in class: the linear interpolation from the
     * first sample, rounded and clamped to offsets 1 .. WM_Q - 1.
     */
    static inline wm_pt wm_contour_crossing(float va, float vb, int32_t x,
                                            int32_t y, int vertical)
    {
        const double t = (double)va / ((double)va - (double)vb);
        const double o = t * WM_Q + 0.5;
        const int32_t off =
            o < 1.0 ? 1 : (o >= WM_Q - 1 ? WM_Q - 1 : (int32_t)o);
        wm_pt p = {x, y};
        if (vertical)
            p.y += off;
        else
            p.x += off;
        return p;
    }

    /**
     * The ring edge wm_contour_extract makes in cell (c, r) of the field
     * (0 <= c, r < n) when the cell holds exactly one: *a to *b, in ring
     * order. Returns 0 for a cell with no crossing or two (a saddle).
     */
    int wm_contour_cell_edge(const wm_field *f, int32_t c, int32_t r, wm_pt *a,
                             wm_pt *b);

#ifdef __cplusplus
}
#endif

#endif /* WM_CONTOUR_H */
