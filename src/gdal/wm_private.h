/*
 * wm_private.h - the GDAL side's internal interface: options, sources,
 * scene ingestion, the parallel block runner and feature emission. Shared
 * by the C API, the driver and the CLI so each thing is done in one place.
 */
#ifndef WM_PRIVATE_H
#define WM_PRIVATE_H

#include "watermesh.h"

#include "../core/block.h"
#include "../core/drape.h"
#include "../core/scene.h"

CPL_C_START

/** Widest river accepted, metres: wider values are data errors (and would
 *  make a single river reach thousands of blocks). */
#define WM_MAX_WIDTH 100000.0

/** Every option name, in documentation order (NULL-terminated). */
extern const char *const WM_OPTION_NAMES[];

/** DEVICE: where the field is computed. */
typedef enum
{
    WM_DEVICE_AUTO = 0, /* C, or WATERMESH_OPENCL_DEVICE when set */
    WM_DEVICE_CPU,      /* the C path */
    WM_DEVICE_OPENCL    /* OpenCL, an error when there is no device */
} WMDeviceKind;

/** MESH_GEOMETRY: the form of a mesh feature. */
typedef enum
{
    WM_MESH_MULTIPOLYGON = 0, /* a polygon's triangles, one MultiPolygon */
    WM_MESH_TIN,              /* a polygon's triangles, one TIN */
    WM_MESH_TRIANGLES         /* one Polygon feature per triangle */
} WMMeshForm;

/** Parsed, validated parameters. */
typedef struct
{
    double width;         /* default river width, m */
    char *width_field;    /* or NULL: a field, or "field:hstore key" */
    char *class_field;    /* WIDTH_BY_CLASS's field (as width_field), or
                             NULL */
    char **class_names;   /* its classes ("*": any other) ... */
    double *class_widths; /* ... and their widths, m */
    int nclasses;
    double pixel;            /* PIXEL_SIZE, m */
    double block;            /* BLOCK_SIZE, m */
    int32_t n;               /* block / pixel */
    double simplify;         /* m */
    wm_method method;        /* METHOD */
    int heuristic;           /* HEURISTIC, a wm_heuristic (METHOD=PAPER) */
    double merge;            /* MERGE_DISTANCE, m; 0: off */
    double min_feature_area; /* MIN_FEATURE_AREA, m^2; 0: off */
    double min_angle;        /* MIN_ANGLE, degrees; 0: off */
    double max_edge;         /* MAX_EDGE, m; 0: off */
    WMMeshForm mesh_form;    /* MESH_GEOMETRY */
    WMDeviceKind device;
    int num_threads;
    char *target_srs; /* or NULL */
    int have_spat;
    double spat[4];         /* xmin, ymin, xmax, ymax in the working CRS */
    int64_t shard, nshards; /* SHARD=i/N: the i-th of N contiguous runs of
                               the grid's cells (nshards 0: all) */
    char *shard_plan;       /* SHARD_PLAN: file of the scan's result, or NULL */
    int nblockrects;        /* BLOCKS: rectangles of block indices */
    int64_t (*blockrects)[4]; /* bx0, by0, bx1, by1, inclusive (owned) */
    char *elevation;          /* ELEVATION: a raster, or NULL */
    int elevation_band;       /* ELEVATION_BAND */
    double lake_percentile;   /* LAKE_LEVEL_PERCENTILE, 0 .. 100 */
    int flow_line;            /* FLOW=LINE_DIRECTION (else DEM) */
    int stats;
} WMParams;

/** Parses and validates options; CPLError and FALSE on a bad value. */
int WMParamsParse(CSLConstList papszOptions, WMParams *p);
void WMParamsFree(WMParams *p);

/** The inputs of a run: datasets opened from RIVERS / LAKES options. */
typedef struct
{
    GDALDatasetH hRiversDS, hLakesDS;
    OGRLayerH hRivers, hLakes;
} WMSources;

/** Opens RIVERS/RIVERS_LAYER/RIVERS_WHERE and the LAKES ones; CPLError
 *  naming the input and FALSE on failure (nothing left open). */
int WMSourcesOpen(CSLConstList papszOptions, WMSources *src);
void WMSourcesClose(WMSources *src);

/**
 * Reads a .watermesh descriptor (XML, root <WaterMesh>, one element per
 * option) into a NAME=VALUE list, datasource paths made absolute against
 * the descriptor's folder. Returns NULL with a CPLError on failure; caller
 * frees with CSLDestroy().
 */
char **WMReadDescriptor(const char *pszPath);

/** SHARD=i/N's share of the block grid (wm_shard.c): cells [first, last)
 *  of the nx x ny grid from (gx0, gy0), row-major. */
typedef struct
{
    int on;
    int64_t gx0, gy0, nx, ny;
    uint64_t first, last;
} WMShard;

