"""Reference ("oracle") water polygons and the comparison helpers.

The oracle is the exact buffer-and-dissolve of a scene, computed with GEOS
through shapely only: every river buffered by width/2 (round caps and joins,
64 segments per quarter circle), every lake polygon made valid
(make_valid: even-odd per polygon), all unioned, then clipped to the squares
of the global block grid. OGR/OSR are used only to read the inputs and to
reproject them to the working CRS, applying the same input rules as the
driver's specification (WHERE filters, WIDTH_FIELD parsing and fallback,
skipped empty/NULL/zero-length geometries, curves linearized, Z/M dropped).

The comparison helpers work on plain records (see `Feat`): they do not know
about GDAL datasets. Works with shapely 1.8 and 2.x.
"""

import math
import re
from collections import defaultdict, namedtuple

import numpy as np
from osgeo import ogr, osr
from shapely import wkb as shapely_wkb
from shapely.geometry import (GeometryCollection, LineString, MultiPolygon,
                              Polygon, box)
from shapely.ops import unary_union
from shapely.prepared import prep

try:  # shapely >= 1.8
    from shapely.validation import make_valid as _make_valid
except ImportError:  # pragma: no cover
    from shapely import make_valid as _make_valid

SHAPELY2 = int(__import__('shapely').__version__.split('.')[0]) >= 2

QUAD_SEGS = 64

# One driver output feature: block (bx, by), shapely geometry, the WKB as
# read from OGR, and the attribute fields (dict).
Feat = namedtuple('Feat', 'block geom wkb fields')


# ----------------------------------------------------------------------------
# report shared by the tests (printed / written by conftest at session end)
# ----------------------------------------------------------------------------

REPORT = []


def record(name, **figures):
    """Records measured figures under `name` (printed at the end of the
    session and written to autotest/oracle_report.txt by conftest)."""
    REPORT.append((name, figures))
    print('\n[oracle] %s: %s' % (name, format_figures(figures)))


def format_figures(figures):
    out = []
    for k, v in figures.items():
        if isinstance(v, float):
            out.append('%s=%.6g' % (k, v))
        else:
            out.append('%s=%s' % (k, v))
    return ' '.join(out)


# ----------------------------------------------------------------------------
# inputs
# ----------------------------------------------------------------------------

_NUMBER_RE = re.compile(r'^\s*([+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)')


def parse_width(value):
    """Width from a field value as the spec reads it: a number, or a text
    starting with a number ("3", "2.5 m"). Returns None when NULL, empty,
    unparsable, not finite or <= 0 (the caller then falls back to WIDTH)."""
    if value is None:
        return None
    if isinstance(value, (int, float)):
        v = float(value)
    else:
        m = _NUMBER_RE.match(str(value))
        if not m:
            return None
        v = float(m.group(1))
    if not math.isfinite(v) or v <= 0:
        return None
    return v


def _srs(crs):
    if crs is None:
        return None
    if isinstance(crs, osr.SpatialReference):
        s = crs.Clone()
    else:
        s = osr.SpatialReference()
        if isinstance(crs, int):
            s.ImportFromEPSG(crs)
        else:
            assert s.SetFromUserInput(str(crs)) == 0, crs
    s.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    return s


def utm_epsg(lon, lat):
    """EPSG code of the WGS 84 UTM zone holding (lon, lat)."""
    zone = int(math.floor((lon + 180.0) / 6.0)) + 1
    zone = min(max(zone, 1), 60)
    return (32600 if lat >= 0 else 32700) + zone


def _open_layer(path, layer, where):
    ds = ogr.Open(path)
    assert ds is not None, 'oracle: cannot open %s' % path
    lyr = ds.GetLayerByName(layer) if layer else ds.GetLayer(0)
    assert lyr is not None, 'oracle: no layer %s in %s' % (layer, path)
    if where:
        assert lyr.SetAttributeFilter(where) == 0, where
    return ds, lyr


def _layer_srs(lyr):
    s = lyr.GetSpatialRef()
    if s is not None:
        s = s.Clone()
        s.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    return s


def _geographic_center(lyrs):
    """Center (lon, lat) of the union of the layers' extents."""
    env = None
    for lyr in lyrs:
        if lyr is None:
            continue
        e = lyr.GetExtent()
        env = e if env is None else (min(env[0], e[0]), max(env[1], e[1]),
                                     min(env[2], e[2]), max(env[3], e[3]))
    return (env[0] + env[1]) / 2.0, (env[2] + env[3]) / 2.0


Inputs = namedtuple('Inputs', 'rivers lakes srs n_fallback_widths')


