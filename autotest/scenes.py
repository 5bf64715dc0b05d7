"""Synthetic input scenes for the watermesh autotest.

Everything here is deterministic: random scenes take a seed and use their own
random.Random(seed) (no global random state), hand-made scenes are fixed.
Every writer returns the path it wrote.

Conventions of the written GeoPackages (used by the tests and by oracle.py):
  - layer ``rivers``: LineString, fields ``width`` (Real) and ``name`` (String);
    the hand-made scene adds ``width_txt`` (String);
  - layer ``lakes``: MultiPolygon (parts may have holes), field ``name``;
  - layers are written rivers first, so layer 0 of a scene is ``rivers``;
  - CRS EPSG:32631 unless a writer says otherwise.
"""

import math
import os
import random
from xml.sax.saxutils import escape

from osgeo import ogr, osr

SCENE_EPSG = 32631
SCENE_ORIGIN = (400000.0, 4700000.0)


# ----------------------------------------------------------------------------
# low-level writer
# ----------------------------------------------------------------------------

def srs_from(crs):
    """osr.SpatialReference (traditional GIS axis order) from an EPSG code,
    any string osr understands, or an existing SpatialReference; None stays
    None."""
    if crs is None:
        return None
    if isinstance(crs, osr.SpatialReference):
        srs = crs.Clone()
    else:
        srs = osr.SpatialReference()
        if isinstance(crs, int):
            assert srs.ImportFromEPSG(crs) == 0, crs
        else:
            assert srs.SetFromUserInput(str(crs)) == 0, crs
    srs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    return srs


def _to_ogr_geometry(geom):
    """Accepts None, WKT, an ogr.Geometry or a shapely geometry."""
    if geom is None:
        return None
    if isinstance(geom, ogr.Geometry):
        return geom.Clone()
    if isinstance(geom, str):
        g = ogr.CreateGeometryFromWkt(geom)
        assert g is not None, "bad WKT in test scene: %r" % geom
        return g
    # shapely
    return ogr.CreateGeometryFromWkb(bytes(geom.wkb))


_OGR_FIELD_TYPES = {'Real': ogr.OFTReal, 'String': ogr.OFTString,
                    'Integer': ogr.OFTInteger}


def write_layer(path, layer_name, geom_type, crs, features, fields=None,
                driver='GPKG'):
    """Writes (appends to an existing GPKG) one layer.

    features: iterable of dicts {'geom': WKT|ogr|shapely|None, 'fid': int
    (optional), other keys: field values}. fields: list of (name, 'Real' |
    'String' | 'Integer'); by default guessed from the first feature.
    """
    drv = ogr.GetDriverByName(driver)
    ds = None
    if os.path.exists(path) and driver == 'GPKG':
        ds = ogr.Open(path, update=1)
    if ds is None:
        ds = drv.CreateDataSource(path)
    assert ds is not None, "cannot create %s" % path
    lyr = ds.CreateLayer(layer_name, srs_from(crs), geom_type,
                         options=['SPATIAL_INDEX=NO'] if driver == 'GPKG' else [])
    assert lyr is not None, "cannot create layer %s in %s" % (layer_name, path)
    features = list(features)
    if fields is None:
        fields = []
        for f in features[:1]:
            for k, v in f.items():
                if k in ('geom', 'fid'):
                    continue
                fields.append((k, 'Real' if isinstance(v, float) else
                               'Integer' if isinstance(v, int) else 'String'))
    for name, typ in fields:
        assert lyr.CreateField(ogr.FieldDefn(name, _OGR_FIELD_TYPES[typ])) == 0
    defn = lyr.GetLayerDefn()
    for f in features:
        feat = ogr.Feature(defn)
        for k, v in f.items():
            if k == 'geom':
                g = _to_ogr_geometry(v)
                if g is not None:
                    feat.SetGeometryDirectly(g)
            elif k == 'fid':
                feat.SetFID(v)
            elif v is None:
                feat.SetFieldNull(k)
            else:
                feat.SetField(k, v)
        assert lyr.CreateFeature(feat) == 0, "cannot write feature %r" % (f,)
    ds = None
    return path


