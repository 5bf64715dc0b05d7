"""Bad inputs (refused with a clear message naming the input and the
problem) and odd-but-valid inputs (handled: no crash, valid output)."""

import os

import pytest
from osgeo import gdal, ogr

import oracle
import scenes

CRS_WORDS = ('crs', 'srs', 'spatial reference', 'coordinate', 'projection')
NONFINITE_WORDS = ('nan', 'finite', 'infinit')


def assert_refused(wm, options, path='WATERMESH:', all_of=(), any_of=(), flags=gdal.OF_VECTOR):
    """Open must fail; the message must contain every string of all_of and
    at least one of any_of (case-insensitive). Returns the message."""
    ds, cap = wm.open(options, path=path, flags=flags, any_driver=(path != 'WATERMESH:'))
    msg = cap.text or gdal.GetLastErrorMsg()
    assert ds is None, 'bad input accepted: %s %s (messages: %r)' % (path, options, msg)
    assert msg.strip(), 'no error message for %s %s' % (path, options)
    low = msg.lower()
    for s in all_of:
        assert s.lower() in low, '%r not in the error message %r' % (s, msg)
    if any_of:
        assert any(s.lower() in low for s in any_of), 'none of %r in the error message %r' % (any_of, msg)
    return msg


# ----------------------------------------------------------------------------
# bad inputs
# ----------------------------------------------------------------------------

def test_missing_rivers_datasource(wm, tmp_dir):
    p = os.path.join(tmp_dir, 'no_such_rivers.gpkg')
    assert_refused(wm, {'RIVERS': p}, all_of=['no_such_rivers.gpkg'])


def test_missing_lakes_datasource(wm, simple_options, tmp_dir):
    p = os.path.join(tmp_dir, 'no_such_lakes.gpkg')
    assert_refused(wm, dict(simple_options, LAKES=p), all_of=['no_such_lakes.gpkg'])


def test_unreadable_datasource(wm, tmp_dir):
    p = os.path.join(tmp_dir, 'garbage_rivers.gpkg')
    with open(p, 'w') as f:
        f.write('this is not a GeoPackage\n' * 10)
    assert_refused(wm, {'RIVERS': p}, all_of=['garbage_rivers.gpkg'])


def test_directory_as_datasource(wm, tmp_dir):
    d = os.path.join(tmp_dir, 'empty_dir_rivers')
    os.mkdir(d)
    assert_refused(wm, {'RIVERS': d}, all_of=['empty_dir_rivers'])


def test_missing_rivers_layer(wm, simple_options):
    assert_refused(wm, dict(simple_options, RIVERS_LAYER='no_such_layer_r'), all_of=['no_such_layer_r'])


def test_missing_lakes_layer(wm, simple_options):
    assert_refused(wm, dict(simple_options, LAKES_LAYER='no_such_layer_l'), all_of=['no_such_layer_l'])


def test_point_rivers(wm, tmp_dir):
    p = scenes.make_bad_scene(os.path.join(tmp_dir, 'point_rivers.gpkg'), 'points')
    assert_refused(wm, {'RIVERS': p, 'RIVERS_LAYER': 'rivers'}, all_of=['point'],
                   any_of=['point_rivers.gpkg', 'rivers'])


def test_polygons_as_rivers(wm, simple_scene):
    assert_refused(wm, {'RIVERS': simple_scene, 'RIVERS_LAYER': 'lakes'}, all_of=['polygon'],
                   any_of=[os.path.basename(simple_scene), 'lakes'])


def test_no_crs_refused(wm, tmp_dir):
    p = scenes.make_bad_scene(os.path.join(tmp_dir, 'no_crs_rivers.shp'), 'no_crs')
    msg = assert_refused(wm, {'RIVERS': p}, any_of=CRS_WORDS)
    assert 'no_crs_rivers' in msg, msg


