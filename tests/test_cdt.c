/*
 * test_cdt.c - wm_cdt_triangulate on small exact cases, on cocircular
 * lattices, on many random polygons with holes on small lattices and on
 * large random polygons; every result is checked for the triangle count,
 * orientation, ring edges, edge manifoldness, exact local Delaunay property
 * and exact area. Invalid inputs must fail cleanly. Set WM_TEST_BIG to add
 * two polygons of 1e6 vertices, WM_TEST_INC to the number of random
 * polygons the incremental path (ring splits and points inside, in rounds)
 * is checked on (1,500 by default).
 */
#include "cdt.h"
#include "lattice.h"
#include "tap.h"

#include <math.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

static uint64_t lcg_state = 20240601;

static uint32_t lcg(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (uint32_t)(lcg_state >> 33);
}

/* uniform in [0, 1) */
static double unif(void)
{
    return (double)lcg() / 4294967296.0;
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

/* A ring of three points, in their order. */
static void triangle(wm_rings *r, int ax, int ay, int bx, int by, int cx,
                     int cy)
{
    push(r, ax, ay);
    push(r, bx, by);
    push(r, cx, cy);
    close_ring(r);
}

/* Axis-aligned rectangle with `extra` collinear points per side, ccw or
 * clockwise. */
static void rect(wm_rings *r, int x0, int y0, int x1, int y1, int ccw,
                 int extra)
{
    const int cx[4] = {x0, x1, x1, x0}, cy[4] = {y0, y0, y1, y1};
    for (int s = 0; s < 4; s++)
    {
        const int c = ccw ? s : (4 - s) % 4;
        const int d = ccw ? (c + 1) % 4 : (c + 3) % 4;
        for (int k = 0; k <= extra; k++)
        {
            const long long t = k, m = extra + 1;
            push(r, (int)(cx[c] + (cx[d] - cx[c]) * t / m),
                 (int)(cy[c] + (cy[d] - cy[c]) * t / m));
        }
    }
    close_ring(r);
}

/* ---- checking ------------------------------------------------------- */

typedef struct
{
    uint32_t lo, hi, from, opp;
} hedge;

typedef struct
{
    uint32_t lo, hi, from;
} redge;

static int cmp_hedge(const void *a, const void *b)
{
    const hedge *x = a, *y = b;
    if (x->lo != y->lo)
        return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi)
        return x->hi < y->hi ? -1 : 1;
    return (x->from > y->from) - (x->from < y->from);
}

static int cmp_redge(const void *a, const void *b)
{
    const redge *x = a, *y = b;
    if (x->lo != y->lo)
        return x->lo < y->lo ? -1 : 1;
    return (x->hi > y->hi) - (x->hi < y->hi);
}

static const redge *find_redge(const redge *re, size_t n, uint32_t lo,
                               uint32_t hi)
{
    size_t a = 0, b = n;
    while (a < b)
    {
        const size_t mid = a + (b - a) / 2;
        if (re[mid].lo < lo || (re[mid].lo == lo && re[mid].hi < hi))
            a = mid + 1;
        else
            b = mid;
    }
    return (a < n && re[a].lo == lo && re[a].hi == hi) ? &re[a] : NULL;
}

static int nerrors;

static void on_error(void *user, wm_status status, const char *msg)
{
    (void)user;
    printf("#   reported (status %d): %s\n", (int)status, msg);
    nerrors++;
}

