/*
 * watermesh.h - public C API of watermesh, in the style of GDAL's
 * gdal_alg.h: layers in, layers out, options as a NULL-terminated list of
 * "NAME=VALUE" strings, a GDALProgressFunc, a CPLErr back. Errors are
 * reported through CPLError.
 */
#ifndef WATERMESH_H
#define WATERMESH_H

#include <cpl_port.h>
#include <cpl_progress.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

CPL_C_START

/** Version string of the library, e.g. "0.1.0". */
const char CPL_DLL *WMVersion(void);

/**
 * Works out the CRS the mesh is computed and written in, from the inputs
 * and the TARGET_SRS option: TARGET_SRS if given; else the rivers' CRS if
 * projected; else the lakes' CRS if projected; else (geographic input) the
 * UTM zone of the inputs' centre. Either layer may be NULL, not both.
 *
 * @return a new spatial reference, caller releases it with OSRRelease(),
 *         or NULL with a CPLError (e.g. no CRS at all and no TARGET_SRS).
 */
OGRSpatialReferenceH CPL_DLL WMGetWorkingSRS(OGRLayerH hRivers,
                                             OGRLayerH hLakes,
                                             CSLConstList papszOptions);

/**
 * Computes the dissolved water polygons and their constrained Delaunay
 * mesh, block by block, and writes them to two existing layers.
 *
 * @param hRivers  river centerlines (LineString/MultiLineString), or NULL;
 *                 its attribute filter, if any, is honoured
 * @param hLakes   lakes (Polygon/MultiPolygon), or NULL (not both NULL)
 * @param hWater   output layer for polygons (one feature per connected
 *                 polygon per block), or NULL; fields block_x, block_y,
 *                 area, polygon are set when the layer has them
 * @param hMesh    output layer for triangles (one MultiPolygon, or TIN
 *                 under MESH_GEOMETRY=TIN, per polygon per block; one
 *                 Polygon per triangle under MESH_GEOMETRY=TRIANGLES), or
 *                 NULL; fields block_x, block_y, triangles, polygon are set
 *                 when present
 * @param papszOptions WIDTH, WIDTH_FIELD, PIXEL_SIZE, BLOCK_SIZE, SIMPLIFY,
 *                 METHOD, HEURISTIC, MERGE_DISTANCE, MIN_FEATURE_AREA,
 *                 MESH_GEOMETRY, DEVICE, NUM_THREADS, TARGET_SRS (see
 *                 the driver documentation), SPAT=xmin,ymin,xmax,ymax
 *                 (working CRS: only blocks touching it), STATS=YES
 *                 (print the per-stage timing table to stdout)
 * @param pfnProgress progress callback or NULL; returning FALSE cancels
 * @param pProgressArg its argument
 * @return CE_None, or CE_Failure after a CPLError (CPLE_UserInterrupt on
 *         cancellation). Geometries are in the working CRS
 *         (WMGetWorkingSRS). Features are built in worker threads from the
 *         output layers' definitions, which must not change during the
 *         call; they are written from the calling thread.
 */
CPLErr CPL_DLL WMGenerate(OGRLayerH hRivers, OGRLayerH hLakes, OGRLayerH hWater,
                          OGRLayerH hMesh, CSLConstList papszOptions,
                          GDALProgressFunc pfnProgress, void *pProgressArg);

CPL_C_END

#endif /* WATERMESH_H */