def test_no_crs_accepted_with_target_srs(wm, tmp_dir):
    p = scenes.make_bad_scene(os.path.join(tmp_dir, 'no_crs_rivers.shp'), 'no_crs')
    o = {'RIVERS': p, 'TARGET_SRS': 'EPSG:32631', 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}
    res = wm.run(o)
    assert res.water
    problems = oracle.check_water(res.water, 512)
    assert not problems, '\n'.join(problems[:10])
    # 300 m x 10 m river with round caps
    a = oracle.total_area(res.water)
    want = 300 * 10 + 3.14159 * 25
    assert abs(a - want) < 0.02 * want, (a, want)


@pytest.mark.parametrize('kind', ['nan', 'inf'])
def test_nonfinite_river_coordinates(wm, tmp_dir, kind):
    p = scenes.make_bad_scene(os.path.join(tmp_dir, '%s_rivers.gpkg' % kind), kind)
    assert_refused(wm, {'RIVERS': p, 'RIVERS_LAYER': 'rivers', 'LAKES': p, 'LAKES_LAYER': 'lakes'},
                   all_of=['77'], any_of=NONFINITE_WORDS)


def test_nonfinite_lake_coordinates(wm, tmp_dir):
    p = scenes.make_bad_scene(os.path.join(tmp_dir, 'nan_lakes.gpkg'), 'lake_nan')
    assert_refused(wm, {'RIVERS': p, 'RIVERS_LAYER': 'rivers', 'LAKES': p, 'LAKES_LAYER': 'lakes'},
                   all_of=['78'], any_of=NONFINITE_WORDS)


@pytest.mark.parametrize('value', ['0', '-1'])
def test_pixel_size_not_positive(wm, simple_options, value):
    assert_refused(wm, dict(simple_options, PIXEL_SIZE=value), all_of=['PIXEL_SIZE'])


@pytest.mark.parametrize('option,value', [('METHOD', 'MARCHING'), ('HEURISTIC', 'RANDOM'),
                                          ('MERGE_DISTANCE', '-1'), ('MERGE_DISTANCE', 'far'),
                                          ('MIN_FEATURE_AREA', '-1'),
                                          ('MIN_FEATURE_AREA', 'tiny'),
                                          ('MESH_GEOMETRY', 'TRIANGLE_SOUP')])
def test_method_options_refused(wm, simple_options, option, value):
    assert_refused(wm, dict(simple_options, **{option: value}), all_of=[option, value])


def test_block_size_not_multiple_of_pixel_size(wm, simple_options):
    assert_refused(wm, dict(simple_options, PIXEL_SIZE=3, BLOCK_SIZE=1000), all_of=['BLOCK_SIZE'])


def test_block_too_large_for_memory(wm, simple_options):
    assert_refused(wm, dict(simple_options, PIXEL_SIZE=0.5, BLOCK_SIZE=1000000000),
                   any_of=['BLOCK_SIZE', 'memory'])


def test_block_too_large_raster(wm, simple_options):
    assert_refused(wm, dict(simple_options, PIXEL_SIZE=0.5, BLOCK_SIZE=1000000000),
                   any_of=['BLOCK_SIZE', 'memory'], flags=gdal.OF_RASTER)


def test_grid_too_many_blocks_per_side(wm, tmp_dir):
    """Two rivers 3,000 km apart over 2 m blocks: 1.5 M blocks per side,
    more than 2^20. Refused at open, naming the grid and the way out."""
    src = os.path.join(tmp_dir, 'far_apart.gpkg')
    scenes.write_layer(src, 'rivers', ogr.wkbLineString, 3857,
                       [{'geom': 'LINESTRING (0 0, 10 0)', 'width': 2.0},
                        {'geom': 'LINESTRING (3000000 0, 3000010 0)', 'width': 2.0}],
                       fields=[('width', 'Real')])
    assert_refused(wm, {'RIVERS': src, 'WIDTH_FIELD': 'width', 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 2},
                   all_of=['blocks', 'larger BLOCK_SIZE'])


