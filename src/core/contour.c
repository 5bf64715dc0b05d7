/*
 * contour.c - marching squares at level 0 with sub-pixel crossings, rings
 * closed along the block square.
 *
 * Method (Lorensen & Cline 1987, in 2D; cf. GDAL alg/marching_squares).
 * A sample is water when its value is <= 0 (the buffer is a closed set).
 * Every cell edge whose two samples differ in class holds one crossing, at
 * the linear interpolation of the two values, rounded to the lattice and
 * clamped to the open edge (offset 1 .. WM_Q-1 from its first sample):
 * crossings therefore never coincide with samples nor with each other, and
 * each cell's segments lie inside the cell. Segments are oriented with
 * water on their left (outer rings counter-clockwise, holes clockwise).
 *
 * Case table: corners 0 (c,r), 1 (c+1,r), 2 (c+1,r+1), 3 (c,r+1), i.e.
 * counter-clockwise in the y-up frame; edges B (0-1), R (1-2), T (2-3),
 * L (3-0). Walking the cell counter-clockwise, each crossing edge goes
 * water->land ("out") or land->water ("in"). A segment runs from an out
 * edge to an in edge. With one out edge the pairing is forced.
 *
 * Saddle rule (two out edges: diagonal corners 0,2 or 1,3 are water): with
 * the inputs at hand (a probe) a saddle cell is ambiguous and rebuilt
 * exactly (subpixel.c): which diagonal the boundary separates is decided
 * by the inputs, not the samples. Without a probe (unit tests of the field
 * alone) the mean of the four corner values (summed in corner order), the
 * bilinear interpolant's value at the centre as in GDAL's contour, decides:
 * if it is water the water corners are joined through the centre and each
 * out edge pairs with the next in edge counter-clockwise, otherwise they
 * are separated and each out edge pairs with the previous in edge. The
 * decision belongs to the cell alone (a cell is in one block), so it is
 * deterministic, and the two segments cut opposite corners and cannot meet.
 *
 * Closing: chains that end on the block square are joined by walking the
 * square counter-clockwise from an exit crossing to the next entry
 * crossing, adding the corners passed (a square's corner is water exactly
 * when such a walk passes it). The square walked through water from an exit
 * reaches an entry first because crossings alternate along it.
 *
 * Cost: O(cells in mixed tiles + crossings) with an open-addressing hash
 * from cell edge to segment; no per-point allocation.
 */
#include "contour.h"

#include "lattice.h"
#include "subpixel.h"

#include <stdlib.h>
#include <string.h>

enum
{
    EB = 0,
    ER = 1,
    ET = 2,
    EL = 3
};

/* A segment of a cell, from the crossing on its side `iside` (its in edge)
 * to the one on `oside` (its out edge), with its links: the chains are
 * walked in link order, so what a step reads is in one place. */
typedef struct
{
    wm_pt in_pt, out_pt;
    int32_t c, r; /* its cell */
    uint8_t iside, oside;
    uint8_t flags; /* HAS_PRED, USED, LINK_IN, LINK_OUT */
    uint32_t next; /* the segment its out edge leads to, or NO_SEG */
} seg;

#define NO_SEG UINT32_MAX
enum
{
    HAS_PRED = 1, /* some segment's next */
    USED = 2,     /* walked */
    LINK_IN = 4,  /* its in edge is linked through the hash: it lies on an
                     ambiguous cell, or the segment is one of such a cell */
    LINK_OUT = 8  /* likewise its out edge */
};

/* The segments of one tile: segs[s0, s1), its first cell (c0, r0). */
typedef struct
{
    size_t s0, s1;
    int32_t c0, r0;
} tilesegs;

typedef struct
{
    int32_t n;            /* cells per side */
    wm_hidden hid;        /* hidden crossings and ambiguous cells */
    int32_t cur_c, cur_r; /* the ambiguous cell being done */
    seg *segs;
    size_t nsegs, cap;
    tilesegs *tiles;
    size_t ntiles, tcap;
} state;

