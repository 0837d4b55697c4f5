"""Reading the images that bitmap textures and environment maps name: OpenEXR (through the OpenEXR library),
Radiance RGBE `.hdr` (read here: flat or new-style run-length scanlines) and 8- or 16-bit PNG, 8-bit JPEG (through
Pillow).

`read_image(path)` returns (pixels as float32 H x W x 3, linear): EXR and HDR hold linear values already; 8-bit
and 16-bit images hold sRGB-encoded values, which are decoded unless `raw` (Mitsuba's convention for `bitmap`: 8-bit images
are sRGB unless `raw` is set). Grey images become three equal channels; an alpha channel is dropped.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import SceneError


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function's inverse on values in [0, 1] (IEC 61966-2-1)."""
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def read_image(path, raw: bool = False, location=None) -> np.ndarray:
    path = Path(path)
    if not path.is_file():
        what = "not found" if not path.exists() else "is not a regular file (a folder or a device)"
        raise SceneError(f"image file '{path}' {what}", location)
    suffix = path.suffix.lower()
    try:
        if suffix == ".exr":
            img = _read_exr(path)
        elif suffix in (".hdr", ".rgbe", ".pic"):
            img = _read_rgbe(path)
        elif suffix in (".png", ".jpg", ".jpeg"):
            img = _read_8bit(path, raw)
        else:
            raise SceneError(f"'{path.name}': unsupported image format '{suffix}'; expected .exr, .hdr, .png, "
                             ".jpg or .jpeg", location)
    except SceneError:
        raise
    except MemoryError:
        raise SceneError(f"image '{path}' is too large for the host memory", location) from None
    except Exception as exc:  # OpenEXR raises RuntimeError for a corrupt file, Pillow its DecompressionBombError
        raise SceneError(f"cannot read image '{path}': {exc}", location) from None
    if not np.all(np.isfinite(img)):
        raise SceneError(f"image '{path}' holds NaN or infinite values", location)
    return img


def _read_exr(path: Path) -> np.ndarray:
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        if "RGB" in ch or "RGBA" in ch:
            img = np.asarray((ch.get("RGB") or ch["RGBA"]).pixels, np.float32)[..., :3]
        elif all(c in ch for c in "RGB"):
            img = np.stack([np.asarray(ch[c].pixels, np.float32) for c in "RGB"], axis=-1)
        elif "Y" in ch:
            img = np.repeat(np.asarray(ch["Y"].pixels, np.float32)[..., None], 3, axis=-1)
        else:
            raise ValueError(f"no R, G, B (or Y) channels; it has {sorted(ch)}")
    return np.ascontiguousarray(img, np.float32)


def _read_8bit(path: Path, raw: bool) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as im:
        wide = True
        if im.mode in ("I;16", "I;16L", "I;16B") or (im.mode == "I" and path.suffix.lower() == ".png"):  # 16-bit grey
            a = np.repeat((np.asarray(im, np.float64) / 65535.0)[..., None], 3, axis=-1)
        elif im.mode not in ("L", "LA", "RGB", "RGBA", "P"):
            raise ValueError(f"only 8- or 16-bit grey or RGB images are supported, this one is mode {im.mode}")
        elif _png16_layout(im) is not None:
            a = _read_png16(path)
        else:
            a, wide = np.asarray(im.convert("RGB"), np.float64) / 255.0, False
    a = a if raw else srgb_to_linear(a)
    # Mitsuba keeps a 16-bit image's (decoded) values as half floats (checked against Mitsuba 3.9.1's bitmap)
    return (a.astype(np.float16) if wide else a).astype(np.float32)


#: 16-bit colour PNG sample layouts that Pillow decodes to 8 bits (its high bytes). (16-bit grey + alpha, which
#: Pillow has no little-endian unpacker for, is read at 8 bits.)
_PNG16 = ("RGB;16B", "RGBA;16B")


def _png16_layout(im):
    tile = getattr(im, "tile", None)
    if im.format != "PNG" or not tile or len(tile) != 1:
        return None
    return tile[0].args if tile[0].args in _PNG16 else None


