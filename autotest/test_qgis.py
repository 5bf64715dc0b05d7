"""The QGIS Processing provider (qgis/watermesh), headless: Debian's
qgis_process.bin (its qgis_process wrapper passes --noversioncheck, which
3.22 refuses) with the plugin enabled in a throw-away profile, and PyQGIS
for what qgis_process cannot pass (a memory layer with a selection). The
outputs must equal the CLI's, feature for feature."""

import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest
from osgeo import gdal, ogr

from conftest import BUILD_DIR, CLI_PATH, DATA_DIR

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
QGIS_PROCESS = '/usr/bin/qgis_process.bin'
ANDORRA = os.path.join(DATA_DIR, 'osm_andorra_2023.gpkg')


@pytest.fixture(scope='module')
def qgis_env(tmp_path_factory):
    assert os.access(QGIS_PROCESS, os.X_OK), \
        '%s missing: bootstrap.sh installs Debian\'s qgis and python3-qgis' % QGIS_PROCESS
    cfg = tmp_path_factory.mktemp('qgis_profile')
    ini = cfg / 'profiles' / 'default' / 'QGIS'
    ini.mkdir(parents=True)
    (ini / 'QGIS3.ini').write_text('[PythonPlugins]\nwatermesh=true\n')
    return dict(os.environ, QGIS_CUSTOM_CONFIG_PATH=str(cfg),
                QGIS_PLUGINPATH=os.path.join(REPO, 'qgis'), WATERMESH_CLI=CLI_PATH,
                QT_QPA_PLATFORM='offscreen')


def qgis_process(env, *args):
    return subprocess.run([QGIS_PROCESS] + list(args), env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, universal_newlines=True, timeout=600)


def features(path, layer=None):
    """Sorted (fields, WKB) of a layer: block_x, block_y, polygon and the
    geometry, which the CLI and the algorithm must agree on."""
    ds = gdal.OpenEx(path, gdal.OF_VECTOR)
    lyr = ds.GetLayerByName(layer) if layer else ds.GetLayer(0)
    out = sorted((f['block_x'], f['block_y'], f['polygon'], f.GetGeometryRef().ExportToWkb())
                 for f in lyr)
    ds = None
    return out


def cli(tmp, *extra):
    out = os.path.join(tmp, 'cli.gpkg')
    p = subprocess.run([CLI_PATH, '-q', '-overwrite', '-rivers', ANDORRA, '-rivers_layer',
                        'rivers', '-lakes', ANDORRA, '-lakes_layer', 'lakes'] + list(extra)
                       + [out], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True)
    assert p.returncode == 0, p.stderr
    return out


def test_provider_listed(qgis_env):
    p = qgis_process(qgis_env, 'list')
    assert p.returncode == 0, p.stderr
    assert 'watermesh:watermesh\tWater mesh from rivers and lakes' in p.stdout, p.stdout[-2000:]


@pytest.mark.parametrize('form', ['MULTIPOLYGON', 'TRIANGLES'])
def test_andorra_equals_cli(qgis_env, tmp_path, form):
    water, mesh = str(tmp_path / 'water.gpkg'), str(tmp_path / 'mesh.gpkg')
    p = qgis_process(qgis_env, 'run', 'watermesh:watermesh',
                     '--RIVERS=%s|layername=rivers' % ANDORRA,
                     '--LAKES=%s|layername=lakes' % ANDORRA,
                     '--MESH_GEOMETRY=%d' % ['MULTIPOLYGON', 'TIN', 'TRIANGLES'].index(form),
                     '--WATER=' + water, '--MESH=' + mesh)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    assert '100 - done.' in p.stdout and '-mesh_geometry %s' % form in p.stdout, p.stdout
    ref = cli(str(tmp_path), '-mesh_geometry', form)
    want_water, want_mesh = features(ref, 'water'), features(ref, 'mesh')
    assert len(want_water) > 300
    assert features(water) == want_water
    assert features(mesh) == want_mesh