def working_srs(rivers_lyr, lakes_lyr, target_srs=None):
    """The spec's working CRS: TARGET_SRS, else the rivers' CRS (the lakes'
    when there are no rivers) if projected, else the UTM zone of the
    scene's center."""
    if target_srs is not None:
        return _srs(target_srs)
    main = rivers_lyr if rivers_lyr is not None else lakes_lyr
    s = _layer_srs(main)
    assert s is not None, 'oracle: input has no CRS'
    if s.IsProjected():
        return s
    geo = [l for l in (rivers_lyr, lakes_lyr) if l is not None]
    # the extents are in the (geographic) layer CRS, traditional order
    lon, lat = _geographic_center(geo)
    return _srs(utm_epsg(lon, lat))


def _to_shapely_parts(g, ct, want):
    """OGR geometry -> list of shapely parts (LineString or Polygon), curves
    linearized, Z/M dropped, reprojected with ct (may be None)."""
    if g is None or g.IsEmpty():
        return []
    g = g.Clone()
    if ogr.GT_IsNonLinear(g.GetGeometryType()):
        g = g.GetLinearGeometry()
    g.FlattenTo2D()
    if hasattr(g, 'SetMeasured'):
        g.SetMeasured(False)
    if ct is not None:
        assert g.Transform(ct) == 0, 'oracle: reprojection failed'
    s = shapely_wkb.loads(bytes(g.ExportToIsoWkb()))
    parts, flat = [s], []
    while parts:  # collections flattened, nested ones too
        p = parts.pop(0)
        if hasattr(p, 'geoms'):
            parts[:0] = list(p.geoms)
        else:
            flat.append(p)
    parts = flat
    out = []
    for p in parts:
        if p.is_empty:
            continue
        if want == 'line' and p.geom_type == 'LineString':
            out.append(p)
        elif want == 'polygon' and p.geom_type == 'Polygon':
            out.append(p)
    return out


def load_inputs(rivers=None, rivers_layer=None, rivers_where=None,
                lakes=None, lakes_layer=None, lakes_where=None,
                width=10.0, width_field=None, target_srs=None, bbox=None):
    """Reads a scene the way the spec says the driver reads it.

    bbox (xmin, ymin, xmax, ymax) in the working CRS, optional: keep only
    the features that can reach it (speed-up for large real data sets).
    Returns Inputs(rivers=[(LineString, width)], lakes=[Polygon], srs,
    n_fallback_widths)."""
    rds = lds = rl = ll = None
    if rivers:
        rds, rl = _open_layer(rivers, rivers_layer, rivers_where)
    if lakes:
        lds, ll = _open_layer(lakes, lakes_layer, lakes_where)
    assert rl is not None or ll is not None
    wsrs = working_srs(rl, ll, target_srs)

    def ct_for(lyr):
        s = _layer_srs(lyr)
        if s is None or s.IsSame(wsrs):
            return None
        return osr.CoordinateTransformation(s, wsrs)

    def near(geom, pad):
        if bbox is None:
            return True
        x0, y0, x1, y1 = geom.bounds
        return not (x1 < bbox[0] - pad or x0 > bbox[2] + pad or
                    y1 < bbox[1] - pad or y0 > bbox[3] + pad)

    river_list, lake_list, n_fallback = [], [], 0
    if rl is not None:
        ct = ct_for(rl)
        for f in rl:
            w = width
            if width_field:
                v = parse_width(f.GetField(width_field)) if f.IsFieldSetAndNotNull(width_field) else None
                if v is None:
                    n_fallback += 1
                else:
                    w = v
            for part in _to_shapely_parts(f.GetGeometryRef(), ct, 'line'):
                if part.length == 0:
                    continue  # zero-length rivers are skipped
                if near(part, w):
                    river_list.append((part, w))
    if ll is not None:
        ct = ct_for(ll)
        for f in ll:
            for part in _to_shapely_parts(f.GetGeometryRef(), ct, 'polygon'):
                if near(part, 0.0):
                    lake_list.append(part)
    del rds, lds
    return Inputs(river_list, lake_list, wsrs, n_fallback)


# ----------------------------------------------------------------------------
# the oracle geometry
# ----------------------------------------------------------------------------

def _polygonal(g):
    """Polygonal part of a geometry (drops points/lines make_valid may add)."""
    if g.is_empty:
        return []
    if g.geom_type == 'Polygon':
        return [g]
    if g.geom_type == 'MultiPolygon':
        return list(g.geoms)
    if g.geom_type == 'GeometryCollection':
        out = []
        for p in g.geoms:
            out.extend(_polygonal(p))
        return out
    return []


def _buffer(geom, r):
    if SHAPELY2:
        return geom.buffer(r, quad_segs=QUAD_SEGS)
    return geom.buffer(r, resolution=QUAD_SEGS)


def buffer_river(line, width):
    """The river's water: its line grown by width / 2. A line that is not
    simple is grown segment by segment and dissolved (the definition):
    GEOS 3.11 buffers a line that loops and runs over its first segment
    again as a filled disc, the land inside the loop lost (twins seed
    126099 at 0.5 m: 458 m² instead of 277 m²)."""
    if line.is_simple:
        return _buffer(line, width / 2.0)
    c = list(line.coords)
    return unary_union([_buffer(LineString(c[i:i + 2]), width / 2.0)
                        for i in range(len(c) - 1)])


