/*
 * wm_device.c - DEVICE=AUTO|CPU|OPENCL: which path computes a scene's
 * field, chosen once per scene (never per block: the two paths agree to
 * about 1e-6 px, not bit for bit, and block seams need bit-identical
 * shared samples).
 *
 * AUTO takes the C path and loads no OpenCL at all, unless
 * WATERMESH_OPENCL_DEVICE names a device: the C path was faster at the
 * default thread count on every machine measured, a 16-core host with an
 * NVIDIA H200 included (docs/opencl.md), and probing costs 40-200 ms and
 * 60 MB of libraries per process. OPENCL takes the first GPU or
 * accelerator, else the first device. A named device that cannot be had
 * (no platform, no match, a scene outside the kernel's exact range, a
 * failing build): AUTO falls back to the C path with a CPLDebug line,
 * OPENCL fails with a CPLError. A device failing during a run: AUTO warns
 * once (CE_Warning, from the thread that runs the blocks) and the C path
 * computes the rest; OPENCL fails the block.
 *
 * Opened devices (context and built program, ~0.6 s to build cold) are kept
 * per process, keyed by the device name and kernel folder, so a second
 * scene or dataset reuses them.
 */
#include "wm_private.h"

#include "../cl/wm_cl.h"

#include <cpl_conv.h>
#include <cpl_string.h>

#include <pthread.h>
#include <string.h>

typedef struct cached
{
    char *name, *kernel_dir; /* the key (CPLStrdup'ed, "" when unset) */
    wm_cl *cl;               /* NULL when opening failed */
    char *err;               /* why, then */
    struct cached *next;
} cached;

static cached *g_devices;
static pthread_mutex_t g_mu = PTHREAD_MUTEX_INITIALIZER;

/* The open device for (name, kernel_dir), opened on first use. NULL with
 * *err set (the caller frees it with CPLFree) when that failed. */
static wm_cl *device_open(const char *name, const char *kernel_dir, char **err)
{
    name = name ? name : "";
    kernel_dir = kernel_dir ? kernel_dir : "";
    pthread_mutex_lock(&g_mu);
    cached *c = g_devices;
    while (c && !(strcmp(c->name, name) == 0 &&
                  strcmp(c->kernel_dir, kernel_dir) == 0))
        c = c->next;
    if (!c)
    {
        c = CPLCalloc(1, sizeof *c);
        c->name = CPLStrdup(name);
        c->kernel_dir = CPLStrdup(kernel_dir);
        wm_ctx ctx = {WMKeepFirstError, &c->err, NULL};
        wm_cl_open(name, kernel_dir, &c->cl, &ctx);
        c->next = g_devices;
        g_devices = c;
    }
    wm_cl *cl = c->cl;
    if (!cl)
        *err = CPLStrdup(c->err ? c->err : "OpenCL failed");
    pthread_mutex_unlock(&g_mu);
    return cl;
}

void WMDeviceCleanup(void)
{
    pthread_mutex_lock(&g_mu);
    while (g_devices)
    {
        cached *c = g_devices;
        g_devices = c->next;
        wm_cl_close(c->cl);
        CPLFree(c->name);
        CPLFree(c->kernel_dir);
        CPLFree(c->err);
        CPLFree(c);
    }
    pthread_mutex_unlock(&g_mu);
}

/* The scene's field device: OpenCL, handing over to the C path for good
 * when the device fails under DEVICE=AUTO. */
static wm_status eval_device(void *user, const wm_field_batch *b,
                             const wm_ctx *ctx)
{
    WMDevice *d = user;
    if (!__atomic_load_n(&d->failed, __ATOMIC_ACQUIRE))
    {
        char *msg = NULL;
        wm_ctx own = {WMKeepFirstError, &msg, NULL};
        const wm_status st = wm_cl_eval(d->cl, b, &own);
        if (st == WM_OK || st != WM_ERR_DEVICE || !d->auto_mode)
        {
            if (st != WM_OK)
                wm_fail(ctx, st, "%s", msg ? msg : "OpenCL failed");
            CPLFree(msg);
            return st;
        }
        /* the first failure keeps its message for WMDeviceWarn, which
         * reports it from the calling thread (GDAL error handlers are per
         * thread) */
        int expected = 0;
        if (__atomic_compare_exchange_n(&d->failed, &expected, 1, 0,
                                        __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE))
        {
            CPLDebug("WATERMESH", "DEVICE=AUTO: %s", msg ? msg : "");
            snprintf(d->fail_msg, sizeof d->fail_msg, "%s",
                     msg ? msg : "unknown error");
            __atomic_store_n(&d->failed, 2, __ATOMIC_RELEASE);
        }
        CPLFree(msg);
    }
    return wm_field_eval_c(NULL, b, ctx);
}

