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
#include <string.h>

/* Rectangle in (xmin, ymin, xmax, ymax) between layer h's CRS and the
 * working CRS dst, either way (to_layer), into out; TRUE as is when they
 * are the same or the layer has none. FALSE after a CPLError. */
static int transform_rect(OGRLayerH h, OGRSpatialReferenceH dst, int to_layer,
                          const double in[4], double out[4])
{
    memcpy(out, in, 4 * sizeof *out);
    OGRSpatialReferenceH src = OGR_L_GetSpatialRef(h);
    if (!src || OSRIsSame(src, dst))
        return TRUE;
    OGRSpatialReferenceH s = OSRClone(src);
    OSRSetAxisMappingStrategy(s, OAMS_TRADITIONAL_GIS_ORDER);
    OGRCoordinateTransformationH ct =
        to_layer ? OCTNewCoordinateTransformation(dst, s)
                 : OCTNewCoordinateTransformation(s, dst);
    OSRRelease(s);
    const int ok =
        ct && OCTTransformBounds(ct, in[0], in[1], in[2], in[3], &out[0],
                                 &out[1], &out[2], &out[3], 21);
    OCTDestroyCoordinateTransformation(ct);
    if (!ok)
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: SHARD: a rectangle cannot be expressed between "
                 "the CRS of layer '%s' and the working CRS.",
                 OGR_L_GetName(h));
    return ok;
}

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
    const double in[4] = {e.MinX, e.MinY, e.MaxX, e.MaxY};
    double r[4];
    if (!transform_rect(h, dst, FALSE, in, r))
        return FALSE;
    b[0] = fmin(b[0], r[0]);
    b[1] = fmin(b[1], r[1]);
    b[2] = fmax(b[2], r[2]);
    b[3] = fmax(b[3], r[3]);
    return TRUE;
}

/* Sets on layer h the spatial filter of rectangle r (working CRS dst),
 * in the layer's CRS. */
static int filter_layer(OGRLayerH h, OGRSpatialReferenceH dst,
                        const double r[4])
{
    double f[4];
    if (!transform_rect(h, dst, TRUE, r, f))
        return FALSE;
    OGR_L_SetSpatialFilterRect(h, f[0], f[1], f[2], f[3]);
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
