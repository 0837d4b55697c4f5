"""The XML readers' modules in their order (issue 26): xmlbase (pass one and the shared builder machinery) under the
Nori and Mitsuba builders, the front door xmlparser above both. test_layers fails on a circle among them; this also
fails where no circle forms yet but the order is gone: a builder leaning on the other builder (as the Mitsuba reader
once subclassed the Nori reader's private builder) or on the front door, or the base on either."""
from test_layers import _import_graph

#: a module may import the readers below its own level only
LEVELS = {
    "clrender.scene.xmlbase": 0,
    "clrender.scene.mitsuba_legacy": 0,
    "clrender.scene.nori_xml": 1,
    "clrender.scene.mitsuba_xml": 1,
    "clrender.scene.xmlparser": 2,
}


def test_the_xml_readers_import_downwards_only():
    graph = _import_graph()
    missing = [m for m in LEVELS if m not in graph]
    assert not missing, f"renamed or gone (update LEVELS and the README's layout): {missing}"
    sideways_or_up = sorted((m, d) for m in LEVELS for d in graph[m] if d in LEVELS and LEVELS[d] >= LEVELS[m])
    assert not sideways_or_up, f"(module, the reader it imports at its own level or above): {sideways_or_up}"
    # each builder stands on the base, and the front door reaches both builders
    assert "clrender.scene.xmlbase" in graph["clrender.scene.nori_xml"] & graph["clrender.scene.mitsuba_xml"]
    assert {"clrender.scene.nori_xml", "clrender.scene.mitsuba_xml"} <= graph["clrender.scene.xmlparser"]
