"""DEVICE=AUTO|CPU|OPENCL: device choice, the OpenCL path end to end, and
every fallback (no platform, a kernel that does not build, a device that
fails during the run).

Which half runs depends on conftest.OPENCL_EXPECTED: with a device (the
normal `make check` after bootstrap.sh installs PoCL) the OpenCL tests; in
CI's fallback run (OCL_ICD_VENDORS pointing at an empty folder,
WM_EXPECT_OPENCL=0) or a --disable-opencl build, the tests that DEVICE=AUTO
quietly takes the C path and DEVICE=OPENCL fails cleanly.
"""

import contextlib
import os

import pytest

import oracle
from conftest import OPENCL_EXPECTED

from osgeo import gdal



def opencl_only(test):
    """Defines the test only where an OpenCL device is expected (not a
    skip: the other environment runs the fallback tests instead)."""
    return test if OPENCL_EXPECTED else None


def fallback_only(test):
    return None if OPENCL_EXPECTED else test


def with_(options, **kw):
    o = dict(options)
    o.update(kw)
    return o


@contextlib.contextmanager
def config(**kw):
    """Sets GDAL config options for the block, restoring them after."""
    old = {k: gdal.GetConfigOption(k) for k in kw}
    for k, v in kw.items():
        gdal.SetConfigOption(k, v)
    try:
        yield
    finally:
        for k, v in old.items():
            gdal.SetConfigOption(k, v)


def debug_lines(cap):
    return [m for c, _, m in cap.records if c == gdal.CE_Debug and 'DEVICE=' in m]


def kernel_dir(tmp_path, text):
    d = tmp_path / 'kernels'
    d.mkdir()
    (d / 'field.cl').write_text(text)
    return str(d)


BROKEN_KERNEL = '__kernel void wm_field_tiles(__global float *v) { v[0] = nonsense; }\n'
WRONG_ARGS_KERNEL = '__kernel void wm_field_tiles(__global float *v) { v[0] = 1.0f; }\n'


def test_driver_reports_opencl_build(wm):
    item = gdal.GetDriverByName('WATERMESH').GetMetadataItem('WATERMESH_OPENCL')
    assert item in ('YES', 'NO')
    if OPENCL_EXPECTED:
        assert item == 'YES'


def test_device_cpu_logs_choice(wm, simple_options):
    with config(CPL_DEBUG='ON'):
        res = wm.run(with_(simple_options, DEVICE='CPU'))
    assert any('DEVICE=CPU: the C path' in m for m in debug_lines(res.cap)), res.cap.text


# --------------------------------------------------------------------------
# with an OpenCL device
# --------------------------------------------------------------------------

def test_auto_takes_c_path(wm, simple_options):
    """AUTO without a named device is the C path on every machine (faster
    than OpenCL on all measured, a GPU host included: docs/opencl.md)."""
    with config(CPL_DEBUG='ON'):
        res = wm.run(with_(simple_options, DEVICE='AUTO'))
    assert any('DEVICE=AUTO: the C path' in m for m in debug_lines(res.cap)), res.cap.text
    assert res.signature() == wm.run(with_(simple_options, DEVICE='CPU')).signature()


def icd_stems():
    """The OpenCL implementations the ICD loader would load ("libpocl.so")."""
    import glob
    where = os.environ.get('OCL_ICD_VENDORS', '/etc/OpenCL/vendors')
    files = glob.glob(os.path.join(where, '*.icd')) if os.path.isdir(where) else [where]
    stems = []
    for f in files:
        with open(f) as fp:
            lib = os.path.basename(fp.read().strip())
        stems.append(lib.split('.so')[0] + '.so')
    return stems


