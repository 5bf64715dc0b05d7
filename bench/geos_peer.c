/*
 * geos_peer: the geometric pipeline that watermesh competes with, written as
 * a competent GEOS user would write it, on one thread:
 *
 *   read (GDAL)  -> buffer every river by width / 2 (round caps and joins)
 *                -> make invalid lakes valid
 *                -> unary union of all buffers and lakes (cascaded, STRtree)
 *                -> cut into the blocks of the global grid (block (bx, by)
 *                   covers [bx*B, (bx+1)*B] x [by*B, (by+1)*B]): an STRtree
 *                   over the union's polygons picks the candidates, a
 *                   polygon inside the block is taken whole, the others are
 *                   clipped (GEOSClipByRect, or an OverlayNG intersection)
 *                -> GEOSTopologyPreserveSimplify per block (tolerance T)
 *                -> GEOSConstrainedDelaunayTriangulation per polygon
 *                -> optionally write the layers water and mesh (GeoPackage,
 *                   the same layout as gdal_watermesh's output)
 *
 * -union block swaps the first two steps: every buffer and lake is cut into
 * blocks first and each block's pieces are unioned on their own.
 *
 * Blocks are streamed: each is cut, simplified, triangulated and written
 * before the next, so only the union (or the buffers) and one block are
 * held. Stage times are wall-clock (CLOCK_MONOTONIC) summed over blocks,
 * like gdal_watermesh -stats. Reentrant GEOS API (GEOS_init_r and *_r
 * functions) throughout.
 */
#define _POSIX_C_SOURCE 200809L

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include <cpl_conv.h>
#include <cpl_string.h>
#include <gdal.h>
#include <geos_c.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#define MAX_WIDTH 100000.0

enum
{
    ST_READ,
    ST_BUFFER,
    ST_VALID,
    ST_UNION,
    ST_CLIP,
    ST_SIMPLIFY,
    ST_TRIANGULATE,
    ST_WRITE,
    ST_COUNT
};
static const char *stage_names[ST_COUNT] = {
    "read", "buffer",   "lake validity", "union",
    "clip", "simplify", "triangulate",   "write"};

typedef struct
{
    const char *rivers, *rivers_layer, *lakes, *lakes_layer;
    const char *width_field, *out;
    double width, block, simplify;
    int quadsegs, clip_rect, union_per_block, check_valid;
} options;

typedef struct
{
    GEOSGeometry **g;
    size_t n, cap;
} geom_list;

typedef struct
{
    double sec[ST_COUNT];
    size_t river_vertices, lake_vertices, lakes_made_valid, union_parts;
    size_t union_polygons, blocks;
    size_t polygons, vertices, triangles, cdt_failures;
    size_t invalid_clipped, invalid_simplified;
} stats;

