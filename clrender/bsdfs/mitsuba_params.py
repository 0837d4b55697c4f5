"""What Mitsuba 3's conductor and dielectric plugins share on the host: parameters that are a value or a nested
texture (`<texture name="alpha" .../>`), and the microfacet distribution's parameters (distribution, alpha or
alpha_u/alpha_v, sample_visible) with Mitsuba's defaults and rules.
"""
from __future__ import annotations

import numpy as np

from ..errors import SceneError

#: kernels/bsdfs/distribution.h's MF_BECKMANN / MF_GGX
DISTRIBUTIONS = {"beckmann": 0, "ggx": 1}


def named_textures(children, names, owner: str) -> dict:
    """The nested textures by name; a texture named otherwise, or twice, is an error naming the accepted ones."""
    found = {}
    for c in children:
        spec = getattr(c, "spec", None)
        name = getattr(spec, "name", None)
        if name not in names:
            raise SceneError(f"{owner} takes textures named {', '.join(repr(n) for n in names)}, not {name!r}",
                             getattr(spec, "location", None))
        if name in found:
            raise SceneError(f"{owner} has two {name!r} textures", getattr(spec, "location", None))
        found[name] = c
    return found


def _check_single(props, textures, name):
    if name in textures and props.has(name):
        raise SceneError(f"{name} given both as a value and as a texture", props.location(name))


def color_or_texture(props, textures, name, default=1.0):
    """(colour, texture or None) of a non-negative colour parameter."""
    _check_single(props, textures, name)
    c = np.asarray(props.get_color(name, np.full(3, default)), np.float64)
    if np.any(c < 0) or not np.all(np.isfinite(c)):
        raise SceneError(f"{name} must be non-negative and finite, got {c.tolist()}", props.location(name))
    return c, textures.get(name)


def float_value(props, name, default, unbounded=False) -> float:
    """A float parameter that Mitsuba reads as a texture (eval_1): a number, or a colour, whose channels' mean is
    what Mitsuba's constant colour gives there (checked against Mitsuba 3.9.1)."""
    if props.has(name) and props.tag(name) in ("rgb", "spectrum", "color"):
        return float(np.mean(props.get_color(name, unbounded=unbounded)))
    return float(props.get_float(name, default))


def float_or_texture(props, textures, name, default, positive: bool = True):
    """(value, texture or None) of a float parameter, positive unless `positive` is False (then only finite; Mitsuba
    takes the principled BSDFs' values as given); a texture's float view is read: Mitsuba's eval_1."""
    _check_single(props, textures, name)
    if name in textures:
        return 1.0, textures[name].float_view()     # the constant is not read
    v = float_value(props, name, default, unbounded=True)
    if not ((v > 0 or not positive) and np.isfinite(v)):
        raise SceneError(f"{name} must be {'positive' if positive else 'finite'}, got {v}",
                         props.location(name) if props.has(name) else None)
    return v, None


class Distribution:
    """distribution, alpha | (alpha_u, alpha_v), sample_visible as Mitsuba reads them (default: isotropic Beckmann,
    alpha 0.1, visible-normal sampling)."""

    NAMES = ("alpha", "alpha_u", "alpha_v")

    def __init__(self, props, textures, owner_location=None):
        kind = props.get_string("distribution", "beckmann")
        if kind not in DISTRIBUTIONS:
            raise SceneError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got {kind!r}",
                             props.location("distribution"))
        self.type = DISTRIBUTIONS[kind]
        self.name = kind
        given = [n for n in self.NAMES if props.has(n) or n in textures]
        if "alpha_u" in given or "alpha_v" in given:
            if not ("alpha_u" in given and "alpha_v" in given):
                raise SceneError("both alpha_u and alpha_v must be given (or alpha alone)", owner_location)
            if "alpha" in given:
                raise SceneError("give either alpha or alpha_u and alpha_v, not both", owner_location)
            self.alpha_u = float_or_texture(props, textures, "alpha_u", None)
            self.alpha_v = float_or_texture(props, textures, "alpha_v", None)
        else:
            self.alpha_u = self.alpha_v = float_or_texture(props, textures, "alpha", 0.1)
        self.sample_visible = bool(props.get_bool("sample_visible", True))

    def fill(self, p, table) -> bool:
        """Write alpha_u, alpha_v (+ _tex), distribution, sample_visible; whether the BSDF needs the surface's
        parametrisation: a texture is read, or the roughness is anisotropic (alpha_u runs along dp/du, as in
        Mitsuba: the shape's shading frame follows it then)."""
        uses = self.alpha_u is not self.alpha_v and self.alpha_u != self.alpha_v
        for name, (v, tex) in (("alpha_u", self.alpha_u), ("alpha_v", self.alpha_v)):
            uses |= fill_color(p, name, (v, tex), table)
        p["distribution"] = self.type
        p["sample_visible"] = int(self.sample_visible)
        return uses


def fill_color(p, name, value_tex, table) -> bool:
    """Fill a "texture" or "float_texture" parameter from (value, texture or None); whether a texture is read."""
    from ..textures.texture import param

    return param(p, name, value_tex[0], value_tex[1], table)
