/*
 * wm_cl.h - the distance field on an OpenCL device: device discovery and
 * choice, program build, and a field device (wm_field_device) running the
 * kernel of kernels/field.cl on batches of tiles.
 *
 * Plain C like the core: no GDAL; errors go through wm_ctx. Built from
 * wm_cl.c with OpenCL, or from wm_cl_none.c (./configure --disable-opencl),
 * whose functions report that the build has no OpenCL.
 */
#ifndef WM_CL_H
#define WM_CL_H

#include "../core/field.h"

#ifdef __cplusplus
extern "C"
{
#endif

    /** An OpenCL device with its context and the built field program. */
    typedef struct wm_cl wm_cl;

    /** 1 when this build has the OpenCL path, 0 otherwise. */
    int wm_cl_built(void);

    /**
     * Finds the device wm_cl_open would take, without building anything:
     * the first device whose name or platform name contains `name`
     * (case-insensitive) when name is non-empty, otherwise the first GPU or
     * accelerator, otherwise the first device of any type.
     *
     * @param desc    receives "device name (platform name)"
     * @param is_gpu  receives 1 for a GPU or accelerator, 0 for a CPU device
     * @return WM_OK, or WM_ERR_DEVICE with a message naming the OpenCL call
     *         and its error (no platform: CL_PLATFORM_NOT_FOUND_KHR, -1001;
     *         no device: CL_DEVICE_NOT_FOUND, -1; no device matching name)
     */
    wm_status wm_cl_probe(const char *name, char *desc, size_t desc_size,
                          int *is_gpu, const wm_ctx *ctx);

    /**
     * Opens the device wm_cl_probe finds and builds the field program: the
     * embedded kernels/field.cl, or `kernel_dir`/field.cl when kernel_dir is
     * non-NULL (for kernel development). A failed build reports the
     * compiler's log.
     *
     * @return WM_OK with *out set (caller frees with wm_cl_close()), or an
     *         error status with *out NULL
     */
    wm_status wm_cl_open(const char *name, const char *kernel_dir, wm_cl **out,
                         const wm_ctx *ctx);

    /** Releases everything; cl may be NULL. */
    void wm_cl_close(wm_cl *cl);

    /** "device name (platform name)" of an open device. */
    const char *wm_cl_describe(const wm_cl *cl);

    /**
     * 1 when the device runs the double-precision kernel, whose every
     * value is bit-identical to the C path's (the device has cl_khr_fp64),
     * 0 when it runs the single-precision one (within about 1e-6 px of it:
     * rings may then move by a lattice unit).
     */
    int wm_cl_exact(const wm_cl *cl);

    /** Makes cl run the single-precision kernel (for tests). */
    void wm_cl_use_float(wm_cl *cl);

    /** The embedded kernels/field.cl ("" in a build without OpenCL). */
    const char *wm_cl_source(void);

    /**
     * 1 when every coordinate the kernel will see for this scene stays in
     * its exact integer range (|x| < 2^30 lattice units relative to a tile:
     * segments shorter than about 2^29 units, radii likewise), 0 otherwise.
     * Decide per scene, never per block: two paths in one run would differ
     * by float rounding at shared block borders.
     */
    int wm_cl_fits(const wm_scene *s);

    /** A wm_field_eval_fn: evaluates a batch on the device `user` (a
     *  wm_cl *). Thread-safe: each call uses its own queue and kernel. */
    wm_status wm_cl_eval(void *user, const wm_field_batch *b,
                         const wm_ctx *ctx);

    /** Name of an OpenCL error code ("CL_OUT_OF_RESOURCES"), or
     *  "unknown OpenCL error". */
    const char *wm_cl_strerror(int code);

#ifdef __cplusplus
}
#endif

#endif /* WM_CL_H */
