#!/usr/bin/python3
"""Synthetic benchmark scenes at the scales of the paper's Table 1.

    /usr/bin/python3 bench/gen_scene.py L3 bench/data/L3.gpkg [--seed 1] [--spread 4]

Writes a GeoPackage (EPSG:32631) with the layers
  - ``rivers``: LineString, field ``width`` (Real, 2 to 30 m);
  - ``lakes``:  MultiPolygon (some with an island hole, a few with two parts).

Each preset reproduces exactly the counts of Table 1: river vertices, river
features, lake vertices and lake features, counted as watermesh counts them
(OGR point counts, so a ring's closing point counts). The area is the
table's area.

How a scene is made (everything from one random.Random(seed)):
  - the square scene is cut into basins (a jittered grid); each basin holds a
    river network: a trunk crossing the basin, tributaries branching from a
    vertex of an existing river (the junction is a shared vertex), up to
    three levels deep, until the basin's share of the vertex budget is used;
  - rivers meander (the heading oscillates with a random amplitude and
    wavelength, plus correlated noise); vertex spacing 5 to 20 m; width
    10-30 m for trunks, 4-15 m for first-level tributaries, 2-8 m deeper;
  - each river polyline is cut into features at random vertices (consecutive
    features share their end vertex), as real data cuts rivers at junctions
    and name changes;
  - lakes are star-shaped blobs (random harmonics); about 40 % sit on a river
    vertex (the river runs through the lake, or into it when the vertex is a
    river end), the rest are free-standing; about a quarter have an island
    (a hole) and 5 % a second part.
Presets S3 and S5 are sparse networks with L3's and L5's river counts and
area: independent meandering lines 2-15 m wide that rarely meet, few lakes.
--spread 4 or 16 keeps every feature's shape and moves each basin away from
the scene origin so that the same features cover 4 or 16 times the area.
"""

import argparse
import math
import os
import random
import sys

from osgeo import gdal, ogr, osr

gdal.UseExceptions()

EPSG = 32631
ORIGIN = (300000.0, 4400000.0)

# Table 1 of the paper: river vertices, river features, lake vertices,
# lake features, area in km2
PRESETS = {
    'L1': (34923, 1059, 8122, 130, 1980.0),
    'L2': (90741, 2939, 3376, 14, 729.0),
    'L3': (279354, 24922, 41520, 731, 1485.0),
    'L4': (281743, 5208, 2266, 9, 1485.0),
    'L5': (641022, 44825, 83867, 1519, 36852.0),
    # sparse networks (issue 14): L3's and L5's rivers as independent lines
    # that rarely meet, and few lakes
    'S3': (279354, 24922, 2266, 9, 1485.0),
    'S5': (641022, 44825, 4532, 18, 36852.0),
}
SPARSE = {'S3', 'S5'}

STEP = (5.0, 20.0)       # vertex spacing of rivers, m
MEAN_STEP = sum(STEP) / 2
MIN_LAKE_RING = 9        # points of the smallest lake ring (closing included)


class Basin:
    """A square cell of the scene with its river polylines."""

    def __init__(self, cx, cy, size):
        self.cx, self.cy, self.size = cx, cy, size
        h = 0.55 * size
        self.bounds = (cx - h, cy - h, cx + h, cy + h)
        self.rivers = []  # [pts, width, depth]


def meander(rng, start, heading, length, bounds, amplitude, wavelength):
    """Meandering polyline from start; stops after `length` m or before
    leaving bounds. Returns the list of points (start included)."""
    x, y = start
    pts = [(x, y)]
    amp = rng.uniform(*amplitude)
    lam = rng.uniform(*wavelength)
    phase = rng.uniform(0.0, 2.0 * math.pi)
    drift = rng.gauss(0.0, 0.04)  # slow turn of the valley, rad per km
    travelled, jitter = 0.0, 0.0
    while travelled < length:
        d = rng.uniform(*STEP)
        jitter = 0.8 * jitter + rng.gauss(0.0, 0.06)
        h = (heading + drift * travelled / 1000.0 +
             amp * math.sin(2.0 * math.pi * travelled / lam + phase) + jitter)
        nx, ny = x + d * math.cos(h), y + d * math.sin(h)
        if not (bounds[0] <= nx <= bounds[2] and bounds[1] <= ny <= bounds[3]):
            break
        x, y = nx, ny
        pts.append((x, y))
        travelled += d
    return pts