def _read_png16(path: Path) -> np.ndarray:
    """A 16-bit colour PNG at full precision, as RGB in [0, 1]. Pillow has no 16-bit colour mode: it unfilters the
    rows as 16-bit data, then keeps one byte of each sample; reading the file twice, keeping the high bytes
    (big-endian unpacking) and then the low ones (little-endian unpacking), gives both."""
    from PIL import Image

    halves = []
    for order in ("B", "L"):
        with Image.open(path) as im:
            im.tile = [im.tile[0]._replace(args=_png16_layout(im)[:-1] + order)]
            im.load()
            halves.append(np.asarray(im, np.float64)[..., :3])
    return (halves[0] * 256.0 + halves[1]) / 65535.0


def _read_rgbe(path: Path) -> np.ndarray:
    data = path.read_bytes()
    if not (data.startswith(b"#?RADIANCE") or data.startswith(b"#?RGBE")):
        raise ValueError("not a Radiance RGBE file (it must start with #?RADIANCE or #?RGBE)")
    pos = 0
    while True:  # header lines up to an empty line
        end = data.index(b"\n", pos)
        line = data[pos:end].strip()
        pos = end + 1
        if line.startswith(b"FORMAT=") and line != b"FORMAT=32-bit_rle_rgbe":
            raise ValueError(f"unsupported {line.decode(errors='replace')} (only 32-bit_rle_rgbe)")
        if not line:
            break
    end = data.index(b"\n", pos)
    res = data[pos:end].split()
    pos = end + 1
    if len(res) != 4 or res[0] != b"-Y" or res[2] != b"+X":
        raise ValueError(f"unsupported resolution line {b' '.join(res).decode(errors='replace')!r} (only -Y H +X W)")
    h, w = int(res[1]), int(res[3])
    buf = np.frombuffer(data, np.uint8, offset=pos)
    if h < 0 or w < 0 or h * w > 16 * (len(buf) + 1):
        # a run-length scanline stores at least 127 values of a component in 2 bytes: no more than ~16 pixels
        # a byte; a larger claim is a corrupt resolution line, not a reason to allocate it
        raise ValueError(f"the resolution line claims {w} x {h} pixels but only {len(buf)} bytes follow")
    out = np.empty((h, w, 4), np.uint8)
    i = 0
    for y in range(h):
        if 8 <= w < 0x8000 and i + 4 <= len(buf) and buf[i] == 2 and buf[i + 1] == 2 and buf[i + 2] < 128:
            if (int(buf[i + 2]) << 8 | int(buf[i + 3])) != w:
                raise ValueError(f"scanline {y}: run-length width does not match the image width {w}")
            i += 4
            for c in range(4):  # each component run-length encoded in turn
                x = 0
                while x < w:
                    n = int(buf[i])
                    i += 1
                    if n > 128:
                        n -= 128
                        out[y, x:x + n, c] = buf[i]
                        i += 1
                    else:
                        if n == 0 or x + n > w:
                            raise ValueError(f"scanline {y}: bad run")
                        out[y, x:x + n, c] = buf[i:i + n]
                        i += n
                    x += n
        else:  # flat pixels
            if i + 4 * w > len(buf):
                raise ValueError("file ends before its last scanline")
            out[y] = buf[i:i + 4 * w].reshape(w, 4)
            i += 4 * w
    e = out[..., 3].astype(np.int32)
    scale = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)
    return (out[..., :3].astype(np.float64) * scale[..., None]).astype(np.float32)


def write_rgbe(path, img: np.ndarray) -> None:
    """Write linear RGB (H x W x 3) as a flat (not run-length encoded) Radiance file (test assets)."""
    img = np.asarray(img, np.float64)
    h, w, _ = img.shape
    m = img.max(axis=-1)
    mant, e = np.frexp(m)
    rgbe = np.zeros((h, w, 4), np.uint8)
    ok = m > 1e-32
    scale = np.where(ok, mant * 256.0 / np.where(ok, m, 1.0), 0.0)
    rgbe[..., :3] = np.clip(np.floor(img * scale[..., None]), 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(ok, e + 128, 0).astype(np.uint8)
    head = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n".encode()
    Path(path).write_bytes(head + rgbe.tobytes())
