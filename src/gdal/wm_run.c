/*
 * wm_run.c - the parallel block runner, feature emission and the public
 * entry point WMGenerate.
 *
 * Runner: worker threads take block indices in order from a shared
 * counter, never more than `window` ahead of the consumer, and park their
 * results in a ring of slots; the calling thread hands results to the sink
 * strictly in block order. So output order (and bytes) do not depend on the
 * thread count (invariant 7) and memory is bounded by the window, not by
 * the scene.
 *
 * With an OpenCL field device the blocks are pipelined: a feeder thread
 * computes the fields in block order (host preparation, then the device),
 * parking them in the same ring, while the workers run the CPU stages of
 * the blocks whose fields are ready. So the device computes block k+1's
 * field while the CPU extracts, simplifies and triangulates block k.
 */
#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_string.h>

#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct
{
    const WMScene *s;
    const int64_t *blocks;
    size_t nblocks, window;
    const WMBlockSink *sink;
    wm_block_opts opts;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    size_t next;     /* next block to take */
    size_t consumed; /* blocks handed to the sink */
    int stop;
    wm_block_result *slot; /* window slots */
    void **prep;           /* per slot: what sink->prepare made */
    int *ready;            /* per slot: 0 empty, 1 ok, -1 failed */
    char **msg;            /* per slot: error text */
    /* pipelined runs only (a feeder computes the fields) */
    int pipelined;
    wm_field *field; /* per slot: the block's field */
    int *fready;     /* per slot: 0 not yet, 1 ok, -1 failed */
    char **fmsg;     /* per slot: the field's error text */
    double *fsec;    /* per slot: the field's time */
} runner;

void WMKeepFirstError(void *user, wm_status status, const char *msg)
{
    (void)status;
    char **dst = user;
    if (!*dst)
        *dst = CPLStrdup(msg);
}

