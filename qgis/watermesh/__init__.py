"""QGIS plugin: the watermesh Processing provider."""


def classFactory(iface):  # noqa: N802 (QGIS's name)
    from .plugin import WatermeshPlugin
    return WatermeshPlugin(iface)
