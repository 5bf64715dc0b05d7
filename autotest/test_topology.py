"""Driver output on the adversarial sub-pixel scenes of adversarial.py
(issue 12: acute confluences, near-parallel rivers, tiny islands, sub-pixel
streams and lakes, all of them also across block sides), against the GEOS
oracle.

Asserted here, on every scene, for SIMPLIFY=0 and the default SIMPLIFY
(1 and 2 threads; also DEVICE=OPENCL with SIMPLIFY=0 where an OpenCL device
is expected, see conftest.OPENCL_EXPECTED), what the product holds today:
  - no GDAL error; every water polygon valid (oracle.check_water);
  - the mesh covers each water polygon exactly, without overlaps
    (oracle.check_mesh, relative 1e-9), one mesh feature per polygon;
  - zero T-junctions and zero gaps on shared block sides, water and mesh
    (oracle.check_seams);
  - identical features, in the same order, for NUM_THREADS 1 and 2;
  - OpenCL: the same number of features as the C path, area within 1e-4;
  - SIMPLIFY=0, scenes with more than 100 m² of oracle water:
    |area - oracle area| <= 0.5 % of the oracle area + the exact union's
    land narrower than 2 px (adversarial.narrow_land_area). Before the
    sub-pixel search sampling filled such land (up to 7 %); the flat 0.5 %
    alone fails on a few scenes of strips along a block side.
The default SIMPLIFY's area is only recorded: Douglas-Peucker at T = 1 px on
lakes of 6-20 m radius loses up to 9 % of their area.

Asserted for issue 12 (sub-pixel topology, docs/architecture.md 4a):
  - no specks (output rings whose vertices all lie within half a pixel of
    each other where the exact union has no such ring), SIMPLIFY=0 and the
    default, every family;
  - SIMPLIFY=0: no lake or island ring under 2 px lost;
  - SIMPLIFY=0: boundary Hausdorff <= 0.5 px on every scene (measured
    0.48 px at worst here, 0.50 px on 6,000 held-out scenes, seeds
    94000-94999, and 0.48 px on 21,000 more at seven other scales, with
    nothing lost; bench/topology.py).
Recorded (printed with pytest -s and in autotest/oracle_report.txt): the
Hausdorff distance and its 99th percentile (px), the ring count difference
and the symmetric difference, per scene (adversarial.measure);
bench/topology.py prints the same figures per family over many seeds.
"""

import os

import pytest
from shapely.geometry import LineString, Point, Polygon

import adversarial
import oracle
from conftest import OPENCL_EXPECTED

PIXEL_SIZE = adversarial.PIXEL_SIZE   # 0.5 m
BLOCK_SIZE = adversarial.BLOCK_SIZE   # 64 m
AREA_REL = 0.005                      # 0.5 % ...
AREA_MIN_M2 = 100.0                   # ... for scenes with more water than this
NARROW_PX = 2.0                       # + land narrower than this (see the docstring)
MESH_REL = 1e-9
OPENCL_AREA_REL = 1e-4

# seeds per family: 40 (440 scenes, ~2.5 min on 2 cores); WM_TOPOLOGY_SEEDS=N runs
# N per family by hand (bench/topology.py prints the figures per family)
SEEDS = range(int(os.environ.get('WM_TOPOLOGY_SEEDS', '40')))
# held-out scenes that failed once (bench/topology.py): seeds 94000-94999,
# a corner on a sample column seeded in one cell only (shore, 0.64 px), two
# islands of three river banks 0.013 px wide dropped as rounding remnants;
# at PIXEL_SIZE 1, BLOCK_SIZE 128 ("@pixel:block"), a wedge's tip 0.4
# lattice unit off a block side lost with its corner (0.58 px); seeds
# 99000-99299, a lake's island lost where its edge crossed a dividing
# segment at a lattice point, classed by the ray rule on the edge (6.5 px);
# at 2:256 (seeds 101000-101499) two wedge tips skipped by the corner
# recovery because their cell's interpolated edge ran within a quarter pixel
# while the contour had taken exact crossings there (0.62 px), the hairpin's
# one then also out of reach of its 4 nearest edges, the far banks of both
# arms (0.64 px); at 0.25:32 (seeds 100000-100499) a lake 0.18 px wide
# touching a sample row at its vertex, lost where a dividing segment ended
# there (4 px); a spike along an edge two lake pieces share (mosaic seed
# 116135, 1.01 px); at 0.25:32 the thin tip of one of four lake pieces
# meeting at a point taken for land, two specks 5 m inside the lake (mosaic
# seed 119073, 20 px); at 2:256 the land of a block touching its side
# along another block's lake edge a hole a unit off the side (grid seed
# 118104, a speck); at 1:128 a water speck at a block corner two lakes
# touch along one edge, the block dry (grid seed 126145); the oracle's
# GEOS buffer of a river that loops over its first segment again filled
# the loop (twins seed 126099, 22 px against a right output); a land
# triangle of the exact union 1.7 x 0.7 lattice units, below the lattice,
# counted as lost (mosaic seed 131073, 2.7 px: adversarial.resolvable now
# excuses such features from being kept); at 0.3:48 a river bank on a
# block line but for the rounding of the inputs (0.3 m is no binary
# fraction): its samples on the line 1e-13 px inside the water, the block
# across kept a strip one unit thick and 34 m long (grid seed 136003; seed
# 136125 the other way, GEOS's strip 1e-9 m thick); a river's tip 0.3
# units wide beside a block corner, 1.7 units long, kept as the exact union
# has it, though below the lattice (seam seed 136414: ring_diff counts
# only rings outside what the exact union and its resolvable part have);
# at 0.9:115.2 the notch between the round caps of two rivers ending side
# by side, its tip 0.54 px off: the corner recovery refused the tip because
# a point of the new triangle's median lay 0.01 px inside a cap that
# bulges across the chord (seam seed 146366; crease.c's class_near); at
# 3:384 four lake pieces pointing their tips at one point 0.5 px apart: the
# other pieces' rings took the corner recovery's eight nearest edges for
# one tip, cut 0.52 px short (mosaic seed 175119; crease.c's RINGS).
# (The seam
# scenes at other block sizes lie on real seams since the family's origin
# is a corner of that block grid.)
REGRESSIONS = ['shore-94103', 'island-94499', 'island-94036', 'seam-98214@1:128',
               'island-99111', 'wedge-101159@2:256', 'seam-101080@2:256',
               'subpixel-100273@0.25:32', 'mosaic-116135', 'mosaic-119073@0.25:32',
               'grid-118104@2:256', 'grid-126145@1:128', 'twins-126099',
               'mosaic-131073', 'grid-136003@0.3:48', 'grid-136125@0.3:48',
               'seam-136414', 'seam-146366@0.9:115.2', 'mosaic-175119@3:384']
