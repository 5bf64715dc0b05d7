"""gdal_watermesh command line utility."""

import os
import sqlite3

import pytest
from osgeo import gdal, ogr

import oracle
import scenes

STATS_COLUMNS = ('field', 'extraction', 'simplification', 'holes', 'triangulation', 'total')


def ok(p):
    assert p.returncode == 0, 'exit %d\nstdout:\n%s\nstderr:\n%s' % (p.returncode, p.stdout, p.stderr)
    assert 'ERROR' not in p.stderr, p.stderr
    return p


def failed(p):
    assert p.returncode != 0, 'expected a failure, got exit 0\nstdout:\n%s\nstderr:\n%s' % (p.stdout, p.stderr)
    assert 'ERROR' in p.stderr, 'no ERROR on stderr: %r' % p.stderr
    return p


def listing(d):
    return sorted(os.listdir(d))


@pytest.fixture(scope='module')
def simple_args(wm, simple_options):
    return wm.cli_args(simple_options)


def test_help(wm):
    p = ok(wm.cli(['--help']))
    out = p.stdout + p.stderr
    for opt in ('-rivers', '-lakes', '-width', '-pixel_size', '-block_size', '-spat', '-of', '-overwrite', '-stats'):
        assert opt in out, '%s not in --help output:\n%s' % (opt, out)


def test_version(wm):
    p = ok(wm.cli(['--version']))
    assert (p.stdout + p.stderr).strip(), 'empty --version output'


def test_no_arguments_fails(wm):
    p = wm.cli([])
    assert p.returncode != 0


def test_basic_run_gpkg(wm, simple_options, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + [dst]))
    ds = gdal.OpenEx(dst, gdal.OF_VECTOR)
    assert ds is not None
    assert ds.GetDriver().ShortName == 'GPKG'
    names = sorted(ds.GetLayer(i).GetName() for i in range(ds.GetLayerCount()))
    assert names == ['mesh', 'water'], names
    ds = None
    out = wm.read_output(dst)
    ref = wm.run(simple_options)
    assert wm.signature(out['water']) == wm.signature(ref.water)
    assert wm.signature(out['mesh']) == wm.signature(ref.mesh)


def test_no_temporary_left(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + [dst]))
    assert listing(tmp_dir) == ['out.gpkg'], listing(tmp_dir)


def test_stats(wm, simple_args, tmp_dir):
    p = ok(wm.cli(simple_args + ['-stats', os.path.join(tmp_dir, 'out.gpkg')]))
    out = p.stdout + p.stderr
    for col in STATS_COLUMNS:
        assert col in out.lower(), 'column %s missing from -stats output:\n%s' % (col, out)
    assert 'V =' in out, '"V =" missing from -stats output:\n%s' % out


def test_spat(wm, simple_options, simple_args, tmp_dir):
    B = simple_options['BLOCK_SIZE']
    x0, y0 = scenes.xy(300, 350)
    x1, y1 = scenes.xy(600, 450)
    touched = oracle.blocks_touching((x0, y0, x1, y1), B)
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + ['-spat', x0, y0, x1, y1, dst]))
    out = wm.read_output(dst)
    full = wm.run(simple_options)
    for name, feats, ref in (('water', out['water'], full.water), ('mesh', out['mesh'], full.mesh)):
        assert feats, 'no %s features with -spat' % name
        blocks = {f.block for f in feats}
        assert blocks <= touched, (name, sorted(blocks), sorted(touched))
        sub = wm.signature([f for f in ref if f.block in touched])
        assert all(s in sub for s in wm.signature(feats)), name


def test_refuses_existing_dst_without_overwrite(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + [dst]))
    with open(dst, 'rb') as f:
        before = f.read()
    mtime = os.stat(dst).st_mtime_ns
    failed(wm.cli(simple_args + ['-width', '20', dst]))
    with open(dst, 'rb') as f:
        assert f.read() == before, 'dst modified although -overwrite was not given'
    assert os.stat(dst).st_mtime_ns == mtime
    assert listing(tmp_dir) == ['out.gpkg'], listing(tmp_dir)


def test_refuses_existing_non_datasource_dst(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    with open(dst, 'w') as f:
        f.write('precious')
    failed(wm.cli(simple_args + [dst]))
    with open(dst) as f:
        assert f.read() == 'precious'


def test_overwrite(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + ['-width', '10', dst]))
    a10 = oracle.total_area(wm.read_output(dst)['water'])
    ok(wm.cli(simple_args + ['-width', '20', '-overwrite', dst]))
    a20 = oracle.total_area(wm.read_output(dst)['water'])
    assert a20 > 1.2 * a10, 'dst not replaced by -overwrite (%r, %r)' % (a10, a20)
    assert listing(tmp_dir) == ['out.gpkg'], listing(tmp_dir)