static int push_seg(state *s, wm_pt ip, wm_pt op, int32_t c, int32_t r,
                    int iside, int oside)
{
    if (s->nsegs == s->cap)
    {
        size_t nc = s->cap ? 2 * s->cap : 1024;
        seg *p = realloc(s->segs, nc * sizeof *p);
        if (!p)
            return 0;
        s->segs = p;
        s->cap = nc;
    }
    seg *g = &s->segs[s->nsegs++];
    g->in_pt = ip;
    g->out_pt = op;
    g->c = c;
    g->r = r;
    g->iside = (uint8_t)iside;
    g->oside = (uint8_t)oside;
    g->flags = 0;
    g->next = NO_SEG;
    return 1;
}

/* Cell (c, r) whose lower-left sample is at p in its tile's value array
 * (row stride WM_TILE + 1); its corners are not all on one side (the caller
 * visits only those). */
static int cell(state *s, int32_t c, int32_t r, const float *p)
{
    const float v[4] = {p[0], p[1], p[WM_TILE + 2], p[WM_TILE + 1]};
    const int w[4] = {v[0] <= 0, v[1] <= 0, v[2] <= 0, v[3] <= 0};
    /* per edge, CCW from corner k to k+1: crossing, out/in */
    wm_pt pt[4];
    int kind[4]; /* 0 none, 1 out (water->land), 2 in */
    const int32_t X = c * WM_Q, Y = r * WM_Q;
    for (int k = 0; k < 4; k++)
        kind[k] = w[k] == w[(k + 1) & 3] ? 0 : (w[k] ? 1 : 2);
    /* crossings always interpolated from the edge's lower sample */
    if (kind[EB])
        pt[EB] = wm_contour_crossing(v[0], v[1], X, Y, 0);
    if (kind[ER])
        pt[ER] = wm_contour_crossing(v[1], v[2], X + WM_Q, Y, 1);
    if (kind[ET])
        pt[ET] = wm_contour_crossing(v[3], v[2], X, Y + WM_Q, 0);
    if (kind[EL])
        pt[EL] = wm_contour_crossing(v[0], v[3], X, Y, 1);
    const int saddle = w[0] == w[2] && w[1] == w[3];
    int joined = 0;
    if (saddle)
    {
        const double mean = ((double)v[0] + v[1] + v[2] + v[3]) / 4.0;
        joined = mean <= 0;
    }
    for (int k = 0; k < 4; k++)
    {
        if (kind[k] != 1)
            continue;
        int m;
        if (!saddle || joined)
        { /* next in edge counter-clockwise */
            m = (k + 1) & 3;
            while (kind[m] != 2)
                m = (m + 1) & 3;
        }
        else
        { /* previous in edge */
            m = (k + 3) & 3;
            while (kind[m] != 2)
                m = (m + 3) & 3;
        }
        if (!push_seg(s, pt[k], pt[m], c, r, k, m))
            return 0;
    }
    return 1;
}

int wm_contour_cell_edge(const wm_field *f, int32_t c, int32_t r, wm_pt *a,
                         wm_pt *b)
{
    float v[4];
    wm_field_cell(f, c, r, v);
    const int w[4] = {v[0] <= 0, v[1] <= 0, v[2] <= 0, v[3] <= 0};
    const int32_t X = c * WM_Q, Y = r * WM_Q;
    int nout = 0, nin = 0;
    for (int k = 0; k < 4; k++)
    {
        if (w[k] == w[(k + 1) & 3])
            continue;
        /* cell()'s crossing on edge k (corner k to k + 1), from the edge's
         * lower sample */
        const wm_pt p =
            k == EB   ? wm_contour_crossing(v[0], v[1], X, Y, 0)
            : k == ER ? wm_contour_crossing(v[1], v[2], X + WM_Q, Y, 1)
            : k == ET ? wm_contour_crossing(v[3], v[2], X, Y + WM_Q, 0)
                      : wm_contour_crossing(v[0], v[3], X, Y, 1);
        if (w[k])
        {
            *a = p; /* an out edge: where the segment starts */
            nout++;
        }
        else
        {
            *b = p;
            nin++;
        }
    }
    return nout == 1 && nin == 1;
}

/* Whether p lies on the sides of the block square [0, S]^2. */
static int on_square(wm_pt p, int32_t S)
{
    return p.x == 0 || p.y == 0 || p.x == S || p.y == S;
}

