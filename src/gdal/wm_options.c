/*
 * wm_options.c - options, input datasources and .watermesh descriptors.
 * One parser for every way in (driver open options, descriptor elements,
 * CLI flags, C API options), so a name means the same thing everywhere.
 */
#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_minixml.h>
#include <cpl_multiproc.h>
#include <cpl_string.h>
#include <cpl_vsi.h>

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const WM_OPTION_NAMES[] = {"RIVERS",
                                       "RIVERS_LAYER",
                                       "RIVERS_WHERE",
                                       "LAKES",
                                       "LAKES_LAYER",
                                       "LAKES_WHERE",
                                       "WIDTH",
                                       "WIDTH_FIELD",
                                       "WIDTH_BY_CLASS",
                                       "PIXEL_SIZE",
                                       "BLOCK_SIZE",
                                       "SIMPLIFY",
                                       "METHOD",
                                       "HEURISTIC",
                                       "MERGE_DISTANCE",
                                       "DEVICE",
                                       "NUM_THREADS",
                                       "TARGET_SRS",
                                       "MIN_FEATURE_AREA",
                                       "MESH_GEOMETRY",
                                       "MIN_ANGLE",
                                       "MAX_EDGE",
                                       "ELEVATION",
                                       "ELEVATION_BAND",
                                       "LAKE_LEVEL_PERCENTILE",
                                       "FLOW",
                                       NULL};

/* Parses a strictly numeric option value; CPLError on failure. */
static int number(CSLConstList opts, const char *name, double def, double *out)
{
    const char *v = CSLFetchNameValue(opts, name);
    if (!v || !*v)
    {
        *out = def;
        return TRUE;
    }
    char *end = NULL;
    const double d = CPLStrtod(v, &end);
    while (end && (*end == ' ' || *end == '\t'))
        end++;
    if (end == v || (end && *end) || !isfinite(d))
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: %s=%s is not a number.", name, v);
        return FALSE;
    }
    *out = d;
    return TRUE;
}

static int params_parse(CSLConstList opts, WMParams *p);

/* WIDTH_BY_CLASS=<field>:<class>=<width>,<class>=<width>,...[,*=<width>]:
 * the field (a field, or "field:hstore key") is what precedes the last ':'
 * before the first '='. */
static int parse_classes(const char *spec, WMParams *p)
{
    const char *eq = strchr(spec, '=');
    const char *colon = NULL;
    for (const char *c = spec; eq && c < eq; c++)
        if (*c == ':')
            colon = c;
    int ok = colon && colon > spec;
    if (ok)
    {
        p->class_field = CPLStrdup(spec);
        p->class_field[colon - spec] = '\0';
        char **items = CSLTokenizeString2(
            colon + 1, ",", CSLT_STRIPLEADSPACES | CSLT_STRIPENDSPACES);
        for (int i = 0; ok && items[i]; i++)
        {
            char *e = strchr(items[i], '=');
            char *end = NULL;
            const double w = e ? CPLStrtod(e + 1, &end) : 0;
            ok = e && e > items[i] && end != e + 1 && *end == '\0' && w > 0 &&
                 w <= WM_MAX_WIDTH;
            if (!ok)
                break;
            while (e > items[i] && isspace((unsigned char)e[-1]))
                e--;
            *e = '\0';
            p->class_names = CSLAddString(p->class_names, items[i]);
            p->class_widths = CPLRealloc(
                p->class_widths, (size_t)(p->nclasses + 1) * sizeof(double));
            p->class_widths[p->nclasses++] = w;
        }
        ok = ok && p->nclasses > 0;
        CSLDestroy(items);
    }
    if (!ok)
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: WIDTH_BY_CLASS=%s: expected "
                 "<field>:<class>=<width>,<class>=<width>,... (widths in "
                 "metres, > 0 and <= 100000; * for any other class), e.g. "
                 "waterway:river=10,stream=2,*=3.",
                 spec);
    return ok;
}

/* One index or an inclusive range a..b of BLOCKS; TRUE when valid. */
static int parse_range(const char *t, int64_t *lo, int64_t *hi)
{
    char *end = NULL;
    *lo = strtoll(t, &end, 10);
    if (end == t)
        return FALSE;
    *hi = *lo;
    if (end[0] == '.' && end[1] == '.')
    {
        const char *u = end + 2;
        *hi = strtoll(u, &end, 10);
        if (end == u)
            return FALSE;
    }
    return *end == 0 && *lo <= *hi;
}

