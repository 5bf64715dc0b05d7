/* field_check.h - fields for the tests: bit-identity checks of fields
 * computed over different windows (DESIGN invariant 2), and fields made by
 * hand. */
#ifndef WM_FIELD_CHECK_H
#define WM_FIELD_CHECK_H

#include "field.h"

#include <stdlib.h>
#include <string.h>

static inline int fc_same_bits(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Rows of a's column n that differ in bits from b's column 0 (a and b are
 * horizontally adjacent blocks of n cells sharing that column). */
static inline int fc_shared_column_diff(const wm_field *a, const wm_field *b,
                                        int n)
{
    int diff = 0;
    for (int r = 0; r < a->h; r++)
        diff += !fc_same_bits(wm_field_at(a, n, r), wm_field_at(b, 0, r));
    return diff;
}

/* Samples of window w, whose sample (0, 0) is (gx0, gy0) of the blocks'
 * grid, differing in bits from the blocks a (columns 0..n) and b
 * (columns n..2n). */
static inline int fc_window_diff(const wm_field *w, int gx0, int gy0,
                                 const wm_field *a, const wm_field *b, int n)
{
    int diff = 0;
    for (int r = 0; r < w->h; r++)
        for (int c = 0; c < w->w; c++)
        {
            const int gc = gx0 + c, gr = gy0 + r;
            const float ref =
                gc <= n ? wm_field_at(a, gc, gr) : wm_field_at(b, gc - n, gr);
            diff += !fc_same_bits(wm_field_at(w, c, r), ref);
        }
    return diff;
}

/* A w x h field from a dense row-major array v (row 0 at the bottom), all
 * tiles mixed, clamp band `band`: fields made by hand for the tests of the
 * stages after the field. Free with wm_field_free(). */
static inline void fc_make_field(wm_field *f, int32_t w, int32_t h,
                                 const float *v, float band)
{
    memset(f, 0, sizeof *f);
    f->w = w;
    f->h = h;
    f->band = band;
    f->ntx = w > 1 ? (w - 2) / WM_TILE + 1 : 1;
    f->nty = h > 1 ? (h - 2) / WM_TILE + 1 : 1;
    const size_t nt = (size_t)f->ntx * (size_t)f->nty;
    f->kind = calloc(nt, 1);
    f->val = calloc(nt, sizeof *f->val);
    f->slab = malloc(sizeof *f->slab);
    f->slab[0] = calloc(nt * (WM_TILE + 1) * (WM_TILE + 1), sizeof(float));
    f->nslab = 1;
    for (int32_t ty = 0; ty < f->nty; ty++)
        for (int32_t tx = 0; tx < f->ntx; tx++)
        {
            const size_t t = (size_t)ty * (size_t)f->ntx + (size_t)tx;
            float *o = f->slab[0] + t * (WM_TILE + 1) * (WM_TILE + 1);
            for (int32_t j = 0; j <= WM_TILE; j++)
                for (int32_t i = 0; i <= WM_TILE; i++)
                {
                    const int32_t c = tx * WM_TILE + i, r = ty * WM_TILE + j;
                    if (c < w && r < h)
                        o[j * (WM_TILE + 1) + i] = v[r * w + c];
                }
            f->val[t] = o;
            f->kind[t] = WM_TILE_MIXED;
        }
    wm_field_index(f);
}

#endif /* WM_FIELD_CHECK_H */
