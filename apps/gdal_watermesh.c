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
#include <sys/stat.h>
#include <unistd.h>

static void usage(int code)
{
    FILE *f = code ? stderr : stdout;
    fprintf(
        f,
        "Usage: gdal_watermesh [--help] [--version] [--help-general]\n"
        "       [-rivers <ds>] [-rivers_layer <name>] [-rivers_where <expr>]\n"
        "       [-lakes <ds>] [-lakes_layer <name>] [-lakes_where <expr>]\n"
        "       [-width <m>] [-width_field <field>]\n"
        "       [-width_by_class <field>:<class>=<m>,...] [-pixel_size <m>]\n"
        "       [-block_size <m>] [-simplify <m>] [-method CONTOUR|PAPER]\n"
        "       [-heuristic "
        "CLOSEST|DIRECTIONAL_CW|DIRECTIONAL_CCW|LEAST_ANGLE]\n"
        "       [-merge_distance <m>] [-min_feature_area <m2>]\n"
        "       [-device AUTO|CPU|OPENCL] [-num_threads <n>|ALL_CPUS]\n"
        "       [-target_srs <srs>] [-spat <xmin> <ymin> <xmax> <ymax>]\n"
        "       [-mesh_geometry MULTIPOLYGON|TIN|TRIANGLES]\n"
        "       [-min_angle <deg>] [-max_edge <m>]\n"
        "       [-elevation <raster>] [-elevation_band <n>]\n"
        "       [-lake_level_percentile <p>] [-flow DEM|LINE_DIRECTION]\n"
        "       [-of <format>] [-lco <NAME>=<VALUE>]... [-dsco "
        "<NAME>=<VALUE>]...\n"
        "       [-overwrite] [-progress|-q] [-stats]\n"
        "       [-shard <i>/<N>] [-shard-env <var>] [-shard-plan <file>]\n"
        "       [-blocks <bx>:<by>[,...]] [-resume] [-list-blocks]\n"
        "       [<scene.watermesh>] <dst_datasource>\n"
        "\n"
        "Writes layers 'water' (dissolved polygons per block) and 'mesh'\n"
        "(constrained Delaunay triangles per polygon) to <dst_datasource>\n"
        "(default format GPKG, or guessed from the extension). With -of GLB,\n"
        "<dst_datasource> is a folder of binary glTF 2.0 files, one per "
        "block,\n"
        "and index.json.\n");
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
                            char **lco, const WMField *fields)
{
    OGRLayerH l = GDALDatasetCreateLayer(ds, name, srs, t, lco);
    if (!l)
        return NULL;
    for (const WMField *f = fields; f->name; f++)
    {
        OGRFieldDefnH fd = OGR_Fld_Create(f->name, f->type);
        const OGRErr e = OGR_L_CreateField(l, fd, TRUE);
        OGR_Fld_Destroy(fd);
        if (e != OGRERR_NONE)
            return NULL;
    }
    return l;
}

/* Formats whose file holds one layer. Named as a file (or always, for
 * the JSON ones, which have no folder form), the destination becomes two
 * files, <name>_water.<ext> and <name>_mesh.<ext>; named as a folder, the
 * format's folder form holds water.<ext> and mesh.<ext>. */
static int single_layer_file(GDALDriverH drv, const char *dst)
{
    static const char *const folder_form[] = {"ESRI Shapefile", "FlatGeobuf",
                                              "MapInfo File", "CSV", NULL};
    static const char *const file_only[] = {"GeoJSON", "GeoJSONSeq", NULL};
    const char *name = GDALGetDriverShortName(drv);
    for (int i = 0; file_only[i]; i++)
        if (EQUAL(name, file_only[i]))
            return TRUE;
    for (int i = 0; folder_form[i]; i++)
        if (EQUAL(name, folder_form[i]))
            return *CPLGetExtension(dst) != '\0';
    return FALSE;
}

/* The file a layer goes to under the single-layer rule: <name>_<layer>.<ext>
 * beside dst (ext: dst's, else the format's). */
static char *layer_file(GDALDriverH drv, const char *dst, const char *layer)
{
    const char *ext = CPLGetExtension(dst);
    if (!*ext)
        ext = GDALGetMetadataItem(drv, GDAL_DMD_EXTENSION, NULL);
    char *base = CPLStrdup(CPLGetBasename(dst));
    char *path = CPLStrdup(CPLFormFilename(
        CPLGetPath(dst), CPLSPrintf("%s_%s", base, layer), ext));
    CPLFree(base);
    return path;
}

