"""What every shape plugin shares: its nested BSDF (default: diffuse, albedo 0.5), optional area emitter, and
its row of the shapes table.

A shape owns its geometry on both sides: `fill(ctx, index, row)` adds it to the scene's tables (PackContext.
add_table) and `area_distribution()` says how its area is spread for sampling; its kernel half
(`kernel = "shapes/<name>.h"`) gives `<name>_surface` (the surface record at a BVH hit), `<name>_sample` (a point
seen from a reference point, with its solid-angle density) and `<name>_pdf`, reached through the switch generated
into gen/mesh_dispatch.h (see clrender/device/dispatch.py, kind SHAPE).
"""
from __future__ import annotations

import abc

import numpy as np

from ..device import dispatch
from ..device.layout import NONE
from ..errors import SceneError

#: Largest world-space coordinate of a triangle's vertex. The watertight triangle test (kernels/bvh_common.h)
#: multiplies three coordinate differences in single precision: beyond about 7e12 its products overflow and the
#: triangle is silently missed (measured: a quad at 1e11 renders, at 1e13 it vanishes). 1e12 keeps a margin for
#: ray origins elsewhere in the scene.
TRIANGLE_COORD_MAX = 1e12
#: The same for an analytic sphere, whose test squares coordinate differences (|center| + radius): beyond about
#: 1.8e19 the squares overflow (measured: radius 1e19 renders, 1e20 vanishes).
SPHERE_EXTENT_MAX = 1e18


class Shape(abc.ABC):
    kernel: str = ""
    PARAMS: list = []
    FLAGS: tuple = ()
    METHODS: tuple = ("surface", "sample", "pdf")
    children = ("bsdf", "emitter", "medium")

    def pack(self, ctx, index: int, row) -> None:
        """Fill the Shape row `row` of shape number `index` (its bsdf/emitter fields are the caller's) and add the
        shape's geometry, and for an emitting shape its area distribution, to `ctx`'s tables."""
        cls = type(self)
        row["type"] = dispatch.tag_of(cls)
        row["cdf"] = NONE
        self.fill(ctx, index, row)
        if self.emitter is not None:
            cdf, area = self.area_distribution()
            if not (area > 0 and np.isfinite(area)):
                raise SceneError(f"an area emitter's shape has no area to emit from (area {area})",
                                 getattr(getattr(self, "spec", None), "location", None))
            row["area"] = area
            if cdf is not None:
                row["cdf"] = ctx.add_table("cdf", "float", cdf)

    @abc.abstractmethod
    def fill(self, ctx, index: int, row) -> None:
        """Add the geometry to ctx's tables; set row's first/count/flags (and this plugin's member of its union)."""

    @abc.abstractmethod
    def area_distribution(self):
        """(cdf, total area): the normalised cumulative area of the shape's pieces that its kernel's `_sample`
        searches (None when it samples analytically) and the surface area."""

    def _attach(self, children, spec):
        self.bsdf = None
        self.emitter = None
        self.interior = self.exterior = None   # media (clrender/media/): what lies on either side of the surface
        for c in children:
            kind = c.spec.tag
            if kind == "medium":
                side = c.spec.name
                if side not in ("interior", "exterior"):
                    raise SceneError(f'a <medium> in a shape needs name="interior" or name="exterior" (the side it '
                                     f'fills), got {"no name" if side is None else repr(side)}', c.spec.location)
                if getattr(self, side) is not None:
                    raise SceneError(f"a shape can have only one {side} medium", c.spec.location)
                setattr(self, side, c)
            elif kind == "bsdf":
                if self.bsdf is not None:
                    raise SceneError(f"a shape can have only one <bsdf> (first at line {self.bsdf.spec.location.line})",
                                     c.spec.location)
                self.bsdf = c
            elif kind == "emitter":
                if self.emitter is not None:
                    raise SceneError("a shape can have only one <emitter>", c.spec.location)
                if not getattr(c, "is_area", False):
                    raise SceneError(f"<emitter type=\"{c.spec.type}\"> cannot be attached to a shape; "
                                     "only area emitters can", c.spec.location)
                self.emitter = c
        if self.bsdf is None:
            from ..bsdfs.diffuse import Diffuse

            # Nori gives every shape without a BSDF a diffuse one of albedo 0.5; Mitsuba 3 does too, except that
            # an emitting shape's is black (reflectance 0: checked against Mitsuba 3.9's loaded scenes).
            black = getattr(spec, "format", "nori") == "mitsuba" and self.emitter is not None
            self.bsdf = Diffuse.default(0.0 if black else 0.5)
