"""The public C API (watermesh.h) through tests/capi_demo, and interrupting
the CLI: a cancelled run reports CPLE_UserInterrupt and writes nothing."""

import math
import os
import re
import signal
import subprocess
import time

import pytest
from osgeo import ogr

import conftest
import scenes

DEMO = os.path.join(conftest.BUILD_DIR, 'tests', 'capi_demo')
ANDORRA = os.path.join(conftest.DATA_DIR, 'osm_andorra_2023.gpkg')


def run_demo(*args):
    assert os.path.exists(DEMO), 'C API demo not built: %s' % DEMO
    return subprocess.run([DEMO] + [str(a) for a in args], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, universal_newlines=True, timeout=300)


def parse(stdout):
    tok = stdout.split()
    return {tok[i]: float(tok[i + 1]) for i in range(0, len(tok) - 1, 2)}


def test_capi_generate(simple_scene):
    p = run_demo(simple_scene, 'rivers', simple_scene, 'lakes', 'PIXEL_SIZE=1', 'BLOCK_SIZE=512')
    assert p.returncode == 0, p.stderr
    got = parse(p.stdout)
    assert got['water'] > 0 and got['water'] == got['mesh'], got
    assert got['area'] > 1000, got
    # progress: one call at start plus one per block
    assert got['progress_calls'] >= 2, got


def test_capi_matches_driver(wm, simple_scene, simple_options):
    p = run_demo(simple_scene, 'rivers', simple_scene, 'lakes', 'PIXEL_SIZE=1', 'BLOCK_SIZE=512')
    assert p.returncode == 0, p.stderr
    got = parse(p.stdout)
    res = wm.run(simple_options)
    area = sum(f.geom.area for f in res.water)
    assert got['water'] == len(res.water)
    assert abs(got['area'] - area) <= 1e-6 * area, (got['area'], area)


def test_capi_cancel(simple_scene):
    p = run_demo(simple_scene, 'rivers', simple_scene, 'lakes', '--cancel', 'PIXEL_SIZE=1', 'BLOCK_SIZE=256')
    assert p.returncode == 2, 'expected a cancellation (exit 2), got %d: %s' % (p.returncode, p.stderr)
    assert 'User terminated' in p.stderr, p.stderr


def test_capi_bad_option(simple_scene):
    p = run_demo(simple_scene, 'rivers', simple_scene, 'lakes', 'PIXEL_SIZE=-1')
    assert p.returncode == 1
    assert 'PIXEL_SIZE' in p.stderr, p.stderr


def test_capi_lakes_only(simple_scene):
    p = run_demo('-', '-', simple_scene, 'lakes', 'PIXEL_SIZE=1', 'BLOCK_SIZE=512')
    assert p.returncode == 0, p.stderr
    assert parse(p.stdout)['water'] > 0


def test_cli_interrupted_leaves_nothing(wm, tmp_dir):
    dst = os.path.join(tmp_dir, 'interrupted.gpkg')
    # a run of several seconds (0.1 m pixels: about 7 s on one thread here)
    args = [conftest.CLI_PATH, '-rivers', ANDORRA, '-rivers_layer', 'rivers', '-lakes', ANDORRA,
            '-lakes_layer', 'lakes', '-pixel_size', '0.1', '-num_threads', '1', dst]
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            universal_newlines=True)
    time.sleep(1.5)
    if proc.poll() is not None:
        pytest.fail('run finished before it could be interrupted (%d)' % proc.returncode)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode != 0, err
    assert 'interrupted' in err or 'User terminated' in err, err
    assert not os.path.exists(dst)
    assert [f for f in os.listdir(tmp_dir) if 'watermesh' in f and f.endswith('.tmp')] == []


def _dense_river(path):
    """One river 200 m long of 200,000 vertices 1 mm apart with a 1 cm
    wiggle, 3 m wide (issue 13): minutes of work inside one block."""
    n = 200000
    wkt = 'LINESTRING (%s)' % ','.join(
        '%.4f %.4f' % (400000 + i * 0.001, 4700000 + 0.01 * math.sin(i * 0.7)) for i in range(n))
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, 32631, [{'geom': wkt, 'width': 3.0}],
                       fields=[('width', 'Real')])
    return path


def _serpentine(path):
    """One river 5 m wide winding 256 km inside one block of 16384 m (at
    0.25 m pixels: one block of 65536 x 65536 samples, about 6 s on one
    thread here)."""
    pts = []
    x0, y0 = 393300.0, 4702300.0  # block (24, 287) of 16384 m
    for row in range(40):
        xs = [x0 + k * 10.0 for k in range(1600)]
        for x in (xs[::-1] if row % 2 else xs):
            pts.append((x, y0 + row * 400.0 + 20.0 * math.sin(x / 37.0)))
    wkt = 'LINESTRING (%s)' % ','.join('%.3f %.3f' % p for p in pts)
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, 32631, [{'geom': wkt, 'width': 5.0}],
                       fields=[('width', 'Real')])
    return path


