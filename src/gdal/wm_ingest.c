/*
 * wm_ingest.c - scene ingestion: reads the river and lake layers, checks
 * them, reprojects to the working CRS, reads widths, and quantizes every
 * coordinate once to the global lattice (DESIGN invariant 2).
 *
 * Input policy (documented in docs/driver.rst):
 * - rivers: LineString / MultiLineString (curves linearized); points and
 *   polygons are refused; empty and NULL geometries skipped; a river whose
 *   vertices all quantize to one point is skipped with a warning.
 * - lakes: Polygon / MultiPolygon (curves linearized); each polygon part is
 *   filled even-odd over its rings and parts union; lines and points are
 *   refused.
 * - Z and M are ignored; NaN or infinite coordinates are an error naming
 *   the feature.
 */
#include "config.h"

#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_string.h>

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *WMVersion(void)
{
    return PACKAGE_VERSION;
}

static OGRSpatialReferenceH layer_srs(OGRLayerH h)
{
    return h ? OGR_L_GetSpatialRef(h) : NULL;
}

static OGRSpatialReferenceH clone_trad(OGRSpatialReferenceH s)
{
    OGRSpatialReferenceH c = OSRClone(s);
    OSRSetAxisMappingStrategy(c, OAMS_TRADITIONAL_GIS_ORDER);
    return c;
}

/* Longitudes covered by the inputs, in bins of a tenth of a degree (the
 * working CRS's zone needs no finer), and their latitude range. */
#define LON_BINS 3600

typedef struct
{
    unsigned char bin[LON_BINS];
    double lat0, lat1;
} lon_cover;

/* Marks longitude x (degrees, any turn) covered. */
static void cover_lon(lon_cover *c, double x)
{
    double b = fmod(floor((x + 180.0) * (LON_BINS / 360.0)), LON_BINS);
    c->bin[(int)(b < 0 ? b + LON_BINS : b)] = 1;
}

/* Marks the longitudes of every vertex of geometry g (layer CRS),
 * transformed by ct to WGS 84. */
static void cover_vertices(lon_cover *c, OGRGeometryH g,
                           OGRCoordinateTransformationH ct)
{
    const int parts = OGR_G_GetGeometryCount(g);
    for (int k = 0; k < parts; k++)
        cover_vertices(c, OGR_G_GetGeometryRef(g, k), ct);
    const int n = parts ? 0 : OGR_G_GetPointCount(g);
    for (int i = 0; i < n; i++)
    {
        double x = OGR_G_GetX(g, i), y = OGR_G_GetY(g, i);
        if (OCTTransform(ct, 1, &x, &y, NULL))
            cover_lon(c, x);
    }
}

/* Marks the longitudes and latitudes of layer h, whose CRS `ls` is
 * geographic and extent e: the extent's when it spans at most half the
 * globe, else each vertex's (data across the antimeridian: a line from
 * 179.99 to -179.99 has an extent all round the Earth). FALSE after
 * CPLError when the extent is out of range for a geographic CRS
 * (projected coordinates in a layer said to be geographic, such as
 * GeoPackage's "undefined geographic" srs_id 0). */
static int cover_layer(lon_cover *c, OGRLayerH h, OGRSpatialReferenceH ls,
                       const OGREnvelope *e)
{
    if (e->MinX < -360 || e->MaxX > 360 || e->MinY < -90.000001 ||
        e->MaxY > 90.000001)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: layer '%s' has a geographic CRS but coordinates "
                 "out of range for one (x %.6g .. %.6g, y %.6g .. %.6g); "
                 "assign the layer its right CRS or set TARGET_SRS.",
                 OGR_L_GetName(h), e->MinX, e->MaxX, e->MinY, e->MaxY);
        return FALSE;
    }
    OGRSpatialReferenceH ll = OSRNewSpatialReference(NULL);
    OSRSetWellKnownGeogCS(ll, "WGS84");
    OSRSetAxisMappingStrategy(ll, OAMS_TRADITIONAL_GIS_ORDER);
    OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(ls, ll);
    OSRRelease(ll);
    if (!ct)
        return TRUE;
    double x[2] = {e->MinX, e->MaxX}, y[2] = {e->MinY, e->MaxY};
    if (OCTTransform(ct, 2, x, y, NULL))
    {
        c->lat0 = fmin(c->lat0, fmin(y[0], y[1]));
        c->lat1 = fmax(c->lat1, fmax(y[0], y[1]));
        if (e->MaxX - e->MinX <= 180)
            for (double v = x[0]; v < x[1]; v += 360.0 / LON_BINS)
                cover_lon(c, v);
        cover_lon(c, x[0]);
        cover_lon(c, x[1]);
    }
    if (e->MaxX - e->MinX > 180)
    {
        OGR_L_ResetReading(h);
        OGRFeatureH f;
        while ((f = OGR_L_GetNextFeature(h)) != NULL)
        {
            OGRGeometryH g = OGR_F_GetGeometryRef(f);
            if (g && !OGR_G_IsEmpty(g))
                cover_vertices(c, g, ct);
            OGR_F_Destroy(f);
        }
        OGR_L_ResetReading(h);
    }
    OCTDestroyCoordinateTransformation(ct);
    return TRUE;
}

/* The middle of the shortest arc holding every covered longitude: the
 * complement of the widest run of uncovered bins, around the circle. */
static double cover_centre(const lon_cover *c)
{
    int first = -1;
    for (int i = 0; i < LON_BINS && first < 0; i++)
        if (c->bin[i])
            first = i;
    if (first < 0)
        return 0;
    int best = 0, best_end = first; /* widest gap, and the bin after it */
    for (int i = 1, run = 0; i <= LON_BINS; i++)
    {
        const int b = (first + i) % LON_BINS;
        if (!c->bin[b])
            run++;
        else
        {
            if (run > best)
                best = run, best_end = b;
            run = 0;
        }
    }
    /* the arc runs from bin best_end over LON_BINS - best bins */
    const double mid = best_end + (LON_BINS - best) / 2.0;
    const double lon = mid * (360.0 / LON_BINS) - 180.0;
    return lon > 180 ? lon - 360 : lon;
}

/* The centre (WGS 84 degrees) of the inputs, all geographic: the middle of
 * the shortest arc of longitudes holding them all (across the antimeridian
 * too), and of their latitudes. FALSE after CPLError. */
