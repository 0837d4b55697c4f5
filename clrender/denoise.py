"""Denoising with Intel Open Image Denoise (OIDN), through `pyoidn` (the `denoise` extra:
``pip install "clrender[denoise]"``; MIT-licensed bindings shipping OIDN's Apache-2.0 libraries, wheels for any
Python 3 on x86-64 Linux; runs on the CPU).

OIDN's `RT` filter in HDR mode (our images are linear radiance) with the albedo and normal AOVs as guides. Ours are
Monte Carlo estimates, as noisy as the image at low spp, so they are prefiltered first as OIDN's documentation
recommends for noisy guides: each denoised alone by the RT filter (albedo, then normal, as that filter's only
input and output), and the image then filtered with ``cleanAux`` set. Without guides (a film rendered without
feature AOVs) the image is filtered alone.
"""
from __future__ import annotations

import numpy as np

from .errors import ClrenderError

INSTALL = 'pip install "clrender[denoise]"'


def _oidn():
    try:
        import pyoidn
    except ImportError as e:
        raise ClrenderError(f"denoising needs Intel Open Image Denoise, which is not installed ({e}): {INSTALL}") \
            from None
    return pyoidn


def available() -> None:
    """Raise ClrenderError saying what to install when the `denoise` extra is missing."""
    _oidn()


def _check(dev, what: str) -> None:
    err = dev.get_error()
    if err:
        raise ClrenderError(f"Open Image Denoise failed ({what}): {err}")


def _filter(pyoidn, dev, inputs: dict, output: np.ndarray, **flags) -> None:
    f = pyoidn.Filter(dev, pyoidn.OIDN_FILTER_TYPE_RT)
    try:
        for name, img in inputs.items():
            f.set_image(name, img, pyoidn.OIDN_FORMAT_FLOAT3)
        f.set_image(pyoidn.OIDN_IMAGE_OUTPUT, output, pyoidn.OIDN_FORMAT_FLOAT3)
        for k, v in flags.items():
            f.set_bool(k, v)
        f.commit()
        _check(dev, "filter setup")
        f.execute()
        _check(dev, "filter")
    finally:
        f.release()


def denoise(color: np.ndarray, albedo: np.ndarray | None = None, normal: np.ndarray | None = None) -> np.ndarray:
    """(H, W, 3) float32: `color` (linear HDR radiance) denoised, guided by `albedo` and `normal` when given (both
    or neither; prefiltered, see the module's docstring)."""
    pyoidn = _oidn()
    if (albedo is None) != (normal is None):
        raise ValueError("give both albedo and normal guides, or neither")
    c32 = lambda a: np.ascontiguousarray(np.nan_to_num(a, nan=0.0, posinf=0.0, neginf=0.0), np.float32)  # noqa: E731
    color = np.maximum(c32(color), 0.0)   # OIDN's HDR input is non-negative
    dev = pyoidn.Device(pyoidn.OIDN_DEVICE_TYPE_CPU)
    try:
        _check(dev, "device")
        dev.commit()
        _check(dev, "device")
        out = np.empty_like(color)
        if albedo is None:
            _filter(pyoidn, dev, {pyoidn.OIDN_IMAGE_COLOR: color}, out, hdr=True)
            return out
        a = np.clip(c32(albedo), 0.0, 1.0)
        n = np.clip(c32(normal), -1.0, 1.0)
        a_clean, n_clean = np.empty_like(a), np.empty_like(n)
        _filter(pyoidn, dev, {pyoidn.OIDN_IMAGE_ALBEDO: a}, a_clean)
        _filter(pyoidn, dev, {pyoidn.OIDN_IMAGE_NORMAL: n}, n_clean)
        _filter(pyoidn, dev, {pyoidn.OIDN_IMAGE_COLOR: color, pyoidn.OIDN_IMAGE_ALBEDO: a_clean,
                              pyoidn.OIDN_IMAGE_NORMAL: n_clean}, out, hdr=True, cleanAux=True)
        return out
    finally:
        dev.release()
