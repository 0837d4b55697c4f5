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

import logging

from ..device import dispatch, layout
from ..errors import SceneError

log = logging.getLogger("clrender")

#: a grid's values this fraction of its range outside it are clamped (interpolation ringing), further out refused
RINGING = 0.01


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

    @staticmethod
    def _volume_children(props, children, spec, names) -> dict:
        """{name: volume} of the nested <volume>s, each named one of `names` and given once."""
        volumes = {}
        for c in children:
            if c.spec.tag != "volume":
                continue
            name = c.spec.name
            if name not in names:
                raise SceneError(f"a <volume> in {spec.describe()} needs " + " or ".join(f'name="{n}"' for n in names)
                                 + f', got {"no name" if name is None else repr(name)}', c.spec.location)
            if name in volumes or props.has(name):
                raise SceneError(f"{spec.describe()} is given '{name}' twice", c.spec.location)
            volumes[name] = c
        return volumes

    @staticmethod
    def _clamp_ringing(name, vol, hi, where) -> None:
        """A grid's values a little outside [0, hi] (a density's interpolation ringing: lajolla's coloured smoke holds
        values down to -0.004 of its peak 1.6) clamped with a warning, as Mitsuba renders them unchecked; further
        out, or a constant outside the range, is left for the caller's located error."""
        from ..volumes.gridvolume import GridVolume

        if not isinstance(vol, GridVolume):
            return
        low, high = vol.min_value(), float(vol.data.max())
        span = max(high, 1e-30) if hi is None else hi
        if -RINGING * span <= low and (hi is None or high <= hi * (1 + RINGING)) and vol.clamp(0.0, hi):
            log.warning("%s: %s's grid %s holds values a little outside [0, %s] (%g to %g); clamped",
                        where, name, vol.filename, "inf" if hi is None else hi, low, high)

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