static int geographic_centre(OGRLayerH hRivers, OGRLayerH hLakes, double *lon,
                             double *lat)
{
    lon_cover *c = CPLCalloc(1, sizeof *c);
    c->lat0 = INFINITY;
    c->lat1 = -INFINITY;
    OGRLayerH hl[2] = {hRivers, hLakes};
    for (int i = 0; i < 2; i++)
    {
        OGREnvelope e;
        if (!hl[i] || OGR_L_GetExtent(hl[i], &e, TRUE) != OGRERR_NONE)
            continue;
        OGRSpatialReferenceH ls = clone_trad(layer_srs(hl[i]));
        const int ok = cover_layer(c, hl[i], ls, &e);
        OSRRelease(ls);
        if (!ok)
        {
            CPLFree(c);
            return FALSE;
        }
    }
    const int none = !(c->lat0 <= c->lat1);
    *lon = cover_centre(c);
    *lat = (c->lat0 + c->lat1) / 2;
    CPLFree(c);
    if (none)
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: the inputs are geographic and their extent "
                 "could not be read; set TARGET_SRS.");
    return !none;
}

/* The projected CRS for geographic inputs centred at (lon, lat): the UTM
 * zone of the centre, or UPS north of 84 N and south of 80 S (where UTM
 * is not defined), with a warning naming it. */
static OGRSpatialReferenceH auto_projected(double lon, double lat)
{
    int epsg;
    char name[64];
    if (lat > 84 || lat < -80)
    {
        epsg = lat > 0 ? 32661 : 32761;
        snprintf(name, sizeof name, "UPS %s", lat > 0 ? "North" : "South");
    }
    else
    {
        int zone = (int)floor((lon + 180.0) / 6.0) + 1;
        zone = zone < 1 ? 1 : zone > 60 ? 60 : zone;
        epsg = (lat >= 0 ? 32600 : 32700) + zone;
        snprintf(name, sizeof name, "UTM zone %d%c", zone,
                 lat >= 0 ? 'N' : 'S');
    }
    OGRSpatialReferenceH u = OSRNewSpatialReference(NULL);
    OSRImportFromEPSG(u, epsg);
    OSRSetAxisMappingStrategy(u, OAMS_TRADITIONAL_GIS_ORDER);
    CPLError(CE_Warning, CPLE_AppDefined,
             "WATERMESH: the inputs are geographic; computing in %s "
             "(EPSG:%d). Set TARGET_SRS to choose another CRS.",
             name, epsg);
    return u;
}

static OGRSpatialReferenceH working_srs(OGRLayerH hRivers, OGRLayerH hLakes,
                                        CSLConstList opts);

OGRSpatialReferenceH WMGetWorkingSRS(OGRLayerH hRivers, OGRLayerH hLakes,
                                     CSLConstList opts)
{
    OGRSpatialReferenceH s = working_srs(hRivers, hLakes, opts);
    if (s && fabs(OSRGetLinearUnits(s, NULL) - 1.0) > 1e-12)
    {
        char *name = NULL;
        OSRGetLinearUnits(s, &name);
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: the working CRS '%s' is in %s, not metres; "
                 "set TARGET_SRS to a metric projected CRS.",
                 OSRGetName(s) ? OSRGetName(s) : "?", name ? name : "?");
        OSRRelease(s);
        return NULL;
    }
    return s;
}

static OGRSpatialReferenceH working_srs(OGRLayerH hRivers, OGRLayerH hLakes,
                                        CSLConstList opts)
{
    const char *target = CSLFetchNameValue(opts, "TARGET_SRS");
    if (target && *target)
    {
        OGRSpatialReferenceH s = OSRNewSpatialReference(NULL);
        if (OSRSetFromUserInput(s, target) != OGRERR_NONE)
        {
            OSRRelease(s);
            CPLError(CE_Failure, CPLE_IllegalArg,
                     "WATERMESH: TARGET_SRS=%s is not a valid CRS.", target);
            return NULL;
        }
        if (!OSRIsProjected(s))
        {
            OSRRelease(s);
            CPLError(CE_Failure, CPLE_IllegalArg,
                     "WATERMESH: TARGET_SRS=%s is not a projected CRS "
                     "(distances must be in metres).",
                     target);
            return NULL;
        }
        OSRSetAxisMappingStrategy(s, OAMS_TRADITIONAL_GIS_ORDER);
        return s;
    }
    OGRSpatialReferenceH r = layer_srs(hRivers), l = layer_srs(hLakes);
    if ((hRivers && !r) || (hLakes && !l))
    {
        OGRLayerH h = (hRivers && !r) ? hRivers : hLakes;
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: %s layer '%s' has no CRS; set TARGET_SRS to "
                 "say which CRS it is in.",
                 h == hRivers ? "RIVERS" : "LAKES", OGR_L_GetName(h));
        return NULL;
    }
    if (r && OSRIsProjected(r))
        return clone_trad(r);
    if (l && OSRIsProjected(l))
        return clone_trad(l);
    /* geographic: the UTM zone (UPS near the poles) of the inputs'
     * centre */
    double lon, lat;
    if (!geographic_centre(hRivers, hLakes, &lon, &lat))
        return NULL;
    return auto_projected(lon, lat);
}

/* The transformation from layer h's CRS to the working CRS dst, or NULL
 * when none is needed (same CRS, or a layer without CRS, taken to be in
 * dst). FALSE after GDAL's CPLError when it cannot be made. */
static int to_working(OGRLayerH h, OGRSpatialReferenceH dst,
                      OGRCoordinateTransformationH *ct)
{
    OGRSpatialReferenceH src = layer_srs(h);
    *ct = NULL;
    if (!src)
        return TRUE;
    OGRSpatialReferenceH s = clone_trad(src);
    if (!OSRIsSame(s, dst))
        *ct = OCTNewCoordinateTransformation(s, dst);
    const int same = OSRIsSame(s, dst);
    OSRRelease(s);
    return same || *ct != NULL;
}

/* Growable arrays for the scene. */
typedef struct
{
    wm_river_seg *segs;
    size_t nsegs, segs_cap;
    wm_lake_edge *edges;
    size_t nedges, edges_cap;
    size_t *poly_start;
    size_t npolys, poly_cap;
    int64_t *px, *py; /* quantized points of the current line or ring */
    size_t npts, pts_cap;
    size_t *line_end; /* per river line part: the end of its segments */
    size_t nlines, lines_cap;
} builder;

static int reserve(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return TRUE;
    size_t n = *cap ? *cap : 256;
    while (n < need)
        n *= 2;
    void *q = VSIRealloc(*p, n * elem);
    if (!q)
    {
        CPLError(CE_Failure, CPLE_OutOfMemory,
                 "WATERMESH: out of memory reading the input.");
        return FALSE;
    }
    *p = q;
    *cap = n;
    return TRUE;
}