SCENE_IDS = ['%s-%d' % (f, s) for f in adversarial.FAMILIES for s in SEEDS] + REGRESSIONS

RUNS = {  # name: extra open options (METHOD=CONTOUR is the default)
    'exact': {'SIMPLIFY': 0, 'NUM_THREADS': 1},
    'exact_t2': {'SIMPLIFY': 0, 'NUM_THREADS': 2},
    'default': {'NUM_THREADS': 1},
    'default_t2': {'NUM_THREADS': 2},
}
THREAD_PAIRS = [('exact', 'exact_t2'), ('default', 'default_t2')]
if OPENCL_EXPECTED:
    RUNS['exact_cl'] = {'SIMPLIFY': 0, 'NUM_THREADS': 1, 'DEVICE': 'OPENCL'}
ALL_RUNS = sorted(RUNS)
MEASURED_RUNS = ['exact', 'default']


class Scene:
    """One adversarial scene: options, oracle clipped to blocks, driver runs
    and cached figures."""

    def __init__(self, wm, sid, scene_dir):
        self.wm, self.id = wm, sid
        name, _, scale = sid.partition('@')
        self.px, self.B = (float(v) for v in scale.split(':')) if scale else \
            (PIXEL_SIZE, BLOCK_SIZE)
        self.family, seed = name.rsplit('-', 1)
        self.seed = int(seed)
        path = os.path.join(scene_dir, 'adv_%s_%d.gpkg' % (self.family, self.seed))
        self.options = adversarial.make_scene(path, self.family, self.seed, self.px, self.B)
        self.meta = adversarial.scene_features(self.family, self.seed, self.px, self.B)[2]
        self.describe = adversarial.describe(self.family, self.seed, self.px, self.B)
        self.water = oracle.water(oracle.inputs_from_options(self.options))
        self.oracle = oracle.clip_to_blocks(self.water, self.B)
        assert self.oracle, 'scene %s has no water' % sid
        self.runs, self._cache = {}, {}

    def run(self, name):
        if name not in self.runs:
            self.runs[name] = self.wm.run(dict(self.options, **RUNS[name]))
        return self.runs[name]

    def cached(self, key, fn):
        if key not in self._cache:
            self._cache[key] = fn()
        return self._cache[key]

    def narrow_land(self):
        return self.cached('narrow', lambda: adversarial.narrow_land_area(
            self.water, self.px, NARROW_PX))

    def measure(self, name):
        def f():
            fig, _ = adversarial.measure(self.run(name).water, self.oracle, self.B, self.px)
            oracle.record('%s %s topology' % (self.id, name),
                          hausdorff_px=fig['hausdorff_px'], p99_px=fig['p99_px'],
                          specks_outer=fig['specks_outer'], specks_hole=fig['specks_hole'],
                          lost_outer=fig['lost_outer'], lost_hole=fig['lost_hole'],
                          ring_diff=fig['ring_diff'], rel_area_diff=fig['rel_area_diff'],
                          symdiff_m2=fig['symdiff_m2'], oracle_area_m2=fig['oracle_area_m2'],
                          narrow_land_m2=self.narrow_land(), worst_at=fig['worst_at'],
                          polygons=len(self.run(name).water))
            return fig
        return self.cached(('measure', name), f)


@pytest.fixture(scope='module', params=SCENE_IDS)
def scene(request, wm, scene_dir):
    return Scene(wm, request.param, scene_dir)


def test_generator_deterministic():
    for fam in adversarial.FAMILIES:
        a = adversarial.scene_features(fam, 3)
        assert a == adversarial.scene_features(fam, 3)
        assert a[:2] != adversarial.scene_features(fam, 4)[:2]
    with pytest.raises(ValueError):
        adversarial.scene_features('nonesuch', 0)


