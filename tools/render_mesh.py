#!/usr/bin/python3
"""Draws the `mesh` (and `water`) layers of a watermesh output as a PNG.

Usage: render_mesh.py OUT.gpkg PICTURE.png [xmin ymin xmax ymax]

Water polygons are filled, triangle edges drawn as a wireframe. With a
window, only that part is drawn (a close-up of a junction, say).
"""
import sys

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection, PolyCollection  # noqa: E402
from osgeo import ogr  # noqa: E402


def rings_of(geom):
    t = ogr.GT_Flatten(geom.GetGeometryType())
    if t == ogr.wkbPolygon:
        yield [geom.GetGeometryRef(i).GetPoints() for i in range(geom.GetGeometryCount())]
    else:
        for k in range(geom.GetGeometryCount()):
            yield from rings_of(geom.GetGeometryRef(k))


def main(argv):
    if len(argv) not in (3, 7):
        sys.exit(__doc__)
    src, png = argv[1], argv[2]
    window = [float(v) for v in argv[3:]] if len(argv) == 7 else None
    ds = ogr.Open(src)
    if ds is None:
        sys.exit(f'render_mesh: cannot open {src}')
    water, mesh = ds.GetLayerByName('water'), ds.GetLayerByName('mesh')
    for lyr in (water, mesh):
        if window:
            lyr.SetSpatialFilterRect(*window)
    fills, edges = [], []
    for f in water:
        for rings in rings_of(f.GetGeometryRef()):
            fills.append([p[:2] for p in rings[0]])
    ntri = 0
    for f in mesh:
        ntri += f['triangles']
        for rings in rings_of(f.GetGeometryRef()):
            edges.append([p[:2] for p in rings[0]])
    if not fills:
        sys.exit('render_mesh: nothing to draw')
    fig, ax = plt.subplots(figsize=(10, 10), dpi=150)
    ax.add_collection(PolyCollection(fills, facecolors='#9cc9f0', edgecolors='none'))
    ax.add_collection(LineCollection(edges, colors='#1f4e79', linewidths=0.15))
    xs = [x for r in fills for x, _ in r]
    ys = [y for r in fills for _, y in r]
    x0, x1 = (window[0], window[2]) if window else (min(xs), max(xs))
    y0, y1 = (window[1], window[3]) if window else (min(ys), max(ys))
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect('equal')
    ax.set_title(f'{src}: {len(fills)} polygons, {ntri} triangles', fontsize=9)
    ax.tick_params(labelsize=6)
    fig.text(0.01, 0.005, 'Data (c) OpenStreetMap contributors, ODbL', fontsize=6)
    fig.savefig(png, bbox_inches='tight')


if __name__ == '__main__':
    main(sys.argv)
