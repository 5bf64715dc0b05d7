/* field_check.h - bit-identity checks of fields computed over different
 * windows (DESIGN invariant 2), shared by the field tests of both paths. */
#ifndef WM_FIELD_CHECK_H
#define WM_FIELD_CHECK_H

#include "field.h"

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

#endif /* WM_FIELD_CHECK_H */