def water(inputs):
    """Exact buffer-and-dissolve of the scene (a shapely (Multi)Polygon)."""
    parts = [buffer_river(l, w) for l, w in inputs.rivers]
    for p in inputs.lakes:
        parts.extend(_polygonal(_make_valid(p)))
    if not parts:
        return GeometryCollection()
    return _drop_degenerate(unary_union(parts))


def _drop_degenerate(geom):
    """geom without the degenerate rings GEOS's union may leave (a hole
    thinner than a micron, 2 * area / perimeter, where two inputs share a
    boundary up to rounding): no land or water is there, and they would
    count as boundary."""
    def ok(ring):
        return 2.0 * Polygon(ring).area > 1e-6 * ring.length
    polys = [Polygon(p.exterior, [r for r in p.interiors if ok(r)])
             for p in polygons_of(geom) if ok(p.exterior)]
    return MultiPolygon(polys) if len(polys) != 1 else polys[0]


def block_box(block, block_size):
    bx, by = block
    return box(bx * block_size, by * block_size, (bx + 1) * block_size, (by + 1) * block_size)


def blocks_touching(bounds, block_size):
    """Blocks whose closed square meets the closed rectangle bounds."""
    x0, y0, x1, y1 = bounds
    bxs = range(int(math.floor(x0 / block_size)), int(math.floor(x1 / block_size)) + 1)
    bys = range(int(math.floor(y0 / block_size)), int(math.floor(y1 / block_size)) + 1)
    return {(bx, by) for bx in bxs for by in bys}


def clip_to_blocks(geom, block_size, blocks=None):
    """{block: polygonal geometry of geom inside the block square} for the
    blocks (default: every block geom touches) where it has positive area."""
    if geom.is_empty:
        return {}
    if blocks is None:
        blocks = blocks_touching(geom.bounds, block_size)
    out = {}
    pg = prep(geom)
    for b in sorted(blocks):
        sq = block_box(b, block_size)
        if not pg.intersects(sq):
            continue
        c = unary_union(_polygonal(geom.intersection(sq)))
        if not c.is_empty and c.area > 0:
            out[b] = c
    return out


def oracle_blocks(inputs, block_size, blocks=None):
    """water(inputs) clipped to blocks: {block: geometry}."""
    return clip_to_blocks(water(inputs), block_size, blocks)


# ----------------------------------------------------------------------------
# small geometry helpers (numpy, in block-local coordinates where it matters)
# ----------------------------------------------------------------------------

def polygons_of(geom):
    if geom is None or geom.is_empty:
        return []
    if geom.geom_type == 'Polygon':
        return [geom]
    if hasattr(geom, 'geoms'):
        out = []
        for g in geom.geoms:
            out.extend(polygons_of(g))
        return out
    return []


def rings_of(poly):
    return [np.asarray(poly.exterior.coords, dtype=float)] + \
           [np.asarray(r.coords, dtype=float) for r in poly.interiors]


def ring_area(coords, origin=(0.0, 0.0)):
    """Unsigned shoelace area of a closed ring, computed relative to origin."""
    x = coords[:, 0] - origin[0]
    y = coords[:, 1] - origin[1]
    return abs(0.5 * float(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1])))


def polygon_area(poly, origin=(0.0, 0.0)):
    rings = rings_of(poly)
    return ring_area(rings[0], origin) - sum(ring_area(r, origin) for r in rings[1:])


def geom_area(geom, origin=(0.0, 0.0)):
    return sum(polygon_area(p, origin) for p in polygons_of(geom))


def block_origin(block, block_size):
    return (block[0] * block_size, block[1] * block_size)


def vertex_count(feats):
    n = 0
    for f in feats:
        for p in polygons_of(f.geom):
            n += sum(len(r) - 1 for r in rings_of(p))
    return n


def by_block(feats):
    d = defaultdict(list)
    for f in feats:
        d[f.block].append(f)
    return d


def explain_validity(geom):
    try:
        from shapely.validation import explain_validity as ev
        return ev(geom)
    except Exception:  # pragma: no cover
        return 'invalid'


# ----------------------------------------------------------------------------
# checks on driver output (return lists of problems: empty list == OK)
# ----------------------------------------------------------------------------

