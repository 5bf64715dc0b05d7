"""Seeded adversarial scenes for sub-pixel topology (issue 12).

Every scene is small (a few blocks of BLOCK_SIZE = 64 m at PIXEL_SIZE =
0.5 m, i.e. 128 x 128 samples per block) and built around one "feature of
interest" whose exact shape the lattice cannot resolve by sampling alone:

  wedge     two rivers (widths 1-6 m) sharing their start vertex and
            diverging at 1-30 degrees, long enough that the land wedge
            between them grows to 3.5-5 px; sometimes a wider trunk river
            ends at the shared vertex (a confluence), sometimes the two
            branches are one polyline (a hairpin bend); at 1 degree the rivers
            are up to ~230 m long. The feature of
            interest is the exact tip of the land wedge.
  parallel  two near-parallel rivers (widths 1-8 m) whose banks leave a land
            strip 0.01-3 px wide (log-uniform), at a random angle to the
            grid (a quarter of them within 2 degrees of an axis); half of
            them converge so that the strip ends in a tip (then the rivers
            overlap past it), a quarter of the others are closed by two
            cross rivers so the strip becomes a long thin island (a hole).
  island    either a lake (radius 6-20 m) with 1-3 islands (holes) of
            diameter 0.1-2 px, or a triangular island of diameter 0.1-3 px
            enclosed by three rivers (each river's bank runs exactly along
            one side of the triangle, so the exact hole is the triangle).
  subpixel  a meandering river 0.1-0.8 px wide and 1-2 lakes of diameter
            0.1-1 px (a polygon of 3-12 vertices) nearby.
  shore     a lake whose boundary passes through samples (a rectangle with
            its corners on samples and an edge along a sample row or
            column, or a triangle with its apex on a sample) and a river
            (width 0.5-6 m) whose bank runs 0.01-1.5 px from that edge or
            apex, tilted by up to 3 degrees: a land strip thinner than a
            pixel along a boundary whose samples have distance 0 (real
            shores digitised on round coordinates do this). Not part of
            the seam family's draw.
  grid      shores on the block grid (about a block corner): a rectangle
            lake with sides on block lines (water on one side of them), a
            rectangle cut along the lines into 2 or 4 lakes sharing their
            edges (tiled hydrography), a river whose bank runs along a line
            (sometimes with a lake touching it from across), a triangle
            whose apex lies on a block corner or side; two times in five a
            river passing by. Rotated by quarter turns.
  mosaic    a lake of diameter 12-40 m cut along one or two lines into
            pieces that share their edges inside the union (riverbank
            polygons, tiled lakes), or one time in four lie 0.01-1.5 px
            apart (a land strip); one to three rivers (0.5-6 m) cross it,
            some ending inside.
  twins     inputs that coincide: a lake given twice, a lake with a hole
            and a lake filling it, a river given twice (once reversed), a
            river whose bank or centre line runs along a lake edge, a river
            that loops with a repeated vertex; two times in three a river
            crossing.
  spike     a lake's own sharp features: a spike of water (a convex corner
            of half-angle 0.3-15 degrees), a notch of land as sharp cut
            into it, or two lobes joined by a channel 0.05-1.5 px wide;
            half the time a river passing by or through.
  cluster   2-6 short rivers (2-4 vertices, 0.05-2 px wide, log-uniform)
            and 0-3 lakes (0.1-3 px across, 3-8 vertices) at random within
            a square of 1, 2 or 4 px: many sub-pixel features, crossings,
            islands, wedges and near misses in a few cells at once; two
            times in five on a block side or corner (placed as the seam
            family's).
  shoal     thin features along the sample grid: a lake with 1-3 islands
            0.03-0.4 px wide 0.05-0.6 px from its straight shore and each
            other, a stack of 2-4 lakes 0.03-0.5 px wide 0.02-0.5 px
            apart, or both; along a sample row or at up to 3 degrees.
  seam      one of the four above with its feature of interest moved onto a
            block side (or, one time in five, a block corner): exactly on it
            one time in four, else within +-0.4 of the feature's size (at
            least +-0.5 px) of it.

Outside the seam, grid and cluster families the feature of interest lies
inside block (0, 0) of the scene (origin ORIGIN, a corner of the global 64 m
block grid), at least 12 m from its sides; long rivers still cross other
blocks. The grid family's lies on a block corner, the seam family's (and two
in five of the cluster family's) on a side or a corner of the grid of its
own block size.

All vertex coordinates are snapped to the driver's lattice (PIXEL_SIZE /
256, exactly representable in binary), so the driver and the GEOS oracle see
exactly the same input geometry, even for gaps of a few lattice units.
Everything is deterministic: random.Random('<family>:<seed>').

    make_scene(path, family, seed) -> open options (dict)
    scene_features(family, seed) -> (rivers, lakes, meta)
    describe(family, seed) -> one line with the scene's parameters

The second half measures a run against the oracle the way issue 12 counts
defects (measure(), topology_figures(): Hausdorff and its 99th percentile,
specks, lost small features, ring counts, symmetric difference), for
autotest/test_topology.py and bench/topology.py.
"""

import math
import os
import random
from collections import Counter, defaultdict

import numpy as np
from osgeo import ogr
from shapely.geometry import (GeometryCollection, LinearRing, MultiPolygon, Point,
                              Polygon, box)
from shapely.ops import unary_union

import oracle
import scenes

PIXEL_SIZE = 0.5
BLOCK_SIZE = 64.0
LATTICE_Q = 256  # WM_Q: lattice points per pixel
THIN_UNITS = 0.5  # block.c's WM_THIN: rings thinner (2 area / perimeter, units) are rounding
EPSG = scenes.SCENE_EPSG  # 32631
# a corner of the global block grid near scenes.SCENE_ORIGIN
# (400000 / 64 = 6250, 4699968 / 64 = 73437)
ORIGIN = (400000.0, 4699968.0)

BASE_FAMILIES = ('wedge', 'parallel', 'island', 'subpixel')
FAMILIES = BASE_FAMILIES + ('seam', 'shore', 'grid', 'mosaic', 'twins', 'spike', 'cluster',
                            'shoal')


# ----------------------------------------------------------------------------
# small helpers
# ----------------------------------------------------------------------------

def _log_uniform(rng, lo, hi):
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def _rot(p, a):
    c, s = math.cos(a), math.sin(a)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def _add(p, q):
    return (p[0] + q[0], p[1] + q[1])


def _ngon(rng, cx, cy, diameter, n, rough=0.15):
    """Closed counter-clockwise ring of n vertices around (cx, cy), radii
    within +-rough of diameter / 2, random rotation."""
    a0 = rng.uniform(0, 2 * math.pi)
    pts = []
    for i in range(n):
        t = a0 + 2 * math.pi * i / n
        r = 0.5 * diameter * (1.0 + rng.uniform(-rough, rough))
        pts.append((cx + r * math.cos(t), cy + r * math.sin(t)))
    pts.append(pts[0])
    return pts


def _line_intersection(n1, c1, n2, c2):
    """Point P with n1 . P = c1 and n2 . P = c2."""
    det = n1[0] * n2[1] - n1[1] * n2[0]
    return ((c1 * n2[1] - c2 * n1[1]) / det, (n1[0] * c2 - n2[0] * c1) / det)


