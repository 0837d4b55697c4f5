"""Accumulator EXRs ("parts"): the per-pixel sums of a range of samples, written by
`clrender render --sample-range START:COUNT` and added up by `clrender merge`.

A part holds what the Film holds (sum w*L, sum w, sum (w*L)^2, sample and dropped counts) as EXR channels,
beside an RGB preview of its own samples, and says in its header what it is a part of:

    clrender.kind          "accumulators"
    clrender.scene_hash    content hash of the scene (scenesource.py)
    clrender.seed          the seed
    clrender.sample_start  first sample index, and clrender.sample_count how many per pixel
    clrender.dialect       the Nori dialect the scene was read with ("upstream" when absent)
    clrender.version       clrender's version (samples of different versions need not agree)
    clrender.integrator    the integrator kernel
    clrender.aovs          the layers asked for with --aov (comma-separated; "" when none)

With feature AOVs (albedo, normal, depth, position) it also holds their twelve per-pixel sums as channels
feature.0 .. feature.11 (kernels/feature_aovs.h's layout), which merge adds up like the image's. A splatting
film's part (clrender.film "splat") also holds its sums of w^2 L and w^2 (sum_w2l.R/G/B, sum_w2); parts of the
two films do not merge.

Samples are numbered globally, so parts with disjoint ranges add up to the render of their union.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import ClrenderError
from .film import FEATURE_AOVS, Film, _atomic_write
from .scenesource import DEFAULT_DIALECT

KIND = "accumulators"
_SUM_CHANNELS = {"sum_wl": ("sum_wl.R", "sum_wl.G", "sum_wl.B"), "sum_wl2": ("sum_wl2.R", "sum_wl2.G", "sum_wl2.B")}
#: header fields that every part of one frame must share
MATCHING = ("scene_hash", "seed", "width", "height", "version", "dialect", "integrator", "aovs", "film")
_SPLAT_CHANNELS = ("sum_w2l.R", "sum_w2l.G", "sum_w2l.B")
FEATURE_CHANNELS = tuple(f"feature.{i}" for i in range(12))


class Accumulator:
    """Float64 per-pixel sums, added to in a caller-chosen fixed order (so the result does not depend on
    which task or file arrived first)."""

    def __init__(self, width: int, height: int):
        self.width, self.height = int(width), int(height)
        n = self.width * self.height
        self.sum_wl = np.zeros((n, 3))
        self.sum_w = np.zeros(n)
        self.sum_wl2 = np.zeros((n, 3))
        self.count = np.zeros(n, np.int64)
        self.dropped = np.zeros(n, np.int64)
        self.features = None   # (n, 12) once a film with feature AOVs is added
        self.sum_w2l = self.sum_w2 = None   # once a splatting film is added (film.py)

    def add_raw(self, p0: int, acc: dict) -> None:
        """Add the device's accumulators of pixels p0.. (Renderer.render_accumulators), read as a Film of them
        reads them (pixels whose float32 sums overflowed: dropped and counted)."""
        self.add_film(Film.from_accumulators(len(acc["acc0"]), 1, acc), p0)

    def add_film(self, film: Film, p0: int = 0) -> None:
        """Add a film's sums to pixels p0.. (a whole film, or a band of its pixels)."""
        p1 = p0 + film.width * film.height
        self.sum_wl[p0:p1] += film.sum_wl.reshape(-1, 3)
        self.sum_w[p0:p1] += film.sum_w.reshape(-1)
        self.sum_wl2[p0:p1] += film.sum_wl2.reshape(-1, 3)
        self.count[p0:p1] += np.rint(film.count.reshape(-1)).astype(np.int64)
        self.dropped[p0:p1] += film.dropped.reshape(-1).astype(np.int64)
        if film.features is not None:
            if self.features is None:
                self.features = np.zeros((self.width * self.height, 12))
            self.features[p0:p1] += film.features.reshape(-1, 12)
        if film.sum_w2 is not None:
            if self.sum_w2 is None:
                self.sum_w2l, self.sum_w2 = np.zeros((len(self.sum_w), 3)), np.zeros(len(self.sum_w))
            self.sum_w2l[p0:p1] += film.sum_w2l.reshape(-1, 3)
            self.sum_w2[p0:p1] += film.sum_w2.reshape(-1)

    def film(self, metadata: dict) -> Film:
        h, w = self.height, self.width
        return Film(w, h, self.sum_wl.reshape(h, w, 3).copy(), self.sum_w.reshape(h, w).copy(),
                    self.sum_wl2.reshape(h, w, 3).copy(), self.count.reshape(h, w).copy(),
                    self.dropped.reshape(h, w).copy(), dict(metadata),
                    features=None if self.features is None else self.features.reshape(h, w, 12).copy(),
                    sum_w2l=None if self.sum_w2 is None else self.sum_w2l.reshape(h, w, 3).copy(),
                    sum_w2=None if self.sum_w2 is None else self.sum_w2.reshape(h, w).copy())


