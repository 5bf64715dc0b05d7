/*
 * field_bench.c - throughput of the field stage alone, C path against the
 * OpenCL device, on one scene: every block's field computed (and freed),
 * nothing else.
 *
 * Usage: field_bench <rivers_ds> <rivers_layer> <lakes_ds> <lakes_layer>
 *                    [NAME=VALUE ...]   (WATERMESH options, e.g. WIDTH_FIELD)
 * Prints one markdown table row per path: C on 1 thread, C on every core
 * (blocks split between threads), OpenCL (one host thread; the device uses
 * what it has), with seconds, samples evaluated, sample-segment pairs and
 * both rates. The OpenCL row is left out when no device can be opened.
 */
#include "../src/gdal/wm_private.h"

#include <cpl_conv.h>
#include <cpl_multiproc.h>
#include <cpl_string.h>

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct
{
    const WMScene *s;
    const int64_t *blocks;
    size_t nblocks, next;
    const wm_field_device *dev;
    pthread_mutex_t mu;
    uint64_t samples, pairs;
    int failed;
} job;

static void *work(void *arg)
{
    job *j = arg;
    wm_block_opts opts = {.dev = j->dev};
    for (;;)
    {
        pthread_mutex_lock(&j->mu);
        const size_t i = j->next++;
        pthread_mutex_unlock(&j->mu);
        if (i >= j->nblocks)
            break;
        wm_field f;
        if (wm_block_field(&j->s->core, j->blocks[2 * i], j->blocks[2 * i + 1],
                           &opts, &f, NULL) != WM_OK)
        {
            j->failed = 1;
            continue;
        }
        pthread_mutex_lock(&j->mu);
        j->samples += f.samples;
        j->pairs += f.pairs;
        pthread_mutex_unlock(&j->mu);
        wm_field_free(&f);
    }
    return NULL;
}

static void row(const char *path, const WMScene *s, const int64_t *blocks,
                size_t nblocks, const wm_field_device *dev, int threads)
{
    job j = {s, blocks, nblocks, 0, dev, PTHREAD_MUTEX_INITIALIZER, 0, 0, 0};
    pthread_t th[64];
    const double t0 = wm_now();
    for (int t = 0; t < threads; t++)
        pthread_create(&th[t], NULL, work, &j);
    for (int t = 0; t < threads; t++)
        pthread_join(th[t], NULL);
    const double sec = wm_now() - t0;
    printf("| %s | %d | %.3f | %.1f M | %.1f M | %.1f M | %.1f M |%s\n", path,
           threads, sec, (double)j.samples / 1e6, (double)j.pairs / 1e6,
           (double)j.samples / sec / 1e6, (double)j.pairs / sec / 1e6,
           j.failed ? " (some blocks failed)" : "");
}

int main(int argc, char **argv)
{
    if (argc < 5)
    {
        fprintf(stderr, "usage: field_bench <rivers_ds> <rivers_layer> "
                        "<lakes_ds> <lakes_layer> [NAME=VALUE ...]\n");
        return 2;
    }
    GDALAllRegister();
    GDALDatasetH hr = GDALOpenEx(argv[1], GDAL_OF_VECTOR, NULL, NULL, NULL);
    GDALDatasetH hl = GDALOpenEx(argv[3], GDAL_OF_VECTOR, NULL, NULL, NULL);
    OGRLayerH lr = hr ? GDALDatasetGetLayerByName(hr, argv[2]) : NULL;
    OGRLayerH ll = hl ? GDALDatasetGetLayerByName(hl, argv[4]) : NULL;
    if (!lr || !ll)
    {
        fprintf(stderr, "cannot open the input layers\n");
        return 1;
    }
    char **opts = NULL;
    for (int i = 5; i < argc; i++)
        opts = CSLAddString(opts, argv[i]);
    opts = CSLSetNameValue(opts, "DEVICE", "OPENCL");
    CPLPushErrorHandler(CPLQuietErrorHandler);
    WMScene *s = WMSceneBuild(lr, ll, opts);
    CPLPopErrorHandler();
    const int have_cl = s != NULL;
    if (!s)
    {
        opts = CSLSetNameValue(opts, "DEVICE", "CPU");
        s = WMSceneBuild(lr, ll, opts);
    }
    if (!s)
        return 1;
    uint64_t count = 0;
    size_t nblocks = 0;
    WMBlockWalk w;
    WMBlockCount(s, NULL, &count);
    int64_t *blocks = VSIMalloc2((size_t)count + 1, 2 * sizeof *blocks);
    WMBlockWalkBegin(&w, s, NULL);
    if (!blocks || !WMBlockWalkNext(&w, blocks, (size_t)count, &nblocks))
        return 1;
    WMBlockWalkEnd(&w);
    const int ncpu = CPLGetNumCPUs() < 64 ? CPLGetNumCPUs() : 64;
    printf("| path | host threads | field s | samples | pairs | samples/s | "
           "pairs/s |\n|---|---|---|---|---|---|---|\n");
    row("C", s, blocks, nblocks, NULL, 1);
    if (ncpu > 1)
        row("C", s, blocks, nblocks, NULL, ncpu);
    if (have_cl)
    {
        char name[540];
        snprintf(name, sizeof name, "%s", s->device->desc);
        /* the first batches pay for PoCL's per-size kernel specialization:
         * warm up on one block */
        row("(OpenCL warm-up)", s, blocks, nblocks < 2 ? nblocks : 2,
            WMDeviceField(s->device), 1);
        row(name, s, blocks, nblocks, WMDeviceField(s->device), 1);
    }
    VSIFree(blocks);
    WMSceneFree(s);
    CSLDestroy(opts);
    GDALClose(hr);
    GDALClose(hl);
    return 0;
}