static void *feeder(void *arg)
{
    runner *r = arg;
    pthread_mutex_lock(&r->mu);
    for (size_t i = 0;; i++)
    {
        while (!r->stop && i < r->nblocks && i >= r->consumed + r->window)
            pthread_cond_wait(&r->cv, &r->mu);
        if (r->stop || i >= r->nblocks)
            break;
        pthread_mutex_unlock(&r->mu);

        wm_field f;
        char *msg = NULL;
        wm_ctx ctx = {WMKeepFirstError, &msg, &r->stop};
        const double t0 = wm_now();
        const wm_status st =
            wm_block_field(&r->s->core, r->blocks[2 * i], r->blocks[2 * i + 1],
                           &r->opts, &f, &ctx);
        const double sec = wm_now() - t0;
        pthread_mutex_lock(&r->mu);
        const size_t k = i % r->window;
        r->field[k] = f;
        r->fmsg[k] = msg;
        r->fsec[k] = sec;
        r->fready[k] = st == WM_OK ? 1 : -1;
        pthread_cond_broadcast(&r->cv);
    }
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

static void *worker(void *arg)
{
    runner *r = arg;
    pthread_mutex_lock(&r->mu);
    for (;;)
    {
        while (!r->stop && r->next < r->nblocks &&
               (r->next >= r->consumed + r->window ||
                (r->pipelined && !r->fready[r->next % r->window])))
            pthread_cond_wait(&r->cv, &r->mu);
        if (r->stop || r->next >= r->nblocks)
            break;
        const size_t i = r->next++;
        const size_t k = i % r->window;
        wm_field f;
        int fok = 1;
        char *msg = NULL;
        double fsec = 0;
        if (r->pipelined)
        {
            f = r->field[k];
            fok = r->fready[k] > 0;
            msg = r->fmsg[k];
            fsec = r->fsec[k];
            r->fready[k] = 0;
            r->fmsg[k] = NULL;
        }
        pthread_mutex_unlock(&r->mu);

        wm_block_result res;
        memset(&res, 0, sizeof res);
        wm_ctx ctx = {WMKeepFirstError, &msg, &r->stop};
        const int64_t bx = r->blocks[2 * i], by = r->blocks[2 * i + 1];
        wm_status st = WM_ERR_DEVICE;
        if (!r->pipelined)
            st = wm_block_run(&r->s->core, bx, by, &r->opts, &res, &ctx);
        else if (fok)
        {
            st = wm_block_finish(&r->s->core, bx, by, &f, &r->opts, &res, &ctx);
            res.seconds[WM_STAGE_FIELD] = fsec;
        }
        if (st == WM_OK && r->s->drape)
        {
            const double t0 = wm_now();
            st = wm_drape_block(&r->s->core, &r->s->drape->core, &res);
            if (st != WM_OK)
            {
                wm_fail(&ctx, st, "out of memory draping the block");
                wm_block_result_free(&res); /* failed slots are not freed */
            }
            res.seconds[WM_STAGE_TRIANGULATE] += wm_now() - t0;
        }
        void *prep = st == WM_OK && r->sink->prepare
                         ? r->sink->prepare(r->sink->user, &res)
                         : NULL;
        pthread_mutex_lock(&r->mu);
        r->slot[k] = res;
        r->prep[k] = prep;
        r->msg[k] = msg;
        r->ready[k] = st == WM_OK ? 1 : -1;
        pthread_cond_broadcast(&r->cv);
    }
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

/* Waits (r->mu held) until slot k is ready, asking pfn every 100 ms
 * (with the fraction done) whether to go on; FALSE when it says stop:
 * then the workers stop too, within a few milliseconds of work (the core's
 * loops check r->stop through their wm_ctx). */
static int wait_ready(runner *r, size_t k, GDALProgressFunc pfn, void *pArg,
                      double done)
{
    while (!r->ready[k])
    {
        if (!pfn)
        {
            pthread_cond_wait(&r->cv, &r->mu);
            continue;
        }
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += 100 * 1000 * 1000;
        if (ts.tv_nsec >= 1000 * 1000 * 1000)
        {
            ts.tv_sec++;
            ts.tv_nsec -= 1000 * 1000 * 1000;
        }
        if (pthread_cond_timedwait(&r->cv, &r->mu, &ts) == 0 || r->ready[k])
            continue;
        pthread_mutex_unlock(&r->mu);
        const int go_on = pfn(done, "", pArg);
        pthread_mutex_lock(&r->mu);
        if (!go_on)
        {
            __atomic_store_n(&r->stop, 1, __ATOMIC_RELAXED);
            pthread_cond_broadcast(&r->cv);
            return FALSE;
        }
    }
    return TRUE;
}

/* The block options of scene s, in lattice units. */
static wm_block_opts block_opts(const WMScene *s)
{
    wm_block_opts o;
    memset(&o, 0, sizeof o);
    o.simplify = s->params.simplify / s->unit;
    o.triangulate = 1;
    o.method = s->params.method;
    o.heuristic = s->params.heuristic;
    o.merge = s->params.merge / s->unit;
    o.min_area = s->params.min_feature_area / (s->unit * s->unit);
    o.min_angle = s->params.min_angle;
    o.max_edge = s->params.max_edge / s->unit;
    o.dev = WMDeviceField(s->device);
    return o;
}

static void runner_init(runner *r, const WMScene *s, const int64_t *blocks,
                        size_t nblocks, const WMBlockSink *sink, int nthreads)
{
    memset(r, 0, sizeof *r);
    r->s = s;
    r->blocks = blocks;
    r->nblocks = nblocks;
    r->sink = sink;
    r->window = 4 * (size_t)nthreads + 1; /* slack behind a slow block */
    r->opts = block_opts(s);
    r->pipelined = r->opts.dev != NULL;
    r->slot = CPLCalloc(r->window, sizeof *r->slot);
    r->prep = CPLCalloc(r->window, sizeof *r->prep);
    r->field = CPLCalloc(r->window, sizeof *r->field);
    r->fready = CPLCalloc(r->window, sizeof *r->fready);
    r->fmsg = CPLCalloc(r->window, sizeof *r->fmsg);
    r->fsec = CPLCalloc(r->window, sizeof *r->fsec);
    r->ready = CPLCalloc(r->window, sizeof *r->ready);
    r->msg = CPLCalloc(r->window, sizeof *r->msg);
    pthread_mutex_init(&r->mu, NULL);
    pthread_cond_init(&r->cv, NULL);
}

/* Starts the feeder (pipelined runs) and up to nthreads workers into th;
 * returns how many threads started, *workers how many of them work. */
static int start_threads(runner *r, int nthreads, pthread_t *th, int *workers)
{
    int started = 0;
    *workers = 0;
    if (r->pipelined && pthread_create(&th[started], NULL, feeder, r) != 0)
        return 0;
    started += r->pipelined;
    for (; *workers < nthreads; (*workers)++, started++)
        if (pthread_create(&th[started], NULL, worker, r) != 0)
            break;
    return started;
}

/* Stops and joins the threads, then frees what the slots still hold. */
static void runner_free(runner *r, pthread_t *th, int started)
{
    pthread_mutex_lock(&r->mu);
    __atomic_store_n(&r->stop, 1, __ATOMIC_RELAXED);
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    for (int t = 0; t < started; t++)
        pthread_join(th[t], NULL);
    for (size_t k = 0; k < r->window; k++)
    {
        if (r->ready[k] > 0)
            wm_block_result_free(&r->slot[k]);
        if (r->prep[k])
            r->sink->drop(r->sink->user, r->prep[k]);
        if (r->fready[k] > 0)
            wm_field_free(&r->field[k]);
        CPLFree(r->msg[k]);
        CPLFree(r->fmsg[k]);
    }
    CPLFree(r->field);
    CPLFree(r->fready);
    CPLFree(r->fmsg);
    CPLFree(r->fsec);
    CPLFree(r->slot);
    CPLFree(r->prep);
    CPLFree(r->ready);
    CPLFree(r->msg);
    pthread_mutex_destroy(&r->mu);
    pthread_cond_destroy(&r->cv);
}

/* Takes block i's result out of its slot once ready (*prep: what the sink
 * prepared); CE_Failure when the user stopped the run or the block failed,
 * with the error reported. */
static CPLErr take_block(runner *r, size_t i, GDALProgressFunc pfn, void *pArg,
                         wm_block_result *res, void **prep)
{
    const size_t k = i % r->window;
    pthread_mutex_lock(&r->mu);
    if (!wait_ready(r, k, pfn, pArg, (double)i / (double)r->nblocks))
    {
        pthread_mutex_unlock(&r->mu);
        CPLError(CE_Failure, CPLE_UserInterrupt, "User terminated");
        return CE_Failure;
    }
    *res = r->slot[k];
    *prep = r->prep[k];
    r->prep[k] = NULL;
    const int ok = r->ready[k] > 0;
    char *msg = r->msg[k];
    r->ready[k] = 0;
    r->msg[k] = NULL;
    r->consumed = i + 1;
    pthread_cond_broadcast(&r->cv);
    pthread_mutex_unlock(&r->mu);
    if (!ok)
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: block (%lld, %lld): %s",
                 (long long)r->blocks[2 * i], (long long)r->blocks[2 * i + 1],
                 msg ? msg : "failed");
    CPLFree(msg);
    return ok ? CE_None : CE_Failure;
}

/* Adds block result res to the run's figures. */
static void add_block_stats(WMRunStats *stats, const wm_block_result *res)
{
    for (int st = 0; st < WM_STAGE_COUNT; st++)
        stats->seconds[st] += res->seconds[st];
    stats->blocks++;
    stats->polygons += res->npolys;
    stats->vertices += res->rings.npts;
    stats->triangles += res->poly_tri ? res->poly_tri[res->npolys] : 0;
    stats->mixed_tiles += res->mixed_tiles;
    stats->samples += res->samples;
    stats->pairs += res->pairs;
    stats->contour_vertices += res->contour_vertices;
    stats->steiner += res->steiner;
    stats->small_input += res->small_input;
    stats->left += res->left;
    stats->at_side += res->at_side;
}

CPLErr WMRunBlocks(const WMScene *s, const int64_t *blocks, size_t nblocks,
                   const WMBlockSink *sink, GDALProgressFunc pfn, void *pArg,
                   WMRunStats *stats)
{
    CPLErr err = CE_None;
    runner r;
    memset(stats, 0, sizeof *stats);
    const double t0 = wm_now();
    int nthreads = s->params.num_threads;
    if ((size_t)nthreads > nblocks)
        nthreads = nblocks ? (int)nblocks : 1;
    runner_init(&r, s, blocks, nblocks, sink, nthreads);
    pthread_t *th = CPLCalloc((size_t)nthreads + 1, sizeof *th);
    int workers;
    const int started = start_threads(&r, nthreads, th, &workers);
    if (workers == 0)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: cannot start worker threads.");
        err = CE_Failure;
    }
    if (pfn && !pfn(0.0, "", pArg))
    {
        CPLError(CE_Failure, CPLE_UserInterrupt, "User terminated");
        err = CE_Failure;
    }
    for (size_t i = 0; err == CE_None && i < nblocks; i++)
    {
        wm_block_result res;
        void *prep;
        err = take_block(&r, i, pfn, pArg, &res, &prep);
        if (err != CE_None)
            break;
        WMDeviceWarn(s->device);
        add_block_stats(stats, &res);
        if (!sink->put(sink->user, &res, prep))
            err = CE_Failure;
        else if (pfn && !pfn((double)(i + 1) / (double)nblocks, "", pArg))
        {
            CPLError(CE_Failure, CPLE_UserInterrupt, "User terminated");
            err = CE_Failure;
        }
    }
    runner_free(&r, th, started);
    CPLFree(th);
    stats->wall = wm_now() - t0;
    return err;
}

