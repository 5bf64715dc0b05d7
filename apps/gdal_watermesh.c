/*
 * gdal_watermesh - command-line tool in the style of GDAL's utilities:
 * reads rivers and lakes, writes the `water` and `mesh` layers of the
 * dissolved, triangulated water bodies to a new vector dataset.
 *
 * The destination is written under a temporary folder beside it and moved
 * into place only when everything succeeded: a failed or interrupted run
 * leaves nothing at the destination, and an existing destination is
 * replaced only with -overwrite.
 */
#include "../src/gdal/wm_private.h"

#include <cpl_conv.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>

#include <ctype.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void usage(int code)
{
    FILE *f = code ? stderr : stdout;
    fprintf(
        f,
        "Usage: gdal_watermesh [--help] [--version] [--help-general]\n"
        "       [-rivers <ds>] [-rivers_layer <name>] [-rivers_where <expr>]\n"
        "       [-lakes <ds>] [-lakes_layer <name>] [-lakes_where <expr>]\n"
        "       [-width <m>] [-width_field <field>] [-pixel_size <m>]\n"
        "       [-block_size <m>] [-simplify <m>] [-method CONTOUR|PAPER]\n"
        "       [-heuristic "
        "CLOSEST|DIRECTIONAL_CW|DIRECTIONAL_CCW|LEAST_ANGLE]\n"
        "       [-merge_distance <m>] [-min_feature_area <m2>]\n"
        "       [-device AUTO|CPU|OPENCL] [-num_threads <n>|ALL_CPUS]\n"
        "       [-target_srs <srs>] [-spat <xmin> <ymin> <xmax> <ymax>]\n"
        "       [-of <format>] [-lco <NAME>=<VALUE>]... [-dsco "
        "<NAME>=<VALUE>]...\n"
        "       [-overwrite] [-progress|-q] [-stats]\n"
        "       [<scene.watermesh>] <dst_datasource>\n"
        "\n"
        "Writes layers 'water' (dissolved polygons per block) and 'mesh'\n"
        "(constrained Delaunay triangles per polygon) to <dst_datasource>\n"
        "(default format GPKG, or guessed from the extension).\n");
    exit(code);
}

static volatile sig_atomic_t g_interrupted = 0;
static void on_signal(int sig)
{
    (void)sig;
    g_interrupted = 1;
}

static int CPL_STDCALL progress(double f, const char *msg, void *arg)
{
    if (g_interrupted)
        return FALSE;
    if (arg)
        return GDALTermProgress(f, msg, NULL);
    return TRUE;
}

/* Guesses a vector driver from the destination's extension. */
static GDALDriverH guess_driver(const char *dst)
{
    const char *ext = CPLGetExtension(dst);
    if (!*ext)
        return GDALGetDriverByName("GPKG");
    for (int i = 0; i < GDALGetDriverCount(); i++)
    {
        GDALDriverH d = GDALGetDriver(i);
        const char *exts = GDALGetMetadataItem(d, GDAL_DMD_EXTENSIONS, NULL);
        if (!GDALGetMetadataItem(d, GDAL_DCAP_VECTOR, NULL) ||
            !GDALGetMetadataItem(d, GDAL_DCAP_CREATE, NULL) || !exts)
            continue;
        char **tok = CSLTokenizeString(exts);
        const int hit = CSLFindString(tok, ext) >= 0;
        CSLDestroy(tok);
        if (hit)
            return d;
    }
    return NULL;
}

static OGRLayerH make_layer(GDALDatasetH ds, const char *name,
                            OGRwkbGeometryType t, OGRSpatialReferenceH srs,
                            char **lco, const char *last, OGRFieldType lt)
{
    OGRLayerH l = GDALDatasetCreateLayer(ds, name, srs, t, lco);
    if (!l)
        return NULL;
    const char *names[3] = {"block_x", "block_y", last};
    const OGRFieldType types[3] = {OFTInteger, OFTInteger, lt};
    for (int i = 0; i < 3; i++)
    {
        OGRFieldDefnH fd = OGR_Fld_Create(names[i], types[i]);
        const OGRErr e = OGR_L_CreateField(l, fd, TRUE);
        OGR_Fld_Destroy(fd);
        if (e != OGRERR_NONE)
            return NULL;
    }
    return l;
}

/* Moves every entry of folder `from` into folder `to`: files replace files
 * of the same name (rename() does that atomically), folders are merged
 * entry by entry, so an existing destination folder loses only what this
 * run rewrites. An entry that exists without `overwrite` is an error. */
