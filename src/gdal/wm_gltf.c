/*
 * wm_gltf.c - the mesh as binary glTF 2.0, one file per block
 * (gdal_watermesh -of GLB <folder>).
 *
 * A file is the 12-byte header, a JSON chunk and a BIN chunk (glTF 2.0,
 * "GLB file format specification"). One mesh, one primitive of
 * triangles: POSITION (float32 VEC3, with its min and max), with
 * ELEVATION NORMAL (float32 unit VEC3, from the height rule's gradient)
 * and y the vertex's height, and uint32 indices, in a buffer
 * of the positions, the normals, then the indices. Positions are
 * metres relative to the block's origin (its lower-left corner in the
 * working CRS), so float32 keeps them to the lattice; glTF's axes are +X
 * east, +Y up, +Z south, which keeps the triangles counter-clockwise seen
 * from above. The scene's extras carry the origin, the block and the CRS.
 * index.json lists the files with their origins and triangle counts.
 *
 * Each file is written under a temporary name and renamed when complete.
 */
#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_string.h>
#include <cpl_vsi.h>

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct
{
    const WMScene *s;
    const char *folder;
    char *crs;      /* JSON string (quoted) */
    char **entries; /* index.json's block entries (nentries, cap) */
    size_t nentries, cap;
} glb_sink;

/* s as a JSON string literal (quoted, escaped); CPLFree it. */
static char *json_string(const char *s)
{
    size_t n = 3;
    for (const char *p = s; *p; p++)
        n += 6;
    char *out = CPLMalloc(n), *o = out;
    *o++ = '"';
    for (const unsigned char *p = (const unsigned char *)s; *p; p++)
    {
        if (*p == '"' || *p == '\\')
        {
            *o++ = '\\';
            *o++ = (char)*p;
        }
        else if (*p < 0x20)
            o += snprintf(o, 7, "\\u%04x", *p);
        else
            *o++ = (char)*p;
    }
    *o++ = '"';
    *o = '\0';
    return out;
}

/* The working CRS as "AUTH:CODE" when it has one, else its WKT. */
static char *crs_json(OGRSpatialReferenceH srs)
{
    const char *auth = OSRGetAuthorityName(srs, NULL);
    const char *code = OSRGetAuthorityCode(srs, NULL);
    if (auth && code)
        return json_string(CPLSPrintf("%s:%s", auth, code));
    char *wkt = NULL;
    OSRExportToWkt(srs, &wkt);
    char *j = json_string(wkt ? wkt : "");
    CPLFree(wkt);
    return j;
}

/* Appends n bytes of padding byte pad so that *len is a multiple of 4. */
static int pad4(VSILFILE *fp, size_t len, char pad)
{
    static const char spaces[3] = {' ', ' ', ' '}, zeros[3] = {0, 0, 0};
    const size_t n = (4 - len % 4) % 4;
    return VSIFWriteL(pad == ' ' ? spaces : zeros, 1, n, fp) == n;
}

static int put_u32(VSILFILE *fp, uint32_t v)
{
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8),
                          (unsigned char)(v >> 16), (unsigned char)(v >> 24)};
    return VSIFWriteL(b, 1, 4, fp) == 4;
}

/* Bytes of the BIN chunk: positions, normals (with heights), indices. */
static size_t bin_length(const wm_block_result *r, size_t nv, size_t nt)
{
    return (r->z ? 24 : 12) * nv + 12 * nt;
}

/* Unit normals of the vertices of r (glTF axes: x east, y up, z south)
 * from the gradient of the height rule (drape.h): (-dz/dx, 1, dz/dy),
 * normalized. A pure function of position, like the heights: a vertex on
 * a block side has the same normal in both blocks, so shading shows no
 * seam; lakes point straight up. */
static void normals(const WMScene *s, const wm_block_result *r, size_t nv,
                    float *nrm)
{
    for (size_t i = 0; i < nv; i++)
    {
        const double gx = r->zgrad[2 * i] / s->unit;
        const double gy = r->zgrad[2 * i + 1] / s->unit;
        const double len = sqrt(gx * gx + 1 + gy * gy);
        nrm[3 * i] = (float)(-gx / len);
        nrm[3 * i + 1] = (float)(1 / len);
        nrm[3 * i + 2] = (float)(gy / len);
    }
}

/* The BIN chunk's content: float32 positions (x, z, -y), then with heights
 * float32 unit normals, then uint32 indices; *min and *max of the
 * positions. CPLFree the result. */
