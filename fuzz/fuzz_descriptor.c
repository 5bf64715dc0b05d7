/*
 * fuzz_descriptor.c - libFuzzer target: .watermesh descriptors. The input
 * is the descriptor's text. It is read (WMReadDescriptor), its options
 * parsed, and when its datasources are the small scene this target keeps
 * in /vsimem/fuzz/ (never a real file), the scene is built and its first
 * blocks run: layer names, WHERE filters and widths from a descriptor all
 * reach the core.
 */
#include "fuzz_util.h"

#include <cpl_string.h>
#include <cpl_vsi.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define SCENE "/vsimem/fuzz/scene.gpkg"

/* Two rivers (width field "width", text) and a lake, in EPSG:32631. */
static void make_scene(void)
{
    GDALDriverH drv = GDALGetDriverByName("GPKG");
    GDALDatasetH ds = GDALCreate(drv, SCENE, 0, 0, 0, GDT_Unknown, NULL);
    OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
    OSRImportFromEPSG(srs, 32631);
    OGRLayerH r =
        GDALDatasetCreateLayer(ds, "rivers", srs, wkbLineString, NULL);
    OGRFieldDefnH fd = OGR_Fld_Create("width", OFTString);
    OGR_L_CreateField(r, fd, TRUE);
    OGR_Fld_Destroy(fd);
    static const char *const rivers[][2] = {
        {"LINESTRING (400000 4700000, 400030 4700012, 400061 4700003)", "4"},
        {"LINESTRING (400020 4700030, 400031 4700005, 400040 4699980)",
         "2.5 m"}};
    for (int i = 0; i < 2; i++)
    {
        OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(r));
        OGRGeometryH g = NULL;
        char *wkt = (char *)rivers[i][0];
        OGR_G_CreateFromWkt(&wkt, NULL, &g);
        OGR_F_SetGeometryDirectly(f, g);
        OGR_F_SetFieldString(f, 0, rivers[i][1]);
        if (OGR_L_CreateFeature(r, f) != OGRERR_NONE)
            abort(); /* the fixture itself is broken */
        OGR_F_Destroy(f);
    }
    OGRLayerH l = GDALDatasetCreateLayer(ds, "lakes", srs, wkbPolygon, NULL);
    OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(l));
    OGRGeometryH g = NULL;
    char *wkt = (char *)"POLYGON ((400050 4699990, 400070 4699990, "
                        "400070 4700010, 400050 4700010, 400050 4699990))";
    OGR_G_CreateFromWkt(&wkt, NULL, &g);
    OGR_F_SetGeometryDirectly(f, g);
    if (OGR_L_CreateFeature(l, f) != OGRERR_NONE)
        abort();
    OGR_F_Destroy(f);
    OSRRelease(srs);
    GDALClose(ds);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_setup();
    make_scene();
    return 0;
}

/* A datasource this target may open: the in-memory scene only. */
static int ours(CSLConstList opts, const char *role)
{
    const char *v = CSLFetchNameValue(opts, role);
    return !v || strcmp(v, SCENE) == 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = "/vsimem/fuzz/in.watermesh";
    VSILFILE *fp = VSIFileFromMemBuffer(path, (GByte *)data, size, FALSE);
    if (!fp)
        return 0;
    VSIFCloseL(fp);
    char **opts = WMReadDescriptor(path);
    VSIUnlink(path);
    if (opts)
    {
        WMParams p;
        memset(&p, 0, sizeof p);
        /* a run's work is bounded: blocks of at most 512 x 512 samples,
         * one thread, the C path (so that a slow input is a finding) */
        const int ok = WMParamsParse(opts, &p);
        WMParamsFree(&p);
        if (ok && p.n <= 512)
        {
            opts = CSLSetNameValue(opts, "NUM_THREADS", "1");
            opts = CSLSetNameValue(opts, "DEVICE", "CPU");
            WMSources src;
            if (ours(opts, "RIVERS") && ours(opts, "LAKES") &&
                WMSourcesOpen(opts, &src))
            {
                WMScene *s = WMSceneBuild(src.hRivers, src.hLakes, opts);
                if (s)
                {
                    fuzz_run_scene(s);
                    WMSceneFree(s);
                }
                WMSourcesClose(&src);
            }
        }
    }
    CSLDestroy(opts);
    CPLErrorReset();
    return 0;
}
