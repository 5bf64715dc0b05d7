/*
 * field.h - the signed distance field of a rectangular window of samples.
 */
#ifndef WM_FIELD_H
#define WM_FIELD_H

#include "scene.h"

#ifdef __cplusplus
extern "C"
{
#endif

/** Side of a tile in cells; a tile stores (WM_TILE + 1)^2 samples. */
#define WM_TILE 32

    typedef enum
    {
        WM_TILE_LAND = 0,  /**< every sample is +band */
        WM_TILE_WATER = 1, /**< every sample is -band */
        WM_TILE_MIXED = 2  /**< values stored */
    } wm_tile_kind;

    /**
     * The field over samples gx0 .. gx0+w-1, gy0 .. gy0+h-1 (global indices).
     * Values are in pixels, negative in water, clamped to [-band, +band]. Only
     * tiles with a river segment or lake edge within reach store values
     * (invariant 6); the others are uniform. A sample's value is a pure
     * function of its global index and the scene (invariant 2): it does not
     * depend on the window, the tile or the thread that computed it.
     */
    typedef struct
    {
        int64_t gx0, gy0;
        int32_t w, h;     /**< samples */
        int32_t ntx, nty; /**< tiles; tile (tx,ty) covers samples
                               tx*WM_TILE .. min(tx*WM_TILE+WM_TILE, w-1) */
        float band;       /**< clamp, pixels */
        uint8_t *kind;    /**< ntx*nty wm_tile_kind (owned) */
        float **val;      /**< ntx*nty pointers, (WM_TILE+1)^2 row-major values
                               for MIXED tiles, NULL otherwise (owned; the
                               values live in `slab`) */
        float **slab;     /**< nslab blocks holding the tiles' values (owned) */
        size_t nslab;
        size_t mixed;         /**< number of MIXED tiles */
        uint32_t *mixed_tile; /**< the MIXED tiles, ascending (owned; see
                                   wm_field_index) */
        uint64_t *bits;       /**< per MIXED tile, in mixed_tile's order, 2 *
                                   WM_TS1 words: for each row j of its samples
                                   the water bits (v <= 0) at [2j] and the near
                                   bits (|v| < 1 pixel) at [2j + 1], bit i for
                                   sample i: what marching squares and the
                                   sub-pixel screen test first (owned) */
        uint64_t samples;     /**< samples evaluated (statistics): on the C path
                                   only the narrow band's, on a device every
                                   sample of a mixed tile */
        uint64_t pairs; /**< sample-item distances evaluated (statistics) */
    } wm_field;

    /** Samples per tile side. */
#define WM_TS1 (WM_TILE + 1)

    /**
     * Tiles whose samples need evaluating, as handed to a field device.
     *
     * wm_field_compute decides which tiles are uniform (nothing in reach, or
     * inside a polygon with no edge in reach) and gathers the others in
     * batches of at most WM_FIELD_BATCH tiles. For every batch tile it lists
     * the river segments in reach and, per lake polygon with edges in reach,
     * those edges (a "group") with the polygon's even-odd parity at each
     * tile sample, computed exactly on the host. A device turns that into
     * values: val[k * WM_TS1^2 + j * WM_TS1 + i] is tile k's sample (i, j),
     *   min( band, min_rivers |p - seg| - r, min_groups (+/-) min_edges
     *        |p - edge| ) clamped below at -band, in pixels,
     * the sign of a group being - where its parity bit is set. Every tile is
     * a full WM_TS1 x WM_TS1 square even where it overhangs the window
     * (those samples are never read).
     */
    typedef struct
    {
        const wm_scene *s;
        size_t ntiles;
        const int64_t *org;       /**< 2 * ntiles: lattice (X, Y) of each
                                       tile's sample (0, 0) */
        const size_t *seg_start;  /**< ntiles + 1 offsets into seg */
        const uint32_t *seg;      /**< indices into s->segs */
        const size_t *grp_start;  /**< ntiles + 1 offsets into the groups */
        size_t ngroups;           /**< groups of all tiles */
        const size_t *edge_start; /**< ngroups + 1 offsets into edge */
        const uint32_t *edge;     /**< indices into s->edges */
        const uint64_t *mask;     /**< ngroups * WM_TS1 words: bit i of word
                                       g * WM_TS1 + j is the group polygon's
                                       parity at tile sample (i, j) */
        float *val;               /**< out: ntiles * WM_TS1 * WM_TS1 */
        uint64_t *samples;        /**< out (statistics): increased by the
                                       samples the device computed */
        uint64_t *pairs;          /**< out (statistics): increased by the
                                       sample-item distances it computed */
    } wm_field_batch;

/** Most tiles in one batch (bounds the batch's memory to ~4.5 MB). */
#define WM_FIELD_BATCH 1024

    /** Evaluates a batch: fills b->val. Returns WM_OK or an error status
     *  (reported through ctx). */
    typedef wm_status (*wm_field_eval_fn)(void *user, const wm_field_batch *b,
                                          const wm_ctx *ctx);

    /** Where field values are computed: the C path or an OpenCL device. */
    typedef struct
    {
        wm_field_eval_fn eval;
        void *user;
    } wm_field_device;

    /** The C path's evaluator (double arithmetic; `user` is unused). */
    wm_status wm_field_eval_c(void *user, const wm_field_batch *b,
                              const wm_ctx *ctx);

    /** Computes the field of a window; `f` is overwritten (free it with
     *  wm_field_free()). w, h >= 1. `dev` evaluates the tiles; NULL means
     *  the C path. */
    wm_status wm_field_compute(const wm_scene *s, int64_t gx0, int64_t gy0,
                               int32_t w, int32_t h, const wm_field_device *dev,
                               wm_field *f, const wm_ctx *ctx);

    /** Value of window sample (c, r), 0 <= c < w, 0 <= r < h. */
    float wm_field_at(const wm_field *f, int32_t c, int32_t r);

    /** The values of the four samples of cell (c, r) (0 <= c < w - 1,
     *  0 <= r < h - 1) counter-clockwise from (c, r): (c, r), (c + 1, r),
     *  (c + 1, r + 1), (c, r + 1), as wm_field_at() gives them, with one
     *  tile lookup (a cell lies in one tile). */
    void wm_field_cell(const wm_field *f, int32_t c, int32_t r, float v[4]);

    /** Lists f's MIXED tiles and their rows' bits (mixed_tile, bits) from
     *  `kind` and `val`: wm_field_compute calls it; a field made by hand
     *  calls it once its values are set. Returns WM_ERR_NOMEM or WM_OK. */
    wm_status wm_field_index(wm_field *f);

    /** A key of cell (c, r) of f, tile by tile (tile index << 32 | (r %
     *  WM_TILE) * WM_TILE + c % WM_TILE): the cells of a tile are one run of
     *  sorted keys. */
    static inline uint64_t wm_field_cell_key(const wm_field *f, int32_t c,
                                             int32_t r)
    {
        const uint64_t t = (uint64_t)(r / WM_TILE) * (uint64_t)f->ntx +
                           (uint64_t)(c / WM_TILE);
        return t << 32 | (uint64_t)((r % WM_TILE) * WM_TILE + c % WM_TILE);
    }

    /** The bits (wm_field.bits) of the k-th MIXED tile. */
    static inline const uint64_t *wm_field_bits(const wm_field *f, size_t k)
    {
        return f->bits + k * 2 * WM_TS1;
    }

    /** Asks the cache for what wm_field_at(f, c, r) will read: a caller
     *  reading scattered samples issues it some samples ahead, so that the
     *  memory latencies overlap. */
    void wm_field_prefetch(const wm_field *f, int32_t c, int32_t r);

    /** Asks the cache for the samples of the k-th MIXED tile that lie in
     *  or beside a row's span of near ones (|v| < 1), which the screening of
     *  hidden crossings and the contour read: a caller walking the tiles
     *  issues it a tile ahead, so that the tile's misses overlap the work
     *  on the one before. k may be f->mixed (nothing is asked). */
    void wm_field_prefetch_tile(const wm_field *f, size_t k);

    /** Frees what f owns; f may be NULL. */
    void wm_field_free(wm_field *f);

#ifdef __cplusplus
}
#endif

#endif /* WM_FIELD_H */
