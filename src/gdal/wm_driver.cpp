/*
 * wm_driver.cpp - the WATERMESH GDAL driver: thin C++ glue over the C
 * pipeline (wm_private.h). A dataset opened from "WATERMESH:" plus open
 * options, or from a .watermesh descriptor, exposes
 *   - vector layers `water` and `mesh`, computed lazily block by block
 *     (only the blocks the spatial filter touches), and
 *   - a Float32 raster band: the signed distance field in metres on the
 *     global sample grid, computed per raster block on demand.
 * No C++ exception crosses into GDAL: every entry point catches.
 */
#include "wm_private.h"

#include "../cl/wm_cl.h"
#include "../core/field.h"

#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <climits>
#include <cctype>
#include <cstring>
#include <new>
#include <cmath>
#include <map>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace
{

constexpr int RASTER_BLOCK = 256;

struct ResultDeleter
{
    void operator()(wm_block_result *r) const
    {
        wm_block_result_free(r);
        delete r;
    }
};
using ResultPtr = std::shared_ptr<wm_block_result>;

/* A walk over a scene's blocks that ends itself. */
struct BlockWalk
{
    WMBlockWalk w;
    BlockWalk(const WMScene *s, const double *spat)
    {
        WMBlockWalkBegin(&w, s, spat);
    }
    ~BlockWalk()
    {
        WMBlockWalkEnd(&w);
    }
    BlockWalk(const BlockWalk &) = delete;
    BlockWalk &operator=(const BlockWalk &) = delete;
};

class WaterMeshLayer;

class WaterMeshDataset final : public GDALDataset
{
    friend class WaterMeshLayer;
    friend class WaterMeshBand;
    WMScene *m_poScene = nullptr;
    std::vector<std::unique_ptr<WaterMeshLayer>> m_apoLayers;

    /* Computed blocks, least recently used first out once their size
     * passes m_nCacheMax (WATERMESH_CACHE_MAX, MB): memory is bounded by
     * that plus the blocks a reader holds, not by the scene. Polygon and
     * triangle counts of every computed block stay (a few bytes each). */
    using BlockKey = std::pair<int64_t, int64_t>;
    struct CacheEntry
    {
        ResultPtr r;
        uint64_t tick;
        size_t bytes;
    };
    std::map<BlockKey, CacheEntry> m_oCache;
    std::map<uint64_t, BlockKey> m_oByAge;
    std::map<BlockKey, std::pair<size_t, size_t>> m_oCounts;
    size_t m_nCacheBytes = 0, m_nCacheMax = 0;
    uint64_t m_nTick = 0;

    void Remember(const ResultPtr &r);
    void Evict();

  public:
    WaterMeshDataset() = default;
    ~WaterMeshDataset() override;

    static int Identify(GDALOpenInfo *poOpenInfo);
    static GDALDataset *Open(GDALOpenInfo *poOpenInfo);

    int GetLayerCount() override
    {
        return static_cast<int>(m_apoLayers.size());
    }
    OGRLayer *GetLayer(int i) override;
    int TestCapability(const char *pszCap) override
    {
        /* ELEVATION gives both layers Z */
        return EQUAL(pszCap, ODsCZGeometries) && m_poScene &&
               m_poScene->params.elevation != nullptr;
    }
    CPLErr GetGeoTransform(double *padfGT) override;
    const OGRSpatialReference *GetSpatialRef() const override
    {
        return nBands ? OGRSpatialReference::FromHandle(m_poScene->hSRS)
                      : nullptr;
    }

    /** Results of blocks[0 .. 2n-1] (bx, by pairs), computing the missing
     *  ones; out may be null (then only the cache and counts fill). */
    bool Fetch(const int64_t *blocks, size_t n, std::vector<ResultPtr> *out);
    /** Blocks per Fetch of a streaming read. */
    size_t ChunkBlocks() const
    {
        return static_cast<size_t>(
            std::max(32, 8 * m_poScene->params.num_threads));
    }
};

class WaterMeshLayer final : public OGRLayer,
                             public OGRGetNextFeatureThroughRaw<WaterMeshLayer>
{
    WaterMeshDataset *m_poDS;
    bool m_bMesh;
    bool m_bPerTriangle; /* mesh, MESH_GEOMETRY=TRIANGLES */
    OGRFeatureDefn *m_poDefn;
    /* a read walks the blocks (for the filter's envelope) a chunk at a
     * time: the chunk's blocks (bx, by pairs) and their results */
    std::unique_ptr<BlockWalk> m_poWalk;
    bool m_bDone = false;
    std::vector<int64_t> m_anBlocks;
    std::vector<ResultPtr> m_aoChunk;
    /* the next feature: block of the chunk, item of the block (polygon,
     * or triangle), and the polygon of a triangle */
    size_t m_iBlock = 0, m_iItem = 0, m_iPoly = 0;

    /** Features of block result r: its polygons, or triangles. */
    size_t Items(const wm_block_result *r) const
    {
        return m_bPerTriangle ? (r->poly_tri ? r->poly_tri[r->npolys] : 0)
                              : r->npolys;
    }

  public:
    WaterMeshLayer(WaterMeshDataset *poDS, bool bMesh);
    ~WaterMeshLayer() override;

    OGRFeatureDefn *GetLayerDefn() override
    {
        return m_poDefn;
    }
    void ResetReading() override
    {
        m_poWalk.reset();
        m_bDone = false;
        m_anBlocks.clear();
        m_aoChunk.clear();
        m_iBlock = m_iItem = m_iPoly = 0;
    }
    OGRFeature *GetNextRawFeature();
    DEFINE_GET_NEXT_FEATURE_THROUGH_RAW(WaterMeshLayer)
    GIntBig GetFeatureCount(int bForce) override;
    OGRErr GetExtent(OGREnvelope *psExtent, int bForce) override;
    OGRErr GetExtent(int iGeomField, OGREnvelope *psExtent, int bForce) override
    {
        return iGeomField == 0
                   ? GetExtent(psExtent, bForce)
                   : OGRLayer::GetExtent(iGeomField, psExtent, bForce);
    }
    int TestCapability(const char *pszCap) override;
};

class WaterMeshBand final : public GDALRasterBand
{
  public:
    WaterMeshBand(WaterMeshDataset *poDS, int nX, int nY)
    {
        this->poDS = poDS;
        nBand = 1;
        eDataType = GDT_Float32;
        nRasterXSize = nX;
        nRasterYSize = nY;
        nBlockXSize = RASTER_BLOCK;
        nBlockYSize = RASTER_BLOCK;
        SetDescription("signed distance (m), negative in water");
    }
    CPLErr IReadBlock(int nBlockXOff, int nBlockYOff, void *pImage) override;
    const char *GetUnitType() override
    {
        return "m";
    }
};

/* ------------------------------------------------------------------ */

WaterMeshDataset::~WaterMeshDataset()
{
    m_apoLayers.clear();
    m_oCache.clear();
    WMSceneFree(m_poScene);
}

OGRLayer *WaterMeshDataset::GetLayer(int i)
{
    if (i < 0 || i >= GetLayerCount())
        return nullptr;
    return m_apoLayers[static_cast<size_t>(i)].get();
}

CPLErr WaterMeshDataset::GetGeoTransform(double *gt)
{
    if (!nBands)
        return CE_Failure;
    const wm_scene &c = m_poScene->core;
    const double px = m_poScene->params.pixel;
    gt[0] = static_cast<double>(c.bx0 * c.n) * px - px / 2;
    gt[1] = px;
    gt[2] = 0;
    gt[3] = static_cast<double>((c.by0 + c.nby) * c.n) * px + px / 2;
    gt[4] = 0;
    gt[5] = -px;
    return CE_None;
}

/* Bytes a block result holds. */
static size_t result_bytes(const wm_block_result *r)
{
    return sizeof *r + (r->rings.pts_cap + r->nxpts) * sizeof(wm_pt) +
           (r->z ? wm_block_npoints(r) * sizeof(double) : 0) +
           (r->poly_body ? r->npolys * sizeof(int32_t) : 0) +
           r->rings.start_cap * sizeof(size_t) +
           2 * (r->npolys + 1) * sizeof(size_t) +
           (r->poly_tri ? r->poly_tri[r->npolys] : 0) * 3 * sizeof(uint32_t);
}

void WaterMeshDataset::Remember(const ResultPtr &r)
{
    const BlockKey key{r->bx, r->by};
    m_oCounts[key] = {r->npolys, r->poly_tri ? r->poly_tri[r->npolys] : 0};
    auto it = m_oCache.find(key);
    if (it != m_oCache.end())
    {
        m_oByAge.erase(it->second.tick);
        m_nCacheBytes -= it->second.bytes;
        m_oCache.erase(it);
    }
    const size_t bytes = result_bytes(r.get());
    m_oCache[key] = CacheEntry{r, ++m_nTick, bytes};
    m_oByAge[m_nTick] = key;
    m_nCacheBytes += bytes;
}

void WaterMeshDataset::Evict()
{
    while (m_nCacheBytes > m_nCacheMax && !m_oByAge.empty())
    {
        auto old = m_oByAge.begin();
        auto it = m_oCache.find(old->second);
        m_nCacheBytes -= it->second.bytes;
        m_oCache.erase(it);
        m_oByAge.erase(old);
    }
}

struct FetchSink
{
    std::map<std::pair<int64_t, int64_t>, ResultPtr> *computed;
};

static int fetch_sink(void *user, wm_block_result *res, void *)
{
    auto *s = static_cast<FetchSink *>(user);
    wm_block_result *copy = nullptr;
    try
    {
        copy = new wm_block_result(*res);
        memset(res, 0, sizeof *res);        /* ownership moved to copy */
        ResultPtr p(copy, ResultDeleter()); /* deletes copy if it throws */
        copy = nullptr;
        (*s->computed)[{p->bx, p->by}] = p;
        return TRUE;
    }
    catch (const std::exception &)
    {
        if (copy)
            ResultDeleter()(copy);
        wm_block_result_free(res);
        CPLError(CE_Failure, CPLE_OutOfMemory, "WATERMESH: out of memory.");
        return FALSE;
    }
}

bool WaterMeshDataset::Fetch(const int64_t *blocks, size_t n,
                             std::vector<ResultPtr> *out)
{
    std::map<BlockKey, ResultPtr> got;
    std::vector<int64_t> todo;
    for (size_t i = 0; i < n; i++)
    {
        const BlockKey key{blocks[2 * i], blocks[2 * i + 1]};
        auto it = m_oCache.find(key);
        if (it == m_oCache.end())
        {
            todo.push_back(key.first);
            todo.push_back(key.second);
            continue;
        }
        got[key] = it->second.r;
        m_oByAge.erase(it->second.tick); /* used: youngest again */
        it->second.tick = ++m_nTick;
        m_oByAge[m_nTick] = key;
    }
    if (!todo.empty())
    {
        std::map<BlockKey, ResultPtr> computed;
        FetchSink fetched{&computed};
        const WMBlockSink sink = {fetch_sink, nullptr, nullptr, &fetched};
        WMRunStats st;
        if (WMRunBlocks(m_poScene, todo.data(), todo.size() / 2, &sink, nullptr,
                        nullptr, &st) != CE_None)
            return false;
        for (auto &kv : computed)
        {
            Remember(kv.second);
            got[kv.first] = kv.second;
        }
        Evict();
    }
    if (out)
    {
        out->clear();
        for (size_t i = 0; i < n; i++)
            out->push_back(got[{blocks[2 * i], blocks[2 * i + 1]}]);
    }
    return true;
}

/* ------------------------------------------------------------------ */

WaterMeshLayer::WaterMeshLayer(WaterMeshDataset *poDS, bool bMesh)
    : m_poDS(poDS), m_bMesh(bMesh),
      m_bPerTriangle(bMesh &&
                     poDS->m_poScene->params.mesh_form == WM_MESH_TRIANGLES),
      m_poDefn(new OGRFeatureDefn(bMesh ? "mesh" : "water"))
{
    SetDescription(m_poDefn->GetName());
    m_poDefn->Reference();
    m_poDefn->SetGeomType(bMesh ? WMMeshType(poDS->m_poScene)
                                : WMWaterType(poDS->m_poScene));
    m_poDefn->GetGeomFieldDefn(0)->SetSpatialRef(
        OGRSpatialReference::FromHandle(poDS->m_poScene->hSRS));
    const WMField *fields = WMLayerFields(poDS->m_poScene, bMesh);
    for (const WMField *f = fields; f->name; f++)
    {
        OGRFieldDefn o(f->name, f->type);
        m_poDefn->AddFieldDefn(&o);
    }
}

WaterMeshLayer::~WaterMeshLayer()
{
    m_poDefn->Release();
}

OGRFeature *WaterMeshLayer::GetNextRawFeature()
{
    try
    {
        if (m_bDone)
            return nullptr;
        if (!m_poWalk)
        {
            double spat[4];
            if (m_poFilterGeom)
            {
                OGREnvelope env;
                m_poFilterGeom->getEnvelope(&env);
                spat[0] = env.MinX;
                spat[1] = env.MinY;
                spat[2] = env.MaxX;
                spat[3] = env.MaxY;
            }
            m_poWalk.reset(new BlockWalk(m_poDS->m_poScene,
                                         m_poFilterGeom ? spat : nullptr));
            m_aoChunk.clear();
            m_iBlock = m_iPoly = 0;
        }
        for (;;)
        {
            if (m_iBlock >= m_aoChunk.size())
            {
                /* the next blocks, computed a chunk at a time */
                const size_t k = m_poDS->ChunkBlocks();
                size_t n = 0;
                m_anBlocks.resize(2 * k);
                m_aoChunk.clear();
                m_iBlock = m_iItem = m_iPoly = 0;
                if (!WMBlockWalkNext(&m_poWalk->w, m_anBlocks.data(), k, &n) ||
                    n == 0 || !m_poDS->Fetch(m_anBlocks.data(), n, &m_aoChunk))
                {
                    /* the end, or an error that stands: stop */
                    m_aoChunk.clear();
                    m_bDone = true;
                    return nullptr;
                }
            }
            if (m_iItem < Items(m_aoChunk[m_iBlock].get()))
                break;
            m_iBlock++;
            m_iItem = m_iPoly = 0;
        }
        const wm_block_result *r = m_aoChunk[m_iBlock].get();
        const size_t item = m_iItem++;
        if (m_bPerTriangle)
            while (r->poly_tri[m_iPoly + 1] <= item)
                m_iPoly++;
        else
            m_iPoly = item;
        const WMScene *s = m_poDS->m_poScene;
        /* stable FID: the block's place in the scene grid, then the
         * polygon's (or triangle's) index in the block */
        const GIntBig blk =
            (r->by - s->core.by0) * s->core.nbx + (r->bx - s->core.bx0);
        auto poFeature = OGRFeature::FromHandle(
            WMNewFeature(s, OGRFeatureDefn::ToHandle(m_poDefn), m_bMesh, r,
                         m_iPoly, m_bPerTriangle ? item : SIZE_MAX));
        if (!poFeature)
            throw std::bad_alloc();
        poFeature->SetFID(m_bPerTriangle
                              ? (blk << 32) + static_cast<GIntBig>(item)
                              : (blk << 24) + static_cast<GIntBig>(item));
        poFeature->GetGeometryRef()->assignSpatialReference(
            m_poDefn->GetGeomFieldDefn(0)->GetSpatialRef());
        return poFeature;
    }
    catch (const std::exception &e)
    {
        /* the walk has moved on: the read stops rather than skip blocks */
        CPLError(CE_Failure, CPLE_AppDefined, "WATERMESH: %s", e.what());
        m_aoChunk.clear();
        m_bDone = true;
        return nullptr;
    }
}

GIntBig WaterMeshLayer::GetFeatureCount(int bForce)
{
    if (m_poFilterGeom || m_poAttrQuery)
        return OGRLayer::GetFeatureCount(bForce);
    try
    {
        /* every block's polygon count, computing (a chunk at a time, through
         * the bounded cache) the blocks not seen yet */
        const size_t k = m_poDS->ChunkBlocks();
        std::vector<int64_t> chunk(2 * k), todo;
        BlockWalk walk(m_poDS->m_poScene, nullptr);
        GIntBig total = 0;
        bool ok = true;
        size_t n = 0;
        while (ok && (ok = WMBlockWalkNext(&walk.w, chunk.data(), k, &n)) &&
               n > 0)
        {
            todo.clear();
            for (size_t i = 0; i < n; i++)
                if (!m_poDS->m_oCounts.count({chunk[2 * i], chunk[2 * i + 1]}))
                {
                    todo.push_back(chunk[2 * i]);
                    todo.push_back(chunk[2 * i + 1]);
                }
            ok = m_poDS->Fetch(todo.data(), todo.size() / 2, nullptr);
            for (size_t i = 0; ok && i < n; i++)
            {
                const auto &c =
                    m_poDS->m_oCounts[{chunk[2 * i], chunk[2 * i + 1]}];
                total +=
                    static_cast<GIntBig>(m_bPerTriangle ? c.second : c.first);
            }
        }
        return ok ? total : -1;
    }
    catch (const std::exception &)
    {
        return -1;
    }
}

OGRErr WaterMeshLayer::GetExtent(OGREnvelope *psExtent, int)
{
    /* the water's box (the capsules' and polygons', not the block grid,
     * which reaches the clamp band beyond them), grown by a pixel: sampled
     * crossings lie within that of the exact boundary */
    const wm_scene &c = m_poDS->m_poScene->core;
    if (c.nbx == 0)
        return OGRERR_FAILURE;
    const double u = m_poDS->m_poScene->unit;
    const int64_t px = WM_Q;
    psExtent->MinX = static_cast<double>(c.water.x0 - px) * u;
    psExtent->MinY = static_cast<double>(c.water.y0 - px) * u;
    psExtent->MaxX = static_cast<double>(c.water.x1 + px) * u;
    psExtent->MaxY = static_cast<double>(c.water.y1 + px) * u;
    return OGRERR_NONE;
}

int WaterMeshLayer::TestCapability(const char *pszCap)
{
    if (EQUAL(pszCap, OLCFastFeatureCount))
        return m_poFilterGeom == nullptr && m_poAttrQuery == nullptr;
    if (EQUAL(pszCap, OLCFastGetExtent))
        return TRUE;
    if (EQUAL(pszCap, OLCStringsAsUTF8))
        return TRUE;
    if (EQUAL(pszCap, OLCZGeometries)) /* ELEVATION */
        return m_poDS->m_poScene->params.elevation != nullptr;
    return FALSE;
}

/* ------------------------------------------------------------------ */

CPLErr WaterMeshBand::IReadBlock(int nBlockXOff, int nBlockYOff, void *pImage)
{
    auto *ds = static_cast<WaterMeshDataset *>(poDS);
    const wm_scene &c = ds->m_poScene->core;
    const int c0 = nBlockXOff * RASTER_BLOCK, k0 = nBlockYOff * RASTER_BLOCK;
    const int wc = std::min(RASTER_BLOCK, nRasterXSize - c0);
    const int hc = std::min(RASTER_BLOCK, nRasterYSize - k0);
    const int64_t gx0 = c.bx0 * c.n + c0;
    const int64_t gytop = (c.by0 + c.nby) * c.n - k0;
    float *out = static_cast<float *>(pImage);
    const float band = static_cast<float>(c.band * ds->m_poScene->params.pixel);
    for (int i = 0; i < RASTER_BLOCK * RASTER_BLOCK; i++)
        out[i] = band;
    wm_field f;
    char *msg = nullptr;
    wm_ctx ctx = {WMKeepFirstError, &msg, NULL};
    if (wm_field_compute(&c, gx0, gytop - hc + 1, wc, hc,
                         WMDeviceField(ds->m_poScene->device), &f,
                         &ctx) != WM_OK)
    {
        CPLError(CE_Failure, CPLE_AppDefined, "WATERMESH: %s",
                 msg ? msg : "field computation failed");
        CPLFree(msg);
        return CE_Failure;
    }
    WMDeviceWarn(ds->m_poScene->device);
    const float px = static_cast<float>(ds->m_poScene->params.pixel);
    for (int row = 0; row < hc; row++)
        for (int col = 0; col < wc; col++)
            out[row * RASTER_BLOCK + col] =
                wm_field_at(&f, col, hc - 1 - row) * px;
    wm_field_free(&f);
    return CE_None;
}

/* ------------------------------------------------------------------ */

int WaterMeshDataset::Identify(GDALOpenInfo *poOpenInfo)
{
    if (STARTS_WITH_CI(poOpenInfo->pszFilename, "WATERMESH:"))
        return TRUE;
    if (EQUAL(CPLGetExtension(poOpenInfo->pszFilename), "watermesh"))
        return TRUE;
    /* an XML file whose root element is <WaterMesh> (after an optional
     * XML declaration) */
    if (poOpenInfo->pabyHeader == nullptr)
        return FALSE;
    const char *h = reinterpret_cast<const char *>(poOpenInfo->pabyHeader);
    while (isspace(static_cast<unsigned char>(*h)))
        h++;
    if (STARTS_WITH(h, "<?xml"))
    {
        h = strstr(h, "?>");
        if (!h)
            return FALSE;
        h += 2;
        while (isspace(static_cast<unsigned char>(*h)))
            h++;
    }
    return STARTS_WITH(h, "<WaterMesh");
}

/* WATERMESH_CACHE_MAX (MB, default 512) in bytes; false, with the error
 * reported, when it is not a number >= 0. */
static bool CacheMaxFromConfig(size_t *pnBytes)
{
    const char *pszVal = CPLGetConfigOption("WATERMESH_CACHE_MAX", "512");
    const char *pszNum = pszVal;
    while (*pszNum == ' ' || *pszNum == '\t')
        pszNum++;
    char *pszEnd = nullptr;
    const double dfMB = CPLStrtod(pszNum, &pszEnd);
    while (pszEnd && (*pszEnd == ' ' || *pszEnd == '\t'))
        pszEnd++;
    if (*pszNum == '\0' || pszEnd == pszNum || !pszEnd || *pszEnd != '\0' ||
        !(dfMB >= 0) || !std::isfinite(dfMB))
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: WATERMESH_CACHE_MAX=%s is not a number of "
                 "megabytes (0 or more).",
                 pszVal);
        return false;
    }
    /* at most 1e15 bytes, and never more than size_t holds */
    const double dfMax = std::min(1e15, static_cast<double>(SIZE_MAX));
    *pnBytes = static_cast<size_t>(std::min(dfMB * 1048576.0, dfMax));
    return true;
}

