"""WATERMESH driver: metadata, opening, layers, every open option, the
descriptor file, the raster view and the spatial filter."""

import math
import os
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from osgeo import gdal, ogr, osr

import oracle
from shapely.geometry import Polygon
from shapely.ops import unary_union
import scenes

ALL_OPTIONS = ('RIVERS', 'RIVERS_LAYER', 'RIVERS_WHERE', 'LAKES', 'LAKES_LAYER',
               'LAKES_WHERE', 'WIDTH', 'WIDTH_FIELD', 'PIXEL_SIZE', 'BLOCK_SIZE',
               'SIMPLIFY', 'METHOD', 'HEURISTIC', 'MERGE_DISTANCE', 'DEVICE',
               'NUM_THREADS', 'TARGET_SRS', 'MIN_FEATURE_AREA', 'MESH_GEOMETRY')

AREA_REL_TOL = 0.01  # driver water area vs oracle on the small hand-made scene


def with_(base, **kw):
    """Copy of an options dict with changes (None removes an option)."""
    o = dict(base)
    for k, v in kw.items():
        if v is None:
            o.pop(k.upper(), None)
        else:
            o[k.upper()] = v
    return o


def assert_area_close(wm, res, options, rel=AREA_REL_TOL):
    """Total water area of a run within rel of the oracle's; returns it."""
    got = oracle.total_area(res.water)
    want = oracle.water_area(options)
    assert want > 0
    assert abs(got - want) <= rel * want, \
        'water area %.1f m2 vs oracle %.1f m2 (rel %.4f > %.4f) for %s' % (
            got, want, (got - want) / want, rel, options)
    return got


def srs_is(srs, crs):
    """srs (osr or None) is the same CRS as crs (EPSG code or string)."""
    return srs is not None and srs.IsSame(scenes.srs_from(crs)) == 1


# a transverse Mercator centred on the simple scene: scale ~1 there, so the
# width of a river is the same in it and in UTM
LOCAL_TMERC = '+proj=tmerc +lat_0=42.45 +lon_0=1.8 +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m +no_defs'


# ----------------------------------------------------------------------------
# driver metadata
# ----------------------------------------------------------------------------

@pytest.fixture(scope='module')
def driver(wm):
    drv = gdal.GetDriverByName(wm.DRIVER_NAME)
    assert drv is not None, 'WATERMESH driver not registered'
    return drv


def test_driver_capabilities(driver):
    assert driver.GetMetadataItem(gdal.DCAP_RASTER) == 'YES'
    assert driver.GetMetadataItem(gdal.DCAP_VECTOR) == 'YES'


def test_driver_extensions(driver):
    exts = (driver.GetMetadataItem(gdal.DMD_EXTENSIONS) or '').lower().split()
    assert 'watermesh' in exts, 'DMD_EXTENSIONS = %r' % exts


def test_driver_connection_prefix(driver):
    assert driver.GetMetadataItem(gdal.DMD_CONNECTION_PREFIX) == 'WATERMESH:'


def test_driver_open_option_list(driver):
    xml = driver.GetMetadataItem(gdal.DMD_OPENOPTIONLIST)
    assert xml, 'no DMD_OPENOPTIONLIST'
    root = ET.fromstring(xml)
    names = {o.get('name', '').upper() for o in root.iter('Option')}
    missing = [n for n in ALL_OPTIONS if n not in names]
    assert not missing, 'options missing from DMD_OPENOPTIONLIST: %s' % missing


# ----------------------------------------------------------------------------
# opening, layers
# ----------------------------------------------------------------------------

def test_open_connection_string(wm, simple_options):
    ds, cap = wm.open(simple_options)
    assert ds is not None, cap.text
    names = [ds.GetLayer(i).GetName() for i in range(ds.GetLayerCount())]
    assert sorted(names) == ['mesh', 'water'], names


def field_types(lyr):
    d = lyr.GetLayerDefn()
    return {d.GetFieldDefn(i).GetName(): d.GetFieldDefn(i).GetType() for i in range(d.GetFieldCount())}


def test_water_layer_schema(wm, simple_options):
    ds, cap = wm.open(simple_options)
    assert ds is not None, cap.text
    lyr = ds.GetLayerByName('water')
    assert ogr.GT_Flatten(lyr.GetGeomType()) == ogr.wkbPolygon, ogr.GeometryTypeToName(lyr.GetGeomType())
    ft = field_types(lyr)
    assert ft.get('block_x') == ogr.OFTInteger, ft
    assert ft.get('block_y') == ogr.OFTInteger, ft
    assert ft.get('area') == ogr.OFTReal, ft
    assert ft.get('polygon') == ogr.OFTInteger, ft


def test_mesh_layer_schema(wm, simple_options):
    ds, cap = wm.open(simple_options)
    assert ds is not None, cap.text
    lyr = ds.GetLayerByName('mesh')
    assert ogr.GT_Flatten(lyr.GetGeomType()) == ogr.wkbMultiPolygon, ogr.GeometryTypeToName(lyr.GetGeomType())
    ft = field_types(lyr)
    assert ft.get('block_x') == ogr.OFTInteger, ft
    assert ft.get('block_y') == ogr.OFTInteger, ft
    assert ft.get('triangles') == ogr.OFTInteger, ft
    assert ft.get('polygon') == ogr.OFTInteger, ft


def test_polygon_field_names_the_water_polygon(wm, simple_options):
    """(block_x, block_y, polygon) is a key of the water layer, and each
    mesh feature carries its water polygon's key."""
    ds, cap = wm.open(simple_options)
    assert ds is not None, cap.text
    water = [(f['block_x'], f['block_y'], f['polygon']) for f in ds.GetLayerByName('water')]
    mesh = [(f['block_x'], f['block_y'], f['polygon']) for f in ds.GetLayerByName('mesh')]
    assert len(set(water)) == len(water) > 1
    assert mesh == water
    assert min(p for _, _, p in water) == 0


