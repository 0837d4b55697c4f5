"""Plugin specs from Mitsuba-style plugin dicts (as `mi.load_dict` takes them), so a test can build the same BSDF
in clrender that it evaluates in Mitsuba: nested dicts with a type other than "rgb" are child plugins."""
from __future__ import annotations

from ..scene.properties import PropertyList
from ..scene.spec import PluginSpec


def spec_from_dict(d: dict, tag: str = "bsdf") -> PluginSpec:
    props = PropertyList(f'<{tag} type="{d["type"]}">', None, fmt="mitsuba")
    children = []
    for k, v in d.items():
        if k == "type":
            continue
        if isinstance(v, dict) and v.get("type") == "rgb":
            props.add(k, "color", v["value"])
        elif isinstance(v, dict):
            children.append(spec_from_dict(v))
        elif isinstance(v, bool):
            props.add(k, "boolean", v)
        elif isinstance(v, (int, float)):
            props.add(k, "float", float(v))
        else:
            props.add(k, "string", v)
    return PluginSpec(tag, d["type"], None, props, children, None, format="mitsuba")