GDALDataset *WaterMeshDataset::Open(GDALOpenInfo *poOpenInfo)
{
    if (!Identify(poOpenInfo))
        return nullptr;
    if (poOpenInfo->eAccess == GA_Update)
        return nullptr; /* read-only; quiet so ogrinfo/QGIS retry */
    size_t nCacheMax = 0;
    if (!CacheMaxFromConfig(&nCacheMax))
        return nullptr;
    char **papszOpts = nullptr;
    if (!STARTS_WITH_CI(poOpenInfo->pszFilename, "WATERMESH:"))
    {
        papszOpts = WMReadDescriptor(poOpenInfo->pszFilename);
        if (!papszOpts)
            return nullptr;
    }
    else
    {
        const char *rest = poOpenInfo->pszFilename + strlen("WATERMESH:");
        if (*rest)
        {
            CPLError(CE_Failure, CPLE_OpenFailed,
                     "WATERMESH: unexpected text after 'WATERMESH:' (%s); "
                     "give inputs as open options (-oo RIVERS=...).",
                     rest);
            return nullptr;
        }
    }
    /* open options override descriptor elements */
    for (CSLConstList p = poOpenInfo->papszOpenOptions; p && *p; ++p)
    {
        char *key = nullptr;
        const char *val = CPLParseNameValue(*p, &key);
        if (key && val)
            papszOpts = CSLSetNameValue(papszOpts, key, val);
        CPLFree(key);
    }
    WMSources src;
    if (!WMSourcesOpen(papszOpts, &src))
    {
        CSLDestroy(papszOpts);
        return nullptr;
    }
    WMScene *scene = WMSceneBuild(src.hRivers, src.hLakes, papszOpts);
    WMSourcesClose(&src);
    CSLDestroy(papszOpts);
    if (!scene)
        return nullptr;
    try
    {
        auto poDS = std::make_unique<WaterMeshDataset>();
        poDS->m_poScene = scene;
        poDS->m_nCacheMax = nCacheMax;
        poDS->SetDescription(poOpenInfo->pszFilename);
        if (poOpenInfo->nOpenFlags & GDAL_OF_VECTOR)
        {
            poDS->m_apoLayers.emplace_back(
                new WaterMeshLayer(poDS.get(), false));
            poDS->m_apoLayers.emplace_back(
                new WaterMeshLayer(poDS.get(), true));
        }
        if ((poOpenInfo->nOpenFlags & GDAL_OF_RASTER) && scene->core.nbx > 0)
        {
            /* samples: N per block plus the last shared border */
            const double n = scene->core.n;
            const double w = static_cast<double>(scene->core.nbx) * n + 1;
            const double h = static_cast<double>(scene->core.nby) * n + 1;
            if (w > INT_MAX || h > INT_MAX)
            {
                CPLError(CE_Failure, CPLE_AppDefined,
                         "WATERMESH: the raster view would be %.0f x %.0f "
                         "pixels, more than GDAL supports; use a larger "
                         "PIXEL_SIZE.",
                         w, h);
                return nullptr;
            }
            poDS->nRasterXSize = static_cast<int>(w);
            poDS->nRasterYSize = static_cast<int>(h);
            poDS->SetBand(1, new WaterMeshBand(poDS.get(), poDS->nRasterXSize,
                                               poDS->nRasterYSize));
        }
        return poDS.release();
    }
    catch (const std::exception &e)
    {
        CPLError(CE_Failure, CPLE_AppDefined, "WATERMESH: %s", e.what());
        return nullptr;
    }
}

} // namespace