typedef struct
{
    const char *role;
    OGRLayerH layer;
    GIntBig fid;
    double unit;
    OGRCoordinateTransformationH ct;
} feat_ctx;

/* Quantizes the points of a simple curve (LineString/LinearRing) into
 * b->px/py, dropping consecutive duplicates. */
static int read_points(builder *b, OGRGeometryH g, const feat_ctx *fc)
{
    const int n = OGR_G_GetPointCount(g);
    b->npts = 0;
    if (!reserve((void **)&b->px, &b->pts_cap, (size_t)n + 1, sizeof(int64_t)))
        return FALSE;
    int64_t *py = VSIRealloc(b->py, b->pts_cap * sizeof(int64_t));
    if (!py)
    {
        CPLError(CE_Failure, CPLE_OutOfMemory, "WATERMESH: out of memory.");
        return FALSE;
    }
    b->py = py;
    for (int i = 0; i < n; i++)
    {
        double x = OGR_G_GetX(g, i), y = OGR_G_GetY(g, i);
        if (!isfinite(x) || !isfinite(y))
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: %s layer '%s', feature " CPL_FRMT_GIB
                     ": coordinate %d is not finite (%g, %g).",
                     fc->role, OGR_L_GetName(fc->layer), fc->fid, i, x, y);
            return FALSE;
        }
        if (fc->ct && !OCTTransform(fc->ct, 1, &x, &y, NULL))
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: %s layer '%s', feature " CPL_FRMT_GIB
                     ": coordinate %d cannot be reprojected to the working "
                     "CRS.",
                     fc->role, OGR_L_GetName(fc->layer), fc->fid, i);
            return FALSE;
        }
        const double qx = x / fc->unit, qy = y / fc->unit;
        if (!(fabs(qx) < 4e15) || !(fabs(qy) < 4e15))
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: %s layer '%s', feature " CPL_FRMT_GIB
                     ": coordinate (%g, %g) is too far from the origin for "
                     "PIXEL_SIZE.",
                     fc->role, OGR_L_GetName(fc->layer), fc->fid, x, y);
            return FALSE;
        }
        const int64_t X = (int64_t)llround(qx), Y = (int64_t)llround(qy);
        if (b->npts && b->px[b->npts - 1] == X && b->py[b->npts - 1] == Y)
            continue;
        b->px[b->npts] = X;
        b->py[b->npts] = Y;
        b->npts++;
    }
    return TRUE;
}

/* River vertices closer than DENSE_GAP lattice units (a quarter pixel) to
 * the previous one form a dense run. A run of more than DENSE_PER_PX
 * vertices per pixel of its length is thinned: Douglas-Peucker keeps the
 * vertices farther than a tolerance from the kept line, the least of 1,
 * 2, 4, 8 and DENSE_TOL (16) lattice units that leaves at most
 * DENSE_PER_PX per pixel (DENSE_TOL when none does). A line that dense
 * (GPS traces, lines traced from rasters or LiDAR, densified exports)
 * otherwise costs the field, the sub-pixel search and the corner searches
 * per vertex (read as they were, ten vertices per pixel made the synthetic
 * scenes 60 times slower); the union of the capsules moves by at most the
 * tolerance. The least one keeps the inputs' own features: a densified
 * line (its vertices on the lattice within a unit of the line drawn)
 * thins back to that line, not 1/16 pixel off it (two concentric arcs
 * with a vertex every 0.08 pixel closed the 4-unit land strip between
 * them at 1/16, test_densified_arcs_keep_their_strip; a river of 17
 * vertices per pixel left a land speck against two lake edges: held-out
 * subpixel seed 152200 at 30 m). A sparser run
 * is read as it is: thinning moves the river's bank against the other
 * inputs, and opened or closed land features narrower than that (a
 * meander with a vertex every 0.17 pixel, at 12 m pixels, thinned off a
 * lake whose corner reached 1.4 units into it: held-out subpixel seed
 * 146706, the lake a separate speck). */
#define DENSE_GAP (WM_Q / 4)
#define DENSE_TOL (WM_Q / 16)
#define DENSE_PER_PX 8
#define DP_WORK 32

/* Squared distance from (px, py) to segment a -> b (doubles). */
static double seg_d2(double ax, double ay, double bx, double by, double px,
                     double py)
{
    const double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    const double ex = ax + t * dx - px, ey = ay + t * dy - py;
    return ex * ex + ey * ey;
}

/* Douglas-Peucker on points s .. e of b (s and e kept) with tolerance
 * tol lattice units, marking keep[] (an explicit stack of index pairs,
 * e - s + 1 of them at most); returns how many points it keeps. With a
 * bound `most`, it gives up (returns SIZE_MAX, keep[] partly marked) once
 * it keeps more, or once it has measured DP_WORK distances per point: a
 * wiggle finer than tol on a slightly sloping chord splits off one period
 * at a time, each split measuring the rest again (29 s for 200,000
 * vertices at 1 unit: a 1 cm wiggle at 0.5 m pixels). Of points equally
 * far from the chord the one nearest the middle splits it. */
static size_t dp_run(const builder *b, size_t s, size_t e, double tol,
                     size_t most, uint8_t *keep, size_t *stack)
{
    size_t kept = 2, work = 0;
    const size_t budget = most == SIZE_MAX ? SIZE_MAX : DP_WORK * (e - s + 1);
    for (size_t k = s + 1; k < e; k++)
        keep[k] = 0;
    size_t top = 0;
    stack[top++] = s;
    stack[top++] = e;
    const double tol2 = tol * tol;
    while (top)
    {
        if (kept > most || work > budget)
            return SIZE_MAX;
        const size_t j = stack[--top], i = stack[--top];
        work += j - i;
        const size_t mid = i + (j - i) / 2;
        double best = -1;
        size_t at = i;
        for (size_t k = i + 1; k < j; k++)
        {
            const double d =
                seg_d2((double)b->px[i], (double)b->py[i], (double)b->px[j],
                       (double)b->py[j], (double)b->px[k], (double)b->py[k]);
            if (d > best || (d == best && (k > mid ? k - mid : mid - k) <
                                              (at > mid ? at - mid : mid - at)))
            {
                best = d;
                at = k;
            }
        }
        if (best > tol2)
        {
            keep[at] = 1;
            kept++;
            stack[top++] = i;
            stack[top++] = at;
            stack[top++] = at;
            stack[top++] = j;
        }
    }
    return kept;
}