/* Position along the square, counter-clockwise from (0,0). */
static int64_t perim(wm_pt p, int32_t S)
{
    if (p.y == 0)
        return p.x;
    if (p.x == S)
        return (int64_t)S + p.y;
    if (p.y == S)
        return 2 * (int64_t)S + (S - p.x);
    return 3 * (int64_t)S + (S - p.y);
}

typedef struct
{
    int64_t pos;
    size_t seg; /* first segment of the chain */
} entry;

static int cmp_entry(const void *a, const void *b)
{
    const int64_t x = ((const entry *)a)->pos, y = ((const entry *)b)->pos;
    return (x > y) - (x < y);
}

/* The cell across side `side` of cell (c, r). */
static const int32_t side_dc[4] = {0, 1, 0, -1}, side_dr[4] = {-1, 0, 1, 0};

/* Whether segment i's in edge (in == 1) or out edge (in == 0) is linked
 * through the hash: it lies on a side of its tile (the cell across it in
 * another tile or off the block), or on an ambiguous cell. */
static int crosses_tile(const state *s, size_t i, int in)
{
    const seg *g = &s->segs[i];
    if (g->flags & (in ? LINK_IN : LINK_OUT))
        return 1;
    const int side = in ? g->iside : g->oside;
    const int32_t c = g->c + side_dc[side], r = g->r + side_dr[side];
    /* tiles are WM_TILE-aligned: same tile when the same tile index */
    return c < 0 || r < 0 || c / WM_TILE != g->c / WM_TILE ||
           r / WM_TILE != g->r / WM_TILE;
}

/* Links the segments whose out edge is inside their tile and lists in bnd
 * the segments with an edge on a tile side. Returns how many. */
static size_t link_tiles(state *s, size_t *bnd)
{
    uint32_t first[WM_TILE * WM_TILE]; /* 1 + offset of the cell's first */
    size_t nbnd = 0;
    memset(first, 0, sizeof first);
    for (size_t t = 0; t < s->ntiles; t++)
    {
        const tilesegs *ts = &s->tiles[t];
        /* a cell's segments are consecutive: the first one is enough */
        for (size_t i = ts->s1; i-- > ts->s0;)
            first[(s->segs[i].r - ts->r0) * WM_TILE + (s->segs[i].c - ts->c0)] =
                (uint32_t)(i - ts->s0 + 1);
        for (size_t i = ts->s0; i < ts->s1; i++)
        {
            seg *g = &s->segs[i];
            const int out_crosses = crosses_tile(s, i, 0);
            if (out_crosses || crosses_tile(s, i, 1))
                bnd[nbnd++] = i;
            if (out_crosses)
                continue;
            const int32_t c = g->c + side_dc[g->oside];
            const int32_t r = g->r + side_dr[g->oside];
            const uint32_t f0 = first[(r - ts->r0) * WM_TILE + (c - ts->c0)];
            for (size_t j = ts->s0 + f0 - 1; f0 && j < ts->s1; j++)
            {
                if (s->segs[j].c != c || s->segs[j].r != r)
                    break;
                if (s->segs[j].iside == ((g->oside + 2) & 3)) /* across */
                {
                    g->next = (uint32_t)j;
                    s->segs[j].flags |= HAS_PRED;
                    break;
                }
            }
        }
        for (size_t i = ts->s0; i < ts->s1; i++)
            first[(s->segs[i].r - ts->r0) * WM_TILE + (s->segs[i].c - ts->c0)] =
                0;
    }
    return nbnd;
}

/* Rows of tile t's cells among the sorted keys k[0 .. n) as bit masks
 * (mask[row], bit: column in the tile); *at walks the keys tile by tile.
 * Returns whether there is any. */
static int cells_of_tile(const uint64_t *k, size_t n, size_t t, size_t *at,
                         uint64_t *mask)
{
    int has = 0;
    memset(mask, 0, WM_TILE * sizeof *mask);
    while (*at < n && (k[*at] >> 32) < t)
        (*at)++;
    for (; *at < n && (k[*at] >> 32) == t; (*at)++)
    {
        const uint32_t local = (uint32_t)(k[*at] & 0xffffffffu);
        mask[local / WM_TILE] |= UINT64_C(1) << (local % WM_TILE);
        has = 1;
    }
    return has;
}

