"""What every shape plugin shares: its nested BSDF (default: diffuse, albedo 0.5; in a Mitsuba scene black for a
shape that emits, as Mitsuba's default) and optional emitter."""
from __future__ import annotations

import numpy as np

from ..errors import SceneError


class Shape:
    children = ("bsdf", "emitter")

    def _attach(self, children, spec):
        self.bsdf = None
        self.emitter = None
        for c in children:
            kind = c.spec.tag
            if kind == "bsdf":
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

            self.bsdf = Diffuse.default()
            if self.emitter is not None and getattr(spec, "format", "nori") == "mitsuba":
                self.bsdf.albedo = np.zeros(3)   # Mitsuba: an emitting shape without a BSDF reflects nothing