/* The length of points s .. e of b, in pixels. */
static double run_pixels(const builder *b, size_t s, size_t e)
{
    double len = 0;
    for (size_t k = s; k < e; k++)
        len += hypot((double)(b->px[k + 1] - b->px[k]),
                     (double)(b->py[k + 1] - b->py[k]));
    return len / WM_Q;
}

/* Thins the dense runs of b->px/py (see DENSE_GAP). FALSE when out of
 * memory. */
static int thin_dense(builder *b)
{
    const size_t n = b->npts;
    size_t s = 0;
    uint8_t *keep = NULL;
    size_t *stack = NULL;
    for (size_t i = 1; i <= n; i++)
    {
        const int dense = i < n && llabs(b->px[i] - b->px[i - 1]) < DENSE_GAP &&
                          llabs(b->py[i] - b->py[i - 1]) < DENSE_GAP;
        if (dense)
            continue;
        /* a run s .. i - 1 of consecutive close vertices */
        if (i - 1 > s + 1)
        {
            if (!keep)
            {
                keep = VSICalloc(n, 1);
                stack = VSIMalloc2(2 * n, sizeof *stack);
                if (!keep || !stack)
                {
                    VSIFree(keep);
                    VSIFree(stack);
                    CPLError(CE_Failure, CPLE_OutOfMemory,
                             "WATERMESH: out of memory.");
                    return FALSE;
                }
                memset(keep, 1, n);
            }
            const size_t most =
                (size_t)(DENSE_PER_PX * run_pixels(b, s, i - 1)) + 2;
            int tol = 1;
            while (i - s > most && tol < DENSE_TOL &&
                   dp_run(b, s, i - 1, tol, most, keep, stack) > most)
                tol *= 2;
            if (i - s > most && tol == DENSE_TOL)
                dp_run(b, s, i - 1, tol, SIZE_MAX, keep, stack);
        }
        s = i;
    }
    if (!keep)
        return TRUE;
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (keep[i])
        {
            b->px[m] = b->px[i];
            b->py[m] = b->py[i];
            m++;
        }
    b->npts = m;
    VSIFree(keep);
    VSIFree(stack);
    return TRUE;
}

/* A positive number at *s and the factor of the unit after it ("2.5",
 * "8 ft", "3m"; *unit 0 when none is written); *s moves past them. */
static int width_number(const char **s, double *v, double *unit)
{
    static const struct
    {
        const char *name;
        double m;
    } units[] = {{"metres", 1},    {"meters", 1},  {"metre", 1},
                 {"meter", 1},     {"m", 1},       {"feet", 0.3048},
                 {"foot", 0.3048}, {"ft", 0.3048}, {"'", 0.3048}};
    char *end = NULL;
    *v = CPLStrtod(*s, &end);
    if (end == *s || !isfinite(*v) || !(*v > 0))
        return FALSE;
    while (isspace((unsigned char)*end))
        end++;
    *unit = 0;
    for (size_t i = 0; i < sizeof units / sizeof *units; i++)
        if (EQUALN(end, units[i].name, strlen(units[i].name)))
        {
            *unit = units[i].m;
            end += strlen(units[i].name);
            break;
        }
    while (isspace((unsigned char)*end))
        end++;
    *s = end;
    return TRUE;
}

/* One width: a number, "~" before it (about), or a range "5-8" (its
 * mean), in metres when a unit is written (*unit its factor; one unit
 * serves both ends of a range: "10-20 ft"), else as written (*unit 0). */
static int width_range(const char *s, double *w, double *unit)
{
    while (isspace((unsigned char)*s) || *s == '~')
        s++;
    double a, ua, b = 0, ub = 0;
    if (!width_number(&s, &a, &ua))
        return FALSE;
    const int range = *s == '-';
    if (range)
    {
        s++;
        while (isspace((unsigned char)*s))
            s++;
        if (!width_number(&s, &b, &ub))
            return FALSE;
    }
    *unit = ub ? ub : ua;
    const double f = *unit ? *unit : 1;
    *w = range ? (a * (ua ? ua : f) + b * (ub ? ub : f)) / 2 : a * f;
    return *s == '\0';
}

/* Parses a width value as OSM writes them: a number ("12", "2.5",
 * decimal comma "1,5"), with a unit (m, metres, ft, feet, '), about
 * ("~5"), a range ("5-8": the mean) or a list ("3;4": the largest). A
 * unit written last applies to the numbers written without one
 * ("10-20 ft", "3;4 ft"). */
static int parse_width(const char *text, double *w)
{
    char buf[128];
    if (strlen(text) >= sizeof buf)
        return FALSE;
    strcpy(buf, text);
    char *comma = strchr(buf, ',');
    if (comma && !strchr(buf, '.') && !strchr(comma + 1, ','))
        *comma = '.';
    double v[16], u[16], last = 1;
    char *save = NULL;
    int n = 0;
    for (char *part = strtok_r(buf, ";", &save); part;
         part = strtok_r(NULL, ";", &save), n++)
        if (n == 16 || !width_range(part, &v[n], &u[n]))
            return FALSE;
    if (n > 0 && u[n - 1])
        last = u[n - 1];
    double best = 0;
    for (int i = 0; i < n; i++)
    {
        /* v[i] is in metres when its unit was written */
        const double m = u[i] ? v[i] : v[i] * last;
        best = m > best ? m : best;
    }
    *w = best;
    return n > 0 && best > 0;
}

/* Where a river attribute comes from: a field, or a key of an hstore
 * field (OSM's other_tags: "k"=>"v",...) for "field:key" when the layer
 * has no field of that whole name. */
typedef struct
{
    int field; /* -1: none */
    const char *key;
    OGRFieldType type;
} attr_ref;

static int attr_resolve(OGRLayerH h, const char *spec, const char *option,
                        attr_ref *a)
{
    OGRFeatureDefnH d = OGR_L_GetLayerDefn(h);
    a->key = NULL;
    a->field = OGR_FD_GetFieldIndex(d, spec);
    const char *colon = strchr(spec, ':');
    if (a->field < 0 && colon)
    {
        char *name = CPLStrdup(spec);
        name[colon - spec] = '\0';
        a->field = OGR_FD_GetFieldIndex(d, name);
        CPLFree(name);
        a->key = colon + 1;
    }
    if (a->field < 0)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: RIVERS layer '%s' has no field '%s' (%s)%s.",
                 OGR_L_GetName(h), spec, option,
                 colon ? ", nor a field before the ':' to read an hstore key "
                         "from"
                       : "");
        return FALSE;
    }
    a->type = OGR_Fld_GetType(OGR_FD_GetFieldDefn(d, a->field));
    if (a->key && a->type != OFTString)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: RIVERS layer '%s': %s=%s reads a key of a text "
                 "(hstore) field, and this field is %s.",
                 OGR_L_GetName(h), option, spec, OGR_GetFieldTypeName(a->type));
        return FALSE;
    }
    return TRUE;
}