def write_part(film: Film, path, scene_hash: str, seed: int, sample_start: int, sample_count: int,
               dialect: str = DEFAULT_DIALECT, extra: dict | None = None) -> Path:
    """Write `film` (samples sample_start .. sample_start+sample_count-1) as an accumulator EXR."""
    import OpenEXR

    from .version import __version__

    meta = {"kind": KIND, "scene_hash": scene_hash, "seed": int(seed), "sample_start": int(sample_start),
            "sample_count": int(sample_count), "dialect": dialect or DEFAULT_DIALECT, "version": __version__,
            "integrator": film.metadata.get("integrator", ""), "width": film.width, "height": film.height,
            "aovs": ",".join(film.layers), "film": film.metadata.get("film", "sampling")}
    for k, v in (extra or {}).items():
        meta.setdefault(k, v)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for k, v in meta.items():
        header[f"clrender.{k}"] = str(v)
    f32 = lambda a: np.ascontiguousarray(a, np.float32)  # noqa: E731  (fresh contiguous copies: see film.py)
    channels = {"RGB": f32(film.image), "sum_w": f32(film.sum_w),
                "count": np.ascontiguousarray(np.rint(film.count), np.uint32),
                "dropped": np.ascontiguousarray(film.dropped, np.uint32)}
    for name in _SUM_CHANNELS:  # (H, W, 3) arrays are written as channels NAME.R, NAME.G, NAME.B
        channels[name] = f32(getattr(film, name))
    if film.features is not None:
        for i, name in enumerate(FEATURE_CHANNELS):
            channels[name] = f32(film.features[..., i])
    if film.sum_w2 is not None:
        channels["sum_w2l"] = f32(film.sum_w2l)
        channels["sum_w2"] = f32(film.sum_w2)
    return _atomic_write(Path(path), lambda tmp: OpenEXR.File(header, channels).write(str(tmp)))


@dataclass
class Part:
    path: str
    meta: dict
    film: Film

    @property
    def start(self) -> int:
        return int(self.meta["sample_start"])

    @property
    def stop(self) -> int:
        return self.start + int(self.meta["sample_count"])


def read_part(path) -> Part:
    """Read an accumulator EXR; a clear ClrenderError if it is not one."""
    import OpenEXR

    path = str(path)
    try:
        with OpenEXR.File(path) as f:
            header = dict(f.header())
            ch = {k: np.array(v.pixels) for k, v in f.channels().items()}
    except Exception as exc:  # OpenEXR raises plain Exceptions for missing or corrupt files
        raise ClrenderError(f"{path}: cannot read as EXR ({exc})") from None
    meta = {k[len("clrender."):]: v for k, v in header.items() if k.startswith("clrender.")}
    if meta.get("kind") != KIND:
        raise ClrenderError(f"{path}: not an accumulator EXR (written by `clrender render --sample-range`); "
                            "a plain image holds no sample counts and cannot be merged")
    meta.setdefault("dialect", DEFAULT_DIALECT)  # parts written before the dialect was recorded
    meta.setdefault("aovs", "")  # and before the layers were
    meta.setdefault("film", "sampling")  # and before films could splat
    for name, names in _SUM_CHANNELS.items():  # OpenEXR groups NAME.R/G/B into one (H, W, 3) array
        if name not in ch and all(c in ch for c in names):
            ch[name] = np.stack([ch[c] for c in names], -1)
    need = ["sum_w", "count", "dropped"] + list(_SUM_CHANNELS)
    missing = [c for c in need if c not in ch or (c in _SUM_CHANNELS and ch[c].ndim != 3)]
    if missing:
        raise ClrenderError(f"{path}: accumulator EXR lacks channel(s) {', '.join(missing)}")
    for key in ("seed", "sample_start", "sample_count", "width", "height"):
        try:
            meta[key] = int(meta[key])
        except (KeyError, ValueError):
            raise ClrenderError(f"{path}: header field clrender.{key} is missing or not an integer") from None
    h, w = ch["sum_w"].shape
    if (w, h) != (meta["width"], meta["height"]):
        raise ClrenderError(f"{path}: the header says {meta['width']}x{meta['height']}, the pixels are {w}x{h}")
    features = None
    if any(c in ch for c in FEATURE_CHANNELS):
        if not all(c in ch for c in FEATURE_CHANNELS):
            raise ClrenderError(f"{path}: accumulator EXR has some feature AOV channels but not all twelve")
        features = np.stack([ch[c] for c in FEATURE_CHANNELS], -1).astype(np.float64)
    splat = None
    if meta["film"] == "splat":
        if "sum_w2l" not in ch and all(c in ch for c in _SPLAT_CHANNELS):
            ch["sum_w2l"] = np.stack([ch[c] for c in _SPLAT_CHANNELS], -1)
        if "sum_w2l" not in ch or ch["sum_w2l"].ndim != 3 or "sum_w2" not in ch:
            raise ClrenderError(f"{path}: a splatting film's accumulator EXR lacks its sum_w2l/sum_w2 channels")
        splat = ch["sum_w2l"].astype(np.float64), ch["sum_w2"].astype(np.float64)
    film = Film(w, h, ch["sum_wl"].astype(np.float64), ch["sum_w"].astype(np.float64),
                ch["sum_wl2"].astype(np.float64),
                ch["count"].astype(np.int64), ch["dropped"].astype(np.int64), dict(meta), features=features,
                sum_w2l=None if splat is None else splat[0], sum_w2=None if splat is None else splat[1])
    return Part(path, meta, film)


