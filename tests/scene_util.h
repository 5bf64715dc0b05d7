/* scene_util.h - building small wm_scene values by hand for core tests. */
#ifndef WM_SCENE_UTIL_H
#define WM_SCENE_UTIL_H

#include "scene.h"

#include <stdlib.h>
#include <string.h>

/* Adds a river polyline given in pixels (x0,y0,x1,y1,...), radius in px. */
static inline void su_river(wm_scene *s, const double *xy, int npts, double r)
{
    s->segs = realloc(s->segs, (s->nsegs + (size_t)npts) * sizeof *s->segs);
    for (int i = 0; i + 1 < npts; i++)
    {
        wm_river_seg *g = &s->segs[s->nsegs++];
        g->ax = (int64_t)(xy[2 * i] * WM_Q);
        g->ay = (int64_t)(xy[2 * i + 1] * WM_Q);
        g->bx = (int64_t)(xy[2 * i + 2] * WM_Q);
        g->by = (int64_t)(xy[2 * i + 3] * WM_Q);
        g->r = r * WM_Q;
    }
}

/* Adds a lake polygon made of nrings rings (pixels), ring k having
 * counts[k] points, all concatenated in xy. */
static inline void su_lake(wm_scene *s, const double *xy, const int *counts,
                           int nrings)
{
    size_t total = 0;
    for (int k = 0; k < nrings; k++)
        total += (size_t)counts[k];
    s->edges = realloc(s->edges, (s->nedges + total) * sizeof *s->edges);
    s->poly_start =
        realloc(s->poly_start, (s->npolys + 2) * sizeof *s->poly_start);
    if (s->npolys == 0)
        s->poly_start[0] = 0;
    size_t off = 0;
    for (int k = 0; k < nrings; k++)
    {
        for (int i = 0; i < counts[k]; i++)
        {
            const int j = (i + 1) % counts[k];
            wm_lake_edge *e = &s->edges[s->nedges++];
            e->ax = (int64_t)(xy[2 * (off + (size_t)i)] * WM_Q);
            e->ay = (int64_t)(xy[2 * (off + (size_t)i) + 1] * WM_Q);
            e->bx = (int64_t)(xy[2 * (off + (size_t)j)] * WM_Q);
            e->by = (int64_t)(xy[2 * (off + (size_t)j) + 1] * WM_Q);
        }
        off += (size_t)counts[k];
    }
    s->poly_start[++s->npolys] = s->nedges;
}

static inline void su_init(wm_scene *s, int32_t n)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    s->band = 2;
}

static inline void su_finish(wm_scene *s)
{
    if (!s->poly_start)
        s->poly_start = calloc(1, sizeof *s->poly_start);
    wm_scene_index(s, NULL);
}

#endif