def _triangles(g):
    """Sorted triangles (each its sorted corners) of a MultiPolygon or TIN."""
    out = []
    for i in range(g.GetGeometryCount()):
        ring = g.GetGeometryRef(i).GetGeometryRef(0)
        out.append(tuple(sorted((round(ring.GetX(k), 6), round(ring.GetY(k), 6))
                                for k in range(3))))
    return sorted(out)


def test_mesh_geometry_tin(wm, simple_options):
    """MESH_GEOMETRY=TIN: the mesh layer is of TINs with the same triangles
    as the default MultiPolygon, feature for feature; each TIN is a valid
    surface: triangles that overlap nowhere (the area of their union is
    the sum of theirs). GDAL's IsValid on a TIN needs SFCGAL."""
    ds, cap = wm.open(with_(simple_options, MESH_GEOMETRY='TIN'))
    assert ds is not None, cap.text
    tin = ds.GetLayerByName('mesh')
    assert ogr.GT_Flatten(tin.GetGeomType()) == ogr.wkbTIN, ogr.GeometryTypeToName(tin.GetGeomType())
    ref_ds, _ = wm.open(simple_options)
    a, b = [f for f in tin], [f for f in ref_ds.GetLayerByName('mesh')]
    assert len(a) == len(b) > 0
    for fa, fb in zip(a, b):
        ga, gb = fa.GetGeometryRef(), fb.GetGeometryRef()
        assert ogr.GT_Flatten(ga.GetGeometryType()) == ogr.wkbTIN
        assert ga.GetGeometryCount() == fa['triangles'] == gb.GetGeometryCount()
        assert _triangles(ga) == _triangles(gb)
        tris = [Polygon(ga.GetGeometryRef(i).GetGeometryRef(0).GetPoints())
                for i in range(ga.GetGeometryCount())]
        assert all(t.is_valid and t.area > 0 for t in tris)
        total = sum(t.area for t in tris)
        assert abs(unary_union(tris).area - total) <= 1e-9 * total