static GEOSContextHandle_t ctx;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void die(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("geos_peer: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(1);
}

static void geos_error(const char *message, void *userdata)
{
    (void)userdata;
    fprintf(stderr, "geos_peer: GEOS error: %s\n", message);
}

static void geos_notice(const char *message, void *userdata)
{
    (void)message;
    (void)userdata;
}

static void list_push(geom_list *l, GEOSGeometry *g)
{
    if (l->n == l->cap)
    {
        l->cap = l->cap ? 2 * l->cap : 256;
        l->g = realloc(l->g, l->cap * sizeof *l->g);
        if (!l->g)
            die("out of memory");
    }
    l->g[l->n++] = g;
}

/* A width value as gdal_watermesh reads it: a number, optionally followed by
 * m / meters / metres or ft / feet / '. */
static int parse_width(const char *s, double *w)
{
    char *end = NULL;
    while (*s && isspace((unsigned char)*s))
        s++;
    const double v = CPLStrtod(s, &end);
    if (end == s || !isfinite(v))
        return 0;
    while (*end && isspace((unsigned char)*end))
        end++;
    double f = 1.0;
    if (EQUAL(end, "ft") || EQUAL(end, "feet") || EQUAL(end, "'"))
        f = 0.3048;
    else if (*end && !EQUAL(end, "m") && !EQUAL(end, "meters") &&
             !EQUAL(end, "metres"))
        return 0;
    *w = v * f;
    return *w > 0 && *w <= MAX_WIDTH;
}

static double feature_width(OGRFeatureH f, int field, OGRFieldType type,
                            double fallback)
{
    if (field < 0 || !OGR_F_IsFieldSetAndNotNull(f, field))
        return fallback;
    double v;
    if (type == OFTReal || type == OFTInteger || type == OFTInteger64)
    {
        v = OGR_F_GetFieldAsDouble(f, field);
        return isfinite(v) && v > 0 && v <= MAX_WIDTH ? v : fallback;
    }
    return parse_width(OGR_F_GetFieldAsString(f, field), &v) ? v : fallback;
}

/* OGR geometry -> GEOS (2D, curves linearized, reprojected with ct). */
static GEOSGeometry *to_geos(OGRGeometryH g0, OGRCoordinateTransformationH ct,
                             size_t *npoints)
{
    OGRGeometryH g = OGR_G_HasCurveGeometry(g0, TRUE)
                         ? OGR_G_GetLinearGeometry(g0, 0, NULL)
                         : OGR_G_Clone(g0);
    OGR_G_FlattenTo2D(g);
    if (ct && OGR_G_Transform(g, ct) != OGRERR_NONE)
        die("reprojection failed");
    const size_t size = (size_t)OGR_G_WkbSize(g);
    unsigned char *buf = malloc(size);
    if (!buf)
        die("out of memory");
    OGR_G_ExportToWkb(g, wkbNDR, buf);
    OGR_G_DestroyGeometry(g);
    GEOSGeometry *out = GEOSGeomFromWKB_buf_r(ctx, buf, size);
    free(buf);
    if (!out)
        die("cannot convert a geometry to GEOS");
    *npoints += (size_t)GEOSGetNumCoordinates_r(ctx, out);
    return out;
}

static OGRLayerH open_layer(const char *path, const char *name,
                            GDALDatasetH *ds)
{
    *ds = GDALOpenEx(path, GDAL_OF_VECTOR | GDAL_OF_READONLY, NULL, NULL, NULL);
    if (!*ds)
        die("cannot open %s", path);
    OGRLayerH l = name ? GDALDatasetGetLayerByName(*ds, name)
                       : GDALDatasetGetLayer(*ds, 0);
    if (!l)
        die("no layer %s in %s", name ? name : "0", path);
    return l;
}

static OGRCoordinateTransformationH transform_to(OGRLayerH l,
                                                 OGRSpatialReferenceH dst)
{
    OGRSpatialReferenceH s = OGR_L_GetSpatialRef(l);
    if (!s || OSRIsSame(s, dst))
        return NULL;
    OGRCoordinateTransformationH ct = OCTNewCoordinateTransformation(s, dst);
    if (!ct)
        die("cannot reproject layer %s", OGR_L_GetName(l));
    return ct;
}

/* Reads the rivers: GEOS lines and their widths. */
static void read_rivers(OGRLayerH l, OGRSpatialReferenceH srs, const options *o,
                        geom_list *lines, double **widths, stats *st)
{
    int field = -1;
    OGRFieldType type = OFTString;
    if (o->width_field)
    {
        field = OGR_FD_GetFieldIndex(OGR_L_GetLayerDefn(l), o->width_field);
        if (field < 0)
            die("rivers layer has no field %s", o->width_field);
        type =
            OGR_Fld_GetType(OGR_FD_GetFieldDefn(OGR_L_GetLayerDefn(l), field));
    }
    OGRCoordinateTransformationH ct = transform_to(l, srs);
    size_t cap = 0;
    OGRFeatureH f;
    OGR_L_ResetReading(l);
    while ((f = OGR_L_GetNextFeature(l)) != NULL)
    {
        OGRGeometryH g = OGR_F_GetGeometryRef(f);
        if (g && !OGR_G_IsEmpty(g))
        {
            GEOSGeometry *line = to_geos(g, ct, &st->river_vertices);
            double len = 0;
            if (GEOSLength_r(ctx, line, &len) != 1 || len <= 0)
                GEOSGeom_destroy_r(ctx, line); /* watermesh skips these too */
            else
            {
                if (lines->n == cap)
                {
                    cap = cap ? 2 * cap : 256;
                    *widths = realloc(*widths, cap * sizeof **widths);
                    if (!*widths)
                        die("out of memory");
                }
                (*widths)[lines->n] = feature_width(f, field, type, o->width);
                list_push(lines, line);
            }
        }
        OGR_F_Destroy(f);
    }
    if (ct)
        OCTDestroyCoordinateTransformation(ct);
}

static void read_lakes(OGRLayerH l, OGRSpatialReferenceH srs, geom_list *lakes,
                       stats *st)
{
    OGRCoordinateTransformationH ct = transform_to(l, srs);
    OGRFeatureH f;
    OGR_L_ResetReading(l);
    while ((f = OGR_L_GetNextFeature(l)) != NULL)
    {
        OGRGeometryH g = OGR_F_GetGeometryRef(f);
        if (g && !OGR_G_IsEmpty(g))
            list_push(lakes, to_geos(g, ct, &st->lake_vertices));
        OGR_F_Destroy(f);
    }
    if (ct)
        OCTDestroyCoordinateTransformation(ct);
}

/* Appends copies of the polygons of g with positive area to out. */
static void add_polygons(const GEOSGeometry *g, geom_list *out)
{
    const int t = GEOSGeomTypeId_r(ctx, g);
    if (t == GEOS_POLYGON)
    {
        double a = 0;
        if (!GEOSisEmpty_r(ctx, g) && GEOSArea_r(ctx, g, &a) == 1 && a > 0)
            list_push(out, GEOSGeom_clone_r(ctx, g));
    }
    else if (t == GEOS_MULTIPOLYGON || t == GEOS_GEOMETRYCOLLECTION)
    {
        const int n = GEOSGetNumGeometries_r(ctx, g);
        for (int i = 0; i < n; i++)
            add_polygons(GEOSGetGeometryN_r(ctx, g, i), out);
    }
}

static size_t ring_vertices(const GEOSGeometry *poly)
{
    /* coordinates without the closing point of each ring */
    return (size_t)GEOSGetNumCoordinates_r(ctx, poly) -
           (size_t)(1 + GEOSGetNumInteriorRings_r(ctx, poly));
}

static void envelope(const GEOSGeometry *g, double e[4])
{
    GEOSGeom_getXMin_r(ctx, g, &e[0]);
    GEOSGeom_getYMin_r(ctx, g, &e[1]);
    GEOSGeom_getXMax_r(ctx, g, &e[2]);
    GEOSGeom_getYMax_r(ctx, g, &e[3]);
}

typedef struct
{
    size_t *idx;
    size_t n, cap;
} hits;

static void collect(void *item, void *data)
{
    hits *h = data;
    if (h->n == h->cap)
    {
        h->cap = h->cap ? 2 * h->cap : 64;
        h->idx = realloc(h->idx, h->cap * sizeof *h->idx);
        if (!h->idx)
            die("out of memory");
    }
    h->idx[h->n++] = (size_t)(uintptr_t)item - 1; /* items are index + 1 */
}

static int cmp_size(const void *a, const void *b)
{
    const size_t x = *(const size_t *)a, y = *(const size_t *)b;
    return x < y ? -1 : x > y;
}

static OGRGeometryH to_ogr(const GEOSGeometry *g)
{
    size_t size = 0;
    unsigned char *buf = GEOSGeomToWKB_buf_r(ctx, g, &size);
    OGRGeometryH out = NULL;
    if (!buf || OGR_G_CreateFromWkb(buf, NULL, &out, (int)size) != OGRERR_NONE)
        die("cannot convert a GEOS geometry to OGR");
    GEOSFree_r(ctx, buf);
    return out;
}

typedef struct
{
    GDALDatasetH ds;
    OGRLayerH water, mesh;
} output;

static void open_output(output *out, const char *path, OGRSpatialReferenceH srs)
{
    GDALDriverH drv = GDALGetDriverByName("GPKG");
    VSIUnlink(path);
    out->ds = GDALCreate(drv, path, 0, 0, 0, GDT_Unknown, NULL);
    if (!out->ds)
        die("cannot create %s", path);
    out->water =
        GDALDatasetCreateLayer(out->ds, "water", srs, wkbPolygon, NULL);
    out->mesh =
        GDALDatasetCreateLayer(out->ds, "mesh", srs, wkbMultiPolygon, NULL);
    if (!out->water || !out->mesh)
        die("cannot create the output layers");
    const char *wf[] = {"block_x", "block_y", "area"};
    const char *mf[] = {"block_x", "block_y", "triangles"};
    for (int i = 0; i < 3; i++)
    {
        OGRFieldDefnH fd = OGR_Fld_Create(wf[i], i == 2 ? OFTReal : OFTInteger);
        OGR_L_CreateField(out->water, fd, TRUE);
        OGR_Fld_Destroy(fd);
        fd = OGR_Fld_Create(mf[i], OFTInteger);
        OGR_L_CreateField(out->mesh, fd, TRUE);
        OGR_Fld_Destroy(fd);
    }
    GDALDatasetStartTransaction(out->ds, FALSE);
}

static void write_polygon(output *out, long bx, long by,
                          const GEOSGeometry *poly, const GEOSGeometry *tris)
{
    double area = 0;
    GEOSArea_r(ctx, poly, &area);
    OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(out->water));
    OGR_F_SetFieldInteger(f, 0, (int)bx);
    OGR_F_SetFieldInteger(f, 1, (int)by);
    OGR_F_SetFieldDouble(f, 2, area);
    OGR_F_SetGeometryDirectly(f, to_ogr(poly));
    if (OGR_L_CreateFeature(out->water, f) != OGRERR_NONE)
        die("cannot write a water feature");
    OGR_F_Destroy(f);
    if (!tris)
        return;
    f = OGR_F_Create(OGR_L_GetLayerDefn(out->mesh));
    OGR_F_SetFieldInteger(f, 0, (int)bx);
    OGR_F_SetFieldInteger(f, 1, (int)by);
    OGR_F_SetFieldInteger(f, 2, GEOSGetNumGeometries_r(ctx, tris));
    OGR_F_SetGeometryDirectly(f, OGR_G_ForceToMultiPolygon(to_ogr(tris)));
    if (OGR_L_CreateFeature(out->mesh, f) != OGRERR_NONE)
        die("cannot write a mesh feature");
    OGR_F_Destroy(f);
}

