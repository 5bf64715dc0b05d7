/* test_nomem_glue.c - allocation failure in the GDAL glue, as test_nomem
 * does it for the core. The glue's sources (wm_options.c, wm_ingest.c,
 * wm_run.c, wm_device.c) are linked into this test with
 * -Wl,--wrap=VSIMalloc,VSIMalloc2,VSICalloc,VSIRealloc (the allocations it
 * checks) and --wrap=malloc,calloc,realloc (the core's). A dry run of
 * WMGenerate notes the call site of each allocation; then every site fails
 * at its first and at its last allocation. Each run must end in CE_Failure
 * with an error message, or CE_None, never a crash. Fixed-size bookkeeping
 * uses CPLMalloc/CPLStrdup, which end the process with GDAL's fatal "Out of
 * memory" by design, and is not failed here. CI's sanitizer pass runs this
 * under AddressSanitizer and LeakSanitizer: a leak on an error path fails
 * it there. */
#include "watermesh.h"

#include "tap.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t m);
void *__real_realloc(void *p, size_t n);
void *__real_VSIMalloc(size_t n);
void *__real_VSIMalloc2(size_t n, size_t m);
void *__real_VSICalloc(size_t n, size_t m);
void *__real_VSIRealloc(void *p, size_t n);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t m);
void *__wrap_realloc(void *p, size_t n);
void *__wrap_VSIMalloc(size_t n);
void *__wrap_VSIMalloc2(size_t n, size_t m);
void *__wrap_VSICalloc(size_t n, size_t m);
void *__wrap_VSIRealloc(void *p, size_t n);

/* one worker thread allocates while the calling thread waits: the counters
 * are atomic, and the order of allocations is the same in every run */
static long calls, fail_at, failed, record, read_failures;
#define MAX_SEQ (1L << 22)
static void **seq;
static long nseq;

static int fail_now(void *site)
{
    const long k = __atomic_add_fetch(&calls, 1, __ATOMIC_SEQ_CST);
    if (__atomic_load_n(&record, __ATOMIC_SEQ_CST) && k <= MAX_SEQ)
    {
        seq[k - 1] = site;
        nseq = k;
    }
    if (k != __atomic_load_n(&fail_at, __ATOMIC_SEQ_CST))
        return 0;
    __atomic_store_n(&failed, 1, __ATOMIC_SEQ_CST);
    return 1;
}

#define SITE __builtin_return_address(0)
void *__wrap_malloc(size_t n)
{
    return fail_now(SITE) ? NULL : __real_malloc(n);
}
void *__wrap_calloc(size_t n, size_t m)
{
    return fail_now(SITE) ? NULL : __real_calloc(n, m);
}
void *__wrap_realloc(void *p, size_t n)
{
    return fail_now(SITE) ? NULL : __real_realloc(p, n);
}
void *__wrap_VSIMalloc(size_t n)
{
    return fail_now(SITE) ? NULL : __real_VSIMalloc(n);
}
void *__wrap_VSIMalloc2(size_t n, size_t m)
{
    return fail_now(SITE) ? NULL : __real_VSIMalloc2(n, m);
}
void *__wrap_VSICalloc(size_t n, size_t m)
{
    return fail_now(SITE) ? NULL : __real_VSICalloc(n, m);
}
void *__wrap_VSIRealloc(void *p, size_t n)
{
    return fail_now(SITE) ? NULL : __real_VSIRealloc(p, n);
}

static void add(OGRLayerH l, const char *wkt, double width)
{
    OGRGeometryH g = NULL;
    char *p = (char *)wkt;
    OGR_G_CreateFromWkt(&p, NULL, &g);
    OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(l));
    OGR_F_SetGeometryDirectly(f, g);
    if (width > 0)
        OGR_F_SetFieldDouble(f, 0, width);
    if (OGR_L_CreateFeature(l, f) != OGRERR_NONE)
        abort(); /* the fixture itself is broken */
    OGR_F_Destroy(f);
}

/* Rivers (one of them dense, so that reading thins it) and a lake with a
 * hole, over a few blocks, in memory. */