static double now_s(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* What verify() finds wrong with a triangulation (all zero when right). */
typedef struct
{
    size_t bad_count, bad_ccw, bad_area, missing_ring, bad_ring;
    size_t bad_shared, bad_delaunay, interior;
} verdict;

static size_t verdict_errors(const verdict *v)
{
    return v->bad_count + v->bad_ccw + v->bad_area + v->missing_ring +
           v->bad_ring + v->bad_shared + v->bad_delaunay;
}

/* Checks tris against the rings and the points P[r->npts .. np) strictly
 * inside them (P[0 .. r->npts) are the rings' points), exactly: count,
 * orientation, area, ring edges, manifold edges, local Delaunay property. */
static verdict verify_ex(const wm_rings *r, const wm_pt *P, size_t np,
                         const uint32_t *tris, size_t nt)
{
    verdict vd;
    memset(&vd, 0, sizeof vd);
    const size_t n = r->npts;
    vd.bad_count = nt != n + 2 * (r->nrings - 1) - 2 + 2 * (np - n);

    /* orientation, indices, area */
    wm_i128 area = 0, ring_area = 0;
    for (size_t t = 0; t < nt; t++)
    {
        const uint32_t *v = tris + 3 * t;
        if (v[0] >= np || v[1] >= np || v[2] >= np)
        {
            vd.bad_ccw++;
            continue;
        }
        if (wm_orient(P[v[0]], P[v[1]], P[v[2]]) <= 0)
            vd.bad_ccw++;
        area += wm_orient_det(P[v[0]], P[v[1]], P[v[2]]);
    }
    for (size_t i = 0; i < r->nrings; i++)
        ring_area += wm_ring_area2(r->pts + r->start[i], wm_rings_len(r, i));
    vd.bad_area = area != ring_area;
    if (vd.bad_ccw)
        return vd; /* indices may be out of range: stop here */

    /* edges: every triangle side, sorted by undirected edge */
    hedge *he = malloc((3 * nt + 1) * sizeof *he);
    redge *re = malloc(n * sizeof *re);
    if (!he || !re)
        abort();
    for (size_t t = 0; t < nt; t++)
    {
        for (int i = 0; i < 3; i++)
        {
            const uint32_t a = tris[3 * t + i], b = tris[3 * t + (i + 1) % 3];
            hedge *h = he + 3 * t + i;
            h->lo = a < b ? a : b;
            h->hi = a < b ? b : a;
            h->from = a;
            h->opp = tris[3 * t + (i + 2) % 3];
        }
    }
    for (size_t i = 0; i < r->nrings; i++)
    {
        const size_t s = r->start[i], len = wm_rings_len(r, i);
        for (size_t j = 0; j < len; j++)
        {
            const uint32_t a = (uint32_t)(s + j);
            const uint32_t b = (uint32_t)(s + (j + 1) % len);
            re[s + j].lo = a < b ? a : b;
            re[s + j].hi = a < b ? b : a;
            re[s + j].from = a;
        }
    }
    qsort(he, 3 * nt, sizeof *he, cmp_hedge);
    qsort(re, n, sizeof *re, cmp_redge);
    size_t ring_found = 0;
    for (size_t i = 0; i < 3 * nt;)
    {
        size_t j = i + 1;
        while (j < 3 * nt && he[j].lo == he[i].lo && he[j].hi == he[i].hi)
            j++;
        const redge *ring = find_redge(re, n, he[i].lo, he[i].hi);
        if (ring)
        {
            ring_found++;
            /* exactly one triangle, on the left of the ring's direction */
            if (j - i != 1 || he[i].from != ring->from)
                vd.bad_ring++;
        }
        else if (j - i != 2 || he[i].from == he[i + 1].from)
            vd.bad_shared++;
        else
        {
            vd.interior++;
            const hedge *a = he + i, *b = he + i + 1;
            const uint32_t to = a->from == a->lo ? a->hi : a->lo;
            if (wm_incircle(P[a->from], P[to], P[a->opp], P[b->opp]) > 0)
                vd.bad_delaunay++;
        }
        i = j;
    }
    vd.missing_ring = n - ring_found;
    free(he);
    free(re);
    return vd;
}

static verdict verify(const wm_rings *r, const uint32_t *tris, size_t nt)
{
    return verify_ex(r, r->pts, r->npts, tris, nt);
}

/* Triangulates r and checks everything, one TAP line per property;
 * returns the seconds spent in wm_cdt_triangulate. */
static double check(const char *name, const wm_rings *r)
{
    const wm_ctx ctx = {on_error, NULL, NULL};
    uint32_t *tris = NULL;
    size_t nt = 0;
    const size_t n = r->npts;
    const double t0 = now_s();
    const wm_status st =
        wm_cdt_triangulate(r->pts, r->start, r->nrings, &tris, &nt, &ctx);
    const double dt = now_s() - t0;
    TAP_EQ(st, WM_OK, "%s: status (%zu vertices, %zu holes)", name, n,
           r->nrings - 1);
    if (st != WM_OK)
    {
        free(tris);
        return dt;
    }
    const verdict vd = verify(r, tris, nt);
    TAP_EQ(vd.bad_count, 0, "%s: %zu triangles, as the formula says", name, nt);
    TAP_EQ(vd.bad_ccw, 0, "%s: every triangle counter-clockwise", name);
    TAP_EQ(vd.bad_area, 0, "%s: triangle area == polygon area", name);
    TAP_EQ(vd.missing_ring, 0, "%s: every ring edge is a triangle edge", name);
    TAP_EQ(vd.bad_ring, 0, "%s: ring edges bound one triangle, water left",
           name);
    TAP_EQ(vd.bad_shared, 0, "%s: other edges shared by two triangles", name);
    TAP_EQ(vd.bad_delaunay, 0, "%s: %zu interior edges locally Delaunay", name,
           vd.interior);
    free(tris);
    return dt;
}

/* ---- polygons ---------------------------------------------------------- */

static void comb(wm_rings *r, int teeth, int width, int gap, int height,
                 int base, int bottom_step)
{
    const int pitch = width + gap;
    const int xend = pitch * (teeth - 1) + width;
    for (int x = 0; x < xend; x += bottom_step)
        push(r, x, 0);
    for (int i = teeth - 1; i >= 0; i--)
    {
        push(r, pitch * i + width, i == teeth - 1 ? 0 : base);
        if (i == teeth - 1)
            push(r, pitch * i + width, base);
        push(r, pitch * i + width, height);
        push(r, pitch * i, height);
        if (i > 0)
            push(r, pitch * i, base);
    }
    close_ring(r);
}

/* Star-shaped polygon around the centre of the lattice: n vertices at
 * evenly spaced angles, radii from rad(i). Simple as long as every edge
 * turns counter-clockwise around the centre; returns that check. */
static int polar(wm_rings *r, size_t n, double (*rad)(size_t))
{
    const double c = (double)(1 << 23), pi2 = 6.283185307179586;
    const size_t s = r->npts;
    for (size_t i = 0; i < n; i++)
    {
        const double a = pi2 * (double)i / (double)n, q = rad(i);
        push(r, (int)lround(c + q * cos(a)), (int)lround(c + q * sin(a)));
    }
    close_ring(r);
    wm_pt ctr;
    ctr.x = ctr.y = 1 << 23;
    for (size_t i = 0; i < n; i++)
    {
        if (wm_orient(ctr, r->pts[s + i], r->pts[s + (i + 1) % n]) <= 0)
            return 0;
    }
    return 1;
}

static double spiky(size_t i)
{
    (void)i;
    return 8.0e6 * (0.5 + 0.5 * unif());
}

/* Radii as a bounded random walk; the walk does not come back to where it
 * started, so the closing edge is a long radial one that crosses many
 * triangles of the Delaunay triangulation (a large cavity). */
static double walk_r;

static double smooth(size_t i)
{
    (void)i;
    walk_r += 2000.0 * (unif() - 0.5);
    if (walk_r < 3.0e6)
        walk_r = 3.0e6;
    if (walk_r > 8.0e6)
        walk_r = 8.0e6;
    return walk_r;
}

/* ---- random polygons with holes, on small lattices ---------------------- */

static int rnd(int lo, int hi) /* inclusive */
{
    return lo + (int)(lcg() % (uint32_t)(hi - lo + 1));
}

/* Edge i of ring ri, as two points. */
static void ring_edge(const wm_rings *r, size_t ri, size_t i, wm_pt *a,
                      wm_pt *b)
{
    const size_t s = r->start[ri], len = wm_rings_len(r, ri);
    *a = r->pts[s + i];
    *b = r->pts[s + (i + 1) % len];
}

/* Brute-force contract check, independent of the code under test: rings
 * simple and pairwise disjoint, holes inside the outer ring and not in
 * each other, orientations right. O(n^2). */
static int rings_valid(const wm_rings *r)
{
    for (size_t ri = 0; ri < r->nrings; ri++)
    {
        const size_t len = wm_rings_len(r, ri);
        for (size_t i = 0; i < len; i++)
        {
            wm_pt a, b;
            ring_edge(r, ri, i, &a, &b);
            for (size_t rj = ri; rj < r->nrings; rj++)
            {
                const size_t len2 = wm_rings_len(r, rj);
                for (size_t j = rj == ri ? i + 1 : 0; j < len2; j++)
                {
                    wm_pt c, d;
                    ring_edge(r, rj, j, &c, &d);
                    if (rj == ri && (j == i + 1 || (i == 0 && j == len - 1)))
                    {
                        /* neighbours share one vertex and must not fold */
                        const wm_pt q = j == i + 1 ? b : a;
                        const wm_pt o1 = j == i + 1 ? a : b;
                        const wm_pt o2 = j == i + 1 ? d : c;
                        if (wm_pt_eq(o1, o2) ||
                            (wm_orient(o1, q, o2) == 0 &&
                             (int64_t)(o1.x - q.x) * (o2.x - q.x) +
                                     (int64_t)(o1.y - q.y) * (o2.y - q.y) >
                                 0))
                            return 0;
                        continue;
                    }
                    if (wm_segments_meet(a, b, c, d))
                        return 0;
                }
            }
        }
    }
    if (wm_ring_area2(r->pts, wm_rings_len(r, 0)) <= 0)
        return 0;
    for (size_t ri = 1; ri < r->nrings; ri++)
    {
        const wm_pt q = r->pts[r->start[ri]];
        if (wm_ring_area2(r->pts + r->start[ri], wm_rings_len(r, ri)) >= 0 ||
            wm_point_in_ring(r->pts, wm_rings_len(r, 0), q) != 1)
            return 0;
        for (size_t rj = 1; rj < r->nrings; rj++)
        {
            if (rj != ri && wm_point_in_ring(r->pts + r->start[rj],
                                             wm_rings_len(r, rj), q) != 0)
                return 0;
        }
    }
    return 1;
}

/* A random polygon on an l x l lattice: a star-shaped outer ring (random
 * angles and radii, some collinear points added on its edges), then up to
 * maxh random holes (squares, thin or random triangles) kept when valid.
 * Small lattices give many collinear and cocircular vertices. Returns 0
 * when the outer ring came out invalid. */
static int random_polygon(wm_rings *r, int l, int maxh)
{
    wm_rings_clear(r);
    const int nv = rnd(3, 40);
    double ang[40];
    for (int i = 0; i < nv; i++)
        ang[i] = 6.283185307179586 * unif();
    for (int i = 1; i < nv; i++) /* insertion sort */
        for (int j = i; j > 0 && ang[j] < ang[j - 1]; j--)
        {
            const double t = ang[j];
            ang[j] = ang[j - 1];
            ang[j - 1] = t;
        }
    for (int i = 0; i < nv; i++)
    {
        const double q = (0.1 + 0.4 * unif()) * l;
        const int x = (int)lround(l / 2.0 + q * cos(ang[i]));
        const int y = (int)lround(l / 2.0 + q * sin(ang[i]));
        const size_t np = r->npts;
        if (np > 0 && r->pts[np - 1].x == x && r->pts[np - 1].y == y)
            continue;
        push(r, x, y);
        /* sometimes a collinear point halfway to the next angle's point */
        if (i + 1 < nv && rnd(0, 2) == 0)
        {
            const double q2 = (0.1 + 0.4 * unif()) * l;
            const int x2 = (int)lround(l / 2.0 + q2 * cos(ang[i + 1]));
            const int y2 = (int)lround(l / 2.0 + q2 * sin(ang[i + 1]));
            if ((x + x2) % 2 == 0 && (y + y2) % 2 == 0)
            {
                push(r, (x + x2) / 2, (y + y2) / 2);
                push(r, x2, y2);
                i++;
            }
        }
    }
    if (r->npts < 3)
        return 0;
    close_ring(r);
    if (!rings_valid(r))
        return 0;
    const int nh = rnd(0, maxh);
    for (int h = 0; h < nh; h++)
    {
        /* near the centre, where the outer ring surely is */
        const int lo = l / 2 - l / 5, hi = l / 2 + l / 5;
        const int kind = rnd(0, 2), x = rnd(lo, hi), y = rnd(lo, hi);
        if (kind == 0)
        {
            const int e = rnd(1, l / 16 > 1 ? l / 16 : 1);
            push(r, x, y);
            push(r, x, y + e);
            push(r, x + e, y + e);
            push(r, x + e, y);
        }
        else
        {
            const int x2 = rnd(lo, hi), y2 = rnd(lo, hi);
            push(r, x, y);
            push(r, x2, y2);
            if (kind == 1)
                push(r, x2 + rnd(-2, 2), y2 + rnd(-2, 2));
            else
                push(r, rnd(lo, hi), rnd(lo, hi));
            const size_t s = r->npts - 3;
            if (wm_ring_area2(r->pts + s, 3) > 0)
            {
                const wm_pt t = r->pts[s + 1];
                r->pts[s + 1] = r->pts[s + 2];
                r->pts[s + 2] = t;
            }
        }
        close_ring(r);
        if (!rings_valid(r))
        {
            r->nrings--;
            r->npts = r->start[r->nrings];
        }
    }
    return 1;
}

/* Many random polygons: every result must verify. */
static void random_batch(int cases)
{
    wm_rings r;
    memset(&r, 0, sizeof r);
    int done = 0, failed = 0;
    size_t verts = 0, holes = 0;
    while (done < cases)
    {
        const int l = 1 << rnd(3, 10);
        if (!random_polygon(&r, l, 25))
            continue;
        done++;
        verts += r.npts;
        holes += r.nrings - 1;
        uint32_t *tris = NULL;
        size_t nt = 0;
        const wm_status st =
            wm_cdt_triangulate(r.pts, r.start, r.nrings, &tris, &nt, NULL);
        const verdict vd = verify(&r, tris, st == WM_OK ? nt : 0);
        if (st != WM_OK || verdict_errors(&vd) != 0)
        {
            if (failed++ < 3)
            {
                printf("# random case %d failed (status %d):\n", done, (int)st);
                for (size_t ri = 0; ri < r.nrings; ri++)
                {
                    printf("#   ring %zu:", ri);
                    for (size_t i = r.start[ri]; i < r.start[ri + 1]; i++)
                        printf(" %d,%d", (int)r.pts[i].x, (int)r.pts[i].y);
                    printf("\n");
                }
            }
        }
        free(tris);
    }
    TAP_EQ(failed, 0,
           "%d random polygons on small lattices (%zu vertices, %zu holes "
           "in all) give verified CDTs",
           cases, verts, holes);
    wm_rings_free(&r);
}

/* ---- the incremental path (wm_cdt_open, wm_cdt_split, wm_cdt_insert) -- */

/* A polygon as the incremental CDT numbers it: P[k] is vertex k, the rings
 * list vertex numbers (ring q: rv[rs[q] .. rs[q + 1])), ex the points
 * strictly inside. */
typedef struct
{
    wm_pt *P;
    uint32_t *rv, *ex;
    size_t np, nrv, nex, nrings;
    size_t rs[64];
} inc_poly;

/* The rings in position order (out) and every point in verify_ex's order
 * (layout: ring positions, then ex); map: vertex number -> layout index. */
static void inc_layout(const inc_poly *q, wm_rings *out, wm_pt *layout,
                       uint32_t *map)
{
    wm_rings_clear(out);
    for (size_t k = 0; k < q->nrings; k++)
    {
        for (size_t i = q->rs[k]; i < q->rs[k + 1]; i++)
        {
            map[q->rv[i]] = (uint32_t)out->npts;
            layout[out->npts] = q->P[q->rv[i]];
            push(out, q->P[q->rv[i]].x, q->P[q->rv[i]].y);
        }
        close_ring(out);
    }
    for (size_t i = 0; i < q->nex; i++)
    {
        map[q->ex[i]] = (uint32_t)(q->nrv + i);
        layout[q->nrv + i] = q->P[q->ex[i]];
    }
}

/* Whether p lies in the closed triangle a, b, c (any orientation). */
static int in_closed(wm_pt a, wm_pt b, wm_pt c, wm_pt p)
{
    const int o1 = wm_orient(a, b, p), o2 = wm_orient(b, c, p);
    const int o3 = wm_orient(c, a, p);
    return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

/* Tries to split ring edge i of q (positions in rv) at its rounded
 * midpoint: kept when the rings stay valid and no point inside lies in the
 * closed triangle of the edge and the midpoint. Returns 1 when split. */
static int inc_split(inc_poly *q, wm_cdt *c, size_t i, wm_rings *tmp,
                     wm_pt *cut)
{
    size_t k = 0;
    while (q->rs[k + 1] <= i)
        k++;
    const size_t len = q->rs[k + 1] - q->rs[k];
    const uint32_t a = q->rv[i];
    const uint32_t b = q->rv[q->rs[k] + (i - q->rs[k] + 1) % len];
    const wm_pt pa = q->P[a], pb = q->P[b];
    const wm_pt m = {(int32_t)(((int64_t)pa.x + pb.x) >> 1),
                     (int32_t)(((int64_t)pa.y + pb.y) >> 1)};
    for (size_t v = 0; v < q->np; v++)
        if (wm_pt_eq(q->P[v], m))
            return 0;
    for (size_t e = 0; e < q->nex; e++)
        if (in_closed(pa, m, pb, q->P[q->ex[e]]))
            return 0;
    /* the rings with m after position i */
    wm_rings_clear(tmp);
    for (size_t kk = 0; kk < q->nrings; kk++)
    {
        for (size_t j = q->rs[kk]; j < q->rs[kk + 1]; j++)
        {
            push(tmp, q->P[q->rv[j]].x, q->P[q->rv[j]].y);
            if (j == i)
                push(tmp, m.x, m.y);
        }
        close_ring(tmp);
    }
    if (!rings_valid(tmp))
        return 0;
    uint32_t nq = UINT32_MAX;
    if (wm_cdt_split(c, a, b, m, &nq, NULL) != WM_OK || nq != q->np)
        return -1;
    q->P[q->np++] = m;
    memmove(q->rv + i + 2, q->rv + i + 1, (q->nrv - i - 1) * sizeof *q->rv);
    q->rv[i + 1] = nq;
    q->nrv++;
    for (size_t kk = k + 1; kk <= q->nrings; kk++)
        q->rs[kk]++;
    cut[0] = pa;
    cut[1] = m;
    cut[2] = pb;
    return 1;
}

/* Whether nb gives each half-edge of tris its twin, or -1 on the nring
 * ring edges alone. */
static int neighbours_ok(const uint32_t *tris, size_t nt, const int32_t *nb,
                         size_t nring)
{
    size_t border = 0;
    for (size_t h = 0; nb && h < 3 * nt; h++)
    {
        const size_t h1 = h - h % 3 + (h + 1) % 3;
        if (nb[h] < 0)
        {
            border++;
            continue;
        }
        const size_t g = (size_t)nb[h], g1 = g - g % 3 + (g + 1) % 3;
        if (g >= 3 * nt || nb[g] != (int32_t)h || tris[g] != tris[h1] ||
            tris[g1] != tris[h])
            return 0;
    }
    return nb && border == nring;
}

/* Rounds of ring splits and points inside on random polygons, each
 * round's triangulation verified as a from-scratch one would be. */
static void incremental_batch(int cases)
{
    wm_rings r, cur, tmp;
    memset(&r, 0, sizeof r);
    memset(&cur, 0, sizeof cur);
    memset(&tmp, 0, sizeof tmp);
    int done = 0, failed = 0;
    size_t nsplit = 0, ninside = 0;
    enum
    {
        CAP = 4096
    };
    inc_poly q;
    q.P = malloc(CAP * sizeof *q.P);
    q.rv = malloc(CAP * sizeof *q.rv);
    q.ex = malloc(CAP * sizeof *q.ex);
    wm_pt *layout = malloc(CAP * sizeof *layout),
          *add = malloc(CAP * sizeof *add);
    wm_pt *cuts = malloc(3 * CAP * sizeof *cuts);
    uint32_t *map = malloc(CAP * sizeof *map);
    if (!q.P || !q.rv || !q.ex || !layout || !add || !cuts || !map)
        abort();
    while (done < cases)
    {
        const int l = 1 << rnd(5, 12);
        if (!random_polygon(&r, l, 6) || r.nrings > 60)
            continue;
        done++;
        q.np = q.nrv = r.npts;
        q.nex = 0;
        q.nrings = r.nrings;
        for (size_t i = 0; i < r.npts; i++)
        {
            q.P[i] = r.pts[i];
            q.rv[i] = (uint32_t)i;
        }
        memcpy(q.rs, r.start, (r.nrings + 1) * sizeof *q.rs);
        wm_cdt *c = NULL;
        uint32_t *tris = NULL;
        int32_t *nb = NULL;
        size_t nt = 0;
        wm_status st = wm_cdt_open(r.pts, r.start, r.nrings, 0, &c, &tris, &nt,
                                   NULL, NULL);
        int bad = st != WM_OK;
        for (int round = 0; round < 6 && !bad; round++)
        {
            /* splits of random ring edges */
            size_t ncut = 0;
            const int ns = rnd(0, 3);
            for (int k = 0; k < ns && q.np + 8 < CAP / 2; k++)
            {
                const int sp = inc_split(&q, c, (size_t)rnd(0, (int)q.nrv - 1),
                                         &tmp, cuts + 3 * ncut);
                bad |= sp < 0;
                ncut += sp > 0;
            }
            /* centroids of random triangles of the last round, strictly
             * inside them and clear of this round's splits */
            size_t na = 0;
            const int ni = rnd(0, 20);
            for (int k = 0; k < ni && !bad && nt > 0 && q.np + na + 8 < CAP / 2;
                 k++)
            {
                const uint32_t *v = tris + 3 * (size_t)rnd(0, (int)nt - 1);
                const wm_pt a = q.P[v[0]], b = q.P[v[1]], d = q.P[v[2]];
                const wm_pt g = {(int32_t)(((int64_t)a.x + b.x + d.x) / 3),
                                 (int32_t)(((int64_t)a.y + b.y + d.y) / 3)};
                int ok = wm_orient(a, b, g) > 0 && wm_orient(b, d, g) > 0 &&
                         wm_orient(d, a, g) > 0;
                for (size_t j = 0; ok && j < ncut; j++)
                    ok = !in_closed(cuts[3 * j], cuts[3 * j + 1],
                                    cuts[3 * j + 2], g);
                for (size_t j = 0; ok && j < na; j++)
                    ok = !wm_pt_eq(add[j], g);
                if (ok)
                    add[na++] = g;
            }
            free(tris);
            tris = NULL;
            st = bad ? WM_ERR_INTERNAL
                     : wm_cdt_insert(c, add, na, &tris, &nt, &nb, NULL);
            for (size_t j = 0; j < na; j++)
            {
                q.ex[q.nex++] = (uint32_t)q.np;
                q.P[q.np++] = add[j];
            }
            nsplit += ncut;
            ninside += na;
            if (st != WM_OK)
            {
                bad = 1;
                break;
            }
            inc_layout(&q, &cur, layout, map);
            uint32_t *mt = malloc((3 * nt + 1) * sizeof *mt);
            if (!mt)
                abort();
            for (size_t i = 0; i < 3 * nt; i++)
                mt[i] = tris[i] < q.np ? map[tris[i]] : UINT32_MAX;
            const verdict vd = verify_ex(&cur, layout, q.np, mt, nt);
            free(mt);
            const int nbad = !neighbours_ok(tris, nt, nb, q.nrv);
            free(nb);
            nb = NULL;
            bad = verdict_errors(&vd) != 0 || nbad;
            if (bad)
                printf("# round %d: neighbours %d, count %zu ccw %zu area %zu "
                       "miss %zu ring %zu shared %zu del %zu; np %zu nt %zu "
                       "splits %zu add %zu\n",
                       round, nbad, vd.bad_count, vd.bad_ccw, vd.bad_area,
                       vd.missing_ring, vd.bad_ring, vd.bad_shared,
                       vd.bad_delaunay, q.np, nt, ncut, na);
        }
        if (bad && failed++ < 3)
            printf("# incremental case %d failed (status %d)\n", done, (int)st);
        free(tris);
        wm_cdt_free(c);
    }
    TAP_EQ(failed, 0,
           "%d random polygons, rounds of %zu ring splits and %zu points "
           "inside in all: every round's triangulation verified",
           cases, nsplit, ninside);
    free(q.P);
    free(q.rv);
    free(q.ex);
    free(layout);
    free(add);
    free(cuts);
    free(map);
    wm_rings_free(&r);
    wm_rings_free(&cur);
    wm_rings_free(&tmp);
}

/* A point inside that becomes a ring vertex (a split at it): one inserted
 * (at_open 0) or one of wm_cdt_open's extra points (at_open 1). */
static void incremental_existing(int at_open)
{
    wm_rings r, after;
    memset(&r, 0, sizeof r);
    memset(&after, 0, sizeof after);
    rect(&r, 0, 0, 100, 100, 1, 0);
    wm_cdt *c = NULL;
    uint32_t *tris = NULL;
    size_t nt = 0;
    const wm_pt in[2] = {{50, 1}, {30, 60}};
    wm_pt all[6];
    memcpy(all, r.pts, 4 * sizeof *all);
    memcpy(all + 4, in, sizeof in);
    wm_status st = wm_cdt_open(all, r.start, r.nrings, at_open ? 2 : 0, &c,
                               &tris, &nt, NULL, NULL);
    free(tris);
    tris = NULL;
    if (st == WM_OK && !at_open)
        st = wm_cdt_insert(c, in, 2, &tris, &nt, NULL, NULL);
    free(tris);
    uint32_t q = 4; /* (50, 1) */
    if (st == WM_OK)
        st = wm_cdt_split(c, 0, 1, in[0], &q, NULL);
    tris = NULL;
    if (st == WM_OK)
        st = wm_cdt_insert(c, NULL, 0, &tris, &nt, NULL, NULL);
    TAP_EQ(st, WM_OK, "incremental: a point inside (%s) becomes a ring vertex",
           at_open ? "given to wm_cdt_open" : "inserted");
    /* rings (0,0) (50,1) (100,0) (100,100) (0,100), then (30, 60) */
    const int ring[5][2] = {{0, 0}, {50, 1}, {100, 0}, {100, 100}, {0, 100}};
    for (int k = 0; k < 5; k++)
        push(&after, ring[k][0], ring[k][1]);
    close_ring(&after);
    const wm_pt P[6] = {{0, 0},     {50, 1},  {100, 0},
                        {100, 100}, {0, 100}, {30, 60}};
    const uint32_t to[6] = {0, 2, 3, 4, 1, 5}; /* vertex number -> P */
    for (size_t i = 0; st == WM_OK && i < 3 * nt; i++)
        tris[i] = tris[i] < 6 ? to[tris[i]] : UINT32_MAX;
    const verdict vd = verify_ex(&after, P, 6, tris, st == WM_OK ? nt : 0);
    TAP_EQ(verdict_errors(&vd), 0,
           "incremental: its triangulation verified (%zu triangles)", nt);
    free(tris);
    wm_cdt_free(c);
    wm_rings_free(&r);
    wm_rings_free(&after);
}

/* The incremental path refuses what breaks its contract, by name. */
static void incremental_invalid(void)
{
    wm_rings r;
    memset(&r, 0, sizeof r);
    rect(&r, 0, 0, 100, 100, 1, 0);
    const wm_ctx ctx = {on_error, NULL, NULL};
    const struct
    {
        const char *name;
        wm_pt p;
    } bad[] = {{"a point outside the polygon", {150, 50}},
               {"a point on a ring edge", {50, 0}},
               {"a point on a vertex", {100, 100}}};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++)
    {
        wm_cdt *c = NULL;
        uint32_t *tris = NULL;
        size_t nt = 0;
        TAP_EQ(wm_cdt_open(r.pts, r.start, r.nrings, 0, &c, &tris, &nt, NULL,
                           &ctx),
               WM_OK, "incremental: a square");
        free(tris);
        const int before = nerrors;
        const wm_status st =
            wm_cdt_insert(c, &bad[k].p, 1, &tris, &nt, NULL, &ctx);
        TAP_EQ(st, WM_ERR_INVALID, "incremental: %s is refused", bad[k].name);
        TAP_OK(tris == NULL && nerrors > before, "incremental: %s reported",
               bad[k].name);
        wm_cdt_free(c);
    }
    wm_cdt *c = NULL;
    uint32_t *tris = NULL;
    size_t nt = 0;
    wm_cdt_open(r.pts, r.start, r.nrings, 0, &c, &tris, &nt, NULL, &ctx);
    free(tris);
    uint32_t q = UINT32_MAX;
    const wm_pt m = {50, 50};
    TAP_EQ(wm_cdt_split(c, 0, 2, m, &q, &ctx), WM_ERR_INVALID,
           "incremental: splitting a diagonal (no ring edge) is refused");
    wm_cdt_free(c);
    /* a thin clockwise hole whose third vertex lies between edge 4-5 and
     * that edge's rounded midpoint: re-routed through it, the hole would
     * turn inside out (counter-clockwise), which no count sees */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 300, 300, 1, 0);
    triangle(&r, 100, 100, 108, 103, 103, 101);
    wm_cdt_open(r.pts, r.start, r.nrings, 0, &c, &tris, &nt, NULL, &ctx);
    free(tris);
    q = UINT32_MAX;
    const wm_pt mid = {104, 101};
    TAP_EQ(wm_cdt_split(c, 4, 5, mid, &q, &ctx), WM_ERR_INVALID,
           "incremental: a split that turns its ring inside out is refused");
    wm_cdt_free(c);
    wm_cdt_open(r.pts, r.start, r.nrings, 0, &c, &tris, &nt, NULL, &ctx);
    free(tris);
    q = 99;
    TAP_EQ(wm_cdt_split(c, 4, 4000000000u, mid, &q, &ctx), WM_ERR_INVALID,
           "incremental: a vertex number out of range is refused");
    wm_cdt_free(c);
    wm_rings_free(&r);
}

