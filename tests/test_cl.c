/* test_cl.c - the OpenCL field kernel against the C path, on random and
 * adversarial scenes; device discovery, build failures and the "no
 * platform" fallback.
 *
 * WM_EXPECT_OPENCL says what the environment offers: 1 (the default in a
 * build with OpenCL) requires a working device; 0 requires that there is
 * none (CI's run with OCL_ICD_VENDORS pointing at an empty folder), so
 * every failure is reported the way the fallback expects. */
#define _POSIX_C_SOURCE 200809L
#include "field_check.h"
#include "scene_util.h"
#include "tap.h"
#include "wm_cl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char last_msg[8192];
static wm_status last_status;
/* the kernel under test ("double", bit-identical to the C path: 0 px; or
 * "float", within 1e-4 px) */
static const char *kernel = "double";
static double tol = 0.0;

static void keep(void *user, wm_status st, const char *msg)
{
    (void)user;
    last_status = st;
    snprintf(last_msg, sizeof last_msg, "%s", msg);
}

static const wm_ctx ctx = {keep, NULL, NULL};

/* Field of a window on both paths; returns max |delta| in px and counts
 * samples whose sign differs while |C value| >= 1e-4 px. */
static double compare(const wm_scene *s, const wm_field_device *dev,
                      int64_t gx0, int64_t gy0, int32_t w, int32_t h,
                      int *sign_bad, size_t *mixed)
{
    wm_field a, b;
    *sign_bad = -1;
    if (wm_field_compute(s, gx0, gy0, w, h, NULL, &a, &ctx) != WM_OK)
        return INFINITY;
    if (wm_field_compute(s, gx0, gy0, w, h, dev, &b, &ctx) != WM_OK)
    {
        wm_field_free(&a);
        return INFINITY;
    }
    double worst = 0;
    *sign_bad = 0;
    for (int32_t r = 0; r < h; r++)
        for (int32_t c = 0; c < w; c++)
        {
            const float x = wm_field_at(&a, c, r), y = wm_field_at(&b, c, r);
            /* any other bits count (0 and -0 too): a difference of 1 px
             * where the kernel must be the C path's bit for bit */
            const double d = memcmp(&x, &y, sizeof x) == 0 ? 0.0
                             : tol == 0                    ? 1.0
                                        : fabs((double)x - (double)y);
            worst = d > worst ? d : worst;
            if (fabsf(x) >= 1e-4f && ((x < 0) != (y < 0)))
                (*sign_bad)++;
        }
    *mixed = a.mixed;
    wm_field_free(&a);
    wm_field_free(&b);
    return worst;
}

static double urand(unsigned *state, double lo, double hi)
{
    *state = *state * 1103515245u + 12345u;
    return lo + (hi - lo) * (double)((*state >> 8) & 0xffffff) / 16777216.0;
}

/* A star-shaped lake of n vertices around (cx, cy), radii in [r0, r1]. */
static void star_lake(wm_scene *s, double cx, double cy, double r0, double r1,
                      int n, unsigned *seed)
{
    double *xy = malloc(sizeof(double) * 2 * (size_t)n);
    for (int i = 0; i < n; i++)
    {
        const double a = 6.283185307179586 * i / n, r = urand(seed, r0, r1);
        xy[2 * i] = cx + r * cos(a);
        xy[2 * i + 1] = cy + r * sin(a);
    }
    su_lake(s, xy, &n, 1);
    free(xy);
}

static void check_scene(const char *what, const wm_scene *s,
                        const wm_field_device *dev, int64_t gx0, int64_t gy0,
                        int32_t w, int32_t h)
{
    int bad;
    size_t mixed = 0;
    const double d = compare(s, dev, gx0, gy0, w, h, &bad, &mixed);
    TAP_OK(d <= tol && bad == 0 && mixed > 0,
           "%s kernel, %s: max |kernel - C| = %.2g px (%.2g allowed), %d "
           "sign mismatches, %zu mixed tiles",
           kernel, what, d, tol, bad, mixed);
    if (d > tol || bad)
        printf("#   %s\n", last_msg);
}