def grow_basin(rng, basin, budget, remaining, sparse=False):
    """Adds polylines to the basin until it holds `budget` net vertices
    (sum of (n - 1) over its polylines) or remaining() says the scene is
    full. remaining(n) is called with the vertex count of each new polyline
    and returns how many of its vertices may be kept (0: stop). Sparse: every
    polyline is an independent meandering line from a random point (no
    tributaries), 2 to 15 m wide."""
    used = 0
    attempts = 0
    while used < budget and attempts < 2000:
        attempts += 1
        if sparse:
            x0, y0, x1, y1 = basin.bounds
            pts = meander(rng, (rng.uniform(x0, x1), rng.uniform(y0, y1)),
                          rng.uniform(0.0, 2.0 * math.pi),
                          rng.uniform(0.3, 1.0) * basin.size, basin.bounds,
                          (0.2, 0.7), (100.0, 400.0))
            width, depth = rng.uniform(2.0, 15.0), 0
        elif not basin.rivers:
            ang = rng.uniform(0.0, 2.0 * math.pi)
            r = 0.5 * basin.size
            start = (basin.cx - r * math.cos(ang), basin.cy - r * math.sin(ang))
            pts = meander(rng, start, ang + rng.gauss(0.0, 0.2), 1.6 * basin.size,
                          basin.bounds, (0.3, 0.9), (150.0, 600.0))
            width, depth = rng.uniform(10.0, 30.0), 0
        else:
            parents = [r for r in basin.rivers if r[2] < 3 and len(r[0]) >= 6]
            if not parents:
                break
            weights = [len(r[0]) for r in parents]
            ppts, pwidth, pdepth = rng.choices(parents, weights)[0]
            i = rng.randrange(1, len(ppts) - 2)
            (ax, ay), (bx, by) = ppts[i], ppts[i + 1]
            down = math.atan2(by - ay, bx - ax)
            heading = down + math.radians(rng.uniform(40.0, 100.0)) * rng.choice((-1, 1))
            length = rng.uniform(0.15, 0.5) * basin.size / (1 + pdepth)
            pts = meander(rng, ppts[i], heading, length, basin.bounds,
                          (0.2, 0.7), (100.0, 400.0))
            depth = pdepth + 1
            width = rng.uniform(4.0, 15.0) if depth == 1 else rng.uniform(2.0, 8.0)
            width = min(width, pwidth)
        if len(pts) < 4:
            continue
        keep = remaining(len(pts))
        if keep == 0:
            return False
        pts = pts[:keep]
        basin.rivers.append([pts, width, depth])
        used += len(pts) - 1
    return True


def split_counts(rng, ns, total):
    """Pieces per polyline: k_r in [1, n_r - 1], sum k_r = total, about
    proportional to n_r - 1."""
    cap = [n - 1 for n in ns]
    assert len(ns) <= total <= sum(cap), (len(ns), total, sum(cap))
    share = [(total - len(ns)) * (c - 1) / max(1, sum(cap) - len(ns)) for c in cap]
    k = [1 + int(s) for s in share]
    rest = total - sum(k)
    order = sorted(range(len(ns)), key=lambda i: -(share[i] - int(share[i]) + rng.random() * 1e-6))
    while rest > 0:
        for i in order:
            if rest == 0:
                break
            if k[i] < cap[i]:
                k[i] += 1
                rest -= 1
    return k


def cut(rng, pts, k):
    """k pieces of a polyline, cut at k - 1 distinct random inner vertices;
    consecutive pieces share the cut vertex."""
    if k == 1:
        return [pts]
    cuts = sorted(rng.sample(range(1, len(pts) - 1), k - 1))
    bounds = [0] + cuts + [len(pts) - 1]
    return [pts[a:b + 1] for a, b in zip(bounds[:-1], bounds[1:])]


def lake_sizes(rng, n_lakes, n_vertices):
    """Point count of every lake (rings, closing points included), summing
    to n_vertices: log-normal around the mean, at least MIN_LAKE_RING."""
    mean = n_vertices / n_lakes
    raw = [rng.lognormvariate(0.0, 0.6) for _ in range(n_lakes)]
    scale = (n_vertices - MIN_LAKE_RING * n_lakes) / sum(raw)
    sizes = [MIN_LAKE_RING + int(r * scale) for r in raw]
    i = 0
    while sum(sizes) < n_vertices:
        sizes[i % n_lakes] += 1
        i += 1
    assert sum(sizes) == n_vertices and min(sizes) >= MIN_LAKE_RING, mean
    return sizes