def write_descriptor(path, **options):
    """Writes a .watermesh descriptor: <WaterMesh><OPT>value</OPT>...</WaterMesh>.
    Option names are given in any case (upper-cased); values are str()-ed."""
    body = ''.join('  <%s>%s</%s>\n' % (k.upper(), escape(str(v)), k.upper())
                   for k, v in options.items())
    text = '<WaterMesh>\n%s</WaterMesh>\n' % body
    if path.startswith('/vsimem/'):
        from osgeo import gdal
        gdal.FileFromMemBuffer(path, text.encode('utf-8'))
    else:
        with open(path, 'w', encoding='utf-8') as f:
            f.write(text)
    return path


# ----------------------------------------------------------------------------
# random meandering river trees
# ----------------------------------------------------------------------------

def _walk(rng, start, heading, length, step, bounds, amplitude=(0.3, 0.8),
          wavelength=(120.0, 400.0), noise=0.05):
    """Meandering polyline from start: the heading oscillates around its
    initial value (sine of random amplitude in rad and wavelength in m, plus
    a little noise); stops at `length` or before leaving bounds
    (xmin, ymin, xmax, ymax)."""
    x, y = start
    pts = [(x, y)]
    amp = rng.uniform(*amplitude)
    lam = rng.uniform(*wavelength)
    phase = rng.uniform(0, 2 * math.pi)
    travelled = 0.0
    jitter = 0.0
    while travelled < length:
        d = rng.uniform(*step)
        jitter = 0.7 * jitter + rng.gauss(0.0, noise)
        h = heading + amp * math.sin(2 * math.pi * travelled / lam + phase) + jitter
        nx, ny = x + d * math.cos(h), y + d * math.sin(h)
        if not (bounds[0] <= nx <= bounds[2] and bounds[1] <= ny <= bounds[3]):
            break
        x, y = nx, ny
        pts.append((x, y))
        travelled += d
    return pts


def _blob(rng, cx, cy, r, n=48, rough=0.18, harmonics=4):
    """Smooth star-shaped ring (counter-clockwise, closed) around (cx, cy)
    with mean radius r; the radius stays in [r*(1-rough*h), r*(1+rough*h)]."""
    amps = [(rng.uniform(-rough, rough), rng.uniform(0, 2 * math.pi))
            for _ in range(harmonics)]
    pts = []
    for i in range(n):
        t = 2 * math.pi * i / n
        k = 1.0 + sum(a * math.sin((j + 2) * t + ph) / (j + 1)
                      for j, (a, ph) in enumerate(amps))
        pts.append((cx + r * k * math.cos(t), cy + r * k * math.sin(t)))
    pts.append(pts[0])
    return pts


def _ring_wkt(pts):
    return '(' + ','.join('%.3f %.3f' % p for p in pts) + ')'


