/*
 * field.cl - the signed distance field of a batch of tiles (OpenCL C 1.2),
 * the same function as the C path's wm_field_eval_c (src/core/field.c).
 *
 * Work: one work-item per tile sample; dimension 0 runs over the
 * WM_TS1 x WM_TS1 samples of a tile (padded to the local size), dimension 1
 * over the tiles of the batch. A sample's value is
 *   min( band, min_rivers |p - seg| - r, min_groups (+/-) min_edges
 *        |p - edge| ), clamped below at -band, in pixels,
 * a group being one lake polygon's edges in reach of the tile, its sign
 * the polygon's even-odd parity at the sample (a host-computed bit mask).
 *
 * This kernel runs where the device has no doubles (consumer GPUs);
 * wm_field_tiles_f64 below, the C path's double operations bit for bit,
 * where it has (cl_khr_fp64). Precision without doubles: the host gives
 * every coordinate as a lattice integer relative to the tile's sample
 * (0, 0), |x| < 2^30, so every difference, dot and cross product is exact
 * in 64-bit integers. Floating point enters only in quotients whose
 * numerator is already small near the shore:
 *   beside the segment:  |p - seg| - r = (|cross| - r |ab|) / |ab|
 *   past an end point q:  |p - q| - r  = (|pq|^2 - r^2) / (|pq| + r)
 * where |cross| and |pq|^2 are exact integers and r |ab|, r^2 come from the
 * host split into an integer part and a float fraction, so the numerator
 * is rounded once, relative to itself. Within the band the error is a few
 * float ulps of the band, about 1e-6 px, however wide the river or far the
 * end point: the C path's double result is matched to well under 1e-4 px.
 * Values far outside the band lose relative precision only and are clamped
 * anyway. No contraction (FP_CONTRACT OFF), no fast-math build options: a
 * sample's value is the same in every tile and work-group that computes it
 * (DESIGN invariant 2 on this path).
 */
#pragma OPENCL FP_CONTRACT OFF

#define WM_Q 256
#define WM_TS1 33

/* Where sample p lies against segment g = (ax, ay, bx, by): past an end
 * point (returns 1, *q2 = |p - that end|^2) or beside the segment (returns
 * 0, *cr = |cross(b - a, p - a)|). Exact in 64-bit integers. */
static int locate(const long px, const long py, const int4 g, long *q2,
                  long *cr)
{
    const long abx = (long)g.z - g.x, aby = (long)g.w - g.y;
    const long apx = px - g.x, apy = py - g.y;
    const long dot = apx * abx + apy * aby;
    if (dot <= 0 || dot >= abx * abx + aby * aby)
    {
        const long qx = dot <= 0 ? apx : px - g.z;
        const long qy = dot <= 0 ? apy : py - g.w;
        *q2 = qx * qx + qy * qy;
        return 1;
    }
    const long c = abx * apy - aby * apx;
    *cr = c < 0 ? -c : c;
    return 0;
}

/* Rivers: xy = (ax, ay, bx, by) relative to the tile; k = (integer part of
 * r |ab|, integer part of r^2); f = (fraction of r |ab|, fraction of r^2,
 * r, |ab|). Lakes: edge_xy likewise, edge_len = |ab|. All lengths in
 * lattice units. */
__kernel void wm_field_tiles(const uint ntiles, const float bandl,
                             __global const uint *seg_start,
                             __global const int4 *seg_xy,
                             __global const long2 *seg_k,
                             __global const float4 *seg_f,
                             __global const uint *grp_start,
                             __global const uint *edge_start,
                             __global const int4 *edge_xy,
                             __global const float *edge_len,
                             __global const ulong *mask,
                             __global float *val)
{
    const uint i = (uint)get_global_id(0);
    const uint t = (uint)get_global_id(1);
    if (i >= WM_TS1 * WM_TS1 || t >= ntiles)
        return;
    const int q = (int)(i % WM_TS1), j = (int)(i / WM_TS1);
    const long px = (long)q * WM_Q, py = (long)j * WM_Q;
    float v = bandl;

    for (uint k = seg_start[t]; k < seg_start[t + 1]; k++)
    {
        const float4 c = seg_f[k];
        long q2, cr;
        float d;
        if (locate(px, py, seg_xy[k], &q2, &cr))
        {
            const float num = (float)(q2 - seg_k[k].y) - c.y;
            const float den = sqrt((float)q2) + c.z;
            d = den > 0.0f ? num / den : 0.0f;
        }
        else
            d = ((float)(cr - seg_k[k].x) - c.x) / c.w;
        v = d < v ? d : v;
    }

    for (uint g = grp_start[t]; g < grp_start[t + 1]; g++)
    {
        float du = INFINITY;
        for (uint e = edge_start[g]; e < edge_start[g + 1]; e++)
        {
            long q2, cr;
            const float d = locate(px, py, edge_xy[e], &q2, &cr)
                                 ? sqrt((float)q2)
                                 : (float)cr / edge_len[e];
            du = d < du ? d : du;
        }
        const float d = (mask[(size_t)g * WM_TS1 + (size_t)j] >> q) & 1 ? -du
                                                                       : du;
        v = d < v ? d : v;
    }
    v = v < -bandl ? -bandl : v;
    val[(size_t)t * (WM_TS1 * WM_TS1) + i] = v * (1.0f / WM_Q);
}

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable

/* wm_field_tiles_f64: the same field in double precision, operation for
 * operation the C path's (field.c: seg_d2, river_min, edge_min2, lake_min,
 * clamp_out), so every value is bit-identical to it (IEEE double: +, -, *,
 * / and sqrt correctly rounded, no contraction). Every sample is
 * evaluated against every item of its tile; the C path's narrow band and
 * row spans skip only terms that cannot change a clamped value. Devices
 * without cl_khr_fp64 run wm_field_tiles above. */

/* Squared distance from p to segment [0, ab] (p relative to a); inv =
 * 1 / |ab|^2, or 0 for a point (field.c's seg_d2). */
static double seg_d2(const double px, const double py, const double abx,
                     const double aby, const double inv)
{
    double t = (px * abx + py * aby) * inv;
    t = t < 0.0 ? 0.0 : t;
    t = t > 1.0 ? 1.0 : t;
    const double dx = px - t * abx, dy = py - t * aby;
    return dx * dx + dy * dy;
}

/* Segment g (relative to its tile) seen from the tile's sample (q, j), as
 * field.c forms it: p - a, b - a, |b - a|^2 and its inverse (0 for a
 * point). */
typedef struct
{
    double px, py, abx, aby, len2, inv;
} seg_view;

static seg_view view_of(const int4 g, const int q, const int j)
{
    seg_view s;
    s.abx = (double)((long)g.z - g.x);
    s.aby = (double)((long)g.w - g.y);
    s.len2 = s.abx * s.abx + s.aby * s.aby;
    s.inv = s.len2 > 0.0 ? 1.0 / s.len2 : 0.0;
    s.px = (double)(-(long)g.x) + (double)q * WM_Q;
    s.py = (double)(-(long)g.y) + (double)j * WM_Q;
    return s;
}

/* Rivers: seg_xy as above, seg_r their radii (lattice units); lakes:
 * edge_xy. */
__kernel void wm_field_tiles_f64(const uint ntiles, const double bandl,
                                 __global const uint *seg_start,
                                 __global const int4 *seg_xy,
                                 __global const double *seg_r,
                                 __global const uint *grp_start,
                                 __global const uint *edge_start,
                                 __global const int4 *edge_xy,
                                 __global const ulong *mask,
                                 __global float *val)
{
    const uint i = (uint)get_global_id(0);
    const uint t = (uint)get_global_id(1);
    if (i >= WM_TS1 * WM_TS1 || t >= ntiles)
        return;
    const int q = (int)(i % WM_TS1), j = (int)(i / WM_TS1);
    double v = bandl;

    for (uint k = seg_start[t]; k < seg_start[t + 1]; k++)
    {
        const seg_view g = view_of(seg_xy[k], q, j);
        const double d =
            sqrt(seg_d2(g.px, g.py, g.abx, g.aby, g.inv)) - seg_r[k];
        v = d < v ? d : v;
    }

    for (uint g = grp_start[t]; g < grp_start[t + 1]; g++)
    {
        double du2 = INFINITY;
        for (uint e = edge_start[g]; e < edge_start[g + 1]; e++)
        {
            const seg_view c = view_of(edge_xy[e], q, j);
            /* a sample on the edge is exactly 0 away (field.c) */
            const double dot = c.px * c.abx + c.py * c.aby;
            const double d2 = c.len2 > 0.0 && c.px * c.aby == c.py * c.abx &&
                                      dot >= 0.0 && dot <= c.len2
                    ? 0.0
                    : seg_d2(c.px, c.py, c.abx, c.aby, c.inv);
            du2 = d2 < du2 ? d2 : du2;
        }
        const double sign =
            1.0 - 2.0 * (double)((mask[(size_t)g * WM_TS1 + (size_t)j] >> q) &
                                 1);
        const double d = sign * sqrt(du2);
        v = d < v ? d : v;
    }
    v = v < -bandl ? -bandl : v;
    val[(size_t)t * (WM_TS1 * WM_TS1) + i] = (float)(v / WM_Q);
}
#endif