def test_sparse_grid_accepted(wm, tmp_dir):
    """The same two rivers over 64 m blocks: a grid of 46,900 x 1 blocks, two
    of them in reach. Accepted, and a read visits only those (the index and
    the walk grow with the input, not with the grid)."""
    src = os.path.join(tmp_dir, 'far_apart.gpkg')
    scenes.write_layer(src, 'rivers', ogr.wkbLineString, 3857,
                       [{'geom': 'LINESTRING (10 10, 20 10)', 'width': 2.0},
                        {'geom': 'LINESTRING (3000010 10, 3000020 10)', 'width': 2.0}],
                       fields=[('width', 'Real')])
    ds, cap = wm.open({'RIVERS': src, 'WIDTH_FIELD': 'width', 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 64})
    assert ds is not None, cap.text
    blocks = sorted((f['block_x'], f['block_y']) for f in ds.GetLayerByName('water'))
    assert blocks == [(0, 0), (46875, 0)], blocks


def test_neither_rivers_nor_lakes(wm):
    assert_refused(wm, {'WIDTH': 5}, all_of=['RIVERS', 'LAKES'])


def test_neither_rivers_nor_lakes_in_descriptor(wm, tmp_dir):
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'nothing.watermesh'), WIDTH=5)
    assert_refused(wm, {}, path=desc, all_of=['RIVERS', 'LAKES'])


@pytest.mark.parametrize('text', [
    '<WaterMesh><RIVERS>x.gpkg</RIVERS>',            # truncated
    '<WaterMesh><RIVERS>x.gpkg</LAKES></WaterMesh>',  # mismatched tags
    '<WaterMesh><RIVERS>x.gpkg</RIVERS><WaterMesh>',  # unclosed root
])
def test_malformed_descriptor(wm, tmp_dir, text):
    desc = os.path.join(tmp_dir, 'malformed_scene.watermesh')
    with open(desc, 'w') as f:
        f.write(text)
    assert_refused(wm, {}, path=desc, any_of=['malformed_scene.watermesh', 'xml'])


def test_descriptor_missing_datasource(wm, tmp_dir):
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'scene.watermesh'),
                                   RIVERS='missing_relative_rivers.gpkg')
    assert_refused(wm, {}, path=desc, all_of=['missing_relative_rivers.gpkg'])


FILTER_FORMATS = {'GPKG': 'gpkg', 'FlatGeobuf': 'fgb', 'ESRI Shapefile': 'shp', 'GeoJSON': 'geojson'}


@pytest.mark.parametrize('fmt', sorted(FILTER_FORMATS))
@pytest.mark.parametrize('role', ['RIVERS', 'LAKES'])
def test_invalid_where_refused(wm, simple_scene, tmp_dir, fmt, role):
    """An attribute filter the input's driver cannot apply is an error on
    every format (GeoPackage accepts any filter and fails on the first
    read), naming the option, the filter and the layer."""
    layer = role.lower()
    path = os.path.join(tmp_dir, '%s.%s' % (layer, FILTER_FORMATS[fmt]))
    gdal.VectorTranslate(path, simple_scene, format=fmt, layers=[layer],
                         layerName=layer)
    o = {role: path, role + '_LAYER': layer, 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512,
         role + '_WHERE': 'nosuchfield = 1'}
    assert_refused(wm, o, all_of=[role + '_WHERE', 'nosuchfield', layer])


