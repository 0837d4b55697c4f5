"""Mitsuba 3.9's sun and sky (`sunsky`): the Hosek-Wilkie sky model and a uniform solar disk, as Mitsuba 3.9.1's
RGB variants render them, from Mitsuba's own tables read at load time.

```xml
<emitter type="sunsky">
    <float name="turbidity" value="3"/>      <!-- in [1, 10], default 3 -->
    <rgb name="albedo" value="0.3"/>         <!-- ground albedo, each channel in [0, 1], default 0.3 -->
    <!-- the sun's position: either a direction (world space, towards the sun) ... -->
    <vector name="sun_direction" x="0" y="0.5" z="1"/>
    <!-- ... or a place and time (not both); defaults: Tokyo, 2010-07-10 15:00 -->
    <float name="latitude" value="35.6894"/>    <float name="longitude" value="139.6917"/>
    <float name="timezone" value="9"/>          <!-- hours east of UTC -->
    <integer name="year" value="2010"/>  <integer name="month" value="7"/>  <integer name="day" value="10"/>
    <float name="hour" value="15"/>  <float name="minute" value="0"/>  <float name="second" value="0"/>
    <float name="sun_scale" value="1"/>      <!-- >= 0, 0 turns the sun off -->
    <float name="sky_scale" value="1"/>      <!-- >= 0, 0 turns the sky off -->
    <float name="sun_aperture" value="0.5358"/>   <!-- the sun's apparent diameter in degrees, in (0, 180) -->
    <boolean name="complex_sun" value="false"/>   <!-- true (limb darkening) is refused -->
    <transform name="to_world"> ... </transform>  <!-- a rotation; default identity -->
</emitter>
```
Local frame (Mitsuba's code): +z is up (the zenith) and the sun at azimuth 180° (due south) lies along +x
(Mitsuba's docs call +x north; we follow its code, which puts the noon sun of the northern hemisphere there);
directions with z < 0 receive nothing, and when the sun is below the horizon neither does any other direction
(Mitsuba warns, and so do we). Radiance is in Mitsuba's units
(W m⁻² sr⁻¹ nm⁻¹ times its CIE normalisation), so a scene should be modelled in metres. Mitsuba's docs give the
default aperture as 0.5338°; its code uses 0.5358°, which is what it renders and what we take.

**The tables** (Hosek & Wilkie's sky coefficients refitted by Mitsuba, and Mitsuba's solar irradiance tables) are not
part of clrender: they are read at load time from the files the `mitsuba` wheel ships
(`mitsuba/data/sunsky/sunsky_datasets.bin`, `sampling_data.bin`), installed by the `sunsky` extra
(`pip install "clrender[sunsky]"`); without it the scene is refused with that advice. Nothing of Mitsuba is imported.

**How it renders**: the sky is a row of its own (kernels/emitters/sunsky.h) that evaluates the model per direction
on the device (its coefficients stored after its map's texels) and is importance sampled through `envmap`'s
functions by a SKY_WIDTH x SKY_HEIGHT (512 x 257) latitude-longitude map of the sky made here (the horizon on a row,
no weight below it); the row's fields are an envmap's. A map alone is not enough: below the horizon Mitsuba's sky
is black and just above it rises as sqrt(cos θ), which bilinear lookup blurs over a row (a bright band under a bare
horizon, several percent off just above it). The sun is a `distantdisk` row of uniform radiance (Mitsuba's
default sun, which has no limb darkening) with the sun's angular radius, sampled uniformly in its cone as Mitsuba
samples it. The scene gets these two emitter rows for the one element (`parts()`). Where they differ from
Mitsuba: a sun within its own radius of the horizon is drawn whole where Mitsuba cuts its lower part off; light
sampling picks sky and sun like any two emitters (Mitsuba splits its samples by their irradiance), which changes
the noise, not the image.

Checked against Mitsuba 3.9.1 (scalar_rgb; scripts outside the repository): the emitter's radiance at random
directions within 6e-5 (relative) of Mitsuba's eval, the sun's direction from a date within 0.01°, its radiance
within 1e-6; a diffuse plane and sphere with the bare horizon in view (hours 7.5, 12, 15, 18.5 in Tokyo; turbidity
2, 3, 6, 10; sky alone, sun alone), 6 seeds of 32 spp each: image means within 0.06 % (|z| < 1.5), every 16 x 16
block within noise (rms z 1.05..1.3, as t statistics of 10 degrees of freedom give).

Emitter row of the sky (kernels/emitters/sunsky.h): an envmap's fields, p.sunsky.dims = (first texel row, W, H,
offset of the CDFs), inv[0..2].xyz = rows of the world-to-map rotation (to_world · ENVMAP_TO_LOCAL, transposed),
inv[0].w = 1; after the map's H x (W + 1) texels, 11 rows of coefficients (coefficient_rows()).

The model, for each RGB channel (Mitsuba's `eval_sky`, the Hosek-Wilkie formula with its nine coefficients A..I):
L(θ, γ) = (1 + A e^{B / (cos θ + 0.01)}) (C + D e^{E γ} + F cos²γ + G χ(I, γ) + H √cos θ) · L_M · k,
χ(g, γ) = (1 + cos²γ) / (1 + g² − 2 g cos γ)^{3/2}, θ the angle from the zenith, γ the angle to the sun and
k = 1/106.7502593994140625 (Mitsuba's CIE Y normalisation). The coefficients A..I and L_M are the tables'
interpolated linearly in turbidity, then linearly in the channel's albedo, then as a quintic Bézier curve over
x = cbrt(2 η / π) (η the sun's elevation). The sun's radiance is Mitsuba's irradiance table (11 wavelengths
320..720 nm, turbidity x 30 elevations 2°..89°), turned into linear sRGB by the CIE 1931 matching functions at
those wavelengths (mean over the 11), times 467.069280386 · k and divided by the disk's solid angle
2π (1 − cos(aperture / 2)). The sun's position from a date uses the PSA algorithm (Blanco-Muriel et al. 2001), in
single precision as Mitsuba computes it (its Julian date is a float: times of day round to a quarter of a day
in the ecliptic terms, which moves the sun by hundredths of a degree; we round the same way).
"""
from __future__ import annotations

