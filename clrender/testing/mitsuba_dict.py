"""Plugin specs from Mitsuba-style plugin dicts (as `mi.load_dict` takes them), so a test can build the same BSDF
in clrender that it evaluates in Mitsuba: nested dicts with a type other than "rgb" are child plugins."""
from __future__ import annotations

from ..scene import registry
from ..scene.properties import PropertyList
from ..scene.spec import PluginSpec


def spec_from_dict(d: dict, tag: str = "bsdf", name: str | None = None, special=None) -> PluginSpec:
    """``special(props, key, value)``, when given, may add a property itself (e.g. a file name resolved
    somewhere, a transform) and return True; nested dicts become children named by their key."""
    props = PropertyList(f'<{tag} type="{d["type"]}">', None, fmt="mitsuba")
    children = []
    for k, v in d.items():
        if k == "type" or (special is not None and special(props, k, v)):
            continue
        if isinstance(v, dict) and v.get("type") == "rgb":
            props.add(k, "color", v["value"])
        elif isinstance(v, dict):
            # a <texture> where its type is a registered Mitsuba texture (no BSDF has such a name), else a <bsdf>
            textures = registry.registered("texture", fmt="mitsuba")
            children.append(spec_from_dict(v, "texture" if v["type"] in textures else "bsdf", k, special))
        elif isinstance(v, bool):
            props.add(k, "boolean", v)
        elif isinstance(v, (int, float)):
            props.add(k, "float", float(v))
        else:
            props.add(k, "string", v)
    return PluginSpec(tag, d["type"], name, props, children, None, format="mitsuba")


def rounded(x):
    """Floats rounded to 7 significant digits (float32's precision) through nested lists and dicts: the reference
    values that the dev scripts write from Mitsuba, in smaller files."""
    if isinstance(x, float):
        return float(f"{x:.7g}")
    if isinstance(x, (list, tuple)):
        return [rounded(v) for v in x]
    if isinstance(x, dict):
        return {k: rounded(v) for k, v in x.items()}
    return x