/* Moving the new output into place, undoably: every file it replaces is
 * first renamed into a folder of old files, and on any failure the new
 * files are removed and the old ones renamed back. */
typedef struct
{
    const char *olddir;  /* where replaced files wait */
    char **placed;       /* new entries moved into place */
    char **old, **saved; /* replaced files, and where they wait */
    int fail_at;         /* test hook: this rename fails (0: none) */
    int renames;
} swap;

static int do_rename(swap *w, const char *from, const char *to)
{
    if (++w->renames == w->fail_at || VSIRename(from, to) != 0)
    {
        CPLError(CE_Failure, CPLE_FileIO,
                 "gdal_watermesh: cannot move %s to %s.", from, to);
        return FALSE;
    }
    return TRUE;
}

static int set_aside(swap *w, const char *path)
{
    char *to = CPLStrdup(
        CPLFormFilename(w->olddir, CPLSPrintf("%d", CSLCount(w->old)), NULL));
    const int ok = do_rename(w, path, to);
    if (ok)
    {
        w->old = CSLAddString(w->old, path);
        w->saved = CSLAddString(w->saved, to);
    }
    CPLFree(to);
    return ok;
}

/* With -overwrite, every file of the old dataset at `target` is set
 * aside, so that none of its side files (a .qix, .cpg, -wal) outlives it
 * next to the new one. A folder target is merged into (a Shapefile
 * folder), or set aside whole with whole_folder (-of GLB: no stale block
 * file may stay beside the new index). */
static int set_aside_dataset(swap *w, const char *target, int whole_folder)
{
    VSIStatBufL sb;
    if (VSIStatL(target, &sb) != 0)
        return TRUE;
    if (VSI_ISDIR(sb.st_mode))
        return !whole_folder || set_aside(w, target);
    CPLPushErrorHandler(CPLQuietErrorHandler);
    GDALDatasetH ds = GDALOpenEx(target, GDAL_OF_VECTOR, NULL, NULL, NULL);
    CPLPopErrorHandler();
    char **files = ds ? GDALGetFileList(ds) : NULL;
    if (ds)
        GDALClose(ds);
    if (!files)
        files = CSLAddString(NULL, target);
    int ok = TRUE;
    for (char **f = files; ok && *f; f++)
        if (VSIStatL(*f, &sb) == 0 && !VSI_ISDIR(sb.st_mode))
            ok = set_aside(w, *f);
    CSLDestroy(files);
    return ok;
}

/* Walks folder `from` into folder `to`. With w NULL it only checks: FALSE
 * (after a CPLError) when an entry would replace one without `overwrite`,
 * or a file by a folder or the reverse. With w it moves: files replace
 * files of the same name (set aside first), folders are merged entry by
 * entry, so an existing destination folder loses only what this run
 * rewrites. */
static int move_into_place(swap *w, const char *from, const char *to,
                           int overwrite)
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
        const int dst_dir = exists && VSI_ISDIR(ds.st_mode);
        if (!w && exists && !overwrite)
        {
            CPLError(CE_Failure, CPLE_FileIO,
                     "gdal_watermesh: %s already exists; use -overwrite.", dst);
            ok = FALSE;
        }
        else if (src_dir && dst_dir)
            ok = move_into_place(w, src, dst, overwrite);
        else if (!w && exists && src_dir != dst_dir)
        {
            CPLError(CE_Failure, CPLE_FileIO,
                     "gdal_watermesh: cannot replace %s: one of the old and "
                     "the new is a folder, the other a file.",
                     dst);
            ok = FALSE;
        }
        else if (w)
        {
            ok = (!exists || set_aside(w, dst)) && do_rename(w, src, dst);
            if (ok)
                w->placed = CSLAddString(w->placed, dst);
        }
        CPLFree(src);
        CPLFree(dst);
    }
    CSLDestroy(entries);
    return ok;
}

/* Removes what was placed and renames the old files back. */
static void undo(swap *w)
{
    CPLPushErrorHandler(CPLQuietErrorHandler);
    for (int i = CSLCount(w->placed) - 1; i >= 0; i--)
    {
        VSIStatBufL sb;
        if (VSIStatL(w->placed[i], &sb) == 0 && VSI_ISDIR(sb.st_mode))
            VSIRmdirRecursive(w->placed[i]);
        else
            VSIUnlink(w->placed[i]);
    }
    for (int i = CSLCount(w->old) - 1; i >= 0; i--)
        VSIRename(w->saved[i], w->old[i]);
    CPLPopErrorHandler();
}