def check_water(feats, block_size, area_rel=1e-9):
    """Every water feature: a non-empty valid Polygon inside its block
    square, `area` field equal to its area; polygons of a block pairwise
    interior-disjoint."""
    problems = []
    for i, f in enumerate(feats):
        g = f.geom
        tag = 'water feature #%d block %s' % (i, f.block)
        if g is None or g.is_empty:
            problems.append('%s: empty geometry' % tag)
            continue
        if g.geom_type != 'Polygon':
            problems.append('%s: geometry type %s, not Polygon' % (tag, g.geom_type))
        if not g.is_valid:
            problems.append('%s: invalid: %s' % (tag, explain_validity(g)))
        x0, y0, x1, y1 = g.bounds
        bx0, by0 = block_origin(f.block, block_size)
        if x0 < bx0 or y0 < by0 or x1 > bx0 + block_size or y1 > by0 + block_size:
            problems.append('%s: bounds %s outside block square' % (tag, (x0, y0, x1, y1)))
        a = geom_area(g, (bx0, by0))
        if a <= 0:
            problems.append('%s: non-positive area %r' % (tag, a))
        fa = f.fields.get('area')
        if fa is None or abs(fa - a) > area_rel * max(a, 1e-300) + 1e-12:
            problems.append('%s: area field %r != polygon area %r' % (tag, fa, a))
    for b, fs in by_block(feats).items():
        if len(fs) < 2:
            continue
        polys = [f.geom for f in fs if f.geom is not None and f.geom.is_valid]
        total = sum(p.area for p in polys)
        try:
            u = unary_union(polys).area
        except Exception as e:  # pragma: no cover
            problems.append('block %s: union of water polygons failed: %s' % (b, e))
            continue
        if total - u > 1e-9 * total:
            problems.append('block %s: water polygons overlap (sum %r > union %r)' % (b, total, u))
    return problems


def _triangles_array(mp):
    """(n, 4, 2) array of the triangles of a mesh MultiPolygon, or None when
    some part is not a closed 4-point ring without holes."""
    tris = polygons_of(mp)
    arr = []
    for t in tris:
        c = np.asarray(t.exterior.coords, dtype=float)
        if len(t.interiors) or c.shape != (4, 2) or not np.array_equal(c[0], c[3]):
            return None
        arr.append(c)
    return np.asarray(arr, dtype=float).reshape(-1, 4, 2)


def _tri_areas(arr, origin):
    a = arr[:, :, 0] - origin[0]
    b = arr[:, :, 1] - origin[1]
    return 0.5 * ((a[:, 1] - a[:, 0]) * (b[:, 2] - b[:, 0]) - (a[:, 2] - a[:, 0]) * (b[:, 1] - b[:, 0]))


def check_mesh(mesh_feats, water_feats, block_size, rel=1e-9):
    """Mesh features against water features. Returns (problems, stats).

    Per mesh feature: a MultiPolygon of triangles (Polygon, 4 points, positive
    area), `triangles` field = number of triangles, in the same block as
    exactly one water polygon that contains it; triangle area sum equals that
    polygon's area (relative `rel`); triangles do not overlap (sum of areas
    equals the area of their union, relative `rel`) and cover the polygon
    (symmetric difference area <= rel * area). Every water polygon has
    exactly one mesh feature. Computed in block-local coordinates."""
    problems = []
    stats = {'mesh_features': len(mesh_feats), 'triangles': 0,
             'max_rel_area_err': 0.0, 'max_rel_overlap': 0.0, 'max_rel_cover_err': 0.0}
    water_bb = by_block(water_feats)
    used = defaultdict(int)
    for i, m in enumerate(mesh_feats):
        tag = 'mesh feature #%d block %s' % (i, m.block)
        if m.geom is None or m.geom.is_empty or m.geom.geom_type != 'MultiPolygon':
            problems.append('%s: geometry %s is not a non-empty MultiPolygon'
                            % (tag, None if m.geom is None else m.geom.geom_type))
            continue
        arr = _triangles_array(m.geom)
        if arr is None:
            problems.append('%s: a part is not a triangle (Polygon with 4 points)' % tag)
            continue
        ntri = arr.shape[0]
        stats['triangles'] += ntri
        if m.fields.get('triangles') != ntri:
            problems.append('%s: triangles field %r != %d parts' % (tag, m.fields.get('triangles'), ntri))
        origin = block_origin(m.block, block_size)
        x0, y0, x1, y1 = m.geom.bounds
        if x0 < origin[0] or y0 < origin[1] or x1 > origin[0] + block_size or y1 > origin[1] + block_size:
            problems.append('%s: bounds outside block square' % tag)
        areas = np.abs(_tri_areas(arr, origin))
        if not np.all(areas > 0):
            problems.append('%s: %d degenerate triangles' % (tag, int(np.sum(areas <= 0))))
        # matching water polygon: the one containing a triangle's centroid
        c = arr[0, :3].mean(axis=0)
        from shapely.geometry import Point
        cands = [j for j, w in enumerate(water_bb.get(m.block, []))
                 if w.geom is not None and w.geom.contains(Point(c[0], c[1]))]
        if len(cands) != 1:
            problems.append('%s: %d water polygons of the block contain its first triangle'
                            % (tag, len(cands)))
            continue
        j = cands[0]
        used[(m.block, j)] += 1
        w = water_bb[m.block][j].geom
        wa = geom_area(w, origin)
        s = float(np.sum(areas))
        err = abs(s - wa) / wa
        stats['max_rel_area_err'] = max(stats['max_rel_area_err'], err)
        if err > rel:
            problems.append('%s: triangle area sum %r != water polygon area %r (rel %.3g)' % (tag, s, wa, err))
        local = [Polygon(t[:3] - np.asarray(origin)) for t in arr]
        try:
            u = unary_union(local)
        except Exception as e:  # pragma: no cover
            problems.append('%s: union of triangles failed: %s' % (tag, e))
            continue
        ov = (s - u.area) / s
        stats['max_rel_overlap'] = max(stats['max_rel_overlap'], ov)
        if ov > rel:
            problems.append('%s: triangles overlap: sum %r > union %r (rel %.3g)' % (tag, s, u.area, ov))
        wl = Polygon(*_local_rings(w, origin))
        try:
            cover = u.symmetric_difference(wl).area / wa
        except Exception as e:  # pragma: no cover
            problems.append('%s: coverage overlay failed: %s' % (tag, e))
            continue
        stats['max_rel_cover_err'] = max(stats['max_rel_cover_err'], cover)
        if cover > rel:
            problems.append('%s: triangles do not cover the water polygon (sym. diff. rel %.3g)' % (tag, cover))
    for b, ws in water_bb.items():
        for j in range(len(ws)):
            if used.get((b, j), 0) != 1:
                problems.append('water polygon #%d of block %s has %d mesh features'
                                % (j, b, used.get((b, j), 0)))
    return problems, stats


