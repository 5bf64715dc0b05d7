/*
 * wm_shard.c - SHARD=i/N: a job of an array computes the i-th of N
 * contiguous runs of the cells of the block grid around the inputs
 * (row-major from the lowest row: the order of a whole run), and reads
 * only the features within its cells grown by the halo.
 *
 * The grid comes from the envelope of the inputs' geometries, found by one
 * streaming pass over both layers (a layer's declared extent is not enough:
 * the OSM driver gives its file's header bounds), which also finds the
 * widest river; nothing of it is kept, so a job's memory follows its share.
 * The halo is the widest river's half-width plus the field's reach (2
 * pixels) and a pixel: a block's result depends only on
 * the river capsules and lake edges within that distance of it, so the
 * job's blocks come out as in a whole run, and appending the jobs'
 * outputs in shard order gives the whole run's features.
 */
#include "wm_private.h"

#include <cpl_conv.h>
#include <math.h>

/* Scans layer h (WMLayerScan) and merges the bounds of its geometries,
 * in the working CRS dst, into b (xmin, ymin, xmax, ymax); TRUE, or -1
 * when it has none, FALSE after a CPLError. */
static int layer_bounds(OGRLayerH h, const WMParams *p, int rivers,
                        OGRSpatialReferenceH dst, double b[4], double *wmax)
{
    OGREnvelope e;
    const int st = WMLayerScan(h, p, rivers, &e, wmax);
    if (st != TRUE)
        return st;
    double x0 = e.MinX, y0 = e.MinY, x1 = e.MaxX, y1 = e.MaxY;
    OGRSpatialReferenceH src = OGR_L_GetSpatialRef(h);
    if (src && !OSRIsSame(src, dst))
    {
        OGRSpatialReferenceH s = OSRClone(src);
        OSRSetAxisMappingStrategy(s, OAMS_TRADITIONAL_GIS_ORDER);
        OGRCoordinateTransformationH ct =
            OCTNewCoordinateTransformation(s, dst);
        OSRRelease(s);
        const int ok = ct && OCTTransformBounds(ct, e.MinX, e.MinY, e.MaxX,
                                                e.MaxY, &x0, &y0, &x1, &y1, 21);
        OCTDestroyCoordinateTransformation(ct);
        if (!ok)
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: SHARD: the extent of layer '%s' cannot be "
                     "expressed in the working CRS.",
                     OGR_L_GetName(h));
            return FALSE;
        }
    }
    b[0] = fmin(b[0], x0);
    b[1] = fmin(b[1], y0);
    b[2] = fmax(b[2], x1);
    b[3] = fmax(b[3], y1);
    return TRUE;
}

/* Sets on layer h the spatial filter of rectangle r (working CRS dst),
 * in the layer's CRS. */
static int filter_layer(OGRLayerH h, OGRSpatialReferenceH dst,
                        const double r[4])
{
    double x0 = r[0], y0 = r[1], x1 = r[2], y1 = r[3];
    OGRSpatialReferenceH src = OGR_L_GetSpatialRef(h);
    if (src && !OSRIsSame(src, dst))
    {
        OGRSpatialReferenceH s = OSRClone(src);
        OSRSetAxisMappingStrategy(s, OAMS_TRADITIONAL_GIS_ORDER);
        OGRCoordinateTransformationH ct =
            OCTNewCoordinateTransformation(dst, s);
        OSRRelease(s);
        const int ok = ct && OCTTransformBounds(ct, r[0], r[1], r[2], r[3], &x0,
                                                &y0, &x1, &y1, 21);
        OCTDestroyCoordinateTransformation(ct);
        if (!ok)
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: SHARD: the job's area cannot be expressed "
                     "in the CRS of layer '%s'.",
                     OGR_L_GetName(h));
            return FALSE;
        }
    }
    OGR_L_SetSpatialFilterRect(h, x0, y0, x1, y1);
    return TRUE;
}

int WMShardPrepare(WMScene *s, OGRLayerH hRivers, OGRLayerH hLakes)
{
    const WMParams *p = &s->params;
    double b[4] = {HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, wmax = 0;
    const int rv =
        hRivers ? layer_bounds(hRivers, p, TRUE, s->hSRS, b, &wmax) : -1;
    const int lk =
        hLakes ? layer_bounds(hLakes, p, FALSE, s->hSRS, b, &wmax) : -1;
    if (!rv || !lk)
        return FALSE;
    const int any = rv == TRUE || lk == TRUE;
    const double halo = wmax / 2 + 3 * p->pixel, B = p->block;
    WMShard *g = &s->shard;
    if (any)
    {
        g->gx0 = (int64_t)floor((b[0] - halo) / B);
        g->gy0 = (int64_t)floor((b[1] - halo) / B);
        g->nx = (int64_t)floor((b[2] + halo) / B) - g->gx0 + 1;
        g->ny = (int64_t)floor((b[3] + halo) / B) - g->gy0 + 1;
    }
    const uint64_t total = (uint64_t)g->nx * (uint64_t)g->ny,
                   i = (uint64_t)p->shard, n = (uint64_t)p->nshards;
    /* i * total / n without overflow (n < 2^31, total < 2^62) */
    g->first = i * (total / n) + i * (total % n) / n;
    g->last = (i + 1) * (total / n) + (i + 1) * (total % n) / n;
    g->on = TRUE;
    /* the job's cells: whole rows, or part of one */
    double rect[4] = {0, 0, 0, 0};
    if (g->last > g->first)
    {
        const int64_t nx = g->nx, f = (int64_t)g->first,
                      l = (int64_t)g->last - 1;
        const int64_t c0 = f / nx == l / nx ? f % nx : 0,
                      c1 = f / nx == l / nx ? l % nx : nx - 1;
        rect[0] = (double)(g->gx0 + c0) * B - halo;
        rect[1] = (double)(g->gy0 + f / nx) * B - halo;
        rect[2] = (double)(g->gx0 + c1 + 1) * B + halo;
        rect[3] = (double)(g->gy0 + l / nx + 1) * B + halo;
    }
    else /* an empty share: a rectangle beside the inputs, which holds none */
    {
        rect[0] = rect[2] = b[2] + 10 * (halo + B);
        rect[1] = rect[3] = b[3] + 10 * (halo + B);
    }
    return (!hRivers || filter_layer(hRivers, s->hSRS, rect)) &&
           (!hLakes || filter_layer(hLakes, s->hSRS, rect));
}

int WMShardHas(const WMScene *s, int64_t bx, int64_t by)
{
    const WMShard *g = &s->shard;
    if (!g->on)
        return TRUE;
    const int64_t c = bx - g->gx0, r = by - g->gy0;
    if (c < 0 || r < 0 || c >= g->nx || r >= g->ny)
        return FALSE;
    const uint64_t k = (uint64_t)r * (uint64_t)g->nx + (uint64_t)c;
    return k >= g->first && k < g->last;
}