# ----------------------------------------------------------------------------
# families; each returns geometry in local coordinates around the feature of
# interest at (0, 0): rivers [(pts, width)], lakes [(shell, [holes])], meta
# (meta['scale']: size of the feature in m, for the seam placement)
# ----------------------------------------------------------------------------

def _wedge(rng, px):
    theta = _log_uniform(rng, 1.0, 30.0)
    h = math.radians(theta) / 2.0
    w1, w2 = rng.uniform(1.0, 6.0), rng.uniform(1.0, 6.0)
    hairpin = rng.random() < 0.25
    if hairpin:
        w2 = w1
    target = rng.uniform(3.5, 5.0) * px          # land width reached at the far end
    reach = target / (2.0 * math.tan(h))         # bisector distance tip -> that width
    max_len = 200.0
    # tip of the land wedge, bisector along +x, V = (0, 0); x_tip ~ (r1 + r2) / (2 sin h)
    x_tip = (w1 + w2) / 4.0 / math.sin(h)
    if x_tip + reach > max_len:                  # shrink the widths (not below 1 m)
        k = max((max_len - reach) / x_tip, 1.0 / min(w1, w2))
        w1, w2 = w1 * k, w2 * k
    r1, r2 = w1 / 2.0, w2 / 2.0
    # upper ray (cos h, sin h), outward normal (-sin h, cos h); lower ray mirrored
    n1, n2 = (-math.sin(h), math.cos(h)), (-math.sin(h), -math.cos(h))
    tip = _line_intersection(n1, -r1, n2, -r2)
    length = (tip[0] + reach) / math.cos(h) + rng.uniform(2.0, 10.0)
    e1 = (length * math.cos(h), length * math.sin(h))
    e2 = (length * math.cos(h), -length * math.sin(h))
    phi = rng.uniform(0, 2 * math.pi)

    def loc(p):  # wedge frame -> local frame with the tip at (0, 0)
        return _rot((p[0] - tip[0], p[1] - tip[1]), phi)
    v = loc((0.0, 0.0))
    rivers = []
    if hairpin:
        rivers.append(([loc(e1), v, loc(e2)], w1))
    else:
        rivers.append(([v, loc(e1)], w1))
        rivers.append(([v, loc(e2)], w2))
    trunk = rng.random() < 0.5
    if trunk:
        tw = max(w1, w2) * rng.uniform(1.0, 1.5)
        ta = math.pi + math.radians(rng.uniform(-20.0, 20.0))
        tl = rng.uniform(20.0, 40.0)
        rivers.insert(0, ([loc((tl * math.cos(ta), tl * math.sin(ta))), v], tw))
    meta = dict(angle_deg=theta, widths=(w1, w2), hairpin=hairpin, trunk=trunk,
                tip_slope=2.0 * math.tan(h),
                tip_from_vertex_m=math.hypot(*tip), length_m=length, scale=px)
    return rivers, [], meta


def _parallel(rng, px):
    if rng.random() < 0.25:
        phi = math.radians(90.0 * rng.randrange(4) + rng.uniform(-2.0, 2.0))
    else:
        phi = rng.uniform(0, math.pi)
    w1, w2 = rng.uniform(1.0, 8.0), rng.uniform(1.0, 8.0)
    r1, r2 = w1 / 2.0, w2 / 2.0
    gap = _log_uniform(rng, 0.01, 3.0) * px
    L = rng.uniform(30.0, 100.0)
    converge = rng.random() < 0.5
    closed = (not converge) and rng.random() < 0.25
    if converge:
        # gap(-L/2) = gap, gap(s_tip) = 0, negative (overlap) beyond
        s_tip = rng.uniform(0.0, 0.3) * L
        slope = -gap / (s_tip + L / 2.0)
        s0 = s_tip  # feature of interest: the tip of the strip
    else:
        slope, s0 = 0.0, rng.uniform(-0.25, 0.25) * L

    def g(s):
        return gap + slope * (s + L / 2.0)

    def pt(s, off):  # strip frame (s along, off across) -> local frame
        return _rot((s - s0, off), phi)
    a = [pt(-L / 2, -(r1 + g(-L / 2) / 2)), pt(L / 2, -(r1 + g(L / 2) / 2))]
    b = [pt(-L / 2, r2 + g(-L / 2) / 2), pt(L / 2, r2 + g(L / 2) / 2)]
    rivers = [(a, w1), (b, w2)]
    if closed:
        for s in (-L / 2 + rng.uniform(1.0, 8.0), L / 2 - rng.uniform(1.0, 8.0)):
            cw = rng.uniform(2.0, 4.0)
            ext = max(r1, r2) * 2 + rng.uniform(1.0, 5.0)
            rivers.append(([pt(s, -ext), pt(s, ext)], cw))
    meta = dict(angle_deg=math.degrees(phi) % 180.0, widths=(w1, w2), gap_px=gap / px,
                length_m=L, converge=converge, closed=closed, scale=max(gap, px))
    if converge:
        meta['tip_slope'] = -slope  # gap change per metre along the strip
    return rivers, [], meta


def _island(rng, px):
    variant = 'lake' if rng.random() < 0.5 else 'rivers'
    if variant == 'lake':
        R = rng.uniform(6.0, 20.0)
        ang = rng.uniform(0, 2 * math.pi)
        off = rng.uniform(0.0, 0.5) * R
        cx, cy = off * math.cos(ang), off * math.sin(ang)
        shell = scenes._blob(rng, cx, cy, R, n=rng.choice((24, 36, 48)), rough=0.08,
                             harmonics=3)
        holes, diams = [], []
        d0 = _log_uniform(rng, 0.1, 2.0) * px
        holes.append(_ngon(rng, 0.0, 0.0, d0, rng.choice((3, 4, 6, 8, 12, 24)))[::-1])
        diams.append(d0 / px)
        centres = [(0.0, 0.0)]
        for _ in range(rng.randrange(3)):  # up to 2 more islands, 2-6 m away
            d = _log_uniform(rng, 0.1, 2.0) * px
            t = rng.uniform(0, 2 * math.pi)
            dist = rng.uniform(2.0, 6.0)
            x, y = dist * math.cos(t), dist * math.sin(t)
            if math.hypot(x - cx, y - cy) > 0.6 * R or \
                    min(math.hypot(x - u, y - v) for u, v in centres) < 2.0:
                continue
            centres.append((x, y))
            holes.append(_ngon(rng, x, y, d, rng.choice((3, 4, 6, 8, 12, 24)))[::-1])
            diams.append(d / px)
        meta = dict(variant=variant, lake_radius_m=R, island_diam_px=diams, scale=d0)
        return [], [(shell, holes)], meta
    # a triangle enclosed by three rivers: each river's bank is one side
    D = _log_uniform(rng, 0.1, 3.0) * px
    while True:
        ts = sorted(rng.uniform(0, 2 * math.pi) for _ in range(3))
        tri = [(0.5 * D * math.cos(t), 0.5 * D * math.sin(t)) for t in ts]  # CCW

        def angle(i):
            p, q, r = tri[i], tri[(i + 1) % 3], tri[(i - 1) % 3]
            v1, v2 = (q[0] - p[0], q[1] - p[1]), (r[0] - p[0], r[1] - p[1])
            return math.degrees(math.acos(max(-1.0, min(1.0, (v1[0] * v2[0] + v1[1] * v2[1]) /
                                                      (math.hypot(*v1) * math.hypot(*v2))))))
        if min(angle(i) for i in range(3)) >= 8.0:
            break
    rivers, widths = [], []
    for i in range(3):
        p, q = tri[i], tri[(i + 1) % 3]
        dx, dy = q[0] - p[0], q[1] - p[1]
        ln = math.hypot(dx, dy)
        ux, uy = dx / ln, dy / ln
        nx, ny = uy, -ux  # outward normal of a CCW triangle's side
        w = rng.uniform(1.0, 6.0)
        e0, e1 = rng.uniform(5.0, 20.0), rng.uniform(5.0, 20.0)
        o = w / 2.0
        rivers.append(([(p[0] - e0 * ux + o * nx, p[1] - e0 * uy + o * ny),
                        (q[0] + e1 * ux + o * nx, q[1] + e1 * uy + o * ny)], w))
        widths.append(w)
    meta = dict(variant=variant, island_diam_px=[D / px], widths=widths, scale=D)
    return rivers, [], meta


