"""What every phase function plugin shares: its row of the scene's `phases` table (layout.ROWS "Phase"), which
the media that use it point at. The kernel half is `kernels/phase/<name>.h`: `<name>_eval` (the density of wo)
and `<name>_sample` (a direction wo, its pdf, and the weight eval / pdf), reached through the switch generated
into gen/phase_dispatch.h (clrender/device/dispatch.py, kind PHASE)."""
from __future__ import annotations

from ..device import dispatch, layout


class Phase:
    kernel: str = ""
    PARAMS: list = []
    FLAGS: tuple = ()
    children: tuple = ()

    def pack(self) -> "layout.np.ndarray":
        """This phase function's row of the `phases` table."""
        row = layout.zeros("Phase")[0]
        row["type"] = dispatch.tag_of(type(self))
        self.fill(row)
        return row

    def fill(self, row) -> None:
        """Set this plugin's member of the row's union (nothing for a plugin without parameters)."""