def test_mesh_geometry_triangles(wm, simple_options):
    """MESH_GEOMETRY=TRIANGLES: one valid Polygon feature per triangle,
    carrying its water polygon's key; together the triangles of each
    polygon are the default MultiPolygon's, and the feature count (fast
    and by reading) is the number of triangles; FIDs are unique."""
    ds, cap = wm.open(with_(simple_options, MESH_GEOMETRY='TRIANGLES'))
    assert ds is not None, cap.text
    lyr = ds.GetLayerByName('mesh')
    assert ogr.GT_Flatten(lyr.GetGeomType()) == ogr.wkbPolygon, ogr.GeometryTypeToName(lyr.GetGeomType())
    assert 'triangles' not in field_types(lyr) and field_types(lyr).get('polygon') == ogr.OFTInteger
    ref_ds, _ = wm.open(simple_options)
    want = {(f['block_x'], f['block_y'], f['polygon']): _triangles(f.GetGeometryRef())
            for f in ref_ds.GetLayerByName('mesh')}
    got, fids = {}, set()
    for f in lyr:
        g = f.GetGeometryRef()
        assert g.GetGeometryType() == ogr.wkbPolygon and g.GetGeometryCount() == 1
        assert g.GetGeometryRef(0).GetPointCount() == 4 and g.IsValid() and g.GetArea() > 0
        fids.add(f.GetFID())
        key = (f['block_x'], f['block_y'], f['polygon'])
        ring = g.GetGeometryRef(0)
        got.setdefault(key, []).append(
            tuple(sorted((round(ring.GetX(k), 6), round(ring.GetY(k), 6)) for k in range(3))))
    n = sum(len(t) for t in want.values())
    assert len(fids) == n > 0
    assert {k: sorted(v) for k, v in got.items()} == want
    assert lyr.GetFeatureCount() == n
    feat = lyr.GetFeature(sorted(fids)[len(fids) // 2])
    assert feat is not None and feat.GetGeometryRef().GetGeometryType() == ogr.wkbPolygon


def test_layer_srs_is_rivers_crs(wm, simple_options):
    res = wm.run(simple_options)
    assert srs_is(res.srs, scenes.SCENE_EPSG), res.srs.ExportToWkt() if res.srs else None


def test_simple_scene_output(wm, simple_options):
    res = wm.run(simple_options)
    B = simple_options['BLOCK_SIZE']
    assert res.water and res.mesh
    problems = oracle.check_water(res.water, B)
    assert not problems, '\n'.join(problems[:10])
    problems, stats = oracle.check_mesh(res.mesh, res.water, B)
    assert not problems, '\n'.join(problems[:10])
    tj, gaps, details = oracle.check_seams(res.water, B)
    assert (tj, gaps) == (0, 0), '\n'.join(details[:10])
    assert_area_close(wm, res, simple_options)


def test_feature_order_deterministic(wm, simple_options):
    a = wm.run(simple_options)
    b = wm.run(simple_options)
    assert a.signature() == b.signature(), 'two runs gave different features/order'
    for feats in (a.water, a.mesh):
        seen, last = set(), None
        for f in feats:
            if f.block != last:
                assert f.block not in seen, 'features of block %s are not contiguous' % (f.block,)
                seen.add(f.block)
                last = f.block


def test_vector_open_has_no_bands(wm, simple_options):
    ds, cap = wm.open(simple_options, flags=gdal.OF_VECTOR)
    assert ds is not None, cap.text
    assert ds.RasterCount == 0
    assert ds.GetLayerCount() == 2


def test_raster_open_has_no_layers(wm, simple_options):
    ds, cap = wm.open(simple_options, flags=gdal.OF_RASTER)
    assert ds is not None, cap.text
    assert ds.GetLayerCount() == 0
    assert ds.RasterCount >= 1


# ----------------------------------------------------------------------------
# each open option has an effect
# ----------------------------------------------------------------------------

def test_width_default_is_10(wm, simple_options):
    a = wm.run(with_(simple_options, WIDTH=None))
    b = wm.run(with_(simple_options, WIDTH=10))
    assert a.signature() == b.signature()


def test_width_changes_area(wm, simple_options):
    o10, o20 = with_(simple_options, WIDTH=10), with_(simple_options, WIDTH=20)
    a10 = assert_area_close(wm, wm.run(o10), o10)
    a20 = assert_area_close(wm, wm.run(o20), o20)
    assert a20 > a10 * 1.2, (a10, a20)


def test_width_field_numeric(wm, simple_options):
    o = with_(simple_options, WIDTH_FIELD='width')
    res = wm.run(o)
    a = assert_area_close(wm, res, o)
    a10 = oracle.total_area(wm.run(simple_options).water)
    assert abs(a - a10) > 0.02 * a10, 'WIDTH_FIELD had no effect (%.1f vs %.1f)' % (a, a10)


def test_width_field_text_with_unit(wm, simple_options):
    # river B's width_txt is '2.5 m'
    o = with_(simple_options, WIDTH_FIELD='width_txt', RIVERS_WHERE="name = 'B'",
              LAKES=None, LAKES_LAYER=None, PIXEL_SIZE=0.5, SIMPLIFY=0)
    res = wm.run(o)
    a = assert_area_close(wm, res, o, rel=0.03)
    fallback = oracle.water_area(with_(o, WIDTH_FIELD=None))
    assert a < 0.5 * fallback, 'text width "2.5 m" not used (%.1f m2, WIDTH fallback gives %.1f)' % (a, fallback)
    assert not [w for w in res.cap.warnings if 'width' in w.lower()], res.cap.warnings


def test_width_field_invalid_values_warn(wm, simple_options):
    o = with_(simple_options, WIDTH_FIELD='width_txt')
    res = wm.run(o)
    warns = res.cap.warnings
    assert warns, 'no warning for the %d invalid text widths' % scenes.SIMPLE_INVALID_TEXT_WIDTHS
    n = str(scenes.SIMPLE_INVALID_TEXT_WIDTHS)
    assert any(n in w for w in warns), 'no warning counts the %s invalid widths: %s' % (n, warns)
    inputs = oracle.inputs_from_options(o)
    assert inputs.n_fallback_widths == scenes.SIMPLE_INVALID_TEXT_WIDTHS
    assert_area_close(wm, res, o)


def test_rivers_where(wm, simple_options):
    o = with_(simple_options, RIVERS_WHERE="name = 'A'")
    res = wm.run(o)
    a = assert_area_close(wm, res, o)
    assert a < oracle.total_area(wm.run(simple_options).water)


def test_lakes_where(wm, simple_options):
    o = with_(simple_options, LAKES_WHERE="name = 'L2'")
    res = wm.run(o)
    a = assert_area_close(wm, res, o)
    assert a < oracle.total_area(wm.run(simple_options).water)


def test_rivers_layer(wm, simple_options):
    o = with_(simple_options, RIVERS_LAYER='rivers2')
    res = wm.run(o)
    assert_area_close(wm, res, o)
    assert res.signature() != wm.run(simple_options).signature()


def test_lakes_layer(wm, simple_options):
    o = with_(simple_options, LAKES_LAYER='ponds')
    res = wm.run(o)
    assert_area_close(wm, res, o)
    assert res.signature() != wm.run(simple_options).signature()


def test_default_layer_is_first(wm, simple_options, simple_scene):
    ds = ogr.Open(simple_scene)
    first = ds.GetLayer(0).GetName()
    ds = None
    assert first == 'rivers'
    o = with_(simple_options, LAKES=None, LAKES_LAYER=None)
    a = wm.run(with_(o, RIVERS_LAYER=None))
    b = wm.run(o)
    assert a.signature() == b.signature()


def test_default_layers_by_geometry_type(wm, simple_options, simple_scene, tmp_dir):
    """RIVERS and LAKES naming one file with no *_LAYER: rivers take the
    first layer of lines, lakes the first of polygons, even when a polygon
    layer comes first (issue 15: it was "LAKES layer 'rivers' has Line
    String geometries")."""
    src = os.path.join(tmp_dir, 'lakes_first.gpkg')
    inp = ogr.Open(simple_scene)
    out = ogr.GetDriverByName('GPKG').CreateDataSource(src)
    for name in ('ponds', 'lakes', 'rivers', 'rivers2'):
        out.CopyLayer(inp.GetLayerByName(name), name)
    out = inp = None
    gdal.SetConfigOption('CPL_DEBUG', 'ON')
    try:
        got, cap = wm.open({'RIVERS': src, 'LAKES': src, 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512})
    finally:
        gdal.SetConfigOption('CPL_DEBUG', None)
    assert got is not None, cap.text
    assert "layer 'rivers', the first of lines" in cap.text, cap.text
    assert "layer 'ponds', the first of polygons" in cap.text, cap.text
    got = None
    a = wm.run({'RIVERS': src, 'LAKES': src, 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512})
    b = wm.run(with_(simple_options, LAKES_LAYER='ponds'))
    assert a.signature() == b.signature()


def test_layer_extent_is_the_waters(wm, simple_options):
    """GetExtent is the water's box (the capsules' and lakes' boxes, grown
    by a pixel), not the block grid's: it holds every feature and lies
    within two pixels of their envelope."""
    ds, cap = wm.open(simple_options)
    for name in ('water', 'mesh'):
        lyr = ds.GetLayerByName(name)
        ext = lyr.GetExtent()
        env = [math.inf, -math.inf, math.inf, -math.inf]
        for f in lyr:
            e = f.GetGeometryRef().GetEnvelope()
            env = [min(env[0], e[0]), max(env[1], e[1]), min(env[2], e[2]), max(env[3], e[3])]
        px = float(simple_options['PIXEL_SIZE'])
        assert ext[0] <= env[0] and ext[2] <= env[2], (name, ext, env)
        assert ext[1] >= env[1] and ext[3] >= env[3], (name, ext, env)
        assert all(abs(a - b) <= 2 * px for a, b in zip(ext, env)), (name, ext, env)


def test_rivers_only(wm, simple_options):
    o = with_(simple_options, LAKES=None, LAKES_LAYER=None)
    assert_area_close(wm, wm.run(o), o)


def test_lakes_only(wm, simple_options):
    o = with_(simple_options, RIVERS=None, RIVERS_LAYER=None)
    res = wm.run(o)
    assert_area_close(wm, res, o)
    assert srs_is(res.srs, scenes.SCENE_EPSG)


def test_pixel_size_changes_vertex_density(wm, simple_options):
    fine = wm.run(with_(simple_options, PIXEL_SIZE=0.5, SIMPLIFY=0))
    coarse = wm.run(with_(simple_options, PIXEL_SIZE=1, SIMPLIFY=0))
    nf, nc = oracle.vertex_count(fine.water), oracle.vertex_count(coarse.water)
    assert nf > 1.5 * nc, 'vertices: PIXEL_SIZE=0.5 -> %d, PIXEL_SIZE=1 -> %d' % (nf, nc)


def test_block_size_changes_blocks(wm, simple_options):
    r256 = wm.run(with_(simple_options, BLOCK_SIZE=256))
    r512 = wm.run(with_(simple_options, BLOCK_SIZE=512))
    b256 = {f.block for f in r256.water}
    b512 = {f.block for f in r512.water}
    assert len(b256) > len(b512), (sorted(b256), sorted(b512))
    assert {(bx // 2, by // 2) for bx, by in b256} == b512, (sorted(b256), sorted(b512))
    for res, B in ((r256, 256), (r512, 512)):
        problems = oracle.check_water(res.water, B)
        assert not problems, '\n'.join(problems[:10])
    # simplification anchors differ with the block grid: within the area
    # threshold of the oracle tests (0.5 %)
    a256, a512 = oracle.total_area(r256.water), oracle.total_area(r512.water)
    assert abs(a256 - a512) <= 5e-3 * a512, (a256, a512)
    # unsimplified, the union is the same region whatever the block size
    u256 = oracle.total_area(wm.run(with_(simple_options, BLOCK_SIZE=256, SIMPLIFY=0)).water)
    u512 = oracle.total_area(wm.run(with_(simple_options, BLOCK_SIZE=512, SIMPLIFY=0)).water)
    assert abs(u256 - u512) <= 1e-9 * u512, (u256, u512)


def test_simplify_changes_vertex_count(wm, simple_options):
    n0 = oracle.vertex_count(wm.run(with_(simple_options, SIMPLIFY=0)).water)
    nd = oracle.vertex_count(wm.run(simple_options).water)
    n3 = oracle.vertex_count(wm.run(with_(simple_options, SIMPLIFY=3)).water)
    assert n0 > nd > n3, 'vertices: SIMPLIFY=0 %d, default %d, SIMPLIFY=3 %d' % (n0, nd, n3)


def test_simplify_default_is_pixel_size(wm, simple_options):
    a = wm.run(with_(simple_options, SIMPLIFY=None))
    b = wm.run(with_(simple_options, SIMPLIFY=simple_options['PIXEL_SIZE']))
    assert a.signature() == b.signature()


def test_pixel_size_default(wm, simple_options):
    a = wm.run(with_(simple_options, PIXEL_SIZE=None))
    b = wm.run(with_(simple_options, PIXEL_SIZE=oracle.DEFAULT_PIXEL_SIZE))
    assert a.signature() == b.signature()


def test_block_size_default(wm, simple_options):
    res = wm.run(with_(simple_options, BLOCK_SIZE=None))
    B = oracle.DEFAULT_BLOCK_SIZE
    problems = oracle.check_water(res.water, B)
    assert not problems, '\n'.join(problems[:10])
    # the whole simple scene lies in one 4096 m block
    assert {f.block for f in res.water} == {(int(400000 // B), int(4700000 // B))}


def test_method_contour(wm, simple_options):
    a = wm.run(with_(simple_options, METHOD='CONTOUR'))
    b = wm.run(simple_options)
    assert a.signature() == b.signature()


def test_method_paper(wm, simple_options):
    """METHOD=PAPER: other rings (vertices on samples), same water to within
    a few percent, valid and seamless."""
    a = wm.run(with_(simple_options, METHOD='PAPER', SIMPLIFY=0))
    b = wm.run(with_(simple_options, SIMPLIFY=0))
    assert a.signature() != b.signature()
    ca, cb = oracle.total_area(a.water), oracle.total_area(b.water)
    assert abs(ca - cb) <= 0.03 * cb, (ca, cb)
    assert not oracle.check_water(a.water, 512)
    assert oracle.check_seams(a.water, 512)[:2] == (0, 0)
    # vertices on samples: PIXEL_SIZE 1, so every coordinate is an integer
    # number of pixels from the block origin
    for f in a.water:
        for ring in oracle.rings_of(f.geom):
            assert all(float(x).is_integer() and float(y).is_integer() for x, y in ring)


def test_heuristic_changes_the_walk(wm, simple_options):
    o = with_(simple_options, METHOD='PAPER', SIMPLIFY=0)
    runs = {h: wm.run(with_(o, HEURISTIC=h))
            for h in ('CLOSEST', 'DIRECTIONAL_CW', 'DIRECTIONAL_CCW', 'LEAST_ANGLE')}
    assert len({repr(r.signature()) for r in runs.values()}) >= 2, \
        'every HEURISTIC gave the same output'
    # DIRECTIONAL_CW traces the region exactly, the others may cut corners
    n = {h: oracle.vertex_count(r.water) for h, r in runs.items()}
    assert n['DIRECTIONAL_CW'] == max(n.values()), n
    for r in runs.values():
        assert not oracle.check_water(r.water, 512)


@pytest.mark.parametrize('method', ['CONTOUR', 'PAPER'])
def test_merge_distance(wm, simple_options, method):
    o = with_(simple_options, METHOD=method, SIMPLIFY=0)
    a = wm.run(o)
    b = wm.run(with_(o, MERGE_DISTANCE=2))
    va, vb = oracle.vertex_count(a.water), oracle.vertex_count(b.water)
    assert vb < va, (va, vb)
    assert not oracle.check_water(b.water, 512)
    assert oracle.check_seams(b.water, 512)[:2] == (0, 0)
    assert oracle.check_seams(b.mesh, 512)[:2] == (0, 0)
    problems, _ = oracle.check_mesh(b.mesh, b.water, 512)
    assert not problems, problems[:5]


def test_method_invalid_is_reported(wm, simple_options):
    ds, cap = wm.open(with_(simple_options, METHOD='NO_SUCH_METHOD'))
    assert 'METHOD' in cap.text.upper() or 'NO_SUCH_METHOD' in cap.text.upper(), \
        'an invalid METHOD gave no message (ds=%s)' % ds


def test_device_cpu(wm, simple_options):
    cpu = wm.run(with_(simple_options, DEVICE='CPU'))
    auto = wm.run(with_(simple_options, DEVICE='AUTO'))
    a, b = oracle.total_area(cpu.water), oracle.total_area(auto.water)
    assert abs(a - b) <= 1e-3 * b, (a, b)
    assert len(cpu.water) == len(auto.water)


def test_device_invalid_is_reported(wm, simple_options):
    ds, cap = wm.open(with_(simple_options, DEVICE='NO_SUCH_DEVICE'))
    assert 'DEVICE' in cap.text.upper() or 'NO_SUCH_DEVICE' in cap.text.upper(), \
        'an invalid DEVICE gave no message (ds=%s)' % ds


def _read_with_fids(wm, options, cache_mb):
    """(FID, WKB) of both layers, the feature counts, read with
    WATERMESH_CACHE_MAX=cache_mb; the water layer is read twice."""
    gdal.SetConfigOption('WATERMESH_CACHE_MAX', str(cache_mb))
    try:
        ds, cap = wm.open(options)
        assert ds is not None, cap.text
        out = {}
        for name in ('water', 'mesh', 'water'):
            lyr = ds.GetLayerByName(name)
            lyr.ResetReading()
            got = [(f.GetFID(), bytes(f.GetGeometryRef().ExportToIsoWkb())) for f in lyr]
            if name in out:
                assert got == out[name], 'a second read of %s differs' % name
            out[name] = got
        counts = {name: ds.GetLayerByName(name).GetFeatureCount() for name in ('water', 'mesh')}
        ds = None
        return out, counts
    finally:
        gdal.SetConfigOption('WATERMESH_CACHE_MAX', None)


def test_block_cache_bounded(wm, random_scene):
    """WATERMESH_CACHE_MAX=0 keeps no block beyond the chunk a read holds:
    blocks are recomputed, and every feature, FID and count is the same as
    with the default cache (many blocks: several chunks per read)."""
    path = random_scene(1, extent=1500.0, n_tributaries=5, n_lakes=3)
    o = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'LAKES': path, 'LAKES_LAYER': 'lakes',
         'WIDTH_FIELD': 'width', 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 64, 'NUM_THREADS': 1}
    big, nbig = _read_with_fids(wm, o, 512)
    small, nsmall = _read_with_fids(wm, o, 0)
    assert len({fid >> 24 for fid, _ in big['water']}) > 2 * 32, 'too few blocks to need chunks'
    assert small == big
    assert nsmall == nbig == {k: len(v) for k, v in big.items()}


@pytest.mark.parametrize('value', ['abc', '-5', '12MB', 'nan', '', ' ', 'inf'])
def test_block_cache_max_garbage_refused(wm, simple_options, value):
    """WATERMESH_CACHE_MAX that is not a number of megabytes >= 0 fails the
    open, naming the option and the value (CPLAtof read 'abc' as 0 and
    quietly kept no block)."""
    gdal.SetConfigOption('WATERMESH_CACHE_MAX', value)
    try:
        ds, cap = wm.open(simple_options)
    finally:
        gdal.SetConfigOption('WATERMESH_CACHE_MAX', None)
    assert ds is None
    assert 'WATERMESH_CACHE_MAX=%s' % value in cap.text, cap.text


def test_num_threads_identical(wm, simple_options):
    ref = wm.run(with_(simple_options, NUM_THREADS=1)).signature()
    for n in (2, 4, 'ALL_CPUS'):
        got = wm.run(with_(simple_options, NUM_THREADS=n)).signature()
        assert got == ref, 'NUM_THREADS=%s differs from NUM_THREADS=1' % n


def test_target_srs_reprojects(wm, simple_options):
    o = with_(simple_options, TARGET_SRS=LOCAL_TMERC)
    res = wm.run(o)
    assert srs_is(res.srs, LOCAL_TMERC), res.srs.ExportToWkt() if res.srs else None
    # river A's centerline, reprojected, is water
    ct = osr.CoordinateTransformation(scenes.srs_from(scenes.SCENE_EPSG), scenes.srs_from(LOCAL_TMERC))
    x, y, _ = ct.TransformPoint(*scenes.simple_river_point('A'))
    from shapely.geometry import Point
    assert any(f.geom.contains(Point(x, y)) for f in res.water), (x, y)
    problems = oracle.check_water(res.water, o['BLOCK_SIZE'])
    assert not problems, '\n'.join(problems[:10])
    assert_area_close(wm, res, o)


@pytest.mark.parametrize('lon,lat,epsg', [(1.5, 42.5, 32631), (-58.4, -34.6, 32721)])
def test_geographic_input_gets_utm(wm, tmp_dir, lon, lat, epsg):
    path = scenes.make_geographic_scene(os.path.join(tmp_dir, 'geo.gpkg'), lon, lat)
    o = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'LAKES': path, 'LAKES_LAYER': 'lakes',
         'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}
    res = wm.run(o)
    assert srs_is(res.srs, epsg), res.srs.ExportToWkt() if res.srs else None
    assert_area_close(wm, res, o)


@pytest.mark.parametrize('lat,epsg', [(89.9, 32661), (-85.9, 32761)])
def test_polar_input_gets_ups(wm, tmp_dir, lat, epsg):
    """North of 84 N and south of 80 S UTM is not defined: UPS, and the
    water where the river is."""
    path = os.path.join(tmp_dir, 'polar.gpkg')
    rivers = [{'geom': 'LINESTRING (10 %.4f, 10 %.4f)' % (lat, lat + 0.001),
               'width': 10.0, 'name': 'p'}]
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, 4326, rivers,
                       fields=[('width', 'Real'), ('name', 'String')])
    o = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'WIDTH_FIELD': 'width',
         'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}
    res = wm.run(o)
    assert srs_is(res.srs, epsg), res.srs.ExportToWkt() if res.srs else None
    ct = osr.CoordinateTransformation(scenes.srs_from(4326), scenes.srs_from(epsg))
    x, y, _ = ct.TransformPoint(10.0, lat + 0.0005)
    from shapely.geometry import Point
    assert any(f.geom.contains(Point(x, y)) for f in res.water), (x, y)
    # 111 m of river 10 m wide
    assert 1000 < oracle.total_area(res.water) < 1300


def test_geographic_input_across_the_antimeridian(wm, tmp_dir):
    """A river from 179.999 E to 179.999 W at 10 N: the UTM zone of its
    own longitude (60 N), not of the extent's centre (0, zone 31), and the
    water where the river is."""
    path = os.path.join(tmp_dir, 'anti.gpkg')
    rivers = [{'geom': 'LINESTRING (179.999 10, 180 10.0005)', 'width': 10.0, 'name': 'e'},
              {'geom': 'LINESTRING (-180 10.0005, -179.999 10.001)', 'width': 10.0, 'name': 'w'}]
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, 4326, rivers,
                       fields=[('width', 'Real'), ('name', 'String')])
    o = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'WIDTH_FIELD': 'width',
         'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}
    res = wm.run(o)
    assert srs_is(res.srs, 32660), res.srs.ExportToWkt() if res.srs else None
    ct = osr.CoordinateTransformation(scenes.srs_from(4326), scenes.srs_from(32660))
    from shapely.geometry import Point
    for lon, lat in ((179.9995, 10.00025), (-179.9995, 10.00075)):
        x, y, _ = ct.TransformPoint(lon, lat)
        assert any(f.geom.distance(Point(x, y)) < 1.0 for f in res.water), (lon, lat, x, y)
    # about 220 m of river 10 m wide
    assert 1500 < oracle.total_area(res.water) < 3000


@pytest.mark.parametrize('lakes_across', [False, True])
def test_geographic_features_across_the_antimeridian(wm, tmp_dir, lakes_across):
    """One river line crossing the antimeridian (its extent spans the
    globe), or rivers just west of it and a lake across it (the layers'
    centres 180 degrees apart): the zone of their own longitudes, 60 S or
    1 S, never one 90 degrees away (zones 16, 31 and 31 S were taken:
    scale 3.2 there, every width and pixel off by that much)."""
    path = os.path.join(tmp_dir, 'anti2.gpkg')
    if lakes_across:
        rivers = [{'geom': 'LINESTRING (-179.9996 -17.5, -179.9990 -17.5004)', 'width': 8.0}]
        lakes = [{'geom': 'POLYGON ((179.9994 -17.5001, -179.9997 -17.5001, '
                          '-179.9997 -17.5004, 179.9994 -17.5004, 179.9994 -17.5001))'}]
        scenes.write_layer(path, 'lakes', ogr.wkbPolygon, 4326, lakes)
    else:
        rivers = [{'geom': 'LINESTRING (179.9992 -17.5, -179.9993 -17.5002)', 'width': 8.0}]
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, 4326, rivers,
                       fields=[('width', 'Real')])
    o = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'WIDTH_FIELD': 'width',
         'PIXEL_SIZE': 0.5, 'BLOCK_SIZE': 256}
    if lakes_across:
        o.update({'LAKES': path, 'LAKES_LAYER': 'lakes'})
    res = wm.run(o)
    assert srs_is(res.srs, 32760) or srs_is(res.srs, 32701), \
        res.srs.ExportToWkt() if res.srs else None
    # the lake 96 m x 33 m and the river 77 m x 8 m beside it, or the river
    # alone 161 m x 8 m (scale 1 in the right zone; 3.2 in the wrong ones)
    area = oracle.total_area(res.water)
    assert (3000 < area < 4500) if lakes_across else (1100 < area < 1500), area


def test_negative_block_indices(wm, tmp_dir):
    path = scenes.make_negative_scene(os.path.join(tmp_dir, 'neg.gpkg'))
    o = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'LAKES': path, 'LAKES_LAYER': 'lakes',
         'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}
    res = wm.run(o)
    blocks = {f.block for f in res.water}
    assert any(bx < 0 for bx, _ in blocks), sorted(blocks)
    assert any(bx >= 0 for bx, _ in blocks), sorted(blocks)
    problems = oracle.check_water(res.water, 512)
    assert not problems, '\n'.join(problems[:10])
    tj, gaps, details = oracle.check_seams(res.water, 512)
    assert (tj, gaps) == (0, 0), '\n'.join(details[:10])
    assert_area_close(wm, res, o)


# ----------------------------------------------------------------------------
# descriptor file
# ----------------------------------------------------------------------------

def descriptor_options(simple_options, rel_path):
    o = with_(simple_options, RIVERS=rel_path, LAKES=rel_path)
    return o


def test_descriptor_relative_paths(wm, simple_options, simple_scene, tmp_dir):
    os.makedirs(os.path.join(tmp_dir, 'data'))
    shutil.copy(simple_scene, os.path.join(tmp_dir, 'data', 'simple.gpkg'))
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'scene.watermesh'),
                                   **descriptor_options(simple_options, 'data/simple.gpkg'))
    # opened by path, driver chosen by GDAL, from another working directory
    cwd = os.getcwd()
    os.chdir('/')
    try:
        res = wm.run({}, path=desc, any_driver=True)
    finally:
        os.chdir(cwd)
    ref = wm.run(simple_options)
    assert res.signature() == ref.signature()