/* World coordinates of a block-local lattice point. */
static void world(const WMScene *s, const wm_block_result *r, wm_pt p,
                  double *x, double *y)
{
    const int64_t side = (int64_t)s->core.n * WM_Q;
    *x = (double)(r->bx * side + p.x) * s->unit;
    *y = (double)(r->by * side + p.y) * s->unit;
}

/* ---- geometries: written as WKB, then imported by OGR in one call ----- */

/* A WKB writer into a buffer sized beforehand; native byte order. */
typedef struct
{
    unsigned char *p;
    const WMScene *s;
    const wm_block_result *r;
} wkb_out;

#define WKB_HEAD 9 /* byte order, type, count */

/* Bytes of a ring of n points (with its count). */
static size_t ring_bytes(const wm_block_result *r, size_t n)
{
    return 4 + n * (r->z ? 24 : 16);
}

static void put_u32(wkb_out *o, size_t v)
{
    const uint32_t u = (uint32_t)v;
    memcpy(o->p, &u, 4);
    o->p += 4;
}

/* A geometry's header: ISO type (2D code; Z adds 1000), then count. */
static void put_head(wkb_out *o, uint32_t iso_type, size_t count)
{
    *o->p++ = CPL_IS_LSB;
    put_u32(o, iso_type + (o->r->z ? 1000 : 0));
    put_u32(o, count);
}

