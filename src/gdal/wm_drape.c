/*
 * wm_drape.c - ELEVATION: the levels of the lakes and rivers, from an
 * elevation raster, before any block runs (the core's drape.c turns them
 * into vertex heights).
 *
 * Lakes. Lake polygons that overlap (a vertex of one inside the other)
 * form one water body. A body's level is the LAKE_LEVEL_PERCENTILE-th
 * percentile of the raster sampled along its polygons' rings (every
 * PIXEL_SIZE, or every half raster pixel when the raster shares the
 * working CRS and is coarser), leaving out the points inside another
 * polygon of the body; its spread is the samples' max - min. Computed once
 * from the whole polygons, so a lake split over blocks is one level.
 *
 * Rivers. The river lines' vertices are the nodes of one network (lines
 * meet where they share a vertex). Each node takes the raster's value
 * (bilinear over the pixel centres, nodata left out; a node without one
 * takes its line's nearest valued vertex, then its network's). A line
 * flows from its higher end to its lower (FLOW=DEM) or along its digitized
 * direction (FLOW=LINE_DIRECTION). Nodes inside a lake are pinned at the
 * lake's level. Then levels are carved downstream (a node takes the
 * lowest level upstream of it, running minimum) and filled upstream of
 * pinned nodes (a node upstream of a lake is at least the lake's level):
 * along every segment the level never rises downstream, and a river
 * meets a lake at its level. Where two lakes make that impossible (water
 * flowing from a lower lake into a higher one) a warning counts the
 * segments left rising.
 */
#include "wm_private.h"

#include <cpl_conv.h>
#include <cpl_string.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The raster is read in TILE x TILE windows, NCACHE of them kept
 * (direct-mapped by tile index): a point costs a few loads, not four
 * RasterIO calls. */
#define TILE 256
#define NCACHE 64

typedef struct
{
    int tx, ty; /* -1: empty */
    int ok;     /* the read worked */
    double *v;  /* TILE * TILE values (NAN: nodata or off the raster) */
} dem_tile;

typedef struct
{
    const char *path;
    GDALDatasetH ds;
    GDALRasterBandH band;
    dem_tile cache[NCACHE];
    double inv[6]; /* world (raster CRS) to pixel */
    int nx, ny, has_nodata;
    double nodata;
    OGRCoordinateTransformationH ct; /* working CRS to the raster's, or
                                        NULL when they are the same */
} dem_t;

static void dem_close(dem_t *d)
{
    for (int i = 0; i < NCACHE; i++)
        CPLFree(d->cache[i].v);
    if (d->ct)
        OCTDestroyCoordinateTransformation(d->ct);
    if (d->ds)
        GDALClose(d->ds);
}

/* Opens ELEVATION; *step: the sample spacing along shores, metres. */
static int dem_open(dem_t *d, const WMScene *s, double *step)
{
    const WMParams *p = &s->params;
    memset(d, 0, sizeof *d);
    for (int i = 0; i < NCACHE; i++)
        d->cache[i].tx = -1;
    d->path = p->elevation;
    d->ds = GDALOpenEx(p->elevation, GDAL_OF_RASTER | GDAL_OF_VERBOSE_ERROR,
                       NULL, NULL, NULL);
    if (!d->ds)
    {
        CPLError(CE_Failure, CPLE_OpenFailed,
                 "WATERMESH: cannot open ELEVATION raster '%s'.", d->path);
        return FALSE;
    }
    if (p->elevation_band > GDALGetRasterCount(d->ds))
    {
        CPLError(CE_Failure, CPLE_IllegalArg,
                 "WATERMESH: ELEVATION raster '%s' has %d band(s); "
                 "ELEVATION_BAND=%d.",
                 d->path, GDALGetRasterCount(d->ds), p->elevation_band);
        return FALSE;
    }
    d->band = GDALGetRasterBand(d->ds, p->elevation_band);
    d->nx = GDALGetRasterXSize(d->ds);
    d->ny = GDALGetRasterYSize(d->ds);
    double gt[6];
    if (GDALGetGeoTransform(d->ds, gt) != CE_None ||
        !GDALInvGeoTransform(gt, d->inv))
    {
        CPLError(CE_Failure, CPLE_AppDefined,
                 "WATERMESH: ELEVATION raster '%s' has no usable "
                 "geotransform.",
                 d->path);
        return FALSE;
    }
    d->nodata = GDALGetRasterNoDataValue(d->band, &d->has_nodata);
    *step = p->pixel;
    OGRSpatialReferenceH rs = GDALGetSpatialRef(d->ds);
    if (rs && !OSRIsSame(rs, s->hSRS))
    {
        OGRSpatialReferenceH c = OSRClone(rs);
        OSRSetAxisMappingStrategy(c, OAMS_TRADITIONAL_GIS_ORDER);
        d->ct = OCTNewCoordinateTransformation(s->hSRS, c);
        OSRRelease(c);
        if (!d->ct)
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: ELEVATION raster '%s': no transformation "
                     "from the working CRS to its CRS.",
                     d->path);
            return FALSE;
        }
    }
    else
    {
        const double res = fmin(fabs(gt[1]), fabs(gt[5])) / 2;
        *step = res > *step ? res : *step;
    }
    return TRUE;
}