/* Segments s0.. of the tile from cell (c0, r0) whose cells are set in
 * lmask: an in or out edge takes its exact crossing where one is listed;
 * on a side of an ambiguous cell it is linked through the hash. */
static void mark_links(state *s, const wm_field *f, size_t s0, int32_t c0,
                       int32_t r0, const uint64_t *lmask)
{
    for (size_t i = s0; i < s->nsegs; i++)
    {
        seg *g = &s->segs[i];
        if (!((lmask[g->r - r0] >> (g->c - c0)) & 1))
            continue;
        for (int in = 0; in < 2; in++)
        {
            const int side = in ? g->iside : g->oside;
            if (wm_hidden_is_cell(&s->hid, f, g->c + side_dc[side],
                                  g->r + side_dr[side]))
                g->flags |= in ? LINK_IN : LINK_OUT;
            wm_hidden_side_crossing(&s->hid, f, g->c, g->r, side,
                                    in ? &g->in_pt : &g->out_pt);
        }
    }
}

/* The segments of the cells of the k-th mixed tile (tile-major order) that
 * are not ambiguous; hc[0] walks the ambiguous cells, hc[1] the linked
 * ones. Returns 0 when out of memory. */
static int tile_segments(state *s, const wm_field *f, size_t k, size_t *hc)
{
    const size_t t = f->mixed_tile[k];
    const uint64_t *bits = wm_field_bits(f, k);
    const int32_t n = s->n;
    const int32_t c0 = (int32_t)(t % (size_t)f->ntx) * WM_TILE;
    const int32_t r0 = (int32_t)(t / (size_t)f->ntx) * WM_TILE;
    const int32_t c1 = c0 + WM_TILE < n ? c0 + WM_TILE : n;
    const int32_t r1 = r0 + WM_TILE < n ? r0 + WM_TILE : n;
    if (!wm_grow((void **)&s->tiles, &s->tcap, s->ntiles + 1, sizeof *s->tiles))
        return 0;
    const size_t s0 = s->nsegs;
    /* ambiguous cells are done apart (cmask: per row of the tile) */
    uint64_t cmask[WM_TILE];
    cells_of_tile(s->hid.cell, s->hid.ncell, t, &hc[0], cmask);
    /* water bits of the tile's sample rows; a cell needs work only where
     * its four corner bits differ */
    uint64_t below = bits[0];
    for (int32_t r = r0; r < r1; r++)
    {
        const float *row = f->val[t] + (r - r0) * (WM_TILE + 1);
        const uint64_t above = bits[2 * (r - r0 + 1)];
        uint64_t mixed =
            (below ^ (below >> 1)) | (above ^ (above >> 1)) | (below ^ above);
        mixed &= ((UINT64_C(1) << (c1 - c0)) - 1) & ~cmask[r - r0];
        while (mixed)
        {
            const int32_t q = __builtin_ctzll(mixed);
            mixed &= mixed - 1;
            if (!cell(s, c0 + q, r, row + q))
                return 0;
        }
        below = above;
    }
    if (cells_of_tile(s->hid.link, s->hid.nlink, t, &hc[1], cmask))
        mark_links(s, f, s0, c0, r0, cmask);
    const tilesegs ts = {s0, s->nsegs, c0, r0};
    s->tiles[s->ntiles++] = ts;
    return 1;
}

/* wm_segment_fn for the segments of an ambiguous cell: linked through the
 * hash at both ends (their cell is not used). */
static int push_ambiguous(void *user, wm_pt a, wm_pt b)
{
    state *s = user;
    if (!push_seg(s, a, b, 0, 0, 0, 0))
        return 0;
    s->segs[s->nsegs - 1].flags = LINK_IN | LINK_OUT;
    return 1;
}

wm_status wm_contour_extract(const wm_field *f, wm_rings *out,
                             const wm_ctx *ctx)
{
    return wm_contour_extract_probed(f, NULL, out, ctx);
}

static wm_status nomem(const wm_ctx *ctx)
{
    return wm_fail(ctx, WM_ERR_NOMEM, "out of memory extracting contours");
}

/* Step 1: the segments of every mixed tile's cells, then those of the
 * ambiguous cells (rebuilt exactly from the probe's inputs); *ntileseg:
 * how many came from the tiles. */