def test_generator_feature(scene):
    """The oracle has the feature the scene is built around, at its anchor."""
    m, w = scene.meta, scene.water
    px, B = scene.px, scene.B
    a = Point(m['anchor'])
    sub = m['sub_family']
    unit = px / adversarial.LATTICE_Q
    assert all(abs(c / unit - round(c / unit)) < 1e-6
               for line, _ in oracle.inputs_from_options(scene.options).rivers
               for c in (line.coords[0][0], line.coords[0][1])), 'vertices off the lattice'
    if sub == 'wedge' or (sub == 'parallel' and m['converge']):
        # the tip of the land wedge / strip is on the exact boundary, up to
        # the snapping to the lattice (a gap change of <= sqrt(2) unit moves
        # the tip by that / the rate at which the land widens)
        d = w.boundary.distance(a)
        assert d <= 0.1 * px + 2.0 * unit / m['tip_slope'], (d, scene.describe)
        if sub == 'wedge':
            assert 1.0 - 1e-9 <= m['angle_deg'] <= 30.0 + 1e-9
    elif sub == 'parallel':
        assert not w.contains(a), 'the strip centre is water: %s' % scene.describe
        assert 0.01 <= m['gap_px'] <= 3.0
        if m['closed']:
            holes = [Polygon(r) for p in oracle.polygons_of(w) for r in p.interiors]
            assert any(h.contains(a) for h in holes), 'closed strip is no hole: %s' % scene.describe
    elif sub == 'island':
        holes = [Polygon(r) for p in oracle.polygons_of(w) for r in p.interiors]
        near = [h for h in holes if h.distance(a) <= 1.5 * px]
        assert near and min(max(h.bounds[2] - h.bounds[0], h.bounds[3] - h.bounds[1])
                            for h in near) < 3.5 * px, scene.describe
    elif sub == 'shore':
        # the lake's edge or apex is on a sample, and on the exact boundary
        assert all(abs(c / px - round(c / px)) < 1e-9 for c in m['anchor']), scene.describe
        assert w.boundary.distance(a) <= 2.0 * unit, scene.describe
        assert 0.01 - 1e-9 <= m['gap_px'] <= 1.5 + 1e-9
    elif sub == 'grid':
        # the exact boundary runs along or meets a block line through the
        # anchor (a block corner), where a shore or bank lies on it
        lines = [LineString([(a.x, a.y - B), (a.x, a.y + B)]),
                 LineString([(a.x - B, a.y), (a.x + B, a.y)])]
        assert any(w.boundary.intersection(ln.buffer(2.0 * unit)).length > 0
                   for ln in lines), scene.describe
    elif sub == 'mosaic':
        # pieces of one lake around the anchor, joined along their shared
        # edges or a thin land strip apart
        assert m['pieces'] >= 2, scene.describe
        assert m['gap_px'] == 0 or 0.01 - 1e-9 <= m['gap_px'] <= 1.5 + 1e-9
        if m['gap_px'] == 0:
            assert w.distance(a) == 0, 'the lake centre is land: %s' % scene.describe
    elif sub == 'twins':
        # coinciding inputs: the exact union has water at the anchor but
        # inside the lap of a looping river
        assert m['kind'] in ('lake2', 'hole', 'river2', 'bank', 'loop'), scene.describe
        assert m['kind'] == 'loop' or w.distance(a) == 0, scene.describe
    elif sub == 'spike':
        # the lake's own spike, notch or channel, around its first lobe
        assert m['kind'] in ('spike', 'notch', 'neck'), scene.describe
        if m['kind'] == 'neck':
            assert 0.05 - 1e-9 <= m['width_px'] <= 1.5 + 1e-9
            assert w.distance(a) == 0, 'the lobe centre is land: %s' % scene.describe
        else:
            assert 0.3 - 1e-9 <= m['half_angle_deg'] <= 15.0 + 1e-9
    elif sub == 'cluster':
        # inputs scattered in a square of 1, 2 or 4 px around the anchor
        assert m['span_px'] in (1.0, 2.0, 4.0), scene.describe
        assert w.distance(a) <= m['span_px'] * px, 'no water near the cluster: %s' % scene.describe
    elif sub == 'shoal':
        # on a sample; thin islands in a lake near the anchor, a stack of
        # thin lakes apart from each other, or both
        assert all(abs(c / px - round(c / px)) < 1e-9 for c in m['anchor']), scene.describe
        near = [p for p in oracle.polygons_of(w) if p.distance(a) <= 4 * px]
        if m['kind'] != 'stack':
            assert any(p.interiors for p in near), 'no island: %s' % scene.describe
        if m['kind'] != 'islands':
            assert len(near) >= 2, 'the stack joined: %s' % scene.describe
    else:  # subpixel
        assert 0.1 - 1e-9 <= m['width_px'] <= 0.8 + 1e-9
        assert any(max(p.bounds[2] - p.bounds[0], p.bounds[3] - p.bounds[1]) <= 1.3 * px
                   for p in oracle.polygons_of(w)), 'no sub-pixel lake: %s' % scene.describe
    if scene.family == 'grid':
        assert m['anchor_in_block'] == (B, B), scene.describe
    elif 'seam' in m:  # the seam family, and some of the cluster family
        x, y = m['anchor_in_block']
        d = min(abs(x - B) if m['seam'] in ('x', 'corner') else B,
                abs(y - B) if m['seam'] in ('y', 'corner') else B)
        assert d <= max(0.4 * m['scale'], 0.5 * px) + 1e-9, scene.describe
    else:
        x, y = m['anchor_in_block']
        lo, hi = (v * B / BLOCK_SIZE for v in (12.0, 52.0))  # scaled scenes too
        assert lo <= x <= hi and lo <= y <= hi


@pytest.mark.parametrize('name', ALL_RUNS)
def test_valid_polygons(scene, name):
    res = scene.run(name)
    assert not res.cap.errors, '%s: GDAL errors: %s' % (scene.describe, res.cap.errors[:3])
    problems = oracle.check_water(res.water, scene.B)
    assert not problems, '%s: %d problems:\n%s' % (scene.describe, len(problems),
                                                   '\n'.join(problems[:10]))