/* A set of polygons indexed by an STRtree (items: index + 1). */
typedef struct
{
    const geom_list *g;
    double (*env)[4];
    GEOSSTRtree *tree;
    double ext[4]; /* extent of all, xmin > xmax when empty */
} indexed;

static void index_build(indexed *x, const geom_list *g)
{
    x->g = g;
    x->env = malloc((g->n ? g->n : 1) * sizeof *x->env);
    x->tree = GEOSSTRtree_create_r(ctx, 10);
    if (!x->env || !x->tree)
        die("out of memory");
    x->ext[0] = x->ext[1] = HUGE_VAL;
    x->ext[2] = x->ext[3] = -HUGE_VAL;
    for (size_t i = 0; i < g->n; i++)
    {
        envelope(g->g[i], x->env[i]);
        GEOSSTRtree_insert_r(ctx, x->tree, g->g[i], (void *)(uintptr_t)(i + 1));
        for (int k = 0; k < 2; k++)
        {
            x->ext[k] = fmin(x->ext[k], x->env[i][k]);
            x->ext[k + 2] = fmax(x->ext[k + 2], x->env[i][k + 2]);
        }
    }
}

static void index_free(indexed *x)
{
    GEOSSTRtree_destroy_r(ctx, x->tree);
    free(x->env);
}