def test_terrain_options_equal_cli(qgis_env, tmp_path):
    """The advanced parameters reach the command: an elevation raster (a
    synthetic one over Andorra), flow from the lines, a lake level
    percentile, MIN_ANGLE and MAX_EDGE give the CLI's draped, refined
    output, Z included."""
    dem = str(tmp_path / 'dem.tif')
    subprocess.run([sys.executable, os.path.join(REPO, 'tools', 'make_dem.py'), dem, '32631',
                    '368000', '4689000', '402000', '4723500', '50'], check=True)
    water, mesh = str(tmp_path / 'water.gpkg'), str(tmp_path / 'mesh.gpkg')
    p = qgis_process(qgis_env, 'run', 'watermesh:watermesh',
                     '--RIVERS=%s|layername=rivers' % ANDORRA,
                     '--LAKES=%s|layername=lakes' % ANDORRA,
                     '--ELEVATION=' + dem, '--FLOW=1', '--LAKE_LEVEL_PERCENTILE=25',
                     '--MIN_ANGLE=20', '--MAX_EDGE=60',
                     '--WATER=' + water, '--MESH=' + mesh)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    for flag in ('-elevation ' + dem, '-flow LINE_DIRECTION', '-lake_level_percentile 25.0',
                 '-min_angle 20.0', '-max_edge 60.0'):
        assert flag in p.stdout, (flag, p.stdout[-2000:])
    ref = cli(str(tmp_path), '-elevation', dem, '-flow', 'LINE_DIRECTION',
              '-lake_level_percentile', '25', '-min_angle', '20', '-max_edge', '60')
    want_water, want_mesh = features(ref, 'water'), features(ref, 'mesh')
    for got, layer in ((water, 'water'), (mesh, 'mesh')):
        ds, ds_ref = ogr.Open(got), ogr.Open(ref)
        kind = ds.GetLayer(0).GetGeomType()
        assert ogr.GT_HasZ(kind) and kind == ds_ref.GetLayerByName(layer).GetGeomType()
        ds = ds_ref = None
    assert features(water) == want_water
    assert features(mesh) == want_mesh


def test_failure_reported(qgis_env, tmp_path):
    p = qgis_process(qgis_env, 'run', 'watermesh:watermesh',
                     '--RIVERS=%s|layername=rivers' % ANDORRA, '--WIDTH_BY_CLASS=nonsense',
                     '--WATER=' + str(tmp_path / 'w.gpkg'), '--MESH=' + str(tmp_path / 'm.gpkg'))
    text = p.stdout + p.stderr
    assert p.returncode != 0 and 'WIDTH_BY_CLASS=nonsense' in text, text[-2000:]


# what both PyQGIS scripts start with: QGIS, Processing and the provider
# (argv: plugin folder, input, water output, mesh output)
PYQGIS_PREAMBLE = r'''
import os, sys, time
from qgis.core import (QgsApplication, QgsFeatureRequest, QgsProcessingContext,
                       QgsProcessingException, QgsProcessingFeatureSourceDefinition,
                       QgsProcessingFeedback, QgsProject, QgsVectorLayer)
app = QgsApplication([], False)
app.initQgis()
sys.path.insert(0, '/usr/share/qgis/python/plugins')
sys.path.insert(0, sys.argv[1])
from processing.core.Processing import Processing
import processing
Processing.initialize()
from watermesh.provider import WatermeshProvider
provider = WatermeshProvider()  # kept: the registry does not own it
QgsApplication.processingRegistry().addProvider(provider)
'''


def run_pyqgis(qgis_env, tmp_path, body):
    """Runs PYQGIS_PREAMBLE + body on Andorra; (process, water, mesh)."""
    script = tmp_path / 'script.py'
    script.write_text(PYQGIS_PREAMBLE + body)
    water, mesh = str(tmp_path / 'water.gpkg'), str(tmp_path / 'mesh.gpkg')
    p = subprocess.run([sys.executable, str(script), os.path.join(REPO, 'qgis'), ANDORRA,
                        water, mesh], env=qgis_env, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, universal_newlines=True, timeout=600)
    return p, water, mesh


PYQGIS_SELECTION = r'''
src = QgsVectorLayer(sys.argv[2] + '|layername=rivers', 'rivers', 'ogr')
mem = src.materialize(QgsFeatureRequest())
QgsProject.instance().addMapLayer(mem)
mem.selectByExpression('"waterway" = \'river\' OR "tunnel" IS NOT NULL')
print('SELECTED', mem.selectedFeatureCount(), mem.featureCount())
res = processing.run('watermesh:watermesh', {
    'RIVERS': QgsProcessingFeatureSourceDefinition(mem.id(), selectedFeaturesOnly=True),
    'WATER': sys.argv[3], 'MESH': sys.argv[4]})
print('RESULT', res['WATER'], res['MESH'])
QgsProject.instance().clear()
QgsApplication.processingRegistry().removeProvider(provider)
sys.stdout.flush()
os._exit(0)  # PyQGIS 3.22 may crash in exitQgis after processing; nothing left to do
'''


