/*
 * wm_cl.c - the OpenCL field path: device choice, program build, batch
 * evaluation (kernels/field.cl).
 *
 * Device choice: a name filter (case-insensitive substring of the device
 * or platform name) when given; otherwise the first GPU or accelerator;
 * otherwise the first device. Failures name the OpenCL call and the error
 * code, so the caller can log them and fall back to the C path.
 *
 * Evaluation: each call packs its batch into device buffers (coordinates
 * relative to each tile, river constants split into integer and fraction
 * parts, see field.cl), runs one work-item per tile sample and reads the
 * values back. Calls are independent (their own queue, kernel object and
 * buffers), so worker threads may share one wm_cl. The global size's tile
 * dimension is rounded up to a power of two: some implementations (PoCL)
 * specialize the kernel for every new launch size, so a handful of sizes
 * is cheaper than one per batch.
 *
 * Cost: packing is O(tile-item pairs); the device does O(samples x items
 * in reach), as the C path does.
 */
#define CL_TARGET_OPENCL_VERSION 120
#include "wm_cl.h"

#include <CL/cl.h>
#include <CL/cl_ext.h>
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Work-group size along the samples of a tile. */
#define LOCAL 64
/* Samples per tile rounded up to the work-group size. */
#define PADDED (((WM_TS1 * WM_TS1) + LOCAL - 1) / LOCAL * LOCAL)
/* Bound of every coordinate relative to a tile (see field.cl). */
#define REL_MAX (INT64_C(1) << 30)

extern const char wm_cl_field_source[];

struct wm_cl
{
    cl_device_id device;
    cl_context context;
    cl_program program;
    int use_local; /* the kernel runs with LOCAL work-items per group */
    int f64;       /* runs wm_field_tiles_f64 (the device has doubles) */
    char desc[256];
};

int wm_cl_built(void)
{
    return 1;
}

