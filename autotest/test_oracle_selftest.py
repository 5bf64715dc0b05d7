"""Self-test of oracle.py and scenes.py (no driver output involved): the
checks pass on the oracle itself and catch injected defects, so a passing
driver test means something."""

import random

import numpy as np
import pytest
from shapely.geometry import LineString, Point, Polygon, box

import oracle
import scenes

B = 512
PX = 0.5


@pytest.fixture(scope='module')
def oracle_scene(tmp_path_factory):
    path = scenes.make_random_scene(str(tmp_path_factory.mktemp('selftest') / 'scene.gpkg'), 7,
                                    extent=1200.0, n_tributaries=4, n_lakes=2)
    opts = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'LAKES': path, 'LAKES_LAYER': 'lakes',
            'WIDTH_FIELD': 'width'}
    blocks = oracle.oracle_blocks(oracle.inputs_from_options(opts), B)
    water = oracle.as_feats(blocks)
    mesh = []
    for f in water:
        m = oracle.reference_mesh(f.geom)
        mesh.append(oracle.Feat(f.block, m, bytes(m.wkb),
                                {'block_x': f.block[0], 'block_y': f.block[1], 'triangles': len(m.geoms)}))
    return blocks, water, mesh


def test_scene_is_deterministic(tmp_path):
    a = scenes.random_scene_features(5)
    b = scenes.random_scene_features(5)
    c = scenes.random_scene_features(6)
    assert a == b and a != c


def test_scene_properties(tmp_path):
    path = scenes.make_random_scene(str(tmp_path / 's.gpkg'), 3)
    inputs = oracle.load_inputs(rivers=path, rivers_layer='rivers', lakes=path, lakes_layer='lakes',
                                width_field='width')
    widths = [w for _, w in inputs.rivers]
    assert all(2 <= w <= 60 for w in widths), widths
    assert len(inputs.rivers) >= 4
    # tributaries start at a vertex of another river
    verts = [set(l.coords) for l, _ in inputs.rivers]
    for i, (l, _) in enumerate(inputs.rivers[1:], 1):
        assert any(l.coords[0] in verts[j] for j in range(len(verts)) if j != i)
    # lakes with islands, a river passing through a lake
    assert any(len(p.interiors) for p in inputs.lakes)
    main = inputs.rivers[0][0]
    assert any(main.intersects(p) for p in inputs.lakes)
    assert inputs.srs.GetAuthorityCode(None) == str(scenes.SCENE_EPSG)


def test_parse_width():
    assert oracle.parse_width('3') == 3.0
    assert oracle.parse_width('2.5 m') == 2.5
    assert oracle.parse_width(' 7') == 7.0
    assert oracle.parse_width(4) == 4.0
    for bad in (None, '', 'wide', '-3', '0', 0, -1.0, 'nan', float('nan'), float('inf')):
        assert oracle.parse_width(bad) is None, bad


def test_oracle_checks_pass_on_oracle(oracle_scene):
    blocks, water, mesh = oracle_scene
    assert len(blocks) >= 4
    assert oracle.check_water(water, B) == []
    problems, stats = oracle.check_mesh(mesh, water, B)
    assert problems == [], problems[:5]
    assert oracle.check_seams(water, B)[:2] == (0, 0)
    assert oracle.check_seams(mesh, B)[:2] == (0, 0)
    c = oracle.compare(water, blocks, B, PX)
    assert c['hausdorff'] < 1e-6 and abs(c['rel_area_diff']) < 1e-12, c


def test_hausdorff_measures_offset(oracle_scene):
    blocks, water, _ = oracle_scene
    grown = oracle.clip_to_blocks(oracle.water_union(blocks).buffer(0.3, 64), B)
    c = oracle.compare(oracle.as_feats(grown), blocks, B, PX)
    # every grown boundary point is 0.3 m from the original boundary (up to
    # the sampling step); the other way can be more (dry wedges fill in)
    assert 0.3 - PX / 20 <= c['driver_to_oracle'] <= 0.3 + 1e-6, c
    assert c['hausdorff'] >= c['driver_to_oracle']
    assert c['rel_area_diff'] > 0


def test_hausdorff_catches_missing_island(oracle_scene):
    blocks, water, _ = oracle_scene
    # fill every hole: the island's boundary is then far from the output
    filled = {b: oracle.fill_holes(g) for b, g in blocks.items()}
    if all(oracle.fill_holes(g).equals(g) for g in blocks.values()):
        pytest.skip('scene without holes')  # pragma: no cover
    c = oracle.compare(oracle.as_feats(filled), blocks, B, PX)
    assert c['hausdorff'] > 1.0, c