/* Point k of the block (world coordinates, and its height when the
 * result has heights). */
static void put_point(wkb_out *o, size_t k)
{
    double c[3];
    world(o->s, o->r, wm_block_point(o->r, k), &c[0], &c[1]);
    size_t dim = 2;
    if (o->r->z)
        c[dim++] = o->r->z[k];
    memcpy(o->p, c, dim * sizeof(double));
    o->p += dim * sizeof(double);
}

enum
{
    ISO_POLYGON = 3,
    ISO_MULTIPOLYGON = 6,
    ISO_TIN = 16,
    ISO_TRIANGLE = 17
};

static size_t polygon_bytes(const wm_block_result *r, size_t p)
{
    size_t b = WKB_HEAD;
    for (size_t ri = r->poly_ring[p]; ri < r->poly_ring[p + 1]; ri++)
        b += ring_bytes(r, wm_rings_len(&r->rings, ri) + 1);
    return b;
}

/* Polygon p: its rings, each closed. */
static void put_polygon(wkb_out *o, size_t p)
{
    const wm_block_result *r = o->r;
    put_head(o, ISO_POLYGON, r->poly_ring[p + 1] - r->poly_ring[p]);
    for (size_t ri = r->poly_ring[p]; ri < r->poly_ring[p + 1]; ri++)
    {
        const size_t a = r->rings.start[ri], b = r->rings.start[ri + 1];
        put_u32(o, b - a + 1);
        for (size_t k = a; k <= b; k++)
            put_point(o, k == b ? a : k);
    }
}

static size_t triangle_bytes(const wm_block_result *r)
{
    return WKB_HEAD + ring_bytes(r, 4);
}

/* Triangle t as a Polygon or a Triangle: one closed counter-clockwise
 * ring. */