def _subpixel(rng, px):
    w = rng.uniform(0.1, 0.8) * px
    L = rng.uniform(20.0, 50.0)
    A = rng.uniform(0.0, 3.0)
    lam = rng.uniform(15.0, 40.0)
    ph = rng.uniform(0, 2 * math.pi)
    phi = rng.uniform(0, 2 * math.pi)
    lake_first = rng.random() < 0.5
    # river frame: along x, through (0, 0), |y| <= 2 A
    pts, s = [], -L / 2
    while True:
        pts.append((s, A * (math.sin(2 * math.pi * s / lam + ph) - math.sin(ph))))
        if s >= L / 2:
            break
        s = min(L / 2, s + rng.uniform(1.0, 3.0))
    side = rng.choice((-1, 1))
    clear = 2.0 * A + rng.uniform(3.0, 8.0)  # lake centre <-> river axis
    river_shift = (0.0, -side * clear) if lake_first else (0.0, 0.0)
    lakes, diams = [], []
    for k in range(rng.choice((1, 2))):
        d = _log_uniform(rng, 0.1, 1.0) * px
        if lake_first:
            c = (0.0, 0.0) if k == 0 else (rng.choice((-1, 1)) * rng.uniform(3.0, 10.0), 0.0)
        else:
            c = (rng.uniform(-L / 3, L / 3), side * clear)
        c = _rot(c, phi)
        lakes.append((_ngon(rng, c[0], c[1], d, rng.choice((3, 4, 5, 8, 12)), rough=0.2), []))
        diams.append(d / px)
    river = [_rot(_add(p, river_shift), phi) for p in pts]
    meta = dict(width_px=w / px, length_m=L, meander_m=A, lake_diam_px=diams,
                lake_at_anchor=lake_first, scale=(diams[0] * px if lake_first else w))
    return [(river, w)], lakes, meta


def _shore(rng, px):
    g = _log_uniform(rng, 0.01, 1.5) * px
    w = rng.uniform(0.5, 6.0)
    tilt = math.radians(rng.uniform(-3.0, 3.0))
    apex = rng.random() < 0.5
    if apex:
        # a triangle whose apex, on a sample, points up at the river
        h = math.radians(rng.uniform(20.0, 70.0))
        depth = rng.uniform(8.0, 12.0)
        lake = [(0.0, 0.0), (-depth * math.tan(h), -depth),
                (depth * math.tan(h), -depth), (0.0, 0.0)]
        phi = math.radians(rng.uniform(-60.0, 60.0))
    else:
        # a rectangle with its corners on samples, its top edge on a row
        half = round(rng.uniform(10.0, 20.0) / px) * px
        depth = round(rng.uniform(6.0, 12.0) / px) * px
        x0 = round(rng.uniform(-0.5, 0.5) * half / px) * px
        lake = [(x0 - half, -depth), (x0 + half, -depth), (x0 + half, 0.0),
                (x0 - half, 0.0), (x0 - half, -depth)]
        phi = rng.choice((0.0, 0.5, 1.0, 1.5)) * math.pi
    # the river's bank g above (0, 0), tilted about that point
    c = (0.0, g + w / 2.0)
    d = (25.0 * math.cos(tilt), 25.0 * math.sin(tilt))
    river = [(c[0] - d[0], c[1] - d[1]), (c[0] + d[0], c[1] + d[1])]
    rot = [(_rot(p, phi)) for p in lake]
    if not apex:  # right angles keep sample corners on samples
        rot = [(round(x / px) * px, round(y / px) * px) for x, y in rot]
    meta = dict(gap_px=g / px, width_m=w, tilt_deg=math.degrees(tilt),
                apex=apex, normal=_rot((0.0, 1.0), phi), scale=px,
                on_samples=True)
    return [([_rot(p, phi) for p in river], w)], [(rot, [])], meta


def _grid(rng, px, B):
    """Shores on the block grid: coordinates relative to a block corner,
    the block lines at x, y = 0 (and +-B, out of reach)."""
    kind = rng.choice(('ends', 'tiles', 'bank', 'tip'))

    def size(lo, hi):
        return round(rng.uniform(lo, hi) / px) * px
    rivers, lakes = [], []
    meta = dict(kind=kind, scale=px)
    if kind == 'ends':
        # a rectangle with one to four of its sides on block lines, the
        # water on one side of each
        x0, x1 = rng.choice(((0.0, size(3, 20)), (-size(3, 20), 0.0),
                             (-size(3, 20), size(3, 20))))
        y0, y1 = rng.choice(((0.0, size(3, 20)), (-size(3, 20), 0.0),
                             (-size(3, 20), size(3, 20))))
        lakes.append(([(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)], []))
    elif kind == 'tiles':
        # a rectangle across the lines cut along them into 2 or 4 lakes that
        # share their edges (tiled hydrography); one tile may be shorter
        x0, x1, y0, y1 = -size(3, 20), size(3, 20), -size(3, 20), size(3, 20)
        xs = [x0, 0.0, x1]
        ys = [y0, 0.0, y1] if rng.random() < 0.5 else [y0, y1]
        short = rng.random() < 0.3
        for i in range(2):
            for j in range(len(ys) - 1):
                a, b, c, d = xs[i], xs[i + 1], ys[j], ys[j + 1]
                if short and i == 1 and j == 0:
                    c = c + size(1, 0.8 * (d - c))
                lakes.append(([(a, c), (b, c), (b, d), (a, d), (a, c)], []))
        meta.update(tiles=len(lakes), short=short)
    elif kind == 'bank':
        # a river along the line, its bank on it, and sometimes a lake on
        # the other side of the line touching it
        w = size(1, 8)
        L = size(10, 40)
        side = rng.choice((-1.0, 1.0))
        rivers.append(([(-L, side * w / 2), (L, side * w / 2)], w))
        if rng.random() < 0.5:
            a, b = size(3, 15), size(3, 15)
            y = -side * size(3, 15)
            lakes.append(([(-a, 0.0), (b, 0.0), (b, y), (-a, y), (-a, 0.0)], []))
        meta.update(width_m=w)
    else:
        # a triangle whose apex lies on a block corner or on a side
        h = math.radians(rng.uniform(10.0, 60.0))
        depth = size(4, 15)
        apex = (0.0, 0.0) if rng.random() < 0.5 else (0.0, size(2, 10))
        phi = rng.choice((0.0, 0.5, 1.0, 1.5)) * math.pi + math.radians(rng.uniform(-40, 40))
        tri = [(0.0, 0.0), _rot((depth, -depth * math.tan(h)), phi),
               _rot((depth, depth * math.tan(h)), phi), (0.0, 0.0)]
        lakes.append(([_add(p, apex) for p in tri], []))
        meta.update(half_angle_deg=math.degrees(h))
    if rng.random() < 0.4:
        # a river passing by at a random angle
        a = rng.uniform(0.0, math.pi)
        off = rng.uniform(-6.0, 6.0)
        n = (-math.sin(a), math.cos(a))
        d = (30.0 * math.cos(a), 30.0 * math.sin(a))
        c = (off * n[0], off * n[1])
        rivers.append(([(c[0] - d[0], c[1] - d[1]), (c[0] + d[0], c[1] + d[1])],
                       rng.uniform(0.5, 6.0)))
    quarter = rng.choice((0, 1, 2, 3)) * math.pi / 2  # lines stay lines
    rivers = [([_rot(p, quarter) for p in pts], w) for pts, w in rivers]
    lakes = [([_rot(p, quarter) for p in shell], []) for shell, _ in lakes]
    return rivers, lakes, meta