@pytest.mark.parametrize('sig', [signal.SIGTERM, signal.SIGINT])
def test_cli_signal_acted_on_within_a_second(tmp_dir, sig):
    """A signal in the middle of a block of several seconds: the run stops
    within a second (the core's loops check the runner's stop flag, which
    the progress callback sets from the signal), exits non-zero, and leaves
    nothing at the destination or beside it."""
    src = _serpentine(os.path.join(tmp_dir, 'serpentine.gpkg'))
    out_dir = os.path.join(tmp_dir, 'out')
    os.mkdir(out_dir)
    dst = os.path.join(out_dir, 'serpentine_out.gpkg')
    proc = subprocess.Popen([conftest.CLI_PATH, '-rivers', src, '-width_field', 'width', '-q',
                             '-pixel_size', '0.25', '-block_size', '16384', '-num_threads', '1',
                             dst],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    time.sleep(1.5)  # the block takes 2.5-6 s here: the signal lands inside it
    if proc.poll() is not None:
        pytest.fail('run finished before the signal (%d): %s' % (proc.returncode, proc.stderr.read()))
    t = time.time()
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail('still running 30 s after the signal')
    waited = time.time() - t
    assert waited <= 1.0, 'stopped %.2f s after the signal' % waited
    assert proc.returncode != 0, err
    assert 'interrupted' in err, err
    assert os.listdir(out_dir) == [], os.listdir(out_dir)


def test_dense_river_bounded(tmp_dir):
    """The same over-dense river (vertices 1 mm apart, closer than a
    lattice unit) runs in seconds under a 1.5 GB address-space cap: dense
    runs of vertices are thinned at reading (the 1 cm wiggle to 8 lattice
    units: at 1, 2 and 4 Douglas-Peucker gives up after 32 distances per
    vertex, which took 29 s unbounded). Its area is the
    straight river's within 1 % (the 1 cm wiggle widens the union by at
    most 2 cm: 0.7 %; GEOS itself takes minutes to buffer the raw line)."""
    import resource
    src = _dense_river(os.path.join(tmp_dir, 'dense.gpkg'))
    dst = os.path.join(tmp_dir, 'dense_out.gpkg')

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (1536 << 20, 1536 << 20))
    t = time.time()
    p = subprocess.run([conftest.CLI_PATH, '-rivers', src, '-width_field', 'width', '-q',
                        '-simplify', '0', dst], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, timeout=120, preexec_fn=cap)
    took = time.time() - t
    assert p.returncode == 0, p.stderr
    assert took < 20, 'took %.1f s' % took
    from shapely.geometry import LineString
    want = LineString([(400000, 4700000), (400199.999, 4700000)]).buffer(1.5, 64).area
    out = ogr.Open(dst)
    water = out.GetLayerByName('water')
    got = sum(f.GetGeometryRef().GetArea() for f in water)
    assert abs(got - want) <= 0.01 * want, (got, want)


def test_wide_river_over_tiny_blocks_opens_cheaply(tmp_dir):
    """One river of two points, 10 m long and 100 km wide, over 13 m blocks
    (issue 13): the grid has 7,700 x 7,700 blocks, nearly all of them in
    reach of the river. The index holds the river's one reach box, not a
    row per block (was 26 s and 2.4 GB just to open), so opening it and
    reading the blocks under a small spatial filter fits a 1 GB
    address-space cap in seconds, and the blocks read are the river's."""
    import resource
    src = os.path.join(tmp_dir, 'wide.gpkg')
    scenes.write_layer(src, 'rivers', ogr.wkbLineString, 32631,
                       [{'geom': 'LINESTRING (500000 5000000, 500010 5000000)',
                         'width': 100000.0}], fields=[('width', 'Real')])

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))
    t = time.time()
    p = subprocess.run(['ogrinfo', '-ro', '-q', 'WATERMESH:', '-oo', 'RIVERS=' + src,
                        '-oo', 'WIDTH_FIELD=width', '-oo', 'PIXEL_SIZE=1', '-oo', 'BLOCK_SIZE=13',
                        'water', '-spat', '500000', '5000000', '500030', '5000030'],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                       timeout=120, preexec_fn=cap)
    took = time.time() - t
    assert p.returncode == 0, p.stderr
    assert took < 10, 'took %.1f s' % took
    # blocks 38461..38463 x 384615..384617 (3 x 3, whole water squares)
    blocks = set(re.findall(r'block_x \(Integer\) = (\d+)\s+block_y \(Integer\) = (\d+)',
                            p.stdout))
    assert blocks == {(str(x), str(y)) for x in range(38461, 38464)
                      for y in range(384615, 384618)}, sorted(blocks)