/* Moves the run's output (folder newdir) into dstdir, replacing the
 * targets' old files with -overwrite; all or nothing. */
static int put_in_place(const char *newdir, const char *olddir,
                        const char *dstdir, const char *const targets[2],
                        int overwrite, int whole_folder)
{
    if (!move_into_place(NULL, newdir, dstdir, overwrite))
        return FALSE;
    swap w = {olddir, NULL, NULL, NULL, 0, 0};
    w.fail_at =
        atoi(CPLGetConfigOption("GDAL_WATERMESH_TEST_RENAME_FAILURE", "0"));
    int ok = VSIMkdir(olddir, 0755) == 0;
    for (int t = 0; ok && overwrite && t < 2 && targets[t]; t++)
        ok = set_aside_dataset(&w, targets[t], whole_folder);
    ok = ok && move_into_place(&w, newdir, dstdir, overwrite);
    if (!ok)
        undo(&w);
    CSLDestroy(w.placed);
    CSLDestroy(w.old);
    CSLDestroy(w.saved);
    return ok;
}

/* SHARD=i/N from -shard i/N, or from -shard N (or i/N) and -shard-env
 * VAR, whose value is i (a job array's task id); FALSE after a message. */
static int add_shard(char ***opts, const char *shard, const char *env)
{
    const char *slash = shard ? strchr(shard, '/') : NULL;
    const char *n = slash ? slash + 1 : shard;
    char *end = NULL;
    if (!n || strtol(n, &end, 10) < 1 || *end || (!env && !slash))
    {
        fprintf(stderr, "ERROR: -shard needs i/N (or N with -shard-env).\n");
        return FALSE;
    }
    const char *i = env ? getenv(env) : NULL;
    if (env && (!i || !*i || strtol(i, &end, 10) < 0 || *end))
    {
        fprintf(stderr,
                "ERROR: -shard-env %s: the variable holds no shard index "
                "(%s).\n",
                env, i ? i : "unset");
        return FALSE;
    }
    char *spec = env ? CPLStrdup(CPLSPrintf("%s/%s", i, n)) : CPLStrdup(shard);
    *opts = CSLSetNameValue(*opts, "SHARD", spec);
    CPLFree(spec);
    return TRUE;
}

/* -list-blocks: the blocks a run would compute (of SHARD, SPAT), "bx by"
 * a line, in run order; FALSE after a CPLError. */
static int list_blocks(char **all)
{
    WMSources src;
    if (!WMSourcesOpen(all, &src))
        return FALSE;
    WMScene *s = WMSceneBuild(src.hRivers, src.hLakes, all);
    WMSourcesClose(&src);
    if (!s)
        return FALSE;
    const double *spat = s->params.have_spat ? s->params.spat : NULL;
    WMBlockWalk w;
    WMBlockWalkBegin(&w, s, spat);
    int64_t b[2];
    size_t n = 0;
    int ok;
    while ((ok = WMBlockWalkNext(&w, b, 1, &n)) && n == 1)
        if (WMShardHas(s, b[0], b[1]))
            printf("%lld %lld\n", (long long)b[0], (long long)b[1]);
    WMBlockWalkEnd(&w);
    WMSceneFree(s);
    return ok;
}

/* -resume: TRUE (with a note) when every target exists: a job that
 * finished, since outputs are only ever put in place complete. */
static int done_before(const char *const targets[2], int quiet)
{
    for (int t = 0; t < 2 && targets[t]; t++)
    {
        VSIStatBufL sb;
        if (VSIStatL(targets[t], &sb) != 0)
            return FALSE;
    }
    if (!quiet)
        fprintf(stderr, "gdal_watermesh: %s exists; skipped (-resume).\n",
                targets[0]);
    return TRUE;
}

/* Writes the scene as binary glTF files into the new folder `path`;
 * FALSE after a CPLError. */
static int write_glb(const WMScene *scene, const char *path, int show_progress)
{
    if (VSIMkdir(path, 0755) != 0)
    {
        CPLError(CE_Failure, CPLE_FileIO, "gdal_watermesh: cannot create %s.",
                 path);
        return FALSE;
    }
    return WMSceneWriteGLB(scene, path, progress,
                           show_progress ? (void *)1 : NULL) == CE_None &&
           !g_interrupted;
}

