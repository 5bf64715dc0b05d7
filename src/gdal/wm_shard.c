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
 *
 * SHARD_PLAN keeps the pass's result in a file for the other jobs; BLOCKS
 * narrows a job (SHARD=0/1 when not set) to rectangles of block indices,
 * and its spatial filter to their bounding box grown by the halo.
 */
#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_multiproc.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
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

/* ---- SHARD_PLAN: the scan's result, kept in a file ------------------ */

#define PLAN_MAGIC "WATERMESH_SHARD_PLAN 1"

/* What the scan's result depends on, as one line: the layers and the
 * options that choose their features, widths and CRS. */
static char *plan_key(OGRLayerH hRivers, OGRLayerH hLakes, CSLConstList opts)
{
    static const char *const keys[] = {
        "RIVERS",      "RIVERS_WHERE",   "LAKES",      "LAKES_WHERE", "WIDTH",
        "WIDTH_FIELD", "WIDTH_BY_CLASS", "TARGET_SRS", NULL};
    char *k = CPLStrdup(CPLSPrintf("rivers_layer=%s lakes_layer=%s",
                                   hRivers ? OGR_L_GetName(hRivers) : "",
                                   hLakes ? OGR_L_GetName(hLakes) : ""));
    for (int i = 0; keys[i]; i++)
    {
        const char *v = CSLFetchNameValue(opts, keys[i]);
        char *n = CPLStrdup(CPLSPrintf("%s %s=%s", k, keys[i], v ? v : ""));
        CPLFree(k);
        k = n;
    }
    for (char *c = k; *c; c++) /* one line */
        if (*c == '\n' || *c == '\r')
            *c = ' ';
    return k;
}

/* Reads plan file path into b / wmax / any: TRUE, -1 when the file does
 * not exist, FALSE after a CPLError (unreadable, or made for another
 * scene). */
static int plan_read(const char *path, const char *key, double b[4],
                     double *wmax, int *any)
{
    VSIStatBufL st;
    if (VSIStatL(path, &st) != 0)
        return -1;
    char **lines = CSLLoad(path);
    const int n = CSLCount(lines);
    int ok =
        n >= 4 && EQUAL(lines[0], PLAN_MAGIC) && STARTS_WITH(lines[1], "key ");
    if (ok && strcmp(lines[1] + 4, key) != 0)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: SHARD_PLAN %s was made for other inputs or "
                 "options (%s); this run has (%s). Remove it to scan "
                 "again.",
                 path, lines[1] + 4, key);
        CSLDestroy(lines);
        return FALSE;
    }
    *any = ok && !EQUAL(lines[2], "envelope none");
    char tail = 0;
    ok = ok && (!*any || sscanf(lines[2], "envelope %lf %lf %lf %lf%c", &b[0],
                                &b[1], &b[2], &b[3], &tail) == 4);
    ok = ok && sscanf(lines[3], "wmax %lf%c", wmax, &tail) == 1;
    CSLDestroy(lines);
    if (!ok)
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: SHARD_PLAN %s is not a plan written by "
                 "gdal_watermesh.",
                 path);
    return ok;
}

/* Writes the plan atomically: a temporary file beside path, renamed (jobs
 * starting together may each write the same plan). */
static int plan_write(const char *path, const char *key, const double b[4],
                      double wmax, int any)
{
    const char *tmp = CPLSPrintf("%s.tmp.%ld", path, (long)CPLGetPID());
    char *t = CPLStrdup(tmp);
    VSILFILE *fp = VSIFOpenL(t, "wb");
    int ok = fp != NULL;
    if (fp)
    {
        ok = VSIFPrintfL(fp, "%s\nkey %s\n", PLAN_MAGIC, key) > 0;
        ok = ok && (any ? VSIFPrintfL(fp, "envelope %.17g %.17g %.17g %.17g\n",
                                      b[0], b[1], b[2], b[3])
                        : VSIFPrintfL(fp, "envelope none\n")) > 0;
        ok = ok && VSIFPrintfL(fp, "wmax %.17g\n", wmax) > 0;
        ok = VSIFCloseL(fp) == 0 && ok;
    }
    ok = ok && VSIRename(t, path) == 0;
    if (!ok)
    {
        VSIUnlink(t);
        CPLError(CE_Failure, CPLE_FileIO,
                 "WATERMESH: SHARD_PLAN %s cannot be written.", path);
    }
    CPLFree(t);
    return ok;
}

/* The envelope of the inputs (working CRS) and the widest river: from the
 * plan file when there is one, else by the scan (written to the plan file
 * when one is named). */
static int scene_bounds(WMScene *s, OGRLayerH hRivers, OGRLayerH hLakes,
                        CSLConstList opts, double b[4], double *wmax, int *any)
{
    const WMParams *p = &s->params;
    char *key = p->shard_plan ? plan_key(hRivers, hLakes, opts) : NULL;
    if (key)
    {
        const int st = plan_read(p->shard_plan, key, b, wmax, any);
        if (st == TRUE)
            CPLDebug("WATERMESH", "SHARD_PLAN %s read: no scan", p->shard_plan);
        if (st != -1)
        {
            CPLFree(key);
            return st;
        }
    }
    const int rv =
        hRivers ? layer_bounds(hRivers, p, TRUE, s->hSRS, b, wmax) : -1;
    const int lk =
        hLakes ? layer_bounds(hLakes, p, FALSE, s->hSRS, b, wmax) : -1;
    int ok = rv && lk;
    *any = rv == TRUE || lk == TRUE;
    if (ok && key)
        ok = plan_write(p->shard_plan, key, b, *wmax, *any);
    CPLFree(key);
    return ok;
}

int WMShardPrepare(WMScene *s, OGRLayerH hRivers, OGRLayerH hLakes,
                   CSLConstList opts)
{
    const WMParams *p = &s->params;
    double b[4] = {HUGE_VAL, HUGE_VAL, -HUGE_VAL, -HUGE_VAL}, wmax = 0;
    int any = FALSE;
    if (!scene_bounds(s, hRivers, hLakes, opts, b, &wmax, &any))
        return FALSE;
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
    double rect[4] = {0, 0, 0, 0}, bb[4] = {0, 0, 0, 0};
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
    /* BLOCKS: within the bounding box of its rectangles too */
    for (int k = 0; k < p->nblockrects; k++)
    {
        const int64_t *r = p->blockrects[k];
        const double q[4] = {(double)r[0] * B, (double)r[1] * B,
                             (double)(r[2] + 1) * B, (double)(r[3] + 1) * B};
        for (int j = 0; j < 4; j++)
            bb[j] = k == 0  ? q[j]
                    : j < 2 ? fmin(bb[j], q[j])
                            : fmax(bb[j], q[j]);
    }
    if (p->nblockrects)
    {
        rect[0] = fmax(rect[0], bb[0] - halo);
        rect[1] = fmax(rect[1], bb[1] - halo);
        rect[2] = fmin(rect[2], bb[2] + halo);
        rect[3] = fmin(rect[3], bb[3] + halo);
    }
    if (g->last <= g->first || rect[0] > rect[2] || rect[1] > rect[3])
    { /* an empty share: a rectangle beside the inputs, which holds none */
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
    if (k < g->first || k >= g->last)
        return FALSE;
    const WMParams *p = &s->params;
    for (int i = 0; i < p->nblockrects; i++)
    {
        const int64_t *q = p->blockrects[i];
        if (bx >= q[0] && bx <= q[2] && by >= q[1] && by <= q[3])
            return TRUE;
    }
    return p->nblockrects == 0;
}