static int valid(const dem_t *d, double v)
{
    return isfinite(v) && !(d->has_nodata && v == d->nodata);
}

/* Pixel (i, j) of the raster (inside it), NAN for nodata or a failed
 * read. */
static double pixel(dem_t *d, int i, int j)
{
    const int tx = i / TILE, ty = j / TILE;
    dem_tile *t = &d->cache[(unsigned)(tx * 31 + ty) % NCACHE];
    if (t->tx != tx || t->ty != ty)
    {
        if (!t->v)
            t->v = CPLMalloc(sizeof(double) * TILE * TILE);
        const int w = d->nx - tx * TILE < TILE ? d->nx - tx * TILE : TILE;
        const int h = d->ny - ty * TILE < TILE ? d->ny - ty * TILE : TILE;
        t->ok = GDALRasterIO(d->band, GF_Read, tx * TILE, ty * TILE, w, h, t->v,
                             w, h, GDT_Float64, 0,
                             TILE * (int)sizeof(double)) == CE_None;
        t->tx = tx;
        t->ty = ty;
    }
    const double v =
        t->v[(size_t)(j - ty * TILE) * TILE + (size_t)(i - tx * TILE)];
    return t->ok && valid(d, v) ? v : NAN;
}

/* The raster at world point (x, y) of the working CRS, bilinear over the
 * four nearest pixel centres that hold data; NAN where none does. */
static double dem_at(dem_t *d, double x, double y)
{
    if (d->ct && !OCTTransform(d->ct, 1, &x, &y, NULL))
        return NAN;
    const double u = d->inv[0] + x * d->inv[1] + y * d->inv[2] - 0.5;
    const double v = d->inv[3] + x * d->inv[4] + y * d->inv[5] - 0.5;
    if (!(u > -1 && v > -1 && u < d->nx && v < d->ny))
        return NAN;
    const int i0 = (int)floor(u), j0 = (int)floor(v);
    const double fx = u - i0, fy = v - j0;
    double sum = 0, wsum = 0;
    for (int dj = 0; dj < 2; dj++)
        for (int di = 0; di < 2; di++)
        {
            const int i = i0 + di, j = j0 + dj;
            const double w = (di ? fx : 1 - fx) * (dj ? fy : 1 - fy);
            if (i < 0 || j < 0 || i >= d->nx || j >= d->ny || w <= 0)
                continue;
            const double val = pixel(d, i, j);
            if (isnan(val))
                continue;
            sum += w * val;
            wsum += w;
        }
    return wsum > 0 ? sum / wsum : NAN;
}

static int32_t uf_find(int32_t *up, int32_t i)
{
    while (up[i] != i)
        i = up[i] = up[up[i]];
    return i;
}

/* Whether a vertex of polygon a lies inside polygon b. */
static int vertex_inside(const wm_lake_bands *li, size_t a, size_t b)
{
    const wm_scene *s = li->s;
    for (size_t e = s->poly_start[a]; e < s->poly_start[a + 1]; e++)
        if (wm_lake_bands_inside(li, b, s->edges[e].ax, s->edges[e].ay))
            return 1;
    return 0;
}

