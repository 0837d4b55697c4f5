"""Reading the images that bitmap textures and environment maps name, by their content (as Mitsuba's `Bitmap`
detects them), not their extension:

- OpenEXR: through the OpenEXR library;
- PNG, JPEG, BMP, TGA, PPM/PGM/PBM, TIFF and greyscale PFM: through Pillow (16-bit colour PNG, TIFF and PPM, which
  Pillow decodes to 8 bits, at full precision: see `_read_wide`);
- Radiance RGBE (`.hdr`) and colour PFM, which none of the allowed libraries reads (Pillow reads greyscale PFM
  only; OpenEXR neither): the small readers below, after the formats' descriptions (Greg Ward's RGBE with flat or
  new-style run-length scanlines; PFM: "PF" or "Pf", width, height, a scale whose sign gives the byte order
  (negative: little-endian) and whose magnitude multiplies the values, as Mitsuba applies it; rows bottom-up).

`read_image(path)` returns (pixels as float32 H x W x 3, linear). Mitsuba's conventions: EXR, HDR, PFM and float
TIFF hold linear values; 8- and 16-bit images hold sRGB-encoded values, which are decoded unless `raw`. A 16-bit
image's (decoded) values are kept as half floats, as Mitsuba's `bitmap` texture stores them (`half=False`: as
float32, as its `envmap` does). Grey images become three equal channels; an alpha channel is dropped, as Mitsuba's
`bitmap` and `envmap` drop it (colours as stored, not divided by alpha).

`storage` is the bitmap texture's `format` (Mitsuba 3.9.1's src/textures/bitmap.cpp, values checked against its
own lookups): `auto` as above (Mitsuba keeps 8-bit images as bytes decoded texel by texel, the same values);
`variant` float32 throughout (a 16-bit image not rounded to half); `float16` every value rounded to half after
decoding; `uint8` every channel as a byte: an 8-bit image as it is, a 16-bit one's (encoded) values and a float
image's linear ones, clamped to [0, 1], to the nearest 1/255 (Mitsuba dithers there, so its texels differ from
these by one step at most, about half of them near a half step).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import SceneError, git_lfs_hint

#: the bitmap texture's `format`s (Mitsuba 3.9.1's; "fp16", its old name for float16, is read as float16)
STORAGE = ("auto", "variant", "float16", "uint8")
#: Pillow's names of the formats we read through it (Mitsuba 3.9.1 reads PNG, JPEG, BMP, TGA, PPM; TIFF is ours).
PILLOW_FORMATS = ("PNG", "JPEG", "BMP", "TGA", "PPM", "TIFF")
EXR_MAGIC = b"\x76\x2f\x31\x01"
FORMATS_SAID = "OpenEXR, Radiance HDR, PFM, PNG, JPEG, BMP, TGA, PPM/PGM or TIFF"


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """The sRGB transfer function's inverse on values in [0, 1] (IEC 61966-2-1)."""
    x = np.asarray(x, np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def read_image(path, raw: bool = False, location=None, half: bool = True, storage: str = "auto") -> np.ndarray:
    """The image's pixels, linear float32 (H, W, 3); ``half``: an `auto` 16-bit image's values rounded to half floats
    (the bitmap texture's, not the envmap's); ``storage``: the bitmap's `format` (see the module's docstring)."""
    if storage == "variant":
        half = False
    path = Path(path)
    if not path.is_file():
        what = "not found" if not path.exists() else "is not a regular file (a folder or a device)"
        raise SceneError(f"image file '{path}' {what}", location)
    try:
        with open(path, "rb") as f:
            head = f.read(4)
        linear = True   # float values (not 8 or 16 bits): what `float16` and `uint8` storage round
        if head == EXR_MAGIC:
            img = _read_exr(path)
        elif head[:2] == b"#?":
            img = _read_rgbe(path)
        elif head[:2] == b"PF":
            img = _read_pfm(path)
        else:
            img, linear = _read_pillow(path, raw, half, location, storage)
        if linear and storage == "float16":
            img = img.astype(np.float16).astype(np.float32)
        elif linear and storage == "uint8":
            img = _to_bytes(img).astype(np.float32)
    except SceneError:
        raise
    except MemoryError:
        raise SceneError(f"image '{path}' is too large for the host memory", location) from None
    except Exception as exc:  # OpenEXR raises RuntimeError for a corrupt file, Pillow its DecompressionBombError
        raise SceneError(f"cannot read image '{path}': {exc}", location) from None
    if img.shape[0] < 1 or img.shape[1] < 1:
        raise SceneError(f"image '{path}' holds no pixels", location)
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


def _to_bytes(a: np.ndarray) -> np.ndarray:
    """Values clamped to [0, 1] and rounded to the nearest 1/255 (8-bit storage)."""
    return np.round(np.clip(np.asarray(a, np.float64), 0.0, 1.0) * 255.0) / 255.0


def _read_pillow(path: Path, raw: bool, half: bool, location, storage: str = "auto") -> tuple[np.ndarray, bool]:
    """(pixels, whether they are float values rather than 8- or 16-bit ones)."""
    from PIL import Image, UnidentifiedImageError

    try:
        im = Image.open(path, formats=PILLOW_FORMATS)
    except UnidentifiedImageError:
        with open(path, "rb") as f:
            lfs = git_lfs_hint(f.read(64))
        raise SceneError(f"cannot read image '{path}': unsupported image format (its content is none of "
                         f"{FORMATS_SAID}){lfs}", location) from None
    with im:
        if im.mode == "F":   # greyscale PFM (Pillow gives its scale's magnitude), float TIFF: linear already
            a = np.asarray(im, np.float64) * im.info.get("scale", 1.0)
            return np.repeat(a[..., None], 3, axis=-1).astype(np.float32), True
        wide = True
        if im.mode.startswith("I;16") or (im.mode == "I" and im.format in ("PNG", "PPM")):   # 16-bit grey
            a = np.repeat((np.asarray(im, np.float64) / 65535.0)[..., None], 3, axis=-1)
        elif im.mode in ("I", "I;32", "RGBX;16"):
            raise ValueError(f"only 8- or 16-bit integer or float images are supported, this one is mode {im.mode}")
        elif (wide_rgb := _read_wide(path, im)) is not None:
            a = wide_rgb
        else:   # 1-, 8-bit grey (+ alpha), palette, RGB(A), CMYK: 8 bits a channel
            a, wide = np.asarray(im.convert("RGB"), np.float64) / 255.0, False
    if wide and storage == "uint8":   # the encoded values as bytes, decoded at lookup as Mitsuba does
        a = _to_bytes(a)
    a = a if raw else srgb_to_linear(a)
    # Mitsuba's bitmap keeps a 16-bit image's (decoded) values as half floats (checked against Mitsuba 3.9.1's bitmap)
    rounded = (wide and half and storage == "auto") or storage == "float16"
    return (a.astype(np.float16) if rounded else a).astype(np.float32), False


#: Raw modes of 16-bit colour samples that Pillow decodes to 8 bits (keeping the high byte of each), and the raw
#: mode of the other byte order. (16-bit grey + alpha, which Pillow has no unpacker for, is read at 8 bits.)
_WIDE = {"RGB;16B": "RGB;16L", "RGBA;16B": "RGBA;16L", "RGB;16L": "RGB;16B", "RGBA;16L": "RGBA;16B"}


def _read_wide(path: Path, im) -> np.ndarray | None:
    """A 16-bit colour image at full precision, as RGB in [0, 1]; None if `im` is not one. Pillow has no 16-bit
    colour mode: it decodes (unfilters, decompresses) the samples as 16-bit data, then keeps one byte of each.
    Decoding the file twice, with its own byte order and then the other one, gives both bytes. A binary 16-bit PPM
    (maxval above 255), which Pillow rescales to 8 bits, is big-endian samples after the header Pillow parsed."""
    from PIL import Image

    tile = getattr(im, "tile", None)
    if not tile or len(tile) != 1:
        return None
    t = tile[0]
    if im.format == "PPM" and t.codec_name == "ppm" and isinstance(t.args, tuple) and t.args[1] > 255:
        h, w = im.size[1], im.size[0]
        n = h * w * len(im.mode)
        data = np.fromfile(path, ">u2", count=n, offset=t.offset)
        if data.size != n:
            raise ValueError(f"the file ends before its {n} samples")
        return data.reshape(h, w, len(im.mode))[..., :3] / float(t.args[1])
    args = t.args if isinstance(t.args, tuple) else (t.args,)
    if not args or args[0] not in _WIDE:
        return None
    own = args[0]
    halves = []
    for rawmode in (own, _WIDE[own]):   # the high bytes, then the low ones
        with Image.open(path, formats=(im.format,)) as again:
            t2 = again.tile[0]
            a2 = t2.args if isinstance(t2.args, tuple) else (t2.args,)
            new = (rawmode,) + a2[1:]
            again.tile = [t2._replace(args=new if isinstance(t2.args, tuple) else rawmode)]
            again.load()
            halves.append(np.asarray(again, np.float64)[..., :3])
    return (halves[0] * 256.0 + halves[1]) / 65535.0


def _read_pfm(path: Path) -> np.ndarray:
    """A colour PFM ("PF"; greyscale "Pf" goes through Pillow)."""
    data = path.read_bytes()
    fields, pos = [], 0
    while len(fields) < 4:   # magic, width, height, scale: separated by whitespace, one whitespace byte after scale
        while pos < len(data) and data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while pos < len(data) and not data[pos:pos + 1].isspace():
            pos += 1
        if start == pos or pos - start > 32:
            raise ValueError("not a PFM header (PF, width, height, scale)")
        fields.append(data[start:pos])
    pos += 1
    if fields[0] != b"PF":
        raise ValueError("not a PFM header (PF, width, height, scale)")
    try:
        w, h, scale = int(fields[1]), int(fields[2]), float(fields[3])
    except ValueError:
        raise ValueError(f"cannot parse the PFM header {b' '.join(fields).decode(errors='replace')!r}") from None
    if w < 0 or h < 0 or scale == 0 or not np.isfinite(scale):
        raise ValueError(f"bad PFM header {b' '.join(fields).decode(errors='replace')!r}")
    n = w * h * 3
    if len(data) - pos < 4 * n:
        raise ValueError(f"the file ends before its {w} x {h} pixels")
    px = np.frombuffer(data, "<f4" if scale < 0 else ">f4", count=n, offset=pos).reshape(h, w, 3)
    return (px[::-1].astype(np.float64) * abs(scale)).astype(np.float32)


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
    """Write linear RGB (H x W x 3) as a flat (not run-length encoded) Radiance file (`-o NAME.hdr`, test assets).
    Negative values become 0, values beyond RGBE's largest (2^127 · 255/256) that largest."""
    img = np.clip(np.asarray(img, np.float64), 0.0, 2.0 ** 127 * 255 / 256)
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


def write_pfm(path, img: np.ndarray) -> None:
    """Write linear RGB (H x W x 3) as a little-endian colour PFM (scale -1, bottom row first)."""
    img = np.asarray(img, np.float32)
    h, w, _ = img.shape
    Path(path).write_bytes(f"PF\n{w} {h}\n-1\n".encode() + np.ascontiguousarray(img[::-1], "<f4").tobytes())
