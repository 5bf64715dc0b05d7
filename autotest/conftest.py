"""pytest configuration and shared helpers of the watermesh autotest.

The build directory is $WATERMESH_BUILD (default: the repository root, the
parent of this folder). GDAL loads the plugin from <build>/plugins
(gdal_WATERMESH.so); the CLI is <build>/gdal_watermesh.

A missing WATERMESH driver is a hard error (the session stops with exit
status 3). The only escape hatch: WATERMESH_COLLECT_ONLY=1 together with
`pytest --collect-only`, to check that the suite imports and collects.

Tests reach the helpers through the `wm` fixture (see WM below); scene
files come from the session fixtures `simple_scene`, `random_scene`, ...
"""

import os
import subprocess
import sys
import types

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
BUILD_DIR = os.path.abspath(os.environ.get('WATERMESH_BUILD', os.path.dirname(HERE)))
PLUGIN_DIR = os.path.join(BUILD_DIR, 'plugins')
CLI_PATH = os.path.join(BUILD_DIR, 'gdal_watermesh')
DATA_DIR = os.path.join(os.path.dirname(HERE), 'data', 'osm')
REPORT_PATH = os.environ.get('WATERMESH_ORACLE_REPORT', os.path.join(HERE, 'oracle_report.txt'))

# must happen before osgeo.gdal is imported
os.environ['GDAL_DRIVER_PATH'] = PLUGIN_DIR

from osgeo import gdal, ogr, osr  # noqa: E402

gdal.AllRegister()

if HERE not in sys.path:
    sys.path.insert(0, HERE)

import oracle  # noqa: E402
import scenes  # noqa: E402

DRIVER_NAME = 'WATERMESH'
COLLECT_ONLY_ENV = 'WATERMESH_COLLECT_ONLY'


def _opencl_expected():
    """Whether this environment must offer a working OpenCL device:
    WM_EXPECT_OPENCL=1/0 when set (CI's fallback run sets 0 together with an
    empty OCL_ICD_VENDORS folder), else whether the plugin was built with
    OpenCL (the driver's WATERMESH_OPENCL metadata item)."""
    env = os.environ.get('WM_EXPECT_OPENCL')
    if env is not None:
        return env == '1'
    drv = gdal.GetDriverByName(DRIVER_NAME)
    return drv is not None and drv.GetMetadataItem('WATERMESH_OPENCL') == 'YES'


# tests that need an OpenCL device are generated only when one is expected;
# without one, test_opencl.py checks the fallback instead (nothing skips)
OPENCL_EXPECTED = _opencl_expected()


def pytest_sessionstart(session):
    if gdal.GetDriverByName(DRIVER_NAME) is not None:
        return
    collect_only = session.config.getoption('collectonly', False)
    if os.environ.get(COLLECT_ONLY_ENV) == '1' and collect_only:
        return
    so = os.path.join(PLUGIN_DIR, 'gdal_WATERMESH.so')
    msg = ('GDAL driver %s not found: GDAL_DRIVER_PATH=%s (%s). Build the plugin or set '
           'WATERMESH_BUILD. (%s=1 only allows --collect-only.)'
           % (DRIVER_NAME, PLUGIN_DIR,
              'gdal_WATERMESH.so exists but did not register - check GDAL\'s error output'
              if os.path.exists(so) else 'no gdal_WATERMESH.so there', COLLECT_ONLY_ENV))
    pytest.exit(msg, returncode=3)


# ----------------------------------------------------------------------------
# error capture
# ----------------------------------------------------------------------------

class ErrorCapture:
    """Context manager collecting the GDAL errors/warnings raised in this
    thread: .records is a list of (class, number, message); .errors,
    .warnings, .text for convenience."""

    def __init__(self):
        self.records = []

    def _handler(self, err_class, err_no, msg):
        self.records.append((err_class, err_no, msg))

    def __enter__(self):
        gdal.ErrorReset()
        gdal.PushErrorHandler(self._handler)
        return self

    def __exit__(self, *exc):
        gdal.PopErrorHandler()
        return False

    @property
    def errors(self):
        return [m for c, _, m in self.records if c in (gdal.CE_Failure, gdal.CE_Fatal)]

    @property
    def warnings(self):
        return [m for c, _, m in self.records if c == gdal.CE_Warning]

    @property
    def text(self):
        return '\n'.join(m for _, _, m in self.records)


# ----------------------------------------------------------------------------
# opening and reading the driver
# ----------------------------------------------------------------------------

