#!/usr/bin/python3
"""Writes a synthetic elevation raster (GeoTIFF, Float32) for trying
ELEVATION: an analytic surface, a valley falling to the north-east with
hills on it, so that raw terrain along a river rises and falls. Made by
this script alone (no outside data): free to use as the repository is.

Usage: make_dem.py OUT.tif EPSG XMIN YMIN XMAX YMAX [RESOLUTION]
"""
import sys

import numpy as np
from osgeo import gdal, osr


def surface(x, y, x0, y0):
    return (600 - 0.004 * (x - x0) - 0.006 * (y - y0)
            + 25 * np.sin((x - x0) / 600.0) * np.cos((y - y0) / 750.0)
            + 8 * np.sin((x - x0 + y - y0) / 180.0))


def main(argv):
    if len(argv) not in (7, 8):
        sys.exit(__doc__)
    out, epsg = argv[1], int(argv[2])
    x0, y0, x1, y1 = map(float, argv[3:7])
    res = float(argv[7]) if len(argv) == 8 else 10.0
    nx, ny = int(np.ceil((x1 - x0) / res)), int(np.ceil((y1 - y0) / res))
    xs = x0 + res * (np.arange(nx) + 0.5)
    ys = y1 - res * (np.arange(ny) + 0.5)
    gx, gy = np.meshgrid(xs, ys)
    ds = gdal.GetDriverByName('GTiff').Create(out, nx, ny, 1, gdal.GDT_Float32,
                                              ['COMPRESS=DEFLATE'])
    ds.SetGeoTransform((x0, res, 0, y1, 0, -res))
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(epsg)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(surface(gx, gy, x0, y0).astype('f4'))
    ds = None


if __name__ == '__main__':
    main(sys.argv)