@pytest.mark.parametrize('name', ALL_RUNS)
def test_mesh(scene, name):
    res = scene.run(name)
    problems, stats = oracle.check_mesh(res.mesh, res.water, scene.B, rel=MESH_REL)
    assert not problems, '%s: %d problems:\n%s' % (scene.describe, len(problems),
                                                   '\n'.join(problems[:10]))
    assert stats['mesh_features'] == len(res.water)


@pytest.mark.parametrize('name', ALL_RUNS)
@pytest.mark.parametrize('layer', ['water', 'mesh'])
def test_seams(scene, name, layer):
    res = scene.run(name)
    tj, gaps, details = oracle.check_seams(res.water if layer == 'water' else res.mesh, scene.B)
    assert tj == 0 and gaps == 0, '%s: %d T-junctions, %d gaps:\n%s' % (
        scene.describe, tj, gaps, '\n'.join(details[:10]))


@pytest.mark.parametrize('pair', THREAD_PAIRS, ids=lambda p: p[0])
def test_threads_identical(scene, pair):
    ref, got = (scene.run(n).signature() for n in pair)
    assert got == ref, '%s: %s differs from %s (%d/%d vs %d/%d features)' % (
        scene.describe, pair[1], pair[0], len(got[0]), len(got[1]), len(ref[0]), len(ref[1]))


if OPENCL_EXPECTED:
    def test_opencl_matches_c_path(scene, opencl_exact):
        """Identical with the double kernel (a device with doubles); the
        same features, area within OPENCL_AREA_REL, with the float one."""
        a, b = scene.run('exact'), scene.run('exact_cl')
        if opencl_exact:
            assert a.signature() == b.signature(), scene.describe
        assert len(a.water) == len(b.water) and len(a.mesh) == len(b.mesh), scene.describe
        ca, cb = oracle.total_area(a.water), oracle.total_area(b.water)
        assert abs(ca - cb) <= OPENCL_AREA_REL * ca, (scene.describe, ca, cb)


def test_area(scene):
    """SIMPLIFY=0: area within 0.5 % of the oracle's plus the exact land
    narrower than 2 px; only for scenes with more than 100 m² of water
    (sub-pixel scenes have a few m²)."""
    fig = scene.measure('exact')
    a, ao = fig['area_m2'], fig['oracle_area_m2']
    if ao <= AREA_MIN_M2:
        return
    allowed = AREA_REL * ao + scene.narrow_land()
    assert abs(a - ao) <= allowed, \
        '%s: area %.3f m2 vs oracle %.3f m2 (rel %.5f): |diff| %.3f > %.3f (0.5 %% + %.3f m2 of land under %g px)' % (
            scene.describe, a, ao, fig['rel_area_diff'], abs(a - ao), allowed, scene.narrow_land(), NARROW_PX)


@pytest.mark.parametrize('name', MEASURED_RUNS)
def test_no_specks(scene, name):
    """No speck: no output ring within half a pixel of itself where the
    exact union has no such ring (land or water), simplified or not."""
    fig = scene.measure(name)
    assert fig['invalid'] == 0, scene.describe
    assert fig['specks_outer'] == 0 and fig['specks_hole'] == 0, \
        '%s: specks %d water / %d land at %s' % (
            scene.describe, fig['specks_outer'], fig['specks_hole'], fig['speck_at'])


@pytest.mark.parametrize('scene', SCENE_IDS, indirect=True)
def test_small_features_kept(scene):
    """SIMPLIFY=0: every lake and island ring of the exact union smaller
    than 2 px is in the output: ponds and islands in lakes (seeded by their
    input), islands that three rivers enclose (seeded by their corners)."""
    fig = scene.measure('exact')
    assert fig['lost_outer'] == 0 and fig['lost_hole'] == 0, \
        '%s: lost %d water / %d land features at %s' % (
            scene.describe, fig['lost_outer'], fig['lost_hole'], fig['lost_at'])


HAUSDORFF_PX = 0.5


@pytest.mark.parametrize('scene', SCENE_IDS, indirect=True)
def test_hausdorff(scene):
    """SIMPLIFY=0: the boundary within half a pixel of the exact union's:
    wedges to their tip, strips between near-parallel rivers, islands and
    ponds, streams narrower than a pixel, and all of them across block
    sides (measured 0.48 px at worst on these scenes, 0.50 px on 6,000
    held-out ones, bench/topology.py)."""
    fig = scene.measure('exact')
    assert fig['hausdorff_px'] <= HAUSDORFF_PX, \
        '%s: Hausdorff %.3f px at %s' % (scene.describe, fig['hausdorff_px'], fig['worst_at'])
    # and no vertex off its own block's exact boundary (a spike along a side)
    assert fig['vertex_off_px'] <= HAUSDORFF_PX, \
        '%s: a vertex %.3f px off its block\'s exact boundary' % (
            scene.describe, fig['vertex_off_px'])