def _mosaic(rng, px):
    """A lake cut into pieces along one or two lines (riverbank polygons
    of OpenStreetMap, lakes tiled by a survey): the pieces share their
    edges inside the union, or one time in four lie a gap of 0.01-1.5 px
    apart (a land strip); one to three rivers cross it, some ending inside."""
    from shapely.geometry import LineString as _Line
    from shapely.ops import split
    d = rng.uniform(12.0, 40.0)
    pieces = [Polygon(_ngon(rng, 0.0, 0.0, d, rng.randint(5, 12), rough=0.2))]
    for _ in range(rng.choice((1, 1, 2))):
        a = rng.uniform(0.0, math.pi)
        off = rng.uniform(-0.2, 0.2) * d
        n, u = (-math.sin(a), math.cos(a)), (d * math.cos(a), d * math.sin(a))
        cut = _Line([(off * n[0] - u[0], off * n[1] - u[1]),
                     (off * n[0] + u[0], off * n[1] + u[1])])
        pieces = [q for p in pieces for q in split(p, cut).geoms]
    gap = _log_uniform(rng, 0.01, 1.5) * px if rng.random() < 0.25 else 0.0
    if gap:
        pieces = [p.buffer(-gap / 2.0, join_style=2) for p in pieces]
        pieces = [q for p in pieces for q in getattr(p, 'geoms', [p]) if not q.is_empty]
    lakes = [(list(p.exterior.coords), []) for p in pieces]
    rivers = []
    for _ in range(rng.randint(1, 3)):
        a = rng.uniform(0.0, math.pi)
        off = rng.uniform(-0.35, 0.35) * d
        n, u = (-math.sin(a), math.cos(a)), (math.cos(a), math.sin(a))
        t0 = -d if rng.random() < 0.7 else rng.uniform(-0.3, 0.3) * d
        rivers.append(([(off * n[0] + t0 * u[0], off * n[1] + t0 * u[1]),
                        (off * n[0] + d * u[0], off * n[1] + d * u[1])],
                       rng.uniform(0.5, 6.0)))
    meta = dict(pieces=len(pieces), gap_px=gap / px, diameter_m=d, scale=px)
    return rivers, lakes, meta


def _twins(rng, px):
    """Inputs that coincide: a lake given twice, a lake with a hole and a
    lake filling it, a river given twice (once reversed), a river whose
    bank runs along a lake edge, a river that loops and repeats vertices;
    with a river crossing two times in three."""
    kind = rng.choice(('lake2', 'hole', 'river2', 'bank', 'loop'))
    d = rng.uniform(10.0, 30.0)
    shell = _ngon(rng, 0.0, 0.0, d, rng.randint(4, 9), rough=0.2)
    rivers, lakes = [], []
    w = rng.uniform(0.5, 5.0)
    if kind == 'lake2':
        lakes = [(shell, []), (list(reversed(shell)), [])]
    elif kind == 'hole':
        hole = _ngon(rng, rng.uniform(-0.1, 0.1) * d, rng.uniform(-0.1, 0.1) * d,
                     rng.uniform(0.2, 0.5) * d, rng.randint(3, 7), rough=0.2)
        lakes = [(shell, [hole]), (list(reversed(hole)) if rng.random() < 0.5 else hole, [])]
    elif kind == 'river2':
        line = [(-d, rng.uniform(-3, 3)), (0.0, 0.0), (d, rng.uniform(-3, 3))]
        rivers = [(line, w), (list(reversed(line)), w)]
        lakes = [([(x + d * 0.8, y) for x, y in shell], [])]
    elif kind == 'bank':
        i = rng.randrange(len(shell) - 1)
        (ax, ay), (bx, by) = shell[i], shell[i + 1]
        L = math.hypot(bx - ax, by - ay)
        n = ((by - ay) / L, -(bx - ax) / L)  # outward for a ccw ring
        off = rng.choice((w / 2.0, 0.0, -w / 2.0))
        rivers = [([(ax + off * n[0], ay + off * n[1]), (bx + off * n[0], by + off * n[1])], w)]
        lakes = [(shell, [])]
    else:
        r0 = rng.uniform(0.3, 0.45) * d
        pts = [(r0 * math.cos(t), r0 * math.sin(t)) for t in
               (2 * math.pi * k / 7 for k in range(8))]
        pts = pts[:3] + [pts[2]] + pts[3:] + [pts[1]]  # a repeated vertex, a lap
        rivers = [(pts, w)]
        lakes = [([(x + d, y) for x, y in shell], [])]
    if rng.random() < 2.0 / 3.0:
        a = rng.uniform(0.0, math.pi)
        rivers.append(([(-d * math.cos(a), -d * math.sin(a)), (d * math.cos(a), d * math.sin(a))],
                       rng.uniform(0.5, 6.0)))
    return rivers, lakes, dict(kind=kind, width_m=w, scale=px)