def open_options(options):
    """{'WIDTH': 12, ...} -> ['WIDTH=12', ...] (None values dropped)."""
    return ['%s=%s' % (k.upper(), v) for k, v in (options or {}).items() if v is not None]


def open_watermesh(options=None, path='WATERMESH:', flags=gdal.OF_VECTOR, any_driver=False):
    """gdal.OpenEx with the WATERMESH driver (any_driver: let GDAL pick the
    driver). Returns (ds, ErrorCapture); ds is None on failure."""
    with ErrorCapture() as cap:
        kwargs = {} if any_driver else {'allowed_drivers': [DRIVER_NAME]}
        ds = gdal.OpenEx(path, flags, open_options=open_options(options), **kwargs)
    if ds is None and not cap.text:
        cap.records.append((gdal.CE_Failure, 0, gdal.GetLastErrorMsg()))
    return ds, cap


def feat_from_ogr(f):
    """ogr.Feature -> oracle.Feat (block from block_x/block_y)."""
    from shapely import wkb as swkb
    fields = {}
    defn = f.GetDefnRef()
    for i in range(defn.GetFieldCount()):
        name = defn.GetFieldDefn(i).GetName()
        fields[name] = f.GetField(i) if f.IsFieldSetAndNotNull(i) else None
    g = f.GetGeometryRef()
    wkb = bytes(g.ExportToIsoWkb()) if g is not None else b''
    geom = swkb.loads(wkb) if g is not None and not g.IsEmpty() else None
    block = (fields.get('block_x'), fields.get('block_y'))
    return oracle.Feat(block, geom, wkb, fields)


def read_layer(lyr, spat=None):
    """All features of an OGR layer as oracle.Feat, in reading order."""
    assert lyr is not None
    if spat is not None:
        lyr.SetSpatialFilterRect(*spat)
    lyr.ResetReading()
    out = []
    f = lyr.GetNextFeature()
    while f is not None:
        out.append(feat_from_ogr(f))
        f = lyr.GetNextFeature()
    return out


class RunResult:
    """Output of one vector run: .water, .mesh (lists of oracle.Feat),
    .cap (ErrorCapture of open + reading), .srs (water layer SRS)."""

    def __init__(self, water, mesh, cap, srs):
        self.water, self.mesh, self.cap, self.srs = water, mesh, cap, srs

    def signature(self):
        return signature(self.water), signature(self.mesh)


def signature(feats):
    """Order-sensitive, comparable form of features: (fields, WKB) tuples."""
    return [(tuple(sorted(f.fields.items())), f.wkb) for f in feats]


def run_vector(options, path='WATERMESH:', spat=None, layers=('water', 'mesh'), any_driver=False):
    """Opens in vector mode, reads the layers (optionally with a spatial
    filter rectangle) and returns a RunResult. Asserts the open worked,
    with GDAL's message in the assertion."""
    ds, cap = open_watermesh(options, path, any_driver=any_driver)
    assert ds is not None, 'open failed (%s %s): %s' % (path, options, cap.text)
    out = {}
    with ErrorCapture() as cap2:
        for name in layers:
            lyr = ds.GetLayerByName(name)
            assert lyr is not None, 'no layer %s' % name
            out[name] = read_layer(lyr, spat)
        srs = ds.GetLayerByName('water').GetSpatialRef()
        srs = srs.Clone() if srs is not None else None
    cap.records.extend(cap2.records)
    ds = None
    return RunResult(out.get('water', []), out.get('mesh', []), cap, srs)


# ----------------------------------------------------------------------------
# the CLI
# ----------------------------------------------------------------------------

CLI_OPTION_NAMES = ('rivers', 'rivers_layer', 'rivers_where', 'lakes', 'lakes_layer',
                    'lakes_where', 'width', 'width_field', 'width_by_class', 'pixel_size',
                    'block_size',
                    'simplify', 'method', 'heuristic', 'merge_distance', 'device',
                    'num_threads', 'target_srs', 'min_feature_area', 'mesh_geometry')


def cli_args(options):
    """Open options {'RIVERS': ..., ...} -> gdal_watermesh arguments."""
    args = []
    for k, v in (options or {}).items():
        if v is None:
            continue
        name = k.lower()
        assert name in CLI_OPTION_NAMES, name
        args += ['-' + name, str(v)]
    return args


def run_cli(args, timeout=300, cwd=None):
    """Runs gdal_watermesh with `args` (list of str); returns the
    CompletedProcess (text mode, stdout and stderr captured)."""
    assert os.path.exists(CLI_PATH), 'CLI not built: %s' % CLI_PATH
    return subprocess.run([CLI_PATH] + [str(a) for a in args], env=dict(os.environ),
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=timeout, cwd=cwd)


