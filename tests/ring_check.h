/* ring_check.h - brute-force checks of the wm_rings invariants, shared by
 * the core tests. */
#ifndef WM_RING_CHECK_H
#define WM_RING_CHECK_H

#include "lattice.h"

#include <string.h>

/* Whether a and b are the same rings, point for point. */
static inline int rings_equal(const wm_rings *a, const wm_rings *b)
{
    if (a->nrings != b->nrings || a->npts != b->npts)
        return 0;
    if (a->nrings &&
        memcmp(a->start, b->start, (a->nrings + 1) * sizeof *a->start))
        return 0;
    return a->npts == 0 || !memcmp(a->pts, b->pts, a->npts * sizeof *a->pts);
}

/* Number of pairs of ring edges that meet, other than consecutive edges of
 * one ring at their shared vertex: 0 for simple, disjoint rings. O(n^2). */
static inline int ring_meetings(const wm_rings *r)
{
    int bad = 0;
    for (size_t i = 0; i < r->nrings; i++)
        for (size_t j = i; j < r->nrings; j++)
        {
            const size_t ni = wm_rings_len(r, i), nj = wm_rings_len(r, j);
            const wm_pt *p = r->pts + r->start[i], *q = r->pts + r->start[j];
            for (size_t a = 0; a < ni; a++)
                for (size_t b = (i == j ? a + 1 : 0); b < nj; b++)
                {
                    if (i == j && (b == a + 1 || (a == 0 && b == ni - 1)))
                        continue;
                    bad += wm_segments_meet(p[a], p[(a + 1) % ni], q[b],
                                            q[(b + 1) % nj]);
                }
        }
    return bad;
}

#endif
