"""ELEVATION: water draped on an elevation raster. Lakes flat to the bit
(across blocks too), rivers never rising downstream and meeting lakes at
their level, Z seams identical, glTF with normals, and the bad inputs.

The scene (EPSG:32632, 1 m pixels, 2048 m blocks): river A digitized
against its flow (east to west, while the terrain falls to the east), a
tributary B joining A at one of its vertices, lake L on A across two block
sides, lake K alone. The terrain has waves along A, so its raw profile
rises and falls: the levels must still descend."""

import json
import math
import os
import struct
import subprocess

import numpy as np
import pytest
from osgeo import gdal, ogr, osr
from shapely.geometry import LineString, Point, Polygon

from test_gltf import validate

EPSG = 32632
X0, Y0 = 500000.0, 5000000.0
BLOCK = 2048
A = [(9000, 5000), (7000, 5050), (5000, 5000), (3000, 4950), (1000, 5000)]
B = [(5000, 9000), (5100, 7000), (5000, 5000)]
L = [(6000, 4300), (8000, 4300), (8000, 5700), (6000, 5700)]
K = [(2000, 7000), (3000, 7000), (3000, 8000), (2000, 8000)]
WIDTH = {'A': 20.0, 'B': 10.0}


def shift(pts):
    return [(X0 + x, Y0 + y) for x, y in pts]


def terrain(x, y):
    """Metres; falls to the east, with waves that make A's profile rise."""
    return 500 - 0.01 * (x - X0) + 12 * np.sin((x - X0) / 250.0) + 0.004 * (y - Y0)


def make_dem(path, srs_epsg=EPSG, hole=None, west_only=False):
    res = 10.0
    nx, ny = 1100, 1100
    if west_only:
        nx = 500
    xs = X0 - 500 + res * (np.arange(nx) + 0.5)
    ys = Y0 + 10500 - res * (np.arange(ny) + 0.5)
    gx, gy = np.meshgrid(xs, ys)
    z = terrain(gx, gy).astype('f4')
    if hole is not None:  # (x0, y0, x1, y1) scene metres: nodata there
        m = ((gx >= X0 + hole[0]) & (gx <= X0 + hole[2]) &
             (gy >= Y0 + hole[1]) & (gy <= Y0 + hole[3]))
        z[m] = -9999
    tmp = path if srs_epsg == EPSG else path + '.utm.tif'
    ds = gdal.GetDriverByName('GTiff').Create(tmp, nx, ny, 1, gdal.GDT_Float32)
    ds.SetGeoTransform((X0 - 500, res, 0, Y0 + 10500, 0, -res))
    s = osr.SpatialReference()
    s.ImportFromEPSG(EPSG)
    ds.SetProjection(s.ExportToWkt())
    ds.GetRasterBand(1).SetNoDataValue(-9999)
    ds.GetRasterBand(1).WriteArray(z)
    ds = None
    if srs_epsg != EPSG:
        gdal.Warp(path, tmp, dstSRS='EPSG:%d' % srs_epsg, resampleAlg='bilinear',
                  dstNodata=-9999)
    return path


@pytest.fixture(scope='module')
def scene(tmp_path_factory):
    d = str(tmp_path_factory.mktemp('elev'))
    path = os.path.join(d, 'scene.gpkg')
    ds = ogr.GetDriverByName('GPKG').CreateDataSource(path)
    s = osr.SpatialReference()
    s.ImportFromEPSG(EPSG)
    lr = ds.CreateLayer('rivers', s, ogr.wkbLineString)
    lr.CreateField(ogr.FieldDefn('width', ogr.OFTReal))
    for name, pts in (('A', A), ('B', B)):
        f = ogr.Feature(lr.GetLayerDefn())
        f['width'] = WIDTH[name]
        f.SetGeometry(ogr.CreateGeometryFromWkt(LineString(shift(pts)).wkt))
        lr.CreateFeature(f)
    ll = ds.CreateLayer('lakes', s, ogr.wkbPolygon)
    for pts in (L, K):
        f = ogr.Feature(ll.GetLayerDefn())
        f.SetGeometry(ogr.CreateGeometryFromWkt(Polygon(shift(pts)).wkt))
        ll.CreateFeature(f)
    ds = None
    return {'dir': d, 'path': path, 'dem': make_dem(os.path.join(d, 'dem.tif'))}