/* Writes the scene: both layers into a new dataset at `path`, or, when
 * mesh_path is set, the water layer to `path` and the mesh layer to
 * mesh_path; FALSE after a CPLError. */
static int write_output(const WMScene *scene, GDALDriverH drv, const char *path,
                        const char *mesh_path, char **lco, char **dsco,
                        int show_progress)
{
    GDALDatasetH out = GDALCreate(drv, path, 0, 0, 0, GDT_Unknown, dsco);
    GDALDatasetH mout = out && mesh_path ? GDALCreate(drv, mesh_path, 0, 0, 0,
                                                      GDT_Unknown, dsco)
                                         : out;
    OGRLayerH lw =
        out && mout ? make_layer(out, "water", WMWaterType(scene), scene->hSRS,
                                 lco, WMLayerFields(scene, FALSE))
                    : NULL;
    OGRLayerH lm = lw ? make_layer(mout, "mesh", WMMeshType(scene), scene->hSRS,
                                   lco, WMLayerFields(scene, TRUE))
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
    /* closing a discarded output is quiet; closing a good one flushes it,
     * and a write that fails there (a full disk) fails the run */
    const int discarded = !ok;
    if (discarded)
        CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    if (mout && mout != out)
        GDALClose(mout);
    if (out)
        GDALClose(out);
    if (discarded)
        CPLPopErrorHandler();
    else if (CPLGetLastErrorType() >= CE_Failure)
        ok = FALSE;
    return ok;
}

/* The command line, parsed. */
typedef struct
{
    char **opts, **lco, **dsco;            /* owned */
    const char *format, *descriptor, *dst; /* dst without a trailing / */
    char *own;                             /* what dst or descriptor is */
    int overwrite, show_progress, quiet, stats, list, resume;
    const char *shard, *shard_env, *shard_plan, *blocks;
} cli;

static void cli_free(cli *c)
{
    CSLDestroy(c->opts);
    CSLDestroy(c->lco);
    CSLDestroy(c->dsco);
    CPLFree(c->own);
}

/* -NAME value for an option of the driver (WM_OPTION_NAMES), any case. */
static void add_option(cli *c, const char *a, const char *value)
{
    char *name = CPLStrdup(a + 1);
    for (char *p = name; *p; p++)
        *p = (char)toupper((unsigned char)*p);
    int known = FALSE;
    for (int k = 0; WM_OPTION_NAMES[k]; k++)
        known |= EQUAL(name, WM_OPTION_NAMES[k]);
    if (!known || !value)
    {
        fprintf(stderr, "ERROR: unknown option or missing value: %s\n", a);
        CPLFree(name);
        usage(1);
    }
    c->opts = CSLSetNameValue(c->opts, name, value);
    CPLFree(name);
}

/* argv[*i] (and its values) when it is one of the flags of the command
 * itself; FALSE otherwise. */
static int cli_flag(cli *c, int argc, char **argv, int *i)
{
    const char *a = argv[*i];
    const char *next = *i + 1 < argc ? argv[*i + 1] : NULL;
    const char **value = EQUAL(a, "-of")           ? &c->format
                         : EQUAL(a, "-shard")      ? &c->shard
                         : EQUAL(a, "-shard-env")  ? &c->shard_env
                         : EQUAL(a, "-shard-plan") ? &c->shard_plan
                         : EQUAL(a, "-blocks")     ? &c->blocks
                                                   : NULL;
    int *flag = EQUAL(a, "-overwrite")                 ? &c->overwrite
                : EQUAL(a, "-progress")                ? &c->show_progress
                : EQUAL(a, "-q") || EQUAL(a, "-quiet") ? &c->quiet
                : EQUAL(a, "-stats")                   ? &c->stats
                : EQUAL(a, "-list-blocks")             ? &c->list
                : EQUAL(a, "-resume")                  ? &c->resume
                                                       : NULL;
    if (EQUAL(a, "--help") || EQUAL(a, "-h"))
        usage(0);
    if (value && next)
        *value = argv[++*i];
    else if (flag)
        *flag = TRUE;
    else if ((EQUAL(a, "-lco") || EQUAL(a, "-dsco")) && next)
    {
        char ***list = EQUAL(a, "-lco") ? &c->lco : &c->dsco;
        *list = CSLAddString(*list, argv[++*i]);
    }
    else if (EQUAL(a, "-spat"))
    {
        if (*i + 4 >= argc)
        {
            fprintf(stderr, "ERROR: -spat needs 4 values.\n");
            usage(1);
        }
        char *v =
            CPLStrdup(CPLSPrintf("%s,%s,%s,%s", argv[*i + 1], argv[*i + 2],
                                 argv[*i + 3], argv[*i + 4]));
        c->opts = CSLSetNameValue(c->opts, "SPAT", v);
        CPLFree(v);
        *i += 4;
    }
    else
        return FALSE;
    return TRUE;
}