def test_descriptor_identified_by_extension(wm, simple_options, simple_scene, tmp_dir):
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'x.watermesh'), **simple_options)
    drv = gdal.IdentifyDriverEx(desc)
    assert drv is not None and drv.ShortName == wm.DRIVER_NAME, drv and drv.ShortName


def test_descriptor_raster(wm, simple_options, tmp_dir):
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'r.watermesh'), **simple_options)
    a, cap = wm.open({}, path=desc, flags=gdal.OF_RASTER, any_driver=True)
    assert a is not None, cap.text
    b, cap = wm.open(simple_options, flags=gdal.OF_RASTER)
    assert b is not None, cap.text
    assert a.GetGeoTransform() == b.GetGeoTransform()
    assert (a.RasterXSize, a.RasterYSize) == (b.RasterXSize, b.RasterYSize)
    w = min(200, a.RasterXSize)
    h = min(200, a.RasterYSize)
    assert np.array_equal(a.GetRasterBand(1).ReadAsArray(0, 0, w, h),
                          b.GetRasterBand(1).ReadAsArray(0, 0, w, h))


def test_descriptor_vsimem(wm, simple_options, simple_scene):
    d = '/vsimem/watermesh_test_desc'
    try:
        with open(simple_scene, 'rb') as f:
            gdal.FileFromMemBuffer(d + '/data/simple.gpkg', f.read())
        desc = scenes.write_descriptor(d + '/scene.watermesh',
                                       **descriptor_options(simple_options, 'data/simple.gpkg'))
        res = wm.run({}, path=desc, any_driver=True)
        ref = wm.run(simple_options)
        assert res.signature() == ref.signature()
    finally:
        gdal.Unlink(d + '/data/simple.gpkg')
        gdal.Unlink(d + '/scene.watermesh')