static int cmp_box_x0(const void *pa, const void *pb, void *ctx)
{
    const wm_box *box = ctx;
    const int64_t a = box[*(const int32_t *)pa].x0;
    const int64_t b = box[*(const int32_t *)pb].x0;
    return (a > b) - (a < b);
}

/* Bodies: overlapping polygons joined (sweep over the boxes in x). */
static void lake_bodies(const wm_lake_bands *li, WMDrape *d)
{
    const wm_scene *s = li->s;
    const size_t n = s->npolys;
    int32_t *up = CPLMalloc((n + 1) * sizeof *up);
    int32_t *ord = CPLMalloc((n + 1) * sizeof *ord);
    for (size_t i = 0; i < n; i++)
        up[i] = ord[i] = (int32_t)i;
    qsort_r(ord, n, sizeof *ord, cmp_box_x0, s->poly_box);
    for (size_t i = 0; i < n; i++)
    {
        const wm_box *a = &s->poly_box[ord[i]];
        for (size_t j = i + 1; j < n; j++)
        {
            const wm_box *b = &s->poly_box[ord[j]];
            if (b->x0 > a->x1)
                break;
            if (b->y0 > a->y1 || b->y1 < a->y0)
                continue;
            const int32_t ra = uf_find(up, ord[i]), rb = uf_find(up, ord[j]);
            if (ra != rb &&
                (vertex_inside(li, (size_t)ord[i], (size_t)ord[j]) ||
                 vertex_inside(li, (size_t)ord[j], (size_t)ord[i])))
                up[ra > rb ? ra : rb] = ra > rb ? rb : ra;
        }
    }
    /* bodies numbered in the order of their first polygon */
    d->nbodies = 0;
    for (size_t i = 0; i < n; i++)
        ord[i] = -1;
    for (size_t i = 0; i < n; i++)
    {
        const int32_t r = uf_find(up, (int32_t)i);
        if (ord[r] < 0)
            ord[r] = (int32_t)d->nbodies++;
        d->poly_body[i] = ord[r];
    }
    CPLFree(up);
    CPLFree(ord);
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef struct
{
    double *v;
    size_t n, cap;
} samples;

/* Samples the shore of polygon p every `step` metres into *out, leaving
 * out the points inside the other polygons of its body (mates[0 .. nmates),
 * p among them). */
static void shore_samples(const WMScene *s, const wm_lake_bands *li, dem_t *dem,
                          size_t p, const size_t *mates, size_t nmates,
                          double step, samples *out)
{
    const wm_scene *c = &s->core;
    for (size_t e = c->poly_start[p]; e < c->poly_start[p + 1]; e++)
    {
        const wm_lake_edge *g = &c->edges[e];
        const double len =
            hypot((double)(g->bx - g->ax), (double)(g->by - g->ay)) * s->unit;
        const int k = (int)ceil(len / step);
        for (int i = 0; i < (k < 1 ? 1 : k); i++)
        {
            const double t = (double)i / (k < 1 ? 1 : k);
            const double X = (double)g->ax + t * (double)(g->bx - g->ax);
            const double Y = (double)g->ay + t * (double)(g->by - g->ay);
            int other = 0;
            for (size_t q = 0; q < nmates && !other; q++)
                other =
                    mates[q] != p &&
                    wm_lake_bands_inside(li, mates[q], llround(X), llround(Y));
            if (other)
                continue;
            const double z = dem_at(dem, X * s->unit, Y * s->unit);
            if (!isfinite(z))
                continue;
            if (out->n == out->cap)
            {
                out->cap = out->cap ? 2 * out->cap : 1024;
                out->v = CPLRealloc(out->v, out->cap * sizeof *out->v);
            }
            out->v[out->n++] = z;
        }
    }
}

static int lake_levels(const WMScene *s, const wm_lake_bands *li, dem_t *dem,
                       WMDrape *d, double step)
{
    const wm_scene *c = &s->core;
    samples *per = CPLCalloc(d->nbodies + 1, sizeof *per);
    /* the polygons of each body, by body */
    size_t *start = CPLCalloc(d->nbodies + 1, sizeof *start);
    size_t *polys = CPLMalloc((c->npolys + 1) * sizeof *polys);
    for (size_t p = 0; p < c->npolys; p++)
        start[d->poly_body[p] + 1]++;
    size_t *cur = wm_csr_begin(start, d->nbodies);
    for (size_t p = 0; cur && p < c->npolys; p++)
        polys[cur[d->poly_body[p]]++] = p;
    for (size_t b = 0; cur && b < d->nbodies; b++)
        for (size_t k = start[b]; k < start[b + 1]; k++)
            shore_samples(s, li, dem, polys[k], polys + start[b],
                          start[b + 1] - start[b], step, &per[b]);
    free(cur);
    CPLFree(start);
    CPLFree(polys);
    int ok = TRUE;
    for (size_t b = 0; b < d->nbodies; b++)
    {
        samples *sm = &per[b];
        if (ok && sm->n == 0)
        {
            size_t p = 0;
            while (d->poly_body[p] != (int32_t)b)
                p++;
            const wm_lake_edge *g = &c->edges[c->poly_start[p]];
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: ELEVATION raster '%s' has no value along "
                     "the shore of the lake at (%.3f, %.3f).",
                     dem->path, (double)g->ax * s->unit,
                     (double)g->ay * s->unit);
            ok = FALSE;
        }
        if (ok)
        {
            qsort(sm->v, sm->n, sizeof *sm->v, cmp_double);
            const double rank = s->params.lake_percentile / 100 * (sm->n - 1);
            const size_t i = (size_t)floor(rank);
            const double f = rank - (double)i;
            d->body_level[b] = i + 1 < sm->n
                                   ? sm->v[i] + f * (sm->v[i + 1] - sm->v[i])
                                   : sm->v[i];
            d->body_spread[b] = sm->v[sm->n - 1] - sm->v[0];
        }
        CPLFree(sm->v);
    }
    CPLFree(per);
    return ok;
}