static const char OPEN_OPTIONS[] =
    "<OpenOptionList>"
    "  <Option name='RIVERS' type='string' description='River centerlines "
    "datasource (lines)'/>"
    "  <Option name='RIVERS_LAYER' type='string' description='Rivers layer "
    "name (default: the first layer of lines)'/>"
    "  <Option name='RIVERS_WHERE' type='string' description='Attribute "
    "filter on rivers'/>"
    "  <Option name='LAKES' type='string' description='Lakes datasource "
    "(polygons)'/>"
    "  <Option name='LAKES_LAYER' type='string' description='Lakes layer "
    "name (default: the first layer of polygons)'/>"
    "  <Option name='LAKES_WHERE' type='string' description='Attribute "
    "filter on lakes'/>"
    "  <Option name='WIDTH' type='float' default='10' min='0' max='100000' "
    "description='Default river width in metres (positive)'/>"
    "  <Option name='WIDTH_FIELD' type='string' description='River field "
    "holding the width (number, or text such as \"2.5 m\", \"~5\", "
    "\"5-8\", \"3;4\", \"1,5\"), or field:key for a key of an hstore "
    "field such as OSM other_tags'/>"
    "  <Option name='WIDTH_BY_CLASS' type='string' description='Widths by "
    "class where WIDTH_FIELD gives none: field:class=width,...,*=width, "
    "e.g. waterway:river=10,canal=8,stream=2,drain=1.5,ditch=1,*=3'/>"
    "  <Option name='PIXEL_SIZE' type='float' default='0.5' min='0' "
    "description='Sample spacing in metres (positive)'/>"
    "  <Option name='BLOCK_SIZE' type='float' default='4096' min='0' "
    "description='Block side in metres, a multiple of PIXEL_SIZE from 2 to "
    "65536 times it'/>"
    "  <Option name='SIMPLIFY' type='float' min='0' "
    "description='Douglas-Peucker "
    "tolerance in metres (default PIXEL_SIZE, 0 disables)'/>"
    "  <Option name='METHOD' type='string-select' default='CONTOUR' "
    "description='Boundary extraction: CONTOUR (marching squares) or PAPER "
    "(the paper&apos;s classes and Border walk)'>"
    "    <Value>CONTOUR</Value><Value>PAPER</Value>"
    "  </Option>"
    "  <Option name='HEURISTIC' type='string-select' default='CLOSEST' "
    "description='METHOD=PAPER: how the Border walk ranks its candidates'>"
    "    <Value>CLOSEST</Value><Value>DIRECTIONAL_CW</Value>"
    "<Value>DIRECTIONAL_CCW</Value><Value>LEAST_ANGLE</Value>"
    "  </Option>"
    "  <Option name='MERGE_DISTANCE' type='float' default='0' min='0' "
    "description='Merge ring vertices closer than this (metres; 0: off)'/>"
    "  <Option name='MIN_FEATURE_AREA' type='float' default='0' min='0' "
    "description='Drop land holes and water parts of a block whose ring "
    "encloses less than this (square metres) and that touch no block side; "
    "0: off'/>"
    "  <Option name='DEVICE' type='string-select' default='AUTO' "
    "description='Where the field is computed: AUTO (the C path, unless "
    "WATERMESH_OPENCL_DEVICE names a device), CPU or OPENCL (the first "
    "GPU, else any OpenCL device)'>"
    "    <Value>AUTO</Value><Value>CPU</Value><Value>OPENCL</Value>"
    "  </Option>"
    "  <Option name='NUM_THREADS' type='string' default='ALL_CPUS' "
    "description='Number of threads: an integer from 1 to 1024, or "
    "ALL_CPUS'/>"
    "  <Option name='TARGET_SRS' type='string' description='Working CRS "
    "(projected, metres)'/>"
    "  <Option name='MESH_GEOMETRY' type='string-select' "
    "default='MULTIPOLYGON' description='Geometry of a mesh feature: "
    "MULTIPOLYGON (its triangles, sharing edges: a set of triangles, not a "
    "valid MultiPolygon), TIN (a TIN of Triangles) or TRIANGLES (one "
    "Polygon feature per triangle)'>"
    "    <Value>MULTIPOLYGON</Value><Value>TIN</Value><Value>TRIANGLES</Value>"
    "  </Option>"
    "  <Option name='MIN_ANGLE' type='float' default='0' min='0' max='30' "
    "description='Refine the mesh (Steiner points) so that no triangle has "
    "an angle below this, in degrees (0: off; 20.7 guaranteed but at and "
    "near small input angles and at block sides)'/>"
    "  <Option name='MAX_EDGE' type='float' default='0' min='0' "
    "description='Refine the mesh so that no triangle edge is longer than "
    "this (metres; 0: off; at least PIXEL_SIZE)'/>"
    "  <Option name='ELEVATION' type='string' description='An elevation "
    "raster (any GDAL raster and CRS): both layers get Z, lakes flat at a "
    "shoreline percentile, rivers level bank to bank and never rising "
    "downstream'/>"
    "  <Option name='ELEVATION_BAND' type='int' default='1' min='1' "
    "description='The band of ELEVATION'/>"
    "  <Option name='LAKE_LEVEL_PERCENTILE' type='float' default='10' "
    "min='0' max='100' description='A lake&apos;s level: this percentile "
    "of the elevation along its shore'/>"
    "  <Option name='FLOW' type='string-select' default='DEM' "
    "description='River flow direction: DEM (from the higher end of each "
    "line to the lower) or LINE_DIRECTION (as digitized)'>"
    "    <Value>DEM</Value><Value>LINE_DIRECTION</Value>"
    "  </Option>"
    "</OpenOptionList>";