import functools
import importlib.metadata
import logging
import struct
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..scene.cie_tables import CIE1931_X, CIE1931_Y, CIE1931_Z, CIE_MIN, CIE_STEP
from ..scene.registry import register
from ..scene.spectrum import XYZ_TO_SRGB, Y_NORMALIZATION
from .distantdisk import DistantDiskEmitter
from .emitter import Emitter
from .envmap import EnvMap

log = logging.getLogger("clrender")

INSTALL = 'pip install "clrender[sunsky]"'
#: the sky map's size: columns, and rows from zenith to nadir (odd, so that the horizon is a row)
SKY_WIDTH, SKY_HEIGHT = 512, 257

WAVELENGTHS = 320.0 + 40.0 * np.arange(11)
#: Mitsuba's reference half-aperture of the sun, to which its sun tables are normalised (radians)
SUN_HALF_APERTURE = np.pi * (0.5 * 0.5358) / 180.0
SPEC_TO_RGB_SUN_CONV = 467.069280386
EARTH_MEAN_RADIUS_KM, ASTRONOMICAL_UNIT_KM = 6371.01, 149597890.0
#: Mitsuba's sun in this frame: local z is up; the envmap's local y is. s = P v maps envmap-local v to sunsky-local s.
ENVMAP_TO_LOCAL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
_TIME_PLACE = ("latitude", "longitude", "timezone", "year", "month", "day", "hour", "minute", "second")
_ONE_MINUS_EPS_F32 = float(np.float32(1.0) - np.float32(2.0 ** -24))


# ------------------------------------------------------------------------------------------------------- tables
def tables_dir(location=None) -> Path:
    """The folder of Mitsuba's sunsky tables in the installed `mitsuba` distribution (found through its metadata;
    the package is never imported)."""
    try:
        d = Path(importlib.metadata.distribution("mitsuba").locate_file("mitsuba/data/sunsky"))
    except importlib.metadata.PackageNotFoundError:
        d = None
    if d is None or not ((d / "sunsky_datasets.bin").is_file() and (d / "sampling_data.bin").is_file()):
        raise SceneError("the sunsky emitter needs the sky model's tables that the mitsuba package ships "
                         f"(mitsuba/data/sunsky/); install the sunsky extra: {INSTALL}", location)
    return d