/* Reads a quoted hstore token ("..." with \ escapes) at *pp into out (at
 * most n bytes; *trunc set when it did not fit). */
static int hstore_token(const char **pp, char *out, size_t n, int *trunc)
{
    const char *p = *pp;
    size_t i = 0;
    if (*p != '"')
        return FALSE;
    for (p++; *p && *p != '"'; p++)
    {
        if (*p == '\\' && p[1])
            p++;
        if (i + 1 < n)
            out[i++] = *p;
        else
            *trunc = TRUE;
    }
    out[i] = '\0';
    if (*p != '"')
        return FALSE;
    *pp = p + 1;
    return TRUE;
}

/* The value of key in hstore text h, into buf; FALSE when absent, NULL or
 * malformed. */
static int hstore_get(const char *h, const char *key, char *buf, size_t n)
{
    const char *p = h;
    for (;;)
    {
        while (*p == ' ' || *p == ',')
            p++;
        if (!*p)
            return FALSE;
        char k[256];
        int ktrunc = FALSE, vtrunc = FALSE;
        if (!hstore_token(&p, k, sizeof k, &ktrunc))
            return FALSE;
        while (*p == ' ')
            p++;
        if (p[0] != '=' || p[1] != '>')
            return FALSE;
        p += 2;
        while (*p == ' ')
            p++;
        const int null = EQUALN(p, "NULL", 4);
        if (null)
            p += 4;
        else if (!hstore_token(&p, buf, n, &vtrunc))
            return FALSE;
        if (!ktrunc && strcmp(k, key) == 0)
            return !null && !vtrunc;
    }
}

/* The attribute's text for feature f, or NULL when unset. */
static const char *attr_text(OGRFeatureH f, const attr_ref *a, char *buf,
                             size_t n)
{
    if (a->field < 0 || !OGR_F_IsFieldSetAndNotNull(f, a->field))
        return NULL;
    const char *v = OGR_F_GetFieldAsString(f, a->field);
    if (!a->key)
        return v;
    return hstore_get(v, a->key, buf, n) ? buf : NULL;
}

/* Feature f's width from WIDTH_FIELD (a usable value), else from
 * WIDTH_BY_CLASS (its class, else "*"), else WIDTH; *source says which
 * (0, 1, 2). */
static double river_width(OGRFeatureH f, const WMParams *p, const attr_ref *wf,
                          const attr_ref *cf, int *source)
{
    char buf[256];
    if (wf->field >= 0)
    {
        double v = 0;
        int good = FALSE;
        if (!wf->key && (wf->type == OFTReal || wf->type == OFTInteger ||
                         wf->type == OFTInteger64))
        {
            good = OGR_F_IsFieldSetAndNotNull(f, wf->field);
            v = OGR_F_GetFieldAsDouble(f, wf->field);
            good = good && isfinite(v) && v > 0;
        }
        else
        {
            const char *t = attr_text(f, wf, buf, sizeof buf);
            good = t && parse_width(t, &v);
        }
        if (good && v <= WM_MAX_WIDTH)
        {
            *source = 0;
            return v;
        }
    }
    const char *c = attr_text(f, cf, buf, sizeof buf);
    int any = -1;
    for (int i = 0; i < p->nclasses; i++)
    {
        if (c && EQUAL(c, p->class_names[i]))
        {
            *source = 1;
            return p->class_widths[i];
        }
        if (EQUAL(p->class_names[i], "*"))
            any = i;
    }
    if (any >= 0)
    {
        *source = 1;
        return p->class_widths[any];
    }
    *source = 2;
    return p->width;
}

int WMLayerScan(OGRLayerH h, const WMParams *p, int rivers, OGREnvelope *env,
                double *wmax)
{
    attr_ref wf = {-1, NULL, OFTString}, cf = {-1, NULL, OFTString};
    if (rivers && ((p->width_field &&
                    !attr_resolve(h, p->width_field, "WIDTH_FIELD", &wf)) ||
                   (p->class_field &&
                    !attr_resolve(h, p->class_field, "WIDTH_BY_CLASS", &cf))))
        return FALSE;
    OGR_L_ResetReading(h);
    int any = FALSE;
    OGRFeatureH f;
    while ((f = OGR_L_GetNextFeature(h)) != NULL)
    {
        OGRGeometryH g = OGR_F_GetGeometryRef(f);
        if (g && !OGR_G_IsEmpty(g))
        {
            OGREnvelope e;
            OGR_G_GetEnvelope(g, &e);
            if (!any)
                *env = e;
            env->MinX = e.MinX < env->MinX ? e.MinX : env->MinX;
            env->MinY = e.MinY < env->MinY ? e.MinY : env->MinY;
            env->MaxX = e.MaxX > env->MaxX ? e.MaxX : env->MaxX;
            env->MaxY = e.MaxY > env->MaxY ? e.MaxY : env->MaxY;
            any = TRUE;
            int source;
            const double w = rivers ? river_width(f, p, &wf, &cf, &source) : 0;
            *wmax = w > *wmax ? w : *wmax;
        }
        OGR_F_Destroy(f);
    }
    OGR_L_ResetReading(h);
    return any ? TRUE : -1;
}

static OGRGeometryH linear(OGRGeometryH g)
{
    if (OGR_G_HasCurveGeometry(g, TRUE))
        return OGR_G_GetLinearGeometry(g, 0, NULL);
    return OGR_G_Clone(g);
}

/* Whether RIVERS layer h's geometry type may hold lines (reported when
 * not). */
static int river_layer_type_ok(OGRLayerH h)
{
    const OGRwkbGeometryType lt = wkbFlatten(OGR_L_GetGeomType(h));
    if (lt == wkbPoint || lt == wkbMultiPoint || lt == wkbPolygon ||
        lt == wkbMultiPolygon || lt == wkbCurvePolygon || lt == wkbMultiSurface)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: RIVERS layer '%s' has %s geometries; rivers "
                 "must be lines (give water areas as LAKES).",
                 OGR_L_GetName(h), OGRGeometryTypeToName(lt));
        return FALSE;
    }
    return TRUE;
}

