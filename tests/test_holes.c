/*
 * test_holes.c - ring nesting (wm_holes_nesting) against exact answers and
 * against a brute-force reference (wm_point_in_ring + smallest area).
 */
#include "holes.h"
#include "lattice.h"
#include "tap.h"

#include <math.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

static uint64_t lcg_state = 12345;

static uint32_t lcg(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (uint32_t)(lcg_state >> 33);
}

static int rnd(int lo, int hi) /* inclusive */
{
    return lo + (int)(lcg() % (uint32_t)(hi - lo + 1));
}

static void push(wm_rings *r, int x, int y)
{
    wm_pt p;
    p.x = x;
    p.y = y;
    if (wm_rings_push(r, p) != WM_OK)
        abort();
}

static void close_ring(wm_rings *r)
{
    if (wm_rings_close(r) != WM_OK)
        abort();
}

/* Axis-aligned rectangle; ccw selects the orientation; `extra` adds
 * collinear vertices on the edges (k per edge); `rot` rotates the start. */
static void rect(wm_rings *r, int x0, int y0, int x1, int y1, int ccw,
                 int extra, int rot)
{
    wm_pt v[64];
    int n = 0;
    const int cx[4] = {x0, x1, x1, x0}, cy[4] = {y0, y0, y1, y1};
    for (int c = 0; c < 4; c++)
    {
        const int nx = cx[(c + 1) % 4], ny = cy[(c + 1) % 4];
        v[n].x = cx[c];
        v[n].y = cy[c];
        n++;
        for (int k = 1; k <= extra; k++)
        {
            const int mx = cx[c] + (nx - cx[c]) * k / (extra + 1);
            const int my = cy[c] + (ny - cy[c]) * k / (extra + 1);
            if ((mx != v[n - 1].x || my != v[n - 1].y) &&
                (mx != nx || my != ny))
            {
                v[n].x = mx;
                v[n].y = my;
                n++;
            }
        }
    }
    for (int i = 0; i < n; i++)
    {
        const int j = ccw ? (i + rot) % n : (n - 1 - (i + rot) % n);
        push(r, v[j].x, v[j].y);
    }
    close_ring(r);
}

static void diamond(wm_rings *r, int cx, int cy, int rad, int ccw)
{
    if (ccw)
    {
        push(r, cx, cy - rad);
        push(r, cx + rad, cy);
        push(r, cx, cy + rad);
        push(r, cx - rad, cy);
    }
    else
    {
        push(r, cx, cy - rad);
        push(r, cx - rad, cy);
        push(r, cx, cy + rad);
        push(r, cx + rad, cy);
    }
    close_ring(r);
}

/* Regular-ish polygon with n vertices, radius rad (integer rounding). */
static void ngon(wm_rings *r, int cx, int cy, int rad, int n, int ccw)
{
    int lx = INT32_MIN, ly = INT32_MIN, fx = 0, fy = 0, cnt = 0;
    for (int i = 0; i < n; i++)
    {
        const int k = ccw ? i : n - i;
        const double a = 6.283185307179586 * k / n;
        const int x = cx + (int)lround(rad * cos(a));
        const int y = cy + (int)lround(rad * sin(a));
        if (x == lx && y == ly)
            continue;
        if (cnt > 0 && i == n - 1 && x == fx && y == fy)
            continue;
        if (cnt == 0)
        {
            fx = x;
            fy = y;
        }
        push(r, x, y);
        lx = x;
        ly = y;
        cnt++;
    }
    close_ring(r);
}

static void brute(const wm_rings *r, int32_t *enc)
{
    for (size_t i = 0; i < r->nrings; i++)
    {
        const wm_pt v = r->pts[r->start[i]];
        wm_i128 best_a = 0;
        enc[i] = -1;
        for (size_t s = 0; s < r->nrings; s++)
        {
            if (s == i)
                continue;
            const size_t n = wm_rings_len(r, s);
            if (wm_point_in_ring(r->pts + r->start[s], n, v) != 1)
                continue;
            wm_i128 a = wm_ring_area2(r->pts + r->start[s], n);
            if (a < 0)
                a = -a;
            if (enc[i] < 0 || a < best_a)
            {
                enc[i] = (int32_t)s;
                best_a = a;
            }
        }
    }
}