const wm_field_device *WMDeviceField(const WMDevice *d)
{
    /* after a failure (AUTO) the C path computes everything: later runs
     * are not pipelined through the device wrapper */
    return d && d->cl && !__atomic_load_n(&d->failed, __ATOMIC_ACQUIRE)
               ? &d->field
               : NULL;
}

void WMDeviceWarn(WMDevice *d)
{
    int expected = 2;
    if (d && __atomic_compare_exchange_n(&d->failed, &expected, 3, 0,
                                         __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE))
        CPLError(CE_Warning, CPLE_AppDefined,
                 "WATERMESH: DEVICE=AUTO: the OpenCL device failed (%s); the "
                 "C path computes the rest of this run (the shared borders "
                 "of blocks computed on different paths may differ by "
                 "about 1e-6 pixel).",
                 d->fail_msg);
}

/* OpenCL cannot be had, for the reason `why`: DEVICE=AUTO settles for the
 * C path (TRUE), DEVICE=OPENCL fails (FALSE, after a CPLError). */
static int use_c(WMDevice *d, const char *why)
{
    if (!d->auto_mode)
    {
        CPLError(CE_Failure, CPLE_AppDefined, "WATERMESH: DEVICE=OPENCL: %s",
                 why);
        return FALSE;
    }
    CPLDebug("WATERMESH", "DEVICE=AUTO: the C path (%s)", why);
    snprintf(d->desc, sizeof d->desc, "CPU (C path; %s)", why);
    return TRUE;
}

int WMDeviceSelect(WMScene *s)
{
    const WMDeviceKind kind = s->params.device;
    WMDevice *d = VSI_CALLOC_VERBOSE(1, sizeof *d);
    if (!d)
        return FALSE;
    s->device = d;
    d->auto_mode = kind == WM_DEVICE_AUTO;
    snprintf(d->desc, sizeof d->desc, "CPU (C path)");
    const char *name = CPLGetConfigOption("WATERMESH_OPENCL_DEVICE", NULL);
    const char *kernel_dir = CPLGetConfigOption("WATERMESH_KERNEL_DIR", NULL);
    char *msg = NULL;
    int ok = TRUE;
    if (kind == WM_DEVICE_CPU || (d->auto_mode && !(name && *name)))
    {
        CPLDebug("WATERMESH", "DEVICE=%s: the C path",
                 d->auto_mode ? "AUTO" : "CPU");
        return TRUE;
    }
    if (!wm_cl_built())
    {
        ok = use_c(d, "this build has no OpenCL (configured with "
                      "--disable-opencl or without OpenCL headers and "
                      "library)");
        goto done;
    }
    if (!wm_cl_fits(&s->core))
    {
        ok = use_c(d, "a river or lake segment is longer than the OpenCL "
                      "kernel's exact coordinate range (about 2^21 pixels); "
                      "use DEVICE=CPU");
        goto done;
    }
    d->cl = device_open(name, kernel_dir, &msg);
    if (!d->cl)
    {
        ok = use_c(d, msg);
        goto done;
    }
    d->field.eval = eval_device;
    d->field.user = d;
    snprintf(d->desc, sizeof d->desc, "OpenCL: %s, %s", wm_cl_describe(d->cl),
             wm_cl_exact(d->cl) ? "double precision (the C path's values)"
                                : "single precision");
    CPLDebug("WATERMESH", "DEVICE=%s: %s",
             kind == WM_DEVICE_AUTO ? "AUTO" : "OPENCL", d->desc);
done:
    CPLFree(msg);
    return ok;
}