# Scenes whose rings the output must match one for one (per block and
# kind): an island whose neck, about a lattice unit wide, crosses a
# subdivision leaf (twins seeds 135011 and 135410 at 1:128), which reading
# the union's connectivity at points a quarter unit apart cut (the points
# miss a neck thinner than their spacing); and junctions of land strips 3
# units wide where a water wedge's tip lies in the leaf, which the leaf's
# pairing rule alone cut into an island (mosaic seeds 135325 at 0.5:64,
# 1.3 px, H 0.22 px, 137127 at 2:256, 136951 where the tip enters a unit
# wide), and a lake's thin tip entering a leaf of six crossings through one
# side and leaving through two (mosaic seed 136904), mended by subpixel.c's
# pair_leaf.
RING_SCENES = ['twins-135011@1:128', 'twins-135410@1:128', 'mosaic-135325',
               'mosaic-137127@2:256', 'mosaic-136951', 'mosaic-136904',
               'spike-138212@5:640', 'spike-138229@5:640',
               'mosaic-139109@1.5:192', 'mosaic-139300@0.6:76.8',
               'spike-140638@8:1024', 'mosaic-141419@2.5:320',
               'grid-142216@3:384', 'grid-142233@3:384',
               # a meander with a vertex every 0.17 px, thinned to 1/16 px as
               # it was read, off a lake whose corner reached 1.4 units into
               # it (the lake a separate speck, subpixel seed 146706 at 12 m,
               # where the lake is no longer sub-pixel and apart) or over a
               # lake's island (lost, 146707): wm_ingest.c's DENSE_PER_PX
               'subpixel-146706@12:1536', 'subpixel-146707@12:1536',
               # a land triangle 0.8 x 0.4 px between a lake's neck, its lobe
               # and a river's bank, across the side between its two cells
               # as three crossings of a side that is not loose, each bank
               # corner in its own cell near the cell's segment (lost until
               # corners were grouped by window of 2 x 2 cells, crowded_cells)
               'spike-152138@3:384',
               # a leaf (a rectangle too small to divide) entered by a land
               # wedge from its bottom and one from its top, the water
               # joined between their tips (a lake's vertex 1.7 units across
               # another lake's edge): two pairs on one side, drawn by the
               # fallback as separated (a land channel a unit wide, the small
               # lake a speck) until draw_pairs() took two such pairs
               'cluster-59', 'cluster-156368@0.25:32',
               # a river with 17 vertices per pixel thinned to 1/16 px as it
               # was read, its bank then a unit off two lake edges that the
               # line as drawn meets at one point: a land speck 2 x 2 units
               # (subpixel seed 152200 at 30 m); now thinned to the least
               # tolerance that leaves 8 per pixel (wm_ingest.c)
               'subpixel-152200@30:3840',
               # a lake 0.46 px across crossing a block side where its edge
               # passes exactly through a sample of the side, which field.c
               # settles to land (the points a unit across differ): the
               # boundary through that end of the side's segment was taken
               # for the closed sample's own and dropped, and the lake's half
               # in one block with it (probe.c's round_crossings)
               'seam-161017@3:384']


@pytest.mark.parametrize('scene', SCENE_IDS + RING_SCENES, indirect=True)
def test_rings_one_for_one(scene):
    """SIMPLIFY=0: as many land and water rings per block as the exact
    union has (but for those below the lattice, adversarial.resolvable):
    no feature cut in two or two joined, which neither the
    Hausdorff distance nor the speck and lost counts need to show (a
    junction of land strips cut into an island 1.3 px long measured 0.22
    px)."""
    fig = scene.measure('exact')
    assert fig['ring_diff'] == 0, '%s: %d rings more or fewer than the exact union' % (
        scene.describe, fig['ring_diff'])


# Blocks of the bundled OSM extracts at scales the other tests do not use,
# that failed once when the whole extract was checked against the exact
# union (file, WIDTH_FIELD, PIXEL_SIZE, BLOCK_SIZE, block): Andorra at 1 m /
# 300 m, where the corner recovery put the crossing of a river's bank with
# an edge two lakes share (inside the union) into a shore that runs on along
# that edge's line: a spike 3.4 px long along the shared edge.
OSM_BLOCKS = [('osm_andorra_2023.gpkg', None, 1.0, 300.0, (1247, 15664))]


@pytest.mark.parametrize('case', OSM_BLOCKS,
                         ids=['%s@%g:%g:%d,%d' % ((c[0].split('_')[1], c[2], c[3]) + c[4])
                              for c in OSM_BLOCKS])
def test_osm_block(wm, case):
    """SIMPLIFY=0 on one block of real data: within half a pixel of the
    exact union, no speck, nothing small lost."""
    name, width_field, px, B, (bx, by) = case
    path = os.path.join(wm.DATA_DIR, name)
    options = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'LAKES': path, 'LAKES_LAYER': 'lakes',
               'PIXEL_SIZE': px, 'BLOCK_SIZE': B, 'SIMPLIFY': 0, 'NUM_THREADS': 1}
    if width_field:
        options['WIDTH_FIELD'] = width_field
    bbox = (bx * B, by * B, (bx + 1) * B, (by + 1) * B)
    spat = (bbox[0] + 0.1, bbox[1] + 0.1, bbox[2] - 0.1, bbox[3] - 0.1)
    orc = oracle.oracle_blocks(oracle.inputs_from_options(options, bbox=bbox), B, [(bx, by)])
    res = wm.run(options, spat=spat)
    fig, _ = adversarial.measure(res.water, orc, B, px)
    assert fig['hausdorff_px'] <= HAUSDORFF_PX, (case, fig['hausdorff_px'], fig['worst_at'])
    assert fig['specks_outer'] == 0 and fig['specks_hole'] == 0, (case, fig['speck_at'])
    assert fig['lost_outer'] == 0 and fig['lost_hole'] == 0, (case, fig['lost_at'])


def _run_measured(wm, options, B, px):
    """Runs options; (the run, the oracle by block, measure()'s figures)."""
    orc = oracle.oracle_blocks(oracle.inputs_from_options(options), B)
    res = wm.run(options)
    return res, orc, adversarial.measure(res.water, orc, B, px)[0]