static void put_triangle(wkb_out *o, size_t t, uint32_t iso_type)
{
    put_head(o, iso_type, 1);
    put_u32(o, 4);
    for (int k = 0; k <= 3; k++)
        put_point(o, o->r->tris[3 * t + (size_t)(k % 3)]);
}

/* The geometry of polygon p (mesh FALSE: the water polygon; TRUE: its
 * triangles, a MultiPolygon of triangles sharing edges (not an OGC-valid
 * MultiPolygon: a set of triangles) or a TIN), or of triangle t as a
 * Polygon (t != SIZE_MAX); NULL when out of memory. */
static OGRGeometryH geometry(const WMScene *s, const wm_block_result *r,
                             int mesh, size_t p, size_t t)
{
    const int tin = s->params.mesh_form == WM_MESH_TIN;
    const size_t t0 = r->poly_tri ? r->poly_tri[p] : 0;
    const size_t nt = r->poly_tri ? r->poly_tri[p + 1] - t0 : 0;
    const size_t bytes = !mesh           ? polygon_bytes(r, p)
                         : t != SIZE_MAX ? triangle_bytes(r)
                                         : WKB_HEAD + nt * triangle_bytes(r);
    unsigned char *buf = VSIMalloc(bytes);
    if (!buf)
        return NULL;
    wkb_out o = {buf, s, r};
    if (!mesh)
        put_polygon(&o, p);
    else if (t != SIZE_MAX)
        put_triangle(&o, t, ISO_POLYGON);
    else
    {
        put_head(&o, tin ? ISO_TIN : ISO_MULTIPOLYGON, nt);
        for (size_t k = t0; k < t0 + nt; k++)
            put_triangle(&o, k, tin ? ISO_TRIANGLE : ISO_POLYGON);
    }
    OGRGeometryH g = NULL;
    if (OGR_G_CreateFromWkb(buf, NULL, &g,
                            bytes <= INT_MAX ? (int)bytes : -1) != OGRERR_NONE)
        g = NULL;
    VSIFree(buf);
    return g;
}

OGRwkbGeometryType WMMeshType(const WMScene *s)
{
    static const OGRwkbGeometryType types[] = {wkbMultiPolygon, wkbTIN,
                                               wkbPolygon};
    const OGRwkbGeometryType t = types[s->params.mesh_form];
    return s->params.elevation ? OGR_GT_SetZ(t) : t;
}

OGRwkbGeometryType WMWaterType(const WMScene *s)
{
    return s->params.elevation ? wkbPolygon25D : wkbPolygon;
}

const WMField *WMLayerFields(const WMScene *s, int mesh)
{
    static const WMField water[] = {{"block_x", OFTInteger},
                                    {"block_y", OFTInteger},
                                    {"area", OFTReal},
                                    {"polygon", OFTInteger},
                                    {NULL, OFTInteger}};
    static const WMField wlevel[] = {
        {"block_x", OFTInteger}, {"block_y", OFTInteger},
        {"area", OFTReal},       {"polygon", OFTInteger},
        {"level", OFTReal},      {"level_spread", OFTReal},
        {NULL, OFTInteger}};
    static const WMField polys[] = {{"block_x", OFTInteger},
                                    {"block_y", OFTInteger},
                                    {"triangles", OFTInteger},
                                    {"polygon", OFTInteger},
                                    {NULL, OFTInteger}};
    static const WMField tris[] = {{"block_x", OFTInteger},
                                   {"block_y", OFTInteger},
                                   {"polygon", OFTInteger},
                                   {NULL, OFTInteger}};
    if (!mesh)
        return s->params.elevation ? wlevel : water;
    return s->params.mesh_form == WM_MESH_TRIANGLES ? tris : polys;
}

static void set_int(OGRFeatureH f, const char *name, GIntBig v)
{
    const int i = OGR_F_GetFieldIndex(f, name);
    if (i >= 0)
        OGR_F_SetFieldInteger64(f, i, v);
}