def test_invalid_where_refused_osm_and_vrt(wm, tmp_dir):
    """The same through the OSM driver (a raw .osm.pbf: its own field
    check) and a VRT over a GeoPackage (whose error comes on the first
    read)."""
    import conftest
    osm = os.path.join(tmp_dir, 'river.osm')
    with open(osm, 'w') as f:
        f.write('<?xml version="1.0"?><osm version="0.6">'
                '<node id="1" lat="47.1" lon="9.5"/><node id="2" lat="47.101" lon="9.501"/>'
                '<way id="3"><nd ref="1"/><nd ref="2"/><tag k="waterway" v="river"/></way>'
                '</osm>')
    assert ogr.Open(osm).GetDriver().GetName() == 'OSM'
    assert_refused(wm, {'RIVERS': osm, 'RIVERS_LAYER': 'lines',
                        'RIVERS_WHERE': 'nosuchfield = 1'},
                   all_of=['RIVERS_WHERE', 'nosuchfield', 'lines'])
    gpkg = os.path.join(conftest.DATA_DIR, 'osm_liechtenstein_2013.gpkg')
    vrt = os.path.join(tmp_dir, 'rivers.vrt')
    with open(vrt, 'w') as f:
        f.write('<OGRVRTDataSource><OGRVRTLayer name="rivers"><SrcDataSource>%s'
                '</SrcDataSource><SrcLayer>rivers</SrcLayer></OGRVRTLayer>'
                '</OGRVRTDataSource>' % gpkg)
    assert_refused(wm, {'RIVERS': vrt, 'RIVERS_LAYER': 'rivers',
                        'RIVERS_WHERE': 'nosuchfield = 1'},
                   all_of=['RIVERS_WHERE', 'nosuchfield', 'rivers.vrt'])


def test_valid_where_still_applies(wm, simple_scene, tmp_dir):
    """The first read that checks a filter leaves the layer's reading
    where it starts: every feature the filter selects is meshed."""
    o = {'RIVERS': simple_scene, 'RIVERS_LAYER': 'rivers', 'PIXEL_SIZE': 1,
         'BLOCK_SIZE': 512, 'RIVERS_WHERE': "name = 'A'"}
    got = oracle.total_area(wm.run(o).water)
    assert abs(got - oracle.water_area(o)) <= 0.005 * got


def test_num_threads_limit_named(wm, simple_options):
    assert_refused(wm, dict(simple_options, NUM_THREADS='100000'),
                   all_of=['NUM_THREADS', '1024'])


def test_geographic_crs_with_projected_coordinates(wm, tmp_dir):
    """GeoPackage's "undefined geographic" CRS (srs_id 0) on projected
    coordinates: refused, saying the coordinates are out of range and what
    to do, not a PROJ error."""
    path = os.path.join(tmp_dir, 'srs0.gpkg')
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, None,
                       [{'geom': 'LINESTRING (389000 4710000, 389100 4710050)'}])
    ds = ogr.Open(path, 1)
    ds.ExecuteSQL('UPDATE gpkg_geometry_columns SET srs_id = 0')
    ds.ExecuteSQL('UPDATE gpkg_contents SET srs_id = 0')
    ds = None
    assert ogr.Open(path).GetLayer(0).GetSpatialRef().IsGeographic()
    assert_refused(wm, {'RIVERS': path, 'RIVERS_LAYER': 'rivers'},
                   all_of=['rivers', 'out of range', 'TARGET_SRS'])


# the same refusals through the CLI: non-zero exit, ERROR on stderr, no dst
def _cli_case(case, tmp_dir, simple_scene):
    if case == 'missing_datasource':
        return ['-rivers', os.path.join(tmp_dir, 'no_such_rivers.gpkg')], 'no_such_rivers.gpkg'
    if case == 'missing_layer':
        return ['-rivers', simple_scene, '-rivers_layer', 'no_such_layer_r'], 'no_such_layer_r'
    if case == 'pixel_size':
        return ['-rivers', simple_scene, '-rivers_layer', 'rivers', '-pixel_size', '0'], 'PIXEL_SIZE'
    if case == 'block_size':
        return ['-rivers', simple_scene, '-rivers_layer', 'rivers', '-pixel_size', '3',
                '-block_size', '1000'], 'BLOCK_SIZE'
    if case == 'polygons_as_rivers':
        return ['-rivers', simple_scene, '-rivers_layer', 'lakes'], 'polygon'
    if case == 'nan':
        p = scenes.make_bad_scene(os.path.join(tmp_dir, 'nan_rivers.gpkg'), 'nan')
        return ['-rivers', p, '-rivers_layer', 'rivers'], '77'
    if case == 'neither':
        return ['-width', '5'], 'LAKES'
    if case == 'heuristic':
        return ['-rivers', simple_scene, '-rivers_layer', 'rivers', '-method', 'PAPER',
                '-heuristic', 'RANDOM'], 'HEURISTIC'
    if case == 'bad_where':  # GeoPackage reports it only on the first read
        return ['-rivers', simple_scene, '-rivers_layer', 'rivers',
                '-rivers_where', 'nosuchfield = 1'], 'nosuchfield'
    raise ValueError(case)