/* Appends to out the polygons of the indexed geometries inside the block
 * square [x0, x1] x [y0, y1]: a geometry inside the square is copied whole,
 * one across its border is clipped. */
static void clip_block(const options *o, const indexed *x, double x0, double y0,
                       double x1, double y1, hits *h, geom_list *out)
{
    GEOSGeometry *box = GEOSGeom_createRectangle_r(ctx, x0, y0, x1, y1);
    h->n = 0;
    GEOSSTRtree_query_r(ctx, x->tree, box, collect, h);
    qsort(h->idx, h->n, sizeof *h->idx, cmp_size); /* deterministic order */
    for (size_t k = 0; k < h->n; k++)
    {
        const size_t i = h->idx[k];
        const GEOSGeometry *c = x->g->g[i];
        const double *e = x->env[i];
        if (e[0] >= x0 && e[1] >= y0 && e[2] <= x1 && e[3] <= y1)
        {
            add_polygons(c, out);
            continue;
        }
        if (e[2] <= x0 || e[0] >= x1 || e[3] <= y0 || e[1] >= y1)
            continue; /* touches the square only on its border */
        GEOSGeometry *r = o->clip_rect
                              ? GEOSClipByRect_r(ctx, c, x0, y0, x1, y1)
                              : GEOSIntersection_r(ctx, c, box);
        if (!r)
            die("clip failed");
        add_polygons(r, out);
        GEOSGeom_destroy_r(ctx, r);
    }
    GEOSGeom_destroy_r(ctx, box);
}