def _local_rings(poly, origin):
    o = np.asarray(origin)
    rings = [r - o for r in rings_of(poly)]
    return rings[0], rings[1:]


# ----------------------------------------------------------------------------
# seams between adjacent blocks
# ----------------------------------------------------------------------------

def _edge_keys(block):
    """The 4 edges of a block: (key, axis, coordinate of the edge line,
    side). key ('v', i, j): vertical line x = i*B between blocks (i-1, j)
    and (i, j); ('h', i, j): horizontal line y = j*B between (i, j-1) and
    (i, j). side 0 = the block is on the low side."""
    bx, by = block
    return [(('v', bx, by), 0, 'lo'), (('v', bx + 1, by), 0, 'hi'),
            (('h', bx, by), 1, 'lo'), (('h', bx, by + 1), 1, 'hi')]


def _merge(intervals):
    out = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return [tuple(i) for i in out]


def _interval_symdiff(a, b):
    """Pieces of positive length covered by exactly one of two merged
    interval lists."""
    pts = sorted(set([x for i in a for x in i] + [x for i in b for x in i]))

    def cov(ints, x):
        return any(lo <= x <= hi for lo, hi in ints)
    out = []
    for lo, hi in zip(pts[:-1], pts[1:]):
        mid = 0.5 * (lo + hi)
        if cov(a, mid) != cov(b, mid):
            out.append((lo, hi))
    return out


def _feature_rings(geom):
    """All ring coordinates of a (Multi)Polygon as one (n, 2) array plus a
    boolean array telling which (k, k+1) pairs are ring segments."""
    rings = [r for p in polygons_of(geom) for r in rings_of(p)]
    if not rings:
        return np.zeros((0, 2)), np.zeros(0, dtype=bool)
    coords = np.vstack(rings)
    seg = np.ones(len(coords), dtype=bool)
    ends = np.cumsum([len(r) for r in rings]) - 1
    seg[ends] = False  # last vertex of a ring starts no segment
    return coords, seg[:-1]


def edge_data(feats, block_size):
    """{edge key: {'lo'|'hi': (set of vertex positions along the edge,
    merged covered intervals)}} from the rings of the features' polygons
    (water polygons or mesh triangles). A vertex is on an edge when its
    coordinate equals the edge line exactly and it lies on the closed edge
    segment; an interval is covered when a ring segment runs along it."""
    B = float(block_size)
    acc = defaultdict(lambda: defaultdict(lambda: (set(), [])))
    for f in feats:
        coords, seg = _feature_rings(f.geom)
        if len(coords) == 0:
            continue
        bx, by = f.block
        for key, axis, side in _edge_keys(f.block):
            line = key[1] * B if key[0] == 'v' else key[2] * B
            other = 1 - axis
            lo = (by if key[0] == 'v' else bx) * B
            hi = lo + B
            on = (coords[:, axis] == line) & (coords[:, other] >= lo) & (coords[:, other] <= hi)
            if not on.any():
                continue
            verts, ints = acc[key][side]
            verts.update(coords[on, other].tolist())
            both = on[:-1] & on[1:] & seg
            ks = np.nonzero(both)[0]
            if len(ks):
                a, b = coords[ks, other], coords[ks + 1, other]
                keep = a != b
                ints.extend(zip(np.minimum(a, b)[keep].tolist(), np.maximum(a, b)[keep].tolist()))
    out = {}
    for key, sides in acc.items():
        out[key] = {s: (v, _merge(i)) for s, (v, i) in sides.items()}
    return out