def read_tensor_file(path: Path) -> dict:
    """Every field of a Mitsuba tensor file ("tensor_file\\0", version, field count, then per field its name, rank,
    type, offset and shape; little-endian) as numpy arrays (float64)."""
    b = Path(path).read_bytes()
    if b[:12] != b"tensor_file\0" or len(b) < 18:
        raise ValueError(f"{path}: not a Mitsuba tensor file")
    (count,) = struct.unpack_from("<I", b, 14)
    o, out = 18, {}
    for _ in range(count):
        (n,) = struct.unpack_from("<H", b, o)
        name = b[o + 2:o + 2 + n].decode()
        o += 2 + n
        ndim, dtype, offset = struct.unpack_from("<HBQ", b, o)
        o += 11
        shape = struct.unpack_from(f"<{ndim}Q", b, o)
        o += 8 * ndim
        fmt = {10: "<f4", 11: "<f8"}.get(dtype)
        if fmt is None:
            raise ValueError(f"{path}: field {name!r} has an unexpected type {dtype}")
        out[name] = np.frombuffer(b, fmt, int(np.prod(shape)), offset).reshape(shape).astype(np.float64)
    return out


@functools.lru_cache(maxsize=None)
def _tables(folder: str) -> dict:
    t = read_tensor_file(Path(folder) / "sunsky_datasets.bin")
    t.update(read_tensor_file(Path(folder) / "sampling_data.bin"))
    return t


def tables(location=None) -> dict:
    """Mitsuba's tables: sky_params_rgb (turbidity 10, albedo 2, control point 6, channel 3, coefficient 9),
    sky_rad_rgb (10, 2, 6, 3), sun_irradiance (turbidity 10, elevation 30, wavelength 11), and others."""
    return _tables(str(tables_dir(location)))


# -------------------------------------------------------------------------------------------------------- model
def take_interp(data: np.ndarray, pos: float) -> np.ndarray:
    """Linear interpolation along axis 0 at fractional index `pos`, as Dr.Jit's take_interp: the lower index is
    clipped to [0, n − 2] and the weight is not, so positions beyond the ends extrapolate."""
    i = int(np.clip(int(pos), 0, data.shape[0] - 2))
    w = pos - i
    return data[i] * (1.0 - w) + data[i + 1] * w


def sky_coefficients(t: dict, turbidity: float, albedo, sun_elevation: float) -> tuple[np.ndarray, np.ndarray]:
    """The nine coefficients (3, 9) and the mean radiance (3,) of each channel for the sun at `sun_elevation`
    (radians above the horizon)."""
    albedo = np.asarray(albedo, np.float64)

    def collapse(data):
        d = take_interp(data, turbidity - 1.0)             # (albedo 2, ctrl 6, channel 3, ...)
        a = albedo.reshape((1, 3) + (1,) * (d.ndim - 3))
        d = d[0] * (1.0 - a) + d[1] * a                   # (ctrl 6, channel 3, ...)
        x = min(np.cbrt(2.0 / np.pi * sun_elevation), _ONE_MINUS_EPS_F32)
        bern = np.array([1, 5, 10, 10, 5, 1]) * x ** np.arange(6) * (1.0 - x) ** (5 - np.arange(6))
        return np.tensordot(bern, d, axes=1)

    return collapse(t["sky_params_rgb"]), collapse(t["sky_rad_rgb"])