OGRFeatureH WMNewFeature(const WMScene *s, OGRFeatureDefnH defn, int mesh,
                         const wm_block_result *r, size_t p, size_t t)
{
    OGRFeatureH f = OGR_F_Create(defn);
    if (!f)
        return NULL;
    set_int(f, "block_x", r->bx);
    set_int(f, "block_y", r->by);
    set_int(f, "polygon", (GIntBig)p);
    if (!mesh)
    {
        const int ia = OGR_F_GetFieldIndex(f, "area");
        if (ia >= 0)
            OGR_F_SetFieldDouble(f, ia, WMPolygonArea(s, r, p));
        const int il = OGR_F_GetFieldIndex(f, "level");
        const int is = OGR_F_GetFieldIndex(f, "level_spread");
        if (r->poly_body && r->poly_body[p] >= 0 && il >= 0 && is >= 0)
        {
            OGR_F_SetFieldDouble(f, il, s->drape->body_level[r->poly_body[p]]);
            OGR_F_SetFieldDouble(f, is, s->drape->body_spread[r->poly_body[p]]);
        }
    }
    else if (t == SIZE_MAX)
        set_int(f, "triangles", (GIntBig)(r->poly_tri[p + 1] - r->poly_tri[p]));
    OGRGeometryH g = geometry(s, r, mesh, p, t);
    if (!g)
    {
        OGR_F_Destroy(f);
        return NULL;
    }
    OGR_F_SetGeometryDirectly(f, g);
    return f;
}

double WMPolygonArea(const WMScene *s, const wm_block_result *r, size_t p)
{
    wm_i128 a2 = 0;
    for (size_t ri = r->poly_ring[p]; ri < r->poly_ring[p + 1]; ri++)
        a2 += wm_ring_area2(r->rings.pts + r->rings.start[ri],
                            wm_rings_len(&r->rings, ri));
    return (double)a2 * 0.5 * s->unit * s->unit;
}

void WMPrintStats(const WMScene *s, const WMRunStats *st)
{
    static const char *names[WM_STAGE_COUNT] = {
        "field", "extraction", "simplification", "holes", "triangulation"};
    double sum = 0;
    printf("%-16s %12s\n", "stage", "seconds");
    for (int i = 0; i < WM_STAGE_COUNT; i++)
    {
        printf("%-16s %12.3f\n", names[i], st->seconds[i]);
        sum += st->seconds[i];
    }
    printf("%-16s %12.3f\n", "total (stages)", sum);
    printf("%-16s %12.3f\n", "total (wall)", st->wall);
    printf("device %s\n", s->device->desc);
    printf("threads %d, blocks %lu, mixed tiles %lu, samples evaluated %llu, "
           "sample-segment pairs %llu\n",
           s->params.num_threads, (unsigned long)st->blocks,
           (unsigned long)st->mixed_tiles, (unsigned long long)st->samples,
           (unsigned long long)st->pairs);
    printf("contour vertices %llu (about the cells the boundary crosses), "
           "samples per contour vertex %.1f\n",
           (unsigned long long)st->contour_vertices,
           st->contour_vertices
               ? (double)st->samples / (double)st->contour_vertices
               : 0.0);
    const double denom =
        2.0 * (double)s->core.river_vertices + (double)s->core.lake_vertices;
    printf("polygons %lu, output vertices %lu, triangles %lu\n",
           (unsigned long)st->polygons, (unsigned long)st->vertices,
           (unsigned long)st->triangles);
    if (s->params.min_angle > 0 || s->params.max_edge > 0)
        printf("refinement: %lu points added; %lu triangles below MIN_ANGLE "
               "at input angles (between two ring edges); %lu others below "
               "MIN_ANGLE or over MAX_EDGE (near input angles below 60 "
               "degrees, or not converged), %lu of them below MIN_ANGLE "
               "touching a block side (whose edges refinement may not "
               "split)\n",
               (unsigned long)st->steiner, (unsigned long)st->small_input,
               (unsigned long)st->left, (unsigned long)st->at_side);
    const size_t *ws = s->width_source;
    if (ws[0] + ws[1] + ws[2])
        printf("river widths: %lu from WIDTH_FIELD, %lu from WIDTH_BY_CLASS, "
               "%lu WIDTH\n",
               (unsigned long)ws[0], (unsigned long)ws[1],
               (unsigned long)ws[2]);
    printf("V = %.3f (output vertices / (2 * %lu river + %lu lake "
           "vertices))\n",
           denom > 0 ? (double)st->vertices / denom : 0.0,
           (unsigned long)s->core.river_vertices,
           (unsigned long)s->core.lake_vertices);
}

/* ---- WMGenerate: the sink writes features to the two layers ---------- */