/** A scene ready to run: the core scene plus what the GDAL side needs. */
typedef struct
{
    wm_scene core;
    double unit; /* metres per lattice unit: pixel / WM_Q */
    OGRSpatialReferenceH hSRS;
    WMParams params;
    struct WMDevice *device; /* where the field is computed (owned) */
    size_t width_source[3];  /* river features whose width came from
                                WIDTH_FIELD, WIDTH_BY_CLASS, WIDTH */
    WMShard shard;           /* SHARD's cells (shard.on FALSE: all) */
    size_t *line_start;      /* nlines + 1 offsets into core.segs: each
                                river line part's segments, in order */
    size_t nlines;
    struct WMDrape *drape; /* ELEVATION's levels, or NULL (owned) */
} WMScene;

/** ELEVATION's levels (wm_drape.c): per river segment end and per lake
 *  water body, and what the core's wm_drape reads. */
typedef struct WMDrape
{
    wm_drape core;
    double *za, *zb;     /* per segment */
    double *tk, *zk;     /* per segment: its knee at a lake's shore */
    int32_t *poly_body;  /* per lake polygon */
    double *body_level;  /* per body */
    double *body_spread; /* per body: max - min of its shoreline samples */
    size_t nbodies;
} WMDrape;

/** Reads ELEVATION and computes the levels of s's lakes and rivers into
 *  s->drape (nothing without ELEVATION). FALSE after a CPLError naming the
 *  raster and the problem. */
int WMDrapePrepare(WMScene *s);
void WMDrapeFree(WMDrape *d);

/** SHARD: finds the job's cells of the grid around the layers' extents and
 *  sets on the layers the spatial filter of those cells grown by the halo
 *  (the widest river's half-width + 3 pixels); FALSE after a CPLError. */
int WMShardPrepare(WMScene *s, OGRLayerH hRivers, OGRLayerH hLakes,
                   CSLConstList opts);

/** Whether block (bx, by) is the job's (always without SHARD). */
int WMShardHas(const WMScene *s, int64_t bx, int64_t by);

/** WMBlockCount of the job's blocks (SHARD). */
int WMShardBlockCount(const WMScene *s, const double *spat, uint64_t *count);

/** One streaming pass over layer h: the envelope of its geometries (layer
 *  CRS) and, for rivers, the widest width (m) its features take into
 *  *wmax. TRUE, or -1 when it has no geometry, FALSE after a CPLError. */
int WMLayerScan(OGRLayerH h, const WMParams *p, int rivers, OGREnvelope *env,
                double *wmax);

/** A scene's field device (wm_device.c): the C path, or OpenCL with the
 *  state of a DEVICE=AUTO run whose device failed. */
typedef struct WMDevice
{
    wm_field_device field; /* runs OpenCL on cl (user: this struct) */
    struct wm_cl *cl;      /* NULL: the C path; else borrowed from the
                              process-wide cache */
    int auto_mode;         /* DEVICE=AUTO: a failing device hands over to C */
    int failed; /* atomic: 0 ok; 1, 2 the device failed (2: fail_msg is
                   set); 3 reported */
    char fail_msg[512];
    char desc[480]; /* "CPU (C path...)" or "OpenCL: <device> (<platform>)" */
} WMDevice;

/** Chooses the field device of a scene (s->device) from DEVICE and the
 *  config options WATERMESH_OPENCL_DEVICE (a device name substring) and
 *  WATERMESH_KERNEL_DIR (a folder with field.cl, for kernel development);
 *  logs the choice with CPLDebug. FALSE with a CPLError when DEVICE=OPENCL
 *  cannot be honoured (or out of memory). */
int WMDeviceSelect(WMScene *s);

/** The field device to hand to the core: NULL for the C path. */
const wm_field_device *WMDeviceField(const WMDevice *d);

/** Emits the CE_Warning of a device that failed under DEVICE=AUTO, once,
 *  from the calling thread (the block runner calls it after each block). */
void WMDeviceWarn(WMDevice *d);

/** Releases the process-wide OpenCL devices (driver unload). */
void WMDeviceCleanup(void);

/** Reads both layers into a scene (reprojecting, quantizing, indexing).
 *  Returns NULL with a CPLError. Caller frees with WMSceneFree(). */
WMScene *WMSceneBuild(OGRLayerH hRivers, OGRLayerH hLakes,
                      CSLConstList papszOptions);
void WMSceneFree(WMScene *s);

/** A walk over the blocks of a scene that something reaches, touching the
 *  spatial filter (if any), in row-major order (rows from the lowest block
 *  y, then x), a batch at a time: memory holds one row's runs, never the
 *  grid's blocks. */
typedef struct
{
    const WMScene *s;
    int64_t x0, y0, x1, y1; /* the window, block indices */
    int64_t by;             /* the row of runs */
    int64_t *runs;          /* its runs (first, last) */
    size_t nruns, irun;
    int64_t bx; /* the next block, in runs[irun] */
} WMBlockWalk;

/** Starts a walk (spat: xmin, ymin, xmax, ymax, or NULL). */
void WMBlockWalkBegin(WMBlockWalk *w, const WMScene *s, const double *spat);
/** The next blocks, at most max (bx, by pairs into out); *n is 0 at the
 *  end. FALSE after a CPLError. */