/* Simplifies, triangulates (and writes) the polygons of one block; takes
 * ownership of the polygons of `polys` and empties it. */
static void finish_block(const options *o, long bx, long by, geom_list *polys,
                         output *out, stats *st)
{
    if (!polys->n)
        return;
    st->blocks++;
    if (o->check_valid)
        for (size_t k = 0; k < polys->n; k++)
            st->invalid_clipped += GEOSisValid_r(ctx, polys->g[k]) != 1;

    /* simplify the block's polygons together, so that the simplifier keeps
     * them apart */
    double t = now();
    geom_list simplified = {0};
    GEOSGeometry *mp = NULL;
    if (o->simplify > 0)
    {
        mp = GEOSGeom_createCollection_r(ctx, GEOS_MULTIPOLYGON, polys->g,
                                         (unsigned)polys->n);
        GEOSGeometry *s = GEOSTopologyPreserveSimplify_r(ctx, mp, o->simplify);
        if (!mp || !s)
            die("simplify failed in block %ld %ld", bx, by);
        add_polygons(s, &simplified);
        GEOSGeom_destroy_r(ctx, s);
    }
    else
        for (size_t k = 0; k < polys->n; k++)
            list_push(&simplified, GEOSGeom_clone_r(ctx, polys->g[k]));
    st->sec[ST_SIMPLIFY] += now() - t;
    if (o->check_valid)
        for (size_t k = 0; k < simplified.n; k++)
            st->invalid_simplified += GEOSisValid_r(ctx, simplified.g[k]) != 1;

    for (size_t k = 0; k < simplified.n; k++)
    {
        const GEOSGeometry *poly = simplified.g[k];
        t = now();
        GEOSGeometry *tris = GEOSConstrainedDelaunayTriangulation_r(ctx, poly);
        st->sec[ST_TRIANGULATE] += now() - t;
        st->polygons++;
        st->vertices += ring_vertices(poly);
        if (tris)
            st->triangles += (size_t)GEOSGetNumGeometries_r(ctx, tris);
        else
            st->cdt_failures++;
        if (o->out)
        {
            t = now();
            write_polygon(out, bx, by, poly, tris);
            st->sec[ST_WRITE] += now() - t;
        }
        if (tris)
            GEOSGeom_destroy_r(ctx, tris);
    }
    t = now();
    for (size_t k = 0; k < simplified.n; k++)
        GEOSGeom_destroy_r(ctx, simplified.g[k]);
    free(simplified.g);
    if (mp)
        GEOSGeom_destroy_r(ctx, mp); /* owns the polygons */
    else
        for (size_t k = 0; k < polys->n; k++)
            GEOSGeom_destroy_r(ctx, polys->g[k]);
    polys->n = 0;
    st->sec[ST_SIMPLIFY] += now() - t;
}

static long block_of(double v, double B)
{
    return (long)floor(v / B);
}