def _spike(rng, px):
    """A lake's own sharp features: a spike of water (a convex corner of
    half-angle 0.3-15 degrees, 2-15 m long), a notch of land cut into it as
    sharp, or two lobes joined by a channel 0.05-1.5 px wide; half the time
    a river passing by or through."""
    kind = rng.choice(('spike', 'notch', 'neck'))
    d = rng.uniform(10.0, 30.0)
    lobe = Polygon(_ngon(rng, 0.0, 0.0, d, rng.randint(5, 10), rough=0.15))
    a = rng.uniform(0.0, 2.0 * math.pi)
    u, n = (math.cos(a), math.sin(a)), (-math.sin(a), math.cos(a))
    half = math.radians(_log_uniform(rng, 0.3, 15.0))
    length = rng.uniform(2.0, 15.0)
    meta = dict(kind=kind, scale=px)
    if kind in ('spike', 'notch'):
        # a thin triangle: tip at r0 + length along u (spike) or r0 -
        # length (notch, r0 outside the lobe), base 2 length tan(half) wide
        r0 = 0.5 * d * (0.7 if kind == 'spike' else 1.4)
        tip = r0 + length if kind == 'spike' else r0 - length - 0.3 * d
        w = abs(tip - r0) * math.tan(half)
        tri = Polygon([(r0 * u[0] + w * n[0], r0 * u[1] + w * n[1]),
                     (tip * u[0], tip * u[1]),
                     (r0 * u[0] - w * n[0], r0 * u[1] - w * n[1])])
        shape = lobe.union(tri) if kind == 'spike' else lobe.difference(tri)
        meta.update(half_angle_deg=math.degrees(half), length_m=abs(tip - r0))
    else:
        gap = _log_uniform(rng, 0.05, 1.5) * px
        other = Polygon(_ngon(rng, (d + length) * u[0], (d + length) * u[1], d,
                            rng.randint(5, 10), rough=0.15))
        h = gap / 2.0
        chan = Polygon([(h * n[0], h * n[1]),
                      ((d + length) * u[0] + h * n[0], (d + length) * u[1] + h * n[1]),
                      ((d + length) * u[0] - h * n[0], (d + length) * u[1] - h * n[1]),
                      (-h * n[0], -h * n[1])])
        shape = lobe.union(other).union(chan)
        meta.update(width_px=gap / px, length_m=length)
    parts = list(getattr(shape, 'geoms', [shape]))
    lakes = [(list(q.exterior.coords), [list(r.coords) for r in q.interiors])
             for q in parts if not q.is_empty]
    rivers = []
    if rng.random() < 0.5:
        b = a + rng.uniform(-0.5, 0.5)
        off = rng.uniform(-0.3, 0.3) * d
        m = (-math.sin(b), math.cos(b))
        rivers.append(([(off * m[0] - d * math.cos(b), off * m[1] - d * math.sin(b)),
                        (off * m[0] + 2 * d * math.cos(b), off * m[1] + 2 * d * math.sin(b))],
                       rng.uniform(0.5, 5.0)))
    return rivers, lakes, meta


def _shoal(rng, px):
    """Thin features along the sample grid: a lake with one to three
    islands 0.03-0.4 px wide, 3-18 px long, 0.05-0.6 px from its straight
    shore and from each other, or a stack of two to four lakes 0.03-0.5 px
    wide 0.02-0.5 px apart, or both; along a sample row (the anchor is a
    sample) or at up to 3 degrees to it. The edges from the last samples
    of water to the shore's land hold three crossings where marching
    squares draws one (subpixel.c's lake_twice)."""
    kind = rng.choice(('islands', 'stack', 'both'))
    y0 = rng.choice((0.0, 0.0, 0.5, rng.random())) * px
    ang = rng.choice((0.0, 0.0, rng.uniform(-0.5, 0.5), rng.uniform(-3.0, 3.0)))
    lakes = []
    y = y0 - rng.uniform(0.0, 0.3) * px  # where a stack begins
    if kind in ('islands', 'both'):
        shore = y0 + rng.uniform(0.3, 1.0) * px
        shell = list(box(-20.0 * px, shore - 20.0 * px, 20.0 * px, shore).exterior.coords)
        holes, yi, x = [], shore - rng.uniform(0.05, 0.6) * px, -17.0 * px
        for _ in range(rng.randint(1, 3)):
            w, ln = rng.uniform(0.03, 0.4) * px, rng.uniform(3.0, 10.0) * px
            holes.append(list(box(x, yi - w, x + ln, yi).exterior.coords)[::-1])
            yi -= w + rng.uniform(0.03, 0.6) * px
            x += ln + rng.uniform(0.5, 2.0) * px
        lakes.append((shell, holes))
        y = shore + rng.uniform(0.02, 0.5) * px
    if kind in ('stack', 'both'):
        for _ in range(rng.randint(2, 4)):
            w = rng.uniform(0.03, 0.5) * px
            x0, x1 = rng.uniform(-12.0, -9.0) * px, rng.uniform(9.0, 15.0) * px
            lakes.append((list(box(x0, y, x1, y + w).exterior.coords), []))
            y += w + rng.uniform(0.02, 0.5) * px
    a = math.radians(ang)
    lakes = [([_rot(p, a) for p in s], [[_rot(p, a) for p in h] for h in hs])
             for s, hs in lakes]
    meta = dict(kind=kind, angle_deg=ang, row_offset_px=y0 / px, on_samples=True,
                scale=px)
    return [], lakes, meta


def _cluster(rng, px):
    """2-6 short rivers and 0-3 small lakes at random within a square of
    1, 2 or 4 px."""
    span = rng.choice((1.0, 2.0, 4.0)) * px
    rivers, lakes = [], []
    for _ in range(rng.randint(2, 6)):
        a = rng.uniform(0, 2 * math.pi)
        c = (rng.uniform(-span, span) / 2, rng.uniform(-span, span) / 2)
        length = rng.uniform(0.5, 6.0) * span
        n = rng.randint(2, 4)
        pts = []
        for k in range(n):
            t = -length / 2 + length * k / (n - 1)
            pts.append((c[0] + t * math.cos(a) + rng.uniform(-0.2, 0.2) * span,
                        c[1] + t * math.sin(a) + rng.uniform(-0.2, 0.2) * span))
        rivers.append((pts, _log_uniform(rng, 0.05, 2.0) * px))
    for _ in range(rng.randint(0, 3)):
        lakes.append((_ngon(rng, rng.uniform(-span, span) / 2, rng.uniform(-span, span) / 2,
                            _log_uniform(rng, 0.1, 3.0) * px, rng.randint(3, 8), rough=0.4), []))
    return rivers, lakes, dict(kind='cluster', span_px=span / px, scale=span)


_GENERATORS = {'wedge': _wedge, 'parallel': _parallel, 'island': _island,
               'subpixel': _subpixel, 'shore': _shore, 'mosaic': _mosaic,
               'twins': _twins, 'spike': _spike, 'cluster': _cluster,
               'shoal': _shoal}


# ----------------------------------------------------------------------------
# placement and output
# ----------------------------------------------------------------------------

def _snap(p, unit):
    return (round(p[0] / unit) * unit, round(p[1] / unit) * unit)


def _dedup(pts):
    out = []
    for p in pts:
        if not out or p != out[-1]:
            out.append(p)
    return out


