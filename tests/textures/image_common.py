"""What the tests of Mitsuba's bitmap texture (tests/textures/test_bitmap.py), of a texture where a float is read
(tests/test_mitsuba_textures.py) and of envmap's image files (tests/emitters/test_envmap.py) share: a bitmap from
its properties, a small random PNG, a 16-bit PNG written by hand, and Mitsuba 3 itself (or a skip) with its own
lookups of a texture."""
import numpy as np
import pytest
from PIL import Image

from clrender.scene import registry
from clrender.scene.transform import Transform


def bitmap(path, **props):
    """A Mitsuba bitmap texture of the image at `path`, its properties given by keyword (booleans, transforms,
    strings)."""
    p = {"filename": ("string", str(path))}
    for k, v in props.items():
        p[k] = ("boolean", v) if isinstance(v, bool) else ("transform", v) if isinstance(v, Transform) else ("string", v)
    return registry.instantiate("texture", "bitmap", p, fmt="mitsuba")


def random_png(folder):
    """A 5 x 7 sRGB PNG of random bytes (seeded) in `folder`: its path and its pixels."""
    img = (np.random.default_rng(4).random((5, 7, 3)) * 255).astype(np.uint8)
    Image.fromarray(img).save(folder / "t.png")
    return folder / "t.png", img


def real_mitsuba(reason):
    """Mitsuba 3 itself, or a skip. Without it, `import mitsuba` finds tests/mitsuba/ (our reference data) as a
    namespace package of that name, so pytest.importorskip would not skip."""
    import sys

    try:
        import mitsuba as mi
    except ImportError:
        mi = None
    if mi is None or not hasattr(mi, "set_variant"):
        sys.modules.pop("mitsuba", None)
        pytest.skip(reason)
    return mi


def write_png16(path, img):
    """A 16-bit RGB PNG (colour type 2, depth 16), its rows filtered None, Sub and Up in turn."""
    import struct
    import zlib

    h, w, _ = img.shape
    data = img.astype(">u2").tobytes()
    stride, rows = w * 6, []
    prev = bytes(stride)
    for y in range(h):
        row = np.frombuffer(data[y * stride:(y + 1) * stride], np.uint8).astype(np.int32)
        kind = y % 3
        if kind == 1:   # Sub: minus the byte one pixel (6 bytes) to the left
            out = row - np.concatenate([np.zeros(6, np.int32), row[:-6]])
        elif kind == 2:   # Up: minus the byte above
            out = row - np.frombuffer(prev, np.uint8).astype(np.int32)
        else:
            out = row
        rows.append(bytes([kind]) + (out % 256).astype(np.uint8).tobytes())
        prev = row.astype(np.uint8).tobytes()

    def chunk(kind, payload):
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))

    ihdr = struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"".join(rows)))
                     + chunk(b"IEND", b""))


def mitsuba_lookups(mi, d: dict, uv, float_lookup: bool = False) -> np.ndarray:
    """Mitsuba's own texture of the dict `d` (as mi.load_dict takes it) at each uv (N, 2): its colour lookup (eval),
    or with `float_lookup` its float one (eval_1)."""
    texture = mi.load_dict(d)
    si = mi.SurfaceInteraction3f()
    out = []
    for u in uv:
        si.uv = mi.Point2f(*u)
        out.append(texture.eval_1(si) if float_lookup else np.array(texture.eval(si)))
    return np.array(out)