static wm_status all_segments(state *s, const wm_field *f, wm_probe *probe,
                              size_t *ntileseg, const wm_ctx *ctx)
{
    wm_status st;
    if (probe && (st = wm_hidden_find(f, probe, &s->hid, ctx)) != WM_OK)
        return st;
    size_t hc[2] = {0, 0}; /* ambiguous and linked cells of the tiles so far */
    for (size_t k = 0; k < f->mixed; k++)
    {
        if (wm_cancelled(ctx))
            return wm_fail(ctx, WM_ERR_CANCELLED, "cancelled");
        wm_field_prefetch_tile(f, k + 1);
        if (!tile_segments(s, f, k, hc))
            return nomem(ctx);
    }
    *ntileseg = s->nsegs;
    if (s->hid.ncell && (st = wm_hidden_cells(f, probe, &s->hid, push_ambiguous,
                                              s, ctx)) != WM_OK)
        return st == WM_ERR_CANCELLED ? wm_fail(ctx, st, "cancelled")
                                      : nomem(ctx);
    return s->nsegs < NO_SEG ? WM_OK : nomem(ctx); /* links: 32 bits */
}

/* Whether the direction v lies before w turning clockwise from ref (all
 * three nonzero lattice vectors; ref itself comes last). */
static int cw_before(int64_t rx, int64_t ry, int64_t vx, int64_t vy, int64_t wx,
                     int64_t wy)
{
    /* half 0: clockwise of ref by (0, pi], half 1: by (pi, 2 pi] */
    const int64_t cv = rx * vy - ry * vx, cw = rx * wy - ry * wx;
    const int hv = cv > 0 || (cv == 0 && rx * vx + ry * vy > 0);
    const int hw = cw > 0 || (cw == 0 && rx * wx + ry * wy > 0);
    if (hv != hw)
        return hv < hw;
    return vx * wy - vy * wx < 0;
}

/* Whether segment j, rather than k, follows segment i, all three meeting
 * at i's out point: a point where the boundary touches itself (two
 * crossings rounded to one point of a dividing segment) has two segments
 * in and two out, and each in goes on along the water on its left, to the
 * first out clockwise from it, so the rings touch there and never cross. A
 * segment already taken comes after one that is not. */
static int takes_before(const state *s, size_t i, size_t j, size_t k)
{
    const seg *g = &s->segs[i], *a = &s->segs[j], *b = &s->segs[k];
    const int ta = (a->flags & HAS_PRED) != 0, tb = (b->flags & HAS_PRED) != 0;
    if (ta != tb)
        return ta < tb;
    return cw_before(
        (int64_t)g->in_pt.x - g->out_pt.x, (int64_t)g->in_pt.y - g->out_pt.y,
        (int64_t)a->out_pt.x - a->in_pt.x, (int64_t)a->out_pt.y - a->in_pt.y,
        (int64_t)b->out_pt.x - b->in_pt.x, (int64_t)b->out_pt.y - b->in_pt.y);
}

/* Step 2b: links the segments of bnd[0 .. nbnd) whose out edge crosses
 * into another tile (or an ambiguous cell) to the one whose in edge is the
 * same crossing, through an open-addressing hash of the crossings
 * (wm_pt_key: a crossing lies on one cell edge, or inside an ambiguous
 * cell, and both segments compute it alike); 0 when out of memory. */
static int link_across(state *s, const size_t *bnd, size_t nbnd)
{
    size_t hcap = 16;
    while (hcap < 2 * nbnd + 2)
        hcap *= 2;
    size_t *slot = malloc(hcap * sizeof *slot);
    if (!slot)
        return 0;
    for (size_t i = 0; i < hcap; i++)
        slot[i] = SIZE_MAX;
    for (size_t b = 0; b < nbnd; b++)
    {
        const size_t i = bnd[b];
        if (!crosses_tile(s, i, 1))
            continue;
        size_t h = wm_hash64(wm_pt_key(s->segs[i].in_pt), hcap - 1);
        while (slot[h] != SIZE_MAX)
            h = (h + 1) & (hcap - 1);
        slot[h] = i;
    }
    for (size_t b = 0; b < nbnd; b++)
    {
        const size_t i = bnd[b];
        if (!crosses_tile(s, i, 0))
            continue;
        const uint64_t key = wm_pt_key(s->segs[i].out_pt);
        size_t best = SIZE_MAX;
        for (size_t h = wm_hash64(key, hcap - 1); slot[h] != SIZE_MAX;
             h = (h + 1) & (hcap - 1))
            if (wm_pt_key(s->segs[slot[h]].in_pt) == key &&
                (best == SIZE_MAX || takes_before(s, i, slot[h], best)))
                best = slot[h];
        if (best != SIZE_MAX)
        {
            s->segs[i].next = (uint32_t)best;
            s->segs[best].flags |= HAS_PRED;
        }
    }
    free(slot);
    return 1;
}