def scene_features(family, seed, pixel_size=PIXEL_SIZE, block_size=BLOCK_SIZE,
                   origin=ORIGIN):
    """(rivers, lakes, meta): rivers [(points, width)], lakes [(shell,
    [holes])] in absolute coordinates of EPSG:32631 snapped to the lattice,
    meta a dict describing the scene (family, sub-family, anchor, ...)."""
    if family not in FAMILIES:
        raise ValueError('unknown family %r (one of %s)' % (family, ', '.join(FAMILIES)))
    rng = random.Random('%s:%d' % (family, seed))
    B = block_size
    if family in ('seam', 'grid', 'cluster'):  # a corner of this block size's grid
        origin = (math.floor(origin[0] / B) * B, math.floor(origin[1] / B) * B)
    if family == 'grid':
        rivers, lakes, meta = _grid(rng, pixel_size, B)
        sub = 'grid'
    else:
        sub = rng.choice(BASE_FAMILIES) if family == 'seam' else family
        rivers, lakes, meta = _GENERATORS[sub](rng, pixel_size)
    lo, hi = 0.1875 * B, 0.8125 * B  # 12 .. 52 m inside a 64 m block
    if family == 'grid':
        ax = ay = B
    elif family == 'seam' or (family == 'cluster' and rng.random() < 0.4):
        where = rng.choice(('x', 'y', 'x', 'y', 'corner'))
        ax = B if where in ('x', 'corner') else rng.uniform(lo, hi)
        ay = B if where in ('y', 'corner') else rng.uniform(lo, hi)
        amp = max(0.4 * meta['scale'], 0.5 * pixel_size)
        exact = rng.random() < 0.25
        if where in ('x', 'corner') and not exact:
            ax += rng.uniform(-amp, amp)
        if where in ('y', 'corner') and not exact:
            ay += rng.uniform(-amp, amp)
        meta.update(seam=where, seam_exact=exact)
    else:
        ax, ay = rng.uniform(lo, hi), rng.uniform(lo, hi)
    if meta.get('on_samples'):  # the feature's edge or vertex on samples
        ax, ay = round(ax / pixel_size) * pixel_size, round(ay / pixel_size) * pixel_size
    anchor = (origin[0] + ax, origin[1] + ay)
    unit = pixel_size / LATTICE_Q

    def place(pts):
        return _dedup([_snap(_add(p, anchor), unit) for p in pts])
    out_rivers = []
    for pts, w in rivers:
        q = place(pts)
        if len(q) >= 2:
            out_rivers.append((q, w))
    out_lakes = []
    for shell, holes in lakes:
        s = place(shell)
        hs = [h for h in (place(h) for h in holes) if len(h) >= 4]
        if len(s) >= 4:
            out_lakes.append((s, hs))
    meta.update(family=family, sub_family=sub, seed=seed, anchor=anchor, anchor_in_block=(ax, ay),
                pixel_size=pixel_size, block_size=block_size)
    return out_rivers, out_lakes, meta


def _coords(pts):
    return ','.join('%.17g %.17g' % p for p in pts)


def make_scene(path, family, seed, pixel_size=PIXEL_SIZE, block_size=BLOCK_SIZE):
    """Writes the scene `family`, `seed` to the GeoPackage `path` (layers
    rivers: LineString + width; lakes: Polygon; EPSG:32631) and returns
    the driver's open options for it (RIVERS, RIVERS_LAYER, LAKES,
    LAKES_LAYER, WIDTH_FIELD, PIXEL_SIZE, BLOCK_SIZE)."""
    if os.path.exists(path):
        os.unlink(path)
    rivers, lakes, meta = scene_features(family, seed, pixel_size, block_size)
    rf = [{'geom': 'LINESTRING (%s)' % _coords(pts), 'width': float(w),
           'name': '%s%d_r%d' % (family, seed, i)} for i, (pts, w) in enumerate(rivers)]
    lf = [{'geom': 'POLYGON (%s)' % ','.join('(%s)' % _coords(r) for r in [s] + hs),
           'name': '%s%d_l%d' % (family, seed, i)} for i, (s, hs) in enumerate(lakes)]
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, EPSG, rf,
                       fields=[('width', 'Real'), ('name', 'String')])
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, EPSG, lf, fields=[('name', 'String')])
    return {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'LAKES': path, 'LAKES_LAYER': 'lakes',
            'WIDTH_FIELD': 'width', 'PIXEL_SIZE': pixel_size, 'BLOCK_SIZE': block_size}


def densify(path, step_px, pixel_size=PIXEL_SIZE):
    """Rewrites the rivers and lakes of the scene at `path` with a vertex
    every `step_px` pixels along their edges (OGR's Segmentize), every
    vertex snapped to the lattice as make_scene's are, so that the oracle
    reads what the driver reads: many nearly collinear pieces (the new
    vertices lie within half a unit of their edge), the inputs of an
    over-dense line or a densified export."""
    unit = pixel_size / LATTICE_Q

    def snap(g):
        for k in range(g.GetGeometryCount()):
            snap(g.GetGeometryRef(k))
        for i in range(g.GetPointCount()):
            g.SetPoint_2D(i, round(g.GetX(i) / unit) * unit, round(g.GetY(i) / unit) * unit)
    ds = ogr.Open(path, update=1)
    for name in ('rivers', 'lakes'):
        lyr = ds.GetLayerByName(name)
        for fid in [f.GetFID() for f in lyr]:
            f = lyr.GetFeature(fid)
            g = f.GetGeometryRef().Clone()
            g.Segmentize(step_px * pixel_size)
            snap(g)
            f.SetGeometry(g)
            lyr.SetFeature(f)
    ds = None


def describe(family, seed, pixel_size=PIXEL_SIZE, block_size=BLOCK_SIZE):
    """One line describing the scene (for reports and failure messages)."""
    meta = scene_features(family, seed, pixel_size, block_size)[2]
    keep = {k: v for k, v in meta.items() if k not in ('family', 'seed', 'pixel_size', 'anchor',
                                                        'block_size', 'scale', 'tip_slope')}
    parts = []
    for k, v in sorted(keep.items()):
        if isinstance(v, float):
            parts.append('%s=%.4g' % (k, v))
        elif isinstance(v, (list, tuple)):
            parts.append('%s=(%s)' % (k, ','.join('%.4g' % x if isinstance(x, float) else str(x)
                                                   for x in v)))
        else:
            parts.append('%s=%s' % (k, v))
    return '%s seed %d: %s' % (family, seed, ' '.join(parts))


# ----------------------------------------------------------------------------
# topology figures against the oracle (shared by test_topology.py and
# bench/topology.py); by_block arguments are {block: [geometries]}
# ----------------------------------------------------------------------------

SPECK_PX = 0.5        # a speck: max pairwise vertex distance <= 0.5 px
MATCH_PX = 1.0        # an oracle ring of the same kind within 1 px excuses it
SMALL_PX = 2.0        # oracle rings with a bounding box under 2 px ...
LOST_PX = 1.0         # ... are lost without an output ring within 1 px
NARROW_PX = 2.0       # narrow_land_area: land strips narrower than 2 px


def ring_diameter(coords, limit):
    """Max pairwise distance of a closed ring's vertices, or inf when its
    bounding box already has a side longer than `limit`."""
    c = np.asarray(coords, dtype=float)
    c = c[:-1] if len(c) > 1 else c
    if (c.max(axis=0) - c.min(axis=0)).max() > limit:
        return math.inf
    d = c[:, None, :] - c[None, :, :]
    return float(np.sqrt((d * d).sum(axis=2)).max())


