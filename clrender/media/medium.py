"""What every participating medium plugin shares: its nested phase function (default isotropic) and its row of the
scene's `media` table (layout.ROWS "Medium"), which shapes (interior/exterior) and the camera point at.

Media are Mitsuba 3's: a shape's `interior` is the medium on the side its normals point away from, `exterior` the
one they point to; a path that crosses the shape's surface goes on in the medium on the side it leaves toward. The
kernel half is `kernels/media/<name>.h`: `<name>_sigma_t` and `<name>_albedo` at a point (and for media that are
not homogeneous `<name>_majorant` and `<name>_clip`) (gen/medium_dispatch.h,
kind MEDIUM in clrender/device/dispatch.py); the integrator (kernels/integrators/media.h) samples free flights.
"""
from __future__ import annotations

import numpy as np

from ..device import dispatch, layout
from ..errors import SceneError


class Medium:
    kernel: str = ""
    PARAMS: list = []
    FLAGS: tuple = ()
    children = ("phase",)

    def _read_phase(self, children, spec) -> None:
        from ..phase.isotropic import Isotropic

        phases = [c for c in children if c.spec.tag == "phase"]
        if len(phases) > 1:
            raise SceneError(f"{spec.describe()} takes one <phase>; this is a second one", phases[1].spec.location)
        self.phase = phases[0] if phases else Isotropic()

    def _read_common(self, props) -> float:
        """Mitsuba's parameters every medium has: sample_emitters and has_spectral_extinction (both default true);
        returns `scale` (default 1), checked."""
        self.sample_emitters = props.get_bool("sample_emitters", True)
        self.spectral = props.get_bool("has_spectral_extinction", True)
        scale = props.get_float("scale", 1.0)
        if not (scale >= 0 and np.isfinite(scale)):
            raise SceneError(f"scale must be non-negative and finite, got {scale}", props.location("scale"))
        return scale

    def capabilities(self) -> tuple:
        """The row's flags: the class's FLAGS, and SAMPLE_EMITTERS and SPECTRAL_EXTINCTION as the file says."""
        extra = ("SAMPLE_EMITTERS",) if getattr(self, "sample_emitters", False) else ()
        if getattr(self, "spectral", False):
            extra += ("SPECTRAL_EXTINCTION",)
        return tuple(self.FLAGS) + extra

    def pack(self, phase_index: int, ctx=None):
        """This medium's row of the `media` table, its phase function being row `phase_index` of `phases` (ctx: the
        PackContext, where a medium that reads volumes adds them)."""
        row = layout.zeros("Medium")[0]
        row["type"] = dispatch.tag_of(type(self))
        row["flags"] = dispatch.flags_of(type(self), self.capabilities())
        row["phase"] = phase_index
        self.fill(row, ctx)
        return row

    def fill(self, row, ctx=None) -> None:
        """Set this plugin's member of the row's union."""