static unsigned char *bin_chunk(const WMScene *s, const wm_block_result *r,
                                size_t nv, size_t nt, float min[3],
                                float max[3])
{
    unsigned char *bin = VSI_MALLOC_VERBOSE(bin_length(r, nv, nt));
    if (!bin)
        return NULL;
    float *pos = (float *)bin;
    for (int k = 0; k < 3; k++)
    {
        min[k] = FLT_MAX;
        max[k] = -FLT_MAX;
    }
    for (size_t i = 0; i < nv; i++)
    {
        const wm_pt p = wm_block_point(r, i);
        const float v[3] = {(float)(p.x * s->unit),
                            r->z ? (float)r->z[i] : 0.0f,
                            -(float)(p.y * s->unit)};
        for (int k = 0; k < 3; k++)
        {
            pos[3 * i + (size_t)k] = v[k];
            min[k] = v[k] < min[k] ? v[k] : min[k];
            max[k] = v[k] > max[k] ? v[k] : max[k];
        }
    }
    if (r->z)
        normals(s, r, nv, pos + 3 * nv);
    uint32_t *idx = (uint32_t *)(bin + bin_length(r, nv, 0));
    for (size_t i = 0; i < 3 * nt; i++)
        idx[i] = r->tris[i];
    return bin;
}

/* printf into a new string of any length; CPLFree it. */
static char *format(const char *fmt, ...) CPL_PRINT_FUNC_FORMAT(1, 2);
static char *format(const char *fmt, ...)
{
    va_list ap;
    char *out = NULL;
    va_start(ap, fmt);
    const int n = CPLVASPrintf(&out, fmt, ap);
    va_end(ap);
    if (n < 0)
    {
        CPLFree(out);
        return CPLStrdup("");
    }
    return out;
}

/* The JSON chunk of block result r. CPLFree it. */
static char *json_chunk(const glb_sink *g, const wm_block_result *r, size_t nv,
                        size_t nt, const float min[3], const float max[3],
                        double x0, double y0)
{
    const size_t pv = 12 * nv, nb = r->z ? 12 * nv : 0, ib = 12 * nt;
    char *normal =
        r->z ? format("{\"bufferView\":1,\"componentType\":5126,\"count\":"
                      "%zu,\"type\":\"VEC3\"},",
                      nv)
             : CPLStrdup("");
    char *nview = r->z ? format("{\"buffer\":0,\"byteOffset\":%zu,"
                                "\"byteLength\":%zu,\"target\":34962},",
                                pv, nb)
                       : CPLStrdup("");
    char *out = format(
        "{\"asset\":{\"version\":\"2.0\",\"generator\":\"watermesh %s\"},"
        "\"scene\":0,\"scenes\":[{\"nodes\":[0],\"extras\":{"
        "\"origin\":[%.17g,%.17g,0],\"block\":[%lld,%lld],\"crs\":%s,"
        "\"axes\":\"x east, y up, z south; metres from origin\"}}],"
        "\"nodes\":[{\"mesh\":0,\"name\":\"block %lld %lld\"}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0%s},"
        "\"indices\":%d,\"mode\":4}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,"
        "\"count\":%zu,\"type\":\"VEC3\",\"min\":[%.9g,%.9g,%.9g],"
        "\"max\":[%.9g,%.9g,%.9g]},%s{\"bufferView\":%d,\"componentType\":"
        "5125,\"count\":%zu,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":%zu,"
        "\"target\":34962},%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":"
        "%zu,\"target\":34963}],\"buffers\":[{\"byteLength\":%zu}]}",
        WMVersion(), x0, y0, (long long)r->bx, (long long)r->by, g->crs,
        (long long)r->bx, (long long)r->by, r->z ? ",\"NORMAL\":1" : "",
        r->z ? 2 : 1, nv, (double)min[0], (double)min[1], (double)min[2],
        (double)max[0], (double)max[1], (double)max[2], normal, r->z ? 2 : 1,
        3 * nt, pv, nview, pv + nb, ib, pv + nb + ib);
    CPLFree(normal);
    CPLFree(nview);
    return out;
}