def test_descriptor_equals_open_options(wm, simple_options, tmp_dir):
    o = with_(simple_options, WIDTH=14, WIDTH_FIELD='width', SIMPLIFY=0.75, NUM_THREADS=2)
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'o.watermesh'), **o)
    res = wm.run({}, path=desc, any_driver=True)
    assert res.signature() == wm.run(o).signature()


# ----------------------------------------------------------------------------
# raster view
# ----------------------------------------------------------------------------

@pytest.fixture(scope='module')
def raster(wm, simple_options):
    ds, cap = wm.open(simple_options, flags=gdal.OF_RASTER)
    assert ds is not None, cap.text
    return ds


def sample_index(gt, x, y):
    """(col, row) of the pixel whose center is the sample nearest (x, y)."""
    return int(math.floor((x - gt[0]) / gt[1])), int(math.floor((y - gt[3]) / gt[5]))


def test_raster_band(raster):
    band = raster.GetRasterBand(1)
    assert band.DataType == gdal.GDT_Float32, gdal.GetDataTypeName(band.DataType)
    assert band.GetNoDataValue() is None


def test_raster_srs(raster):
    srs = raster.GetSpatialRef()
    assert srs_is(srs, scenes.SCENE_EPSG), raster.GetProjection()


def test_raster_geotransform_grid_aligned(raster, simple_options):
    px = float(simple_options['PIXEL_SIZE'])
    gt = raster.GetGeoTransform()
    assert gt[1] == px and gt[5] == -px and gt[2] == 0 and gt[4] == 0, gt
    for v in ((gt[0] + px / 2) / px, (gt[3] - px / 2) / px):
        assert abs(v - round(v)) < 1e-9, 'pixel centers not on multiples of PIXEL_SIZE: %s' % (gt,)
    # the raster covers the scene (rivers' centerlines and lakes)
    x0, y0 = gt[0], gt[3] + gt[5] * raster.RasterYSize
    x1, y1 = gt[0] + gt[1] * raster.RasterXSize, gt[3]
    inputs = oracle.inputs_from_options(simple_options)
    from shapely.ops import unary_union
    sb = unary_union([l for l, _ in inputs.rivers] + list(inputs.lakes)).bounds
    assert x0 <= sb[0] and y0 <= sb[1] and x1 >= sb[2] and y1 >= sb[3], ((x0, y0, x1, y1), sb)