def base_args(scene, *extra):
    return ['-rivers', scene['path'], '-rivers_layer', 'rivers', '-width_field', 'width',
            '-lakes', scene['path'], '-lakes_layer', 'lakes', '-pixel_size', '1',
            '-block_size', str(BLOCK), '-simplify', '0.5', '-q'] + list(extra)


def run(wm, scene, name, *extra, ok=True):
    out = os.path.join(scene['dir'], name)
    p = wm.cli(base_args(scene, *extra) + ['-overwrite', out])
    if ok:
        assert p.returncode == 0, p.stderr
    return p, out


def vertices(path, layer='water'):
    """[(x, y, z, feature)] of every ring vertex of a layer (closing points
    left out), and the features' fields."""
    ds = gdal.OpenEx(path, gdal.OF_VECTOR)
    lyr = ds.GetLayerByName(layer)
    assert ogr.GT_HasZ(lyr.GetGeomType())
    pts, feats = [], []
    for f in lyr:
        feats.append(f.items())
        g = f.GetGeometryRef()
        stack = [g]
        while stack:
            h = stack.pop()
            if h.GetGeometryCount():
                stack.extend(h.GetGeometryRef(i) for i in range(h.GetGeometryCount()))
                continue
            n = h.GetPointCount()
            for i in range(n - 1):
                pts.append((h.GetX(i), h.GetY(i), h.GetZ(i), len(feats) - 1))
    return pts, feats


@pytest.fixture(scope='module')
def draped(wm, scene):
    p, out = run(wm, scene, 'draped.gpkg', '-elevation', scene['dem'])
    return out


LAKES = {'L': Polygon(shift(L)), 'K': Polygon(shift(K))}
LINES = {'A': LineString(shift(A)), 'B': LineString(shift(B))}


def seg_term(x, y, a, b):
    """(|p - [a, b]|, projection parameter t), as drape.c computes them."""
    px, py = x - a[0], y - a[1]
    abx, aby = b[0] - a[0], b[1] - a[1]
    len2 = abx * abx + aby * aby
    u = (px * abx + py * aby) / len2 if len2 > 0 else 0.0
    u = min(max(u, 0.0), 1.0)
    dx, dy = px - u * abx, py - u * aby
    return math.sqrt(dx * dx + dy * dy), u


def nearest_river(x, y):
    """(river, s along its digitized line, term) of the segment nearest in
    the field's terms (|p - seg| - r; ties to the first), as drape.c."""
    best = None
    for k in ('A', 'B'):
        pts = shift(A if k == 'A' else B)
        s0 = 0.0
        for a, b in zip(pts, pts[1:]):
            d, u = seg_term(x, y, a, b)
            seglen = math.hypot(b[0] - a[0], b[1] - a[1])
            term = d - WIDTH[k] / 2
            if best is None or term < best[2]:
                best = (k, s0 + u * seglen, term)
            s0 += seglen
    return best


def owner(x, y):
    """'L' or 'K' for a point in (or on) a lake, or nearest a lake edge; else
    the river nearest in the field's terms (as drape.c decides)."""
    p = Point(x, y)
    for k, poly in LAKES.items():
        if poly.contains(p) or poly.boundary.distance(p) == 0:
            return k
    k, s, term = nearest_river(x, y)
    for name, poly in LAKES.items():
        if poly.exterior.distance(p) <= term:
            return name
    return k


def test_lakes_flat_to_the_bit_across_blocks(draped):
    pts, feats = vertices(draped)
    for name in LAKES:
        zs = {z for x, y, z, fi in pts if owner(x, y) == name}
        blocks = {(feats[fi]['block_x'], feats[fi]['block_y'])
                  for x, y, z, fi in pts if owner(x, y) == name}
        assert len(zs) == 1, (name, sorted(zs)[:5])
        if name == 'L':
            assert len(blocks) >= 3, blocks
        level = zs.pop()
        # the 10th percentile of the terrain along the shore, sampled finely
        ring = LAKES[name].exterior
        samples = [terrain(*ring.interpolate(d).coords[0]) for d in np.arange(0, ring.length, 5.0)]
        assert abs(level - np.percentile(samples, 10)) < 0.5, (level, np.percentile(samples, 10))
        levels = {round(feats[fi]['level'], 9) for x, y, z, fi in pts
                  if owner(x, y) == name and feats[fi]['level'] is not None}
        assert levels and all(abs(v - level) < 1e-9 for v in levels)
        spread = [feats[fi]['level_spread'] for x, y, z, fi in pts if owner(x, y) == name]
        assert all(abs(s - (max(samples) - min(samples))) < 1.0 for s in spread)