extern "C" void CPL_DLL GDALRegister_WATERMESH();

extern "C" void GDALRegister_WATERMESH()
{
    if (!GDAL_CHECK_VERSION("WATERMESH"))
        return;
    if (GDALGetDriverByName("WATERMESH") != nullptr)
        return;
    auto poDriver = new GDALDriver();
    poDriver->SetDescription("WATERMESH");
    poDriver->SetMetadataItem(GDAL_DCAP_RASTER, "YES");
    poDriver->SetMetadataItem(GDAL_DCAP_VECTOR, "YES");
    poDriver->SetMetadataItem(
        GDAL_DMD_LONGNAME,
        "Water mesh from rivers and lakes (watermesh " PACKAGE_VERSION ")");
    poDriver->SetMetadataItem(GDAL_DMD_HELPTOPIC, "docs/driver.rst");
    poDriver->SetMetadataItem(GDAL_DMD_EXTENSIONS, "watermesh");
    poDriver->SetMetadataItem(GDAL_DMD_CONNECTION_PREFIX, "WATERMESH:");
    poDriver->SetMetadataItem(GDAL_DMD_OPENOPTIONLIST, OPEN_OPTIONS);
    poDriver->SetMetadataItem(GDAL_DCAP_VIRTUALIO, "YES");
    poDriver->SetMetadataItem(GDAL_DCAP_Z_GEOMETRIES, "YES");
    poDriver->SetMetadataItem("WATERMESH_OPENCL", wm_cl_built() ? "YES" : "NO");
    poDriver->pfnIdentify = WaterMeshDataset::Identify;
    poDriver->pfnOpen = WaterMeshDataset::Open;
    poDriver->pfnUnloadDriver = [](GDALDriver *) { WMDeviceCleanup(); };
    GetGDALDriverManager()->RegisterDriver(poDriver);
}