/* BLOCKS=X:Y[,X:Y...], X and Y a block index or a range a..b. */
static int parse_blocks(const char *spec, WMParams *p)
{
    char **items = CSLTokenizeString2(spec, ",", CSLT_ALLOWEMPTYTOKENS);
    const int n = CSLCount(items);
    int ok = n > 0;
    p->blockrects = CPLCalloc((size_t)(n > 0 ? n : 1), sizeof *p->blockrects);
    for (int i = 0; ok && i < n; i++)
    {
        char **xy = CSLTokenizeString2(items[i], ":", CSLT_ALLOWEMPTYTOKENS);
        int64_t *r = p->blockrects[i];
        ok = CSLCount(xy) == 2 && parse_range(xy[0], &r[0], &r[2]) &&
             parse_range(xy[1], &r[1], &r[3]);
        CSLDestroy(xy);
    }
    CSLDestroy(items);
    p->nblockrects = ok ? n : 0;
    if (!ok)
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: BLOCKS=%s: expected bx:by items separated by "
                 "commas, each index a number or a range a..b (e.g. "
                 "10..12:40,15:41).",
                 spec);
    return ok;
}

/* ELEVATION, ELEVATION_BAND, LAKE_LEVEL_PERCENTILE and FLOW. */
static int parse_elevation(CSLConstList opts, WMParams *p)
{
    const char *e = CSLFetchNameValue(opts, "ELEVATION");
    if (e && *e)
        p->elevation = CPLStrdup(e);
    double band, pct;
    if (!number(opts, "ELEVATION_BAND", 1, &band) ||
        !number(opts, "LAKE_LEVEL_PERCENTILE", 10, &pct))
        return FALSE;
    if (band < 1 || band > INT32_MAX || band != floor(band))
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: ELEVATION_BAND=%s: expected a band number from "
                 "1.",
                 CSLFetchNameValue(opts, "ELEVATION_BAND"));
        return FALSE;
    }
    if (pct < 0 || pct > 100)
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: LAKE_LEVEL_PERCENTILE=%g: expected 0 to 100.",
                 pct);
        return FALSE;
    }
    p->elevation_band = (int)band;
    p->lake_percentile = pct;
    const char *fl = CSLFetchNameValueDef(opts, "FLOW", "DEM");
    if (!EQUAL(fl, "DEM") && !EQUAL(fl, "LINE_DIRECTION"))
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: FLOW=%s: expected DEM or LINE_DIRECTION.", fl);
        return FALSE;
    }
    p->flow_line = EQUAL(fl, "LINE_DIRECTION");
    if (p->elevation && (p->nshards || p->nblockrects))
    {
        CPLError(CE_Failure, CPLE_NotSupported,
                 "WATERMESH: ELEVATION with SHARD or BLOCKS is not supported: "
                 "a river's levels come from its whole network, which a job "
                 "reads only in part.");
        return FALSE;
    }
    return TRUE;
}

int WMParamsParse(CSLConstList opts, WMParams *p)
{
    memset(p, 0, sizeof *p);
    if (params_parse(opts, p))
        return TRUE;
    WMParamsFree(p);
    return FALSE;
}

/* CPLError(CE_Failure, CPLE_IllegalArg, fmt, ...); FALSE. */
static int illegal(const char *fmt, ...) CPL_PRINT_FUNC_FORMAT(1, 2);
static int illegal(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CPLErrorV(CE_Failure, CPLE_IllegalArg, fmt, ap);
    va_end(ap);
    return FALSE;
}

static int at_least_0(const char *name, double v)
{
    return v >= 0 || illegal("WATERMESH: %s=%g must be >= 0.", name, v);
}

/* WIDTH, PIXEL_SIZE, BLOCK_SIZE (a whole number of pixels, at least two
 * and at most WM_LOCAL_MAX / WM_Q) and SIMPLIFY. */