/* Adds line string part, width w (m), as one river: its points read and
 * thinned, then its segments. */
static int add_river_line(builder *b, OGRGeometryH part, const feat_ctx *fc,
                          double w, size_t *nvert)
{
    *nvert += (size_t)OGR_G_GetPointCount(part);
    if (!read_points(b, part, fc) || !thin_dense(b) ||
        !reserve((void **)&b->segs, &b->segs_cap, b->nsegs + b->npts,
                 sizeof *b->segs))
        return FALSE;
    for (size_t i = 0; i + 1 < b->npts; i++)
    {
        wm_river_seg *s = &b->segs[b->nsegs++];
        s->ax = b->px[i];
        s->ay = b->py[i];
        s->bx = b->px[i + 1];
        s->by = b->py[i + 1];
        s->r = w / 2.0 / fc->unit;
    }
    if (b->npts > 1 && !reserve((void **)&b->line_end, &b->lines_cap,
                                b->nlines + 1, sizeof *b->line_end))
        return FALSE;
    if (b->npts > 1)
        b->line_end[b->nlines++] = b->nsegs;
    return TRUE;
}

/* Reports a geometry of type t that the feature of fc may not hold, as a
 * member (depth > 0) or as the feature's; FALSE. */
static int refuse_geom(const feat_ctx *fc, OGRwkbGeometryType t, int depth,
                       const char *rule)
{
    CPLError(CE_Failure, CPLE_AppDefined,
             "WATERMESH: %s layer '%s', feature " CPL_FRMT_GIB ": %s%s%s; %s.",
             fc->role, OGR_L_GetName(fc->layer), fc->fid, depth ? "a " : "",
             OGRGeometryTypeToName(t), depth ? " member" : " geometry", rule);
    return FALSE;
}

/* Adds river feature geometry g (a line string, or a collection of them,
 * nested or not), width w (m); reports any other geometry, naming it as a
 * member (depth > 0) or the feature's. */
static int add_river_geom(builder *b, OGRGeometryH g, const feat_ctx *fc,
                          double w, size_t *nvert, int depth)
{
    const OGRwkbGeometryType t = wkbFlatten(OGR_G_GetGeometryType(g));
    if (t == wkbLineString)
        return add_river_line(b, g, fc, w, nvert);
    if (t != wkbMultiLineString && t != wkbGeometryCollection)
        return refuse_geom(fc, t, depth, "rivers must be lines");
    for (int k = 0; k < OGR_G_GetGeometryCount(g); k++)
        if (!add_river_geom(b, OGR_G_GetGeometryRef(g, k), fc, w, nvert,
                            depth + 1))
            return FALSE;
    return TRUE;
}

static int add_river(builder *b, OGRGeometryH g, const feat_ctx *fc, double w,
                     size_t *nvert)
{
    return add_river_geom(b, g, fc, w, nvert, 0);
}

/* The warnings of a RIVERS layer read: rivers of zero length or narrower
 * than the lattice skipped, and features whose width field could not be
 * used. */
static void warn_rivers(OGRLayerH h, const WMParams *p, size_t zero,
                        size_t narrow, size_t badw)
{
    if (zero)
        CPLError(CE_Warning, CPLE_AppDefined,
                 "WATERMESH: RIVERS layer '%s': %lu river(s) of zero length "
                 "skipped.",
                 OGR_L_GetName(h), (unsigned long)zero);
    if (narrow)
        CPLError(CE_Warning, CPLE_AppDefined,
                 "WATERMESH: RIVERS layer '%s': %lu river(s) narrower than "
                 "the lattice (PIXEL_SIZE / 256) skipped.",
                 OGR_L_GetName(h), (unsigned long)narrow);
    if (badw)
        CPLError(CE_Warning, CPLE_AppDefined,
                 "WATERMESH: RIVERS layer '%s': %lu feature(s) with a NULL, "
                 "empty, unparsable, non-positive or absurd (> 100 km) '%s' "
                 "use %s.",
                 OGR_L_GetName(h), (unsigned long)badw, p->width_field,
                 p->nclasses ? "WIDTH_BY_CLASS (or WIDTH where no class "
                               "matches)"
                             : CPLSPrintf("WIDTH=%g", p->width));
}

static int read_rivers(builder *b, OGRLayerH h, const WMParams *p, double unit,
                       OGRSpatialReferenceH dst, size_t *nvert, size_t wsrc[3])
{
    feat_ctx fc = {"RIVERS", h, 0, unit, NULL};
    int ok = TRUE;
    size_t zero = 0, narrow = 0, badw = 0;
    attr_ref wf = {-1, NULL, OFTString}, cf = {-1, NULL, OFTString};
    if (!river_layer_type_ok(h) ||
        (p->width_field &&
         !attr_resolve(h, p->width_field, "WIDTH_FIELD", &wf)) ||
        (p->class_field &&
         !attr_resolve(h, p->class_field, "WIDTH_BY_CLASS", &cf)) ||
        !to_working(h, dst, &fc.ct))
        return FALSE;
    OGR_L_ResetReading(h);
    OGRFeatureH f;
    while (ok && (f = OGR_L_GetNextFeature(h)) != NULL)
    {
        fc.fid = OGR_F_GetFID(f);
        OGRGeometryH g0 = OGR_F_GetGeometryRef(f);
        if (g0 && !OGR_G_IsEmpty(g0))
        {
            int source;
            const double w = river_width(f, p, &wf, &cf, &source);
            wsrc[source]++;
            badw += wf.field >= 0 && source != 0;
            if (w < fc.unit)
            { /* below the lattice: its rings would be rounding specks */
                narrow++;
                OGR_F_Destroy(f);
                continue;
            }
            OGRGeometryH g = linear(g0);
            const size_t before = b->nsegs;
            ok = add_river(b, g, &fc, w, nvert);
            zero += ok && b->nsegs == before;
            OGR_G_DestroyGeometry(g);
        }
        OGR_F_Destroy(f);
    }
    if (fc.ct)
        OCTDestroyCoordinateTransformation(fc.ct);
    if (ok)
        warn_rivers(h, p, zero, narrow, badw);
    return ok;
}

/* Whether points i and j of the ring being read are one lattice point. */
static int same_pt(const builder *b, size_t i, size_t j)
{
    return b->px[i] == b->px[j] && b->py[i] == b->py[j];
}