def check_seams(feats, block_size, computed_blocks=None):
    """Seam check between every pair of adjacent computed blocks.

    computed_blocks: the set of blocks the driver computed (None: all
    blocks - a block without features is computed and empty). Returns
    (t_junctions, gaps, details): t_junctions counts the on-edge vertices
    present on one side only, gaps the pieces of a shared edge covered by
    water on one side only."""
    ed = edge_data(feats, block_size)
    t_junctions, gaps, details = 0, 0, []
    for key, sides in sorted(ed.items()):
        kind, i, j = key
        lo_block = (i - 1, j) if kind == 'v' else (i, j - 1)
        hi_block = (i, j)
        # 'hi' edge of lo_block is the 'lo' edge of hi_block
        if computed_blocks is not None and not (lo_block in computed_blocks and hi_block in computed_blocks):
            continue
        va, ia = sides.get('hi', (set(), []))
        vb, ib = sides.get('lo', (set(), []))
        only = va ^ vb
        if only:
            t_junctions += len(only)
            details.append('edge %s between %s and %s: %d vertices on one side only, e.g. %s'
                           % (key, lo_block, hi_block, len(only), sorted(only)[:3]))
        sd = _interval_symdiff(ia, ib)
        if sd:
            gaps += len(sd)
            details.append('edge %s between %s and %s: covered on one side only: %s'
                           % (key, lo_block, hi_block, sd[:3]))
    return t_junctions, gaps, details


# ----------------------------------------------------------------------------
# Hausdorff distance between boundaries (numpy, grid-accelerated)
# ----------------------------------------------------------------------------

def boundary_segments(geoms):
    """(n, 4) array x0, y0, x1, y1 of the ring segments of the polygons."""
    segs = []
    for g in geoms:
        for p in polygons_of(g):
            for r in rings_of(p):
                if len(r) >= 2:
                    segs.append(np.hstack([r[:-1], r[1:]]))
    if not segs:
        return np.zeros((0, 4))
    return np.vstack(segs)


def densify_segments(segs, step):
    """Points along the segments, at most `step` apart (endpoints included)."""
    if len(segs) == 0:
        return np.zeros((0, 2))
    d = segs[:, 2:] - segs[:, :2]
    n = np.maximum(1, np.ceil(np.hypot(d[:, 0], d[:, 1]) / step).astype(np.int64))
    idx = np.repeat(np.arange(len(segs)), n)
    start = np.repeat(np.cumsum(n) - n, n)
    t = (np.arange(int(n.sum())) - start) / np.repeat(n, n)
    pts = segs[idx, :2] + d[idx] * t[:, None]
    return np.vstack([pts, segs[:, 2:]])


def _split_segments(segs, maxlen):
    d = segs[:, 2:] - segs[:, :2]
    n = np.maximum(1, np.ceil(np.hypot(d[:, 0], d[:, 1]) / maxlen).astype(np.int64))
    idx = np.repeat(np.arange(len(segs)), n)
    k = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
    nn = np.repeat(n, n)
    a = segs[idx, :2] + d[idx] * (k / nn)[:, None]
    b = segs[idx, :2] + d[idx] * ((k + 1) / nn)[:, None]
    return np.hstack([a, b])


def _point_segment_dist(p, s):
    """Distances between points p (n, 2) and segments s (n, 4), pairwise."""
    ax, ay = s[:, 0], s[:, 1]
    dx, dy = s[:, 2] - ax, s[:, 3] - ay
    l2 = dx * dx + dy * dy
    with np.errstate(invalid='ignore', divide='ignore'):
        t = ((p[:, 0] - ax) * dx + (p[:, 1] - ay) * dy) / l2
    t = np.where(l2 > 0, np.clip(t, 0.0, 1.0), 0.0)
    return np.hypot(p[:, 0] - (ax + t * dx), p[:, 1] - (ay + t * dy))