/* Step 2: every segment's next, inside a tile through a map from cell to
 * its first segment (link_tiles), across tiles through the hash. */
static int link_all(state *s, size_t ntileseg)
{
    size_t *bnd = malloc((s->nsegs + 1) * sizeof *bnd);
    if (!bnd)
        return 0;
    size_t nbnd = link_tiles(s, bnd);
    for (size_t i = ntileseg; i < s->nsegs; i++)
        bnd[nbnd++] = i;
    const int ok = link_across(s, bnd, nbnd);
    free(bnd);
    return ok;
}

/* Step 3: the chain starts, sorted by their place on the block square's
 * perimeter (side S) into ent[0 .. *nent); a chain that starts or ends
 * inside the block is a linking fault, never closed along it. */
static wm_status chain_starts(const state *s, int32_t S, entry *ent,
                              size_t *nent, const wm_ctx *ctx)
{
    *nent = 0;
    for (size_t i = 0; i < s->nsegs; i++)
    {
        const seg *g = &s->segs[i];
        if ((!(g->flags & HAS_PRED) && !on_square(g->in_pt, S)) ||
            (g->next == NO_SEG && !on_square(g->out_pt, S)))
            return wm_fail(ctx, WM_ERR_INTERNAL,
                           "contour: a chain ends inside the block");
        if (!(g->flags & HAS_PRED))
        {
            ent[*nent].pos = perim(g->in_pt, S);
            ent[*nent].seg = i;
            (*nent)++;
        }
    }
    qsort(ent, *nent, sizeof *ent, cmp_entry);
    return WM_OK;
}

/* Walks the square counter-clockwise from exit position p (of perimeter
 * 4 S) to the next entry of ent[0 .. nent), adding the corners passed;
 * returns that entry's index, or SIZE_MAX when out of memory. */
static size_t along_square(const entry *ent, size_t nent, int64_t p, int32_t S,
                           wm_rings *out)
{
    size_t lo = 0, hi = nent; /* first entry with pos > p */
    while (lo < hi)
    {
        const size_t mid = (lo + hi) / 2;
        if (ent[mid].pos > p)
            hi = mid;
        else
            lo = mid + 1;
    }
    const size_t nx = lo == nent ? 0 : lo;
    const int64_t q = ent[nx].pos + (nx == lo ? 0 : 4 * (int64_t)S);
    for (int64_t k = 1; k <= 8; k++)
    {
        const int64_t cpos = (p / S + k) * S;
        if (cpos >= q)
            break;
        const int64_t m = (cpos / S) & 3;
        const wm_pt corner = {m == 1 || m == 2 ? S : 0, m >= 2 ? S : 0};
        if (wm_rings_push(out, corner) != WM_OK)
            return SIZE_MAX;
    }
    return nx;
}

/* Step 4: the rings of the chains that start on the square, closed along
 * it. */
static wm_status open_chains(state *s, const entry *ent, size_t nent, int32_t S,
                             wm_rings *out, const wm_ctx *ctx)
{
    for (size_t e = 0; e < nent; e++)
    {
        if (s->segs[ent[e].seg].flags & USED)
            continue;
        for (size_t cur = e; !(s->segs[ent[cur].seg].flags & USED);)
        {
            size_t g = ent[cur].seg, last = g;
            if (wm_rings_push(out, s->segs[g].in_pt) != WM_OK)
                return nomem(ctx);
            for (; g != NO_SEG; g = s->segs[g].next)
            {
                if (s->segs[g].flags & USED)
                    return wm_fail(ctx, WM_ERR_INTERNAL,
                                   "contour: chain loops");
                s->segs[g].flags |= USED;
                last = g;
                if (wm_rings_push(out, s->segs[g].out_pt) != WM_OK)
                    return nomem(ctx);
            }
            cur =
                along_square(ent, nent, perim(s->segs[last].out_pt, S), S, out);
            if (cur == SIZE_MAX)
                return nomem(ctx);
        }
        if (wm_rings_close(out) != WM_OK)
            return nomem(ctx);
    }
    return WM_OK;
}

