#!/usr/bin/python3
"""METHOD=CONTOUR against METHOD=PAPER, side by side (docs/methods.md).

Usage (from a built tree):
    /usr/bin/python3 tools/compare_methods.py [--figures DIR] [--no-table]

Table, per scene (a seeded synthetic scene, the Andorra extract) and
PIXEL_SIZE (0.5, 1, 2 m), for both methods:
  - a whole run (gdal_watermesh -stats, BLOCK_SIZE 4096, SIMPLIFY =
    PIXEL_SIZE, one thread): output vertices, V and the stage times;
  - fidelity against the exact buffer-and-dissolve (autotest/oracle.py) on
    BLOCK_SIZE 512 blocks (the whole synthetic scene; the 3 x 3 Andorra
    blocks of autotest/test_oracle.py): Hausdorff distance and its 99th
    percentile in pixels, relative area difference.
Figures (--figures DIR): the mesh as a wireframe around a river-river and
a river-lake junction at the three pixel sizes, one picture per method
(the paper's Fig. 7), with the exact boundary in red.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, 'autotest'))
os.environ.setdefault('GDAL_DRIVER_PATH', os.path.join(ROOT, 'plugins'))

import oracle  # noqa: E402
import scenes  # noqa: E402
from osgeo import ogr  # noqa: E402

CLI = os.path.join(ROOT, 'gdal_watermesh')
PIXELS = (0.5, 1.0, 2.0)
METHODS = ('CONTOUR', 'PAPER')
STAGES = ('field', 'extraction', 'simplification', 'holes', 'triangulation')


def run(scene, out, px, method, block=4096, spat=None, stats=True):
    args = [CLI, '-q', '-overwrite', '-num_threads', '1', '-method', method,
            '-pixel_size', str(px), '-block_size', str(block),
            '-rivers', scene['path'], '-rivers_layer', 'rivers',
            '-lakes', scene['path'], '-lakes_layer', 'lakes']
    if scene.get('width_field'):
        args += ['-width_field', scene['width_field']]
    if spat:
        args += ['-spat'] + [str(v) for v in spat]
    if stats:
        args.append('-stats')
    p = subprocess.run(args + [out], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                       universal_newlines=True, check=True)
    return p.stdout


def parse_stats(text):
    sec = {s: float(re.search(r'^%s\s+([0-9.]+)' % s, text, re.M).group(1)) for s in STAGES}
    sec['total'] = float(re.search(r'^total \(stages\)\s+([0-9.]+)', text, re.M).group(1))
    m = re.search(r'output vertices (\d+)', text)
    v = re.search(r'^V = ([0-9.]+)', text, re.M)
    return sec, int(m.group(1)), float(v.group(1))


def read_water(path):
    ds = ogr.Open(path)
    feats = []
    from shapely import wkb
    for f in ds.GetLayerByName('water'):
        g = f.GetGeometryRef()
        feats.append(oracle.Feat((f.GetField('block_x'), f.GetField('block_y')),
                                 wkb.loads(bytes(g.ExportToIsoWkb())), None, {}))
    return feats


def table(tmp):
    syn = os.path.join(tmp, 'synthetic.gpkg')
    scenes.make_random_scene(syn, 1, extent=1500.0, n_tributaries=5, n_lakes=3)
    andorra = os.path.join(ROOT, 'data', 'osm', 'osm_andorra_2023.gpkg')
    B = 512
    cases = [
        {'name': 'synthetic (autotest/scenes.py, seed 1, 1.5 km)', 'path': syn,
         'width_field': 'width', 'blocks': None},
        {'name': 'Andorra (data/osm)', 'path': andorra, 'width_field': None,
         'blocks': {(x, y) for x in range(745, 748) for y in range(9195, 9198)}},
    ]
    for sc in cases:
        bbox = spat = None
        if sc['blocks']:
            xs = [b[0] for b in sc['blocks']]
            ys = [b[1] for b in sc['blocks']]
            bbox = (min(xs) * B, min(ys) * B, (max(xs) + 1) * B, (max(ys) + 1) * B)
            spat = (bbox[0] + 0.1, bbox[1] + 0.1, bbox[2] - 0.1, bbox[3] - 0.1)
        inputs = oracle.load_inputs(rivers=sc['path'], rivers_layer='rivers', lakes=sc['path'],
                                    lakes_layer='lakes', width_field=sc['width_field'], bbox=bbox)
        orc = oracle.oracle_blocks(inputs, B, sc['blocks'])
        print('### %s\n' % sc['name'])
        print('| PIXEL_SIZE | method | vertices | V | Hausdorff | p99 | area diff | '
              + ' | '.join(STAGES) + ' | total |')
        print('|---' * (7 + len(STAGES)) + '|')
        for px in PIXELS:
            for method in METHODS:
                out = os.path.join(tmp, 'run.gpkg')
                sec, nv, V = parse_stats(run(sc, out, px, method))
                run(sc, out, px, method, block=B, spat=spat, stats=False)
                c = oracle.compare(read_water(out), orc, B, px)
                print('| %g | %s | %d | %.3f | %.2f px | %.2f px | %+.2f %% | %s | %.2f |' % (
                    px, method, nv, V, c['hausdorff_px'], c['p99'] / px,
                    100 * c['rel_area_diff'],
                    ' | '.join('%.2f' % sec[s] for s in STAGES), sec['total']))
        print()


# ---- figures ---------------------------------------------------------------

X0, Y0 = scenes.SCENE_ORIGIN
JUNCTIONS = {  # name: window (xmin, ymin, xmax, ymax) relative to the origin
    'river-river': (75.0, -15.0, 120.0, 20.0),
    'river-lake': (285.0, -20.0, 330.0, 15.0),
}


def figure_scene(path):
    """A main river (8 m) with a tributary (5 m) joining at 30 degrees, and a
    river (6 m) entering a square lake at a shallow angle."""
    def line(pts):
        return 'LINESTRING (%s)' % ', '.join('%.3f %.3f' % (X0 + x, Y0 + y) for x, y in pts)

    rivers = [
        {'geom': line([(0, 0), (200, 0.5)]), 'width': 8.0},
        {'geom': line([(100, 0.25), (13.4, 50.2)]), 'width': 5.0},
        {'geom': line([(220, 22), (330, -4)]), 'width': 6.0},
    ]
    lake = [(300, -40), (420, -40), (420, 40), (300, 40)]
    lakes = [{'geom': 'POLYGON ((%s))' % ', '.join('%.3f %.3f' % (X0 + x, Y0 + y)
                                                   for x, y in lake + lake[:1])}]
    scenes.write_layer(path, 'rivers', ogr.wkbLineString, scenes.SCENE_EPSG, rivers)
    scenes.write_layer(path, 'lakes', ogr.wkbPolygon, scenes.SCENE_EPSG, lakes)


def figures(tmp, folder):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection
    path = os.path.join(tmp, 'junctions.gpkg')
    figure_scene(path)
    sc = {'path': path, 'width_field': 'width'}
    inputs = oracle.load_inputs(rivers=path, rivers_layer='rivers', lakes=path,
                                lakes_layer='lakes', width_field='width')
    exact = oracle.water(inputs)
    os.makedirs(folder, exist_ok=True)
    for method in METHODS:
        fig, axes = plt.subplots(2, 3, figsize=(12, 8))
        for col, px in enumerate(PIXELS):
            out = os.path.join(tmp, 'fig.gpkg')
            run(sc, out, px, method, block=512, stats=False)
            ds = ogr.Open(out)
            for row, (name, w) in enumerate(JUNCTIONS.items()):
                ax = axes[row][col]
                win = (X0 + w[0], Y0 + w[1], X0 + w[2], Y0 + w[3])
                fills, edges = [], []
                for lname in ('water', 'mesh'):
                    lyr = ds.GetLayerByName(lname)
                    lyr.SetSpatialFilterRect(*win)
                    for f in lyr:
                        g = f.GetGeometryRef()
                        polys = [g] if lname == 'water' else [g.GetGeometryRef(i) for i in
                                                               range(g.GetGeometryCount())]
                        for p in polys:
                            ring = p.GetGeometryRef(0).GetPoints()
                            (fills if lname == 'water' else edges).append(
                                [(x, y) for x, y, *_ in ring])
                ax.add_collection(PolyCollection(fills, facecolors='#9ecae1', edgecolors='none'))
                ax.add_collection(LineCollection(edges, colors='#08306b', linewidths=0.4))
                for geom in getattr(exact.boundary, 'geoms', [exact.boundary]):
                    xs, ys = geom.xy
                    ax.plot(xs, ys, color='#d62728', linewidth=0.8)
                ax.set_xlim(win[0], win[2])
                ax.set_ylim(win[1], win[3])
                ax.set_aspect('equal')
                ax.set_xticks([])
                ax.set_yticks([])
                ax.set_title('%s, PIXEL_SIZE %g m' % (name, px), fontsize=9)
            ds = None
        fig.suptitle('METHOD=%s: mesh wireframe (blue), exact boundary (red)' % method)
        fig.tight_layout()
        dst = os.path.join(folder, 'fig7_%s.png' % method.lower())
        fig.savefig(dst, dpi=110)
        plt.close(fig)
        print('wrote %s' % dst, file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--figures', metavar='DIR', help='write the Fig. 7 pictures there')
    ap.add_argument('--no-table', action='store_true')
    a = ap.parse_args()
    if not os.access(CLI, os.X_OK):
        sys.exit('%s is not built: run make first' % CLI)
    with tempfile.TemporaryDirectory() as tmp:
        if not a.no_table:
            table(tmp)
        if a.figures:
            figures(tmp, a.figures)


if __name__ == '__main__':
    main()