def river_profiles(pts):
    """{river: [(s along its digitized line, z)]} of the vertices it owns."""
    prof = {}
    for x, y, z, fi in pts:
        if owner(x, y) in LINES:
            k, s, term = nearest_river(x, y)
            prof.setdefault(k, []).append((s, z))
    return {k: sorted(v) for k, v in prof.items()}


def assert_descending(profile, downstream_is_increasing_s):
    zs = [z for s, z in profile]
    if not downstream_is_increasing_s:
        zs = zs[::-1]
    rises = [(a, b) for a, b in zip(zs, zs[1:]) if b > a + 1e-9]
    assert not rises, rises[:5]


def test_rivers_never_rise_downstream(draped):
    pts, feats = vertices(draped)
    prof = river_profiles(pts)
    assert len(prof['A']) > 20 and len(prof['B']) > 5
    # the terrain falls to the east: A (digitized westwards) flows against
    # its digitized direction, B (digitized southwards) along it
    assert_descending(prof['A'], downstream_is_increasing_s=False)
    assert_descending(prof['B'], downstream_is_increasing_s=True)
    # the raw terrain along A rises and falls: the levels are not the terrain
    raw = [terrain(*LINES['A'].interpolate(s).coords[0]) for s, z in prof['A']]
    assert any(b > a + 1 for a, b in zip(raw[::-1], raw[::-1][1:]))


def test_river_meets_lake_at_its_level(draped):
    pts, feats = vertices(draped)
    level = {z for x, y, z, fi in pts if owner(x, y) == 'L'}.pop()
    upstream = [z for x, y, z, fi in pts if owner(x, y) == 'A' and x < X0 + 6000]
    downstream = [z for x, y, z, fi in pts if owner(x, y) == 'A' and x > X0 + 8000]
    assert upstream and downstream
    assert min(upstream) >= level - 1e-9
    assert max(downstream) <= level + 1e-9
    # next to the shore the river is within the slope of one segment of it
    near = [z for x, y, z, fi in pts if owner(x, y) == 'A' and X0 + 5990 < x < X0 + 6000]
    assert near and max(near) - level < 2.0


def test_line_direction(wm, scene):
    p, out = run(wm, scene, 'linedir.gpkg', '-elevation', scene['dem'], '-flow', 'LINE_DIRECTION')
    prof = river_profiles(vertices(out)[0])
    assert_descending(prof['A'], downstream_is_increasing_s=True)
    assert_descending(prof['B'], downstream_is_increasing_s=True)


def test_z_seams_and_mesh(draped):
    pts, feats = vertices(draped)
    at = {}
    for x, y, z, fi in pts:
        at.setdefault((x, y), set()).add(z)
    side = [k for k in at if (k[0] - 0) % BLOCK == 0 or k[1] % BLOCK == 0]
    assert len(side) > 10
    assert all(len(at[k]) == 1 for k in at), [k for k in at if len(at[k]) > 1][:5]
    mesh, _ = vertices(draped, 'mesh')
    assert mesh and all((x, y) in at and z in at[(x, y)] for x, y, z, fi in mesh)


def test_threads_and_2d_unchanged(wm, scene, draped):
    p, one = run(wm, scene, 'one.gpkg', '-elevation', scene['dem'], '-num_threads', '1')
    a, b = wm.read_output(one), wm.read_output(draped)
    assert wm.signature(a['water']) == wm.signature(b['water'])
    assert wm.signature(a['mesh']) == wm.signature(b['mesh'])
    # the 2D geometry is that of a run without ELEVATION
    p, flat = run(wm, scene, 'flat.gpkg')
    c = wm.read_output(flat)
    from shapely import wkb
    from shapely.ops import transform
    for fa, fc in zip(b['water'], c['water']):
        g2 = transform(lambda x, y, z=None: (x, y), wkb.loads(fa.wkb))
        assert g2.equals_exact(wkb.loads(fc.wkb), 0)


