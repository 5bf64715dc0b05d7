"""Processing algorithm "Water mesh from rivers and lakes".

It wraps the gdal_watermesh command the way QGIS's own GDAL algorithms wrap
GDAL's utilities: each input layer (any QGIS source, memory layers,
selections and subset filters included) is handed over as a file GDAL
reads, exported to a temporary GeoPackage when it is not one already; the
command computes both layers into a temporary GeoPackage, reporting its
progress; the features are then copied into the two outputs. Cancelling
stops the command.

The command is WATERMESH_CLI from the environment, else gdal_watermesh on
the PATH.
"""

import os
import re
import shutil
import subprocess
import tempfile

from qgis.core import (QgsFeatureSink, QgsProcessing, QgsProcessingAlgorithm,
                       QgsProcessingException, QgsProcessingParameterBand,
                       QgsProcessingParameterCrs, QgsProcessingParameterDefinition,
                       QgsProcessingParameterEnum, QgsProcessingParameterFeatureSink,
                       QgsProcessingParameterFeatureSource,
                       QgsProcessingParameterField, QgsProcessingParameterNumber,
                       QgsProcessingParameterRasterLayer,
                       QgsProcessingParameterString, QgsVectorLayer)

METHODS = ['CONTOUR', 'PAPER']
HEURISTICS = ['CLOSEST', 'DIRECTIONAL_CW', 'DIRECTIONAL_CCW', 'LEAST_ANGLE']
DEVICES = ['AUTO', 'CPU', 'OPENCL']
MESH_FORMS = ['MULTIPOLYGON', 'TIN', 'TRIANGLES']
FLOWS = ['DEM', 'LINE_DIRECTION']

# name: (description, default, maximum, advanced) of the numeric options,
# as the driver's open option list gives them (autotest/test_qgis.py checks
# them)
NUMBERS = {
    'WIDTH': ('Default river width (m), where no width field or class gives one', 10.0,
              100000.0, False),
    'PIXEL_SIZE': ('Pixel size: sample spacing (m)', 0.5, None, False),
    'BLOCK_SIZE': ('Block size (m): a multiple of the pixel size', 4096.0, None, False),
    'MERGE_DISTANCE': ('Merge shore vertices closer than (m; 0: off)', 0.0, None, True),
    'MIN_FEATURE_AREA': ('Drop land holes and water parts whose ring encloses less than (m²; 0: off)', 0.0,
                         None, True),
    'MIN_ANGLE': ('Refine the mesh to a minimum angle (degrees; 0: off)', 0.0, 30.0, True),
    'MAX_EDGE': ('Refine the mesh to a maximum edge length (m; 0: off)', 0.0, None, True),
    'LAKE_LEVEL_PERCENTILE': ('Lake level: percentile of the elevation along the shore',
                              10.0, 100.0, True),
}

HELP = """Turns rivers (centerlines with widths) and lakes (polygons) into
dissolved water polygons, seamless across blocks, and their constrained
Delaunay triangle mesh, with the watermesh GDAL driver (docs/driver.rst).

Width field: a numeric or text field of the rivers ("2.5 m", "~5", "5-8",
"3;4" and "1,5" are understood). Width key: a key of that field when it is
an hstore, as OpenStreetMap's other_tags ("width"). Class widths: widths
by class for the rivers without one, e.g.
waterway:river=10,canal=8,stream=2,drain=1.5,ditch=1,*=3 ("*" for any
other class). Simplify: Douglas-Peucker tolerance in metres, empty for the
pixel size, 0 for none. Threads: 0 for every CPU. Mesh geometry:
MULTIPOLYGON (a polygon's triangles in one feature), TIN, or TRIANGLES (one
valid polygon per triangle, what other tools read as a mesh).

Advanced: minimum angle and maximum edge refine the mesh with Steiner
points; an elevation raster drapes both outputs (Z): lakes flat at a
percentile of the raster along their shore, rivers level bank to bank and
never rising downstream (flow from the raster or the lines' direction)."""


def cli_path():
    cli = os.environ.get('WATERMESH_CLI') or shutil.which('gdal_watermesh')
    if not cli or not os.access(cli, os.X_OK):
        raise QgsProcessingException(
            'gdal_watermesh not found: install watermesh (make install) or set '
            'WATERMESH_CLI to its path')
    return cli


