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


@pytest.mark.parametrize('fmt,ext', [('ESRI Shapefile', 'shp'), ('FlatGeobuf', 'fgb'),
                                     ('GeoJSON', 'geojson')])
def test_single_layer_format_writes_two_files(wm, simple_options, simple_args, tmp_dir, fmt, ext):
    """A single-layer format named as a file: <name>_water.<ext> and
    <name>_mesh.<ext>, nothing else (never a stray mesh.<ext> beside it)."""
    out = os.path.join(tmp_dir, 'single')
    os.mkdir(out)
    ok(wm.cli(simple_args + [os.path.join(out, 'out.' + ext)]))
    names = listing(out)
    assert 'out_water.' + ext in names and 'out_mesh.' + ext in names, names
    assert all(n.startswith(('out_water.', 'out_mesh.')) for n in names), names
    ref = wm.run(simple_options)
    for layer, want in (('water', ref.water), ('mesh', ref.mesh)):
        ds = gdal.OpenEx(os.path.join(out, 'out_%s.%s' % (layer, ext)), gdal.OF_VECTOR)
        assert ds.GetDriver().ShortName == fmt
        assert ds.GetLayerCount() == 1
        assert ds.GetLayer(0).GetFeatureCount() == len(want), layer


def test_single_layer_existing_target_refused_before_work(wm, simple_args, tmp_dir):
    out = os.path.join(tmp_dir, 'single')
    os.mkdir(out)
    with open(os.path.join(out, 'out_mesh.shp'), 'w') as f:
        f.write('not ours')
    p = failed(wm.cli(simple_args + ['-stats', os.path.join(out, 'out.shp')]))
    assert 'out_mesh.shp' in p.stderr and '-overwrite' in p.stderr, p.stderr
    assert 'total (wall)' not in p.stdout, 'the run started before refusing'
    assert listing(out) == ['out_mesh.shp']


def test_stray_sidecar_leaves_nothing(wm, simple_args, tmp_dir):
    """Issue 13, item 7: a file of the output's set already there (here a
    .dbf without its .shp) fails the run without -overwrite, and nothing of
    the new output is moved beside it: every entry is checked before any
    is moved."""
    out = os.path.join(tmp_dir, 'single')
    os.mkdir(out)
    with open(os.path.join(out, 'out_mesh.dbf'), 'w') as f:
        f.write('not ours')
    p = failed(wm.cli(simple_args + [os.path.join(out, 'out.shp')]))
    assert 'out_mesh.dbf' in p.stderr, p.stderr
    assert listing(out) == ['out_mesh.dbf']
    assert open(os.path.join(out, 'out_mesh.dbf')).read() == 'not ours'


def test_overwrite_drops_old_side_files(wm, simple_args, tmp_dir):
    """-overwrite replaces a whole old dataset: a spatial index (.qix) the
    old Shapefile had does not outlive it next to the new one."""
    out = os.path.join(tmp_dir, 'single')
    os.mkdir(out)
    dst = os.path.join(out, 'out.shp')
    ok(wm.cli(simple_args + [dst]))
    old = gdal.OpenEx(os.path.join(out, 'out_water.shp'), gdal.OF_VECTOR | gdal.OF_UPDATE)
    old.ExecuteSQL('CREATE SPATIAL INDEX ON out_water')
    old = None
    assert 'out_water.qix' in listing(out)
    ok(wm.cli(simple_args + ['-overwrite', '-width', '14', dst]))
    names = listing(out)
    assert 'out_water.qix' not in names, names
    assert 'out_water.shp' in names and 'out_mesh.shp' in names, names


@pytest.mark.parametrize('k', [1, 5, 8, 9, 12, 16])
def test_failed_move_puts_everything_back(wm, simple_args, tmp_dir, k):
    """A rename that fails while the new output is moved into place (the
    k-th, made to fail by the test hook GDAL_WATERMESH_TEST_RENAME_FAILURE).
    With -overwrite, renames 1-8 set the old files aside (4 per Shapefile)
    and 9-16 move the new ones in. The files already moved are removed and
    the old ones renamed back: the old output is left whole, and nothing of
    the new one."""
    out = os.path.join(tmp_dir, 'single%d' % k)
    os.mkdir(out)
    dst = os.path.join(out, 'out.shp')
    ok(wm.cli(simple_args + [dst]))
    before = {n: open(os.path.join(out, n), 'rb').read() for n in listing(out)}
    p = failed(wm.cli(simple_args + ['-overwrite', '-width', '14', '--config',
                                     'GDAL_WATERMESH_TEST_RENAME_FAILURE', str(k), dst]))
    assert 'cannot move' in p.stderr, p.stderr
    assert listing(out) == sorted(before), listing(out)
    for n, data in before.items():
        assert open(os.path.join(out, n), 'rb').read() == data, n


