"""MIN_FEATURE_AREA: land holes and water parts of a block smaller than the
option's area, touching no block side, are dropped; everything else is
untouched, and seams stay exact.

The scene (PIXEL_SIZE 0.5 m, BLOCK_SIZE 64 m): a 40 m x 30 m lake with a
2 m x 2 m island (4 m2) and a 10 m x 8 m island (80 m2); a 3 m x 3 m pond
(9 m2) on its own; a 4 m x 3 m pond (12 m2) astride the block side x = 64 m,
whose two pieces (6 m2 each) touch that side and so are kept.
"""

import os

import pytest
from shapely.geometry import Polygon

import oracle
import scenes

PIXEL_SIZE = 0.5
BLOCK_SIZE = 64
X0, Y0 = 400000.0, 4700000.0  # a multiple of BLOCK_SIZE: block sides at +64 m


def _square(x0, y0, x1, y1, cw=False):
    pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    if cw:
        pts = pts[::-1]
    return '(' + ','.join('%.3f %.3f' % (X0 + x, Y0 + y) for x, y in pts) + ')'


@pytest.fixture(scope='module')
def options(scene_dir):
    path = os.path.join(scene_dir, 'min_feature_area.gpkg')
    if not os.path.exists(path):
        lakes = [
            {'geom': 'POLYGON (' + _square(5, 5, 45, 35) + ',' +
                     _square(10.25, 10.25, 12.25, 12.25, cw=True) + ',' +
                     _square(25.25, 15.25, 35.25, 23.25, cw=True) + ')',
             'name': 'lake'},
            {'geom': 'POLYGON (' + _square(20.25, 45.25, 23.25, 48.25) + ')',
             'name': 'pond'},
            {'geom': 'POLYGON (' + _square(62.25, 45.25, 65.75, 48.25) + ')',
             'name': 'astride'},
        ]
        scenes.write_layer(path, 'lakes', scenes.ogr.wkbPolygon, scenes.SCENE_EPSG,
                           lakes)
    return {'LAKES': path, 'PIXEL_SIZE': PIXEL_SIZE, 'BLOCK_SIZE': BLOCK_SIZE,
            'SIMPLIFY': 0, 'NUM_THREADS': 1}


def _rings(feats):
    """(area m2, is_hole) of every ring of the water features."""
    out = []
    for f in feats:
        for poly in oracle.polygons_of(f.geom):
            out.append((Polygon(poly.exterior).area, False))
            for h in poly.interiors:
                out.append((Polygon(h).area, True))
    return out


def _near(rings, area, hole, rel=0.1):
    return [a for a, h in rings if h == hole and abs(a - area) <= rel * area]


def test_default_keeps_every_feature(wm, options):
    r = _rings(wm.run(options).water)
    assert _near(r, 4.0, True), r    # small island
    assert _near(r, 80.0, True), r   # large island
    assert _near(r, 9.0, False), r   # small pond
    assert len(_near(r, 5.25, False)) == 2, r  # the pond astride, two pieces


@pytest.mark.parametrize('area', [20, 50])
def test_small_features_dropped(wm, options, area):
    base = wm.run(options)
    run = wm.run(dict(options, MIN_FEATURE_AREA=area))
    r = _rings(run.water)
    assert not _near(r, 4.0, True), r
    assert not _near(r, 9.0, False), r
    assert _near(r, 80.0, True), r
    # astride a block side: pieces of 5.25 m2 each, kept in both blocks
    assert len(_near(r, 5.25, False)) == 2, r
    # the water grew by the island and lost the pond, nothing else
    grown = oracle.total_area(run.water) - oracle.total_area(base.water)
    assert abs(grown - (4.0 - 9.0)) < 0.5, grown
    assert not oracle.check_water(run.water, BLOCK_SIZE)
    assert oracle.check_seams(run.water, BLOCK_SIZE)[:2] == (0, 0)
    assert oracle.check_seams(run.mesh, BLOCK_SIZE)[:2] == (0, 0)
    problems, _ = oracle.check_mesh(run.mesh, run.water, BLOCK_SIZE)
    assert not problems, problems[:5]


def test_cli_option(wm, options, tmp_dir):
    dst = os.path.join(tmp_dir, 'out.gpkg')
    p = wm.cli(['-q'] + wm.cli_args(dict(options, MIN_FEATURE_AREA=20)) + [dst])
    assert p.returncode == 0, p.stderr
    r = _rings(wm.read_output(dst)['water'])
    assert not _near(r, 9.0, False) and _near(r, 80.0, True), r