def read_at(ds, x, y):
    gt = ds.GetGeoTransform()
    c, r = sample_index(gt, x, y)
    return float(ds.GetRasterBand(1).ReadAsArray(c, r, 1, 1)[0, 0])


def test_raster_negative_in_river(raster):
    for name in ('A', 'B', 'C'):
        v = read_at(raster, *scenes.simple_river_point(name))
        assert v < 0, 'SDF %r at river %s centerline' % (v, name)


def test_raster_positive_far_away(raster):
    v = read_at(raster, *scenes.simple_dry_point())
    assert v > 0, v


def test_raster_clamped_band(raster, simple_options):
    px = float(simple_options['PIXEL_SIZE'])
    a = raster.GetRasterBand(1).ReadAsArray()
    assert np.all(np.isfinite(a))
    assert float(np.abs(a).max()) <= 10 * px, 'SDF not clamped to a few pixels: max |d| = %r' % float(np.abs(a).max())
    assert float(a.min()) < 0 < float(a.max())


def test_raster_values_are_distances(raster, simple_options):
    """Outside the water the SDF is the exact Euclidean distance to it."""
    inputs = oracle.inputs_from_options(simple_options)
    gt = raster.GetGeoTransform()
    # window across river A near its junction with B and the lake L1
    x, y = scenes.xy(480, 380)
    c, r = sample_index(gt, x, y)
    w, h = 40, 40
    a = raster.GetRasterBand(1).ReadAsArray(c, r - h, w, h)
    vmax = float(np.abs(raster.GetRasterBand(1).ReadAsArray()).max())
    checked = 0
    for j in range(0, h, 2):
        for i in range(0, w, 2):
            v = float(a[j, i])
            sx = gt[0] + (c + i + 0.5) * gt[1]
            sy = gt[3] + (r - h + j + 0.5) * gt[5]
            d = oracle.exact_signed_distance_outside(inputs, sx, sy)
            if d > 1e-3 and v < 0.9 * vmax:
                assert abs(v - d) <= 2e-3, 'SDF %r, exact distance %r at (%r, %r)' % (v, d, sx, sy)
                checked += 1
            if abs(d) > 1e-3:
                assert (v < 0) == (d < 0), 'SDF sign %r, exact %r at (%r, %r)' % (v, d, sx, sy)
    assert checked > 20, checked