def read_output(path, layers=('water', 'mesh')):
    """Reads layers of a CLI output datasource as {name: [Feat]}."""
    ds = gdal.OpenEx(path, gdal.OF_VECTOR)
    assert ds is not None, 'cannot open CLI output %s' % path
    return {name: read_layer(ds.GetLayerByName(name)) for name in layers}


# ----------------------------------------------------------------------------
# fixtures
# ----------------------------------------------------------------------------

WM = types.SimpleNamespace(
    gdal=gdal, ogr=ogr, osr=osr, oracle=oracle, scenes=scenes,
    BUILD_DIR=BUILD_DIR, PLUGIN_DIR=PLUGIN_DIR, CLI_PATH=CLI_PATH, DATA_DIR=DATA_DIR,
    DRIVER_NAME=DRIVER_NAME, OPENCL_EXPECTED=OPENCL_EXPECTED,
    ErrorCapture=ErrorCapture, open=open_watermesh, open_options=open_options,
    run=run_vector, read_layer=read_layer, signature=signature,
    cli=run_cli, cli_args=cli_args, read_output=read_output,
)


@pytest.fixture(scope='session')
def wm():
    """Helper namespace: wm.open, wm.run, wm.cli, wm.cli_args, wm.signature,
    wm.read_output, wm.ErrorCapture, wm.oracle, wm.scenes, paths."""
    return WM


@pytest.fixture(scope='session')
def scene_dir(tmp_path_factory):
    return str(tmp_path_factory.mktemp('scenes'))


@pytest.fixture(scope='session')
def simple_scene(scene_dir):
    """Path of the hand-made scene (layers rivers, lakes, rivers2, ponds)."""
    return scenes.make_simple_scene(os.path.join(scene_dir, 'simple.gpkg'))


@pytest.fixture(scope='session')
def simple_options(simple_scene):
    """Open options for the simple scene (small blocks, fast)."""
    return {'RIVERS': simple_scene, 'RIVERS_LAYER': 'rivers',
            'LAKES': simple_scene, 'LAKES_LAYER': 'lakes',
            'PIXEL_SIZE': 1, 'BLOCK_SIZE': 512}


@pytest.fixture(scope='session')
def opencl_exact(simple_options):
    """Whether DEVICE=OPENCL runs the double-precision kernel here (the
    device has doubles: its values, and so the output, are the C path's
    bit for bit), as the driver's debug line names the device; False where
    no OpenCL device is expected."""
    if not OPENCL_EXPECTED:
        return False
    old = gdal.GetConfigOption('CPL_DEBUG')
    gdal.SetConfigOption('CPL_DEBUG', 'ON')
    try:
        ds, cap = open_watermesh(dict(simple_options, DEVICE='OPENCL'))
        ds = None
    finally:
        gdal.SetConfigOption('CPL_DEBUG', old)
    lines = [m for c, _, m in cap.records if c == gdal.CE_Debug and 'DEVICE=OPENCL' in m]
    assert lines, cap.text
    return 'double precision' in lines[0]


@pytest.fixture(scope='session')
def random_scene(scene_dir):
    """Factory: random_scene(seed, **kwargs) -> GeoPackage path (cached)."""
    cache = {}

    def make(seed, **kwargs):
        key = (seed, tuple(sorted(kwargs.items())))
        if key not in cache:
            name = 'random_%d_%d.gpkg' % (seed, len(cache))
            cache[key] = scenes.make_random_scene(os.path.join(scene_dir, name), seed, **kwargs)
        return cache[key]
    return make


@pytest.fixture
def tmp_dir(tmp_path):
    return str(tmp_path)


# ----------------------------------------------------------------------------
# oracle report
# ----------------------------------------------------------------------------

def pytest_terminal_summary(terminalreporter, exitstatus, config):
    if not oracle.REPORT:
        return
    lines = ['watermesh oracle figures (GDAL %s, shapely %s)'
             % (gdal.__version__, __import__('shapely').__version__)]
    for name, figures in oracle.REPORT:
        lines.append('%s: %s' % (name, oracle.format_figures(figures)))
    terminalreporter.section('watermesh oracle report')
    for line in lines:
        terminalreporter.write_line(line)
    try:
        with open(REPORT_PATH, 'w', encoding='utf-8') as f:
            f.write('\n'.join(lines) + '\n')
        terminalreporter.write_line('(written to %s)' % REPORT_PATH)
    except OSError as e:  # pragma: no cover
        terminalreporter.write_line('could not write %s: %s' % (REPORT_PATH, e))