def sky_radiance(coefs: np.ndarray, mean: np.ndarray, cos_theta, gamma) -> np.ndarray:
    """The Hosek-Wilkie sky's RGB radiance (..., 3) at view zenith cosines `cos_theta` and sun angles `gamma`
    (without Mitsuba's CIE normalisation), 0 below the horizon."""
    ct = np.asarray(cos_theta, np.float64)[..., None]
    g = np.asarray(gamma, np.float64)[..., None]
    A, B, C, D, E, F, G, H, I = (coefs[:, k] for k in range(9))
    cg = np.cos(g)
    chi = (1.0 + cg ** 2) / (1.0 + I ** 2 - 2.0 * I * cg) ** 1.5
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        c1 = 1.0 + A * np.exp(B / (ct + 0.01))
        c2 = C + D * np.exp(E * g) + F * cg ** 2 + G * chi + H * np.sqrt(np.maximum(ct, 0.0))
        out = c1 * c2 * mean
    return np.where(ct >= 0.0, out, 0.0)


def sun_radiance(t: dict, turbidity: float, sun_elevation: float, half_aperture: float) -> np.ndarray:
    """The solar disk's uniform RGB radiance (Mitsuba's default sun) for a disk of `half_aperture` radians."""
    angle = np.clip((np.degrees(sun_elevation) - 2.0) / 3.0, 0.0, 30.0 - _ONE_MINUS_EPS_F32)
    irr = take_interp(take_interp(t["sun_irradiance"], turbidity - 1.0), angle)   # (11,)
    idx = (WAVELENGTHS - CIE_MIN) / CIE_STEP
    inside = idx >= 0
    xyz = np.zeros((3, 11))
    for k, table in enumerate((CIE1931_X, CIE1931_Y, CIE1931_Z)):
        xyz[k, inside] = table[idx[inside].astype(int)]   # the wavelengths fall on the table's 5 nm grid
    rgb = (XYZ_TO_SRGB @ xyz * irr).mean(axis=1)
    return rgb * SPEC_TO_RGB_SUN_CONV * Y_NORMALIZATION / (2.0 * np.pi * (1.0 - np.cos(half_aperture)))


def _cdiv(a: int, b: int) -> int:
    """C's integer division (truncating toward zero)."""
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b > 0) else -q


def sun_coordinates(year, month, day, hour, minute, second, latitude, longitude, timezone) -> tuple[float, float]:
    """(zenith angle, azimuth − π) of the sun in radians, by the PSA algorithm (Blanco-Muriel et al., Solar Energy
    70(5), 2001) in single precision, as Mitsuba computes it; the direction is (sin θ cos φ, sin θ sin φ, cos θ)."""
    f = np.float32
    dec_hours = f(hour) - f(timezone) + (f(minute) + f(second) / f(60)) / f(60)
    a1 = _cdiv(month - 14, 12)
    a2 = (_cdiv(1461 * (year + 4800 + a1), 4) + _cdiv(367 * (month - 2 - 12 * a1), 12)
          - _cdiv(3 * _cdiv(year + 4900 + a1, 100), 4) + day - 32075)
    n = (f(a2) - f(0.5) + dec_hours / f(24)) - f(2451545)
    omega = f(2.1429) - f(0.0010394594) * n
    mean_longitude = f(4.8950630) + f(0.017202791698) * n
    anomaly = f(6.2400600) + f(0.0172019699) * n
    ecl_longitude = (mean_longitude + f(0.03341607) * np.sin(anomaly) + f(0.00034894) * np.sin(f(2) * anomaly)
                     - f(0.0001134) - f(0.0000203) * np.sin(omega))
    obliquity = f(0.4090928) - f(6.2140e-9) * n + f(0.0000396) * np.cos(omega)
    s = np.sin(ecl_longitude)
    ra = np.arctan2(np.cos(obliquity) * s, np.cos(ecl_longitude))
    ra = ra + f(2 * np.pi) if ra < 0 else ra
    decl = np.arcsin(np.sin(obliquity) * s)
    gmst = f(6.6974243242) + f(0.0657098283) * n + dec_hours
    lmst = (gmst * f(15) + f(longitude)) * f(np.pi / 180)
    lat = f(latitude) * f(np.pi / 180)
    ha = lmst - ra
    zenith = np.arccos(np.cos(lat) * np.cos(ha) * np.cos(decl) + np.sin(decl) * np.sin(lat))
    azimuth = np.arctan2(-np.sin(ha), np.tan(decl) * np.cos(lat) - np.sin(lat) * np.cos(ha))
    azimuth = azimuth + f(2 * np.pi) if azimuth < 0 else azimuth
    zenith = zenith + f(EARTH_MEAN_RADIUS_KM / ASTRONOMICAL_UNIT_KM) * np.sin(zenith)
    return float(zenith), float(azimuth - f(np.pi))