static int move_into_place(const char *from, const char *to, int overwrite)
{
    char **entries = VSIReadDir(from);
    int ok = TRUE;
    for (char **e = entries; ok && e && *e; e++)
    {
        if (!strcmp(*e, ".") || !strcmp(*e, ".."))
            continue;
        char *src = CPLStrdup(CPLFormFilename(from, *e, NULL));
        char *dst = CPLStrdup(CPLFormFilename(to, *e, NULL));
        VSIStatBufL ss, ds;
        const int src_dir = VSIStatL(src, &ss) == 0 && VSI_ISDIR(ss.st_mode);
        const int exists = VSIStatL(dst, &ds) == 0;
        if (exists && !overwrite)
        {
            CPLError(CE_Failure, CPLE_FileIO,
                     "gdal_watermesh: %s already exists; use -overwrite.", dst);
            ok = FALSE;
        }
        else if (exists && src_dir && VSI_ISDIR(ds.st_mode))
            ok = move_into_place(src, dst, overwrite);
        else if (exists && src_dir != (VSI_ISDIR(ds.st_mode) != 0))
        {
            CPLError(CE_Failure, CPLE_FileIO,
                     "gdal_watermesh: cannot replace %s: one of the old and "
                     "the new is a folder, the other a file.",
                     dst);
            ok = FALSE;
        }
        else if (VSIRename(src, dst) != 0)
        {
            CPLError(CE_Failure, CPLE_FileIO,
                     "gdal_watermesh: cannot move %s to %s.", src, dst);
            ok = FALSE;
        }
        CPLFree(src);
        CPLFree(dst);
    }
    CSLDestroy(entries);
    return ok;
}

/* Writes the scene into a new dataset at `path`; FALSE after a CPLError. */
static int write_output(const WMScene *scene, GDALDriverH drv, const char *path,
                        char **lco, char **dsco, int show_progress)
{
    GDALDatasetH out = GDALCreate(drv, path, 0, 0, 0, GDT_Unknown, dsco);
    if (!out)
        return FALSE;
    OGRLayerH lw =
        make_layer(out, "water", wkbPolygon, scene->hSRS, lco, "area", OFTReal);
    OGRLayerH lm = lw ? make_layer(out, "mesh", wkbMultiPolygon, scene->hSRS,
                                   lco, "triangles", OFTInteger)
                      : NULL;
    int ok = lw && lm;
    if (!ok)
        CPLError(CE_Failure, CPLE_AppDefined,
                 "gdal_watermesh: cannot create the output layers in %s.",
                 path);
    if (ok)
    {
        /* one transaction when the format has them: fast GeoPackage
         * writes. On failure the whole temporary folder is discarded, so
         * there is nothing to roll back. */
        const int tx = GDALDatasetStartTransaction(out, FALSE) == OGRERR_NONE;
        ok = WMSceneGenerate(scene, lw, lm, progress,
                             show_progress ? (void *)1 : NULL) == CE_None &&
             !g_interrupted;
        if (ok && tx)
            ok = GDALDatasetCommitTransaction(out) == OGRERR_NONE;
    }
    if (!ok)
        CPLPushErrorHandler(CPLQuietErrorHandler); /* closing a discarded
                                                      output */
    GDALClose(out);
    if (!ok)
        CPLPopErrorHandler();
    return ok;
}