def test_nearest_distances_exact():
    rng = random.Random(1)
    segs = np.array([[rng.uniform(0, 100), rng.uniform(0, 100), rng.uniform(0, 100), rng.uniform(0, 100)]
                     for _ in range(50)])
    pts = np.array([[rng.uniform(-50, 150), rng.uniform(-50, 150)] for _ in range(500)])
    got = oracle.nearest_distances(pts, segs, cell=2.0)
    lines = [LineString([(s[0], s[1]), (s[2], s[3])]) for s in segs]
    want = np.array([min(l.distance(Point(p)) for l in lines) for p in pts])
    assert np.allclose(got, want, rtol=0, atol=1e-9)


def _shared_edge_feature(water):
    """A water feature with a ring segment on its block's right edge."""
    for i, f in enumerate(water):
        x = (f.block[0] + 1) * B
        c = np.asarray(f.geom.exterior.coords)
        for k in range(len(c) - 1):
            if c[k, 0] == x and c[k + 1, 0] == x and abs(c[k, 1] - c[k + 1, 1]) > 1:
                return i, k
    pytest.skip('no water on a right block edge')  # pragma: no cover


def _replace(water, i, geom):
    f = water[i]
    fields = dict(f.fields, area=oracle.geom_area(geom))
    return water[:i] + [oracle.Feat(f.block, geom, bytes(geom.wkb), fields)] + water[i + 1:]


def test_seams_catch_t_junction(oracle_scene):
    _, water, _ = oracle_scene
    i, k = _shared_edge_feature(water)
    c = list(water[i].geom.exterior.coords)
    mid = ((c[k][0] + c[k + 1][0]) / 2, (c[k][1] + c[k + 1][1]) / 2)
    g = Polygon(c[:k + 1] + [mid] + c[k + 1:], [r.coords for r in water[i].geom.interiors])
    assert g.is_valid
    tj, gaps, _ = oracle.check_seams(_replace(water, i, g), B)
    assert tj == 1 and gaps == 0


def test_seams_catch_gap(oracle_scene):
    _, water, _ = oracle_scene
    i, k = _shared_edge_feature(water)
    f = water[i]
    x = (f.block[0] + 1) * B
    c = f.geom.exterior.coords
    y0, y1 = sorted((c[k][1], c[k + 1][1]))
    g = f.geom.difference(box(x - 0.2, y0 + 0.25 * (y1 - y0), x, y0 + 0.5 * (y1 - y0)))
    tj, gaps, _ = oracle.check_seams(_replace(water, i, g), B)
    assert gaps >= 1


def test_seams_skip_uncomputed_neighbours(oracle_scene):
    _, water, _ = oracle_scene
    blocks = {f.block for f in water}
    one = sorted(blocks)[0]
    only = [f for f in water if f.block == one]
    assert oracle.check_seams(only, B, computed_blocks={one})[:2] == (0, 0)
    tj, gaps, _ = oracle.check_seams(only, B, computed_blocks=None)
    assert gaps > 0  # its water reaches an edge whose neighbour is now empty


def test_mesh_catches_overlap_and_hole(oracle_scene):
    _, water, mesh = oracle_scene
    j = max(range(len(mesh)), key=lambda k: len(mesh[k].geom.geoms))
    tris = list(mesh[j].geom.geoms)
    m = mesh[j]

    def variant(ts):
        mp = oracle.MultiPolygon(ts)
        return mesh[:j] + [oracle.Feat(m.block, mp, b'', dict(m.fields, triangles=len(ts)))] + mesh[j + 1:]
    problems, _ = oracle.check_mesh(variant(tris + [tris[0]]), water, B)
    assert any('overlap' in p or 'area' in p for p in problems), problems
    problems, _ = oracle.check_mesh(variant(tris[1:]), water, B)
    assert any('area' in p for p in problems), problems
    problems, _ = oracle.check_mesh(variant(tris)[:j] + variant(tris)[j + 1:], water, B)
    assert any('0 mesh features' in p for p in problems), problems


def test_check_water_catches_invalid_and_wrong_area():
    bow = Polygon([(0, 0), (10, 10), (10, 0), (0, 10)])
    f = oracle.Feat((0, 0), bow, bytes(bow.wkb), {'area': 0.0})
    problems = oracle.check_water([f], B)
    assert any('invalid' in p for p in problems)
    sq = box(1, 1, 3, 3)
    f = oracle.Feat((0, 0), sq, bytes(sq.wkb), {'area': 5.0})
    assert any('area field' in p for p in oracle.check_water([f], B))
    f = oracle.Feat((1, 0), sq, bytes(sq.wkb), {'area': 4.0})
    assert any('outside block' in p for p in oracle.check_water([f], B))
