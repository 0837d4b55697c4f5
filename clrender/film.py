"""The film: per-pixel sums downloaded from the device, their image, and writing it (EXR + PNG, atomically).

Per pixel we hold sum(w L), sum(w), sum((w L)^2) and the sample count, so the film knows its own noise:
`variance()` is the variance of each pixel's mean, used by z-tests and for merging partial renders.
"""
from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


#: the layers a film can write beside its image (Film.aov); the first four are rendered by kernels/feature_aovs.h
FEATURE_AOVS = ("albedo", "normal", "depth", "position")
AOVS = FEATURE_AOVS + ("variance", "count")


@dataclass
class Film:
    width: int
    height: int
    sum_wl: np.ndarray        # (H, W, 3) float64
    sum_w: np.ndarray         # (H, W)
    sum_wl2: np.ndarray       # (H, W, 3)
    count: np.ndarray         # (H, W) samples that were accumulated
    dropped: np.ndarray       # (H, W) samples dropped for NaN/Inf
    metadata: dict = field(default_factory=dict)
    #: layers write_exr adds beside RGB (names aov() knows): an adaptive render's film has ("count",)
    layers: tuple = ()
    #: (H, W, 12) sums of the feature AOVs (kernels/feature_aovs.h) when the Renderer rendered them, else None
    features: np.ndarray | None = None
    #: a splatting film's (kernels/splat.cl) sums of w^2 L (H, W, 3) and w^2 (H, W), else None: its samples
    #: reach several pixels with unequal weights, and variance() needs them
    sum_w2l: np.ndarray | None = None
    sum_w2: np.ndarray | None = None

    def __post_init__(self) -> None:
        # Finite samples of absurd size (a reflectance of 3e38) overflow a pixel's float32 sums on the device, which
        # would write inf to the image: drop that pixel's samples, as the kernel drops NaN/Inf ones, and count them.
        with np.errstate(invalid="ignore"):
            bad = ~(np.isfinite(self.sum_wl).all(axis=-1) & np.isfinite(self.sum_w))
        if bad.any():
            self.dropped = self.dropped + np.where(bad, self.count, 0).astype(np.asarray(self.dropped).dtype)
            for a in (self.sum_wl, self.sum_wl2, self.sum_w, self.count, self.sum_w2l, self.sum_w2):
                if a is not None:
                    a[bad] = 0
            if "dropped_samples" in self.metadata:
                self.metadata["dropped_samples"] = int(self.dropped.sum())

    @classmethod
    def from_accumulators(cls, width, height, acc, metadata=None):
        """From the device's accumulators ``acc`` ({name: array} of clrender/device/layout.py FILM_ACCUMULATORS, one
        element per pixel): acc0 = (sum wL, sum w), acc1 = (sum (wL)^2, count), bad = dropped samples."""
        n = width * height
        a0 = acc["acc0"][:n].astype(np.float64).reshape(height, width, 4)
        a1 = acc["acc1"][:n].astype(np.float64).reshape(height, width, 4)
        a2 = acc["acc2"][:n].astype(np.float64).reshape(height, width, 4) if "acc2" in acc else None
        return cls(width, height, a0[..., :3], a0[..., 3], a1[..., :3], a1[..., 3],
                   acc["bad"][:n].reshape(height, width).astype(np.int64), dict(metadata or {}),
                   sum_w2l=None if a2 is None else a2[..., :3], sum_w2=None if a2 is None else a2[..., 3])

    @property
    def image(self) -> np.ndarray:
        """(H, W, 3) float32 linear radiance: sum(w L) / sum(w); 0 where no weight arrived."""
        w = self.sum_w[..., None]
        with np.errstate(invalid="ignore", divide="ignore"):
            img = np.where(w != 0, self.sum_wl / np.where(w != 0, w, 1), 0.0)
        # a sum near float32's limit over a filter weight below 1 must not become inf in the float32 image
        big = float(np.finfo(np.float32).max)
        return np.clip(img, -big, big).astype(np.float32)

    def variance(self) -> np.ndarray:
        """Variance of each pixel's estimate (H, W, 3), treating sum(wL)/n as the mean of n samples
        (exact for filters with constant weight, a close approximation otherwise). A splatting film's: that of
        the ratio V = sum(w L) / sum(w) over the samples that reach the pixel, to first order,
        sum(w^2 (L - V)^2) / sum(w)^2, times n / (n - 1) for the effective count n = sum(w)^2 / sum(w^2)."""
        if self.sum_w2 is not None:
            return self._splat_variance()
        n = np.maximum(self.count, 1)[..., None]
        mean = self.sum_wl / n
        var = np.maximum(self.sum_wl2 / n - mean * mean, 0.0)
        scale = np.where(self.sum_w[..., None] != 0, n / np.where(self.sum_w[..., None] != 0,
                                                                    self.sum_w[..., None], 1), 0.0)
        return var / np.maximum(n - 1, 1) * scale * scale

    def _splat_variance(self) -> np.ndarray:
        w = self.sum_w[..., None]
        w2 = self.sum_w2[..., None]
        ok = (w != 0) & (w2 != 0)
        with np.errstate(invalid="ignore", divide="ignore"):
            v = np.where(ok, self.sum_wl / np.where(ok, w, 1), 0.0)
            ss = np.maximum(self.sum_wl2 - 2.0 * v * self.sum_w2l + v * v * w2, 0.0)
            n_eff = np.where(ok, w * w / np.where(ok, w2, 1), 0.0)
            var = np.where(ok & (n_eff > 1.0), ss / np.where(ok, w * w, 1) * n_eff / np.maximum(n_eff - 1.0, 1e-12),
                           0.0)
        return var

    def aov(self, name: str) -> np.ndarray:
        """A layer beside the image, (H, W, 3) or (H, W) float32 (names: AOVS):
        - ``albedo``, ``normal``: of the first non-specular surface the camera sample meets (through mirrors and
          glass, tinted by them): the BSDF's directional reflectance estimate and the world-space shading normal
          (the pixel's mean: shorter than 1 where a pixel straddles an edge); what Open Image Denoise takes;
        - ``depth``, ``position``: of the camera ray's first hit (depth from the near clip plane, as Mitsuba's);
          zero where the ray escapes;
        - ``variance``: variance(), of the pixel's estimate; ``count``: the samples each pixel holds.
        The first four need a Renderer made with ``feature_aovs=True``."""
        if name == "variance":
            return self.variance().astype(np.float32)
        if name == "count":
            return np.asarray(self.count, np.float32)
        if name not in FEATURE_AOVS:
            raise ValueError(f"unknown AOV {name!r}: expected one of {', '.join(AOVS)}")
        if self.features is None:
            raise ValueError(f"this film has no {name} AOV: render with feature AOVs (--aov {name}, "
                             f"Renderer(..., feature_aovs=True))")
        f = self.features
        w = f[..., 7:8]
        sl = {"albedo": slice(0, 3), "depth": slice(3, 4), "normal": slice(4, 7), "position": slice(8, 11)}[name]
        with np.errstate(invalid="ignore", divide="ignore"):
            out = np.where(w != 0, f[..., sl] / np.where(w != 0, w, 1), 0.0)
        return (out[..., 0] if name == "depth" else out).astype(np.float32)

    def denoised(self) -> np.ndarray:
        """(H, W, 3) float32: the image denoised by Open Image Denoise (clrender/denoise.py; the `denoise` extra),
        guided by the albedo and normal AOVs when the film has them."""
        from .denoise import denoise

        if self.features is None:
            return denoise(self.image)
        return denoise(self.image, self.aov("albedo"), self.aov("normal"))

    @property
    def spp(self) -> int:
        return int(self.metadata.get("spp", int(self.count.max()) if self.count.size else 0))

    # -- output -------------------------------------------------------------------------------------------
    def write(self, path) -> Path:
        """Write the image in the format its extension names: .png, .jpg/.jpeg (8-bit sRGB), .hdr (Radiance RGBE),
        .pfm (float), anything else OpenEXR with the metadata."""
        suffix = Path(path).suffix.lower()
        if suffix == ".png":
            return self.write_png(path)
        if suffix in (".jpg", ".jpeg"):
            from PIL import Image

            srgb = Image.fromarray(to_srgb8(self.image))
            # full-resolution chroma (4:4:4): a render's coloured edges and noise survive
            return _atomic_write(Path(path), lambda tmp: srgb.save(tmp, format="JPEG", quality=95, subsampling=0))
        if suffix in (".hdr", ".pfm"):
            from .textures.imagefile import write_pfm, write_rgbe

            img = self.image
            return _atomic_write(Path(path), lambda tmp: (write_rgbe if suffix == ".hdr" else write_pfm)(tmp, img))
        return self.write_exr(path)

    def write_exr(self, path, image: np.ndarray | None = None) -> Path:
        """The image (or `image` in its place: a denoised one) and the film's layers, as an EXR with the metadata."""
        import OpenEXR

        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        for k, v in self.metadata.items():
            header[f"clrender.{k}"] = str(v)
        # OpenEXR 3.x writes non-contiguous arrays wrongly without an error: always hand it a fresh copy.
        channels = {"RGB": np.ascontiguousarray(self.image if image is None else image, dtype=np.float32)}
        for name in self.layers:   # (H, W, 3) layers become channels NAME.R, NAME.G, NAME.B
            channels[name] = np.ascontiguousarray(self.aov(name), dtype=np.float32)
        prefix = getattr(self, "moment", None)
        if prefix:   # a `moment` integrator's (integrators/moment.py; box filter: every w is 1)
            m2 = self.second_moment()
            for i, c in enumerate("RGB"):
                channels[f"{prefix}.{c}"] = np.ascontiguousarray(m2[..., i])
        for name, values in (getattr(self, "aovs", None) or {}).items():   # renderer.aov_channels
            channels[name] = np.ascontiguousarray(values, np.float32)
        return _atomic_write(Path(path), lambda tmp: OpenEXR.File(header, channels).write(str(tmp)))

    def second_moment(self) -> np.ndarray:
        """(H, W, 3) float32 sum((w L)^2) / sum(w): with weights of 1 (a box filter) each pixel's mean of its
        samples' squares, Mitsuba's `moment` m2; 0 where no weight arrived."""
        w = self.sum_w[..., None]
        with np.errstate(invalid="ignore", divide="ignore"):
            m2 = np.where(w != 0, self.sum_wl2 / np.where(w != 0, w, 1), 0.0)
        big = float(np.finfo(np.float32).max)
        return np.clip(m2, -big, big).astype(np.float32)

    def write_png(self, path, image: np.ndarray | None = None) -> Path:
        """The sRGB 8-bit image (or `image` in its place), or the scene's own tone map where its film has one
        (``tonemap``, set by the renderer from e.g. an ``ldrfilm``)."""
        from .png import encode_png

        data = encode_png((getattr(self, "tonemap", None) or to_srgb8)(self.image if image is None else image))
        return _atomic_write(Path(path), lambda tmp: tmp.write_bytes(data))