int main(int argc, char **argv)
{
#if defined(__GLIBC__)
    /* Each block allocates and frees tens of MB (tile values, rings,
     * grids). By default glibc hands large blocks back to the kernel and
     * faults fresh pages in for the next block: 10-15 % of a run on the
     * synthetic L3 scene. Keep that memory in the process instead (the
     * library leaves the host application's allocator alone). */
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
    for (int i = 1; i < argc; i++)
        if (EQUAL(argv[i], "--version"))
        { /* ours, before GDAL's general options answer with GDAL's */
            printf("gdal_watermesh %s (GDAL %s)\n", WMVersion(),
                   GDALVersionInfo("RELEASE_NAME"));
            return 0;
        }
    GDALAllRegister();
    argc = GDALGeneralCmdLineProcessor(argc, &argv, 0);
    if (argc < 1)
        exit(-argc);

    char **opts = NULL, **lco = NULL, **dsco = NULL;
    const char *format = NULL, *descriptor = NULL, *dst = NULL;
    int overwrite = FALSE, show_progress = FALSE, quiet = FALSE, stats = FALSE;
    int rc = 1;

    for (int i = 1; i < argc; i++)
    {
        const char *a = argv[i];
        const int more = i + 1 < argc;
        if (EQUAL(a, "--help") || EQUAL(a, "-h"))
            usage(0);
        else if (EQUAL(a, "-of") && more)
            format = argv[++i];
        else if (EQUAL(a, "-lco") && more)
            lco = CSLAddString(lco, argv[++i]);
        else if (EQUAL(a, "-dsco") && more)
            dsco = CSLAddString(dsco, argv[++i]);
        else if (EQUAL(a, "-overwrite"))
            overwrite = TRUE;
        else if (EQUAL(a, "-progress"))
            show_progress = TRUE;
        else if (EQUAL(a, "-q") || EQUAL(a, "-quiet"))
            quiet = TRUE;
        else if (EQUAL(a, "-stats"))
            stats = TRUE;
        else if (EQUAL(a, "-spat"))
        {
            if (i + 4 >= argc)
            {
                fprintf(stderr, "ERROR: -spat needs 4 values.\n");
                usage(1);
            }
            char *v =
                CPLStrdup(CPLSPrintf("%s,%s,%s,%s", argv[i + 1], argv[i + 2],
                                     argv[i + 3], argv[i + 4]));
            opts = CSLSetNameValue(opts, "SPAT", v);
            CPLFree(v);
            i += 4;
        }
        else if (a[0] == '-' && a[1] && !(a[1] >= '0' && a[1] <= '9'))
        {
            char *name = CPLStrdup(a + 1);
            for (char *p = name; *p; p++)
                *p = (char)toupper((unsigned char)*p);
            int known = FALSE;
            for (int k = 0; WM_OPTION_NAMES[k]; k++)
                known |= EQUAL(name, WM_OPTION_NAMES[k]);
            if (!known || !more)
            {
                fprintf(stderr, "ERROR: unknown option or missing value: %s\n",
                        a);
                CPLFree(name);
                usage(1);
            }
            opts = CSLSetNameValue(opts, name, argv[++i]);
            CPLFree(name);
        }
        else if (!dst)
            dst = a;
        else if (!descriptor)
        {
            descriptor = dst;
            dst = a;
        }
        else
        {
            fprintf(stderr, "ERROR: too many arguments: %s\n", a);
            usage(1);
        }
    }
    if (!dst)
    {
        fprintf(stderr, "ERROR: no destination datasource given.\n");
        usage(1);
    }

    char **all = NULL;
    if (descriptor)
    {
        all = WMReadDescriptor(descriptor);
        if (!all)
            goto end;
    }
    for (char **p = opts; p && *p; p++)
    {
        char *key = NULL;
        const char *val = CPLParseNameValue(*p, &key);
        all = CSLSetNameValue(all, key, val);
        CPLFree(key);
    }
    if (stats)
        all = CSLSetNameValue(all, "STATS", "YES");

    VSIStatBufL sb;
    if (VSIStatL(dst, &sb) == 0 && !overwrite)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "gdal_watermesh: %s already exists; use -overwrite to "
                 "replace it.",
                 dst);
        goto end;
    }
    GDALDriverH drv = format ? GDALGetDriverByName(format) : guess_driver(dst);
    if (!drv)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "gdal_watermesh: no vector driver %s%s.",
                 format ? "named " : "for ", format ? format : dst);
        goto end;
    }

    /* read and check every input before anything is created */
    WMSources src;
    if (!WMSourcesOpen(all, &src))
        goto end;
    WMScene *scene = WMSceneBuild(src.hRivers, src.hLakes, all);
    WMSourcesClose(&src);
    if (!scene)
        goto end;

    char *dstdir = CPLStrdup(CPLGetPath(dst));
    if (!*dstdir)
    {
        CPLFree(dstdir);
        dstdir = CPLStrdup(".");
    }
    char *tmpdir = CPLStrdup(CPLFormFilename(
        dstdir, CPLSPrintf(".gdal_watermesh-%ld.tmp", (long)getpid()), NULL));
    int ok = VSIMkdir(tmpdir, 0755) == 0;
    if (!ok)
        CPLError(CE_Failure, CPLE_FileIO,
                 "gdal_watermesh: cannot create a temporary folder in %s.",
                 dstdir);
    if (ok)
    {
        signal(SIGINT, on_signal);
        signal(SIGTERM, on_signal);
        char *tmpdst =
            CPLStrdup(CPLFormFilename(tmpdir, CPLGetFilename(dst), NULL));
        ok = write_output(scene, drv, tmpdst, lco, dsco,
                          show_progress && !quiet);
        CPLFree(tmpdst);
        if (ok)
            ok = move_into_place(tmpdir, dstdir, overwrite);
        VSIRmdirRecursive(tmpdir);
    }
    CPLFree(tmpdir);
    CPLFree(dstdir);
    WMSceneFree(scene);
    rc = ok ? 0 : 1;
    if (!ok && g_interrupted)
        fprintf(stderr, "ERROR: interrupted; nothing written to %s.\n", dst);
end:
    CSLDestroy(all);
    CSLDestroy(opts);
    CSLDestroy(lco);
    CSLDestroy(dsco);
    CSLDestroy(argv);
    GDALDestroyDriverManager();
    return rc;
}