/* The classic order: union everything once, then cut the union into
 * blocks. Consumes the geometries of parts. */
static void run_global_union(const options *o, geom_list *parts, output *out,
                             stats *st)
{
    double t = now();
    GEOSGeometry *coll = GEOSGeom_createCollection_r(
        ctx, GEOS_GEOMETRYCOLLECTION, parts->g, (unsigned)parts->n);
    if (!coll)
        die("cannot build the collection");
    GEOSGeometry *water = GEOSUnaryUnion_r(ctx, coll);
    if (!water)
        die("union failed");
    GEOSGeom_destroy_r(ctx, coll);
    geom_list comps = {0};
    for (int i = 0; i < GEOSGetNumGeometries_r(ctx, water); i++)
        list_push(&comps, (GEOSGeometry *)GEOSGetGeometryN_r(ctx, water, i));
    st->union_polygons = comps.n;
    st->sec[ST_UNION] = now() - t;

    t = now();
    indexed x;
    index_build(&x, &comps);
    st->sec[ST_CLIP] += now() - t;
    hits h = {0};
    geom_list polys = {0};
    const double B = o->block;
    for (long by = block_of(x.ext[1], B);
         comps.n && by <= block_of(x.ext[3], B); by++)
        for (long bx = block_of(x.ext[0], B); bx <= block_of(x.ext[2], B); bx++)
        {
            t = now();
            clip_block(o, &x, (double)bx * B, (double)by * B,
                       (double)(bx + 1) * B, (double)(by + 1) * B, &h, &polys);
            st->sec[ST_CLIP] += now() - t;
            finish_block(o, bx, by, &polys, out, st);
        }
    index_free(&x);
    free(h.idx);
    free(polys.g);
    free(comps.g); /* borrowed from water */
    GEOSGeom_destroy_r(ctx, water);
}

/* Union per block: clip every buffer and lake to the block, then union the
 * pieces of that block only. Consumes the geometries of parts. */
static void run_union_per_block(const options *o, geom_list *parts, output *out,
                                stats *st)
{
    double t = now();
    indexed x;
    index_build(&x, parts);
    st->sec[ST_CLIP] += now() - t;
    hits h = {0};
    geom_list pieces = {0}, polys = {0};
    const double B = o->block;
    for (long by = block_of(x.ext[1], B);
         parts->n && by <= block_of(x.ext[3], B); by++)
        for (long bx = block_of(x.ext[0], B); bx <= block_of(x.ext[2], B); bx++)
        {
            t = now();
            clip_block(o, &x, (double)bx * B, (double)by * B,
                       (double)(bx + 1) * B, (double)(by + 1) * B, &h, &pieces);
            st->sec[ST_CLIP] += now() - t;
            if (!pieces.n)
                continue;
            t = now();
            GEOSGeometry *coll = GEOSGeom_createCollection_r(
                ctx, GEOS_GEOMETRYCOLLECTION, pieces.g, (unsigned)pieces.n);
            GEOSGeometry *u = coll ? GEOSUnaryUnion_r(ctx, coll) : NULL;
            if (!u)
                die("union failed in block %ld %ld", bx, by);
            pieces.n = 0;
            add_polygons(u, &polys);
            st->union_polygons += polys.n;
            GEOSGeom_destroy_r(ctx, u);
            GEOSGeom_destroy_r(ctx, coll);
            st->sec[ST_UNION] += now() - t;
            finish_block(o, bx, by, &polys, out, st);
        }
    index_free(&x);
    free(h.idx);
    free(pieces.g);
    free(polys.g);
    for (size_t i = 0; i < parts->n; i++)
        GEOSGeom_destroy_r(ctx, parts->g[i]);
}