/* Parses the command line into c (exits through usage() when it is
 * wrong). */
static void parse_args(int argc, char **argv, cli *c)
{
    memset(c, 0, sizeof *c);
    const char *dst = NULL;
    for (int i = 1; i < argc; i++)
    {
        const char *a = argv[i];
        if (cli_flag(c, argc, argv, &i))
            continue;
        if (a[0] == '-' && a[1] && !(a[1] >= '0' && a[1] <= '9'))
        {
            add_option(c, a, i + 1 < argc ? argv[i + 1] : NULL);
            i++;
        }
        else if (!dst)
            dst = a;
        else if (!c->descriptor)
        {
            c->descriptor = dst;
            dst = a;
        }
        else
        {
            fprintf(stderr, "ERROR: too many arguments: %s\n", a);
            usage(1);
        }
    }
    c->own = dst ? CPLStrdup(dst) : NULL;
    for (size_t n = c->own ? strlen(c->own) : 0; n > 1 && c->own[n - 1] == '/';)
        c->own[--n] = '\0';
    c->dst = c->own;
    if (c->list && c->dst && !c->descriptor)
    { /* -list-blocks writes nothing */
        c->descriptor = c->dst;
        c->dst = NULL;
    }
    if (!c->dst && !c->list)
    {
        fprintf(stderr, "ERROR: no destination datasource given.\n");
        usage(1);
    }
}

/* The run's options: the descriptor's, then the command line's; FALSE
 * (and *all NULL) after a CPLError or message. */
static int run_options(const cli *c, char ***all)
{
    *all = NULL;
    if (c->descriptor && !(*all = WMReadDescriptor(c->descriptor)))
        return FALSE;
    for (char **p = c->opts; p && *p; p++)
    {
        char *key = NULL;
        const char *val = CPLParseNameValue(*p, &key);
        *all = CSLSetNameValue(*all, key, val);
        CPLFree(key);
    }
    if (c->stats)
        *all = CSLSetNameValue(*all, "STATS", "YES");
    int ok =
        !(c->shard || c->shard_env) || add_shard(all, c->shard, c->shard_env);
    if (ok && c->shard_plan && !c->shard && !c->shard_env && !c->blocks)
    {
        fprintf(stderr, "ERROR: -shard-plan needs -shard or -blocks.\n");
        ok = FALSE;
    }
    if (ok && c->blocks)
        *all = CSLSetNameValue(*all, "BLOCKS", c->blocks);
    if (ok && c->shard_plan)
        *all = CSLSetNameValue(*all, "SHARD_PLAN", c->shard_plan);
    if (!ok)
    {
        CSLDestroy(*all);
        *all = NULL;
    }
    return ok;
}

/* Whether paths a and b name one existing file (or folder). */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

/* Refuses destinations the run cannot write in place of (before any
 * work): one on a GDAL virtual file system (/vsistdout/, /vsimem/, ...:
 * the output is written beside the destination and moved there, and
 * /vsistdout/ has no beside; /vsimem/ would vanish with the process), and
 * a target that is one of the inputs (as ogr2ogr refuses). */
static int destination_usable(const char *dst, const char *const targets[2],
                              char **all)
{
    if (STARTS_WITH_CI(dst, "/vsi"))
    {
        CPLError(CE_Failure, CPLE_NotSupported,
                 "gdal_watermesh: %s is on a GDAL virtual file system; the "
                 "output is written beside its destination and moved into "
                 "place, which needs a file or folder on disk.",
                 dst);
        return FALSE;
    }
    static const char *const inputs[] = {"RIVERS", "LAKES"};
    for (int t = 0; t < 2 && targets[t]; t++)
        for (int i = 0; i < 2; i++)
        {
            const char *in = CSLFetchNameValue(all, inputs[i]);
            if (in && same_file(in, targets[t]))
            {
                CPLError(CE_Failure, CPLE_AppDefined,
                         "gdal_watermesh: the destination %s is the %s "
                         "input; write to another file.",
                         targets[t], inputs[i]);
                return FALSE;
            }
        }
    return TRUE;
}