/* Removes from the ring b->px/py[0 .. npts) (closed implicitly) the spikes
 * that go out and come back along one edge (a, b, a, on the lattice) and
 * the repeated points this leaves: the spike's two edges are one edge
 * twice, which fills nothing even-odd, yet they reached the field and the
 * search as a boundary of no width (a retraced spike gave 100 diamond
 * specks; a ring retracing one edge 20,000 times took 10 s). */
static void cancel_spikes(builder *b)
{
    size_t m = 0;
    for (size_t i = 0; i < b->npts; i++)
    {
        if (m >= 2 && same_pt(b, m - 2, i))
        {
            m--; /* the tip goes, and the point back equals the one before */
            continue;
        }
        if (m >= 1 && same_pt(b, m - 1, i))
            continue;
        b->px[m] = b->px[i];
        b->py[m] = b->py[i];
        m++;
    }
    /* the same across the ring's start */
    for (int changed = 1; changed && m >= 3;)
    {
        if (same_pt(b, m - 1, 0) || same_pt(b, m - 2, 0))
            m--; /* a repeated last point, or a tip at it */
        else if (same_pt(b, m - 1, 1))
        { /* a tip at the first point */
            memmove(b->px, b->px + 1, (m - 1) * sizeof *b->px);
            memmove(b->py, b->py + 1, (m - 1) * sizeof *b->py);
            m--;
        }
        else
            changed = 0;
    }
    b->npts = m;
}

static int add_ring(builder *b)
{
    cancel_spikes(b);
    if (b->npts < 3)
        return TRUE; /* degenerate ring: no area */
    if (!reserve((void **)&b->edges, &b->edges_cap, b->nedges + b->npts,
                 sizeof *b->edges))
        return FALSE;
    for (size_t i = 0; i < b->npts; i++)
    {
        const size_t j = (i + 1) % b->npts;
        wm_lake_edge *e = &b->edges[b->nedges++];
        e->ax = b->px[i];
        e->ay = b->py[i];
        e->bx = b->px[j];
        e->by = b->py[j];
    }
    return TRUE;
}

static int read_polygon(builder *b, OGRGeometryH poly, const feat_ctx *fc)
{
    const size_t before = b->nedges;
    const int nr = OGR_G_GetGeometryCount(poly);
    for (int i = 0; i < nr; i++)
        if (!read_points(b, OGR_G_GetGeometryRef(poly, i), fc) || !add_ring(b))
            return FALSE;
    if (b->nedges == before)
        return TRUE;
    if (!reserve((void **)&b->poly_start, &b->poly_cap, b->npolys + 2,
                 sizeof *b->poly_start))
        return FALSE;
    if (b->npolys == 0)
        b->poly_start[0] = before;
    b->poly_start[++b->npolys] = b->nedges;
    return TRUE;
}

/* Adds lake feature geometry g (a polygon, or a collection of them,
 * nested or not); reports any other geometry, naming it as a member
 * (depth > 0) or the feature's. */
static int add_lake_geom(builder *b, OGRGeometryH g, const feat_ctx *fc,
                         size_t *nvert, int depth)
{
    const OGRwkbGeometryType t = wkbFlatten(OGR_G_GetGeometryType(g));
    if (t == wkbPolygon)
    {
        for (int i = 0; i < OGR_G_GetGeometryCount(g); i++)
            *nvert += (size_t)OGR_G_GetPointCount(OGR_G_GetGeometryRef(g, i));
        return read_polygon(b, g, fc);
    }
    if (t != wkbMultiPolygon && t != wkbGeometryCollection)
        return refuse_geom(fc, t, depth, "lakes must be polygons");
    for (int k = 0; k < OGR_G_GetGeometryCount(g); k++)
        if (!add_lake_geom(b, OGR_G_GetGeometryRef(g, k), fc, nvert, depth + 1))
            return FALSE;
    return TRUE;
}

static int read_lakes(builder *b, OGRLayerH h, double unit,
                      OGRSpatialReferenceH dst, size_t *nvert)
{
    feat_ctx fc = {"LAKES", h, 0, unit, NULL};
    int ok = TRUE;
    const OGRwkbGeometryType lt = wkbFlatten(OGR_L_GetGeomType(h));
    if (lt == wkbPoint || lt == wkbMultiPoint || lt == wkbLineString ||
        lt == wkbMultiLineString || lt == wkbCircularString ||
        lt == wkbCompoundCurve || lt == wkbMultiCurve)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: LAKES layer '%s' has %s geometries; lakes must "
                 "be polygons (give centerlines as RIVERS).",
                 OGR_L_GetName(h), OGRGeometryTypeToName(lt));
        return FALSE;
    }
    if (!to_working(h, dst, &fc.ct))
        return FALSE;
    OGR_L_ResetReading(h);
    OGRFeatureH f;
    size_t collapsed = 0; /* lakes with an area that kept no edge */
    while (ok && (f = OGR_L_GetNextFeature(h)) != NULL)
    {
        fc.fid = OGR_F_GetFID(f);
        OGRGeometryH g0 = OGR_F_GetGeometryRef(f);
        if (!g0 || OGR_G_IsEmpty(g0))
        {
            OGR_F_Destroy(f);
            continue;
        }
        OGRGeometryH g = linear(g0);
        const size_t before = b->nedges;
        ok = add_lake_geom(b, g, &fc, nvert, 0);
        collapsed += ok && b->nedges == before && OGR_G_Area(g) > 0;
        OGR_G_DestroyGeometry(g);
        OGR_F_Destroy(f);
    }
    if (fc.ct)
        OCTDestroyCoordinateTransformation(fc.ct);
    if (ok && collapsed)
        CPLError(CE_Warning, CPLE_AppDefined,
                 "WATERMESH: LAKES layer '%s': %lu lake(s) with an area have "
                 "none once in the working CRS and on the lattice (PIXEL_SIZE "
                 "/ 256): smaller than the lattice, or a cap around a pole "
                 "drawn along a parallel; skipped.",
                 OGR_L_GetName(h), (unsigned long)collapsed);
    return ok;
}