static int parse_grid(CSLConstList opts, WMParams *p)
{
    if (!number(opts, "WIDTH", 10.0, &p->width) ||
        !number(opts, "PIXEL_SIZE", 0.5, &p->pixel) ||
        !number(opts, "BLOCK_SIZE", 4096.0, &p->block))
        return FALSE;
    if (!(p->width > 0) || p->width > WM_MAX_WIDTH)
        return illegal("WATERMESH: WIDTH=%g must be positive and at most %g m.",
                       p->width, WM_MAX_WIDTH);
    if (!(p->pixel > 0))
        return illegal("WATERMESH: PIXEL_SIZE=%g must be positive.", p->pixel);
    if (!(p->block > 0))
        return illegal("WATERMESH: BLOCK_SIZE=%g must be positive.", p->block);
    const double ratio = p->block / p->pixel;
    if (fabs(ratio - floor(ratio + 0.5)) > 1e-9 * ratio || ratio < 1)
        return illegal("WATERMESH: BLOCK_SIZE=%g is not a multiple of "
                       "PIXEL_SIZE=%g.",
                       p->block, p->pixel);
    if (ratio > (double)(WM_LOCAL_MAX / WM_Q))
        return illegal("WATERMESH: BLOCK_SIZE=%g / PIXEL_SIZE=%g = %.0f "
                       "samples per block side: a block would not fit in "
                       "memory (at most %d).",
                       p->block, p->pixel, ratio, WM_LOCAL_MAX / WM_Q);
    if (ratio < 2)
        return illegal("WATERMESH: BLOCK_SIZE=%g must be at least twice "
                       "PIXEL_SIZE=%g.",
                       p->block, p->pixel);
    p->n = (int32_t)floor(ratio + 0.5);
    return number(opts, "SIMPLIFY", p->pixel, &p->simplify) &&
           at_least_0("SIMPLIFY", p->simplify);
}

/* The index in names (NULL-terminated) of the value of option `name`
 * (default def), any case; -1 after a CPLError listing them. */
static int choice(CSLConstList opts, const char *name, const char *def,
                  const char *const *names)
{
    const char *v = CSLFetchNameValueDef(opts, name, def);
    int n = 0;
    for (; names[n]; n++)
        if (EQUAL(v, names[n]))
            return n;
    char list[256] = "";
    for (int i = 0; i < n; i++)
        CPLStrlcat(list,
                   CPLSPrintf("%s%s",
                              i == 0       ? ""
                              : i == n - 1 ? " or "
                                           : ", ",
                              names[i]),
                   sizeof list);
    illegal("WATERMESH: %s=%s: expected %s.", name, v, list);
    return -1;
}

/* METHOD and HEURISTIC, each in its enum's order. */
static int parse_method(CSLConstList opts, WMParams *p)
{
    static const char *const methods[] = {"CONTOUR", "PAPER", NULL};
    static const char *const heuristics[] = {
        "CLOSEST", "DIRECTIONAL_CW", "DIRECTIONAL_CCW", "LEAST_ANGLE", NULL};
    const int m = choice(opts, "METHOD", "CONTOUR", methods);
    p->heuristic =
        m < 0 ? -1 : choice(opts, "HEURISTIC", "CLOSEST", heuristics);
    p->method = (wm_method)m;
    return p->heuristic >= 0;
}

/* MESH_GEOMETRY and DEVICE, each in its enum's order. */
static int parse_output(CSLConstList opts, WMParams *p)
{
    static const char *const forms[] = {"MULTIPOLYGON", "TIN", "TRIANGLES",
                                        NULL};
    static const char *const devices[] = {"AUTO", "CPU", "OPENCL", NULL};
    const int g = choice(opts, "MESH_GEOMETRY", "MULTIPOLYGON", forms);
    const int d = g < 0 ? -1 : choice(opts, "DEVICE", "AUTO", devices);
    p->mesh_form = (WMMeshForm)g;
    p->device = (WMDeviceKind)d;
    return d >= 0;
}