def test_failure_leaves_no_dst(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    failed(wm.cli(['-rivers', os.path.join(tmp_dir, 'no_such_rivers.gpkg'), dst]))
    assert not os.path.exists(dst)
    assert listing(tmp_dir) == [], 'files left behind: %s' % listing(tmp_dir)


def test_failure_bad_option_leaves_no_dst(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    failed(wm.cli(simple_args + ['-pixel_size', '-1', dst]))
    assert listing(tmp_dir) == [], listing(tmp_dir)


def test_failure_bad_format_leaves_no_dst(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.xyz')
    failed(wm.cli(simple_args + ['-of', 'NoSuchFormat', dst]))
    assert listing(tmp_dir) == [], listing(tmp_dir)


def test_failed_overwrite_keeps_old_dst(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + [dst]))
    with open(dst, 'rb') as f:
        before = f.read()
    failed(wm.cli(simple_args + ['-pixel_size', '-1', '-overwrite', dst]))
    with open(dst, 'rb') as f:
        assert f.read() == before, 'a failed -overwrite run damaged the existing dst'


def test_quiet(wm, simple_args, tmp_dir):
    p = ok(wm.cli(simple_args + ['-q', os.path.join(tmp_dir, 'out.gpkg')]))
    assert p.stdout.strip() == '', 'output with -q: %r' % p.stdout
    assert p.stderr.strip() == '', 'stderr with -q: %r' % p.stderr


def test_progress(wm, simple_args, tmp_dir):
    p = ok(wm.cli(simple_args + ['-progress', os.path.join(tmp_dir, 'out.gpkg')]))
    out = p.stdout + p.stderr
    assert '100' in out or 'done' in out, 'no progress output: %r' % out


@pytest.mark.parametrize('fmt', ['ESRI Shapefile', 'FlatGeobuf'])
def test_output_format_directory(wm, simple_options, simple_args, tmp_dir, fmt):
    dst = os.path.join(tmp_dir, 'outdir')
    ok(wm.cli(simple_args + ['-of', fmt, dst]))
    ds = gdal.OpenEx(dst, gdal.OF_VECTOR)
    assert ds is not None, 'cannot open %s output %s (%s)' % (fmt, dst, listing(tmp_dir))
    assert ds.GetDriver().ShortName == fmt
    names = sorted(ds.GetLayer(i).GetName() for i in range(ds.GetLayerCount()))
    assert names == ['mesh', 'water'], names
    ref = wm.run(simple_options)
    assert ds.GetLayerByName('water').GetFeatureCount() == len(ref.water)
    assert ds.GetLayerByName('mesh').GetFeatureCount() == len(ref.mesh)
    water = wm.read_layer(ds.GetLayerByName('water'))
    a, b = oracle.total_area(water), oracle.total_area(ref.water)
    assert abs(a - b) <= 1e-9 * b, (a, b)


def test_lco(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + ['-lco', 'FID=wm_fid', dst]))
    ds = ogr.Open(dst)
    for name in ('water', 'mesh'):
        assert ds.GetLayerByName(name).GetFIDColumn() == 'wm_fid', name


def test_dsco(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + ['-dsco', 'VERSION=1.3', dst]))
    con = sqlite3.connect(dst)
    try:
        assert con.execute('PRAGMA user_version').fetchone()[0] == 10300
    finally:
        con.close()


def test_descriptor_source(wm, simple_options, tmp_dir):
    desc = scenes.write_descriptor(os.path.join(tmp_dir, 'scene.watermesh'), **simple_options)
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli([desc, dst]))
    out = wm.read_output(dst)
    ref = wm.run(simple_options)
    assert wm.signature(out['water']) == wm.signature(ref.water)
    assert wm.signature(out['mesh']) == wm.signature(ref.mesh)


def test_all_options_match_open_options(wm, simple_scene, tmp_dir):
    o = {'RIVERS': simple_scene, 'RIVERS_LAYER': 'rivers', 'RIVERS_WHERE': "name <> 'C'",
         'LAKES': simple_scene, 'LAKES_LAYER': 'lakes', 'LAKES_WHERE': "name = 'L1'",
         'WIDTH': 12, 'WIDTH_FIELD': 'width', 'PIXEL_SIZE': 0.5, 'BLOCK_SIZE': 256,
         'SIMPLIFY': 0.25, 'METHOD': 'CONTOUR', 'DEVICE': 'CPU', 'NUM_THREADS': 2,
         'TARGET_SRS': 'EPSG:%d' % scenes.SCENE_EPSG}
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(wm.cli_args(o) + [dst]))
    out = wm.read_output(dst)
    ref = wm.run(o)
    assert wm.signature(out['water']) == wm.signature(ref.water)
    assert wm.signature(out['mesh']) == wm.signature(ref.mesh)


def test_overwrite_directory_keeps_other_files(wm, simple_options, simple_args, tmp_dir):
    # -overwrite replaces what the run writes, never the rest of a folder
    dst = os.path.join(tmp_dir, 'shpdir')
    ok(wm.cli(simple_args + ['-of', 'ESRI Shapefile', dst]))
    keep = os.path.join(dst, 'keep.txt')
    with open(keep, 'w') as f:
        f.write('not ours')
    ok(wm.cli(simple_args + ['-of', 'ESRI Shapefile', '-overwrite', '-width', '14', dst]))
    assert open(keep).read() == 'not ours'
    ds = gdal.OpenEx(dst, gdal.OF_VECTOR)
    water = wm.read_layer(ds.GetLayerByName('water'))
    ref = wm.run(dict(simple_options, WIDTH=14))
    a, b = oracle.total_area(water), oracle.total_area(ref.water)
    assert abs(a - b) <= 1e-9 * b, (a, b)


def test_failed_run_reports_only_its_error(wm, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    p = failed(wm.cli(simple_args + ['-width_field', 'nosuch', dst]))
    assert 'nosuch' in p.stderr
    assert 'no such table' not in p.stderr, p.stderr
    assert p.stderr.count('ERROR') == 1, p.stderr


def test_huge_spat_is_everything(wm, simple_options, simple_args, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    ok(wm.cli(simple_args + ['-spat', '-1e30', '-1e30', '1e30', '1e30', dst]))
    got = wm.read_output(dst)
    assert len(got['water']) == len(wm.run(simple_options).water)
