"""A ``wavelength:value`` spectrum as the RGB that Mitsuba 3's RGB variants give it.

Mitsuba's RGB variants pre-integrate a tabulated spectrum when they read the scene: the piecewise-linear spectrum
(zero outside its first and last wavelength) is sampled at 1000 evenly spaced wavelengths over the CIE range
360..830 nm, weighted by the CIE 1931 colour matching functions (linearly interpolated from the 5 nm table), and
the XYZ sum is turned into linear sRGB (Rec. 709 primaries, D65 white). Two contexts differ:

- a reflectance-like parameter (``emitter=False``) is lit by D65: each sample is also weighted by the D65
  illuminant scaled to unit luminance, so a constant spectrum of 1 is (almost exactly) white; the result is
  clamped to [0, 1];
- an emitter's radiance (``emitter=True``) is an equal-energy spectrum scaled to unit luminance per unit value;
  only negative channels are clamped (equal energy is a pinkish white in sRGB).

A single constant is a grey value for a reflectance and ``value * xyz_to_srgb(1, 1, 1)`` for an emitter, which
is what Mitsuba does too.
"""
from __future__ import annotations

import logging

import numpy as np

from .cie_tables import CIE1931_X, CIE1931_Y, CIE1931_Z, CIE_MAX, CIE_MIN, CIE_STEP, D65

log = logging.getLogger("clrender")

#: linear sRGB from CIE XYZ (D65 white)
XYZ_TO_SRGB = np.array([[3.240479, -1.537150, -0.498535],
                        [-0.969256, 1.875991, 0.041556],
                        [0.055648, -0.204043, 1.057311]])
_STEPS = 1000
_GRID = np.arange(95) * CIE_STEP + CIE_MIN
#: 1 / the luminance of the tabulated matching functions and of D65 (each integrated over the table)
Y_NORMALIZATION = 1.0 / 106.7502593994140625
D65_NORMALIZATION = 1.0 / 98.99741751876255


def check_spectrum(wavelengths: np.ndarray, values: np.ndarray) -> None:
    if wavelengths.size < 2:
        raise ValueError("a spectrum needs at least two wavelength:value pairs")
    if np.any(np.diff(wavelengths) <= 0):
        raise ValueError("wavelengths must increase from one pair to the next")
    if not (np.all(np.isfinite(wavelengths)) and np.all(np.isfinite(values))):
        raise ValueError("every wavelength and value must be finite")


def spectrum_to_rgb(wavelengths, values, emitter: bool = False, unbounded: bool = False,
                    warn: bool = True) -> np.ndarray:
    """Linear sRGB of a piecewise-linear spectrum (nanometres, increasing), as Mitsuba's RGB variants compute it;
    ``emitter`` selects the radiance convention (module docstring); ``unbounded`` (e.g. an index of refraction)
    only clamps negative channels; ``warn`` logs a clamped colour."""
    lam = np.asarray(wavelengths, np.float64)
    val = np.asarray(values, np.float64)
    check_spectrum(lam, val)
    w = CIE_MIN + np.arange(_STEPS) / (_STEPS - 1) * (CIE_MAX - CIE_MIN)
    inside = (w >= lam[0]) & (w <= lam[-1])
    w = w[inside]
    v = np.interp(w, lam, val)
    xyz = np.stack([np.interp(w, _GRID, t) for t in (CIE1931_X, CIE1931_Y, CIE1931_Z)], axis=-1)
    weight = v * (Y_NORMALIZATION if emitter else np.interp(w, _GRID, D65) * D65_NORMALIZATION * Y_NORMALIZATION)
    total = (xyz * weight[:, None]).sum(axis=0) * ((CIE_MAX - CIE_MIN) / _STEPS)
    rgb = XYZ_TO_SRGB @ total
    bounded = not (emitter or unbounded)
    if bounded and np.any((rgb < 0) | (rgb > 1)):
        if warn:
                log.warning("spectrum %s is outside the sRGB gamut: clamped to [0, 1] (as Mitsuba does)",
                        rgb.round(4).tolist())
        rgb = np.clip(rgb, 0.0, 1.0)
    elif np.any(rgb < 0):
        if warn:
            log.warning("spectrum %s is outside the sRGB gamut: negative channels clamped to 0 (as Mitsuba does)",
                        rgb.round(4).tolist())
        rgb = np.maximum(rgb, 0.0)
    return rgb


def constant_to_rgb(value: float, emitter: bool = False) -> np.ndarray:
    """A constant spectrum: grey for a reflectance, ``value * xyz_to_srgb(1, 1, 1)`` for an emitter."""
    if emitter:
        return value * XYZ_TO_SRGB.sum(axis=1)
    return np.full(3, float(value))