int WMBlockWalkNext(WMBlockWalk *w, int64_t *out, size_t max, size_t *n);
void WMBlockWalkEnd(WMBlockWalk *w);
/** How many blocks a walk with this filter visits (row runs only). */
int WMBlockCount(const WMScene *s, const double *spat, uint64_t *count);

/** Where a run's block results go.
 *  put: called from the calling thread, in block order; takes ownership of
 *  res and prep; returns FALSE to stop the run (after a CPLError).
 *  prepare (optional): called from the worker thread that computed res,
 *  before put, to do put's work that needs no shared state (building
 *  features); what it returns is put's prep (NULL: nothing prepared, or
 *  out of memory: put does it all). drop (required with prepare): frees a
 *  prep that never reached put (a run that stopped early). */
typedef struct
{
    int (*put)(void *user, wm_block_result *res, void *prep);
    void *(*prepare)(void *user, const wm_block_result *res);
    void (*drop)(void *user, void *prep);
    void *user;
} WMBlockSink;

/** Run statistics of WMRunBlocks. */
typedef struct
{
    double seconds[WM_STAGE_COUNT]; /* summed over blocks (thread time) */
    double wall;
    size_t blocks, polygons, vertices, triangles, mixed_tiles;
    uint64_t samples, pairs, contour_vertices;
    size_t steiner, small_input, left, at_side; /* MIN_ANGLE / MAX_EDGE */
} WMRunStats;

/** A wm_error_fn keeping the first message in *(char **)user (CPLStrdup'ed;
 *  the caller frees it with CPLFree). */
void WMKeepFirstError(void *user, wm_status status, const char *msg);

/** Runs blocks on num_threads threads, at most a few per thread in flight,
 *  handing results to sink in order. CE_Failure after a CPLError. */
CPLErr WMRunBlocks(const WMScene *s, const int64_t *blocks, size_t nblocks,
                   const WMBlockSink *sink, GDALProgressFunc pfn, void *pArg,
                   WMRunStats *stats);

/** The mesh layer's geometry type: wkbMultiPolygon, wkbTIN, or wkbPolygon
 *  under MESH_GEOMETRY=TRIANGLES. */
OGRwkbGeometryType WMMeshType(const WMScene *s);
/** The water layer's geometry type: wkbPolygon, wkbPolygon25D with
 *  ELEVATION (the mesh types likewise take Z). */
OGRwkbGeometryType WMWaterType(const WMScene *s);

/** An attribute field of an output layer. */
typedef struct
{
    const char *name;
    OGRFieldType type;
} WMField;

/** The fields of the water layer (mesh FALSE) or the mesh layer, ending
 *  with {NULL}: block_x, block_y, area (water) or triangles (mesh, but
 *  not under MESH_GEOMETRY=TRIANGLES), polygon (the polygon's index in its
 *  block: block_x, block_y, polygon name a water polygon and its mesh). */
const WMField *WMLayerFields(const WMScene *s, int mesh);

/** A feature of layer definition defn with polygon p of block result r
 *  (mesh FALSE: water) or its mesh, or with triangle t (t != SIZE_MAX,
 *  MESH_GEOMETRY=TRIANGLES); the fields of WMLayerFields that defn has are
 *  set. Caller destroys it. NULL when out of memory. Geometries are in
 *  world coordinates: the water polygon; the polygon's triangles as a
 *  MultiPolygon (a set of triangles sharing edges, not OGC-valid) or a
 *  TIN; a triangle as a Polygon. */
OGRFeatureH WMNewFeature(const WMScene *s, OGRFeatureDefnH defn, int mesh,
                         const wm_block_result *r, size_t p, size_t t);
/** Polygon area in m^2 (exact lattice area, then scaled). */
double WMPolygonArea(const WMScene *s, const wm_block_result *r, size_t p);

/** Runs every block of a built scene (those touching SPAT, if set, and of
 *  SHARD's range),
 *  handing each result to sink in block order; prints the stage table
 *  when STATS was set. */
CPLErr WMSceneRun(const WMScene *s, const WMBlockSink *sink,
                  GDALProgressFunc pfn, void *pArg);

/** WMSceneRun writing the features to hWater / hMesh (either may be
 *  NULL). WMGenerate is WMSceneBuild + this. */
CPLErr WMSceneGenerate(const WMScene *s, OGRLayerH hWater, OGRLayerH hMesh,
                       GDALProgressFunc pfn, void *pArg);

/** WMSceneRun writing one binary glTF 2.0 file per block with triangles
 *  into folder (which must exist), block_<bx>_<by>.glb, and index.json
 *  listing them (wm_gltf.c). */
CPLErr WMSceneWriteGLB(const WMScene *s, const char *folder,
                       GDALProgressFunc pfn, void *pArg);

/** Prints the per-stage table and the vertex ratio to stdout. */
void WMPrintStats(const WMScene *s, const WMRunStats *st);

CPL_C_END

#endif /* WM_PRIVATE_H */