/* Refuses targets that exist without -overwrite (before any work). */
static int targets_free(const char *const targets[2], int overwrite)
{
    for (int t = 0; t < 2 && targets[t]; t++)
    {
        VSIStatBufL sb;
        if (VSIStatL(targets[t], &sb) == 0 && !overwrite)
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "gdal_watermesh: %s already exists; use -overwrite to "
                     "replace it.",
                     targets[t]);
            return FALSE;
        }
    }
    return TRUE;
}

/* Writes the scene into a temporary folder beside the destination (drv, or
 * glTF with drv NULL), then puts every target in place; FALSE after an
 * error, with nothing left at the targets but what was there. */
static int write_job(const cli *c, const WMScene *scene, GDALDriverH drv,
                     const char *const targets[2])
{
    char *dstdir = CPLStrdup(CPLGetPath(c->dst));
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
        /* the output is written under tmpdir/new; the files it replaces
         * wait in tmpdir/old until everything is in place */
        const int show = c->show_progress && !c->quiet;
        char *newdir = CPLStrdup(CPLFormFilename(tmpdir, "new", NULL));
        char *olddir = CPLStrdup(CPLFormFilename(tmpdir, "old", NULL));
        char *tmpw = CPLStrdup(
            CPLFormFilename(newdir, CPLGetFilename(targets[0]), NULL));
        char *tmpm = targets[1] ? CPLStrdup(CPLFormFilename(
                                      newdir, CPLGetFilename(targets[1]), NULL))
                                : NULL;
        ok = VSIMkdir(newdir, 0755) == 0 &&
             (drv ? write_output(scene, drv, tmpw, tmpm, c->lco, c->dsco, show)
                  : write_glb(scene, tmpw, show)) &&
             put_in_place(newdir, olddir, dstdir, targets, c->overwrite, !drv);
        CPLFree(tmpw);
        CPLFree(tmpm);
        CPLFree(newdir);
        CPLFree(olddir);
        VSIRmdirRecursive(tmpdir);
    }
    CPLFree(tmpdir);
    CPLFree(dstdir);
    return ok;
}

/* The run after the options: output driver, targets, inputs, writing;
 * the exit code. */
static int run(const cli *c, char **all)
{
    /* -of GLB: a folder of binary glTF files, one per block */
    const int glb = c->format && EQUAL(c->format, "GLB");
    GDALDriverH drv = glb         ? NULL
                      : c->format ? GDALGetDriverByName(c->format)
                                  : guess_driver(c->dst);
    if (!drv && !glb)
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "gdal_watermesh: no vector driver %s%s.",
                 c->format ? "named " : "for ", c->format ? c->format : c->dst);
        return 1;
    }
    /* what the run writes: dst, or two files by the single-layer rule;
     * any of them existing is refused before any work */
    char *water_dst = NULL, *mesh_dst = NULL;
    if (!glb && single_layer_file(drv, c->dst))
    {
        water_dst = layer_file(drv, c->dst, "water");
        mesh_dst = layer_file(drv, c->dst, "mesh");
    }
    else
        water_dst = CPLStrdup(c->dst);
    const char *const targets[2] = {water_dst, mesh_dst};
    int rc = 1;
    if (!destination_usable(c->dst, targets, all))
        rc = 1;
    else if (c->resume && done_before(targets, c->quiet))
        rc = 0;
    else if (targets_free(targets, c->overwrite))
    {
        /* read and check every input before anything is created */
        WMSources src;
        WMScene *scene = NULL;
        if (WMSourcesOpen(all, &src))
        {
            scene = WMSceneBuild(src.hRivers, src.hLakes, all);
            WMSourcesClose(&src);
        }
        if (scene && write_job(c, scene, drv, targets))
            rc = 0;
        else if (scene && g_interrupted)
            fprintf(stderr, "ERROR: interrupted; nothing written to %s.\n",
                    c->dst);
        WMSceneFree(scene);
    }
    CPLFree(water_dst);
    CPLFree(mesh_dst);
    return rc;
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

    cli c;
    parse_args(argc, argv, &c);
    char **all = NULL;
    int rc = 1;
    if (run_options(&c, &all))
        rc = c.list ? (list_blocks(all) ? 0 : 1) : run(&c, all);
    CSLDestroy(all);
    cli_free(&c);
    CSLDestroy(argv);
    GDALDestroyDriverManager();
    return rc;
}
