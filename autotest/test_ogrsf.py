"""GDAL's own OGR conformance program, test_ogrsf (built by `make check` from
Debian's gdal source package, see bootstrap.sh), on both layers: through a
descriptor file, a connection string with open options, each mesh form, and
its full-feature-set mode (-fsf). Read-only (-ro): the driver writes
nothing."""

import os
import subprocess

import pytest

from conftest import BUILD_DIR, DATA_DIR, PLUGIN_DIR

TEST_OGRSF = os.path.join(BUILD_DIR, 'tools', 'test_ogrsf', 'test_ogrsf')
LI = os.path.join(DATA_DIR, 'osm_liechtenstein_2013.gpkg')


def run_test_ogrsf(args):
    assert os.access(TEST_OGRSF, os.X_OK), \
        '%s is not built (make check builds it after ./bootstrap.sh)' % TEST_OGRSF
    env = dict(os.environ, GDAL_DRIVER_PATH=PLUGIN_DIR)
    p = subprocess.run([TEST_OGRSF, '-ro'] + args, env=env, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, universal_newlines=True, timeout=600)
    lines = p.stdout.splitlines()
    errors = [l for l in lines if l.startswith('ERROR') or 'FAILURE' in l]
    assert p.returncode == 0 and not errors, p.stdout[-3000:]
    infos = [l for l in lines if l.startswith('INFO:')]
    # the per-layer checks ran on both layers (each layer gives one of these)
    assert sum('Random read test passed' in l for l in infos) == 2, p.stdout[-3000:]
    return infos


def test_descriptor(tmp_path):
    d = tmp_path / 'li.watermesh'
    d.write_text('<WaterMesh><RIVERS>%s</RIVERS><LAKES>%s</LAKES>'
                 '<WIDTH_FIELD>width</WIDTH_FIELD></WaterMesh>\n' % (LI, LI))
    infos = run_test_ogrsf([str(d)])
    assert any('TestVirtualIO successful' in l for l in infos)


def test_descriptor_full_feature_set(tmp_path):
    d = tmp_path / 'li.watermesh'
    d.write_text('<WaterMesh><RIVERS>%s</RIVERS><LAKES>%s</LAKES></WaterMesh>\n' % (LI, LI))
    run_test_ogrsf(['-fsf', str(d)])


@pytest.mark.parametrize('form', ['MULTIPOLYGON', 'TIN', 'TRIANGLES'])
def test_connection_string(form):
    run_test_ogrsf(['WATERMESH:', '-oo', 'RIVERS=' + LI, '-oo', 'LAKES=' + LI,
                    '-oo', 'MESH_GEOMETRY=' + form])


@pytest.mark.parametrize('form', ['MULTIPOLYGON', 'TIN', 'TRIANGLES'])
def test_draped_and_refined(tmp_path, form):
    """The Z layers of ELEVATION, refined (MIN_ANGLE, MAX_EDGE), pass too."""
    dem = str(tmp_path / 'dem.tif')
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    subprocess.run(['/usr/bin/python3', os.path.join(repo, 'tools', 'make_dem.py'), dem,
                    '32632', '535000', '5201000', '548500', '5239000', '30'], check=True)
    run_test_ogrsf(['WATERMESH:', '-oo', 'RIVERS=' + LI, '-oo', 'LAKES=' + LI,
                    '-oo', 'WIDTH_FIELD=width', '-oo', 'ELEVATION=' + dem,
                    '-oo', 'MIN_ANGLE=20', '-oo', 'MAX_EDGE=50',
                    '-oo', 'MESH_GEOMETRY=' + form])