/* MERGE_DISTANCE, MIN_FEATURE_AREA, MIN_ANGLE and MAX_EDGE. */
static int parse_mesh_options(CSLConstList opts, WMParams *p)
{
    if (!number(opts, "MERGE_DISTANCE", 0.0, &p->merge) ||
        !at_least_0("MERGE_DISTANCE", p->merge) ||
        !number(opts, "MIN_FEATURE_AREA", 0.0, &p->min_feature_area) ||
        !at_least_0("MIN_FEATURE_AREA", p->min_feature_area) ||
        !number(opts, "MIN_ANGLE", 0.0, &p->min_angle) ||
        !number(opts, "MAX_EDGE", 0.0, &p->max_edge))
        return FALSE;
    if (!(p->min_angle >= 0 && p->min_angle <= 30))
        return illegal("WATERMESH: MIN_ANGLE=%g: expected 0 (off) to 30 "
                       "degrees (20.7 is guaranteed; above it refinement may "
                       "not end).",
                       p->min_angle);
    if (!(p->max_edge == 0 || p->max_edge >= p->pixel))
        return illegal("WATERMESH: MAX_EDGE=%g: expected 0 (off) or at least "
                       "PIXEL_SIZE (%g).",
                       p->max_edge, p->pixel);
    return TRUE;
}

/* NUM_THREADS: 1 to 1024, or ALL_CPUS (the default). */
static int parse_threads(CSLConstList opts, WMParams *p)
{
    const char *t = CSLFetchNameValueDef(opts, "NUM_THREADS", "ALL_CPUS");
    long v = CPLGetNumCPUs();
    if (!EQUAL(t, "ALL_CPUS"))
    {
        char *end = NULL;
        v = strtol(t, &end, 10);
        if (end == t || *end || v < 1 || v > 1024)
            return illegal("WATERMESH: NUM_THREADS=%s: expected an integer "
                           "from 1 to 1024, or ALL_CPUS.",
                           t);
    }
    p->num_threads = v < 1 ? 1 : (int)v;
    return TRUE;
}

/* SPAT=xmin,ymin,xmax,ymax (commas or spaces). */
static int parse_spat(const char *spat, WMParams *p)
{
    char **tok = CSLTokenizeString2(spat, ", ", 0);
    int ok = CSLCount(tok) == 4;
    for (int i = 0; ok && i < 4; i++)
    {
        char *end = NULL;
        p->spat[i] = CPLStrtod(tok[i], &end);
        ok = end != tok[i] && !*end && isfinite(p->spat[i]);
    }
    CSLDestroy(tok);
    if (!ok || p->spat[0] > p->spat[2] || p->spat[1] > p->spat[3])
        return illegal("WATERMESH: SPAT=%s: expected xmin,ymin,xmax,ymax.",
                       spat);
    p->have_spat = TRUE;
    return TRUE;
}

/* SHARD=i/N. */
static int parse_shard(const char *shard, WMParams *p)
{
    long long i = -1, n = 0;
    char tail = 0;
    if (sscanf(shard, "%lld/%lld%c", &i, &n, &tail) != 2 || n < 1 ||
        n > INT32_MAX || i < 0 || i >= n)
        return illegal("WATERMESH: SHARD=%s: expected i/N with 0 <= i < N <= "
                       "2^31 - 1.",
                       shard);
    p->shard = i;
    p->nshards = n;
    return TRUE;
}

/* A string option's copy (NULL when unset or empty). */
static char *string_option(CSLConstList opts, const char *name)
{
    const char *v = CSLFetchNameValue(opts, name);
    return v && *v ? CPLStrdup(v) : NULL;
}

static int params_parse(CSLConstList opts, WMParams *p)
{
    if (!parse_grid(opts, p) || !parse_method(opts, p) ||
        !parse_mesh_options(opts, p) || !parse_output(opts, p) ||
        !parse_threads(opts, p))
        return FALSE;
    p->width_field = string_option(opts, "WIDTH_FIELD");
    const char *wc = CSLFetchNameValue(opts, "WIDTH_BY_CLASS");
    if (wc && *wc && !parse_classes(wc, p))
        return FALSE;
    p->target_srs = string_option(opts, "TARGET_SRS");
    const char *spat = CSLFetchNameValue(opts, "SPAT");
    const char *shard = CSLFetchNameValue(opts, "SHARD");
    const char *blk = CSLFetchNameValue(opts, "BLOCKS");
    if ((spat && *spat && !parse_spat(spat, p)) ||
        (shard && !parse_shard(shard, p)) || (blk && !parse_blocks(blk, p)))
        return FALSE;
    if (p->nblockrects && !p->nshards) /* the whole grid, then the rects */
        p->nshards = 1;
    p->shard_plan = string_option(opts, "SHARD_PLAN");
    if (!parse_elevation(opts, p))
        return FALSE;
    p->stats = CPLTestBool(CSLFetchNameValueDef(opts, "STATS", "NO"));
    return TRUE;
}

