/* test_merge.c - vertex merging by distance (MERGE_DISTANCE): short edges
 * collapse, block-border vertices stay, rings stay valid, deterministic. */
#include "contour.h"
#include "field.h"
#include "holes.h"
#include "lattice.h"
#include "merge.h"
#include "ring_check.h"
#include "scene_util.h"
#include "tap.h"

#include <stdlib.h>
#include <string.h>

static void ring(wm_rings *r, const int *xy, int n)
{
    for (int i = 0; i < n; i++)
        wm_rings_push(r, (wm_pt){xy[2 * i], xy[2 * i + 1]});
    wm_rings_close(r);
}

static int on_square(wm_pt p, int32_t size)
{
    return p.x == 0 || p.y == 0 || p.x == size || p.y == size;
}

static size_t border_count(const wm_rings *r, int32_t size)
{
    size_t n = 0;
    for (size_t i = 0; i < r->npts; i++)
        n += on_square(r->pts[i], size);
    return n;
}

/* Every input ring keeps its orientation, its border vertices (in order)
 * and >= 3 vertices; the output's vertices are a subset, in order. */
static int check(const wm_rings *in, const wm_rings *out, int32_t size)
{
    int bad = in->nrings != out->nrings;
    for (size_t i = 0; !bad && i < in->nrings; i++)
    {
        const wm_pt *p = in->pts + in->start[i], *q = out->pts + out->start[i];
        const size_t n = wm_rings_len(in, i), m = wm_rings_len(out, i);
        bad += m < 3;
        bad += (wm_ring_area2(p, n) > 0) != (wm_ring_area2(q, m) > 0);
        size_t k = 0;
        for (size_t j = 0; j < n && k <= m; j++)
        {
            if (k < m && wm_pt_eq(p[j], q[k]))
                k++;
            else
                bad += on_square(p[j], size); /* a border vertex lost */
        }
        bad += k != m; /* not a subsequence */
    }
    return bad + ring_meetings(out);
}

int main(void)
{
    wm_rings r, c;
    memset(&r, 0, sizeof r);
    memset(&c, 0, sizeof c);
    const int32_t S = 64 * WM_Q;

    /* a square with two close vertices near one corner */
    {
        const int sq[] = {2560, 2560, 5120, 2560, 5130,
                          2570, 5120, 5120, 2560, 5120};
        ring(&r, sq, 5);
        size_t n = 0;
        TAP_EQ(wm_merge_rings(&r, S, 64, &n, NULL), WM_OK, "merge a square");
        TAP_EQ(n, 1, "one vertex merged");
        TAP_EQ(r.npts, 4, "four left");
        TAP_OK(ring_meetings(&r) == 0, "still simple");
        wm_rings_clear(&r);
    }
    /* the same on the block border: nothing may move */
    {
        const int sq[] = {0, 0, S, 0, S, 10, S, S, 0, S};
        ring(&r, sq, 5);
        size_t n = 0;
        wm_merge_rings(&r, S, 64, &n, NULL);
        TAP_EQ(n, 0, "border vertices are never merged");
        wm_rings_clear(&r);
    }
    /* a short edge whose collapse would cut off a triangle holding a hole:
     * refused; without the hole it happens */
    {
        /* (3000, 0) is on the block border, so only (3000, 40) may go */
        const int a[] = {1000, 0, 3000, 0, 3000, 40, 1000, 1000};
        const int b[] = {2830, 90, 2850, 100, 2850, 90};
        ring(&r, a, 4);
        ring(&r, b, 3);
        TAP_EQ(ring_meetings(&r), 0,
               "input: a ring with a hole near a "
               "short edge");
        size_t n = 0;
        wm_merge_rings(&r, S, 64, &n, NULL);
        TAP_OK(n == 0 && r.npts == 7,
               "the merge that would cut the hole off is refused (%zu merged)",
               n);
        wm_rings_clear(&r);
        ring(&r, a, 4);
        wm_merge_rings(&r, S, 64, &n, NULL);
        TAP_OK(n == 1 && r.npts == 3, "without the hole it merges");
        wm_rings_clear(&r);
    }
    /* a triangle never loses a vertex, nor a quad its area */
    {
        const int t[] = {100, 100, 140, 100, 100, 140};
        ring(&r, t, 3);
        size_t n = 0;
        wm_merge_rings(&r, S, 1000, &n, NULL);
        TAP_OK(n == 0 && r.npts == 3, "a triangle keeps 3 vertices");
        wm_rings_clear(&r);
    }

    /* real rings: random scenes, contour rings, merge distances from a
     * quarter pixel to four pixels */
    {
        int all = 1;
        size_t before = 0, after = 0, cases = 0;
        for (int t = 0; t < 12; t++)
        {
            wm_scene s;
            su_init(&s, 96);
            srand(100 + t);
            for (int i = 0; i < 10; i++)
            {
                double xy[6];
                for (int j = 0; j < 6; j++)
                    xy[j] = -10 + 116 * (double)rand() / RAND_MAX;
                su_river(&s, xy, 3, 0.4 + 3 * (double)rand() / RAND_MAX);
            }
            const double lake[] = {20, 20, 60, 25, 70, 70, 30, 60};
            const int cnt[] = {4};
            su_lake(&s, lake, cnt, 1);
            su_finish(&s);
            wm_field f;
            if (wm_field_compute(&s, 0, 0, 97, 97, NULL, &f, NULL) != WM_OK ||
                wm_contour_extract(&f, &r, NULL) != WM_OK)
                all = 0;
            wm_field_free(&f);
            const int32_t size = 96 * WM_Q;
            for (int d = 0; d < 4; d++)
            {
                const double dist = 64.0 * (1 << d); /* 1/4 .. 2 px */
                wm_rings_clear(&c);
                for (size_t i = 0; i < r.nrings; i++)
                {
                    for (size_t k = r.start[i]; k < r.start[i + 1]; k++)
                        wm_rings_push(&c, r.pts[k]);
                    wm_rings_close(&c);
                }
                const size_t nb = border_count(&r, size);
                if (wm_merge_rings(&c, size, dist, NULL, NULL) != WM_OK ||
                    check(&r, &c, size) || border_count(&c, size) != nb)
                {
                    printf("#   scene %d dist %g failed\n", t, dist);
                    all = 0;
                }
                before += r.npts;
                after += c.npts;
                cases++;
            }
            wm_scene_free(&s);
        }
        TAP_OK(all,
               "%zu cases: rings valid, orientations, border vertices "
               "and order kept",
               cases);
        TAP_OK(after < before, "vertices %zu -> %zu", before, after);
    }
    /* determinism */
    {
        wm_rings a2, b2;
        memset(&a2, 0, sizeof a2);
        memset(&b2, 0, sizeof b2);
        for (int k = 0; k < 2; k++)
        {
            wm_rings *o = k ? &b2 : &a2;
            for (size_t i = 0; i < r.nrings; i++)
            {
                for (size_t j = r.start[i]; j < r.start[i + 1]; j++)
                    wm_rings_push(o, r.pts[j]);
                wm_rings_close(o);
            }
            wm_merge_rings(o, 96 * WM_Q, 200, NULL, NULL);
        }
        TAP_OK(a2.npts == b2.npts &&
                   memcmp(a2.pts, b2.pts, a2.npts * sizeof *a2.pts) == 0,
               "deterministic");
        wm_rings_free(&a2);
        wm_rings_free(&b2);
    }
    wm_rings_free(&r);
    wm_rings_free(&c);
    return TAP_DONE();
}