static GDALDatasetH scene(OGRLayerH *r, OGRLayerH *l)
{
    GDALDatasetH ds = GDALCreate(GDALGetDriverByName("Memory"), "", 0, 0, 0,
                                 GDT_Unknown, NULL);
    OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
    OSRImportFromEPSG(srs, 32631);
    *r = GDALDatasetCreateLayer(ds, "rivers", srs, wkbLineString, NULL);
    *l = GDALDatasetCreateLayer(ds, "lakes", srs, wkbPolygon, NULL);
    OSRRelease(srs);
    OGRFieldDefnH fd = OGR_Fld_Create("width", OFTReal);
    OGR_L_CreateField(*r, fd, TRUE);
    OGR_Fld_Destroy(fd);
    add(*r, "LINESTRING (400000 4700000, 400060 4700012, 400130 4700050)", 4);
    add(*r, "LINESTRING (400060 4700012, 400100 4699990)", 2.5);
    char wkt[4096] = "LINESTRING (400010 4700080";
    for (int i = 1; i <= 100; i++) /* 5 cm apart: thinned when read */
        snprintf(wkt + strlen(wkt), sizeof wkt - strlen(wkt), ", %.4f %.4f",
                 400010 + i * 0.05, 4700080 + (i % 2) * 0.01);
    strcat(wkt, ", 400040 4700085)");
    add(*r, wkt, 1);
    add(*l,
        "POLYGON ((400070 4700060, 400120 4700060, 400120 4700110, "
        "400070 4700110, 400070 4700060), (400090 4700080, 400091 "
        "4700080, 400091 4700081, 400090 4700080))",
        0);
    return ds;
}

/* One WMGenerate into fresh in-memory layers with allocation k failing;
 * 0 when it ended as it must. */
static int run(OGRLayerH r, OGRLayerH l, long k)
{
    char **opts = NULL;
    opts = CSLSetNameValue(opts, "WIDTH_FIELD", "width");
    opts = CSLSetNameValue(opts, "PIXEL_SIZE", "1");
    opts = CSLSetNameValue(opts, "BLOCK_SIZE", "64");
    opts = CSLSetNameValue(opts, "NUM_THREADS", "1");
    opts = CSLSetNameValue(opts, "DEVICE", "CPU");
    GDALDatasetH out = GDALCreate(GDALGetDriverByName("Memory"), "", 0, 0, 0,
                                  GDT_Unknown, NULL);
    OGRLayerH w = GDALDatasetCreateLayer(out, "water", NULL, wkbPolygon, NULL);
    OGRLayerH m =
        GDALDatasetCreateLayer(out, "mesh", NULL, wkbMultiPolygon, NULL);
    CPLErrorReset();
    __atomic_store_n(&calls, 0, __ATOMIC_SEQ_CST);
    __atomic_store_n(&failed, 0, __ATOMIC_SEQ_CST);
    __atomic_store_n(&fail_at, k, __ATOMIC_SEQ_CST);
    const CPLErr e = WMGenerate(r, l, w, m, opts, NULL, NULL);
    __atomic_store_n(&fail_at, 0, __ATOMIC_SEQ_CST);
    int bad = 0;
    if (e != CE_None && !*CPLGetLastErrorMsg())
        bad = 1;
    if (k == 0 && (e != CE_None || OGR_L_GetFeatureCount(w, TRUE) == 0))
        bad = 1;
    if (e != CE_None && strstr(CPLGetLastErrorMsg(), "reading the input"))
        read_failures++;
    if (k > 0 && !failed)
        bad = 1; /* the runs differ: the k-th allocation never came */
    if (bad)
        printf("# allocation %ld: CPLErr %d, message '%s'\n", k, (int)e,
               CPLGetLastErrorMsg());
    GDALClose(out);
    CSLDestroy(opts);
    return bad;
}

int main(void)
{
    GDALAllRegister();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    seq = __real_malloc(MAX_SEQ * sizeof *seq);
    OGRLayerH r, l;
    GDALDatasetH in = scene(&r, &l);
    __atomic_store_n(&record, 1, __ATOMIC_SEQ_CST);
    int bad = run(r, l, 0);
    __atomic_store_n(&record, 0, __ATOMIC_SEQ_CST);
    const long n = nseq;
    long runs = 0, sites = 0;
    for (long k = 0; k < n && !bad; k++)
    {
        int first = 1, last = 1;
        for (long j = 0; j < n && (first || last); j++)
            if (seq[j] == seq[k] && j != k)
            {
                first &= j > k;
                last &= j < k;
            }
        sites += first;
        if (first || last)
        {
            bad |= run(r, l, k + 1);
            runs++;
        }
    }
    TAP_OK(!bad && n > 0 && n < MAX_SEQ,
           "WMGenerate: %ld call sites of %ld allocations (glue and core), "
           "each failing at its first and last (%ld runs): CE_Failure with "
           "a message or CE_None",
           sites, n, runs);
    TAP_OK(read_failures > 0,
           "the reading's own allocations were among them (%ld runs failed "
           "reading the input)",
           read_failures);
    GDALClose(in);
    CPLPopErrorHandler();
    free(seq);
    GDALDestroyDriverManager();
    return TAP_DONE();
}