def _tiny_disk(path, kib):
    """A folder whose file system holds `kib` KiB: a tmpfs when this
    process may mount one (root), else a folder under a file-size limit
    (RLIMIT_FSIZE, applied to the child). Returns (preexec_fn, how)."""
    import resource
    import subprocess
    os.mkdir(path)
    if os.geteuid() == 0 and subprocess.run(
            ['mount', '-t', 'tmpfs', '-o', 'size=%dk' % kib, 'tmpfs', path],
            stderr=subprocess.DEVNULL).returncode == 0:
        return None, 'tmpfs'

    def limit():
        import signal
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (kib << 10, kib << 10))
    return limit, 'RLIMIT_FSIZE'


def test_full_disk_leaves_nothing(wm, simple_args, tmp_dir):
    """The destination's disk fills during the run (a 256 KiB tmpfs, or a
    file-size limit where mounting is not allowed): a clear error naming
    the write, exit 1, and nothing left at the destination or beside it."""
    import subprocess
    disk = os.path.join(tmp_dir, 'tiny')
    pre, how = _tiny_disk(disk, 256)
    try:
        dst = os.path.join(disk, 'out.gpkg')
        # 2.5 MB of output: the disk fills while features are written
        args = [wm.CLI_PATH] + simple_args + ['-pixel_size', '0.25', '-simplify', '0', dst]
        p = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=300, preexec_fn=pre)
        assert p.returncode == 1, (how, p.returncode, p.stderr)
        assert 'ERROR' in p.stderr, (how, p.stderr)
        low = p.stderr.lower()
        assert any(w in low for w in ('space', 'full', 'too large', 'write', 'disk')), (how, p.stderr)
        assert os.listdir(disk) == [], (how, os.listdir(disk))
    finally:
        if how == 'tmpfs':
            subprocess.run(['umount', disk])


def test_read_only_destination(wm, simple_args, tmp_dir):
    """A destination folder that cannot be written: a read-only bind mount
    as root (for whom modes do not count), else mode 0555. A clear error
    naming the folder, exit 1, nothing created."""
    import subprocess
    ro = os.path.join(tmp_dir, 'readonly')
    os.mkdir(ro)
    how = 'chmod 0555'
    if os.geteuid() == 0:
        assert subprocess.run(['mount', '--bind', ro, ro]).returncode == 0
        assert subprocess.run(['mount', '-o', 'remount,ro,bind', ro]).returncode == 0
        how = 'read-only bind mount'
    else:
        os.chmod(ro, 0o555)
    try:
        p = wm.cli(simple_args + [os.path.join(ro, 'out.gpkg')])
        assert p.returncode == 1, (how, p.stderr)
        assert 'ERROR' in p.stderr and ro in p.stderr, (how, p.stderr)
        assert os.listdir(ro) == [], how
    finally:
        if how == 'chmod 0555':
            os.chmod(ro, 0o755)
        else:
            subprocess.run(['umount', ro])


def _leaf_triangles(g):
    """The triangles of a TIN, or of what GDAL reads a MultiPatch back as (a
    GeometryCollection of a TIN and a MultiPolygon of triangles); each leaf
    must be a closed ring of 3 corners."""
    name = g.GetGeometryName()
    if name in ('TRIANGLE', 'POLYGON'):
        ring = g.GetGeometryRef(0)
        assert g.GetGeometryCount() == 1 and ring.GetPointCount() == 4, g.ExportToWkt()[:200]
        return 1
    assert name in ('TIN', 'MULTIPOLYGON', 'GEOMETRYCOLLECTION'), name
    return sum(_leaf_triangles(g.GetGeometryRef(i)) for i in range(g.GetGeometryCount()))


MESH_FILES = [('gpkg', 'out.gpkg'), ('fgb', 'out_mesh.fgb'), ('shp', 'out_mesh.shp')]