def test_raster_sample_independent_of_block(wm, simple_options):
    """Same global sample -> bit-identical value, whatever BLOCK_SIZE."""
    arrays = []
    for B in (256, 512):
        ds, cap = wm.open(with_(simple_options, BLOCK_SIZE=B), flags=gdal.OF_RASTER)
        assert ds is not None, cap.text
        gt = ds.GetGeoTransform()
        px = gt[1]
        # global sample index of the top-left pixel center
        i0 = int(round((gt[0] + px / 2) / px))
        j0 = int(round((gt[3] - px / 2) / px))
        arrays.append((i0, j0, ds.GetRasterBand(1).ReadAsArray()))
    (ia, ja, a), (ib, jb, b) = arrays
    # overlap in global indices (columns grow with i, rows go down in j)
    i_lo, i_hi = max(ia, ib), min(ia + a.shape[1], ib + b.shape[1])
    j_hi, j_lo = min(ja, jb), max(ja - a.shape[0], jb - b.shape[0])
    assert i_hi - i_lo > 100 and j_hi - j_lo > 100
    sa = a[ja - j_hi:ja - j_lo, i_lo - ia:i_hi - ia]
    sb = b[jb - j_hi:jb - j_lo, i_lo - ib:i_hi - ib]
    assert sa.shape == sb.shape
    assert np.array_equal(sa, sb), '%d samples differ' % int(np.sum(sa != sb))