def nearest_distances(points, segs, cell, chunk=200000):
    """Exact distance from each point to the nearest segment (inf if none),
    with a uniform grid of `cell` m; points whose nearest segment lies beyond
    the grid's guaranteed reach are redone with a coarser grid."""
    n = len(points)
    best = np.full(n, np.inf)
    if n == 0 or len(segs) == 0:
        return best
    lo = np.minimum(points.min(axis=0), np.minimum(segs[:, :2].min(axis=0), segs[:, 2:].min(axis=0)))
    hi = np.maximum(points.max(axis=0), np.maximum(segs[:, :2].max(axis=0), segs[:, 2:].max(axis=0)))
    span = float(np.max(hi - lo))
    pieces = _split_segments(segs, cell / 2.0)
    mid = 0.5 * (pieces[:, :2] + pieces[:, 2:])
    ncell = np.floor((hi - lo) / cell).astype(np.int64) + 3
    ci = np.floor((mid - lo) / cell).astype(np.int64) + 1
    keys = ci[:, 0] * ncell[1] + ci[:, 1]
    order = np.argsort(keys, kind='stable')
    keys, pieces = keys[order], pieces[order]
    for c0 in range(0, n, chunk):
        p = points[c0:c0 + chunk]
        pc = np.floor((p - lo) / cell).astype(np.int64) + 1
        b = np.full(len(p), np.inf)
        for ox in (-1, 0, 1):
            for oy in (-1, 0, 1):
                k = (pc[:, 0] + ox) * ncell[1] + (pc[:, 1] + oy)
                l = np.searchsorted(keys, k, 'left')
                r = np.searchsorted(keys, k, 'right')
                cnt = r - l
                tot = int(cnt.sum())
                if tot == 0:
                    continue
                pi = np.repeat(np.arange(len(p)), cnt)
                first = np.cumsum(cnt) - cnt
                si = np.repeat(l, cnt) + (np.arange(tot) - np.repeat(first, cnt))
                d = _point_segment_dist(p[pi], pieces[si])
                has = cnt > 0
                b[has] = np.minimum(b[has], np.minimum.reduceat(d, first[has]))
        best[c0:c0 + chunk] = b
    if cell > span:
        return best  # every piece was in every point's neighbourhood: exact
    unresolved = np.nonzero(best > 0.75 * cell)[0]
    if len(unresolved):
        best[unresolved] = nearest_distances(points[unresolved], segs, cell * 8.0, chunk)
    return best


def _frame_distance(points, blocks, block_size):
    B = float(block_size)
    x0 = blocks[:, 0] * B
    y0 = blocks[:, 1] * B
    return np.minimum.reduce([points[:, 0] - x0, x0 + B - points[:, 0],
                              points[:, 1] - y0, y0 + B - points[:, 1]])


def _tagged_points(by_block_geoms, step):
    pts, tags = [], []
    for b, geoms in by_block_geoms.items():
        p = densify_segments(boundary_segments(geoms), step)
        pts.append(p)
        tags.append(np.tile(np.asarray(b, dtype=float), (len(p), 1)))
    if not pts:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return np.vstack(pts), np.vstack(tags)


def hausdorff(a_by_block, b_by_block, block_size, step, cell=None):
    """Symmetric Hausdorff distance between the boundaries of two block-wise
    clipped polygon sets ({block: [geometries]}), each block's square
    boundary counted as part of both boundaries (so water cut by a block
    edge is compared like-for-like). Boundaries are sampled every `step` m
    (the result may underestimate by at most step/2); distances to the
    other boundary are exact. Returns dict(hausdorff, a_to_b, b_to_a,
    where (x, y) of the worst point, p99, mean)."""
    if cell is None:
        cell = max(40.0 * step, 1.0)
    out = {}
    worst = (0.0, None)
    all_d = []
    for name, src, dst in (('a_to_b', a_by_block, b_by_block), ('b_to_a', b_by_block, a_by_block)):
        pts, tags = _tagged_points(src, step)
        segs = boundary_segments([g for gs in dst.values() for g in gs])
        d = nearest_distances(pts, segs, cell) if len(pts) else np.zeros(0)
        if len(pts):
            d = np.minimum(d, _frame_distance(pts, tags, block_size))
            k = int(np.argmax(d))
            if d[k] > worst[0]:
                worst = (float(d[k]), (float(pts[k, 0]), float(pts[k, 1])))
        out[name] = float(d.max()) if len(d) else 0.0
        all_d.append(d)
    d = np.concatenate(all_d) if all_d else np.zeros(0)
    out['hausdorff'] = max(out['a_to_b'], out['b_to_a'])
    out['where'] = worst[1]
    out['p99'] = float(np.percentile(d, 99)) if len(d) else 0.0
    out['mean'] = float(d.mean()) if len(d) else 0.0
    return out


# ----------------------------------------------------------------------------
# driver output vs oracle
# ----------------------------------------------------------------------------