void WMParamsFree(WMParams *p)
{
    CPLFree(p->elevation);
    p->elevation = NULL;
    CPLFree(p->width_field);
    CPLFree(p->target_srs);
    CPLFree(p->shard_plan);
    CPLFree(p->blockrects);
    p->blockrects = NULL;
    p->nblockrects = 0;
    CPLFree(p->class_field);
    CSLDestroy(p->class_names);
    CPLFree(p->class_widths);
    p->width_field = p->target_srs = p->class_field = p->shard_plan = NULL;
    p->class_names = NULL;
    p->class_widths = NULL;
    p->nclasses = 0;
}

/* NULL when attribute filter `where` applies to layer h, else the
 * driver's reason (CPLFree it; maybe empty). Some drivers accept any
 * filter and report an error only on the first read (GeoPackage's "failed
 * to prepare SQL"), or through CPLGetLastErrorType alone: the filter is
 * set, one feature is read, and any error on the way counts. */
static char *filter_error(OGRLayerH h, const char *where)
{
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    int ok = OGR_L_SetAttributeFilter(h, where) == OGRERR_NONE &&
             CPLGetLastErrorType() < CE_Failure;
    if (ok)
    {
        OGR_L_ResetReading(h);
        OGRFeatureH f = OGR_L_GetNextFeature(h);
        if (f)
            OGR_F_Destroy(f);
        ok = CPLGetLastErrorType() < CE_Failure;
        OGR_L_ResetReading(h);
    }
    char *why = ok ? NULL : CPLStrdup(CPLGetLastErrorMsg());
    CPLPopErrorHandler();
    CPLErrorReset();
    return why;
}

/* Opens one role's datasource and layer, sets its attribute filter. */
/* The layer a role takes when *_LAYER is not set: the first whose geometry
 * type is the role's (lines for RIVERS, polygons for LAKES), else the first
 * layer (whose type ingestion then refuses, naming it). */
static OGRLayerH default_layer(GDALDatasetH ds, const char *role)
{
    const int rivers = EQUAL(role, "RIVERS");
    const int n = GDALDatasetGetLayerCount(ds);
    for (int i = 0; i < n; i++)
    {
        OGRLayerH l = GDALDatasetGetLayer(ds, i);
        const OGRwkbGeometryType t = wkbFlatten(OGR_L_GetGeomType(l));
        const int fits = rivers ? OGR_GT_IsSubClassOf(t, wkbCurve) ||
                                      OGR_GT_IsSubClassOf(t, wkbMultiCurve)
                                : OGR_GT_IsSubClassOf(t, wkbCurvePolygon) ||
                                      OGR_GT_IsSubClassOf(t, wkbMultiSurface);
        if (fits)
        {
            CPLDebug("WATERMESH", "%s: layer '%s', the first of %s", role,
                     OGR_L_GetName(l), rivers ? "lines" : "polygons");
            return l;
        }
    }
    if (n > 0)
        CPLDebug("WATERMESH", "%s: no layer of %s; the first, '%s'", role,
                 rivers ? "lines" : "polygons",
                 OGR_L_GetName(GDALDatasetGetLayer(ds, 0)));
    return n > 0 ? GDALDatasetGetLayer(ds, 0) : NULL;
}

