/*
 * wm_cl_none.c - the OpenCL field path in a build without OpenCL
 * (./configure --disable-opencl, or no OpenCL headers and library found):
 * every entry point reports that, so DEVICE=AUTO takes the C path and
 * DEVICE=OPENCL fails with a clear message.
 */
#include "wm_cl.h"

static const char *const NONE =
    "this build has no OpenCL (configured with --disable-opencl or without "
    "OpenCL headers and library)";

int wm_cl_built(void)
{
    return 0;
}

wm_status wm_cl_probe(const char *name, char *desc, size_t desc_size,
                      int *is_gpu, const wm_ctx *ctx)
{
    (void)name;
    (void)desc_size;
    desc[0] = '\0';
    *is_gpu = 0;
    return wm_fail(ctx, WM_ERR_DEVICE, "%s", NONE);
}

wm_status wm_cl_open(const char *name, const char *kernel_dir, wm_cl **out,
                     const wm_ctx *ctx)
{
    (void)name;
    (void)kernel_dir;
    *out = NULL;
    return wm_fail(ctx, WM_ERR_DEVICE, "%s", NONE);
}

void wm_cl_close(wm_cl *cl)
{
    (void)cl;
}

const char *wm_cl_describe(const wm_cl *cl)
{
    (void)cl;
    return "";
}

int wm_cl_exact(const wm_cl *cl)
{
    (void)cl;
    return 0;
}

void wm_cl_use_float(wm_cl *cl)
{
    (void)cl;
}

const char *wm_cl_source(void)
{
    return "";
}

int wm_cl_fits(const wm_scene *s)
{
    (void)s;
    return 0;
}

wm_status wm_cl_eval(void *user, const wm_field_batch *b, const wm_ctx *ctx)
{
    (void)user;
    (void)b;
    return wm_fail(ctx, WM_ERR_DEVICE, "%s", NONE);
}

const char *wm_cl_strerror(int code)
{
    (void)code;
    return "unknown OpenCL error";
}