def touches_block(coords, block, block_size, eps=1e-6):
    """Whether a vertex of the ring lies on a side of its block's square."""
    x0, y0 = block[0] * block_size, block[1] * block_size
    x1, y1 = x0 + block_size, y0 + block_size
    x, y = coords[:, 0], coords[:, 1]
    return bool(((abs(x - x0) <= eps) | (abs(x - x1) <= eps) |
                 (abs(y - y0) <= eps) | (abs(y - y1) <= eps)).any())


class Ring:
    """One ring of a block's polygons: kind 'outer' or 'hole', bounds,
    whether it touches the block's square, diameter (inf when large)."""
    __slots__ = ('block', 'kind', 'coords', 'bounds', 'touches', 'diam', 'line')

    def __init__(self, block, kind, coords, block_size, diam_limit):
        self.block, self.kind, self.coords = block, kind, coords
        mn, mx = coords.min(axis=0), coords.max(axis=0)
        self.bounds = (float(mn[0]), float(mn[1]), float(mx[0]), float(mx[1]))
        self.touches = touches_block(coords, block, block_size)
        self.diam = ring_diameter(coords, diam_limit)
        self.line = LinearRing(coords) if len(coords) >= 4 else None

    def size(self):
        return max(self.bounds[2] - self.bounds[0], self.bounds[3] - self.bounds[1])

    def center(self):
        return (float(self.coords[:, 0].mean()), float(self.coords[:, 1].mean()))

    def near(self, other, dist):
        a, b = self.bounds, other.bounds
        if a[0] - dist > b[2] or b[0] - dist > a[2] or a[1] - dist > b[3] or b[1] - dist > a[3]:
            return False
        if self.line is None or other.line is None:
            return False
        return self.line.distance(other.line) <= dist


def block_rings(by_block, block_size, diam_limit):
    out = []
    for b, geoms in by_block.items():
        for g in geoms:
            for p in oracle.polygons_of(g):
                rs = oracle.rings_of(p)
                out.append(Ring(b, 'outer', rs[0], block_size, diam_limit))
                out.extend(Ring(b, 'hole', r, block_size, diam_limit) for r in rs[1:])
    return out


def pinch_points(rings):
    """Where the exact union's pieces meet at a point, as the even-odd parts
    of a lake whose holes overlap do: the points where two rings of a block
    touch, and the vertices a ring meets twice, as {block: [Point]}; and
    the ids of the rings that hold one."""
    by_block = defaultdict(list)
    for o in rings:
        by_block[o.block].append(o)
    points, ids = defaultdict(list), set()
    for b, rs in by_block.items():
        for i, o in enumerate(rs):
            pts = [tuple(p) for p in o.coords[:-1].tolist()]
            seen = Counter(pts)
            twice = [Point(p) for p, n in seen.items() if n > 1]
            if twice:
                points[b].extend(twice)
                ids.add(id(o))
            for q in rs[i + 1:]:
                if o.near(q, 1e-9):
                    meet = o.line.intersection(q.line)
                    points[b].extend(g for g in getattr(meet, 'geoms', [meet])
                                     if g.geom_type == 'Point')
                    ids.update((id(o), id(q)))
    return points, ids


def topology_figures(drv, orc, block_size, px, orc_lost=None):
    """Ring topology of the output `drv` against the oracle `orc`:
      specks_outer / specks_hole: output rings (touching a side of their
        block or not) whose vertices all lie within SPECK_PX of each other (max
        pairwise distance), with no oracle ring of the same kind within
        MATCH_PX that is that small too (diameter <= the speck's + MATCH_PX:
        what a ring within half a pixel of it may measure), and no pinch
        point of the oracle (pinch_points) within MATCH_PX: where pieces of
        the exact union meet at a point, the output may give a piece its own
        ring;
      lost_outer / lost_hole: oracle rings touching no block side, bounding
        box under SMALL_PX on both axes (small_outer / small_hole of them),
        with no output ring of the same kind within LOST_PX (of any kind for
        a ring with a pinch point: a lake's even-odd lens where two of its
        holes overlap meets the lake's water at their crossings, and the
        output may join it to that water there, the hole around it one
        ring); pinched: how many rings had a pinch point (so excused);
      ring_diff: sum over blocks and kinds of how far the output's rings
        fall outside [rings of orc_lost, rings of orc]: fewer than the
        oracle has at the scales the lattice resolves (resolvable()), or more
        than the exact union has at all (a feature below the lattice may be
        kept: seam seed 136414 at 0.5 m, the tip of a river 0.3 units wide
        beside a block corner, 1.7 units long, is one);
      speck_at / lost_at: up to 5 (kind, x, y) each.
    orc_lost (default orc): the oracle whose rings may be lost (resolvable():
    a feature the lattice does not resolve need not be kept, but it may)."""
    dr = block_rings(drv, block_size, SPECK_PX * px)
    orr = block_rings(orc, block_size, (SPECK_PX + MATCH_PX) * px)
    pinch, pinched = pinch_points(orr)
    lost_rings = orr if orc_lost is None else \
        block_rings(orc_lost, block_size, (SPECK_PX + MATCH_PX) * px)
    if orc_lost is not None:
        _, pinched = pinch_points(lost_rings)
    out = dict(specks_outer=0, specks_hole=0, lost_outer=0, lost_hole=0, small_outer=0,
               small_hole=0, speck_at=[], lost_at=[], pinched=len(pinched))
    for r in dr:
        if r.diam > SPECK_PX * px:
            continue
        if not any(o.kind == r.kind and o.diam <= r.diam + MATCH_PX * px and
                   o.near(r, MATCH_PX * px) for o in orr) and \
                not any(r.line is not None and r.line.distance(q) <= MATCH_PX * px
                        for q in pinch.get(r.block, ())):
            out['specks_' + r.kind] += 1
            if len(out['speck_at']) < 5:
                out['speck_at'].append((r.kind,) + r.center())
    for o in lost_rings:
        if o.touches or o.size() >= SMALL_PX * px:
            continue
        out['small_' + o.kind] += 1
        any_kind = id(o) in pinched
        if not any((any_kind or r.kind == o.kind) and r.near(o, LOST_PX * px) for r in dr):
            out['lost_' + o.kind] += 1
            if len(out['lost_at']) < 5:
                out['lost_at'].append((o.kind,) + o.center())
    cd = Counter((r.block, r.kind) for r in dr)
    co = Counter((r.block, r.kind) for r in orr)
    cr = Counter((r.block, r.kind) for r in lost_rings)
    out['ring_diff'] = sum(max(0, cd[k] - co[k]) + max(0, cr[k] - cd[k])
                           for k in set(cd) | set(co) | set(cr))
    return out


