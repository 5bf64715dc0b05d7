/*
 * capi_demo.c - a small program using the public C API the way a user
 * would (watermesh.h): opens a rivers and a lakes layer, runs WMGenerate
 * into in-memory layers and prints what it got. autotest/test_capi.py runs
 * it.
 *
 * Usage: capi_demo <rivers_ds|-> <rivers_layer> <lakes_ds|-> <lakes_layer>
 *                  [--cancel] [NAME=VALUE]...
 * Prints: "water <n> mesh <m> area <a> progress_calls <k>"; exits 0 on
 * success, 2 when cancelled (CPLE_UserInterrupt), 1 on any other failure.
 */
#include "watermesh.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>

#include <stdio.h>
#include <string.h>

static int g_calls = 0;

static int CPL_STDCALL progress(double f, const char *m, void *cancel)
{
    (void)f;
    (void)m;
    g_calls++;
    return !(cancel && g_calls > 1);
}

static OGRLayerH open_layer(const char *path, const char *name,
                            GDALDatasetH *ds)
{
    *ds = NULL;
    if (!strcmp(path, "-"))
        return NULL;
    *ds = GDALOpenEx(path, GDAL_OF_VECTOR, NULL, NULL, NULL);
    return *ds ? GDALDatasetGetLayerByName(*ds, name) : NULL;
}

int main(int argc, char **argv)
{
    if (argc < 5)
    {
        fprintf(stderr, "usage: capi_demo rivers rivers_layer lakes "
                        "lakes_layer [--cancel] [K=V]...\n");
        return 1;
    }
    GDALAllRegister();
    int cancel = 0;
    char **opts = NULL;
    for (int i = 5; i < argc; i++)
        if (!strcmp(argv[i], "--cancel"))
            cancel = 1;
        else
            opts = CSLAddString(opts, argv[i]);
    GDALDatasetH dr, dl;
    OGRLayerH r = open_layer(argv[1], argv[2], &dr);
    OGRLayerH l = open_layer(argv[3], argv[4], &dl);

    OGRSpatialReferenceH srs = WMGetWorkingSRS(r, l, opts);
    if (!srs)
        return 1;
    GDALDriverH mem = GDALGetDriverByName("Memory");
    GDALDatasetH out = GDALCreate(mem, "out", 0, 0, 0, GDT_Unknown, NULL);
    OGRLayerH w = GDALDatasetCreateLayer(out, "water", srs, wkbPolygon, NULL);
    OGRLayerH m =
        GDALDatasetCreateLayer(out, "mesh", srs, wkbMultiPolygon, NULL);
    OGRFieldDefnH fd = OGR_Fld_Create("area", OFTReal);
    OGR_L_CreateField(w, fd, TRUE);
    OGR_Fld_Destroy(fd);

    const CPLErr err =
        WMGenerate(r, l, w, m, opts, progress, cancel ? (void *)1 : NULL);
    int rc = 0;
    if (err != CE_None)
        rc = CPLGetLastErrorNo() == CPLE_UserInterrupt ? 2 : 1;
    else
    {
        double area = 0;
        OGRFeatureH f;
        OGR_L_ResetReading(w);
        while ((f = OGR_L_GetNextFeature(w)) != NULL)
        {
            area += OGR_F_GetFieldAsDouble(f, 0);
            OGR_F_Destroy(f);
        }
        printf("water %lld mesh %lld area %.3f progress_calls %d\n",
               (long long)OGR_L_GetFeatureCount(w, TRUE),
               (long long)OGR_L_GetFeatureCount(m, TRUE), area, g_calls);
    }
    GDALClose(out);
    OSRRelease(srs);
    if (dr)
        GDALClose(dr);
    if (dl)
        GDALClose(dl);
    CSLDestroy(opts);
    return rc;
}