WMScene *WMSceneBuild(OGRLayerH hRivers, OGRLayerH hLakes, CSLConstList opts)
{
    builder b;
    memset(&b, 0, sizeof b);
    WMScene *s = CPLCalloc(1, sizeof *s);
    if (!hRivers && !hLakes)
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: neither RIVERS nor LAKES is set: nothing to "
                 "mesh.");
        goto fail;
    }
    if (!WMParamsParse(opts, &s->params))
        goto fail;
    s->hSRS = WMGetWorkingSRS(hRivers, hLakes, opts);
    if (!s->hSRS)
        goto fail;
    s->unit = s->params.pixel / WM_Q;
    int got = !s->params.nshards || WMShardPrepare(s, hRivers, hLakes, opts);
    got = got &&
          (!hRivers || read_rivers(&b, hRivers, &s->params, s->unit, s->hSRS,
                                   &s->core.river_vertices, s->width_source));
    got = got && (!hLakes || read_lakes(&b, hLakes, s->unit, s->hSRS,
                                        &s->core.lake_vertices));
    if (s->params.nshards && hRivers) /* the layers are the caller's */
        OGR_L_SetSpatialFilter(hRivers, NULL);
    if (s->params.nshards && hLakes)
        OGR_L_SetSpatialFilter(hLakes, NULL);
    if (!got)
        goto fail;
    s->core.segs = b.segs;
    s->core.nsegs = b.nsegs;
    s->core.edges = b.edges;
    s->core.nedges = b.nedges;
    s->core.npolys = b.npolys;
    s->core.poly_start = b.poly_start;
    if (!s->core.poly_start)
        s->core.poly_start = CPLCalloc(1, sizeof(size_t));
    b.segs = NULL;
    b.edges = NULL;
    b.poly_start = NULL;
    s->line_start = CPLMalloc((b.nlines + 1) * sizeof *s->line_start);
    s->line_start[0] = 0;
    if (b.nlines)
        memcpy(s->line_start + 1, b.line_end, b.nlines * sizeof(size_t));
    s->nlines = b.nlines;
    s->core.n = s->params.n;
    s->core.band = 2;
    {
        char *msg = NULL;
        wm_ctx ctx = {WMKeepFirstError, &msg, NULL};
        const wm_status st = wm_scene_index(&s->core, &ctx);
        if (st != WM_OK)
        {
            CPLError(CE_Failure,
                     st == WM_ERR_NOMEM ? CPLE_OutOfMemory : CPLE_AppDefined,
                     "WATERMESH: BLOCK_SIZE=%g: %s.", s->params.block,
                     msg ? msg : "indexing the scene failed");
            CPLFree(msg);
            goto fail;
        }
    }
    if (!WMDrapePrepare(s) || !WMDeviceSelect(s))
        goto fail;
    VSIFree(b.px);
    VSIFree(b.py);
    VSIFree(b.line_end);
    return s;
fail:
    VSIFree(b.line_end);
    VSIFree(b.segs);
    VSIFree(b.edges);
    VSIFree(b.poly_start);
    VSIFree(b.px);
    VSIFree(b.py);
    WMSceneFree(s);
    return NULL;
}

void WMSceneFree(WMScene *s)
{
    if (!s)
        return;
    wm_scene_free(&s->core);
    CPLFree(s->line_start);
    WMDrapeFree(s->drape);
    CPLFree(s->device);
    if (s->hSRS)
        OSRRelease(s->hSRS);
    WMParamsFree(&s->params);
    CPLFree(s);
}

void WMBlockWalkBegin(WMBlockWalk *w, const WMScene *s, const double *spat)
{
    const wm_scene *c = &s->core;
    memset(w, 0, sizeof *w);
    w->s = s;
    w->x0 = c->bx0;
    w->y0 = c->by0;
    w->x1 = c->bx0 + c->nbx - 1;
    w->y1 = c->by0 + c->nby - 1;
    if (spat)
    {
        /* clamp in double first: a huge filter must not overflow int64 */
        const double bs = s->params.block;
        const double lo[2] = {(double)w->x0, (double)w->y0};
        const double hi[2] = {(double)w->x1, (double)w->y1};
        int64_t f[4];
        for (int i = 0; i < 4; i++)
        {
            const double v = floor(spat[i] / bs);
            f[i] = (int64_t)(v < lo[i & 1] - 1
                                 ? lo[i & 1] - 1
                                 : (v > hi[i & 1] + 1 ? hi[i & 1] + 1 : v));
        }
        w->x0 = f[0] > w->x0 ? f[0] : w->x0;
        w->y0 = f[1] > w->y0 ? f[1] : w->y0;
        w->x1 = f[2] < w->x1 ? f[2] : w->x1;
        w->y1 = f[3] < w->y1 ? f[3] : w->y1;
    }
    w->by = w->y0 - 1; /* no row read yet */
}

/* Moves to the next row with runs; FALSE after a CPLError. At the end,
 * w->by passes y1. */
static int next_row(WMBlockWalk *w)
{
    while (w->irun >= w->nruns && w->by <= w->y1)
    {
        free(w->runs);
        w->runs = NULL;
        w->nruns = w->irun = 0;
        if (++w->by > w->y1 || w->x0 > w->x1)
        {
            w->by = w->y1 + 1;
            break;
        }
        if (wm_scene_row_runs(&w->s->core, w->by, w->x0, w->x1, &w->runs,
                              &w->nruns) != WM_OK)
        {
            CPLError(CE_Failure, CPLE_OutOfMemory, "WATERMESH: out of memory.");
            return FALSE;
        }
        if (w->nruns)
            w->bx = w->runs[0];
    }
    return TRUE;
}

int WMBlockWalkNext(WMBlockWalk *w, int64_t *out, size_t max, size_t *n)
{
    *n = 0;
    while (*n < max)
    {
        if (!next_row(w))
            return FALSE;
        if (w->irun >= w->nruns)
            break;
        out[2 * *n] = w->bx;
        out[2 * *n + 1] = w->by;
        ++*n;
        if (++w->bx > w->runs[2 * w->irun + 1] && ++w->irun < w->nruns)
            w->bx = w->runs[2 * w->irun];
    }
    return TRUE;
}

void WMBlockWalkEnd(WMBlockWalk *w)
{
    /* the runs come from the core's malloc */
    free(w->runs);
    w->runs = NULL;
    w->nruns = w->irun = 0;
}

int WMBlockCount(const WMScene *s, const double *spat, uint64_t *count)
{
    WMBlockWalk w;
    WMBlockWalkBegin(&w, s, spat);
    *count = 0;
    for (;;)
    {
        if (!next_row(&w))
        {
            WMBlockWalkEnd(&w);
            return FALSE;
        }
        if (w.irun >= w.nruns)
            break;
        for (size_t i = 0; i < w.nruns; i++)
            *count += (uint64_t)(w.runs[2 * i + 1] - w.runs[2 * i] + 1);
        w.irun = w.nruns;
    }
    WMBlockWalkEnd(&w);
    return TRUE;
}