static void kernel_vs_c(wm_cl *cl)
{
    const wm_field_device dev = {wm_cl_eval, cl};
    unsigned seed = 7;

    /* random rivers (tiny to wide) and lakes with islands */
    for (int k = 0; k < 3; k++)
    {
        wm_scene s;
        su_init(&s, 256);
        for (int i = 0; i < 12; i++)
        {
            double xy[8];
            for (int j = 0; j < 8; j++)
                xy[j] = urand(&seed, -20, 280);
            su_river(&s, xy, 4, urand(&seed, 0.02, 12));
        }
        for (int i = 0; i < 3; i++)
            star_lake(&s, urand(&seed, 20, 240), urand(&seed, 20, 240), 10, 40,
                      60, &seed);
        su_finish(&s);
        char what[64];
        snprintf(what, sizeof what, "random scene %d", k);
        check_scene(what, &s, &dev, 0, 0, 257, 257);
        wm_scene_free(&s);
    }
    {
        /* tiny widths: capsules narrower than a sample spacing */
        wm_scene s;
        su_init(&s, 128);
        const double a[] = {3.3, 5.1, 120.7, 90.2, 30.5, 125.0};
        su_river(&s, a, 3, 0.004);
        su_finish(&s);
        check_scene("tiny width (r = 0.004 px)", &s, &dev, 0, 0, 129, 129);
        wm_scene_free(&s);
    }
    {
        /* huge widths: the shore of a 2e5 px wide river crosses the window,
         * the axis far outside it */
        wm_scene s;
        su_init(&s, 128);
        const double a[] = {-1e5 + 60.3, -500, -1e5 + 64.9, 700};
        su_river(&s, a, 2, 1e5);
        const double b[] = {-3e4, -3e4 + 100.2, 3e4, -3e4 + 99.7};
        su_river(&s, b, 2, 3e4 - 50);
        su_finish(&s);
        check_scene("huge widths (r = 1e5 and 3e4 px)", &s, &dev, 0, 0, 129,
                    129);
        wm_scene_free(&s);
    }
    {
        /* segments longer than many blocks, at shallow angles */
        wm_scene s;
        su_init(&s, 128);
        const double a[] = {-40000.5, -3000.25, 40000.75, 3100.5};
        su_river(&s, a, 2, 3.7);
        const double b[] = {64.2, -50000, 65.1, 50000};
        su_river(&s, b, 2, 0.6);
        su_finish(&s);
        check_scene("segments of 1e5 px", &s, &dev, 0, 0, 129, 129);
        wm_scene_free(&s);
    }
    {
        /* coordinates far from the origin (lattice ~1e10 > 2^32) */
        wm_scene s;
        su_init(&s, 128);
        const double o = 4e7;
        const double a[] = {o + 3.3,  o + 20.7,  o + 60.1,
                            o + 35.2, o + 120.4, o + 110.3};
        su_river(&s, a, 3, 4.4);
        star_lake(&s, o + 80, o + 40, 15, 30, 40, &seed);
        su_finish(&s);
        check_scene("far from the origin (4e7 px)", &s, &dev, (int64_t)o,
                    (int64_t)o, 129, 129);
        wm_scene_free(&s);
    }
    {
        /* many lake edges: a 20,000-vertex ragged lake and a lake with a
         * thousand-vertex island */
        wm_scene s;
        su_init(&s, 256);
        star_lake(&s, 128, 128, 60, 120, 20000, &seed);
        su_finish(&s);
        check_scene("20,000 lake edges", &s, &dev, 0, 0, 257, 257);
        wm_scene_free(&s);
    }

    /* shared border samples: bit-identical between neighbours, and an odd
     * window equal to the blocks, on the OpenCL path too */
    {
        wm_scene s;
        su_init(&s, 64);
        const double river[] = {3.3, 20.7, 60.1, 35.2, 64.0, 35.9, 120.4, 50.3};
        su_river(&s, river, 4, 3.1);
        star_lake(&s, 70, 90, 15, 30, 50, &seed);
        su_finish(&s);
        wm_field a, b, w;
        wm_field_compute(&s, 0, 0, 65, 129, &dev, &a, &ctx);
        wm_field_compute(&s, 64, 0, 65, 129, &dev, &b, &ctx);
        wm_field_compute(&s, 37, 11, 53, 77, &dev, &w, &ctx);
        int diff = fc_shared_column_diff(&a, &b, 64);
        TAP_EQ(diff, 0, "OpenCL, %s kernel: shared border column bit-identical",
               kernel);
        diff = fc_window_diff(&w, 37, 11, &a, &b, 64);
        TAP_EQ(diff, 0,
               "OpenCL, %s kernel: odd window bit-identical to the blocks",
               kernel);
        wm_field_free(&a);
        wm_field_free(&b);
        wm_field_free(&w);
        wm_scene_free(&s);
    }

    /* a hand-made batch: a tile with empty lists and a tile with one
     * segment, evaluated by both evaluators */
    {
        wm_scene s;
        su_init(&s, 64);
        const double a[] = {10.25, 10.5, 20.75, 14.0};
        su_river(&s, a, 2, 1.5);
        su_finish(&s);
        const int64_t org[4] = {1000 * WM_Q, 0, 0, 0};
        const size_t seg_start[3] = {0, 0, 1}, grp_start[3] = {0, 0, 0};
        const size_t edge_start[1] = {0};
        const uint32_t seg[1] = {0};
        static float v1[2 * WM_TS1 * WM_TS1], v2[2 * WM_TS1 * WM_TS1];
        wm_field_batch bt = {&s,        2,    org,        seg_start, seg,
                             grp_start, 0,    edge_start, NULL,      NULL,
                             v1,        NULL, NULL};
        TAP_EQ(wm_field_eval_c(NULL, &bt, &ctx), WM_OK, "C: hand-made batch");
        bt.val = v2;
        TAP_EQ(wm_cl_eval(cl, &bt, &ctx), WM_OK, "OpenCL: hand-made batch");
        int empty_ok = 1;
        double worst = 0;
        for (int i = 0; i < WM_TS1 * WM_TS1; i++)
        {
            empty_ok &= v2[i] == 2.0f;
            const double d = fabs((double)v1[WM_TS1 * WM_TS1 + i] -
                                  (double)v2[WM_TS1 * WM_TS1 + i]);
            worst = d > worst ? d : worst;
        }
        TAP_OK(empty_ok, "OpenCL: a tile with empty lists is +band");
        TAP_OK(worst <= tol,
               "OpenCL, %s kernel: one-segment tile within %.2g px", kernel,
               worst);
        wm_scene_free(&s);
    }
}