def compare(water_feats, oracle_by_block, block_size, pixel_size, step=None):
    """Figures comparing driver water features with the oracle clipped to
    blocks: area_driver, area_oracle, rel_area_diff, symdiff_area,
    hausdorff (+ a_to_b = driver -> oracle, b_to_a, where, p99, mean) and
    the block sets."""
    if step is None:
        step = min(0.1, pixel_size / 10.0)
    drv = defaultdict(list)
    for f in water_feats:
        drv[f.block].append(f.geom)
    orc = {b: [g] for b, g in oracle_by_block.items()}
    area_d = sum(geom_area(g, block_origin(b, block_size)) for b, gs in drv.items() for g in gs)
    area_o = sum(geom_area(g, block_origin(b, block_size)) for b, g in oracle_by_block.items())
    symdiff = 0.0
    for b in set(drv) | set(orc):
        a = unary_union(drv.get(b, []))
        o = oracle_by_block.get(b, GeometryCollection())
        symdiff += a.symmetric_difference(o).area if not (a.is_empty and o.is_empty) else 0.0
    h = hausdorff(drv, orc, block_size, step)
    res = {'area_driver': area_d, 'area_oracle': area_o,
           'rel_area_diff': (area_d - area_o) / area_o if area_o else float('inf'),
           'symdiff_area': symdiff,
           'rel_symdiff': symdiff / area_o if area_o else float('inf'),
           'hausdorff': h['hausdorff'], 'hausdorff_px': h['hausdorff'] / pixel_size,
           'driver_to_oracle': h['a_to_b'], 'oracle_to_driver': h['b_to_a'],
           'p99': h['p99'], 'mean_dist': h['mean'], 'worst_at': h['where'],
           'blocks_driver': len(drv), 'blocks_oracle': len(orc)}
    return res


def as_feats(by_block_geoms, with_area=True):
    """Oracle {block: geometry} -> list of Feat (one per polygon), e.g. to
    run the checks on the oracle itself."""
    out = []
    for b in sorted(by_block_geoms):
        for p in polygons_of(by_block_geoms[b]):
            fields = {'block_x': b[0], 'block_y': b[1]}
            if with_area:
                fields['area'] = p.area
            out.append(Feat(b, p, bytes(p.wkb), fields))
    return out


# ----------------------------------------------------------------------------
# spec options -> oracle
# ----------------------------------------------------------------------------

DEFAULT_WIDTH = 10.0
DEFAULT_PIXEL_SIZE = 0.5
DEFAULT_BLOCK_SIZE = 4096.0


def inputs_from_options(options, bbox=None):
    """load_inputs() from a dict of the driver's open options (RIVERS,
    RIVERS_LAYER, ..., WIDTH, WIDTH_FIELD, TARGET_SRS; others ignored)."""
    o = {k.upper(): v for k, v in options.items() if v is not None}
    return load_inputs(rivers=o.get('RIVERS'), rivers_layer=o.get('RIVERS_LAYER'),
                       rivers_where=o.get('RIVERS_WHERE'), lakes=o.get('LAKES'),
                       lakes_layer=o.get('LAKES_LAYER'), lakes_where=o.get('LAKES_WHERE'),
                       width=float(o.get('WIDTH', DEFAULT_WIDTH)),
                       width_field=o.get('WIDTH_FIELD'), target_srs=o.get('TARGET_SRS'),
                       bbox=bbox)


def water_area(options):
    """Area of the oracle water of a scene given as open options."""
    return water(inputs_from_options(options)).area


def exact_signed_distance_outside(inputs, x, y):
    """Exact distance from (x, y) to the scene's water when (x, y) is
    outside it (min over rivers of centerline distance - width/2 and over
    lakes of the distance to the lake); <= 0 means inside some river/lake
    (the value is then only an upper bound of the depth)."""
    from shapely.geometry import Point
    p = Point(x, y)
    d = float('inf')
    for line, w in inputs.rivers:
        d = min(d, line.distance(p) - w / 2.0)
    for lake in inputs.lakes:
        for part in _polygonal(_make_valid(lake)):
            if part.contains(p):
                d = min(d, -part.boundary.distance(p))
            else:
                d = min(d, part.distance(p))
    return d


def total_area(feats):
    """Sum of the areas of the features' geometries."""
    return sum(f.geom.area for f in feats if f.geom is not None)


# ----------------------------------------------------------------------------
# reference mesh (for the oracle self-test only)
# ----------------------------------------------------------------------------

def reference_mesh(poly):
    """Constrained Delaunay triangulation of a polygon by GEOS (>= 3.10):
    a MultiPolygon of triangles. Used only to check the mesh checks."""
    try:
        import shapely
        return MultiPolygon(list(shapely.constrained_delaunay_triangles(poly).geoms))
    except AttributeError:
        pass
    import ctypes
    from shapely.geos import lgeos
    from shapely.geometry.base import geom_factory
    f = lgeos._lgeos.GEOSConstrainedDelaunayTriangulation_r
    f.restype = ctypes.c_void_p
    f.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    g = geom_factory(f(lgeos.geos_handle, poly._geom))
    return MultiPolygon(list(g.geoms))


def water_union(by_block):
    """Union of an oracle {block: geometry} (undoes the block clipping)."""
    return unary_union(list(by_block.values()))


def fill_holes(geom):
    """The geometry with every hole filled."""
    return unary_union([Polygon(p.exterior) for p in polygons_of(geom)])