static void usage(void)
{
    fputs(
        "Usage: geos_peer [-rivers <ds>] [-rivers_layer <name>]\n"
        "                 [-lakes <ds>] [-lakes_layer <name>]\n"
        "                 [-width <m>] [-width_field <field>]\n"
        "                 [-block_size <m>] [-simplify <m>] [-quadsegs <n>]\n"
        "                 [-union global|block] [-clip rect|overlay]\n"
        "                 [-check_valid] [-o <out.gpkg>]\n"
        "Defaults: -width 10, -block_size 4096, -simplify 0.25, -quadsegs 8,\n"
        "-union global (union everything, then cut into blocks; block: cut\n"
        "every buffer and lake into blocks, then union per block), -clip rect\n"
        "(GEOSClipByRect; overlay: GEOSIntersection). -simplify 0 skips\n"
        "simplification. -check_valid counts (untimed) invalid polygons after\n"
        "clipping/union and after simplification.\n",
        stderr);
    exit(2);
}

static void parse_args(int argc, char **argv, options *o)
{
    memset(o, 0, sizeof *o);
    o->width = 10;
    o->block = 4096;
    o->simplify = 0.25;
    o->quadsegs = 8;
    o->clip_rect = 1;
    for (int i = 1; i < argc; i++)
    {
        const char *a = argv[i];
        const int more = i + 1 < argc;
        if (!strcmp(a, "-rivers") && more)
            o->rivers = argv[++i];
        else if (!strcmp(a, "-rivers_layer") && more)
            o->rivers_layer = argv[++i];
        else if (!strcmp(a, "-lakes") && more)
            o->lakes = argv[++i];
        else if (!strcmp(a, "-lakes_layer") && more)
            o->lakes_layer = argv[++i];
        else if (!strcmp(a, "-width") && more)
            o->width = CPLAtof(argv[++i]);
        else if (!strcmp(a, "-width_field") && more)
            o->width_field = argv[++i];
        else if (!strcmp(a, "-block_size") && more)
            o->block = CPLAtof(argv[++i]);
        else if (!strcmp(a, "-simplify") && more)
            o->simplify = CPLAtof(argv[++i]);
        else if (!strcmp(a, "-quadsegs") && more)
            o->quadsegs = atoi(argv[++i]);
        else if (!strcmp(a, "-clip") && more)
        {
            const char *v = argv[++i];
            if (!strcmp(v, "overlay"))
                o->clip_rect = 0;
            else if (strcmp(v, "rect"))
                usage();
        }
        else if (!strcmp(a, "-union") && more)
        {
            const char *v = argv[++i];
            if (!strcmp(v, "block"))
                o->union_per_block = 1;
            else if (strcmp(v, "global"))
                usage();
        }
        else if (!strcmp(a, "-check_valid"))
            o->check_valid = 1;
        else if (!strcmp(a, "-o") && more)
            o->out = argv[++i];
        else
            usage();
    }
    if ((!o->rivers && !o->lakes) || !(o->width > 0) || !(o->block > 0) ||
        !(o->simplify >= 0) || o->quadsegs < 1)
        usage();
}