def sph_to_dir(theta: float, phi: float) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


# ------------------------------------------------------------------------------------------------------ plugin
@register("emitter", "sunsky", fmt="mitsuba")
class Sunsky(Emitter):
    """Packs as two rows (`parts()`): itself, the sky (kernels/emitters/sunsky.h: the model evaluated on the device,
    sampled through envmap's functions by a map of it), and a distantdisk, the sun; see the module docstring."""

    kernel = "emitters/sunsky.h"
    PARAMS = EnvMap.PARAMS       # field for field, so that envmap.h's functions read this row (kernels/emitters/sunsky.h)
    FLAGS = ("INFINITE",)

    def __init__(self, props, children, spec):
        loc = spec.location
        self.turbidity = props.get_float("turbidity", 3.0)
        if not 1.0 <= self.turbidity <= 10.0:
            raise SceneError(f"turbidity must be in [1, 10], got {self.turbidity:g}", props.location("turbidity"))
        self.albedo = np.asarray(props.get_color("albedo", 0.3), np.float64)
        if np.any(self.albedo < 0) or np.any(self.albedo > 1):
            raise SceneError(f"albedo must be in [0, 1] in every channel, got {self.albedo.tolist()}",
                             props.location("albedo"))
        self.sun_scale, self.sky_scale = (props.get_float(n, 1.0) for n in ("sun_scale", "sky_scale"))
        for n in ("sun_scale", "sky_scale"):
            if not getattr(self, n) >= 0:
                raise SceneError(f"{n} must be >= 0, got {getattr(self, n):g}", props.location(n))
        aperture = props.get_float("sun_aperture", 0.5358)
        if not 0.0 < aperture < 180.0:
            raise SceneError(f"sun_aperture must be in (0, 180) degrees, got {aperture:g}",
                             props.location("sun_aperture"))
        # Mitsuba tests and normalises the disk with the single-precision cosine of the half-aperture: 1 − cos is
        # then off by up to 0.3 % for the real sun, and we take the angle whose 1 − cos that is, as it renders it
        omc = float(np.float32(1.0) - np.cos(np.float32(np.radians(np.float32(0.5) * np.float32(aperture)))))
        self.half_aperture = float(2.0 * np.arcsin(np.sqrt(0.5 * omc)))
        if props.get_bool("complex_sun", False):
            raise SceneError("complex_sun (the limb-darkened sun) is not supported by clrender; remove it or set it "
                             "to false (the uniform sun of the same power)", props.location("complex_sun"))
        m = props.get_transform("to_world").matrix[:3, :3]
        if not np.allclose(m @ m.T, np.eye(3), atol=1e-5):
            raise SceneError("the sunsky's to_world must be a rotation (no scale or shear)",
                             props.location("to_world"))
        self.to_world = m
        given = [n for n in _TIME_PLACE if props.has(n)]
        # read whether used or not, so that an unknown parameter's error lists them all
        ints = {}
        for n, default, lo in (("year", 2010, None), ("month", 7, 0), ("day", 10, 0)):
            ints[n] = props.get_int(n, default)
            if lo is not None and ints[n] < lo:
                raise SceneError(f"{n} must be a non-negative integer, got {ints[n]}", props.location(n))
        floats = {n: props.get_float(n, dflt) for n, dflt in (
            ("latitude", 35.6894), ("longitude", 139.6917), ("timezone", 9.0), ("hour", 15.0), ("minute", 0.0),
            ("second", 0.0))}
        if props.has("sun_direction"):
            if given:
                raise SceneError(f"sun_direction and the time/place parameters ({', '.join(given)}) cannot both be "
                                 "given: the sun's position comes from one or the other", props.location(given[0]))
            d = np.asarray(props.get_vector("sun_direction"), np.float64)
            if not np.linalg.norm(d) > 0:
                raise SceneError("sun_direction must not be zero", props.location("sun_direction"))
            local = m.T @ (d / np.linalg.norm(d))
        else:
            local = sph_to_dir(*sun_coordinates(**ints, **floats))
        self.sun_local = local / np.linalg.norm(local)
        self.sun_direction = m @ self.sun_local
        self.sun_elevation = 0.5 * np.pi - float(np.arccos(np.clip(self.sun_local[2], -1.0, 1.0)))
        if self.sun_local[2] < 0:
            log.warning("%s: the sun is below the horizon at the given time and place: the sunsky emits nothing",
                        loc)
        t = tables(loc)
        self.coefs, self.mean = sky_coefficients(t, self.turbidity, self.albedo, self.sun_elevation)
        self.sun_rgb = self.sun_scale * sun_radiance(t, self.turbidity, self.sun_elevation, self.half_aperture)

    # ---- host references (tests) ----
    def sky(self, d_local) -> np.ndarray:
        """The sky's radiance (..., 3) from local directions (z up), Mitsuba's units."""
        d = np.asarray(d_local, np.float64)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        if self.sun_local[2] < 0 or self.sky_scale == 0:
            return np.zeros(d.shape[:-1] + (3,))
        gamma = np.arccos(np.clip(d @ self.sun_local, -1.0, 1.0))
        return self.sky_scale * Y_NORMALIZATION * sky_radiance(self.coefs, self.mean, d[..., 2], gamma)

    def sky_image(self, width: int = SKY_WIDTH, height: int = SKY_HEIGHT) -> np.ndarray:
        """The sky at the envmap's texel positions (height rows from zenith to nadir, width columns)."""
        v = np.arange(height) / (height - 1)
        u = (np.arange(width) + 0.5) / width
        theta, phi = np.pi * v[:, None], 2.0 * np.pi * u[None, :]
        env_local = np.stack(np.broadcast_arrays(np.sin(phi) * np.sin(theta), np.cos(theta),
                                                 -np.cos(phi) * np.sin(theta)), axis=-1)
        return self.sky(env_local @ ENVMAP_TO_LOCAL.T)

    @functools.cached_property
    def map(self) -> EnvMap:
        """The sky as an environment map: what importance sampling follows (the device evaluates the model
        itself). Its cells below the horizon get no weight, as the sky has no radiance there; the cells just
        above keep theirs (their lower corners' black only lowers it)."""
        img = self.sky_image()
        img[(SKY_HEIGHT - 1) // 2:] = 0.0
        return EnvMap.from_image(img, self.to_world @ ENVMAP_TO_LOCAL)

    def coefficient_rows(self) -> np.ndarray:
        """What kernels/emitters/sunsky.h reads after the map's texels: rows 0..8 the coefficients A..I (x, y, z =
        R, G, B), row 9 the mean radiance times sky_scale and Mitsuba's CIE normalisation, row 10 the direction
        toward the sun in the map's frame (y up)."""
        rows = np.zeros((11, 4))
        rows[:9, :3] = self.coefs.T
        rows[9, :3] = self.mean * self.sky_scale * Y_NORMALIZATION
        rows[10, :3] = ENVMAP_TO_LOCAL.T @ self.sun_local
        return rows

    def eval(self, d_world) -> np.ndarray:
        """The sky's radiance from world directions (..., 3) (host reference of the device's)."""
        return self.sky(np.asarray(d_world, np.float64) @ self.to_world)

    def parts(self) -> list:
        out = []
        if self.sun_local[2] >= 0 and self.sky_scale > 0:
            out.append(self)
        if self.sun_local[2] >= 0 and self.sun_scale > 0:
            out.append(DistantDiskEmitter.from_axis(self.sun_rgb, self.sun_direction,
                                                    np.degrees(self.half_aperture)))
        return out

    def selection_power(self, radius, area):
        return self.map.selection_power(radius, area)

    def fill(self, p, row, ctx, shape):
        self.map.fill(p, row, ctx, shape, extra_texels=self.coefficient_rows())   # an envmap's fields (PARAMS)