def test_raster_translate_projwin(raster):
    gt = raster.GetGeoTransform()
    c, r, w, h = 150, 100, 120, 80
    ulx, uly = gt[0] + c * gt[1], gt[3] + r * gt[5]
    lrx, lry = ulx + w * gt[1], uly + h * gt[5]
    out = '/vsimem/watermesh_projwin.tif'
    try:
        t = gdal.Translate(out, raster, projWin=[ulx, uly, lrx, lry])
        assert t is not None
        assert (t.RasterXSize, t.RasterYSize) == (w, h)
        assert np.array_equal(t.GetRasterBand(1).ReadAsArray(),
                              raster.GetRasterBand(1).ReadAsArray(c, r, w, h))
        t = None
    finally:
        gdal.Unlink(out)


# ----------------------------------------------------------------------------
# spatial filter
# ----------------------------------------------------------------------------

def test_spatial_filter(wm, simple_options):
    B = simple_options['BLOCK_SIZE']
    x0, y0 = scenes.xy(300, 350)
    x1, y1 = scenes.xy(600, 450)
    rect = (x0, y0, x1, y1)
    touched = oracle.blocks_touching(rect, B)
    assert len(touched) == 2, touched
    full = wm.run(simple_options)
    filt = wm.run(simple_options, spat=rect)
    from shapely.geometry import box
    rbox = box(*rect)
    for name, ff, ft in (('water', full.water, filt.water), ('mesh', full.mesh, filt.mesh)):
        assert ft, 'no %s features with the spatial filter' % name
        blocks = {f.block for f in ft}
        assert blocks <= touched, '%s: blocks %s outside %s' % (name, sorted(blocks), sorted(touched))
        subset = [f for f in ff if f.block in touched]
        sig_sub = wm.signature(subset)
        sig_ft = wm.signature(ft)
        # what the filter returned is the unfiltered run's features (same order)
        it = iter(sig_sub)
        assert all(any(s == t for t in it) for s in sig_ft), \
            '%s: filtered features are not the unfiltered ones of the touched blocks' % name
        # ... at least every one of them that meets the rectangle
        must = wm.signature([f for f in subset if f.geom.intersects(rbox)])
        missing = [s for s in must if s not in sig_ft]
        assert not missing, '%s: %d features meeting the filter are missing' % (name, len(missing))