int main(int argc, char **argv)
{
    options o;
    parse_args(argc, argv, &o);
    stats st;
    memset(&st, 0, sizeof st);
    const double t_start = now();

    GDALAllRegister();
    ctx = GEOS_init_r();
    GEOSContext_setErrorMessageHandler_r(ctx, geos_error, NULL);
    GEOSContext_setNoticeMessageHandler_r(ctx, geos_notice, NULL);

    /* ---- read ---- */
    double t = now();
    GDALDatasetH rds = NULL, lds = NULL;
    OGRLayerH rl = o.rivers ? open_layer(o.rivers, o.rivers_layer, &rds) : NULL;
    OGRLayerH ll = o.lakes ? open_layer(o.lakes, o.lakes_layer, &lds) : NULL;
    OGRSpatialReferenceH srs0 = OGR_L_GetSpatialRef(rl ? rl : ll);
    if (!srs0 || !OSRIsProjected(srs0))
        die("the first input layer must be in a projected CRS (metres)");
    OGRSpatialReferenceH srs = OSRClone(srs0);
    OSRSetAxisMappingStrategy(srs, OAMS_TRADITIONAL_GIS_ORDER);
    geom_list lines = {0}, lakes = {0};
    double *widths = NULL;
    if (rl)
        read_rivers(rl, srs, &o, &lines, &widths, &st);
    if (ll)
        read_lakes(ll, srs, &lakes, &st);
    st.sec[ST_READ] = now() - t;

    /* ---- buffer ---- */
    geom_list parts = {0};
    t = now();
    for (size_t i = 0; i < lines.n; i++)
    {
        GEOSGeometry *b =
            GEOSBuffer_r(ctx, lines.g[i], widths[i] / 2.0, o.quadsegs);
        if (!b)
            die("buffer failed");
        GEOSGeom_destroy_r(ctx, lines.g[i]);
        list_push(&parts, b);
    }
    st.sec[ST_BUFFER] = now() - t;
    free(lines.g);
    free(widths);

    /* ---- lakes: make invalid ones valid ---- */
    t = now();
    for (size_t i = 0; i < lakes.n; i++)
    {
        if (GEOSisValid_r(ctx, lakes.g[i]) == 1)
        {
            list_push(&parts, lakes.g[i]);
            continue;
        }
        GEOSGeometry *v = GEOSMakeValid_r(ctx, lakes.g[i]);
        if (!v)
            die("make valid failed");
        st.lakes_made_valid++;
        geom_list polys = {0};
        add_polygons(v, &polys);
        for (size_t k = 0; k < polys.n; k++)
            list_push(&parts, polys.g[k]);
        free(polys.g);
        GEOSGeom_destroy_r(ctx, v);
        GEOSGeom_destroy_r(ctx, lakes.g[i]);
    }
    st.sec[ST_VALID] = now() - t;
    free(lakes.g);

    st.union_parts = parts.n;
    output out = {0};
    if (o.out)
        open_output(&out, o.out, srs);
    if (o.union_per_block)
        run_union_per_block(&o, &parts, &out, &st);
    else
        run_global_union(&o, &parts, &out, &st);
    free(parts.g);
    if (o.out)
    {
        t = now();
        GDALDatasetCommitTransaction(out.ds);
        GDALClose(out.ds);
        st.sec[ST_WRITE] += now() - t;
    }
    OSRDestroySpatialReference(srs);
    if (rds)
        GDALClose(rds);
    if (lds)
        GDALClose(lds);
    GEOS_finish_r(ctx);

    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double total = 0;
    printf("%-16s %12s\n", "stage", "seconds");
    for (int i = 0; i < ST_COUNT; i++)
    {
        printf("%-16s %12.3f\n", stage_names[i], st.sec[i]);
        if (i != ST_READ && i != ST_WRITE)
            total += st.sec[i];
    }
    printf("%-16s %12.3f\n", "total (stages)", total);
    printf("%-16s %12.3f\n", "process", now() - t_start);
    printf("%-16s %12.3f\n", "cpu",
           (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
               (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec);
    printf("peak RSS %ld KB\n", ru.ru_maxrss);
    printf("GEOS %s, quadsegs %d, union %s, clip %s, simplify %g, "
           "block %g\n",
           GEOSversion(), o.quadsegs, o.union_per_block ? "block" : "global",
           o.clip_rect ? "rect" : "overlay", o.simplify, o.block);
    printf("%lu union parts (%lu lakes made valid), %lu union polygons\n",
           (unsigned long)st.union_parts, (unsigned long)st.lakes_made_valid,
           (unsigned long)st.union_polygons);
    printf("blocks %lu, polygons %lu, output vertices %lu, triangles %lu, "
           "CDT failures %lu\n",
           (unsigned long)st.blocks, (unsigned long)st.polygons,
           (unsigned long)st.vertices, (unsigned long)st.triangles,
           (unsigned long)st.cdt_failures);
    if (o.check_valid)
        printf("invalid polygons: %lu after clipping, %lu after "
               "simplification\n",
               (unsigned long)st.invalid_clipped,
               (unsigned long)st.invalid_simplified);
    const double denom =
        2.0 * (double)st.river_vertices + (double)st.lake_vertices;
    printf("V = %.3f (output vertices / (2 * %lu river + %lu lake "
           "vertices))\n",
           denom > 0 ? (double)st.vertices / denom : 0.0,
           (unsigned long)st.river_vertices, (unsigned long)st.lake_vertices);
    return st.cdt_failures ? 1 : 0;
}
