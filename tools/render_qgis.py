#!/usr/bin/python3
"""Renders the outputs of the QGIS algorithm as QGIS draws them (PyQGIS,
offscreen): the water layer filled, the mesh layer's triangles outlined,
over the input rivers; the picture of README's QGIS section.

    /usr/bin/python3 tools/render_qgis.py water.gpkg mesh.gpkg rivers.gpkg out.png \
        [xmin ymin xmax ymax]

Each layer argument is a file or a QGIS source ("out.gpkg|layername=mesh");
the rivers default to the layer named rivers.
"""

import os
import sys

os.environ.setdefault('QT_QPA_PLATFORM', 'offscreen')

from qgis.core import (QgsApplication, QgsFillSymbol, QgsLineSymbol,  # noqa: E402
                       QgsMapRendererParallelJob, QgsMapSettings, QgsRectangle,
                       QgsVectorLayer)
from qgis.PyQt.QtCore import QSize  # noqa: E402
from qgis.PyQt.QtGui import QColor  # noqa: E402


def main(argv):
    if len(argv) not in (5, 9):
        sys.exit(__doc__)
    app = QgsApplication([], False)
    app.initQgis()
    water = QgsVectorLayer(argv[1], 'water', 'ogr')
    mesh = QgsVectorLayer(argv[2], 'mesh', 'ogr')
    rivers = QgsVectorLayer(argv[3] if '|' in argv[3] else argv[3] + '|layername=rivers',
                            'rivers', 'ogr')
    for lyr in (water, mesh, rivers):
        if not lyr.isValid():
            sys.exit('cannot open %s' % lyr.source())
    water.renderer().setSymbol(QgsFillSymbol.createSimple(
        {'color': '120,170,220,255', 'outline_color': '20,60,120', 'outline_width': '0.4'}))
    mesh.renderer().setSymbol(QgsFillSymbol.createSimple(
        {'color': '0,0,0,0', 'outline_color': '30,30,30', 'outline_width': '0.1'}))
    rivers.renderer().setSymbol(QgsLineSymbol.createSimple(
        {'color': '200,40,40', 'width': '0.3', 'line_style': 'dash'}))
    settings = QgsMapSettings()
    settings.setLayers([rivers, mesh, water])
    settings.setDestinationCrs(water.crs())
    settings.setBackgroundColor(QColor(245, 242, 235))
    settings.setOutputSize(QSize(900, 900))
    if len(argv) == 9:
        settings.setExtent(QgsRectangle(*[float(v) for v in argv[5:9]]))
    else:
        settings.setExtent(water.extent())
    job = QgsMapRendererParallelJob(settings)
    job.start()
    job.waitForFinished()
    if not job.renderedImage().save(argv[4], 'png'):
        sys.exit('cannot write %s' % argv[4])
    print('wrote %s' % argv[4])
    sys.stdout.flush()
    os._exit(0)  # PyQGIS 3.22 may crash in exitQgis; nothing left to do


if __name__ == '__main__':
    main(sys.argv)