@pytest.mark.parametrize('case', ['missing_datasource', 'missing_layer', 'pixel_size', 'block_size',
                                  'polygons_as_rivers', 'nan', 'neither', 'heuristic',
                                  'bad_where'])
def test_cli_refuses(wm, tmp_dir, simple_scene, case):
    args, token = _cli_case(case, tmp_dir, simple_scene)
    out_dir = os.path.join(tmp_dir, 'out')
    os.mkdir(out_dir)
    dst = os.path.join(out_dir, 'out.gpkg')
    p = wm.cli(args + [dst])
    assert p.returncode != 0, 'exit 0 for %s: %s' % (case, p.stdout)
    assert 'ERROR' in p.stderr, p.stderr
    assert token.lower() in p.stderr.lower(), '%r not in %r' % (token, p.stderr)
    assert os.listdir(out_dir) == [], 'left behind: %s' % os.listdir(out_dir)


# ----------------------------------------------------------------------------
# odd but valid inputs
# ----------------------------------------------------------------------------

ODD_AREA_TOL = {'curves': 0.03}


def assert_valid_run(wm, options, block_size, area_rel):
    res = wm.run(options)
    assert res.water, 'no water output'
    problems = oracle.check_water(res.water, block_size)
    assert not problems, '\n'.join(problems[:10])
    problems, _ = oracle.check_mesh(res.mesh, res.water, block_size)
    assert not problems, '\n'.join(problems[:10])
    tj, gaps, details = oracle.check_seams(res.water, block_size)
    assert (tj, gaps) == (0, 0), '\n'.join(details[:10])
    tj, gaps, details = oracle.check_seams(res.mesh, block_size)
    assert (tj, gaps) == (0, 0), '\n'.join(details[:10])
    got = oracle.total_area(res.water)
    want = oracle.water_area(options)
    assert abs(got - want) <= area_rel * want, \
        'area %.1f vs oracle %.1f (rel %.4f)' % (got, want, (got - want) / want)
    return res


@pytest.mark.parametrize('method', ['CONTOUR', 'PAPER'])
@pytest.mark.parametrize('kind', scenes.ODD_KINDS)
def test_odd_input(wm, tmp_dir, kind, method):
    p = scenes.make_odd_scene(os.path.join(tmp_dir, '%s.gpkg' % kind), kind)
    o = {'RIVERS': p, 'RIVERS_LAYER': 'rivers', 'LAKES': p, 'LAKES_LAYER': 'lakes',
         'WIDTH_FIELD': 'width', 'PIXEL_SIZE': 0.5, 'BLOCK_SIZE': 256, 'METHOD': method}
    assert_valid_run(wm, o, 256, ODD_AREA_TOL.get(kind, 0.015))


def test_zero_length_river_warns(wm, tmp_dir):
    p = scenes.make_odd_scene(os.path.join(tmp_dir, 'zero.gpkg'), 'zero_length')
    o = {'RIVERS': p, 'RIVERS_LAYER': 'rivers', 'WIDTH_FIELD': 'width', 'PIXEL_SIZE': 0.5, 'BLOCK_SIZE': 256}
    res = wm.run(o)
    assert res.cap.warnings, 'no warning for the zero-length rivers'
    # skipped, not drawn as a disc
    x, y = scenes.xy(400, 500)
    from shapely.geometry import Point
    assert not any(f.geom.intersects(Point(x, y).buffer(5)) for f in res.water)