def test_memory_layer_selection(qgis_env, tmp_path):
    """A memory layer's selection reaches the command (exported to a
    temporary GeoPackage): the result equals the CLI's on a file holding
    just the selected rivers."""
    p, water, mesh = run_pyqgis(qgis_env, tmp_path, PYQGIS_SELECTION)
    assert p.returncode == 0 and 'RESULT' in p.stdout, p.stdout[-2000:] + p.stderr[-2000:]
    n, total = [int(x) for x in p.stdout.split('SELECTED ')[1].split()[:2]]
    assert 0 < n < total
    # the same rivers, by OGR, into a file of their own
    sel = str(tmp_path / 'sel.gpkg')
    gdal.VectorTranslate(sel, ANDORRA, layers=['rivers'],
                         where="waterway = 'river' OR tunnel IS NOT NULL")
    ds = gdal.OpenEx(sel)
    assert ds.GetLayer(0).GetFeatureCount() == n
    ds = None
    out = str(tmp_path / 'cli.gpkg')
    r = subprocess.run([CLI_PATH, '-q', '-rivers', sel, out], stderr=subprocess.PIPE,
                       universal_newlines=True)
    assert r.returncode == 0, r.stderr
    assert features(water) == features(out, 'water')


PYQGIS_CANCEL = r'''
alg = QgsApplication.processingRegistry().createAlgorithmById('watermesh:watermesh')

class Feedback(QgsProcessingFeedback):
    """Cancels at the first progress the command reports."""
    def __init__(self):
        super().__init__()
        self.progressChanged.connect(lambda p: p > 0 and self.cancel())

params = {'RIVERS': sys.argv[2] + '|layername=rivers', 'LAKES': sys.argv[2] + '|layername=lakes',
          'PIXEL_SIZE': 0.25, 'NUM_THREADS': 1, 'WATER': sys.argv[3], 'MESH': sys.argv[4]}
t0 = time.time()
try:
    alg.run(params, QgsProcessingContext(), Feedback(), {}, False)
    print('NOT CANCELLED')
except QgsProcessingException as e:
    print('EXCEPTION', e)
res, ok = alg.run(params, QgsProcessingContext(), Feedback())
print('OK', ok, 'SECONDS %.2f' % (time.time() - t0))
sys.stdout.flush()
os._exit(0)
'''


def test_cancel_stops_the_command(qgis_env, tmp_path):
    """Cancelling through the feedback stops gdal_watermesh at once (a run
    of several seconds ends within one) and writes no output."""
    p, water, mesh = run_pyqgis(qgis_env, tmp_path, PYQGIS_CANCEL)
    out = p.stdout
    assert p.returncode == 0 and 'OK False' in out, out[-2000:] + p.stderr[-2000:]
    assert float(out.split('SECONDS ')[1].split()[0]) < 2.0, out
    assert not os.path.exists(water) and not os.path.exists(mesh)


def test_defaults_are_the_drivers():
    """The algorithm's defaults and choices are the driver's (its XML)."""
    sys.path.insert(0, os.path.join(REPO, 'qgis'))
    from watermesh import algorithm
    drv = gdal.GetDriverByName('WATERMESH')
    xml = {o.get('name'): o for o in
           ET.fromstring(drv.GetMetadataItem(gdal.DMD_OPENOPTIONLIST)).findall('Option')}
    for name, (_, default, top, _) in algorithm.NUMBERS.items():
        assert float(xml[name].get('default')) == default, name
        assert (float(xml[name].get('max')) if xml[name].get('max') else None) == top, name
    for name, values in (('METHOD', algorithm.METHODS), ('DEVICE', algorithm.DEVICES),
                         ('MESH_GEOMETRY', algorithm.MESH_FORMS),
                         ('HEURISTIC', algorithm.HEURISTICS), ('FLOW', algorithm.FLOWS)):
        assert [v.text for v in xml[name].findall('Value')] == values, name
        assert xml[name].get('default') == values[0], name