def test_geographic_dem(wm, scene, draped):
    dem = make_dem(os.path.join(scene['dir'], 'dem4326.tif'), srs_epsg=4326)
    p, out = run(wm, scene, 'geo.gpkg', '-elevation', dem)
    pts, feats = vertices(out)
    ref, _ = vertices(draped)
    for name in LAKES:
        a = {z for x, y, z, fi in pts if owner(x, y) == name}
        b = {z for x, y, z, fi in ref if owner(x, y) == name}
        assert len(a) == 1 and abs(a.pop() - b.pop()) < 0.5
    prof = river_profiles(pts)
    assert_descending(prof['A'], downstream_is_increasing_s=False)


def test_nodata_hole_under_a_river(wm, scene):
    dem = make_dem(os.path.join(scene['dir'], 'hole.tif'), hole=(2500, 4500, 4000, 5500))
    p, out = run(wm, scene, 'hole.gpkg', '-elevation', dem)
    prof = river_profiles(vertices(out)[0])
    assert_descending(prof['A'], downstream_is_increasing_s=False)


def test_dem_not_covering_the_scene(wm, scene):
    dem = make_dem(os.path.join(scene['dir'], 'west.tif'), west_only=True)
    p, out = run(wm, scene, 'west.gpkg', '-elevation', dem, ok=False)
    assert p.returncode != 0
    assert "ELEVATION raster '%s' has no value" % dem in p.stderr, p.stderr
    assert not os.path.exists(out)


@pytest.mark.parametrize('extra,message', [
    (['-elevation', '/nonexistent/dem.tif'], "cannot open ELEVATION raster '/nonexistent/dem.tif'"),
    (['-elevation', '{dem}', '-elevation_band', '2'], 'has 1 band(s); ELEVATION_BAND=2'),
    (['-elevation', '{dem}', '-elevation_band', '0'], 'ELEVATION_BAND=0'),
    (['-elevation', '{dem}', '-lake_level_percentile', '101'], 'LAKE_LEVEL_PERCENTILE=101'),
    (['-elevation', '{dem}', '-flow', 'UPHILL'], 'FLOW=UPHILL: expected DEM or LINE_DIRECTION'),
    (['-elevation', '{dem}', '-shard', '0/2'], 'ELEVATION with SHARD or BLOCKS is not supported'),
])
def test_bad_elevation_options(wm, scene, extra, message):
    extra = [e.format(dem=scene['dem']) for e in extra]
    p, out = run(wm, scene, 'bad.gpkg', *extra, ok=False)
    assert p.returncode != 0
    assert message in p.stderr, p.stderr
    assert not os.path.exists(out)


def test_driver_declares_the_options():
    drv = gdal.GetDriverByName('WATERMESH')
    xml = drv.GetMetadataItem(gdal.DMD_OPENOPTIONLIST)
    for name in ('ELEVATION', 'ELEVATION_BAND', 'LAKE_LEVEL_PERCENTILE', 'FLOW'):
        assert "name='%s'" % name in xml


def read_glb_z(path):
    with open(path, 'rb') as f:
        data = f.read()
    jl, = struct.unpack_from('<I', data, 12)
    doc = json.loads(data[20:20 + jl])
    bin_ = data[28 + jl:]
    prim = doc['meshes'][0]['primitives'][0]
    acc = doc['accessors']
    views = doc['bufferViews']

    def read(i, fmt, width):
        a = acc[i]
        v = struct.unpack_from('<%d%s' % (width * a['count'], fmt), bin_,
                               views[a['bufferView']]['byteOffset'])
        return [v[width * k:width * k + width] for k in range(a['count'])] if width > 1 else list(v)
    pos = read(prim['attributes']['POSITION'], 'f', 3)
    nrm = read(prim['attributes']['NORMAL'], 'f', 3)
    idx = read(prim['indices'], 'I', 1)
    return doc, pos, nrm, idx