def blob(rng, cx, cy, r, n, rough):
    """Closed star-shaped ring of n points (n - 1 distinct) around (cx, cy),
    mean radius r; the radius stays within r * (1 +- rough)."""
    harm = [(rng.uniform(-1.0, 1.0), rng.uniform(0.0, 2.0 * math.pi)) for _ in range(5)]
    norm = sum(1.0 / (j + 1) for j in range(len(harm)))
    pts = []
    m = n - 1
    for i in range(m):
        t = 2.0 * math.pi * i / m
        k = sum(a * math.sin((j + 2) * t + ph) / (j + 1) for j, (a, ph) in enumerate(harm))
        rr = r * (1.0 + rough * k / norm)
        pts.append((cx + rr * math.cos(t), cy + rr * math.sin(t)))
    pts.append(pts[0])
    return pts


def make_lake(rng, cx, cy, npts):
    """(parts, radius): parts is a list of polygons, each a list of rings.
    Splits npts between shell, optional island and optional second part."""
    spacing = rng.uniform(8.0, 40.0)
    kind = rng.random()
    if kind < 0.25 and npts >= 2 * MIN_LAKE_RING + 4:      # island
        nh = max(MIN_LAKE_RING, npts // 4)
        ns = npts - nh
        r = (ns - 1) * spacing / (2.0 * math.pi)
        rough = rng.uniform(0.1, 0.3)
        rmin = r * (1.0 - rough)
        off = rng.uniform(0.0, 0.3) * rmin
        t = rng.uniform(0.0, 2.0 * math.pi)
        hole = blob(rng, cx + off * math.cos(t), cy + off * math.sin(t),
                    0.3 * rmin / 1.3, nh, 0.3)[::-1]
        return [[blob(rng, cx, cy, r, ns, rough), hole]], 1.3 * r
    if kind < 0.30 and npts >= 2 * MIN_LAKE_RING:            # two parts
        n2 = max(MIN_LAKE_RING, npts // 3)
        ns = npts - n2
        r = (ns - 1) * spacing / (2.0 * math.pi)
        r2 = (n2 - 1) * spacing / (2.0 * math.pi)
        t = rng.uniform(0.0, 2.0 * math.pi)
        d = 1.4 * r + 1.4 * r2 + 20.0
        return [[blob(rng, cx, cy, r, ns, 0.25)],
                [blob(rng, cx + d * math.cos(t), cy + d * math.sin(t), r2, n2, 0.25)]], d + 1.3 * r2
    r = (npts - 1) * spacing / (2.0 * math.pi)
    return [[blob(rng, cx, cy, r, npts, rng.uniform(0.1, 0.35))]], 1.35 * r


def generate(preset, seed, spread):
    n_rv, n_rf, n_lv, n_lf, area_km2 = PRESETS[preset]
    rng = random.Random('%s/%d' % (preset, seed))
    side = math.sqrt(area_km2) * 1000.0
    # basin size: the trunk (about 1.6 * size / MEAN_STEP vertices) takes
    # about a third of the basin's vertices
    size = 3.0 * 1.6 * side * side / (MEAN_STEP * n_rv)
    size = min(max(size, 2000.0), 15000.0)
    nb = max(1, round(side / size))
    size = side / nb
    basins = []
    for j in range(nb):
        for i in range(nb):
            cx = ORIGIN[0] + (i + 0.5) * size + rng.uniform(-0.1, 0.1) * size
            cy = ORIGIN[1] + (j + 0.5) * size + rng.uniform(-0.1, 0.1) * size
            basins.append(Basin(cx, cy, size))
    rng.shuffle(basins)

    # sum over polylines of n_r must reach n_rv - n_rf + R (R polylines)
    state = {'sum': 0, 'count': 0, 'done': False}

    def remaining(n):
        target = n_rv - n_rf + state['count'] + 1
        if state['sum'] == target - 1 or state['count'] >= n_rf:
            state['done'] = True
            return 0
        keep = min(n, target - state['sum'])
        state['sum'] += keep
        state['count'] += 1
        if state['sum'] == target:
            state['done'] = True
        return keep

    net_budget = (n_rv - n_rf) / len(basins)
    rounds = 0
    while not state['done']:
        rounds += 1
        assert rounds < 50, 'cannot place the river budget'
        for b in basins:
            if state['done']:
                break
            grow_basin(rng, b, net_budget * rounds - sum(len(r[0]) - 1 for r in b.rivers),
                       lambda n: 0 if state['done'] else remaining(n), preset in SPARSE)
    polylines = [(b, r) for b in basins for r in b.rivers]
    assert sum(len(r[0]) for _, r in polylines) == n_rv - n_rf + len(polylines)

    ks = split_counts(rng, [len(r[0]) for _, r in polylines], n_rf)
    rivers = []  # (basin, pts, width)
    for (b, (pts, width, _)), k in zip(polylines, ks):
        for piece in cut(rng, pts, k):
            w = min(30.0, max(2.0, width * rng.uniform(0.9, 1.1)))
            rivers.append((b, piece, round(w, 2)))
    assert len(rivers) == n_rf and sum(len(p) for _, p, _ in rivers) == n_rv

    lakes = []  # (basin, parts)
    placed = []  # (x, y, radius) to keep lakes apart
    for npts in lake_sizes(rng, n_lf, n_lv):
        for attempt in range(40):
            if rng.random() < 0.4:
                b, pts, _ = rng.choice(rivers)
                # an end vertex: the river runs into the lake
                cx, cy = pts[-1] if rng.random() < 0.5 else rng.choice(pts)
            else:
                b = rng.choice(basins)
                x0, y0, x1, y1 = b.bounds
                cx, cy = rng.uniform(x0, x1), rng.uniform(y0, y1)
            parts, reach = make_lake(rng, cx, cy, npts)
            if all(math.hypot(cx - x, cy - y) > reach + r + 10.0 for x, y, r in placed) \
                    or attempt == 39:
                break
        placed.append((cx, cy, reach))
        lakes.append((b, parts))

    k = math.sqrt(spread)

    def shift(b):
        return ((k - 1.0) * (b.cx - ORIGIN[0]), (k - 1.0) * (b.cy - ORIGIN[1]))
    return ([(shift(b), pts, w) for b, pts, w in rivers],
            [(shift(b), parts) for b, parts in lakes])


def coords(pts, d):
    return ','.join('%.3f %.3f' % (x + d[0], y + d[1]) for x, y in pts)


def write(path, rivers, lakes):
    if os.path.exists(path):
        os.unlink(path)
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(EPSG)
    ds = ogr.GetDriverByName('GPKG').CreateDataSource(path)
    lyr = ds.CreateLayer('rivers', srs, ogr.wkbLineString)
    lyr.CreateField(ogr.FieldDefn('width', ogr.OFTReal))
    ds.StartTransaction()
    defn = lyr.GetLayerDefn()
    for d, pts, w in rivers:
        f = ogr.Feature(defn)
        f.SetField('width', w)
        f.SetGeometryDirectly(ogr.CreateGeometryFromWkt('LINESTRING (%s)' % coords(pts, d)))
        lyr.CreateFeature(f)
    ds.CommitTransaction()
    lyr = ds.CreateLayer('lakes', srs, ogr.wkbMultiPolygon)
    ds.StartTransaction()
    defn = lyr.GetLayerDefn()
    for d, parts in lakes:
        f = ogr.Feature(defn)
        wkt = 'MULTIPOLYGON (%s)' % ','.join(
            '(%s)' % ','.join('(%s)' % coords(ring, d) for ring in poly) for poly in parts)
        f.SetGeometryDirectly(ogr.CreateGeometryFromWkt(wkt))
        lyr.CreateFeature(f)
    ds.CommitTransaction()
    ds = None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('preset', choices=sorted(PRESETS))
    ap.add_argument('output', help='GeoPackage to write (replaced)')
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--spread', type=int, choices=(1, 4, 16), default=1,
                    help='the same features over 1, 4 or 16 times the area')
    a = ap.parse_args(argv)
    rivers, lakes = generate(a.preset, a.seed, a.spread)
    write(a.output, rivers, lakes)
    n_rv, n_rf, n_lv, n_lf, area = PRESETS[a.preset]
    print('%s: %s seed %d spread %d: %d river vertices, %d river features, '
          '%d lake vertices, %d lake features, %.0f km2'
          % (a.output, a.preset, a.seed, a.spread, n_rv, n_rf, n_lv, n_lf, area * a.spread))
    return 0


if __name__ == '__main__':
    sys.exit(main())
