#!/usr/bin/python3
"""Draws a draped watermesh output (ELEVATION) in 3D: the mesh layer's
triangles at their heights, coloured by height, over the elevation raster
as a grey wireframe. The picture of README's "Terrain-ready water".

Usage: render_drape.py OUT.gpkg DEM.tif PICTURE.png XMIN YMIN XMAX YMAX
"""
import sys

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402
from osgeo import gdal, ogr  # noqa: E402


def triangles(path, box):
    ds = ogr.Open(path)
    lyr = ds.GetLayerByName('mesh')
    lyr.SetSpatialFilterRect(*box)
    out = []
    for f in lyr:
        g = f.GetGeometryRef()
        for i in range(g.GetGeometryCount()):
            out.append(g.GetGeometryRef(i).GetGeometryRef(0).GetPoints()[:3])
    return out


def terrain(dem, box, step=4):
    ds = gdal.Open(dem)
    gt = ds.GetGeoTransform()
    z = ds.GetRasterBand(1).ReadAsArray()
    i0, i1 = int((box[0] - gt[0]) / gt[1]), int((box[2] - gt[0]) / gt[1])
    j0, j1 = int((box[3] - gt[3]) / gt[5]), int((box[1] - gt[3]) / gt[5])
    z = z[j0:j1:step, i0:i1:step]
    xs = gt[0] + gt[1] * (np.arange(i0, i1, step) + 0.5)
    ys = gt[3] + gt[5] * (np.arange(j0, j1, step) + 0.5)
    return np.meshgrid(xs, ys) + [z]


def main(argv):
    if len(argv) != 8:
        sys.exit(__doc__)
    out, dem, png = argv[1:4]
    box = [float(v) for v in argv[4:8]]
    tris = triangles(out, box)
    fig = plt.figure(figsize=(9, 6.5))
    ax = fig.add_subplot(projection='3d')
    gx, gy, gz = terrain(dem, box)
    ax.plot_wireframe(gx, gy, gz, color='0.6', linewidth=0.3)
    zs = [np.mean([p[2] for p in t]) for t in tris]
    norm = plt.Normalize(min(zs), max(zs))
    coll = Poly3DCollection(tris, facecolors=plt.cm.viridis(norm(zs)),
                            edgecolors='k', linewidths=0.1)
    ax.add_collection3d(coll)
    ax.set_xlim(box[0], box[2])
    ax.set_ylim(box[1], box[3])
    ax.set_zlim(float(np.min(gz)) - 5, float(np.max(gz)) + 5)
    ax.view_init(elev=35, azim=-60)
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    ax.set_zlabel('z (m)')
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap='viridis'), ax=ax,
                 shrink=0.6, label='water level (m)')
    fig.tight_layout()
    fig.savefig(png, dpi=110)


if __name__ == '__main__':
    main(sys.argv)