const char *wm_cl_strerror(int code)
{
    switch (code)
    {
#define E(x)                                                                   \
    case x:                                                                    \
        return #x;
        E(CL_SUCCESS)
        E(CL_DEVICE_NOT_FOUND)
        E(CL_DEVICE_NOT_AVAILABLE)
        E(CL_COMPILER_NOT_AVAILABLE)
        E(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        E(CL_OUT_OF_RESOURCES)
        E(CL_OUT_OF_HOST_MEMORY)
        E(CL_PROFILING_INFO_NOT_AVAILABLE)
        E(CL_MEM_COPY_OVERLAP)
        E(CL_IMAGE_FORMAT_MISMATCH)
        E(CL_IMAGE_FORMAT_NOT_SUPPORTED)
        E(CL_BUILD_PROGRAM_FAILURE)
        E(CL_MAP_FAILURE)
        E(CL_MISALIGNED_SUB_BUFFER_OFFSET)
        E(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
        E(CL_COMPILE_PROGRAM_FAILURE)
        E(CL_LINKER_NOT_AVAILABLE)
        E(CL_LINK_PROGRAM_FAILURE)
        E(CL_DEVICE_PARTITION_FAILED)
        E(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
        E(CL_INVALID_VALUE)
        E(CL_INVALID_DEVICE_TYPE)
        E(CL_INVALID_PLATFORM)
        E(CL_INVALID_DEVICE)
        E(CL_INVALID_CONTEXT)
        E(CL_INVALID_QUEUE_PROPERTIES)
        E(CL_INVALID_COMMAND_QUEUE)
        E(CL_INVALID_HOST_PTR)
        E(CL_INVALID_MEM_OBJECT)
        E(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
        E(CL_INVALID_IMAGE_SIZE)
        E(CL_INVALID_SAMPLER)
        E(CL_INVALID_BINARY)
        E(CL_INVALID_BUILD_OPTIONS)
        E(CL_INVALID_PROGRAM)
        E(CL_INVALID_PROGRAM_EXECUTABLE)
        E(CL_INVALID_KERNEL_NAME)
        E(CL_INVALID_KERNEL_DEFINITION)
        E(CL_INVALID_KERNEL)
        E(CL_INVALID_ARG_INDEX)
        E(CL_INVALID_ARG_VALUE)
        E(CL_INVALID_ARG_SIZE)
        E(CL_INVALID_KERNEL_ARGS)
        E(CL_INVALID_WORK_DIMENSION)
        E(CL_INVALID_WORK_GROUP_SIZE)
        E(CL_INVALID_WORK_ITEM_SIZE)
        E(CL_INVALID_GLOBAL_OFFSET)
        E(CL_INVALID_EVENT_WAIT_LIST)
        E(CL_INVALID_EVENT)
        E(CL_INVALID_OPERATION)
        E(CL_INVALID_GL_OBJECT)
        E(CL_INVALID_BUFFER_SIZE)
        E(CL_INVALID_MIP_LEVEL)
        E(CL_INVALID_GLOBAL_WORK_SIZE)
        E(CL_INVALID_PROPERTY)
        E(CL_INVALID_IMAGE_DESCRIPTOR)
        E(CL_INVALID_COMPILER_OPTIONS)
        E(CL_INVALID_LINKER_OPTIONS)
        E(CL_INVALID_DEVICE_PARTITION_COUNT)
        E(CL_PLATFORM_NOT_FOUND_KHR)
#undef E
    default:
        return "unknown OpenCL error";
    }
}

/* Reports a failed OpenCL call. */
static wm_status cl_fail(const wm_ctx *ctx, const char *call, cl_int err)
{
    return wm_fail(ctx, WM_ERR_DEVICE, "OpenCL: %s: %s (%d)", call,
                   wm_cl_strerror(err), (int)err);
}

/* Case-insensitive substring test. */
static int contains(const char *hay, const char *needle)
{
    const size_t n = strlen(needle);
    for (; *hay; hay++)
    {
        size_t i = 0;
        while (i < n && hay[i] &&
               tolower((unsigned char)hay[i]) ==
                   tolower((unsigned char)needle[i]))
            i++;
        if (i == n)
            return 1;
    }
    return n == 0;
}

/* Picks a device (see wm_cl_probe). */
static wm_status pick(const char *name, cl_device_id *out, char *desc,
                      size_t desc_size, int *is_gpu, const wm_ctx *ctx)
{
    cl_uint np = 0;
    cl_int err = clGetPlatformIDs(0, NULL, &np);
    if (err == CL_SUCCESS && np == 0)
        err = CL_PLATFORM_NOT_FOUND_KHR;
    if (err != CL_SUCCESS)
        return wm_fail(ctx, WM_ERR_DEVICE,
                       "no OpenCL platform: clGetPlatformIDs: %s (%d)",
                       wm_cl_strerror(err), (int)err);
    cl_platform_id plat[16];
    if (np > 16)
        np = 16;
    err = clGetPlatformIDs(np, plat, NULL);
    if (err != CL_SUCCESS)
        return cl_fail(ctx, "clGetPlatformIDs", err);
    int best = -1; /* 2: name match or GPU, 1: other device */
    char seen[512] = "";
    for (cl_uint p = 0; p < np && best < 2; p++)
    {
        char pname[128] = "";
        clGetPlatformInfo(plat[p], CL_PLATFORM_NAME, sizeof pname - 1, pname,
                          NULL);
        cl_device_id dev[16];
        cl_uint nd = 0;
        err = clGetDeviceIDs(plat[p], CL_DEVICE_TYPE_ALL, 16, dev, &nd);
        if (err != CL_SUCCESS) /* no device, or a broken ICD: next one */
            continue;
        for (cl_uint d = 0; d < nd && d < 16 && best < 2; d++)
        {
            char dname[128] = "";
            cl_device_type type = 0;
            clGetDeviceInfo(dev[d], CL_DEVICE_NAME, sizeof dname - 1, dname,
                            NULL);
            clGetDeviceInfo(dev[d], CL_DEVICE_TYPE, sizeof type, &type, NULL);
            const int gpu =
                (type & (CL_DEVICE_TYPE_GPU | CL_DEVICE_TYPE_ACCELERATOR)) != 0;
            size_t used = strlen(seen);
            snprintf(seen + used, sizeof seen - used, "%s\"%s\"",
                     used ? ", " : "", dname);
            int score;
            if (name && *name)
                score = contains(dname, name) || contains(pname, name) ? 2 : -1;
            else
                score = gpu ? 2 : 1;
            if (score > best)
            {
                best = score;
                *out = dev[d];
                *is_gpu = gpu;
                snprintf(desc, desc_size, "%s (%s)", dname, pname);
            }
        }
    }
    if (best < 0 && name && *name && seen[0])
        return wm_fail(ctx, WM_ERR_DEVICE,
                       "no OpenCL device matches \"%s\" (devices: %s)", name,
                       seen);
    if (best < 0)
        return wm_fail(ctx, WM_ERR_DEVICE,
                       "no OpenCL device: clGetDeviceIDs: %s (%d) on every "
                       "platform",
                       wm_cl_strerror(CL_DEVICE_NOT_FOUND),
                       (int)CL_DEVICE_NOT_FOUND);
    return WM_OK;
}

wm_status wm_cl_probe(const char *name, char *desc, size_t desc_size,
                      int *is_gpu, const wm_ctx *ctx)
{
    cl_device_id dev;
    return pick(name, &dev, desc, desc_size, is_gpu, ctx);
}

/* Reads dir/field.cl; caller frees. */
static char *read_source(const char *dir, const wm_ctx *ctx)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/field.cl", dir);
    FILE *fp = fopen(path, "rb");
    char *src = NULL;
    long n = -1;
    if (fp && fseek(fp, 0, SEEK_END) == 0 && (n = ftell(fp)) >= 0 &&
        fseek(fp, 0, SEEK_SET) == 0 && (src = malloc((size_t)n + 1)) != NULL)
    {
        if (fread(src, 1, (size_t)n, fp) != (size_t)n)
        {
            free(src);
            src = NULL;
        }
        else
            src[n] = '\0';
    }
    if (fp)
        fclose(fp);
    if (!src)
        wm_fail(ctx, WM_ERR_DEVICE, "cannot read the kernel source %s", path);
    return src;
}

static wm_status eval_batch(wm_cl *cl, const wm_field_batch *b,
                            const wm_ctx *ctx);

/* The canned batch that tells whether the double kernel gives the C
 * path's bits: a runtime that fused products into FMAs despite
 * FP_CONTRACT OFF (LLVM with -ffp-contract=fast) would not. CHECK_TILES
 * tiles, each against CHECK_SEGS river segments and a lake group of
 * CHECK_EDGES edges, its parity 0 or 1 over the whole tile (a parity
 * constant where no edge is near, as the C path's narrow band assumes). */
enum
{
    CHECK_TILES = 8,
    CHECK_SEGS = 16,
    CHECK_EDGES = 8
};

typedef struct
{
    wm_river_seg segs[CHECK_SEGS];
    wm_lake_edge edges[CHECK_EDGES];
    wm_scene s;
    int64_t org[2 * CHECK_TILES];
    size_t seg_start[CHECK_TILES + 1], grp_start[CHECK_TILES + 1];
    size_t edge_start[CHECK_TILES + 1];
    uint32_t seg[CHECK_TILES * CHECK_SEGS], edge[CHECK_TILES * CHECK_EDGES];
    uint64_t mask[CHECK_TILES * WM_TS1];
} canned;

static int64_t lcg(uint32_t *x, int64_t range)
{
    *x = *x * 1664525u + 1013904223u;
    return (int64_t)(*x >> 8) % range;
}

/* A pseudo-random edge with both ends in [0, span)^2. */
static wm_lake_edge lcg_edge(uint32_t *x, int64_t span)
{
    wm_lake_edge e;
    e.ax = lcg(x, span);
    e.ay = lcg(x, span);
    e.bx = lcg(x, span);
    e.by = lcg(x, span);
    return e;
}

/* The canned scene: half its segments at random (radii up to 12 px);
 * half lines of no width, 28 px along a sample row: on them the exact
 * value is 0 while the projection's t = i / 28 is inexact, so any other
 * rounding of p - t (b - a) shows (an FMA leaves +-1e-13 where the C
 * path's product rounds to p); elsewhere a double's last bit seldom
 * survives the rounding to float. A kernel built with contraction on
 * differs at 18 of its 8,712 samples on PoCL. */
static void canned_scene(canned *c)
{
    uint32_t x = 20261128u;
    const int64_t span = 48 * WM_Q; /* around the tiles */
    for (int i = 0; i < CHECK_SEGS; i++)
    {
        const wm_lake_edge e = lcg_edge(&x, span);
        wm_river_seg *g = &c->segs[i];
        *g = (wm_river_seg){e.ax, e.ay, e.bx, e.by, 0};
        g->r = (double)lcg(&x, 12 * WM_Q) + 0.37;
        if (i % 2)
            continue;
        g->ax = g->ax / WM_Q * WM_Q;
        g->ay = g->ay / WM_Q * WM_Q;
        g->bx = g->ax + 28 * WM_Q;
        g->by = g->ay;
        g->r = 0;
    }
    for (int i = 0; i < CHECK_EDGES; i++)
        c->edges[i] = lcg_edge(&x, span);
    memset(&c->s, 0, sizeof c->s);
    c->s.segs = c->segs;
    c->s.nsegs = CHECK_SEGS;
    c->s.edges = c->edges;
    c->s.nedges = CHECK_EDGES;
    c->s.band = 2;
}

/* The canned batch: every tile (on the pixel grid) against every item,
 * its values into val. */
static wm_field_batch canned_batch(canned *c, float *val)
{
    for (int t = 0; t <= CHECK_TILES; t++)
    {
        c->seg_start[t] = (size_t)t * CHECK_SEGS;
        c->grp_start[t] = (size_t)t; /* one group per tile */
        c->edge_start[t] = (size_t)t * CHECK_EDGES;
        if (t == CHECK_TILES)
            break;
        c->org[2 * t] = (t % 4) * WM_TILE * WM_Q;
        c->org[2 * t + 1] = (t / 4) * WM_TILE * WM_Q;
        for (int i = 0; i < CHECK_SEGS; i++)
            c->seg[t * CHECK_SEGS + i] = (uint32_t)i;
        for (int i = 0; i < CHECK_EDGES; i++)
            c->edge[t * CHECK_EDGES + i] = (uint32_t)i;
        for (int j = 0; j < WM_TS1; j++) /* parity 1 in odd tiles */
            c->mask[t * WM_TS1 + j] = t % 2 ? ~UINT64_C(0) : 0;
    }
    const wm_field_batch b = {&c->s,   CHECK_TILES,  c->org,      c->seg_start,
                              c->seg,  c->grp_start, CHECK_TILES, c->edge_start,
                              c->edge, c->mask,      val,         NULL,
                              NULL};
    return b;
}

/* Whether the double kernel gives the C path's bits on the canned batch. */
static int f64_exact(wm_cl *cl)
{
    canned c;
    const size_t nv = (size_t)CHECK_TILES * WM_TS1 * WM_TS1;
    float *v = malloc(2 * nv * sizeof *v);
    if (!v)
        return 0;
    canned_scene(&c);
    wm_field_batch b = canned_batch(&c, v);
    int same = wm_field_eval_c(NULL, &b, NULL) == WM_OK;
    b.val = v + nv;
    same = same && eval_batch(cl, &b, NULL) == WM_OK &&
           memcmp(v, v + nv, nv * sizeof *v) == 0;
    free(v);
    return same;
}

wm_status wm_cl_open(const char *name, const char *kernel_dir, wm_cl **out,
                     const wm_ctx *ctx)
{
    wm_status st;
    cl_int err;
    char *own_src = NULL;
    char *log = NULL;
    int gpu;
    *out = NULL;
    wm_cl *cl = calloc(1, sizeof *cl);
    if (!cl)
        return wm_fail(ctx, WM_ERR_NOMEM, "out of memory");
    st = pick(name, &cl->device, cl->desc, sizeof cl->desc, &gpu, ctx);
    if (st != WM_OK)
        goto fail;
    cl->context = clCreateContext(NULL, 1, &cl->device, NULL, NULL, &err);
    if (err != CL_SUCCESS)
    {
        st = cl_fail(ctx, "clCreateContext", err);
        goto fail;
    }
    const char *src = wm_cl_field_source;
    if (kernel_dir && *kernel_dir)
    {
        if (!(src = own_src = read_source(kernel_dir, ctx)))
        {
            st = WM_ERR_DEVICE;
            goto fail;
        }
    }
    cl->program = clCreateProgramWithSource(cl->context, 1, &src, NULL, &err);
    if (err != CL_SUCCESS)
    {
        st = cl_fail(ctx, "clCreateProgramWithSource", err);
        goto fail;
    }
    /* correctly rounded / and sqrt where the device offers them: closer to
     * the C path, never needed for the 1e-4 px bound */
    cl_device_fp_config fp = 0;
    clGetDeviceInfo(cl->device, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp,
                    NULL);
    const char *opts = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT)
                           ? "-cl-fp32-correctly-rounded-divide-sqrt"
                           : "";
    err = clBuildProgram(cl->program, 1, &cl->device, opts, NULL, NULL);
    if (err != CL_SUCCESS)
    {
        size_t n = 0;
        clGetProgramBuildInfo(cl->program, cl->device, CL_PROGRAM_BUILD_LOG, 0,
                              NULL, &n);
        log = calloc(n + 1, 1);
        if (log)
            clGetProgramBuildInfo(cl->program, cl->device, CL_PROGRAM_BUILD_LOG,
                                  n, log, NULL);
        st = wm_fail(ctx, WM_ERR_DEVICE,
                     "OpenCL: building the field kernel for %s failed: %s "
                     "(%d)\n%s",
                     cl->desc, wm_cl_strerror(err), (int)err, log ? log : "");
        goto fail;
    }
    /* both kernels must run with LOCAL work-items per group for it */
    cl->use_local = 1;
    for (int f64 = 1; f64 >= 0; f64--)
    {
        cl_kernel k = clCreateKernel(
            cl->program, f64 ? "wm_field_tiles_f64" : "wm_field_tiles", &err);
        if (f64 && err == CL_INVALID_KERNEL_NAME) /* no cl_khr_fp64 */
            continue;
        if (err != CL_SUCCESS)
        {
            st = cl_fail(ctx,
                         f64 ? "clCreateKernel(wm_field_tiles_f64)"
                             : "clCreateKernel(wm_field_tiles)",
                         err);
            goto fail;
        }
        size_t wg = 0;
        clGetKernelWorkGroupInfo(k, cl->device, CL_KERNEL_WORK_GROUP_SIZE,
                                 sizeof wg, &wg, NULL);
        clReleaseKernel(k);
        cl->use_local &= wg >= LOCAL;
        cl->f64 |= f64;
    }
    /* the double kernel is bit-identical to the C path only if the
     * runtime honours FP_CONTRACT OFF: checked once, on a canned batch */
    if (cl->f64 && !f64_exact(cl))
        cl->f64 = 0;
    *out = cl;
    cl = NULL;
fail:
    free(own_src);
    free(log);
    wm_cl_close(cl);
    return st;
}

void wm_cl_close(wm_cl *cl)
{
    if (!cl)
        return;
    if (cl->program)
        clReleaseProgram(cl->program);
    if (cl->context)
        clReleaseContext(cl->context);
    free(cl);
}

const char *wm_cl_describe(const wm_cl *cl)
{
    return cl->desc;
}

int wm_cl_exact(const wm_cl *cl)
{
    return cl->f64;
}

void wm_cl_use_float(wm_cl *cl)
{
    cl->f64 = 0;
}

const char *wm_cl_source(void)
{
    return wm_cl_field_source;
}

/* max(|bx - ax|, |by - ay|) */
static int64_t span(int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
    const int64_t dx = bx > ax ? bx - ax : ax - bx;
    const int64_t dy = by > ay ? by - ay : ay - by;
    return dx > dy ? dx : dy;
}

int wm_cl_fits(const wm_scene *s)
{
    /* an item in a tile's list passes within its reach (radius + band +
     * a few units) of the tile, so its end points lie within its length +
     * reach + a tile side of the tile's sample (0, 0) */
    int64_t len = 0;
    for (size_t i = 0; i < s->nsegs; i++)
    {
        const wm_river_seg *g = &s->segs[i];
        const int64_t l = span(g->ax, g->ay, g->bx, g->by);
        len = l > len ? l : len;
    }
    for (size_t i = 0; i < s->nedges; i++)
    {
        const wm_lake_edge *g = &s->edges[i];
        const int64_t l = span(g->ax, g->ay, g->bx, g->by);
        len = l > len ? l : len;
    }
    const double reach =
        s->max_r + (double)(s->band + 2 * WM_TS1) * WM_Q + 16.0;
    return (double)len + reach < (double)(REL_MAX / 2);
}

/* The batch packed for the device. */
typedef struct
{
    cl_uint *seg_start, *grp_start, *edge_start;
    cl_int4 *seg_xy, *edge_xy;
    cl_long2 *seg_k;  /* single precision: r |ab| and r^2 split */
    cl_float4 *seg_f; /* (wm_field_tiles) */
    cl_float *edge_len;
    cl_double *seg_r; /* double: the radii (wm_field_tiles_f64) */
} packed;

static void packed_free(packed *p)
{
    free(p->seg_start);
    free(p->grp_start);
    free(p->edge_start);
    free(p->seg_xy);
    free(p->edge_xy);
    free(p->seg_k);
    free(p->seg_f);
    free(p->edge_len);
    free(p->seg_r);
}

/* Coordinates of [a, b] relative to (X, Y); 0 when out of range. */
static int rel(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t X,
               int64_t Y, cl_int4 *o)
{
    const int64_t v[4] = {ax - X, ay - Y, bx - X, by - Y};
    for (int i = 0; i < 4; i++)
    {
        if (v[i] <= -REL_MAX || v[i] >= REL_MAX)
            return 0;
        o->s[i] = (cl_int)v[i];
    }
    return 1;
}

/* x = integer part + fraction, the fraction in [0, 1). */
static void split(double x, cl_long *i, cl_float *f)
{
    const double fl = floor(x);
    *i = (cl_long)fl;
    *f = (cl_float)(x - fl);
}

/* Packs batch b for the kernel: coordinates relative to each tile, and
 * the radii (f64) or single precision's split lengths. */
static wm_status pack(const wm_field_batch *b, int f64, packed *p,
                      const wm_ctx *ctx)
{
    const size_t nt = b->ntiles, ns = b->seg_start[nt],
                 ne = b->edge_start[b->ngroups];
    if (ns >= UINT32_MAX || ne >= UINT32_MAX || b->ngroups >= UINT32_MAX)
        return wm_fail(ctx, WM_ERR_DEVICE, "OpenCL: batch too large");
    p->seg_start = malloc((nt + 1) * sizeof *p->seg_start);
    p->grp_start = malloc((nt + 1) * sizeof *p->grp_start);
    p->edge_start = malloc((b->ngroups + 1) * sizeof *p->edge_start);
    p->seg_xy = malloc((ns + 1) * sizeof *p->seg_xy);
    p->edge_xy = malloc((ne + 1) * sizeof *p->edge_xy);
    if (f64)
        p->seg_r = malloc((ns + 1) * sizeof *p->seg_r);
    else
    {
        p->seg_k = malloc((ns + 1) * sizeof *p->seg_k);
        p->seg_f = malloc((ns + 1) * sizeof *p->seg_f);
        p->edge_len = malloc((ne + 1) * sizeof *p->edge_len);
    }
    if (!p->seg_start || !p->grp_start || !p->edge_start || !p->seg_xy ||
        !p->edge_xy ||
        (f64 ? !p->seg_r : !p->seg_k || !p->seg_f || !p->edge_len))
        return wm_fail(ctx, WM_ERR_NOMEM, "out of memory packing a batch");
    for (size_t k = 0; k <= nt; k++)
    {
        p->seg_start[k] = (cl_uint)b->seg_start[k];
        p->grp_start[k] = (cl_uint)b->grp_start[k];
    }
    for (size_t g = 0; g <= b->ngroups; g++)
        p->edge_start[g] = (cl_uint)b->edge_start[g];
    for (size_t k = 0; k < nt; k++)
    {
        const int64_t X = b->org[2 * k], Y = b->org[2 * k + 1];
        for (size_t i = b->seg_start[k]; i < b->seg_start[k + 1]; i++)
        {
            const wm_river_seg *g = &b->s->segs[b->seg[i]];
            if (!rel(g->ax, g->ay, g->bx, g->by, X, Y, &p->seg_xy[i]))
                goto range;
            if (f64)
            {
                p->seg_r[i] = g->r;
                continue;
            }
            const double dx = (double)(g->bx - g->ax),
                         dy = (double)(g->by - g->ay);
            const double len = sqrt(dx * dx + dy * dy);
            split(g->r * len, &p->seg_k[i].s[0], &p->seg_f[i].s[0]);
            split(g->r * g->r, &p->seg_k[i].s[1], &p->seg_f[i].s[1]);
            p->seg_f[i].s[2] = (cl_float)g->r;
            p->seg_f[i].s[3] = (cl_float)len;
        }
        for (size_t g = b->grp_start[k]; g < b->grp_start[k + 1]; g++)
            for (size_t i = b->edge_start[g]; i < b->edge_start[g + 1]; i++)
            {
                const wm_lake_edge *e = &b->s->edges[b->edge[i]];
                if (!rel(e->ax, e->ay, e->bx, e->by, X, Y, &p->edge_xy[i]))
                    goto range;
                if (f64)
                    continue;
                const double dx = (double)(e->bx - e->ax),
                             dy = (double)(e->by - e->ay);
                p->edge_len[i] = (cl_float)sqrt(dx * dx + dy * dy);
            }
    }
    return WM_OK;
range:
    return wm_fail(ctx, WM_ERR_DEVICE,
                   "OpenCL: an input segment lies outside the kernel's exact "
                   "coordinate range (2^30 lattice units from a tile)");
}

/* The kernel's buffer arguments, in order: wm_field_tiles_f64's or
 * wm_field_tiles's; the last is the output. */
#define MAXBUF 10
typedef struct
{
    const void *host; /* NULL: the output */
    size_t size;
} kbuf;

static int kernel_buffers(const wm_field_batch *b, int f64, const packed *p,
                          kbuf *in)
{
    static const cl_ulong zero = 0; /* an empty group list needs a buffer */
    const size_t nt = b->ntiles, ng = b->ngroups, ns = b->seg_start[nt],
                 ne = b->edge_start[ng];
    const kbuf mask = {ng ? (const void *)b->mask : &zero,
                       (ng ? ng * WM_TS1 : 1) * sizeof(cl_ulong)};
    const kbuf val = {NULL, nt * WM_TS1 * WM_TS1 * sizeof(cl_float)};
    int n = 0;
    in[n++] = (kbuf){p->seg_start, (nt + 1) * sizeof *p->seg_start};
    in[n++] = (kbuf){p->seg_xy, (ns + 1) * sizeof *p->seg_xy};
    if (f64)
        in[n++] = (kbuf){p->seg_r, (ns + 1) * sizeof *p->seg_r};
    else
    {
        in[n++] = (kbuf){p->seg_k, (ns + 1) * sizeof *p->seg_k};
        in[n++] = (kbuf){p->seg_f, (ns + 1) * sizeof *p->seg_f};
    }
    in[n++] = (kbuf){p->grp_start, (nt + 1) * sizeof *p->grp_start};
    in[n++] = (kbuf){p->edge_start, (ng + 1) * sizeof *p->edge_start};
    in[n++] = (kbuf){p->edge_xy, (ne + 1) * sizeof *p->edge_xy};
    if (!f64)
        in[n++] = (kbuf){p->edge_len, (ne + 1) * sizeof *p->edge_len};
    in[n++] = mask;
    in[n++] = val;
    return n;
}

/* Evaluates batch b on device cl with its kernel (cl->f64). */
static wm_status eval_batch(wm_cl *cl, const wm_field_batch *b,
                            const wm_ctx *ctx)
{
    const int f64 = cl->f64;
    packed p;
    wm_status st;
    cl_int err = CL_SUCCESS;
    const char *call = "";
    cl_command_queue q = NULL;
    cl_kernel k = NULL;
    cl_mem buf[MAXBUF];
    kbuf in[MAXBUF];
    memset(&p, 0, sizeof p);
    memset(buf, 0, sizeof buf);
    if (b->ntiles == 0)
        return WM_OK;
    st = pack(b, f64, &p, ctx);
    if (st != WM_OK)
        goto cleanup;
    const size_t nt = b->ntiles, ns = b->seg_start[nt],
                 ne = b->edge_start[b->ngroups];
    const int nb = kernel_buffers(b, f64, &p, in);

    call = "clCreateCommandQueue";
    q = clCreateCommandQueue(cl->context, cl->device, 0, &err);
    if (err != CL_SUCCESS)
        goto clerr;
    call = "clCreateKernel";
    k = clCreateKernel(cl->program,
                       f64 ? "wm_field_tiles_f64" : "wm_field_tiles", &err);
    if (err != CL_SUCCESS)
        goto clerr;
    call = "clCreateBuffer";
    for (int i = 0; i < nb; i++)
    {
        buf[i] =
            clCreateBuffer(cl->context,
                           in[i].host ? CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR
                                      : CL_MEM_WRITE_ONLY,
                           in[i].size, (void *)in[i].host, &err);
        if (err != CL_SUCCESS)
            goto clerr;
    }
    const cl_uint ntiles = (cl_uint)nt;
    const cl_double band64 = (double)b->s->band * WM_Q;
    const cl_float band32 = (cl_float)band64;
    call = "clSetKernelArg";
    err = clSetKernelArg(k, 0, sizeof ntiles, &ntiles);
    if (err == CL_SUCCESS)
        err = f64 ? clSetKernelArg(k, 1, sizeof band64, &band64)
                  : clSetKernelArg(k, 1, sizeof band32, &band32);
    for (cl_uint i = 0; i < (cl_uint)nb && err == CL_SUCCESS; i++)
        err = clSetKernelArg(k, 2 + i, sizeof(cl_mem), &buf[i]);
    if (err != CL_SUCCESS)
        goto clerr;
    size_t rows = 1;
    while (rows < nt)
        rows *= 2;
    const size_t global[2] = {cl->use_local ? PADDED : WM_TS1 * WM_TS1, rows};
    const size_t local[2] = {LOCAL, 1};
    call = "clEnqueueNDRangeKernel";
    err = clEnqueueNDRangeKernel(q, k, 2, NULL, global,
                                 cl->use_local ? local : NULL, 0, NULL, NULL);
    if (err != CL_SUCCESS)
        goto clerr;
    call = "clEnqueueReadBuffer";
    err = clEnqueueReadBuffer(q, buf[nb - 1], CL_TRUE, 0, in[nb - 1].size,
                              b->val, 0, NULL, NULL);
    if (err != CL_SUCCESS)
        goto clerr;
    if (b->samples) /* every sample of every tile, against its items */
        *b->samples += (uint64_t)nt * WM_TS1 * WM_TS1;
    if (b->pairs)
        *b->pairs += (uint64_t)(ns + ne) * WM_TS1 * WM_TS1;
    goto cleanup;
clerr:
    st = cl_fail(ctx, call, err);
cleanup:
    for (int i = 0; i < MAXBUF; i++)
        if (buf[i])
            clReleaseMemObject(buf[i]);
    if (k)
        clReleaseKernel(k);
    if (q)
        clReleaseCommandQueue(q);
    packed_free(&p);
    return st;
}

wm_status wm_cl_eval(void *user, const wm_field_batch *b, const wm_ctx *ctx)
{
    return eval_batch(user, b, ctx);
}