def glb(wm, scene, name, *extra):
    """(index.json, files) of a -of GLB run, every file validated."""
    out = os.path.join(scene['dir'], name)
    p = wm.cli(base_args(scene, '-elevation', scene['dem'], *extra) +
               ['-overwrite', '-of', 'GLB', out])
    assert p.returncode == 0, p.stderr
    with open(os.path.join(out, 'index.json')) as f:
        index = json.load(f)
    files = [os.path.join(out, b['file']) for b in index['blocks']]
    rc, reports = validate(files)
    assert rc == 0 and all(r['errors'] == 0 for r in reports), reports[:3]
    return index, files


def test_glb_heights_and_normals(wm, scene, draped):
    index, files = glb(wm, scene, 'glb')
    out = os.path.dirname(files[0])
    pts, feats = vertices(draped)
    heights = {}
    for x, y, z, fi in pts:
        heights[(round(x, 2), round(y, 2))] = z
    ntri = 0
    normal_at = {}
    for b in index['blocks']:
        doc, pos, nrm, idx = read_glb_z(os.path.join(out, b['file']))
        ntri += len(idx) // 3
        x0, y0 = b['origin']
        for p_, n in zip(pos, nrm):
            assert abs(math.sqrt(sum(c * c for c in n)) - 1) < 1e-5 and n[1] > 0
            key = (round(x0 + p_[0], 2), round(y0 - p_[2], 2))
            assert abs(p_[1] - heights[key]) < 1e-3
            normal_at.setdefault(key, set()).add(tuple(round(c, 6) for c in n))
    ds = gdal.OpenEx(draped, gdal.OF_VECTOR)
    assert ntri == sum(f['triangles'] for f in ds.GetLayerByName('mesh')) > 0
    # normals are a pure function of position: a vertex on a block side
    # has one normal in both blocks; lakes point straight up; sloping
    # rivers tilt them, along their axis
    assert all(len(v) == 1 for v in normal_at.values())
    shared = [k for k in normal_at if k[0] % BLOCK == 0 or k[1] % BLOCK == 0]
    assert len(shared) > 10
    lake = [next(iter(normal_at[k])) for k in normal_at if owner(*k) in LAKES]
    assert lake and all(n == (0.0, 1.0, 0.0) for n in lake)
    river = [next(iter(normal_at[k])) for k in normal_at if owner(*k) in LINES]
    assert any(n[1] < 1 - 1e-9 for n in river)


def test_refined_draped_mesh(wm, scene, draped):
    """MIN_ANGLE and MAX_EDGE add Steiner points inside the water: they are
    draped by the same rule (lakes flat, rivers descending), and the glTF
    files carry the refined triangles."""
    p, out = run(wm, scene, 'refined.gpkg', '-elevation', scene['dem'],
                 '-min_angle', '20', '-max_edge', '60')
    mesh, _ = vertices(out, 'mesh')
    plain, _ = vertices(draped, 'mesh')
    assert len({(x, y) for x, y, z, fi in mesh}) > 3 * len({(x, y) for x, y, z, fi in plain})
    for name in LAKES:
        zs = {z for x, y, z, fi in mesh if owner(x, y) == name}
        assert len(zs) == 1, (name, sorted(zs)[:5])
    prof = river_profiles(mesh)
    assert_descending(prof['A'], downstream_is_increasing_s=False)
    assert_descending(prof['B'], downstream_is_increasing_s=True)
    index, files = glb(wm, scene, 'glb_refined', '-min_angle', '20', '-max_edge', '60')
    ntri = sum(len(read_glb_z(fn)[3]) // 3 for fn in files)
    ds = gdal.OpenEx(out, gdal.OF_VECTOR)
    assert ntri == sum(f['triangles'] for f in ds.GetLayerByName('mesh')) > 0


def test_raster_view_unchanged(wm, scene):
    """The distance raster view ignores ELEVATION (and the refinement)."""
    base = {'RIVERS': scene['path'], 'RIVERS_LAYER': 'rivers', 'WIDTH_FIELD': 'width',
            'LAKES': scene['path'], 'LAKES_LAYER': 'lakes', 'PIXEL_SIZE': 4}
    sums = []
    for extra in ({}, {'ELEVATION': scene['dem'], 'MIN_ANGLE': 20}):
        ds, cap = wm.open(dict(base, **extra), flags=gdal.OF_RASTER)
        assert ds is not None, cap.text
        sums.append((ds.RasterXSize, ds.RasterYSize, ds.GetRasterBand(1).Checksum()))
    assert sums[0] == sums[1] and sums[0][2] != 0