static int check_against_brute(const wm_rings *r, const char *what)
{
    int32_t *a = malloc(r->nrings * sizeof *a);
    int32_t *b = malloc(r->nrings * sizeof *b);
    int bad = 0;
    const wm_status st = wm_holes_nesting(r, a, NULL);
    brute(r, b);
    for (size_t i = 0; i < r->nrings; i++)
        if (a[i] != b[i])
        {
            if (bad < 5)
                printf("#   %s: ring %zu: got %d, want %d\n", what, i, a[i],
                       b[i]);
            bad++;
        }
    TAP_OK(st == WM_OK && bad == 0, "%s: %zu rings match brute force", what,
           r->nrings);
    free(a);
    free(b);
    return bad == 0;
}

/* Random laminar family of rectangles and diamonds: each shape's interior
 * is split into a kx x ky grid of cells, one child per (chosen) cell with
 * margins of 1-2 units, so children never touch and y's coincide a lot. */
static void laminar(wm_rings *r, int x0, int y0, int x1, int y1, int depth,
                    int maxdepth)
{
    const int ccw = depth % 2 == 0;
    const int shape = rnd(0, 3);
    int ix0, iy0, ix1, iy1; /* box available to children */
    if (shape == 0 && x1 - x0 == y1 - y0 && (x1 - x0) % 2 == 0 && x1 - x0 >= 8)
    {
        const int rad = (x1 - x0) / 2;
        diamond(r, x0 + rad, y0 + rad, rad, ccw);
        ix0 = x0 + rad / 2 + 1;
        iy0 = y0 + rad / 2 + 1;
        ix1 = x1 - rad / 2 - 1;
        iy1 = y1 - rad / 2 - 1;
    }
    else
    {
        rect(r, x0, y0, x1, y1, ccw, rnd(0, 2), rnd(0, 7));
        ix0 = x0 + 1;
        iy0 = y0 + 1;
        ix1 = x1 - 1;
        iy1 = y1 - 1;
    }
    if (depth >= maxdepth || ix1 - ix0 < 6 || iy1 - iy0 < 6)
        return;
    const int kx = rnd(1, 3), ky = rnd(1, 3);
    const int cw = (ix1 - ix0) / kx, ch = (iy1 - iy0) / ky;
    for (int a = 0; a < kx; a++)
        for (int b = 0; b < ky; b++)
        {
            if (rnd(0, 4) == 0)
                continue;
            int cx0 = ix0 + a * cw + rnd(0, 1), cy0 = iy0 + b * ch + rnd(0, 1);
            int cx1 = ix0 + (a + 1) * cw - rnd(1, 2);
            int cy1 = iy0 + (b + 1) * ch - rnd(1, 2);
            if (cx1 - cx0 < 2 || cy1 - cy0 < 2)
                continue;
            if (rnd(0, 2) == 0)
            {
                /* square, for a diamond chance */
                int side = cx1 - cx0 < cy1 - cy0 ? cx1 - cx0 : cy1 - cy0;
                side -= side % 2;
                cx1 = cx0 + side;
                cy1 = cy0 + side;
            }
            laminar(r, cx0, cy0, cx1, cy1, depth + 1, maxdepth);
        }
}

/* Copies rings in a shuffled order (ring order must not matter). */
static void shuffled(const wm_rings *in, wm_rings *out)
{
    size_t *perm = malloc((in->nrings ? in->nrings : 1) * sizeof *perm);
    for (size_t i = 0; i < in->nrings; i++)
        perm[i] = i;
    for (size_t i = in->nrings; i > 1; i--)
    {
        const size_t j = lcg() % i, t = perm[i - 1];
        perm[i - 1] = perm[j];
        perm[j] = t;
    }
    wm_rings_clear(out);
    for (size_t k = 0; k < in->nrings; k++)
    {
        const size_t r = perm[k];
        for (size_t i = in->start[r]; i < in->start[r + 1]; i++)
            push(out, in->pts[i].x, in->pts[i].y);
        close_ring(out);
    }
    free(perm);
}