def boundary_distances(drv, orc, block_size, step, orc_src=None):
    """As oracle.hausdorff (each block's square counts as boundary of both
    sides, boundaries sampled every `step`), but returns every sample's
    distance: (distances (numpy array, both directions), hausdorff, (x, y)
    of the worst sample or None). orc_src (default orc): the oracle whose
    boundary samples are measured to the output (resolvable())."""
    all_d, worst = [], (0.0, None)
    for src, dst in ((drv, orc), (orc if orc_src is None else orc_src, drv)):
        pts, tags = oracle._tagged_points(src, step)
        if not len(pts):
            continue
        segs = oracle.boundary_segments([g for gs in dst.values() for g in gs])
        d = oracle.nearest_distances(pts, segs, max(40.0 * step, 1.0))
        d = np.minimum(d, oracle._frame_distance(pts, tags, block_size))
        k = int(np.argmax(d))
        if d[k] > worst[0]:
            worst = (float(d[k]), (float(pts[k, 0]), float(pts[k, 1])))
        all_d.append(d)
    d = np.concatenate(all_d) if all_d else np.zeros(0)
    return d, worst[0], worst[1]


def vertex_offset(drv, oracle_by_block):
    """Largest distance (m) from a vertex of the output's rings to its own
    block's clipped oracle boundary (the block square only where the exact
    water is cut by it). boundary_distances() counts every block's square
    as boundary, so a spike running along a block side a unit from it
    passes there; not here (held-out round 30: spikes up to 13.8 px along
    block sides at 1 m / 16 m, 5 of 280 grid and seam scenes)."""
    worst = 0.0
    for b, geoms in drv.items():
        o = oracle_by_block.get(b)
        if o is None or o.is_empty:
            continue  # water where the exact union has none: ring counts
        segs = oracle.boundary_segments([o])
        pts = [c for g in geoms for p in oracle.polygons_of(g)
               for r in [p.exterior] + list(p.interiors) for c in r.coords[:-1]]
        if pts and len(segs):
            d = oracle.nearest_distances(np.asarray(pts, dtype=float), segs, 1.0)
            worst = max(worst, float(d.max()))
    return worst


def narrow_land_area(water, px, width_px=NARROW_PX):
    """Area of the exact union's land (around `water`, a shapely geometry)
    in strips narrower than width_px pixels: what an opening by half that
    width removes. Sampling at PIXEL_SIZE may fill such land with water."""
    r = 0.5 * width_px * px
    x0, y0, x1, y1 = water.bounds
    land = box(x0 - 4 * r, y0 - 4 * r, x1 + 4 * r, y1 + 4 * r).difference(water)
    return land.difference(land.buffer(-r).buffer(r)).area


def resolvable(oracle_by_block, px, block_size):
    """The oracle without the rings shorter than two lattice units (the
    unit px / 256) in both directions: such a feature meets at most one
    lattice line each way and may hold no lattice point, and the product
    keeps a feature narrower than a unit one unit wide only where a searched
    lattice segment crosses it, then drops what is thinner than half a unit
    (block.c, architecture.md's "What stays unseen"); a hole among them is
    filled, a part dropped. Mosaic seed 131073 has one: a land triangle 1.7
    x 0.7 units where two banks and a lake piece nearly close. A long sliver
    thinner than a unit (a bank crossing a lake edge at a tiny angle) is
    kept, and so must the output keep it, unless it is thinner than half a
    unit on average (2 x area / perimeter below WM_THIN, block.c's bound for
    a ring that is a remnant of rounding: a sliver no more than a unit
    thick where thickest): the strip between two rivers whose densified
    vertices lie on the lattice, half a unit off their lines, pinched into
    rows of such slivers 0.2-0.4 units thick (parallel seed 159087 at 0.5 m
    with `--densify 0.1`). So are the rings touching a block
    side and thinner (2 x area / perimeter) than the rounding of the inputs
    (WM_COINCIDE, 1e-6 units, or GEOS's few ulps of UTM coordinates, 1e-8
    m): a bank or lake edge on a block line but for rounding, whose samples
    there field.c's settle_lines makes land (grid seed 136125 at 0.3 m, a
    bank on the line: GEOS leaves a strip 1e-9 m thick)."""
    unit = px / LATTICE_Q
    small = 2.0 * unit
    coincide = max(1e-6 * unit, 1e-8)

    def thickness(ring):  # 2 x area / perimeter
        poly = Polygon(ring)
        return 2.0 * poly.area / poly.length if poly.length > 0 else 0.0

    def ok(ring):
        x0, y0, x1, y1 = ring.bounds
        return max(x1 - x0, y1 - y0) >= small and thickness(ring) >= THIN_UNITS * unit

    def thin_on_side(ring, b):
        if ring.length == 0 or thickness(ring) >= coincide:
            return False
        x0, y0 = oracle.block_origin(b, block_size)
        square = Polygon([(x0, y0), (x0 + block_size, y0),
                          (x0 + block_size, y0 + block_size), (x0, y0 + block_size)])
        return ring.distance(square.exterior) == 0.0
    out = {}
    for b, g in oracle_by_block.items():
        def keep(r):
            return ok(r) and not thin_on_side(r, b)
        polys = [Polygon(p.exterior, [r for r in p.interiors if keep(r)])
                 for p in oracle.polygons_of(g) if keep(p.exterior)]
        out[b] = polys[0] if len(polys) == 1 else MultiPolygon(polys)
    return out


def measure(water_feats, oracle_by_block, block_size, px, step=None):
    """Figures of one run against the oracle ({block: geometry}), its
    features the lattice does not resolve (resolvable()) excused from being
    kept, not from justifying an output ring there: hausdorff_px, p99_px, worst_at,
    area_m2, oracle_area_m2, rel_area_diff, symdiff_m2, vertex_off_px
    (vertex_offset()), invalid (polygons),
    + topology_figures(); also returns the boundary sample distances in px
    (numpy array) as a second value."""
    if step is None:
        step = min(0.1, px / 10.0)
    res_orc = {b: [g] for b, g in resolvable(oracle_by_block, px, block_size).items()}
    drv = defaultdict(list)
    for f in water_feats:
        if f.geom is not None:
            drv[f.block].append(f.geom)
    orc = {b: [g] for b, g in oracle_by_block.items()}
    area_d = sum(oracle.geom_area(g, oracle.block_origin(b, block_size))
                 for b, gs in drv.items() for g in gs)
    area_o = sum(oracle.geom_area(g, oracle.block_origin(b, block_size))
                 for b, g in oracle_by_block.items())
    symdiff = 0.0
    for b in set(drv) | set(orc):
        a = unary_union(drv.get(b, [])) if all(g.is_valid for g in drv.get(b, [])) \
            else unary_union([g.buffer(0) for g in drv.get(b, [])])
        o = oracle_by_block.get(b, GeometryCollection())
        if not (a.is_empty and o.is_empty):
            symdiff += a.symmetric_difference(o).area
    d, h, where = boundary_distances(drv, orc, block_size, step, res_orc)
    res = dict(hausdorff_px=h / px, p99_px=float(np.percentile(d, 99)) / px if len(d) else 0.0,
               worst_at=where, area_m2=area_d, oracle_area_m2=area_o,
               rel_area_diff=(area_d - area_o) / area_o if area_o else 0.0,
               symdiff_m2=symdiff, vertex_off_px=vertex_offset(drv, oracle_by_block) / px,
               invalid=sum(1 for f in water_feats if f.geom is not None and not f.geom.is_valid))
    res.update(topology_figures(drv, orc, block_size, px, res_orc))
    return res, d / px