static int open_role(CSLConstList opts, const char *role, GDALDatasetH *phDS,
                     OGRLayerH *phLayer)
{
    char key[32];
    const char *path = CSLFetchNameValue(opts, role);
    *phDS = NULL;
    *phLayer = NULL;
    if (!path || !*path)
        return TRUE;
    *phDS = GDALOpenEx(path, GDAL_OF_VECTOR | GDAL_OF_VERBOSE_ERROR, NULL, NULL,
                       NULL);
    if (!*phDS)
    {
        CPLError(CE_Failure, CPLE_OpenFailed,
                 "WATERMESH: cannot open %s datasource '%s'.", role, path);
        return FALSE;
    }
    snprintf(key, sizeof key, "%s_LAYER", role);
    const char *lname = CSLFetchNameValue(opts, key);
    if (lname && *lname)
        *phLayer = GDALDatasetGetLayerByName(*phDS, lname);
    else
        *phLayer = default_layer(*phDS, role);
    if (!*phLayer)
    {
        if (lname && *lname)
            CPLError(CE_Failure, CPLE_OpenFailed,
                     "WATERMESH: %s datasource '%s' has no layer '%s'.", role,
                     path, lname);
        else
            CPLError(CE_Failure, CPLE_OpenFailed,
                     "WATERMESH: %s datasource '%s' has no layer.", role, path);
        GDALClose(*phDS);
        *phDS = NULL;
        return FALSE;
    }
    snprintf(key, sizeof key, "%s_WHERE", role);
    const char *where = CSLFetchNameValue(opts, key);
    char *why = where && *where ? filter_error(*phLayer, where) : NULL;
    if (why)
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: %s=%s is not a valid filter on layer '%s' of "
                 "'%s'%s%s",
                 key, where, OGR_L_GetName(*phLayer), path, *why ? ": " : ".",
                 why);
        CPLFree(why);
        GDALClose(*phDS);
        *phDS = NULL;
        *phLayer = NULL;
        return FALSE;
    }
    return TRUE;
}

int WMSourcesOpen(CSLConstList opts, WMSources *src)
{
    memset(src, 0, sizeof *src);
    const char *r = CSLFetchNameValue(opts, "RIVERS");
    const char *l = CSLFetchNameValue(opts, "LAKES");
    if ((!r || !*r) && (!l || !*l))
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: neither RIVERS nor LAKES is set: nothing to "
                 "mesh.");
        return FALSE;
    }
    if (!open_role(opts, "RIVERS", &src->hRiversDS, &src->hRivers) ||
        !open_role(opts, "LAKES", &src->hLakesDS, &src->hLakes))
    {
        WMSourcesClose(src);
        return FALSE;
    }
    return TRUE;
}

void WMSourcesClose(WMSources *src)
{
    if (src->hRiversDS)
        GDALClose(src->hRiversDS);
    if (src->hLakesDS)
        GDALClose(src->hLakesDS);
    memset(src, 0, sizeof *src);
}

char **WMReadDescriptor(const char *pszPath)
{
    char **opts = NULL;
    CPLXMLNode *root = CPLParseXMLFile(pszPath);
    if (!root)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: '%s' is not a valid watermesh descriptor "
                 "(malformed XML).",
                 pszPath);
        return NULL;
    }
    CPLXMLNode *wm = CPLGetXMLNode(root, "=WaterMesh");
    if (!wm)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: '%s' has no <WaterMesh> root element.", pszPath);
        CPLDestroyXMLNode(root);
        return NULL;
    }
    char *dir = CPLStrdup(CPLGetPath(pszPath));
    int bad = FALSE;
    for (CPLXMLNode *n = wm->psChild; n; n = n->psNext)
    {
        if (n->eType != CXT_Element)
            continue;
        int known = FALSE;
        for (int i = 0; WM_OPTION_NAMES[i]; i++)
            known |= EQUAL(n->pszValue, WM_OPTION_NAMES[i]);
        if (!known)
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: '%s': unknown element <%s>.", pszPath,
                     n->pszValue);
            bad = TRUE;
            break;
        }
        const char *v = CPLGetXMLValue(n, NULL, "");
        VSIStatBufL sb;
        /* a relative datasource path resolves against the descriptor's
         * folder when it names something there (a connection string such
         * as PG:... is left alone) */
        if ((EQUAL(n->pszValue, "RIVERS") || EQUAL(n->pszValue, "LAKES")) &&
            *v && CPLIsFilenameRelative(v) && *dir &&
            VSIStatL(CPLFormFilename(dir, v, NULL), &sb) == 0)
            opts = CSLSetNameValue(opts, n->pszValue,
                                   CPLFormFilename(dir, v, NULL));
        else
            opts = CSLSetNameValue(opts, n->pszValue, v);
    }
    CPLFree(dir);
    CPLDestroyXMLNode(root);
    if (bad)
    {
        CSLDestroy(opts);
        return NULL;
    }
    if (!opts)
        CPLError(CE_Failure, CPLE_AppDefined, "WATERMESH: '%s' sets no option.",
                 pszPath);
    return opts;
}
