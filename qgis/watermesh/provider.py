"""The watermesh Processing provider: one algorithm."""

from qgis.core import QgsProcessingProvider

from .algorithm import WaterMeshAlgorithm


class WatermeshProvider(QgsProcessingProvider):
    def id(self):
        return 'watermesh'

    def name(self):
        return 'watermesh'

    def longName(self):  # noqa: N802
        return 'watermesh: water mesh from rivers and lakes'

    def loadAlgorithms(self):  # noqa: N802
        self.addAlgorithm(WaterMeshAlgorithm())