def test_rivers_and_lakes_in_different_crs(wm, tmp_dir):
    rp, lp = scenes.make_mixed_crs_scene(os.path.join(tmp_dir, 'mixed_rivers.gpkg'),
                                         os.path.join(tmp_dir, 'mixed_lakes.gpkg'))
    o = {'RIVERS': rp, 'LAKES': lp, 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}
    res = assert_valid_run(wm, o, 512, 0.01)
    ref = scenes.srs_from(scenes.SCENE_EPSG)
    assert res.srs is not None and res.srs.IsSame(ref)
    # the reprojected lake L2 is there
    from shapely.geometry import Point
    x, y = scenes.xy(225, 540)
    assert any(f.geom.contains(Point(x, y)) for f in res.water)


def test_non_metric_crs_refused(wm, tmp_dir):
    # widths and PIXEL_SIZE are metres: a CRS in US feet is refused
    p = scenes.make_bad_scene(os.path.join(tmp_dir, 'feet_rivers.shp'), 'no_crs')
    assert_refused(wm, {'RIVERS': p, 'TARGET_SRS': 'EPSG:2263'},
                   all_of=['metres', 'TARGET_SRS'])


def test_absurd_width_refused(wm, simple_options):
    assert_refused(wm, dict(simple_options, WIDTH='1e18'), all_of=['WIDTH'])