def random_scene_features(seed, extent=1500.0, origin=SCENE_ORIGIN,
                          n_tributaries=5, n_lakes=3, max_depth=2,
                          step=(12.0, 35.0), main_width=(25.0, 60.0),
                          trib_width=(2.0, 20.0), junction_deg=(60.0, 120.0)):
    """Returns (rivers, lakes) as lists of feature dicts (see write_layer).

    A main river crosses the extent roughly west to east; tributaries start
    AT a vertex of their parent (the junction is a shared vertex) and leave
    at junction_deg degrees from the parent's downstream direction, up to
    max_depth levels; lakes sit on the main river (it passes through them),
    most with an island (a hole), one as a two-part MultiPolygon.
    Widths are in [2, 60] m.
    """
    rng = random.Random(seed)
    x0, y0 = origin
    margin = 0.04 * extent
    bounds = (x0 + margin, y0 + margin, x0 + extent - margin, y0 + extent - margin)

    rivers = []   # (pts, width, name, depth)
    main = _walk(rng, (bounds[0], y0 + extent * rng.uniform(0.35, 0.65)),
                 rng.uniform(-0.25, 0.25), 3 * extent, step, bounds)
    rivers.append((main, rng.uniform(*main_width), 'main', 0))

    attempts = 0
    while len(rivers) < 1 + n_tributaries and attempts < 50 * (n_tributaries + 1):
        attempts += 1
        candidates = [r for r in rivers if r[3] < max_depth and len(r[0]) >= 8]
        if not candidates:
            break
        parent = rng.choice(candidates)
        ppts, pwidth, _, pdepth = parent
        i = rng.randrange(3, len(ppts) - 3)
        (ax, ay), (bx, by) = ppts[i], ppts[i + 1]
        down = math.atan2(by - ay, bx - ax)
        ang = math.radians(rng.uniform(*junction_deg)) * rng.choice((-1, 1))
        length = rng.uniform(0.25, 0.6) * extent / (1 + pdepth)
        pts = _walk(rng, ppts[i], down + ang, length, step, bounds,
                    amplitude=(0.1, 0.5))
        if len(pts) < 5:
            continue
        width = min(rng.uniform(*trib_width), 0.6 * pwidth)
        width = max(width, trib_width[0])
        rivers.append((pts, width, 'trib%d' % len(rivers), pdepth + 1))

    lakes = []
    used = set()
    for k in range(n_lakes):
        for _ in range(20):
            i = rng.randrange(len(main) // 6, max(len(main) // 6 + 1, 5 * len(main) // 6))
            if all(abs(i - j) > 6 for j in used):
                break
        used.add(i)
        cx, cy = main[i]
        r = rng.uniform(0.05, 0.09) * extent
        shell = _blob(rng, cx, cy, r)
        parts = []
        if k % 3 != 2:
            # island: offset centre, radius small enough to stay inside
            rmin = r * (1 - 0.18 * (1 + 1 / 2 + 1 / 3 + 1 / 4))
            off = rng.uniform(0.2, 0.35) * rmin
            t = rng.uniform(0, 2 * math.pi)
            hole = _blob(rng, cx + off * math.cos(t), cy + off * math.sin(t),
                         0.25 * rmin, n=24, rough=0.1, harmonics=2)
            hole = hole[::-1]  # clockwise
            parts.append('(' + _ring_wkt(shell) + ',' + _ring_wkt(hole) + ')')
        else:
            parts.append('(' + _ring_wkt(shell) + ')')
        if k == 1:
            # a second, separate part of the same MultiPolygon
            ox, oy = cx + 2.2 * r, cy + 1.6 * r
            ox = min(max(ox, bounds[0] + r), bounds[2] - r)
            oy = min(max(oy, bounds[1] + r), bounds[3] - r)
            parts.append('(' + _ring_wkt(_blob(rng, ox, oy, 0.4 * r)) + ')')
        lakes.append({'geom': 'MULTIPOLYGON (' + ','.join(parts) + ')',
                      'name': 'lake%d' % k})

    river_feats = [{'geom': 'LINESTRING (' + ','.join('%.3f %.3f' % p for p in pts) + ')',
                    'width': round(w, 2), 'name': name}
                   for pts, w, name, _ in rivers]
    return river_feats, lakes


def make_random_scene(path, seed, **kwargs):
    """Writes a seeded random scene (layers rivers, lakes; EPSG:32631) to
    the GeoPackage `path` and returns path. kwargs: see random_scene_features
    (extent in m, n_tributaries, n_lakes, max_depth, step, ...)."""
    if os.path.exists(path):
        os.unlink(path)
    rivers, lakes = random_scene_features(seed, **kwargs)
    write_layer(path, 'rivers', ogr.wkbLineString, SCENE_EPSG, rivers,
                fields=[('width', 'Real'), ('name', 'String')])
    write_layer(path, 'lakes', ogr.wkbMultiPolygon, SCENE_EPSG, lakes,
                fields=[('name', 'String')])
    return path


# ----------------------------------------------------------------------------
# the hand-made scene used by the option tests
# ----------------------------------------------------------------------------

def xy(dx, dy, origin=SCENE_ORIGIN):
    return origin[0] + dx, origin[1] + dy


def simple_scene_features(origin=SCENE_ORIGIN):
    """A fixed small scene (about 1.2 km x 0.8 km) - see make_simple_scene."""
    def ls(*pts):
        return 'LINESTRING (' + ','.join('%.3f %.3f' % xy(x, y, origin) for x, y in pts) + ')'

    def ring(pts):
        return '(' + ','.join('%.3f %.3f' % xy(x, y, origin) for x, y in pts) + ')'

    def square(x0, y0, x1, y1):
        return [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]

    rivers = [
        # A: straight, west-east, wide
        {'geom': ls((100, 400), (500, 400), (1100, 400)), 'width': 20.0,
         'name': 'A', 'width_txt': '20'},
        # B: tributary of A, junction at A's vertex (500, 400)
        {'geom': ls((500, 400), (560, 520), (650, 700)), 'width': 8.0,
         'name': 'B', 'width_txt': '2.5 m'},
        # C: separate river in the south
        {'geom': ls((150, 120), (400, 160), (700, 110)), 'width': 12.0,
         'name': 'C', 'width_txt': 'wide'},
        # D: short river, NULL text width
        {'geom': ls((900, 650), (1050, 700)), 'width': 6.0,
         'name': 'D', 'width_txt': None},
        # E: short river, negative text width
        {'geom': ls((200, 650), (320, 720)), 'width': 4.0,
         'name': 'E', 'width_txt': '-3'},
    ]
    lakes = [
        # L1: square lake with a square island, river A passes through it
        {'geom': 'MULTIPOLYGON ((' + ring(square(750, 300, 950, 500)) + ','
                 + ring(square(820, 430, 880, 470)[::-1]) + '))', 'name': 'L1'},
        # L2: lake on its own
        {'geom': 'MULTIPOLYGON ((' + ring(square(150, 500, 300, 580)) + '))', 'name': 'L2'},
    ]
    rivers2 = [
        {'geom': ls((100, 250), (1100, 260)), 'width': 30.0, 'name': 'R2',
         'width_txt': '30'},
    ]
    ponds = [
        {'geom': 'MULTIPOLYGON ((' + ring(square(1000, 100, 1100, 200)) + '))', 'name': 'P1'},
    ]
    return rivers, lakes, rivers2, ponds


SIMPLE_INVALID_TEXT_WIDTHS = 3  # 'wide', NULL, '-3' in width_txt


def make_simple_scene(path, origin=SCENE_ORIGIN, epsg=SCENE_EPSG):
    """Hand-made scene: layers rivers (A, B, C, D, E; fields width Real,
    name, width_txt String with '20', '2.5 m', 'wide', NULL, '-3'), lakes
    (L1 with an island, A passes through it; L2), rivers2 (one river R2)
    and ponds (one lake P1)."""
    if os.path.exists(path):
        os.unlink(path)
    rivers, lakes, rivers2, ponds = simple_scene_features(origin)
    rf = [('width', 'Real'), ('name', 'String'), ('width_txt', 'String')]
    write_layer(path, 'rivers', ogr.wkbLineString, epsg, rivers, fields=rf)
    write_layer(path, 'lakes', ogr.wkbMultiPolygon, epsg, lakes, fields=[('name', 'String')])
    write_layer(path, 'rivers2', ogr.wkbLineString, epsg, rivers2, fields=rf)
    write_layer(path, 'ponds', ogr.wkbMultiPolygon, epsg, ponds, fields=[('name', 'String')])
    return path


def simple_river_point(name, origin=SCENE_ORIGIN):
    """A point on the centerline of a river of the simple scene, between
    vertices (for raster sign tests)."""
    return {'A': xy(300, 400, origin), 'B': xy(530, 460, origin),
            'C': xy(275, 140, origin)}[name]


def simple_dry_point(origin=SCENE_ORIGIN):
    """A point of the simple scene at least 100 m from any water."""
    return xy(600, 260, origin)


# ----------------------------------------------------------------------------
# odd and bad inputs (each returns path; layers named rivers / lakes)
# ----------------------------------------------------------------------------

def _o(dx, dy):
    return '%.3f %.3f' % xy(dx, dy)


def make_odd_scene(path, kind):
    """Writes a small scene exercising one odd-but-valid input `kind`:
    'empty_geometries', 'null_geometries', 'multilinestring', 'multipolygon',
    'collections', 'zm', 'curves', 'duplicate_collinear', 'zero_length', 'bowtie',
    'overlapping_lakes', 'far_coordinates'. Returns path. The scene always has
    a normal river and lake besides, so the output is never empty."""
    if os.path.exists(path):
        os.unlink(path)
    rf = [('width', 'Real'), ('name', 'String')]
    lf = [('name', 'String')]
    base_river = {'geom': 'LINESTRING (%s, %s, %s)' % (_o(50, 300), _o(300, 320), _o(550, 300)),
                  'width': 15.0, 'name': 'base'}
    base_lake = {'geom': 'POLYGON ((%s, %s, %s, %s, %s))' % (
        _o(100, 50), _o(250, 50), _o(250, 150), _o(100, 150), _o(100, 50)), 'name': 'base'}
    rtype, ltype = ogr.wkbLineString, ogr.wkbPolygon
    rivers, lakes = [base_river], [base_lake]
    epsg = SCENE_EPSG
    if kind == 'empty_geometries':
        rtype, ltype = ogr.wkbUnknown, ogr.wkbUnknown
        rivers += [{'geom': 'LINESTRING EMPTY', 'width': 10.0, 'name': 'empty'},
                   {'geom': 'MULTILINESTRING EMPTY', 'width': 10.0, 'name': 'empty2'}]
        lakes += [{'geom': 'POLYGON EMPTY', 'name': 'empty'},
                  {'geom': 'MULTIPOLYGON EMPTY', 'name': 'empty2'}]
    elif kind == 'null_geometries':
        rivers += [{'geom': None, 'width': 10.0, 'name': 'null'}]
        lakes += [{'geom': None, 'name': 'null'}]
    elif kind == 'multilinestring':
        rtype = ogr.wkbMultiLineString
        rivers = [{'geom': 'MULTILINESTRING ((%s, %s, %s), (%s, %s))' % (
            _o(50, 300), _o(300, 320), _o(550, 300), _o(300, 320), _o(350, 500)),
            'width': 15.0, 'name': 'multi'}]
    elif kind == 'multipolygon':
        ltype = ogr.wkbMultiPolygon
        lakes = [{'geom': 'MULTIPOLYGON (((%s, %s, %s, %s, %s), (%s, %s, %s, %s, %s)), ((%s, %s, %s, %s)))' % (
            _o(100, 50), _o(250, 50), _o(250, 150), _o(100, 150), _o(100, 50),
            _o(150, 80), _o(150, 120), _o(200, 120), _o(200, 80), _o(150, 80),
            _o(400, 50), _o(500, 60), _o(450, 150), _o(400, 50)), 'name': 'multi'}]
    elif kind == 'collections':  # nested, and of Multi* members
        rtype, ltype = ogr.wkbGeometryCollection, ogr.wkbGeometryCollection
        rivers = [{'geom': 'GEOMETRYCOLLECTION (MULTILINESTRING ((%s, %s, %s)))' % (
            _o(50, 300), _o(300, 320), _o(550, 300)), 'width': 15.0, 'name': 'gc_multi'},
            {'geom': 'GEOMETRYCOLLECTION (GEOMETRYCOLLECTION (LINESTRING (%s, %s)))' % (
                _o(300, 320), _o(350, 500)), 'width': 15.0, 'name': 'gc_gc'}]
        lakes = [{'geom': 'GEOMETRYCOLLECTION (MULTIPOLYGON (((%s, %s, %s, %s, %s))), POLYGON ((%s, %s, %s, %s)))' % (
            _o(100, 50), _o(250, 50), _o(250, 150), _o(100, 150), _o(100, 50),
            _o(400, 50), _o(500, 60), _o(450, 150), _o(400, 50)), 'name': 'gc_multi'}]
    elif kind == 'zm':
        rtype, ltype = ogr.wkbLineStringZM, ogr.wkbPolygonZM
        rivers = [{'geom': 'LINESTRING ZM (%s 100 1, %s 120 2, %s 90 3)' % (
            _o(50, 300), _o(300, 320), _o(550, 300)), 'width': 15.0, 'name': 'zm'},
            {'geom': 'LINESTRING ZM (%s 5 0, %s 7 0)' % (_o(300, 320), _o(350, 500)),
             'width': 8.0, 'name': 'zm2'}]
        lakes = [{'geom': 'POLYGON ZM ((%s 1 0, %s 2 0, %s 3 0, %s 4 0, %s 1 0))' % (
            _o(100, 50), _o(250, 50), _o(250, 150), _o(100, 150), _o(100, 50)), 'name': 'zm'}]
    elif kind == 'curves':
        rtype, ltype = ogr.wkbUnknown, ogr.wkbUnknown
        rivers += [{'geom': 'CIRCULARSTRING (%s, %s, %s)' % (_o(50, 500), _o(300, 650), _o(550, 500)),
                    'width': 10.0, 'name': 'arc'},
                   {'geom': 'COMPOUNDCURVE ((%s, %s), CIRCULARSTRING (%s, %s, %s))' % (
                       _o(600, 100), _o(650, 100), _o(650, 100), _o(700, 150), _o(750, 100)),
                    'width': 6.0, 'name': 'compound'}]
        lakes += [{'geom': 'CURVEPOLYGON (CIRCULARSTRING (%s, %s, %s))' % (
            _o(400, 80), _o(480, 80), _o(400, 80)), 'name': 'circle'}]
    elif kind == 'duplicate_collinear':
        rivers = [{'geom': 'LINESTRING (%s, %s, %s, %s, %s, %s, %s)' % (
            _o(50, 300), _o(50, 300), _o(100, 300), _o(150, 300), _o(150, 300),
            _o(200, 300), _o(550, 300)), 'width': 15.0, 'name': 'dup'}]
        lakes = [{'geom': 'POLYGON ((%s, %s, %s, %s, %s, %s, %s, %s))' % (
            _o(100, 50), _o(175, 50), _o(250, 50), _o(250, 50), _o(250, 150),
            _o(100, 150), _o(100, 100), _o(100, 50)), 'name': 'dup'}]
    elif kind == 'zero_length':
        rivers += [{'geom': 'LINESTRING (%s, %s)' % (_o(400, 500), _o(400, 500)),
                    'width': 20.0, 'name': 'zero'},
                   {'geom': 'LINESTRING (%s, %s, %s)' % (_o(450, 550), _o(450, 550), _o(450, 550)),
                    'width': 20.0, 'name': 'zero3'}]
    elif kind == 'bowtie':
        lakes += [{'geom': 'POLYGON ((%s, %s, %s, %s, %s))' % (
            _o(350, 450), _o(550, 600), _o(550, 450), _o(350, 600), _o(350, 450)), 'name': 'bowtie'}]
    elif kind == 'overlapping_lakes':
        lakes += [{'geom': 'POLYGON ((%s, %s, %s, %s, %s))' % (
            _o(200, 100), _o(350, 100), _o(350, 200), _o(200, 200), _o(200, 100)), 'name': 'overlap'},
            {'geom': 'POLYGON ((%s, %s, %s, %s, %s))' % (
                _o(100, 50), _o(250, 50), _o(250, 150), _o(100, 150), _o(100, 50)), 'name': 'same'}]
    elif kind == 'far_coordinates':
        # UTM 31S, northing close to 1e7 (just south of the equator)
        epsg = 32731
        far = (500000.0, 9990000.0)

        def f(dx, dy):
            return '%.3f %.3f' % xy(dx, dy, far)
        rivers = [{'geom': 'LINESTRING (%s, %s, %s)' % (f(50, 300), f(300, 320), f(550, 300)),
                   'width': 15.0, 'name': 'far'}]
        lakes = [{'geom': 'POLYGON ((%s, %s, %s, %s, %s))' % (
            f(100, 50), f(250, 50), f(250, 150), f(100, 150), f(100, 50)), 'name': 'far'}]
    else:
        raise ValueError(kind)
    write_layer(path, 'rivers', rtype, epsg, rivers, fields=rf)
    write_layer(path, 'lakes', ltype, epsg, lakes, fields=lf)
    return path


ODD_KINDS = ('empty_geometries', 'null_geometries', 'multilinestring', 'multipolygon',
             'collections', 'zm', 'curves', 'duplicate_collinear', 'zero_length', 'bowtie',
             'overlapping_lakes', 'far_coordinates')


def make_mixed_crs_scene(rivers_path, lakes_path):
    """Rivers in EPSG:32631, lakes (the simple scene's) in EPSG:4326
    (lon/lat, traditional axis order). Returns (rivers_path, lakes_path)."""
    for p in (rivers_path, lakes_path):
        if os.path.exists(p):
            os.unlink(p)
    rivers, lakes, _, _ = simple_scene_features()
    write_layer(rivers_path, 'rivers', ogr.wkbLineString, SCENE_EPSG, rivers,
                fields=[('width', 'Real'), ('name', 'String'), ('width_txt', 'String')])
    ct = osr.CoordinateTransformation(srs_from(SCENE_EPSG), srs_from(4326))
    geo_lakes = []
    for f in lakes:
        g = ogr.CreateGeometryFromWkt(f['geom'])
        g.Segmentize(10.0)  # so the reprojected shape stays close
        assert g.Transform(ct) == 0
        geo_lakes.append({'geom': g, 'name': f['name']})
    write_layer(lakes_path, 'lakes', ogr.wkbMultiPolygon, 4326, geo_lakes,
                fields=[('name', 'String')])
    return rivers_path, lakes_path


def make_geographic_scene(path, lon, lat):
    """A small river + lake in EPSG:4326 around (lon, lat) (about 1 km)."""
    if os.path.exists(path):
        os.unlink(path)
    d = 0.004
    rivers = [{'geom': 'LINESTRING (%.6f %.6f, %.6f %.6f, %.6f %.6f)' % (
        lon - d, lat, lon, lat + d / 4, lon + d, lat), 'width': 15.0, 'name': 'geo'}]
    lakes = [{'geom': 'POLYGON ((%.6f %.6f, %.6f %.6f, %.6f %.6f, %.6f %.6f, %.6f %.6f))' % (
        lon - d / 2, lat - d, lon, lat - d, lon, lat - d / 2, lon - d / 2, lat - d / 2,
        lon - d / 2, lat - d), 'name': 'geo'}]
    write_layer(path, 'rivers', ogr.wkbLineString, 4326, rivers,
                fields=[('width', 'Real'), ('name', 'String')])
    write_layer(path, 'lakes', ogr.wkbPolygon, 4326, lakes, fields=[('name', 'String')])
    return path


def make_negative_scene(path):
    """A river + lake around the origin of EPSG:3857 (x from -700 to 700 m),
    so blocks with negative indices hold water."""
    if os.path.exists(path):
        os.unlink(path)
    y = 5000000.0
    rivers = [{'geom': 'LINESTRING (-700 %f, -100 %f, 300 %f, 700 %f)' % (y + 300, y + 350, y + 200, y + 420),
               'width': 14.0, 'name': 'neg'}]
    lakes = [{'geom': 'POLYGON ((-600 %f, -200 %f, -200 %f, -600 %f, -600 %f))' % (
        y - 300, y - 300, y - 100, y - 100, y - 300), 'name': 'neg'}]
    write_layer(path, 'rivers', ogr.wkbLineString, 3857, rivers,
                fields=[('width', 'Real'), ('name', 'String')])
    write_layer(path, 'lakes', ogr.wkbPolygon, 3857, lakes, fields=[('name', 'String')])
    return path


def make_bad_scene(path, kind):
    """Writes an input that the driver must refuse. kind: 'points' (rivers
    layer of points), 'no_crs' (no SRS; path must end in .shp, the layer is
    named after the file), 'nan' / 'inf' (a river with a NaN / infinite
    coordinate, FID 77), 'lake_nan' (a lake with a NaN coordinate, FID 78).
    Returns path; the layers are named rivers (and lakes)."""
    if os.path.exists(path):
        os.unlink(path)
    rf = [('width', 'Real'), ('name', 'String')]
    good = {'geom': 'LINESTRING (%s, %s)' % (_o(0, 0), _o(300, 0)), 'width': 10.0, 'name': 'good', 'fid': 1}
    good_lake = {'geom': 'POLYGON ((%s, %s, %s, %s))' % (_o(0, 100), _o(100, 100), _o(50, 200), _o(0, 100)),
                 'name': 'good', 'fid': 1}
    if kind == 'points':
        write_layer(path, 'rivers', ogr.wkbPoint, SCENE_EPSG,
                    [{'geom': 'POINT (%s)' % _o(0, 0), 'width': 10.0, 'name': 'p'},
                     {'geom': 'POINT (%s)' % _o(100, 0), 'width': 10.0, 'name': 'q'}], fields=rf)
    elif kind == 'no_crs':
        # a Shapefile without .prj: a GeoPackage would report an "Undefined
        # geographic SRS" instead of none
        assert path.endswith('.shp'), path
        write_layer(path, os.path.basename(path)[:-4], ogr.wkbLineString, None, [good],
                    fields=rf, driver='ESRI Shapefile')
    elif kind in ('nan', 'inf'):
        v = float('nan') if kind == 'nan' else float('inf')
        g = ogr.Geometry(ogr.wkbLineString)
        g.AddPoint_2D(*xy(0, 50))
        g.AddPoint_2D(v, xy(0, 60)[1])
        g.AddPoint_2D(*xy(200, 60))
        from osgeo import gdal
        gdal.PushErrorHandler('CPLQuietErrorHandler')  # GPKG cannot store an inf extent
        try:
            write_layer(path, 'rivers', ogr.wkbLineString, SCENE_EPSG,
                        [good, {'geom': g, 'width': 10.0, 'name': 'bad', 'fid': 77}], fields=rf)
        finally:
            gdal.PopErrorHandler()
        write_layer(path, 'lakes', ogr.wkbPolygon, SCENE_EPSG, [good_lake], fields=[('name', 'String')])
    elif kind == 'lake_nan':
        ring = ogr.Geometry(ogr.wkbLinearRing)
        for dx, dy in ((0, 300), (100, 300), (50, 400), (0, 300)):
            ring.AddPoint_2D(*xy(dx, dy))
        ring.SetPoint_2D(1, float('nan'), xy(0, 300)[1])
        poly = ogr.Geometry(ogr.wkbPolygon)
        poly.AddGeometry(ring)
        write_layer(path, 'rivers', ogr.wkbLineString, SCENE_EPSG, [good], fields=rf)
        write_layer(path, 'lakes', ogr.wkbPolygon, SCENE_EPSG,
                    [good_lake, {'geom': poly, 'name': 'bad', 'fid': 78}], fields=[('name', 'String')])
    else:
        raise ValueError(kind)
    return path
