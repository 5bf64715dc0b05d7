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
                               for MIXED tiles, NULL otherwise (owned) */
        size_t mixed;     /**< number of MIXED tiles */
        uint64_t pairs;   /**< sample-segment pairs evaluated (statistics) */
    } wm_field;

    /** Computes the field of a window; `f` is overwritten (free it with
     *  wm_field_free()). w, h >= 1. */
    wm_status wm_field_compute(const wm_scene *s, int64_t gx0, int64_t gy0,
                               int32_t w, int32_t h, wm_field *f,
                               const wm_ctx *ctx);

    /** Value of window sample (c, r), 0 <= c < w, 0 <= r < h. */
    float wm_field_at(const wm_field *f, int32_t c, int32_t r);

    /** Frees what f owns; f may be NULL. */
    void wm_field_free(wm_field *f);

#ifdef __cplusplus
}
#endif

#endif /* WM_FIELD_H */