def test_absurd_width_field_value_falls_back(wm, tmp_dir):
    # a width of 1e7 m in the data is a data error: WIDTH is used instead,
    # counted in the warning
    p = os.path.join(tmp_dir, 'wide.gpkg')
    o = scenes.xy(0, 0)
    scenes.write_layer(p, 'rivers', ogr.wkbLineString, scenes.SCENE_EPSG,
                       [{'width': 1e7, 'geom': 'LINESTRING (%f %f, %f %f)' % (o[0], o[1], o[0] + 100, o[1])}],
                       fields=[('width', 'Real')])
    res = wm.run({'RIVERS': p, 'WIDTH_FIELD': 'width', 'WIDTH': 10, 'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512})
    assert res.water
    a = oracle.total_area(res.water)
    assert abs(a - (100 * 10 + 3.14159 * 25)) < 0.03 * a, a
    assert "1 feature" in res.cap.text, res.cap.text


def test_cli_refuses_virtual_destination(wm, tmp_dir, simple_scene):
    """The output is written beside its destination and moved into place:
    /vsistdout/ has no beside (it left /vsistdout_water and _mesh in the
    root folder, exit 0), /vsimem/ vanishes with the process."""
    for dst, fmt in (('/vsistdout/', 'GeoJSON'), ('/vsimem/out.gpkg', 'GPKG')):
        p = wm.cli(['-rivers', simple_scene, '-rivers_layer', 'rivers', '-of', fmt, dst],
                   cwd=tmp_dir)
        assert p.returncode != 0, (dst, p.stdout)
        assert 'virtual file system' in p.stderr, p.stderr
    assert not os.path.exists('/vsistdout_water') and not os.path.exists('/vsistdout')
    assert os.listdir(tmp_dir) == [], os.listdir(tmp_dir)


def test_cli_refuses_its_own_input(wm, tmp_dir, simple_scene):
    """A destination that is an input is refused before any work (it was
    replaced by the output, exit 0); the input stays as it was."""
    import shutil
    src = os.path.join(tmp_dir, 'scene.gpkg')
    shutil.copy(simple_scene, src)
    with open(src, 'rb') as f:
        before = f.read()
    p = wm.cli(['-rivers', src, '-rivers_layer', 'rivers', '-overwrite', src])
    assert p.returncode != 0, p.stdout
    assert 'is the RIVERS input' in p.stderr, p.stderr
    with open(src, 'rb') as f:
        assert f.read() == before


def test_collection_member_named(wm, tmp_dir):
    """Collections are read member by member, nested ones too; a member of
    another kind is refused by name."""
    path = os.path.join(tmp_dir, 'gc.gpkg')
    x, y = scenes.xy(100, 100)
    scenes.write_layer(path, 'rivers', ogr.wkbGeometryCollection, scenes.SCENE_EPSG,
                       [{'geom': 'GEOMETRYCOLLECTION (GEOMETRYCOLLECTION (POINT (%f %f)), '
                                 'LINESTRING (%f %f, %f %f))' % (x, y, x, y, x + 50, y),
                         'width': 5.0}], fields=[('width', 'Real')])
    out = os.path.join(tmp_dir, 'out')
    os.mkdir(out)
    p = wm.cli(['-rivers', path, '-rivers_layer', 'rivers', os.path.join(out, 'o.gpkg')])
    assert p.returncode != 0, p.stdout
    assert 'a Point member; rivers must be lines' in p.stderr, p.stderr
    assert os.listdir(out) == []


def test_river_narrower_than_the_lattice_skipped(wm, tmp_dir, simple_scene):
    """A river narrower than a lattice unit (PIXEL_SIZE / 256) has no area
    the lattice can hold: its capsules left rounding specks (27 rings on
    L3 at WIDTH=1e-300). It is skipped, with a warning."""
    out = os.path.join(tmp_dir, 'o.gpkg')
    p = wm.cli(['-rivers', simple_scene, '-rivers_layer', 'rivers', '-width', '1e-6',
                '-pixel_size', '0.5', out])
    assert p.returncode == 0, p.stderr
    assert 'narrower than the lattice' in p.stderr, p.stderr
    assert len(wm.read_output(out)['water']) == 0


def test_lake_with_no_area_left_warned(wm, tmp_dir):
    """A lake with an area in its own CRS that has none once reprojected
    and rounded to the lattice (a cap around the North Pole in EPSG:4326,
    drawn along the parallel 89.999 from -180 to 180: its vertices go to
    two points in UPS North) is skipped with a warning naming the layer,
    not silently (the output was empty without a word)."""
    path = os.path.join(tmp_dir, 'polar.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, 4326, [
        {'geom': 'POLYGON ((-180 89.999, 180 89.999, 180 90, -180 90, -180 89.999))'}])
    out = os.path.join(tmp_dir, 'o.gpkg')
    p = wm.cli(['-lakes', path, '-lakes_layer', 'lakes', '-pixel_size', '0.5',
                '-block_size', '64', out])
    assert p.returncode == 0, p.stderr
    assert "LAKES layer 'lakes': 1 lake(s) with an area have none" in p.stderr, p.stderr
    assert len(wm.read_output(out)['water']) == 0


@pytest.mark.parametrize('spike', ['middle', 'start', 'retraced'])
def test_lake_spike_of_no_width(wm, tmp_dir, spike):
    """A lake ring that goes out along an edge and comes back (a, b, a), at
    its middle, across its start, or retracing one edge many times, fills
    nothing there even-odd: one polygon, the triangle's area (the spike gave
    100 diamond specks; the retraced ring took 10 s)."""
    tri = [scenes.xy(0, 0), scenes.xy(100, 0), scenes.xy(100, 100)]
    tip = scenes.xy(300, 50)
    if spike == 'middle':
        ring = [tri[0], tri[1], tip, tri[1], tri[2]]
    elif spike == 'start':
        ring = [tri[1], tip, tri[1], tri[2], tri[0]]
    else:
        ring = [tri[0]] + [tri[1], tip] * 500 + [tri[1], tri[2]]
    wkt = 'POLYGON ((%s))' % ', '.join('%.3f %.3f' % p for p in ring + ring[:1])
    path = os.path.join(tmp_dir, 'spike.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, scenes.SCENE_EPSG, [{'geom': wkt}])
    res = wm.run({'LAKES': path, 'LAKES_LAYER': 'lakes', 'PIXEL_SIZE': 0.5,
                  'BLOCK_SIZE': 256})
    assert len(res.water) == 1, [f.geom.area for f in res.water]
    assert abs(oracle.total_area(res.water) - 5000.0) < 1.0, oracle.total_area(res.water)