/* The river network: nodes (distinct segment ends) and directed edges. */
typedef struct
{
    int64_t *key; /* 2 per node: x, y (sorted) */
    size_t n;
    size_t *a, *b; /* per segment: its ends' nodes */
    double *level;
    uint8_t *pin;
    size_t *dstart, *down, *ustart, *upn; /* CSR down- and up-neighbours */
} network;

static int cmp_key(const void *pa, const void *pb)
{
    const int64_t *a = pa, *b = pb;
    if (a[0] != b[0])
        return (a[0] > b[0]) - (a[0] < b[0]);
    return (a[1] > b[1]) - (a[1] < b[1]);
}

static size_t node_of(const network *nw, int64_t x, int64_t y)
{
    size_t lo = 0, hi = nw->n;
    while (lo < hi)
    {
        const size_t mid = lo + (hi - lo) / 2;
        const int64_t *k = nw->key + 2 * mid;
        if (k[0] < x || (k[0] == x && k[1] < y))
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

static void network_nodes(const wm_scene *c, network *nw)
{
    nw->key = CPLMalloc((2 * c->nsegs + 1) * 2 * sizeof *nw->key);
    for (size_t i = 0; i < c->nsegs; i++)
    {
        const wm_river_seg *g = &c->segs[i];
        int64_t *k = nw->key + 4 * i;
        k[0] = g->ax, k[1] = g->ay, k[2] = g->bx, k[3] = g->by;
    }
    size_t m = 2 * c->nsegs;
    qsort(nw->key, m, 2 * sizeof *nw->key, cmp_key);
    nw->n = 0;
    for (size_t i = 0; i < m; i++)
        if (nw->n == 0 || cmp_key(nw->key + 2 * i, nw->key + 2 * (nw->n - 1)))
        {
            nw->key[2 * nw->n] = nw->key[2 * i];
            nw->key[2 * nw->n + 1] = nw->key[2 * i + 1];
            nw->n++;
        }
    nw->a = CPLMalloc((c->nsegs + 1) * sizeof *nw->a);
    nw->b = CPLMalloc((c->nsegs + 1) * sizeof *nw->b);
    for (size_t i = 0; i < c->nsegs; i++)
    {
        nw->a[i] = node_of(nw, c->segs[i].ax, c->segs[i].ay);
        nw->b[i] = node_of(nw, c->segs[i].bx, c->segs[i].by);
    }
}

/* Nodes without a value take their line's nearest valued vertex, then a
 * valued neighbour's across the network. FALSE (after a CPLError) when a
 * whole connected part has none. */
static int fill_gaps(const WMScene *s, network *nw, const char *path)
{
    double *lv = nw->level;
    for (size_t l = 0; l < s->nlines; l++)
    {
        const size_t s0 = s->line_start[l], s1 = s->line_start[l + 1];
        for (int pass = 0; pass < 2; pass++) /* forward, then backward */
            for (size_t k = 0; k < s1 - s0; k++)
            {
                const size_t i = pass ? s1 - 1 - k : s0 + k;
                const size_t from = pass ? nw->b[i] : nw->a[i];
                const size_t to = pass ? nw->a[i] : nw->b[i];
                if (isnan(lv[to]) && !isnan(lv[from]))
                    lv[to] = lv[from];
            }
    }
    /* then breadth first from the valued nodes over the network */
    const size_t n = nw->n, m = s->core.nsegs;
    size_t *nb_start = CPLCalloc(n + 1, sizeof(size_t));
    size_t *nb = CPLMalloc((2 * m + 1) * sizeof(size_t));
    size_t *queue = CPLMalloc((n + 1) * sizeof(size_t));
    for (size_t i = 0; i < m; i++)
    {
        nb_start[nw->a[i] + 1]++;
        nb_start[nw->b[i] + 1]++;
    }
    size_t *cur = wm_csr_begin(nb_start, n);
    for (size_t i = 0; cur && i < m; i++)
    {
        nb[cur[nw->a[i]]++] = nw->b[i];
        nb[cur[nw->b[i]]++] = nw->a[i];
    }
    size_t qh = 0, qt = 0;
    for (size_t i = 0; cur && i < n; i++)
        if (!isnan(lv[i]))
            queue[qt++] = i;
    while (qh < qt)
    {
        const size_t u = queue[qh++];
        for (size_t k = nb_start[u]; k < nb_start[u + 1]; k++)
            if (isnan(lv[nb[k]]))
            {
                lv[nb[k]] = lv[u];
                queue[qt++] = nb[k];
            }
    }
    free(cur);
    CPLFree(nb_start);
    CPLFree(nb);
    CPLFree(queue);
    for (size_t i = 0; i < nw->n; i++)
        if (isnan(lv[i]))
        {
            CPLError(CE_Failure, CPLE_AppDefined,
                     "WATERMESH: ELEVATION raster '%s' has no value under "
                     "the river at (%.3f, %.3f) nor anywhere along its "
                     "network.",
                     path, (double)nw->key[2 * i] * s->unit,
                     (double)nw->key[2 * i + 1] * s->unit);
            return FALSE;
        }
    return TRUE;
}

/* Directed edges up -> down, per segment, as CSR lists both ways. */
static void network_edges(const WMScene *s, network *nw, const uint8_t *rev)
{
    const size_t n = nw->n, m = s->core.nsegs;
    nw->dstart = CPLCalloc(n + 1, sizeof(size_t));
    nw->ustart = CPLCalloc(n + 1, sizeof(size_t));
    nw->down = CPLMalloc((m + 1) * sizeof(size_t));
    nw->upn = CPLMalloc((m + 1) * sizeof(size_t));
    for (size_t l = 0; l < s->nlines; l++)
        for (size_t i = s->line_start[l]; i < s->line_start[l + 1]; i++)
        {
            const size_t u = rev[l] ? nw->b[i] : nw->a[i];
            const size_t v = rev[l] ? nw->a[i] : nw->b[i];
            nw->dstart[u + 1]++;
            nw->ustart[v + 1]++;
        }
    size_t *dc = wm_csr_begin(nw->dstart, n);
    size_t *uc = wm_csr_begin(nw->ustart, n);
    for (size_t l = 0; l < s->nlines; l++)
        for (size_t i = s->line_start[l]; i < s->line_start[l + 1]; i++)
        {
            const size_t u = rev[l] ? nw->b[i] : nw->a[i];
            const size_t v = rev[l] ? nw->a[i] : nw->b[i];
            nw->down[dc[u]++] = v;
            nw->upn[uc[v]++] = u;
        }
    free(dc);
    free(uc);
}

/* A binary heap of (key, node), smallest key on top. */
typedef struct
{
    double *key;
    size_t *node;
    size_t n;
} heap;

static void heap_push(heap *h, double key, size_t node)
{
    size_t i = h->n++;
    while (i > 0 && h->key[(i - 1) / 2] > key)
    {
        h->key[i] = h->key[(i - 1) / 2];
        h->node[i] = h->node[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->key[i] = key;
    h->node[i] = node;
}

static void heap_pop(heap *h, double *key, size_t *node)
{
    *key = h->key[0];
    *node = h->node[0];
    const double k = h->key[--h->n];
    const size_t v = h->node[h->n];
    size_t i = 0;
    for (;;)
    {
        size_t c = 2 * i + 1;
        if (c >= h->n)
            break;
        if (c + 1 < h->n && h->key[c + 1] < h->key[c])
            c++;
        if (h->key[c] >= k)
            break;
        h->key[i] = h->key[c];
        h->node[i] = h->node[c];
        i = c;
    }
    h->key[i] = k;
    h->node[i] = v;
}

/* propagate() over any network, cycles too: a node not pinned takes a
 * neighbour u's level where lower (carve, down the flow) or higher (fill,
 * up the flow) than its own. Nodes are settled in order of level, lowest
 * first when carving, highest first when filling (as Dijkstra's
 * algorithm): a node's level moves at most once per neighbour settled
 * before it, so the cost is O(edges log nodes) whatever the network. */
static void propagate_heap(network *nw, const size_t *start, const size_t *next,
                           int fill)
{
    const size_t m = start[nw->n];
    heap h = {CPLMalloc((nw->n + m + 1) * sizeof(double)),
              CPLMalloc((nw->n + m + 1) * sizeof(size_t)), 0};
    const double sign = fill ? -1.0 : 1.0;
    for (size_t i = 0; i < nw->n; i++)
        heap_push(&h, sign * nw->level[i], i);
    while (h.n)
    {
        double key;
        size_t u;
        heap_pop(&h, &key, &u);
        if (key != sign * nw->level[u])
            continue; /* a stale entry: u moved since */
        for (size_t k = start[u]; k < start[u + 1]; k++)
        {
            const size_t v = next[k];
            const int move = fill ? nw->level[v] < nw->level[u]
                                  : nw->level[v] > nw->level[u];
            if (nw->pin[v] || !move)
                continue;
            nw->level[v] = nw->level[u];
            heap_push(&h, sign * nw->level[v], v);
        }
    }
    CPLFree(h.key);
    CPLFree(h.node);
}

/* One relaxation: v takes u's level where lower (carve) or higher (fill)
 * than its own, unless pinned. */
static void relax(network *nw, size_t u, size_t v, int fill)
{
    const int move =
        fill ? nw->level[v] < nw->level[u] : nw->level[v] > nw->level[u];
    if (!nw->pin[v] && move)
        nw->level[v] = nw->level[u];
}

/* Propagates over the CSR lists (start, next): a node not pinned takes a
 * neighbour's level where lower (carve, down the flow) or higher (fill,
 * up the flow) than its own. In topological order (Kahn) a network
 * without cycles is done in O(nodes + edges); braided rivers (cycles)
 * then go through the heap. */
static void propagate(network *nw, const size_t *start, const size_t *next,
                      int fill)
{
    const size_t n = nw->n;
    size_t *indeg = CPLCalloc(n + 1, sizeof *indeg);
    size_t *queue = CPLMalloc((n + 1) * sizeof *queue);
    for (size_t k = 0; k < start[n]; k++)
        indeg[next[k]]++;
    size_t qh = 0, qt = 0;
    for (size_t i = 0; i < n; i++)
        if (!indeg[i])
            queue[qt++] = i;
    while (qh < qt)
    {
        const size_t u = queue[qh++];
        for (size_t k = start[u]; k < start[u + 1]; k++)
        {
            relax(nw, u, next[k], fill);
            if (--indeg[next[k]] == 0)
                queue[qt++] = next[k];
        }
    }
    CPLFree(indeg);
    CPLFree(queue);
    if (qt < n) /* cycles */
        propagate_heap(nw, start, next, fill);
}

static void network_free(network *nw)
{
    CPLFree(nw->key);
    CPLFree(nw->a);
    CPLFree(nw->b);
    CPLFree(nw->level);
    CPLFree(nw->pin);
    CPLFree(nw->dstart);
    CPLFree(nw->down);
    CPLFree(nw->ustart);
    CPLFree(nw->upn);
}

/* Parameter along [a, b] of the crossing of edge [c, e], or -1. */
static double cross_t(const wm_river_seg *g, const wm_lake_edge *e)
{
    const double rx = (double)(g->bx - g->ax), ry = (double)(g->by - g->ay);
    const double sx = (double)(e->bx - e->ax), sy = (double)(e->by - e->ay);
    const double den = rx * sy - ry * sx;
    if (den == 0)
        return -1;
    const double qx = (double)(e->ax - g->ax), qy = (double)(e->ay - g->ay);
    const double t = (qx * sy - qy * sx) / den, u = (qx * ry - qy * rx) / den;
    return t >= 0 && t <= 1 && u >= 0 && u <= 1 ? t : -1;
}

/* The crossing of segment g with polygon p's edges nearest its end
 * outside (a_in: its a end is inside): *best updated. */
static void nearest_crossing(const wm_lake_bands *li, size_t p,
                             const wm_river_seg *g, int a_in, double *best)
{
    const size_t b0 = wm_lake_bands_of(li, p, g->ay < g->by ? g->ay : g->by);
    const size_t b1 = wm_lake_bands_of(li, p, g->ay < g->by ? g->by : g->ay);
    for (size_t k = li->start[b0]; k < li->start[b1 + 1]; k++)
    {
        const double t = cross_t(g, &li->s->edges[li->edge[k]]);
        if (t >= 0 && (*best < 0 || (a_in ? t > *best : t < *best)))
            *best = t;
    }
}

/* Segment i has one end in a lake (a_in: its a end) and the other out:
 * its knee is the shore crossing nearest the end outside, at the lake's
 * level, so the river meets the lake there at the lake's level. `in` is
 * the polygon holding the end inside, or SIZE_MAX when several do. */
static void shore_knee(const wm_lake_bands *li, size_t in,
                       const wm_river_seg *g, int a_in, WMDrape *d, size_t i)
{
    const wm_scene *c = li->s;
    const int64_t X = a_in ? g->ax : g->bx, Y = a_in ? g->ay : g->by;
    double best = -1;
    if (in != SIZE_MAX)
        nearest_crossing(li, in, g, a_in, &best);
    else
        for (size_t p = 0; p < c->npolys; p++)
            if (wm_lake_bands_inside(li, p, X, Y))
                nearest_crossing(li, p, g, a_in, &best);
    if (best < 0)
        return;
    d->tk[i] = best;
    d->zk[i] = a_in ? d->za[i] : d->zb[i];
}

static int river_levels(const WMScene *s, const wm_lake_bands *li, dem_t *dem,
                        WMDrape *d)
{
    const wm_scene *c = &s->core;
    network nw;
    memset(&nw, 0, sizeof nw);
    network_nodes(c, &nw);
    nw.level = CPLMalloc((nw.n + 1) * sizeof *nw.level);
    nw.pin = CPLCalloc(nw.n + 1, 1);
    /* per pinned node: the polygon holding it, SIZE_MAX when several do */
    size_t *pin_poly = CPLMalloc((nw.n + 1) * sizeof *pin_poly);
    for (size_t i = 0; i < nw.n; i++)
        nw.level[i] = dem_at(dem, (double)nw.key[2 * i] * s->unit,
                             (double)nw.key[2 * i + 1] * s->unit);
    int ok = fill_gaps(s, &nw, dem->path);
    uint8_t *rev = CPLCalloc(s->nlines + 1, 1);
    for (size_t l = 0; ok && l < s->nlines; l++)
        rev[l] = !s->params.flow_line &&
                 nw.level[nw.a[s->line_start[l]]] <
                     nw.level[nw.b[s->line_start[l + 1] - 1]];
    for (size_t p = 0; ok && p < c->npolys; p++) /* nodes in lakes */
        for (size_t i = node_of(&nw, c->poly_box[p].x0, INT64_MIN);
             i < nw.n && nw.key[2 * i] <= c->poly_box[p].x1; i++)
            if (wm_lake_bands_inside(li, p, nw.key[2 * i], nw.key[2 * i + 1]))
            {
                const double z = d->body_level[d->poly_body[p]];
                if (!nw.pin[i] || z < nw.level[i])
                    nw.level[i] = z;
                pin_poly[i] = nw.pin[i] ? SIZE_MAX : p;
                nw.pin[i] = 1;
            }
    if (ok)
    {
        network_edges(s, &nw, rev);
        propagate(&nw, nw.dstart, nw.down, 0);
        propagate(&nw, nw.ustart, nw.upn, 1);
        size_t rising = 0;
        for (size_t i = 0; i < c->nsegs; i++)
        {
            d->za[i] = nw.level[nw.a[i]];
            d->zb[i] = nw.level[nw.b[i]];
            d->tk[i] = 1;
            d->zk[i] = d->zb[i];
            if (nw.pin[nw.a[i]] != nw.pin[nw.b[i]])
                shore_knee(li, pin_poly[nw.pin[nw.a[i]] ? nw.a[i] : nw.b[i]],
                           &c->segs[i], nw.pin[nw.a[i]], d, i);
        }
        for (size_t u = 0; u < nw.n; u++)
            for (size_t k = nw.dstart[u]; k < nw.dstart[u + 1]; k++)
                rising += nw.level[nw.down[k]] > nw.level[u];
        if (rising)
            CPLError(CE_Warning, CPLE_AppDefined,
                     "WATERMESH: ELEVATION: %lu river segment(s) rise "
                     "between two lakes whose levels are out of order.",
                     (unsigned long)rising);
    }
    CPLFree(rev);
    CPLFree(pin_poly);
    network_free(&nw);
    return ok;
}

void WMDrapeFree(WMDrape *d)
{
    if (!d)
        return;
    CPLFree(d->za);
    CPLFree(d->zb);
    CPLFree(d->tk);
    CPLFree(d->zk);
    CPLFree(d->poly_body);
    CPLFree(d->body_level);
    CPLFree(d->body_spread);
    CPLFree(d);
}

int WMDrapePrepare(WMScene *s)
{
    if (!s->params.elevation)
        return TRUE;
    const wm_scene *c = &s->core;
    dem_t dem;
    double step;
    WMDrape *d = CPLCalloc(1, sizeof *d);
    d->za = CPLCalloc(c->nsegs + 1, sizeof *d->za);
    d->zb = CPLCalloc(c->nsegs + 1, sizeof *d->zb);
    d->tk = CPLCalloc(c->nsegs + 1, sizeof *d->tk);
    d->zk = CPLCalloc(c->nsegs + 1, sizeof *d->zk);
    d->poly_body = CPLCalloc(c->npolys + 1, sizeof *d->poly_body);
    d->body_level = CPLCalloc(c->npolys + 1, sizeof *d->body_level);
    d->body_spread = CPLCalloc(c->npolys + 1, sizeof *d->body_spread);
    const double t0 = wm_now();
    int ok = dem_open(&dem, s, &step);
    if (ok)
    {
        wm_lake_bands li;
        ok = wm_lake_bands_build(&li, c, NULL, 0) == WM_OK;
        if (!ok)
            CPLError(CE_Failure, CPLE_OutOfMemory,
                     "WATERMESH: ELEVATION: out of memory indexing the lakes.");
        if (ok)
        {
            lake_bodies(&li, d);
            ok = lake_levels(s, &li, &dem, d, step) &&
                 river_levels(s, &li, &dem, d);
        }
        wm_lake_bands_free(&li);
    }
    dem_close(&dem);
    if (!ok)
    {
        WMDrapeFree(d);
        return FALSE;
    }
    d->core.za = d->za;
    d->core.zb = d->zb;
    d->core.tk = d->tk;
    d->core.zk = d->zk;
    d->core.poly_body = d->poly_body;
    d->core.body_level = d->body_level;
    s->drape = d;
    CPLDebug("WATERMESH",
             "ELEVATION '%s': %lu lake bod(ies), %lu river segments, "
             "levels in %.3f s",
             s->params.elevation, (unsigned long)d->nbodies,
             (unsigned long)c->nsegs, wm_now() - t0);
    return TRUE;
}