/* Step 5: the rings of the closed loops inside the block. */
static wm_status closed_loops(state *s, wm_rings *out, const wm_ctx *ctx)
{
    for (size_t i = 0; i < s->nsegs; i++)
    {
        if (s->segs[i].flags & USED)
            continue;
        for (size_t g = i; !(s->segs[g].flags & USED); g = s->segs[g].next)
        {
            if (s->segs[g].next == NO_SEG)
                return wm_fail(ctx, WM_ERR_INTERNAL, "contour: open chain");
            s->segs[g].flags |= USED;
            if (wm_rings_push(out, s->segs[g].out_pt) != WM_OK)
                return nomem(ctx);
        }
        if (wm_rings_close(out) != WM_OK)
            return nomem(ctx);
    }
    return WM_OK;
}

/* Step 6: with no crossing on the square at all, the square is water or
 * land: one ring, or none. */
static wm_status whole_square(const wm_field *f, int32_t S, wm_rings *out,
                              const wm_ctx *ctx)
{
    if (wm_field_at(f, 0, 0) > 0)
        return WM_OK;
    const wm_pt sq[4] = {{0, 0}, {S, 0}, {S, S}, {0, S}};
    for (int k = 0; k < 4; k++)
        if (wm_rings_push(out, sq[k]) != WM_OK)
            return nomem(ctx);
    return wm_rings_close(out) == WM_OK ? WM_OK : nomem(ctx);
}

/* Hands the probe the cells whose segments took exact crossings: the
 * ambiguous ones and the linked ones, merged (both sorted). */
static int keep_rebuilt(const wm_hidden *h, wm_probe *probe)
{
    free(probe->rebuilt);
    probe->nrebuilt = 0;
    probe->rebuilt = malloc((h->ncell + h->nlink + 1) * sizeof *probe->rebuilt);
    if (!probe->rebuilt)
        return 0;
    size_t i = 0, j = 0, n = 0;
    while (i < h->ncell || j < h->nlink)
    {
        const uint64_t a = i < h->ncell ? h->cell[i] : UINT64_MAX;
        const uint64_t b = j < h->nlink ? h->link[j] : UINT64_MAX;
        probe->rebuilt[n++] = a < b ? a : b;
        i += a <= b;
        j += b <= a;
    }
    probe->nrebuilt = n;
    return 1;
}

wm_status wm_contour_extract_probed(const wm_field *f, wm_probe *probe,
                                    wm_rings *out, const wm_ctx *ctx)
{
    wm_rings_clear(out);
    if (f->w != f->h || f->w < 2 || (int64_t)(f->w - 1) * WM_Q > WM_LOCAL_MAX)
        return wm_fail(ctx, WM_ERR_INVALID, "contour: bad block field");
    state s;
    memset(&s, 0, sizeof s);
    s.n = f->w - 1;
    const int32_t S = s.n * WM_Q;
    entry *ent = NULL;
    size_t ntileseg = 0, nent = 0;
    wm_status st = all_segments(&s, f, probe, &ntileseg, ctx);
    if (st == WM_OK && (!link_all(&s, ntileseg) ||
                        !(ent = malloc((s.nsegs + 1) * sizeof *ent))))
        st = nomem(ctx);
    if (st == WM_OK)
        st = chain_starts(&s, S, ent, &nent, ctx);
    if (st == WM_OK)
        st = open_chains(&s, ent, nent, S, out, ctx);
    if (st == WM_OK)
        st = closed_loops(&s, out, ctx);
    if (st == WM_OK && nent == 0)
        st = whole_square(f, S, out, ctx);
    if (st == WM_OK && probe && !keep_rebuilt(&s.hid, probe))
        st = nomem(ctx);
    free(s.segs);
    free(s.tiles);
    wm_hidden_free(&s.hid);
    free(ent);
    return st;
}