static void expect_invalid(const char *name, const wm_rings *r)
{
    const wm_ctx ctx = {on_error, NULL, NULL};
    uint32_t *tris = (uint32_t *)&nerrors; /* must be reset to NULL */
    size_t nt = 7;
    const int before = nerrors;
    const wm_status st =
        wm_cdt_triangulate(r->pts, r->start, r->nrings, &tris, &nt, &ctx);
    TAP_EQ(st, WM_ERR_INVALID, "%s: rejected as invalid", name);
    TAP_OK(tris == NULL && nt == 0 && nerrors > before,
           "%s: no output, message reported", name);
    free(tris == (uint32_t *)&nerrors ? NULL : tris);
}

int main(void)
{
    wm_rings r;
    memset(&r, 0, sizeof r);

    /* a triangle */
    push(&r, 0, 0);
    push(&r, 10, 0);
    push(&r, 0, 10);
    close_ring(&r);
    check("triangle", &r);

    /* a square with 200 points per side (collinear runs on the hull) */
    wm_rings_clear(&r);
    rect(&r, 1000, 1000, 3000, 3000, 1, 199);
    check("square 200/side", &r);

    /* a concave comb: long thin teeth, a bottom with collinear points */
    wm_rings_clear(&r);
    comb(&r, 100, 2, 3, 100000, 10, 7);
    check("comb", &r);

    /* one hole, with collinear points on both rings */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 1000, 1000, 1, 9);
    rect(&r, 300, 400, 700, 600, 0, 5);
    check("one hole", &r);

    /* 400 small square holes in a grid */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 4100, 4100, 1, 99);
    for (int i = 0; i < 20; i++)
        for (int j = 0; j < 20; j++)
            rect(&r, 100 + 200 * i, 100 + 200 * j, 200 + 200 * i, 200 + 200 * j,
                 0, (i + j) % 3);
    check("400 holes", &r);

    /* cocircular: 1x1 holes on a lattice, every lattice point is a vertex,
     * cocircular quadruples everywhere */
    wm_rings_clear(&r);
    {
        const int g = 30, side = 2 * g + 1;
        rect(&r, 0, 0, side, side, 1, side - 1);
        for (int i = 0; i < g; i++)
            for (int j = 0; j < g; j++)
                rect(&r, 2 * i + 1, 2 * j + 1, 2 * i + 2, 2 * j + 2, 0, 0);
    }
    check("cocircular lattice", &r);

    /* the same, scaled up to the top of the lattice range */
    wm_rings_clear(&r);
    {
        const int g = 20, side = 2 * g + 1, k = (1 << 24) / side;
        rect(&r, 0, 0, side * k, side * k, 1, side - 1);
        for (int i = 0; i < g; i++)
            for (int j = 0; j < g; j++)
                rect(&r, (2 * i + 1) * k, (2 * j + 1) * k, (2 * i + 2) * k,
                     (2 * j + 2) * k, 0, 0);
    }
    check("cocircular lattice, scaled", &r);

    /* random polygons with holes: collinear and cocircular vertices,
     * thin holes, cavities that touch themselves */
    random_batch(1500);
    incremental_batch(getenv("WM_TEST_INC") ? atoi(getenv("WM_TEST_INC"))
                                            : 1500);
    incremental_existing(0);
    incremental_existing(1);
    incremental_invalid();

    /* large star-shaped polygons */
    /* (TAP_OK evaluates its condition twice: generate first) */
    wm_rings_clear(&r);
    walk_r = 6.0e6;
    int simple = polar(&r, 100000, smooth);
    TAP_OK(simple, "smooth polar 1e5: generator simple");
    double dt = check("smooth polar 1e5", &r);
    printf("# smooth polar polygon, 1e5 vertices: %.3f s\n", dt);

    wm_rings_clear(&r);
    simple = polar(&r, 100000, spiky);
    TAP_OK(simple, "spiky polar 1e5: generator simple");
    dt = check("spiky polar 1e5", &r);
    printf("# spiky polar polygon (random radii), 1e5 vertices: %.3f s\n", dt);

    /* a large square with 25000 points per side and 2500 holes */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 1 << 24, 1 << 24, 1, 24999);
    for (int i = 0; i < 50; i++)
        for (int j = 0; j < 50; j++)
            rect(&r, 100000 + 330000 * i, 100000 + 330000 * j,
                 300000 + 330000 * i, 300000 + 330000 * j, 0, 1 + (i * j) % 7);
    dt = check("square 25000/side, 2500 holes", &r);
    printf("# square with 2500 holes, %zu vertices: %.3f s\n", r.npts, dt);

    if (getenv("WM_TEST_BIG"))
    {
        wm_rings_clear(&r);
        walk_r = 6.0e6;
        polar(&r, 1000000, smooth);
        dt = check("smooth polar 1e6", &r);
        printf("# smooth polar polygon, 1e6 vertices: %.3f s\n", dt);
        wm_rings_clear(&r);
        polar(&r, 1000000, spiky);
        dt = check("spiky polar 1e6", &r);
        printf("# spiky polar polygon, 1e6 vertices: %.3f s\n", dt);
    }

    /* invalid input */
    wm_rings_clear(&r);
    rect(&r, 0, 0, 100, 100, 1, 0);
    rect(&r, 50, 50, 150, 150, 0, 0);
    expect_invalid("hole crossing the outer ring", &r);

    wm_rings_clear(&r);
    rect(&r, 0, 0, 10, 10, 1, 0);
    triangle(&r, 0, 0, 3, 5, 5, 3);
    expect_invalid("duplicate vertex", &r);

    /* the edge (12,15)-(12,0) crosses (0,5)-(20,5); the area is positive */
    wm_rings_clear(&r);
    push(&r, 0, 5);
    push(&r, 20, 5);
    push(&r, 20, 15);
    push(&r, 12, 15);
    push(&r, 12, 0);
    close_ring(&r);
    expect_invalid("self-crossing ring", &r);

    wm_rings_clear(&r);
    rect(&r, 0, 0, 10, 10, 1, 0);
    push(&r, 5, 0);
    push(&r, 4, 5);
    push(&r, 6, 5);
    close_ring(&r);
    expect_invalid("hole vertex on the outer ring", &r);

    wm_rings_clear(&r);
    rect(&r, 0, 0, 10, 10, 1, 0);
    rect(&r, 20, 20, 30, 30, 0, 0);
    expect_invalid("hole outside the outer ring", &r);

    wm_rings_clear(&r);
    rect(&r, 0, 0, 100, 100, 1, 0);
    rect(&r, 10, 10, 90, 90, 0, 0);
    rect(&r, 20, 20, 80, 80, 0, 0);
    expect_invalid("nested holes", &r);

    wm_rings_clear(&r);
    rect(&r, 0, 0, 10, 10, 1, 0);
    rect(&r, 2, 2, 8, 8, 1, 0);
    expect_invalid("counter-clockwise hole", &r);

    wm_rings_clear(&r);
    rect(&r, 0, 0, (1 << 24) + 1, 10, 1, 0);
    expect_invalid("coordinate out of range", &r);

    {
        uint32_t *tris = NULL;
        size_t nt = 0;
        TAP_EQ(wm_cdt_triangulate(NULL, NULL, 1, &tris, &nt, NULL),
               WM_ERR_INVALID, "NULL input rejected, NULL ctx accepted");
    }

    wm_rings_free(&r);
    return TAP_DONE();
}
