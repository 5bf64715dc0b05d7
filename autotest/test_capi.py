"""The public C API (watermesh.h) through tests/capi_demo, and interrupting
the CLI: a cancelled run reports CPLE_UserInterrupt and writes nothing."""

import os
import signal
import subprocess
import time

import pytest

import conftest

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