/* Writes a kernel file into a fresh folder; returns the folder. */
static const char *kernel_folder(char *dir, const char *text)
{
    strcpy(dir, "/tmp/wm_test_cl_XXXXXX");
    if (!mkdtemp(dir))
        return NULL;
    char path[300];
    snprintf(path, sizeof path, "%s/field.cl", dir);
    FILE *fp = fopen(path, "w");
    if (!fp)
        return NULL;
    fputs(text, fp);
    fclose(fp);
    return dir;
}

static void remove_folder(const char *dir)
{
    char path[300];
    snprintf(path, sizeof path, "%s/field.cl", dir);
    remove(path);
    rmdir(dir);
}

int main(void)
{
    const char *env = getenv("WM_EXPECT_OPENCL");
    const int expect = env ? atoi(env) : wm_cl_built();
    char desc[256] = "";
    int gpu = 0;
    wm_cl *cl = NULL;

    if (!wm_cl_built())
    {
        TAP_EQ(wm_cl_probe(NULL, desc, sizeof desc, &gpu, &ctx), WM_ERR_DEVICE,
               "no OpenCL in this build: probing fails");
        TAP_OK(strstr(last_msg, "no OpenCL") != NULL, "and says why: %s",
               last_msg);
        TAP_EQ(wm_cl_open(NULL, NULL, &cl, &ctx), WM_ERR_DEVICE,
               "no OpenCL in this build: opening fails");
        TAP_OK(cl == NULL, "no device handed out");
        TAP_EQ(expect, 0, "WM_EXPECT_OPENCL agrees with the build");
        return TAP_DONE();
    }

    const wm_status probed = wm_cl_probe(NULL, desc, sizeof desc, &gpu, &ctx);
    if (!expect)
    {
        /* the fallback environment: no platform, or no device */
        TAP_EQ(probed, WM_ERR_DEVICE, "no OpenCL device: probing fails");
        TAP_OK(strstr(last_msg, "CL_PLATFORM_NOT_FOUND_KHR (-1001)") ||
                   strstr(last_msg, "CL_DEVICE_NOT_FOUND (-1)"),
               "naming the OpenCL error: %s", last_msg);
        TAP_EQ(wm_cl_open(NULL, NULL, &cl, &ctx), WM_ERR_DEVICE,
               "no OpenCL device: opening fails cleanly");
        TAP_OK(cl == NULL, "no device handed out");
        return TAP_DONE();
    }

    TAP_EQ(probed, WM_OK, "an OpenCL device: %s (%s)", desc,
           gpu ? "GPU" : "CPU");
    TAP_EQ(wm_cl_probe("no such device at all", desc, sizeof desc, &gpu, &ctx),
           WM_ERR_DEVICE, "a name matching no device fails");
    TAP_OK(strstr(last_msg, "no OpenCL device matches") != NULL,
           "and lists the devices: %s", last_msg);

    /* kernel folders: missing file, a kernel that does not compile, a
     * kernel with the wrong arguments (fails at launch, not at build) */
    TAP_EQ(wm_cl_open(NULL, "/nonexistent/folder", &cl, &ctx), WM_ERR_DEVICE,
           "a kernel folder without field.cl fails");
    TAP_OK(strstr(last_msg, "cannot read") != NULL, "%s", last_msg);
    char dir[64];
    if (kernel_folder(dir, "__kernel void wm_field_tiles(__global float *v)\n"
                           "{ v[0] = undeclared_thing; }\n"))
    {
        TAP_EQ(wm_cl_open(NULL, dir, &cl, &ctx), WM_ERR_DEVICE,
               "a kernel that does not compile fails");
        TAP_OK(strstr(last_msg, "building the field kernel") &&
                   strstr(last_msg, "undeclared_thing"),
               "with the compiler's log (%zu chars)", strlen(last_msg));
        remove_folder(dir);
    }
    if (kernel_folder(dir, "__kernel void wm_field_tiles(__global float *v)\n"
                           "{ v[0] = 1.0f; }\n"))
    {
        TAP_EQ(wm_cl_open(NULL, dir, &cl, &ctx), WM_OK,
               "a kernel with other arguments builds");
        wm_scene s;
        su_init(&s, 64);
        const double a[] = {10.25, 10.5, 20.75, 14.0};
        su_river(&s, a, 2, 1.5);
        su_finish(&s);
        const wm_field_device dev = {wm_cl_eval, cl};
        wm_field f;
        TAP_EQ(wm_field_compute(&s, 0, 0, 65, 65, &dev, &f, &ctx),
               WM_ERR_DEVICE, "and fails at launch with WM_ERR_DEVICE");
        TAP_OK(strstr(last_msg, "clSetKernelArg") != NULL, "%s", last_msg);
        wm_scene_free(&s);
        wm_cl_close(cl);
        remove_folder(dir);
    }

    /* the field kernel with contraction allowed (OpenCL's default, which
     * a runtime ignoring the pragma gives too): the canned batch checked
     * at opening differs from the C path, so the float kernel runs */
    char *fused = strdup(wm_cl_source());
    char *pragma =
        fused ? strstr(fused, "#pragma OPENCL FP_CONTRACT OFF") : NULL;
    if (pragma)
        memcpy(pragma, "#pragma OPENCL FP_CONTRACT ON ", 30);
    if (pragma && kernel_folder(dir, fused))
    {
        TAP_EQ(wm_cl_open(NULL, dir, &cl, &ctx), WM_OK,
               "the kernel with contraction on builds");
        TAP_OK(cl && !wm_cl_exact(cl),
               "and its double kernel is refused: not the C path's bits");
        wm_cl_close(cl);
        remove_folder(dir);
    }
    else
        TAP_OK(0, "the kernel source names FP_CONTRACT OFF");
    free(fused);

    TAP_EQ(wm_cl_open(NULL, NULL, &cl, &ctx), WM_OK, "the field kernel builds");
    if (cl)
    {
        /* a CPU device (PoCL) has doubles: there the double kernel runs,
         * bit-identical to the C path; a GPU may lack them */
        TAP_OK(wm_cl_exact(cl) || gpu,
               "the double kernel runs on %s (%s device)", desc,
               gpu ? "GPU" : "CPU");
        if (wm_cl_exact(cl))
            kernel_vs_c(cl);
        kernel = "float";
        tol = 1e-4;
        wm_cl_use_float(cl);
        TAP_EQ(wm_cl_exact(cl), 0, "the float kernel can be chosen");
        kernel_vs_c(cl);
        wm_cl_close(cl);
    }
    return TAP_DONE();
}