def test_densified_arcs_keep_their_strip(wm, tmp_path):
    """Two concentric river arcs (radii about 40 m) with a vertex every
    0.08 pixel, on the lattice as adversarial.py snaps them, and a land
    strip 4 lattice units wide between their banks. Over 8 vertices per
    pixel the rivers are thinned as they are read; the least tolerance that
    leaves 8 per pixel (1 unit here) keeps the strip, where 1/16 pixel (16
    units, the sagitta of chords about 6 px long) closed it in places: one
    water polygon instead of two (wm_ingest.c's thin_dense; fails on
    8664566 with 2 rings fewer)."""
    import math
    from osgeo import ogr
    import scenes
    px, B = PIXEL_SIZE, BLOCK_SIZE
    unit = px / adversarial.LATTICE_Q
    cx, cy = adversarial.ORIGIN[0] + 4.0, adversarial.ORIGIN[1] + 4.0
    w1, w2, gap = 2.0, 1.5, 4 * unit
    r1 = 40.0
    r2 = r1 + w1 / 2 + gap + w2 / 2
    rivers = []
    for r, w in ((r1, w1), (r2, w2)):
        n = int(r * math.pi / 2 / (0.1 * px))
        pts = [(cx + r * math.cos(0.15 + 1.2 * k / n), cy + r * math.sin(0.15 + 1.2 * k / n))
               for k in range(n + 1)]
        pts = adversarial._dedup([adversarial._snap(p, unit) for p in pts])
        rivers.append({'geom': 'LINESTRING (%s)' % adversarial._coords(pts), 'width': w})
    path = str(tmp_path / 'arcs.gpkg')
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, adversarial.EPSG, rivers,
                       fields=[('width', 'Real')])
    options = {'RIVERS': path, 'RIVERS_LAYER': 'rivers', 'WIDTH_FIELD': 'width',
               'PIXEL_SIZE': px, 'BLOCK_SIZE': B, 'SIMPLIFY': 0, 'NUM_THREADS': 1}
    res, orc, fig = _run_measured(wm, options, B, px)
    assert fig['ring_diff'] == 0, fig
    assert fig['hausdorff_px'] <= HAUSDORFF_PX, (fig['hausdorff_px'], fig['worst_at'])
    assert sum(len(oracle.polygons_of(g)) for g in orc.values()) == len(res.water)


# Thin islands in a lake, lying along a row of samples between a sample of
# the lake and one of the shore's land: (shore, island bottom, island top)
# in pixels above the sample row, and the scene's rotation in degrees. The
# edges up from the lake's samples meet the island's two sides and the
# shore, three crossings where marching squares draws one; their samples'
# values sum to more than the loose bound, and no river is near
# (river_may_hide), so the island was lost, joined to the shore (13 of 250
# held-out island scenes, 9878593). Such an edge is searched exactly when
# lake edges meet it twice (lake_twice).
THIN_ISLANDS = [((0.5, 0.3, 0.4), 0.0), ((0.45, 0.12, 0.2), 0.0),
                ((0.5, 0.2, 0.3), 0.3), ((0.5, 0.15, 0.22), -0.45)]


@pytest.mark.parametrize('case', THIN_ISLANDS,
                         ids=['%g-%g-%g@%g' % (c[0] + (c[1],)) for c in THIN_ISLANDS])
def test_thin_island_along_sample_row_kept(wm, tmp_path, case):
    """A lake 60 x 30 px with an island 0.07-0.1 px wide and 20 px long
    near its straight shore, along a sample row: the island stays a hole,
    within half a pixel of the exact union."""
    from osgeo import ogr
    from shapely.affinity import rotate
    from shapely.geometry import Polygon, box
    import scenes
    (shore, lo, hi), angle = case
    px, B = PIXEL_SIZE, BLOCK_SIZE
    x0, y0 = adversarial.ORIGIN[0] + 2 * px, adversarial.ORIGIN[1] + 60 * px
    island = box(x0 + 10.3 * px, y0 + lo * px, x0 + 30.7 * px, y0 + hi * px)
    lake = Polygon(box(x0, y0 - 30 * px, x0 + 60 * px, y0 + shore * px).exterior.coords,
                   [island.exterior.coords])
    lake = rotate(lake, angle, origin=(x0 + 30 * px, y0))
    path = str(tmp_path / 'island.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, adversarial.EPSG, [{'geom': lake}])
    options = {'LAKES': path, 'LAKES_LAYER': 'lakes', 'PIXEL_SIZE': px,
               'BLOCK_SIZE': B, 'SIMPLIFY': 0, 'NUM_THREADS': 1}
    _, _, fig = _run_measured(wm, options, B, px)
    assert fig['ring_diff'] == 0, fig
    assert fig['lost_hole'] == 0, (fig['lost_hole'], fig['lost_at'])
    assert fig['hausdorff_px'] <= HAUSDORFF_PX, (fig['hausdorff_px'], fig['worst_at'])


def test_stream_leaving_lake_on_block_side(wm, tmp_path):
    """A lake whose top edge lies on a block line, and a stream 0.32 px
    wide leaving it across that edge (held-out round 30, seed 52, 1 m
    pixels, 16 m blocks): in the block above, the corner recovery took the
    lake's corners on the side, 11 px from the stream, for corners of the
    stream's ring (their triangle's class was checked a unit from the side,
    where the next block's lake lies within an eighth of a pixel): two
    spikes a unit wide along the side, 11 px off the exact union. crease.c's
    class_near looks within the block only."""
    from osgeo import ogr
    import scenes
    path = str(tmp_path / 'side.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, adversarial.EPSG, [
        {'geom': 'POLYGON ((400043.2 4700016, 400020.8 4700016, 400020.8 4700004.8, '
                 '400043.2 4700004.8, 400043.2 4700016))'}])
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, adversarial.EPSG, [
        {'geom': 'LINESTRING (400032.0198756479 4700015.749137615, '
                 '400032.9937042184 4700023.709699095)', 'width': 0.3176541578387737}],
        fields=[('width', 'Real')])
    px, B = 1.0, 16.0
    options = {'LAKES': path, 'LAKES_LAYER': 'lakes', 'RIVERS': path, 'RIVERS_LAYER': 'rivers',
               'WIDTH_FIELD': 'width', 'PIXEL_SIZE': px, 'BLOCK_SIZE': B, 'SIMPLIFY': 0,
               'NUM_THREADS': 1}
    res, orc, fig = _run_measured(wm, options, B, px)
    assert fig['hausdorff_px'] <= HAUSDORFF_PX, (fig['hausdorff_px'], fig['worst_at'])
    assert fig['ring_diff'] == 0, fig
    # measure() counts the block square as boundary, and the spikes lie a
    # unit from it: the blocks above the lake, their boundaries as they are
    from shapely.ops import unary_union
    above = {}
    for f in res.water:
        if f.block[1] == 293751:
            above.setdefault(f.block, []).append(f.geom)
    assert above
    for block, geoms in above.items():
        h = unary_union(geoms).boundary.hausdorff_distance(orc[block].boundary) / px
        assert h <= HAUSDORFF_PX, (block, h)