/* Writes the GLB of r to path; FALSE after a CPLError. */
static int write_glb(const glb_sink *g, const wm_block_result *r,
                     const char *path, double x0, double y0)
{
    const size_t nv = wm_block_npoints(r), nt = r->poly_tri[r->npolys];
    float min[3], max[3];
    unsigned char *bin = bin_chunk(g->s, r, nv, nt, min, max);
    if (!bin)
        return FALSE;
    char *json = json_chunk(g, r, nv, nt, min, max, x0, y0);
    const size_t jl = strlen(json), jp = (jl + 3) / 4 * 4,
                 bl = bin_length(r, nv, nt), bp = (bl + 3) / 4 * 4;
    int ok = jp + bp + 28 <= UINT32_MAX;
    VSILFILE *fp = ok ? VSIFOpenL(path, "wb") : NULL;
    ok = fp && put_u32(fp, 0x46546C67u) && put_u32(fp, 2) &&
         put_u32(fp, (uint32_t)(12 + 8 + jp + 8 + bp)) &&
         put_u32(fp, (uint32_t)jp) && put_u32(fp, 0x4E4F534Au) &&
         VSIFWriteL(json, 1, jl, fp) == jl && pad4(fp, jl, ' ') &&
         put_u32(fp, (uint32_t)bp) && put_u32(fp, 0x004E4942u) &&
         VSIFWriteL(bin, 1, bl, fp) == bl && pad4(fp, bl, 0);
    if (fp && VSIFCloseL(fp) != 0)
        ok = FALSE;
    if (!ok)
        CPLError(CE_Failure, CPLE_FileIO, "gdal_watermesh: cannot write %s.",
                 path);
    CPLFree(json);
    VSIFree(bin);
    return ok;
}

static int glb_block(void *user, wm_block_result *r, void *prep)
{
    (void)prep;
    glb_sink *g = user;
    int ok = TRUE;
    if (r->npolys > 0 && r->poly_tri[r->npolys] > 0)
    {
        const double side = (double)g->s->core.n * WM_Q * g->s->unit;
        const double x0 = (double)r->bx * side, y0 = (double)r->by * side;
        const char *name = CPLSPrintf("block_%lld_%lld.glb", (long long)r->bx,
                                      (long long)r->by);
        char *file = CPLStrdup(name);
        char *path = CPLStrdup(CPLFormFilename(g->folder, file, NULL));
        char *tmp = CPLStrdup(CPLSPrintf("%s.tmp", path));
        ok = write_glb(g, r, tmp, x0, y0);
        if (ok && VSIRename(tmp, path) != 0)
        {
            CPLError(CE_Failure, CPLE_FileIO,
                     "gdal_watermesh: cannot move %s to %s.", tmp, path);
            ok = FALSE;
        }
        if (!ok)
            VSIUnlink(tmp);
        else if ((ok = wm_grow((void **)&g->entries, &g->cap, g->nentries + 1,
                               sizeof *g->entries)) != 0)
            g->entries[g->nentries++] = CPLStrdup(CPLSPrintf(
                "{\"file\":\"%s\",\"block\":[%lld,%lld],"
                "\"origin\":[%.17g,%.17g],\"triangles\":%zu,"
                "\"vertices\":%zu}",
                file, (long long)r->bx, (long long)r->by, x0, y0,
                (size_t)r->poly_tri[r->npolys], wm_block_npoints(r)));
        else
            CPLError(CE_Failure, CPLE_OutOfMemory, "WATERMESH: out of memory.");
        CPLFree(file);
        CPLFree(path);
        CPLFree(tmp);
    }
    wm_block_result_free(r);
    return ok;
}

/* index.json: the CRS and the blocks written. */
static int write_index(const glb_sink *g)
{
    const char *path = CPLFormFilename(g->folder, "index.json", NULL);
    VSILFILE *fp = VSIFOpenL(path, "wb");
    int ok = fp != NULL;
    if (ok)
        ok = VSIFPrintfL(fp,
                         "{\"format\":\"watermesh glTF blocks\",\"version\":"
                         "\"%s\",\"crs\":%s,\"axes\":\"x east, y up, z "
                         "south; metres from each block's origin\","
                         "\"blocks\":[",
                         WMVersion(), g->crs) > 0;
    for (size_t i = 0; ok && i < g->nentries; i++)
        ok = VSIFPrintfL(fp, "%s\n  %s", i ? "," : "", g->entries[i]) > 0;
    ok = ok && VSIFPrintfL(fp, "]}\n") > 0;
    if (fp && VSIFCloseL(fp) != 0)
        ok = FALSE;
    if (!ok)
        CPLError(CE_Failure, CPLE_FileIO, "gdal_watermesh: cannot write %s.",
                 path);
    return ok;
}

CPLErr WMSceneWriteGLB(const WMScene *s, const char *folder,
                       GDALProgressFunc pfn, void *pArg)
{
    glb_sink g = {s, folder, crs_json(s->hSRS), NULL, 0, 0};
    const WMBlockSink sink = {glb_block, NULL, NULL, &g};
    CPLErr err = WMSceneRun(s, &sink, pfn, pArg);
    if (err == CE_None && !write_index(&g))
        err = CE_Failure;
    for (size_t i = 0; i < g.nentries; i++)
        CPLFree(g.entries[i]);
    free(g.entries);
    CPLFree(g.crs);
    return err;
}