int main(void)
{
    wm_rings r = {0}, r2 = {0};
    int32_t enc[64];

    /* 1. nested squares, alternating orientation, plus a disjoint polygon */
    rect(&r, 40, 40, 60, 60, 1, 0, 0);   /* 0: island, depth 4 */
    rect(&r, 0, 0, 100, 100, 1, 0, 0);   /* 1: outer */
    rect(&r, 30, 30, 70, 70, 0, 0, 0);   /* 2: hole in 3 */
    rect(&r, 10, 10, 90, 90, 0, 1, 2);   /* 3: hole in 1 */
    rect(&r, 20, 20, 80, 80, 1, 2, 5);   /* 4: island in 3 */
    rect(&r, 45, 45, 55, 55, 0, 0, 0);   /* 5: hole in 0 */
    rect(&r, 200, 0, 300, 100, 1, 0, 0); /* 6: disjoint outer */
    rect(&r, 210, 10, 230, 30, 0, 0, 0); /* 7: hole in 6 */
    rect(&r, 250, 10, 290, 90, 0, 0, 0); /* 8: hole in 6 */
    diamond(&r, 270, 50, 15, 1);         /* 9: island in 8 */
    {
        const int32_t want[10] = {2, -1, 4, 1, 3, 0, -1, 6, 6, 8};
        int ok = wm_holes_nesting(&r, enc, NULL) == WM_OK;
        for (int i = 0; i < 10; i++)
            ok = ok && enc[i] == want[i];
        TAP_OK(ok, "nested squares: exact enclosing indices");
        for (int i = 0; i < 10; i++)
            if (enc[i] != want[i])
                printf("#   ring %d: got %d want %d\n", i, enc[i], want[i]);
    }

    /* 2. disjoint outers side by side, same y range: all -1 */
    wm_rings_clear(&r);
    for (int i = 0; i < 10; i++)
        rect(&r, i * 20, 0, i * 20 + 10, 10, 1, i % 3, i);
    {
        int ok = wm_holes_nesting(&r, enc, NULL) == WM_OK;
        for (int i = 0; i < 10; i++)
            ok = ok && enc[i] == -1;
        TAP_OK(ok, "disjoint outers side by side: all -1");
    }

    /* 3. the ray from q passes exactly through vertices of other rings and
     *    along horizontal edges at q.y */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 200, 100, 1, 0, 0);   /* 0 outer */
    diamond(&r, 30, 50, 20, 0);          /* 1 hole: right vertex (50,50) */
    rect(&r, 60, 50, 70, 60, 0, 0, 0);   /* 2 hole, q=(60,50) */
    rect(&r, 80, 40, 90, 50, 0, 0, 0);   /* 3 hole, top edge at y=50 */
    rect(&r, 100, 50, 110, 70, 0, 1, 1); /* 4 hole, bottom edge at y=50 */
    diamond(&r, 130, 50, 5, 0);          /* 5 hole, side vertices y=50 */
    rect(&r, 140, 50, 150, 52, 0, 0, 0); /* 6 hole, q=(140,50) */
    rect(&r, 102, 52, 108, 60, 1, 0, 0); /* 7 island in 4, q.y=52 */
    diamond(&r, 30, 50, 10, 1);          /* 8 island in 1, same y's */
    rect(&r, 26, 48, 34, 52, 0, 1, 0);   /* 9 hole in 8 */
    diamond(&r, 165, 40, 8, 0);          /* 10 hole, top vertex y=48 */
    rect(&r, 175, 48, 185, 58, 0, 0, 0); /* 11 hole, q=(175,48) */
    diamond(&r, 165, 70, 8, 0);          /* 12 hole, bottom vertex y=62 */
    rect(&r, 175, 62, 185, 66, 0, 0, 3); /* 13 hole, q=(175,62) */
    diamond(&r, 165, 90, 5, 0);          /* 14 hole, right vertex y=90 */
    rect(&r, 175, 90, 185, 95, 0, 2, 1); /* 15 hole, q=(175,90) */
    {
        const int32_t want[16] = {-1, 0, 0, 0, 0, 0, 0, 4,
                                  1,  8, 0, 0, 0, 0, 0, 0};
        int ok = wm_holes_nesting(&r, enc, NULL) == WM_OK;
        for (int i = 0; i < 16; i++)
            ok = ok && enc[i] == want[i];
        TAP_OK(ok, "ray through vertices and along horizontal edges");
        for (int i = 0; i < 16; i++)
            if (enc[i] != want[i])
                printf("#   ring %d: got %d want %d\n", i, enc[i], want[i]);
    }
    check_against_brute(&r, "ray through vertices (brute)");

    /* 4. a 50 x 50 grid of holes in one outer, islands in some holes,
     *    holes in some islands; varied shapes */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 10000, 10000, 1, 3, 1);
    for (int a = 0; a < 50; a++)
        for (int b = 0; b < 50; b++)
        {
            const int x = 50 + a * 198, y = 50 + b * 198;
            const int kind = (a * 7 + b * 3) % 5;
            if (kind == 0)
                rect(&r, x, y, x + 150, y + 150, 0, 1, a % 4);
            else if (kind == 1)
                diamond(&r, x + 75, y + 75, 75, 0);
            else
                ngon(&r, x + 75, y + 75, 75, 7 + (a + b) % 13, 0);
            if ((a + b) % 3 == 0)
            {
                ngon(&r, x + 75, y + 75, 40, 5 + a % 9, 1);
                if (b % 2 == 0)
                    rect(&r, x + 65, y + 65, x + 85, y + 85, 0, 0, 0);
            }
        }
    check_against_brute(&r, "50x50 grid of holes with islands");
    shuffled(&r, &r2);
    check_against_brute(&r2, "same grid, rings shuffled");

    /* 5. random laminar families with many coincident y's */
    {
        int all = 1;
        for (int t = 0; t < 40; t++)
        {
            wm_rings_clear(&r);
            laminar(&r, 0, 0, 60 + rnd(0, 200), 60 + rnd(0, 200), 0, 5);
            if (t % 3 == 0) /* a second top-level family beside it */
                laminar(&r, 500, 0, 600 + rnd(0, 100), 60 + rnd(0, 200), 0, 4);
            shuffled(&r, &r2);
            int32_t *a = malloc(r2.nrings * sizeof *a);
            int32_t *b = malloc(r2.nrings * sizeof *b);
            wm_holes_nesting(&r2, a, NULL);
            brute(&r2, b);
            for (size_t i = 0; i < r2.nrings; i++)
                if (a[i] != b[i])
                {
                    if (all)
                        printf("#   trial %d ring %zu: got %d want %d\n", t, i,
                               a[i], b[i]);
                    all = 0;
                }
            free(a);
            free(b);
        }
        TAP_OK(all, "40 random laminar families (coincident y's) match");
    }

    /* 6. empty input and a single ring */
    wm_rings_clear(&r);
    TAP_EQ(wm_holes_nesting(&r, enc, NULL), WM_OK, "no rings: WM_OK");
    rect(&r, 5, 5, 9, 9, 1, 0, 0);
    enc[0] = 7;
    TAP_OK(wm_holes_nesting(&r, enc, NULL) == WM_OK && enc[0] == -1,
           "single ring: -1");

    /* 7. timing: ~20k rings (140 x 140 holes of 24 vertices, islands in
     *    every other hole) in one outer ring */
    {
        wm_rings_clear(&r);
        rect(&r, 0, 0, 1 << 21, 1 << 21, 1, 0, 0);
        for (int a = 0; a < 140; a++)
            for (int b = 0; b < 140; b++)
            {
                const int x = 4000 + a * 14900, y = 4000 + b * 14900;
                ngon(&r, x + 5000, y + 5000, 5000, 24, 0);
                if ((a + b) % 2 == 0)
                    ngon(&r, x + 5000, y + 5000, 2000, 24, 1);
            }
        int32_t *a = malloc(r.nrings * sizeof *a);
        const clock_t t0 = clock();
        const wm_status st = wm_holes_nesting(&r, a, NULL);
        const double ms = 1000.0 * (double)(clock() - t0) / CLOCKS_PER_SEC;
        int ok = st == WM_OK && a[0] == -1;
        /* rings were emitted as outer, then (hole, island?) pairs */
        for (size_t i = 1; i < r.nrings && ok; i++)
        {
            const int ccw =
                wm_ring_area2(r.pts + r.start[i], wm_rings_len(&r, i)) > 0;
            ok = ccw ? a[i] == (int32_t)(i - 1) : a[i] == 0;
        }
        TAP_OK(ok, "large: %zu rings, %zu vertices", r.nrings, r.npts);
        printf("# timing: wm_holes_nesting, %zu rings, %zu vertices: %.1f ms\n",
               r.nrings, r.npts, ms);
        free(a);
    }

    wm_rings_free(&r);
    wm_rings_free(&r2);
    return TAP_DONE();
}