typedef struct
{
    const WMScene *s;
    OGRLayerH layer[2];      /* water, mesh (either may be NULL) */
    OGRFeatureDefnH defn[2]; /* theirs, read once */
} gen_sink;

/* A block's features in writing order (each polygon's water feature, then
 * its mesh, or its triangles), each with its layer. */
typedef struct
{
    size_t n;
    OGRFeatureH *f;
    unsigned char *mesh; /* per feature: layer index */
} gen_features;

static void drop_features(void *user, void *prep)
{
    (void)user;
    gen_features *gf = prep;
    for (size_t i = 0; i < gf->n; i++)
        OGR_F_Destroy(gf->f[i]);
    VSIFree(gf->f);
    VSIFree(gf->mesh);
    VSIFree(gf);
}

static int add_feature(gen_features *gf, const gen_sink *g, int mesh,
                       const wm_block_result *res, size_t p, size_t t)
{
    OGRFeatureH f = WMNewFeature(g->s, g->defn[mesh], mesh, res, p, t);
    if (!f)
        return FALSE;
    gf->f[gf->n] = f;
    gf->mesh[gf->n++] = (unsigned char)mesh;
    return TRUE;
}

/* Builds block res's features (in a worker: OGR features and geometries
 * are the thread's own; the layer definitions are only read); NULL when
 * out of memory. */
static void *make_features(void *user, const wm_block_result *res)
{
    const gen_sink *g = user;
    const int per_triangle = g->s->params.mesh_form == WM_MESH_TRIANGLES;
    const size_t per_poly =
        (g->layer[0] != NULL) + (g->layer[1] != NULL && !per_triangle);
    const size_t cap =
        res->npolys * per_poly + (g->layer[1] && per_triangle && res->poly_tri
                                      ? res->poly_tri[res->npolys]
                                      : 0);
    gen_features *gf = VSICalloc(1, sizeof *gf);
    if (gf)
    {
        gf->f = VSIMalloc2(cap ? cap : 1, sizeof *gf->f);
        gf->mesh = VSIMalloc(cap ? cap : 1);
    }
    int ok = gf && gf->f && gf->mesh;
    for (size_t p = 0; ok && p < res->npolys; p++)
    {
        if (g->layer[0])
            ok = add_feature(gf, g, FALSE, res, p, SIZE_MAX);
        if (ok && g->layer[1] && !per_triangle)
            ok = add_feature(gf, g, TRUE, res, p, SIZE_MAX);
        for (size_t t = res->poly_tri[p];
             ok && g->layer[1] && per_triangle && t < res->poly_tri[p + 1]; t++)
            ok = add_feature(gf, g, TRUE, res, p, t);
    }
    if (!ok && gf)
    {
        drop_features(user, gf);
        gf = NULL;
    }
    return gf;
}

/* Writes block res's features (prep, or made here) to their layers. */
static int write_block(void *user, wm_block_result *res, void *prep)
{
    gen_sink *g = user;
    gen_features *gf = prep ? prep : make_features(user, res);
    int ok = gf != NULL;
    for (size_t i = 0; ok && i < gf->n; i++)
        ok =
            OGR_L_CreateFeature(g->layer[gf->mesh[i]], gf->f[i]) == OGRERR_NONE;
    if (!ok)
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: writing block (%lld, %lld) failed%s.",
                 (long long)res->bx, (long long)res->by,
                 gf ? "" : ": out of memory");
    if (gf)
        drop_features(user, gf);
    wm_block_result_free(res);
    return ok;
}

/* Blocks per WMRunBlocks of a whole run: a batch's list is all the run
 * holds of the grid. */
#define WM_RUN_BATCH 65536

static void add_stats(WMRunStats *to, const WMRunStats *st)
{
    for (int i = 0; i < WM_STAGE_COUNT; i++)
        to->seconds[i] += st->seconds[i];
    to->wall += st->wall;
    to->blocks += st->blocks;
    to->polygons += st->polygons;
    to->vertices += st->vertices;
    to->triangles += st->triangles;
    to->mixed_tiles += st->mixed_tiles;
    to->samples += st->samples;
    to->pairs += st->pairs;
    to->contour_vertices += st->contour_vertices;
    to->steiner += st->steiner;
    to->small_input += st->small_input;
    to->left += st->left;
    to->at_side += st->at_side;
}

