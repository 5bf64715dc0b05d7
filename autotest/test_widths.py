"""River widths as OpenStreetMap gives them: the forms of the width tag,
a key of an hstore field (WIDTH_FIELD=other_tags:width), widths by class
(WIDTH_BY_CLASS) and the count of each source in -stats."""

import math
import os
import re

import pytest
from osgeo import ogr

import scenes

LENGTH = 200.0
# (width text, waterway class, width expected): one straight river each
CASES = [
    ('12', 'river', 12.0),
    ('2.5 m', 'river', 2.5),
    ('~5', 'river', 5.0),
    ('5-8', 'canal', 6.5),
    ('3;4', 'river', 4.0),
    ('1,5', 'stream', 1.5),
    ('8 ft', 'river', 8 * 0.3048),
    ('3 metres', 'river', 3.0),
    ('wide', 'river', 10.0),     # unparsable: the river class, 10
    (None, 'stream', 2.0),       # no width: the stream class, 2
    (None, 'ditch', 3.0),        # a class not in the table: *, 3
    ('0', 'canal', 8.0),         # not positive: the canal class, 8
    ('10-20 ft', 'river', 15 * 0.3048),   # a range's unit serves both ends
    ('3;4 ft', 'river', 4 * 0.3048),      # a list's last unit serves all
    ('2 m;3', 'river', 3.0),
    ('-5', 'canal', 8.0),        # negative: the canal class
]
CLASSES = 'waterway:river=10,canal=8,stream=2,*=3'


def hstore(pairs):
    return ','.join('"%s"=>"%s"' % (k, v.replace('"', '\\"')) for k, v in pairs if v is not None)


@pytest.fixture(scope='module')
def osm_like(tmp_path_factory):
    """Rivers 200 m long, 60 m apart, with a text `width`, OSM's
    `other_tags` hstore (width among other keys) and `waterway`."""
    path = str(tmp_path_factory.mktemp('widths') / 'osm_like.gpkg')
    x0, y0 = scenes.SCENE_ORIGIN
    feats = []
    for i, (text, cls, _) in enumerate(CASES):
        y = y0 + 60.0 * i
        feats.append({'geom': 'LINESTRING (%r %r, %r %r)' % (x0, y, x0 + LENGTH, y),
                      'width': text, 'waterway': cls,
                      'other_tags': hstore([('name', 'r "%d"' % i), ('width', text),
                                            ('source', 'x=>y'), ('kind', cls)])})
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, scenes.SCENE_EPSG, feats,
                       fields=[('width', 'String'), ('waterway', 'String'),
                               ('other_tags', 'String')])
    return path


def widths(res):
    """Each river's width from its polygon's area (a capsule: L w + pi w^2 / 4),
    by the polygon's y, in the order of CASES."""
    out = []
    for f in sorted(res.water, key=lambda f: f.geom.centroid.y):
        a = f.geom.area
        out.append((-LENGTH + math.sqrt(LENGTH ** 2 + math.pi * a)) / (math.pi / 2))
    return out


@pytest.mark.parametrize('field', ['width', 'other_tags:width'])
def test_osm_width_forms_and_classes(wm, osm_like, field):
    res = wm.run({'RIVERS': osm_like, 'WIDTH_FIELD': field, 'WIDTH_BY_CLASS': CLASSES})
    got = widths(res)
    assert len(got) == len(CASES), got
    for (text, cls, want), w in zip(CASES, got):
        assert abs(w - want) <= 0.1, (text, cls, want, w)
    warn = [m for m in res.cap.warnings if 'WIDTH_BY_CLASS' in m]
    assert len(warn) == 1 and '5 feature(s)' in warn[0], res.cap.text


def test_classes_from_an_hstore_key(wm, osm_like, tmp_path):
    """WIDTH_BY_CLASS's field may be an hstore key too; without '*' an
    unknown class takes WIDTH."""
    want = [8.0 if cls == 'canal' else 4.0 for _, cls, _ in CASES]
    for spec in ('other_tags:kind:canal=8', 'waterway:CANAL=8'):
        res = wm.run({'RIVERS': osm_like, 'WIDTH_BY_CLASS': spec, 'WIDTH': '4'})
        assert all(abs(w - v) <= 0.1 for w, v in zip(widths(res), want)), (spec, widths(res))


def test_stats_count_width_sources(wm, osm_like, tmp_dir):
    out = os.path.join(tmp_dir, 'w.gpkg')
    p = wm.cli(['-rivers', osm_like, '-width_field', 'other_tags:width',
                '-width_by_class', CLASSES, '-stats', '-q', out])
    assert p.returncode == 0, p.stderr
    m = re.search(r'^river widths: (\d+) from WIDTH_FIELD, (\d+) from WIDTH_BY_CLASS, '
                  r'(\d+) WIDTH$', p.stdout, re.M)
    assert m and [int(x) for x in m.groups()] == [11, 5, 0], p.stdout


def test_class_names_trimmed(wm, osm_like):
    res = wm.run({'RIVERS': osm_like, 'WIDTH_BY_CLASS': 'waterway: canal = 8 , river=6', 'WIDTH': '4'})
    want = [8.0 if cls == 'canal' else 6.0 if cls == 'river' else 4.0 for _, cls, _ in CASES]
    assert all(abs(w - v) <= 0.1 for w, v in zip(widths(res), want)), widths(res)


def test_hstore_key_of_a_numeric_field_refused(wm, tmp_path):
    path = str(tmp_path / 'num.gpkg')
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, scenes.SCENE_EPSG,
                       [{'geom': 'LINESTRING (400000 4700000, 400100 4700000)', 'w': 3.0}],
                       fields=[('w', 'Real')])
    ds, cap = wm.open({'RIVERS': path, 'WIDTH_FIELD': 'w:width'})
    assert ds is None and 'text (hstore) field' in cap.text, cap.text


@pytest.mark.parametrize('spec', ['river=10', 'waterway:', 'waterway:river', 'waterway:river=0',
                                  'waterway:river=-2', 'waterway:river=10,stream',
                                  ':river=10', 'waterway:river=1e9'])
def test_width_by_class_refused(wm, osm_like, spec):
    ds, cap = wm.open({'RIVERS': osm_like, 'WIDTH_BY_CLASS': spec})
    assert ds is None and 'WIDTH_BY_CLASS' in cap.text and spec in cap.text, cap.text


def test_hstore_field_missing(wm, osm_like):
    ds, cap = wm.open({'RIVERS': osm_like, 'WIDTH_FIELD': 'tags:width'})
    assert ds is None and "no field 'tags:width'" in cap.text and 'hstore' in cap.text, cap.text
    ds, cap = wm.open({'RIVERS': osm_like, 'WIDTH_BY_CLASS': 'kind:river=3'})
    assert ds is None and "no field 'kind'" in cap.text, cap.text