def loaded_libraries(wm, options, device, tmp_dir):
    """Basenames of the shared objects a CLI run with DEVICE=device loads."""
    out = os.path.join(tmp_dir, 'libs_%s.gpkg' % device)
    env = dict(os.environ, LD_DEBUG='libs')
    import subprocess
    p = subprocess.run([wm.CLI_PATH] + wm.cli_args(with_(options, DEVICE=device)) + ['-q', out],
                       env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    return {os.path.basename(line.split('calling init:')[1].strip())
            for line in p.stderr.splitlines() if 'calling init:' in line}


@opencl_only
def test_auto_loads_no_opencl_implementation(wm, simple_options, tmp_dir):
    """AUTO costs nothing for OpenCL: no implementation (ICD) is loaded,
    while OPENCL loads one."""
    stems = icd_stems()
    assert stems, 'no OpenCL ICD registered'
    def icds(libs):
        return sorted(l for l in libs for st in stems if l.startswith(st))
    assert icds(loaded_libraries(wm, simple_options, 'OPENCL', tmp_dir))
    assert not icds(loaded_libraries(wm, simple_options, 'AUTO', tmp_dir))


@opencl_only
def test_device_opencl_matches_cpu(wm, simple_options, opencl_exact):
    """The double kernel (a device with doubles, PoCL among them) gives the
    C path's output byte for byte; the float one the same features."""
    with config(CPL_DEBUG='ON'):
        cl = wm.run(with_(simple_options, DEVICE='OPENCL'))
    assert any('DEVICE=OPENCL: OpenCL: ' in m for m in debug_lines(cl.cap)), cl.cap.text
    cpu = wm.run(with_(simple_options, DEVICE='CPU'))
    if opencl_exact:
        assert cl.signature() == cpu.signature()
    assert len(cl.water) == len(cpu.water) and len(cl.mesh) == len(cpu.mesh)
    a, b = oracle.total_area(cl.water), oracle.total_area(cpu.water)
    assert abs(a - b) <= 1e-4 * b, (a, b)
    problems = oracle.check_water(cl.water, 512)
    assert not problems, problems[:5]


@opencl_only
def test_device_opencl_threads_identical(wm, simple_options):
    ref = wm.run(with_(simple_options, DEVICE='OPENCL', NUM_THREADS=1)).signature()
    for n in (2, 3):
        got = wm.run(with_(simple_options, DEVICE='OPENCL', NUM_THREADS=n)).signature()
        assert got == ref, 'DEVICE=OPENCL NUM_THREADS=%d differs from 1 thread' % n


def device_word(wm, options):
    """The first word of the device DEVICE=OPENCL takes (e.g. "pthread"):
    a WATERMESH_OPENCL_DEVICE value naming it."""
    with config(CPL_DEBUG='ON'):
        ds, cap = wm.open(with_(options, DEVICE='OPENCL'))
    ds = None
    name = [m for m in debug_lines(cap) if 'OpenCL: ' in m][0].split('OpenCL: ')[1]
    return name.split()[0].split('-')[0]


@opencl_only
def test_auto_with_named_device_uses_it(wm, simple_options):
    ref = wm.run(with_(simple_options, DEVICE='OPENCL'))
    with config(CPL_DEBUG='ON', WATERMESH_OPENCL_DEVICE=device_word(wm, simple_options)):
        res = wm.run(with_(simple_options, DEVICE='AUTO'))
    assert any('DEVICE=AUTO: OpenCL: ' in m for m in debug_lines(res.cap)), res.cap.text
    assert res.signature() == ref.signature()


@opencl_only
def test_named_device_missing(wm, simple_options):
    with config(WATERMESH_OPENCL_DEVICE='no-such-device-anywhere'):
        ds, cap = wm.open(with_(simple_options, DEVICE='OPENCL'))
        assert ds is None
        assert 'no OpenCL device matches "no-such-device-anywhere"' in cap.text, cap.text
        with config(CPL_DEBUG='ON'):
            res = wm.run(with_(simple_options, DEVICE='AUTO'))
    assert any('the C path' in m and 'no-such-device-anywhere' in m
               for m in debug_lines(res.cap)), res.cap.text


@opencl_only
def test_kernel_build_failure(wm, simple_options, tmp_path):
    """A kernel that does not compile: OPENCL fails with the compiler's log,
    AUTO (with a named device) falls back to the C path."""
    d = kernel_dir(tmp_path, BROKEN_KERNEL)
    word = device_word(wm, simple_options)
    with config(WATERMESH_KERNEL_DIR=d):
        ds, cap = wm.open(with_(simple_options, DEVICE='OPENCL'))
        assert ds is None
        assert 'building the field kernel' in cap.text and 'nonsense' in cap.text, cap.text
        with config(CPL_DEBUG='ON', WATERMESH_OPENCL_DEVICE=word):
            res = wm.run(with_(simple_options, DEVICE='AUTO'))
    lines = debug_lines(res.cap)
    assert any('the C path' in m and 'building the field kernel' in m for m in lines), lines
    assert res.signature() == wm.run(with_(simple_options, DEVICE='CPU')).signature()


@opencl_only
def test_device_failing_during_run(wm, simple_options, tmp_path):
    """A kernel that builds but cannot be launched (wrong arguments): under
    OPENCL the run fails naming the OpenCL call; under AUTO one warning, and
    the C path computes everything, so the output equals DEVICE=CPU's."""
    d = kernel_dir(tmp_path, WRONG_ARGS_KERNEL)
    word = device_word(wm, simple_options)
    with config(WATERMESH_KERNEL_DIR=d):
        ds, cap = wm.open(with_(simple_options, DEVICE='OPENCL'))
        assert ds is not None, cap.text
        with wm.ErrorCapture() as cap2:
            lyr = ds.GetLayerByName('water')
            n = sum(1 for _ in lyr)
        ds = None
        assert n == 0 and 'clSetKernelArg' in cap2.text, (n, cap2.text)
        with config(WATERMESH_OPENCL_DEVICE=word):
            res = wm.run(with_(simple_options, DEVICE='AUTO'))
    warn = [m for m in res.cap.warnings if 'the OpenCL device failed' in m]
    assert len(warn) == 1 and 'clSetKernelArg' in warn[0], res.cap.text
    assert res.signature() == wm.run(with_(simple_options, DEVICE='CPU')).signature()


@opencl_only
def test_raster_view_opencl(wm, simple_options):
    """The raster view on the OpenCL path equals the C path's to 1e-4 px."""
    import numpy
    vals = {}
    for dev in ('CPU', 'OPENCL'):
        ds, cap = wm.open(with_(simple_options, DEVICE=dev), flags=gdal.OF_RASTER)
        assert ds is not None, cap.text
        vals[dev] = ds.GetRasterBand(1).ReadAsArray().astype(numpy.float64)
        ds = None
    px = float(simple_options.get('PIXEL_SIZE', 0.5))
    worst = numpy.abs(vals['CPU'] - vals['OPENCL']).max() / px
    assert worst <= 1e-4, worst


@opencl_only
def test_cli_device_opencl_stats(wm, simple_options, tmp_dir):
    out = os.path.join(tmp_dir, 'cl.gpkg')
    p = wm.cli(wm.cli_args(with_(simple_options, DEVICE='OPENCL')) + ['-stats', '-q', out])
    assert p.returncode == 0, p.stderr
    assert 'device OpenCL: ' in p.stdout, p.stdout


# --------------------------------------------------------------------------
# without one: the fallback
# --------------------------------------------------------------------------

@fallback_only
def test_auto_falls_back_quietly(wm, simple_options):
    """AUTO with a named device that cannot be had: the C path, with the
    reason in a debug line and no error or warning."""
    with config(CPL_DEBUG='ON', WATERMESH_OPENCL_DEVICE='gpu'):
        res = wm.run(with_(simple_options, DEVICE='AUTO'))
    assert not res.cap.errors and not res.cap.warnings, res.cap.text
    lines = debug_lines(res.cap)
    assert any('DEVICE=AUTO: the C path' in m for m in lines), res.cap.text
    assert any(k in ' '.join(lines) for k in ('CL_PLATFORM_NOT_FOUND_KHR (-1001)',
                                                'CL_DEVICE_NOT_FOUND (-1)',
                                                'this build has no OpenCL')), lines
    assert res.signature() == wm.run(with_(simple_options, DEVICE='CPU')).signature()


@fallback_only
def test_device_opencl_refused(wm, simple_options):
    """The refusal gives the real reason: the build, or the OpenCL error."""
    ds, cap = wm.open(with_(simple_options, DEVICE='OPENCL'))
    assert ds is None
    assert 'DEVICE=OPENCL' in cap.text, cap.text
    built = gdal.GetDriverByName('WATERMESH').GetMetadataItem('WATERMESH_OPENCL') == 'YES'
    if built:
        assert 'CL_PLATFORM_NOT_FOUND_KHR (-1001)' in cap.text or \
            'CL_DEVICE_NOT_FOUND (-1)' in cap.text, cap.text
    else:
        assert 'this build has no OpenCL' in cap.text, cap.text


@fallback_only
def test_cli_device_opencl_fails_cleanly(wm, simple_options, tmp_dir):
    out = os.path.join(tmp_dir, 'cl.gpkg')
    p = wm.cli(wm.cli_args(with_(simple_options, DEVICE='OPENCL')) + ['-q', out])
    assert p.returncode != 0
    assert 'DEVICE=OPENCL' in p.stderr, p.stderr
    assert not os.path.exists(out)
    assert not [f for f in os.listdir(tmp_dir) if f.startswith('.gdal_watermesh')]