def to_srgb8(img: np.ndarray) -> np.ndarray:
    x = np.clip(np.nan_to_num(img.astype(np.float64), nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.clip(np.round(srgb * 255.0), 0, 255).astype(np.uint8)


def read_exr(path) -> tuple[np.ndarray, dict]:
    """(H, W, 3) float32 and the header of an EXR written by clrender (or any RGB EXR)."""
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        ch = f.channels()
        if "RGB" in ch:
            img = ch["RGB"].pixels
        else:
            img = np.stack([ch[c].pixels for c in "RGB"], axis=-1)
        return np.array(img, np.float32), dict(f.header())


def _umask() -> int:
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    old = os.umask(0o022)  # no /proc: read it by setting it (and put it back at once)
    os.umask(old)
    return old


def _atomic_write(path: Path, write) -> Path:
    """Write through a temporary file in the same folder, then rename: readers never see half a file."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=str(path.parent))
    except OSError as e:  # name the user's file, not our temporary one
        raise OSError(e.errno, f"cannot write '{path}': {e.strerror or e}") from None
    try:
        # mkstemp makes 0600 files; the image gets the permissions any tool would give it (0644 under umask 022)
        os.fchmod(fd, 0o666 & ~_umask())
        os.close(fd)
        write(Path(tmp))
        os.replace(tmp, path)
    except BaseException as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(e, OSError):  # name the user's file, not our temporary one
            raise OSError(e.errno, f"cannot write '{path}': {e.strerror or e}") from None
        raise
    return path
