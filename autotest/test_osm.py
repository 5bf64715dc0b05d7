"""From a raw OpenStreetMap .osm.pbf to a mesh in one command, with the
bundled preset data/osm/osm.watermesh: both bundled extracts, widths from
other_tags and by waterway class, the same inputs as the GeoPackage
extracts made from them."""

import os
import re

import pytest

from conftest import DATA_DIR

PRESET = os.path.join(DATA_DIR, 'osm.watermesh')


def preset(name):
    import xml.etree.ElementTree as ET
    return ET.parse(PRESET).getroot().find(name).text


def river_classes(pbf, where=None):
    """What GDAL's OSM driver reads of the PBF's rivers under the preset's
    RIVERS_WHERE (or `where`): (with a width tag, canals without one, the
    others without one)."""
    from osgeo import gdal
    ds = gdal.OpenEx(os.path.join(DATA_DIR, pbf), gdal.OF_VECTOR)
    lines = ds.GetLayerByName('lines')
    assert lines.SetAttributeFilter(where or preset('RIVERS_WHERE')) == 0
    tagged = canals = others = 0
    for f in lines:
        if '"width"=>' in (f['other_tags'] or ''):
            tagged += 1
        elif f['waterway'] == 'canal':
            canals += 1
        else:
            others += 1
    return tagged, canals, others


def run_preset(wm, pbf, tmp_dir, *extra):
    path = os.path.join(DATA_DIR, pbf)
    out = os.path.join(tmp_dir, 'osm.gpkg')
    p = wm.cli(['-rivers', path, '-lakes', path, '-stats', '-q', '-overwrite'] + list(extra)
               + [PRESET, out])
    assert p.returncode == 0, p.stderr
    num = lambda pat: [int(x) for x in re.search(pat, p.stdout, re.M).groups()]
    return {'widths': num(r'^river widths: (\d+) from WIDTH_FIELD, (\d+) from '
                          r'WIDTH_BY_CLASS, (\d+) WIDTH$'),
            'inputs': num(r'\(2 \* (\d+) river \+ (\d+) lake vertices\)'),
            'out': num(r'^polygons (\d+), output vertices (\d+), triangles (\d+)$'),
            'path': out}


@pytest.mark.parametrize('pbf', ['andorra-20230713.osm.pbf', 'liechtenstein-2013-08-03.osm.pbf'])
def test_pbf_preset(wm, tmp_dir, pbf):
    """Every river tagged with a width takes it (all of them parse), every
    other its class's; tunnels and culverts are left out."""
    tagged, canals, others = river_classes(pbf)
    r = run_preset(wm, pbf, tmp_dir)
    assert r['widths'] == [tagged, canals + others, 0] and canals + others > 0, r
    assert 'tunnel' in preset('RIVERS_WHERE')
    with_tunnels = sum(river_classes(pbf, preset('RIVERS_WHERE').split(' AND ')[0]))
    assert with_tunnels > tagged + canals + others
    assert r['out'][0] > 0 and r['out'][2] > 0, r
    res = wm.read_output(r['path'])
    assert len(res['water']) == r['out'][0] and len(res['mesh']) == r['out'][0]


def test_pbf_inputs_are_the_extracts(wm, tmp_dir):
    """With the extracts' own river classes the PBF gives exactly the
    Andorra GeoPackage's input vertices (38,388 river, 11,223 lake)."""
    r = run_preset(wm, 'andorra-20230713.osm.pbf', tmp_dir,
                   '-rivers_where', "waterway IN ('river','stream','canal')")
    assert r['inputs'] == [38388, 11223], r


def test_preset_flags_override(wm, tmp_dir):
    """A flag overrides the preset: -width_by_class with canals alone, so
    the canals without a width tag take 8 m and the other untagged rivers
    WIDTH (counted from the PBF with GDAL's OSM driver)."""
    pbf = 'liechtenstein-2013-08-03.osm.pbf'
    tagged, canals, untagged = river_classes(pbf)
    r = run_preset(wm, pbf, tmp_dir, '-width_by_class', 'waterway:canal=8')
    assert r['widths'] == [tagged, canals, untagged] and canals and untagged, r