def _assert_valid_and_apart(res):
    """Water output, every polygon valid, no ring through a point twice."""
    assert res.water and all(f.geom.is_valid for f in res.water)
    for f in res.water:
        for poly in getattr(f.geom, 'geoms', [f.geom]):
            for r in [poly.exterior] + list(poly.interiors):
                pts = list(r.coords)[:-1]
                assert len(set(pts)) == len(pts), 'a ring touches itself'


@pytest.mark.parametrize('seed,simplify', [(5, 0), (10, 0), (42, None)])
def test_self_crossing_lake_pinches_opened(wm, tmp_path, seed, simplify):
    """A lake ring of 100-200 random vertices within a few metres crosses
    itself everywhere; rounded to the lattice, the boundary then touches
    itself at points (pinches), which the rings may not do: at SIMPLIFY=0
    the CDT stopped ("duplicate vertex", seeds 5 and 10), with
    simplification the simplifier did ("input rings cross or touch", seed
    42). pinch.c moves all passes but one a unit into their own water."""
    import random
    from osgeo import ogr
    import scenes
    rnd = random.Random(seed)
    n, size = rnd.randint(100, 200), rnd.uniform(1.5, 6)
    ring = [(500000 + rnd.uniform(0, size), 4700000 + rnd.uniform(0, size))
            for _ in range(n)]
    wkt = 'POLYGON ((%s))' % ','.join('%.9f %.9f' % p for p in ring + ring[:1])
    path = str(tmp_path / 'lake.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, adversarial.EPSG, [{'geom': wkt}])
    options = {'LAKES': path, 'LAKES_LAYER': 'lakes', 'PIXEL_SIZE': PIXEL_SIZE,
               'BLOCK_SIZE': 32, 'NUM_THREADS': 1}
    if simplify is not None:
        options['SIMPLIFY'] = simplify
    res = wm.run(options)
    _assert_valid_and_apart(res)
    # (the oracle's even-odd union of such a ring takes GEOS over 24 GiB:
    # test_self_crossing_lake_touches_itself measures a small one)


# QA round 28's cases, each a lake ring (or two) crammed into a few
# hundredths of a pixel, where a vertex of one ring lies inside another
# ring's segment (a T), or specks a unit across cross a segment
# (simplify_cross), with the options that stopped them
CRAMMED = {
    'cdt_t': ([[(400006.41015625, 4700011.43359375), (400006.453125, 4700011.45703125),
                (400006.3984375, 4700011.4296875), (400006.421875, 4700011.42578125),
                (400006.4453125, 4700011.4453125), (400006.41015625, 4700011.42578125),
                (400006.4140625, 4700011.4765625), (400006.39453125, 4700011.42578125),
                (400006.41015625, 4700011.4453125), (400006.43359375, 4700011.453125),
                (400006.44921875, 4700011.4296875), (400006.42578125, 4700011.44921875),
                (400006.44140625, 4700011.46875), (400006.41796875, 4700011.42578125),
                (400006.4375, 4700011.4453125), (400006.40234375, 4700011.421875),
                (400006.45703125, 4700011.46484375)]],
              {'PIXEL_SIZE': 1, 'BLOCK_SIZE': 16, 'SIMPLIFY': 0}),
    'simplify_t': ([[(400008.4613833691, 4700004.803341487), (400008.46185808105, 4700004.799481513),
                     (400008.46832523786, 4700004.80615557), (400008.46267555957, 4700004.80184828),
                     (400008.473304964, 4700004.804636008), (400008.46100781736, 4700004.806314861),
                     (400008.4711322093, 4700004.803984799), (400008.4625868761, 4700004.80224758),
                     (400008.4694976853, 4700004.800299493)],
                    [(400008.4680172994, 4700004.801023), (400008.47112700425, 4700004.795949061),
                     (400008.4678034558, 4700004.794166657), (400008.46262616944, 4700004.806410139)]],
                   {'PIXEL_SIZE': 0.25, 'BLOCK_SIZE': 16}),
    'simplify_cross': ([[(400008.46463783353, 4700004.805740427), (400008.47125803103, 4700004.805544853),
                         (400008.4701711877, 4700004.79334569), (400008.4623771286, 4700004.800301201),
                         (400008.4613833691, 4700004.803341487), (400008.46185808105, 4700004.799481513),
                         (400008.4649853268, 4700004.796495749), (400008.46462916775, 4700004.798222655),
                         (400008.4638258364, 4700004.803411331), (400008.46832523786, 4700004.80615557),
                         (400008.46267555957, 4700004.80184828), (400008.473304964, 4700004.804636008),
                         (400008.46100781736, 4700004.806314861), (400008.4711322093, 4700004.803984799),
                         (400008.4625868761, 4700004.80224758), (400008.4694976853, 4700004.800299493),
                         (400008.46307703084, 4700004.798436954), (400008.47193558107, 4700004.798342012),
                         (400008.4686042171, 4700004.794302194)],
                        [(400008.4680172994, 4700004.801023), (400008.47112700425, 4700004.795949061),
                         (400008.4678034558, 4700004.794166657), (400008.46262616944, 4700004.806410139)]],
                       {'PIXEL_SIZE': 0.25, 'BLOCK_SIZE': 16, 'MIN_ANGLE': 20}),
    'fan_t': ([[(400088.46075025026, 4700110.789641385), (400088.51335571724, 4700110.725394001),
                (400087.21778722596, 4700111.553073797), (400088.3656516461, 4700110.8808408035),
                (400088.49138533016, 4700110.758725617), (400086.9298550918, 4700111.813764501),
                (400088.49811681884, 4700110.887814013), (400087.75743887195, 4700112.253526181),
                (400088.5378837696, 4700110.640153315), (400087.5775295115, 4700112.255665089),
                (400088.3114799886, 4700110.850212865), (400087.2863956638, 4700111.840241517),
                (400088.4023597887, 4700110.751907488), (400088.43437670707, 4700110.643919798),
                (400087.3596186683, 4700110.02243159), (400088.421956503, 4700110.72073611),
                (400087.1371803205, 4700112.090602628)]],
              {'PIXEL_SIZE': 2, 'BLOCK_SIZE': 256}),
}


@pytest.mark.parametrize('case', sorted(CRAMMED))
def test_crammed_lake_tees_opened(wm, tmp_path, case):
    """A vertex inside another ring's segment (a T) stopped the CDT ("cdt:
    vertex lies on ring edge") or the simplifier ("input rings cross or
    touch"); pinch.c moves the vertex into the convex side of its turn.
    Specks thinner than half a unit crossing a segment stopped the
    simplifier; block.c drops them before it (drop_thin)."""
    from osgeo import ogr
    import scenes
    rings, opts = CRAMMED[case]
    feats = [{'geom': 'POLYGON ((%s))' % ','.join('%r %r' % p for p in r + r[:1])}
             for r in rings]
    path = str(tmp_path / 'lake.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, adversarial.EPSG, feats)
    options = dict(opts, LAKES=path, LAKES_LAYER='lakes', NUM_THREADS=1)
    res = wm.run(options)
    assert not res.cap.errors, res.cap.errors
    _assert_valid_and_apart(res)


def test_self_crossing_lake_touches_itself(wm, tmp_path):
    """A lake ring of 12 vertices crossing itself within 2 x 2 m (QA round
    of 2026-11-28, reduced from one of 200 random vertices): two of its
    crossings round to one lattice point of an ambiguous cell's dividing
    segment, where the boundary touches itself, two segments in and two
    out. Both ins were linked to the first out found and the block failed
    with "a chain ends inside the block"; each in now goes on to the first
    out clockwise from it (contour.c takes_before), and the rings touch
    there without crossing."""
    from osgeo import ogr
    import scenes
    px, B = PIXEL_SIZE, BLOCK_SIZE
    ring = [(500000.201407204, 4700000.07720826), (500001.403898953, 4700000.91286124),
            (500001.184124022, 4700001.53176663), (500000.814388717, 4700000.39233982),
            (500000.779190569, 4700000.73207811), (500001.046961576, 4700000.01357093),
            (500000.210960954, 4700000.00637354), (500001.81368004, 4700001.34180863),
            (500001.197766404, 4700000.87173829), (500000.462804591, 4700000.13075474),
            (500000.607978254, 4700000.73057041), (500001.239170741, 4700000.26023769)]
    wkt = 'POLYGON ((%s))' % ','.join('%.9f %.8f' % p for p in ring + ring[:1])
    path = str(tmp_path / 'lake.gpkg')
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, adversarial.EPSG, [{'geom': wkt}])
    options = {'LAKES': path, 'LAKES_LAYER': 'lakes', 'PIXEL_SIZE': px, 'BLOCK_SIZE': B,
               'SIMPLIFY': 0, 'NUM_THREADS': 1}
    res = wm.run(options)
    assert all(f.geom.is_valid for f in res.water)
    orc = oracle.oracle_blocks(oracle.inputs_from_options(options), B)
    fig, _ = adversarial.measure(res.water, orc, B, px)
    assert fig['hausdorff_px'] <= HAUSDORFF_PX, (fig['hausdorff_px'], fig['worst_at'])
    assert fig['specks_outer'] == 0 and fig['specks_hole'] == 0, fig['speck_at']