def cli_mesh_layer(wm, simple_args, tmp_dir, form, ext, mesh_file):
    """Runs the CLI with -mesh_geometry form to out.<ext> in a folder of its
    own; returns the mesh file's dataset and mesh layer."""
    out = os.path.join(tmp_dir, '%s_%s' % (form, ext))
    os.mkdir(out)
    p = wm.cli(simple_args + ['-mesh_geometry', form, os.path.join(out, 'out.' + ext)])
    assert p.returncode == 0, p.stderr
    ds = gdal.OpenEx(os.path.join(out, mesh_file), gdal.OF_VECTOR)
    return ds, ds.GetLayerByName('mesh') if ext == 'gpkg' else ds.GetLayer(0)


@pytest.mark.parametrize('ext,mesh_file', MESH_FILES)
def test_mesh_geometry_tin_reads_back(wm, simple_options, simple_args, tmp_dir, ext, mesh_file):
    """-mesh_geometry TIN to GeoPackage, FlatGeobuf and Shapefile (a
    MultiPatch): every feature reads back with every triangle, as a TIN
    (GeoPackage, FlatGeobuf) or as GDAL reads a MultiPatch."""
    ds, lyr = cli_mesh_layer(wm, simple_args, tmp_dir, 'TIN', ext, mesh_file)
    ref = wm.run(simple_options).mesh
    want = sum(f.fields['triangles'] for f in ref)
    got = 0
    for f in lyr:
        g = f.GetGeometryRef()
        if ext != 'shp':
            assert ogr.GT_Flatten(g.GetGeometryType()) == ogr.wkbTIN, g.GetGeometryName()
        n = _leaf_triangles(g)
        assert n == f['triangles']
        got += n
    assert lyr.GetFeatureCount() == len(ref)
    assert got == want > 0


def _rings(g):
    """The rings of a Polygon or MultiPolygon, each checked to be a closed
    triangle (4 points)."""
    polys = [g] if g.GetGeometryName() == 'POLYGON' else \
        [g.GetGeometryRef(i) for i in range(g.GetGeometryCount())]
    rings = [p.GetGeometryRef(k) for p in polys for k in range(p.GetGeometryCount())]
    assert all(r.GetPointCount() == 4 for r in rings), g.ExportToWkt()[:200]
    return len(rings)


@pytest.mark.parametrize('ext,mesh_file', MESH_FILES)
def test_mesh_geometry_multipolygon_reads_back(wm, simple_args, tmp_dir, ext, mesh_file):
    """The default MULTIPOLYGON form keeps every triangle in GeoPackage,
    FlatGeobuf and Shapefile, each as a ring of its own (Shapefile's ring
    organisation may read a triangle back as an inner ring of another)."""
    ds, lyr = cli_mesh_layer(wm, simple_args, tmp_dir, 'MULTIPOLYGON', ext, mesh_file)
    n = 0
    for f in lyr:
        assert _rings(f.GetGeometryRef()) == f['triangles']
        n += f['triangles']
    assert n > 0


@pytest.mark.parametrize('ext,mesh_file', MESH_FILES)
def test_mesh_geometry_triangles_reads_back(wm, simple_options, simple_args, tmp_dir, ext,
                                            mesh_file):
    """-mesh_geometry TRIANGLES to GeoPackage, FlatGeobuf and Shapefile: one
    valid Polygon per triangle, as many as the triangles the default form
    counts, each polygon's share under its key."""
    ds, lyr = cli_mesh_layer(wm, simple_args, tmp_dir, 'TRIANGLES', ext, mesh_file)
    ref = wm.run(simple_options).mesh
    want = {}
    for f in ref:
        key = (f.fields['block_x'], f.fields['block_y'], f.fields['polygon'])
        want[key] = want.get(key, 0) + f.fields['triangles']
    got = {}
    for f in lyr:
        g = f.GetGeometryRef()
        assert ogr.GT_Flatten(g.GetGeometryType()) == ogr.wkbPolygon, g.GetGeometryName()
        assert g.GetGeometryRef(0).GetPointCount() == 4 and g.IsValid()
        key = (f['block_x'], f['block_y'], f['polygon'])
        got[key] = got.get(key, 0) + 1
    assert got == want and sum(want.values()) > 0


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
