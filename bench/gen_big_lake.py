#!/usr/bin/python3
"""A worst case for ELEVATION's levels pre-pass: one lake of 60,000
vertices (a wavy circle 10 km across) crossed by 1,000 radial rivers of 60
vertices each, so that every river vertex lies in the lake's box.

Usage: bench/gen_big_lake.py OUT.gpkg   (EPSG:32631, layers rivers, lakes)
A raster to go with it: tools/make_dem.py dem.tif 32631 393000 4693000
407000 4707000 30.
"""
import math
import sys

from osgeo import ogr, osr


def main(out):
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(32631)
    ds = ogr.GetDriverByName('GPKG').CreateDataSource(out)
    cx, cy, radius, n = 400000.0, 4700000.0, 5000.0, 60000
    ring = ogr.Geometry(ogr.wkbLinearRing)
    for i in range(n):
        a = 2 * math.pi * i / n
        r = radius * (1 + 0.05 * math.sin(7 * a))
        ring.AddPoint_2D(cx + r * math.cos(a), cy + r * math.sin(a))
    ring.CloseRings()
    poly = ogr.Geometry(ogr.wkbPolygon)
    poly.AddGeometry(ring)
    lakes = ds.CreateLayer('lakes', srs, ogr.wkbPolygon)
    f = ogr.Feature(lakes.GetLayerDefn())
    f.SetGeometry(poly)
    lakes.CreateFeature(f)
    rivers = ds.CreateLayer('rivers', srs, ogr.wkbLineString)
    rivers.CreateField(ogr.FieldDefn('width', ogr.OFTReal))
    for k in range(1000):
        a = 2 * math.pi * k / 1000
        line = ogr.Geometry(ogr.wkbLineString)
        for j in range(60):
            r = radius * 0.9 + j * 25
            line.AddPoint_2D(cx + r * math.cos(a), cy + r * math.sin(a))
        f = ogr.Feature(rivers.GetLayerDefn())
        f.SetGeometry(line)
        f.SetField('width', 4)
        rivers.CreateFeature(f)


if __name__ == '__main__':
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
