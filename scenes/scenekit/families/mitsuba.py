"""8. A Mitsuba 3 scene (read by the Mitsuba reader: rough metal and glass, plastic with a texture, a blend,
parametric shapes, a spot and a disk light under a constant sky). Mitsuba renders the same file.

It is written by hand, not made in code: scenes/mitsuba/showcase.xml is its source, copied to another --out."""
from pathlib import Path

from ..files import write_bytes

SHOWCASE = Path(__file__).resolve().parents[2] / "mitsuba" / "showcase.xml"


def build_mitsuba(out):
    write_bytes(out / "mitsuba" / "showcase.xml", SHOWCASE.read_bytes())