class WaterMeshAlgorithm(QgsProcessingAlgorithm):
    def name(self):
        return 'watermesh'

    def displayName(self):  # noqa: N802
        return 'Water mesh from rivers and lakes'

    def shortHelpString(self):  # noqa: N802
        return HELP

    def createInstance(self):  # noqa: N802
        return WaterMeshAlgorithm()

    def initAlgorithm(self, config=None):  # noqa: N802
        P = QgsProcessingParameterNumber
        self.addParameter(QgsProcessingParameterFeatureSource(
            'RIVERS', 'Rivers (centerlines)', [QgsProcessing.TypeVectorLine], optional=True))
        self.addParameter(QgsProcessingParameterFeatureSource(
            'LAKES', 'Lakes (water areas)', [QgsProcessing.TypeVectorPolygon], optional=True))
        self.addParameter(QgsProcessingParameterField(
            'WIDTH_FIELD', 'Width field', parentLayerParameterName='RIVERS', optional=True))
        self.addParameter(QgsProcessingParameterString(
            'WIDTH_KEY', 'Width key, when the width field is an hstore (OSM: width)',
            optional=True))
        self.addParameter(QgsProcessingParameterString(
            'WIDTH_BY_CLASS', 'Class widths (field:class=width,...,*=width)', optional=True))
        advanced = []
        for name, (desc, default, top, adv) in NUMBERS.items():
            param = P(name, desc, P.Double, default, minValue=0.0)
            if top is not None:
                param.setMaximum(top)
            self.addParameter(param)
            if adv:
                advanced.append(name)
        self.addParameter(P('SIMPLIFY', 'Simplify tolerance (m; empty: the pixel size)',
                            P.Double, None, optional=True, minValue=0.0))
        self.addParameter(QgsProcessingParameterEnum('METHOD', 'Boundary extraction',
                                                     METHODS, defaultValue=0))
        self.addParameter(QgsProcessingParameterEnum(
            'HEURISTIC', 'Border walk heuristic (method PAPER)', HEURISTICS, defaultValue=0))
        self.addParameter(QgsProcessingParameterEnum('DEVICE', 'Device computing the field',
                                                     DEVICES, defaultValue=0))
        self.addParameter(P('NUM_THREADS', 'Threads (0: every CPU)', P.Integer, 0,
                            minValue=0, maxValue=1024))
        self.addParameter(QgsProcessingParameterEnum('MESH_GEOMETRY', 'Mesh geometry',
                                                     MESH_FORMS, defaultValue=0))
        self.addParameter(QgsProcessingParameterCrs(
            'TARGET_SRS', 'Working CRS (projected; empty: the inputs\' or their UTM zone)',
            optional=True))
        self.addParameter(QgsProcessingParameterRasterLayer(
            'ELEVATION', 'Elevation raster (drapes both outputs)', optional=True))
        self.addParameter(QgsProcessingParameterBand(
            'ELEVATION_BAND', 'Elevation band', 1, 'ELEVATION', optional=True))
        self.addParameter(QgsProcessingParameterEnum('FLOW', 'River flow direction', FLOWS,
                                                     defaultValue=0))
        advanced += ['HEURISTIC', 'TARGET_SRS', 'ELEVATION', 'ELEVATION_BAND', 'FLOW']
        for name in advanced:
            param = self.parameterDefinition(name)
            param.setFlags(param.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
        self.addParameter(QgsProcessingParameterFeatureSink(
            'WATER', 'Water', QgsProcessing.TypeVectorPolygon))
        self.addParameter(QgsProcessingParameterFeatureSink(
            'MESH', 'Mesh', QgsProcessing.TypeVectorPolygon))

    def input_args(self, parameters, context, feedback, role):
        """-rivers/-lakes arguments for an input (exported to a GeoPackage
        when GDAL could not read it as it is), or []."""
        if parameters.get(role) is None:
            return []
        path, layer = self.parameterAsCompatibleSourceLayerPathAndLayerName(
            parameters, role, context, ['gpkg', 'shp', 'fgb', 'geojson', 'sqlite'], 'gpkg',
            feedback)
        if not path:
            return []
        args = ['-' + role.lower(), path]
        if layer:
            args += ['-%s_layer' % role.lower(), layer]
        return args

    def command_args(self, parameters, context, feedback, out):
        args = [cli_path(), '-progress', '-overwrite']
        args += self.input_args(parameters, context, feedback, 'RIVERS')
        args += self.input_args(parameters, context, feedback, 'LAKES')
        if '-rivers' not in args and '-lakes' not in args:
            raise QgsProcessingException('Give rivers, lakes or both.')
        field = self.parameterAsString(parameters, 'WIDTH_FIELD', context)
        key = self.parameterAsString(parameters, 'WIDTH_KEY', context)
        if field:
            args += ['-width_field', field + (':' + key if key else '')]
        classes = self.parameterAsString(parameters, 'WIDTH_BY_CLASS', context)
        if classes:
            args += ['-width_by_class', classes]
        for name in NUMBERS:
            args += ['-' + name.lower(), repr(self.parameterAsDouble(parameters, name, context))]
        if parameters.get('SIMPLIFY') is not None:
            args += ['-simplify', repr(self.parameterAsDouble(parameters, 'SIMPLIFY', context))]
        args += ['-method', METHODS[self.parameterAsEnum(parameters, 'METHOD', context)]]
        args += ['-heuristic', HEURISTICS[self.parameterAsEnum(parameters, 'HEURISTIC',
                                                                context)]]
        args += ['-device', DEVICES[self.parameterAsEnum(parameters, 'DEVICE', context)]]
        threads = self.parameterAsInt(parameters, 'NUM_THREADS', context)
        args += ['-num_threads', str(threads) if threads > 0 else 'ALL_CPUS']
        args += ['-mesh_geometry',
                 MESH_FORMS[self.parameterAsEnum(parameters, 'MESH_GEOMETRY', context)]]
        crs = self.parameterAsCrs(parameters, 'TARGET_SRS', context)
        if crs.isValid():
            args += ['-target_srs', crs.authid() or crs.toWkt()]
        args += self.elevation_args(parameters, context)
        return args + [out]

    def elevation_args(self, parameters, context):
        """-elevation and its companions, when an elevation raster is given."""
        dem = self.parameterAsRasterLayer(parameters, 'ELEVATION', context)
        if dem is None:
            return []
        if dem.providerType() != 'gdal':
            raise QgsProcessingException(
                'Elevation raster %s: a file GDAL reads is needed (its provider is %s)'
                % (dem.name(), dem.providerType()))
        band = self.parameterAsInt(parameters, 'ELEVATION_BAND', context)
        return ['-elevation', dem.source(), '-elevation_band', str(band if band > 0 else 1),
                '-flow', FLOWS[self.parameterAsEnum(parameters, 'FLOW', context)]]

    def run_command(self, args, feedback):
        """Runs the command, its progress ("0...10...") to feedback; stops it
        when cancelled."""
        feedback.pushCommandInfo(' '.join(args))
        with subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True, bufsize=1) as proc:
            text = ''
            while True:
                c = proc.stdout.read(1)
                if not c:
                    break
                text += c
                m = re.findall(r'(\d+)(?=\.\.\.|\s*-\s*done)', text)
                if m:
                    feedback.setProgress(0.9 * float(m[-1]))
                if feedback.isCanceled():
                    proc.terminate()
                    proc.wait()
                    raise QgsProcessingException('Cancelled.')
            err = proc.stderr.read()
            if proc.wait() != 0:
                raise QgsProcessingException('gdal_watermesh failed: ' + err.strip())
        for line in err.splitlines():
            if line.strip():
                feedback.pushWarning(line)

    def copy_layer(self, parameters, context, feedback, name, path, layer):
        """Copies layer `layer` of the GeoPackage into output `name`."""
        src = QgsVectorLayer('%s|layername=%s' % (path, layer), layer, 'ogr')
        if not src.isValid():
            raise QgsProcessingException('cannot read %s of %s' % (layer, path))
        sink, dest = self.parameterAsSink(parameters, name, context, src.fields(),
                                          src.wkbType(), src.crs())
        for f in src.getFeatures():
            if feedback.isCanceled():
                break
            sink.addFeature(f, QgsFeatureSink.FastInsert)
        return dest

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        with tempfile.TemporaryDirectory(prefix='watermesh_') as tmp:
            out = os.path.join(tmp, 'watermesh.gpkg')
            self.run_command(self.command_args(parameters, context, feedback, out), feedback)
            water = self.copy_layer(parameters, context, feedback, 'WATER', out, 'water')
            feedback.setProgress(95)
            mesh = self.copy_layer(parameters, context, feedback, 'MESH', out, 'mesh')
            feedback.setProgress(100)
        return {'WATER': water, 'MESH': mesh}
