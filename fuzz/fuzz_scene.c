/*
 * fuzz_scene.c - libFuzzer target: geometry ingestion down to the output
 * of the first blocks. The input is text:
 *
 *   line 1: options, NAME=VALUE separated by spaces (PIXEL_SIZE, WIDTH,
 *           METHOD, SIMPLIFY, ...), and CRS=0..4 for the layers' CRS
 *           (EPSG:32631, 4326, 3857, 2056, or none);
 *   then:   "R <width> <WKT>" a river (the width is the text of a string
 *           field, as OSM has it), "L <WKT>" a lake.
 *
 * The layers are in-memory, read by WMSceneBuild (reprojection, auto-UTM,
 * width parsing, thinning, quantizing, indexing) and the first blocks run
 * through the whole pipeline. BLOCK_SIZE is 128 pixels whatever the input
 * says, so every input's work is bounded and a slow one is a finding.
 */
#include "fuzz_util.h"

#include <cpl_string.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static GDALDriverH mem;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_setup();
    mem = GDALGetDriverByName("Memory");
    return 0;
}

static OGRSpatialReferenceH make_srs(int which)
{
    static const int codes[] = {32631, 4326, 3857, 2056};
    if (which < 0 || which > 3)
        return NULL;
    OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
    OSRImportFromEPSG(srs, codes[which]);
    OSRSetAxisMappingStrategy(srs, OAMS_TRADITIONAL_GIS_ORDER);
    return srs;
}

/* Adds one feature from "<WKT>" (and a width text for rivers). */
static void add(OGRLayerH l, const char *wkt, const char *width)
{
    OGRGeometryH g = NULL;
    char *p = (char *)wkt;
    if (OGR_G_CreateFromWkt(&p, NULL, &g) != OGRERR_NONE)
        return;
    OGRFeatureH f = OGR_F_Create(OGR_L_GetLayerDefn(l));
    OGR_F_SetGeometryDirectly(f, g);
    if (width)
        OGR_F_SetFieldString(f, 0, width);
    /* a feature a layer refuses is simply not part of the scene */
    (void)!OGR_L_CreateFeature(l, f);
    OGR_F_Destroy(f);
}

/* Options of line 1, BLOCK_SIZE forced to 128 pixels, one thread, C. */
static char **options(const char *line, int *crs)
{
    char **in = CSLTokenizeString2(line, " ", 0), **opts = NULL;
    double pixel = 0.5;
    for (int i = 0; in && in[i]; i++)
    {
        char *key = NULL;
        const char *v = CPLParseNameValue(in[i], &key);
        if (key && v && EQUAL(key, "CRS"))
            *crs = atoi(v);
        else if (key && v && !EQUAL(key, "BLOCK_SIZE") &&
                 !EQUAL(key, "NUM_THREADS") && !EQUAL(key, "DEVICE"))
        {
            opts = CSLSetNameValue(opts, key, v);
            if (EQUAL(key, "PIXEL_SIZE"))
                pixel = CPLAtof(v);
        }
        CPLFree(key);
    }
    CSLDestroy(in);
    char block[64];
    snprintf(block, sizeof block, "%.17g", 128 * pixel);
    opts = CSLSetNameValue(opts, "BLOCK_SIZE", block);
    opts = CSLSetNameValue(opts, "NUM_THREADS", "1");
    opts = CSLSetNameValue(opts, "DEVICE", "CPU");
    opts = CSLSetNameValue(opts, "WIDTH_FIELD", "width");
    return opts;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = CPLMalloc(size + 1);
    memcpy(text, data, size);
    text[size] = '\0';
    char **lines = CSLTokenizeString2(text, "\n", CSLT_ALLOWEMPTYTOKENS);
    CPLFree(text);
    int crs = 0;
    char **opts = options(lines && lines[0] ? lines[0] : "", &crs);
    OGRSpatialReferenceH srs = make_srs(crs);
    GDALDatasetH ds = GDALCreate(mem, "", 0, 0, 0, GDT_Unknown, NULL);
    OGRLayerH r = GDALDatasetCreateLayer(ds, "rivers", srs, wkbUnknown, NULL);
    OGRLayerH l = GDALDatasetCreateLayer(ds, "lakes", srs, wkbUnknown, NULL);
    OGRFieldDefnH fd = OGR_Fld_Create("width", OFTString);
    OGR_L_CreateField(r, fd, TRUE);
    OGR_Fld_Destroy(fd);
    int have_r = 0, have_l = 0;
    for (int i = 1; lines && lines[0] && lines[i]; i++)
    {
        const char *t = lines[i];
        if (t[0] == 'L' && t[1] == ' ')
        {
            add(l, t + 2, NULL);
            have_l = 1;
        }
        else if (t[0] == 'R' && t[1] == ' ')
        {
            const char *sp = strchr(t + 2, ' ');
            if (!sp)
                continue;
            char *w = CPLStrdup(t + 2);
            w[sp - (t + 2)] = '\0';
            add(r, sp + 1, w);
            CPLFree(w);
            have_r = 1;
        }
    }
    WMScene *s =
        WMSceneBuild(have_r || !have_l ? r : NULL, have_l ? l : NULL, opts);
    if (s)
    {
        fuzz_run_scene(s);
        WMSceneFree(s);
    }
    GDALClose(ds);
    if (srs)
        OSRRelease(srs);
    CSLDestroy(opts);
    CSLDestroy(lines);
    CPLErrorReset();
    return 0;
}