/* Keeps the blocks of batch (n pairs) that are the job's (SHARD). */
static size_t shard_batch(const WMScene *s, int64_t *batch, size_t n)
{
    size_t kept = 0;
    for (size_t k = 0; k < n; k++)
        if (WMShardHas(s, batch[2 * k], batch[2 * k + 1]))
        {
            batch[2 * kept] = batch[2 * k];
            batch[2 * kept + 1] = batch[2 * k + 1];
            kept++;
        }
    return kept;
}

int WMShardBlockCount(const WMScene *s, const double *spat, uint64_t *count)
{
    if (!s->shard.on)
        return WMBlockCount(s, spat, count);
    int64_t b[2];
    size_t n = 0;
    int ok;
    WMBlockWalk w;
    WMBlockWalkBegin(&w, s, spat);
    *count = 0;
    while ((ok = WMBlockWalkNext(&w, b, 1, &n)) && n == 1)
        *count += (uint64_t)WMShardHas(s, b[0], b[1]);
    WMBlockWalkEnd(&w);
    return ok;
}

CPLErr WMSceneRun(const WMScene *s, const WMBlockSink *sink,
                  GDALProgressFunc pfn, void *pArg)
{
    const double *spat = s->params.have_spat ? s->params.spat : NULL;
    uint64_t total = 0, done = 0;
    if (!WMShardBlockCount(s, spat, &total))
        return CE_Failure;
    int64_t *batch = VSIMalloc2(WM_RUN_BATCH, 2 * sizeof(int64_t));
    if (!batch)
    {
        CPLError(CE_Failure, CPLE_OutOfMemory, "WATERMESH: out of memory.");
        return CE_Failure;
    }
    WMRunStats all;
    memset(&all, 0, sizeof all);
    WMBlockWalk w;
    WMBlockWalkBegin(&w, s, spat);
    CPLErr err = CE_None;
    size_t n = 0, raw = 0;
    do
    {
        if (!WMBlockWalkNext(&w, batch, WM_RUN_BATCH, &raw))
        {
            err = CE_Failure;
            break;
        }
        n = shard_batch(s, batch, raw);
        if (n > 0 || (done == 0 && raw < WM_RUN_BATCH))
        {
            /* one run even for an empty scene or share */
            void *scaled =
                total ? GDALCreateScaledProgress(
                            (double)done / (double)total,
                            (double)(done + n) / (double)total, pfn, pArg)
                      : NULL;
            WMRunStats st;
            err = WMRunBlocks(s, batch, n, sink,
                              scaled ? GDALScaledProgress : pfn,
                              scaled ? scaled : pArg, &st);
            GDALDestroyScaledProgress(scaled);
            add_stats(&all, &st);
            done += n;
        }
    } while (err == CE_None && raw == WM_RUN_BATCH);
    WMBlockWalkEnd(&w);
    VSIFree(batch);
    if (err == CE_None && pfn && !pfn(1.0, "", pArg))
    {
        CPLError(CE_Failure, CPLE_UserInterrupt, "User terminated");
        err = CE_Failure;
    }
    if (err == CE_None && s->params.stats)
        WMPrintStats(s, &all);
    return err;
}

CPLErr WMSceneGenerate(const WMScene *s, OGRLayerH hWater, OGRLayerH hMesh,
                       GDALProgressFunc pfn, void *pArg)
{
    gen_sink g = {s,
                  {hWater, hMesh},
                  {hWater ? OGR_L_GetLayerDefn(hWater) : NULL,
                   hMesh ? OGR_L_GetLayerDefn(hMesh) : NULL}};
    const WMBlockSink sink = {write_block, make_features, drop_features, &g};
    return WMSceneRun(s, &sink, pfn, pArg);
}

CPLErr WMGenerate(OGRLayerH hRivers, OGRLayerH hLakes, OGRLayerH hWater,
                  OGRLayerH hMesh, CSLConstList papszOptions,
                  GDALProgressFunc pfnProgress, void *pProgressArg)
{
    WMScene *s = WMSceneBuild(hRivers, hLakes, papszOptions);
    if (!s)
        return CE_Failure;
    const CPLErr err =
        WMSceneGenerate(s, hWater, hMesh, pfnProgress, pProgressArg);
    WMSceneFree(s);
    return err;
}