def format_ranges(ranges) -> str:
    """[(start, stop), ...] as 'START..LAST' items, e.g. '0..15, 32..47'."""
    return ", ".join(f"{a}..{b - 1}" if b - a > 1 else f"{a}" for a, b in ranges)


def merge_parts(parts: list[Part], allow_missing: bool = False) -> Film:
    """Check that the parts belong together and add them (in order of their sample ranges)."""
    if not parts:
        raise ClrenderError("merge needs at least one part")
    first = parts[0]
    for p in parts[1:]:
        for key in MATCHING:
            if str(p.meta.get(key)) != str(first.meta.get(key)):
                raise ClrenderError(f"{p.path} does not belong with {first.path}: {key} is "
                                    f"{p.meta.get(key)!r} there and {first.meta.get(key)!r} here")
    parts = sorted(parts, key=lambda p: (p.start, p.stop))
    for a, b in zip(parts, parts[1:]):
        if b.start < a.stop:
            raise ClrenderError(f"{b.path} (samples {format_ranges([(b.start, b.stop)])}) overlaps {a.path} "
                                f"(samples {format_ranges([(a.start, a.stop)])}): each sample may be merged once")
    problems = []
    for p in parts:  # an interrupted or time-limited job wrote fewer samples than its range
        lo = int(p.film.count.min()) if p.film.count.size else 0
        if lo < p.stop - p.start:
            problems.append(f"{p.path} holds only {lo} of its {p.stop - p.start} samples in some pixels "
                            f"(an interrupted render)")
    gaps, at = [], 0
    for p in parts:
        if p.start > at:
            gaps.append((at, p.start))
        at = max(at, p.stop)
    if gaps:
        problems.insert(0, f"samples {format_ranges(gaps)} are missing (no part covers them)")
    if problems and not allow_missing:
        raise ClrenderError("; ".join(problems) + " (render the missing ranges, or pass --partial to merge anyway)")
    acc = Accumulator(first.film.width, first.film.height)
    for p in parts:
        acc.add_film(p.film)
    spp = int(acc.count.min()) if acc.count.size else 0
    meta = {k: first.meta[k] for k in ("seed", "scene_hash", "version", "dialect", "integrator")}
    if first.meta.get("film") == "splat":
        meta["film"] = "splat"
    meta.update(spp=spp, spp_max=int(acc.count.max()) if acc.count.size else 0,
                sample_ranges=format_ranges([(p.start, p.stop) for p in parts]), parts=len(parts),
                dropped_samples=int(acc.dropped.sum()), missing=format_ranges(gaps) if gaps else "")
    film = acc.film(meta)
    film.layers = tuple(n for n in str(first.meta.get("aovs", "")).split(",") if n)
    if any(n in FEATURE_AOVS for n in film.layers) and film.features is None:
        raise ClrenderError(f"{first.path}: its header names the layers {first.meta['aovs']} but the parts hold no "
                            "feature AOV channels")
    return film
