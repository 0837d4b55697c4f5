"""Scenes of our own with participating media (Mitsuba 3 XML) and their expected images, shared by the media and
phase function tests. Each scene is built here as text, written to the test's folder and rendered by clrender."""
from __future__ import annotations

from pathlib import Path

import numpy as np

HEAD = '<scene version="3.0.0">'
INTERIOR = '<ref id="{}" name="interior"/>'


def medium_xml(sigma_t, albedo, phase: str = '<phase type="isotropic"/>', name: str = "", mid: str = "",
               extra: str = "") -> str:
    """A homogeneous medium; sigma_t is written as a colour in [0, 1] and a `scale` (Mitsuba 3.9.1 reads an <rgb>
    sigma_t as a reflectance and refuses values above 1), so that Mitsuba reads the scene too."""
    attrs = (f' name="{name}"' if name else "") + (f' id="{mid}"' if mid else "")
    st = np.broadcast_to(np.asarray(sigma_t, np.float64), 3)
    scale = float(st.max()) or 1.0
    return (f'<medium type="homogeneous"{attrs}><rgb name="sigma_t" value="{_rgb(st / scale)}"/>'
            f'<float name="scale" value="{scale:.9g}"/>'
            f'<rgb name="albedo" value="{_rgb(albedo)}"/>{extra}{phase}</medium>')


def _rgb(v) -> str:
    v = np.broadcast_to(np.asarray(v, np.float64), 3)
    return ", ".join(f"{x:.9g}" for x in v)


def ortho_sensor(origin, target, half_width: float, size: int, spp: int, medium: str = "") -> str:
    """An orthographic sensor seeing a square of the given half width (rays all parallel: every pixel sees the same
    path lengths), box filter."""
    o, t = _rgb(origin), _rgb(target)
    up = "0, 1, 0" if abs(np.asarray(origin, float)[1] - np.asarray(target, float)[1]) < 1e-9 else "1, 0, 0"
    return (f'<sensor type="orthographic"><transform name="to_world"><scale x="{half_width}" y="{half_width}"/>'
            f'<lookat origin="{o}" target="{t}" up="{up}"/></transform>'
            f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
            f'<film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>'
            f'<rfilter type="box"/></film>{medium}</sensor>')


def persp_sensor(origin, target, fov: float, size: int, spp: int, medium: str = "") -> str:
    return (f'<sensor type="perspective"><float name="fov" value="{fov}"/><transform name="to_world">'
            f'<lookat origin="{_rgb(origin)}" target="{_rgb(target)}" up="0, 1, 0"/></transform>'
            f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
            f'<film type="hdrfilm"><integer name="width" value="{size}"/><integer name="height" value="{size}"/>'
            f'<rfilter type="box"/></film>{medium}</sensor>')


def box(half_sizes, centre=(0, 0, 0), inner: str = "", bsdf: str = '<bsdf type="null"/>') -> str:
    """Mitsuba's cube ([-1, 1]^3) scaled to the given half sizes about `centre`, with `bsdf` and `inner` (media)."""
    return (f'<shape type="cube"><transform name="to_world"><scale value="{_rgb(half_sizes)}"/>'
            f'<translate value="{_rgb(centre)}"/></transform>{bsdf}{inner}</shape>')


def integrator(kind: str = "volpath", max_depth: int = -1, rr_depth: int = 5) -> str:
    return (f'<integrator type="{kind}"><integer name="max_depth" value="{max_depth}"/>'
            f'<integer name="rr_depth" value="{rr_depth}"/></integrator>')


def render_xml(folder, xml: str, seed: int = 1, name: str = "scene.xml", spp: int | None = None):
    """Write `xml` (a whole scene) into `folder` and render it with clrender; returns the Film."""
    import clrender

    path = Path(folder) / name
    path.write_text(xml)
    return clrender.render(clrender.load_scene(path), spp=spp, seed=seed)


# ------------------------------------------------------------------------------------------------ scenes
def absorbing_slab(sigma_t, radiance, depth: float, kind: str = "volpath", spp: int = 1024,
                   camera_inside: bool = False) -> str:
    """An orthographic camera looking down -z through a slab of an absorbing medium (albedo 0) of thickness
    `depth` (z in [-depth/2, depth/2], wide in x and y) at a wide emitting rectangle of `radiance` at z = -3.
    Every pixel is radiance exp(-sigma_t length), length = absorbing_slab_length(depth, camera_inside): the slab's
    thickness, or with camera_inside (the slab's medium is then the camera's, which sits in it 0.25 below its top)
    0.25 less."""
    med = medium_xml(sigma_t, 0.0, mid="slab")
    z_cam = depth / 2 - 0.25 if camera_inside else 5.0
    cam_medium = '<ref id="slab"/>' if camera_inside else ""
    return (f'{HEAD}{integrator(kind)}{med}'
            f'{ortho_sensor((0, 0, z_cam), (0, 0, -10), 0.5, 8, spp, cam_medium)}'
            f'{box((20, 20, depth / 2), inner=INTERIOR.format("slab"))}'
            f'<shape type="rectangle"><transform name="to_world"><scale value="30"/><translate z="-3"/></transform>'
            f'<emitter type="area"><rgb name="radiance" value="{_rgb(radiance)}"/></emitter></shape></scene>')


def absorbing_slab_length(depth: float, camera_inside: bool) -> float:
    return depth - 0.25 if camera_inside else depth


def furnace(sigma_t, phase: str, spp: int = 256, camera_inside: bool = False, max_depth: int = -1,
            sample_emitters: bool = True) -> str:
    """A cube of a non-absorbing medium (albedo 1) behind a null boundary, in a constant environment of radiance 1:
    every path ends in the environment, so every pixel is 1 (for any phase function and extinction). The camera
    looks at the cube from outside, or sits inside it (its medium then the cube's). Without `sample_emitters` the
    medium's scattering vertices sample no light: only the phase samples reach the environment."""
    extra = "" if sample_emitters else '<boolean name="sample_emitters" value="false"/>'
    med = medium_xml(sigma_t, 1.0, phase, mid="fog", extra=extra)
    origin = (0.2, 0.1, 0.3) if camera_inside else (0, 0, 4)
    cam_medium = '<ref id="fog"/>' if camera_inside else ""
    return (f'{HEAD}{integrator("volpath", max_depth)}{med}'
            f'{persp_sensor(origin, (0, 0, -1) if camera_inside else (0, 0, 0), 30, 8, spp, cam_medium)}'
            f'{box((1, 1, 1), inner=INTERIOR.format("fog"))}'
            f'<emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>')


def single_scattering_slab(sigma_t, albedo, phase: str, depth: float, theta_light: float, irradiance,
                           kind: str = "volpath", max_depth: int = 2, spp: int = 2048,
                           bsdf: str = '<bsdf type="null"/>') -> str:
    """A slab (z in [-depth, 0], wide) of a scattering medium behind null boundaries, lit by a directional light
    from above at `theta_light` degrees from the normal (in the xz plane), seen by an orthographic camera looking
    straight down; nothing else in the scene. With max_depth 2 the image is single scattering alone
    (single_scattering_value; with another `bsdf` on the boundary, times what it lets through on the way in and
    out)."""
    t = np.radians(theta_light)
    d = (np.sin(t), 0.0, -np.cos(t))     # the light travels along d
    med = medium_xml(sigma_t, albedo, phase, mid="slab")
    return (f'{HEAD}{integrator(kind, max_depth)}{med}'
            f'{ortho_sensor((0, 0, 5), (0, 0, -10), 0.25, 8, spp)}'
            f'{box((40, 40, depth / 2), centre=(0, 0, -depth / 2), inner=INTERIOR.format("slab"), bsdf=bsdf)}'
            f'<emitter type="directional"><vector name="direction" value="{_rgb(d)}"/>'
            f'<rgb name="irradiance" value="{_rgb(irradiance)}"/></emitter></scene>')


def single_scattering_value(sigma_t, albedo, phase_fn, depth: float, theta_light: float, irradiance) -> np.ndarray:
    """The radiance single scattering sends up to the camera of single_scattering_slab, by quadrature over the
    depth z of the scattering point (scipy's adaptive Gauss-Kronrod): sigma_s p(cos) E exp(-sigma_t z) (the camera
    ray's way down) exp(-sigma_t z / cos theta_light) (the light's way in), per channel. phase_fn(cos) is the phase
    function at the cosine between the direction to the light and the direction to the camera."""
    from scipy.integrate import quad

    t = np.radians(theta_light)
    to_light = np.array([-np.sin(t), 0.0, np.cos(t)])
    p = phase_fn(float(to_light @ np.array([0.0, 0.0, 1.0])))
    st = np.broadcast_to(np.asarray(sigma_t, np.float64), 3)
    ss = st * np.broadcast_to(np.asarray(albedo, np.float64), 3)
    e = np.broadcast_to(np.asarray(irradiance, np.float64), 3)
    out = np.empty(3)
    for c in range(3):
        val, err = quad(lambda z: np.exp(-st[c] * z * (1 + 1 / np.cos(t))), 0.0, depth, epsabs=1e-12, epsrel=1e-10)
        out[c] = ss[c] * p * e[c] * val
    return out


def thin_sheet_transmittance(cos_i: float, eta: float) -> float:
    """1 - R of Mitsuba's thindielectric: R = 2 F / (1 + F), F the unpolarised Fresnel reflectance of one interface
    of relative index eta (the sum over the light's bounces between the two faces)."""
    sin_t = np.sqrt(max(0.0, 1 - cos_i * cos_i)) / eta
    cos_t = np.sqrt(1 - sin_t * sin_t)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    f = (rs * rs + rp * rp) / 2
    return 1 - 2 * f / (1 + f)


# ------------------------------------------------------------------------------------------------ heterogeneous
def box_to_world(half_sizes, centre=(0, 0, 0)) -> str:
    """The <transform name="to_world"> that maps a volume's unit cube onto the box of box(half_sizes, centre)."""
    h = np.broadcast_to(np.asarray(half_sizes, np.float64), 3)
    lo = np.asarray(centre, np.float64) - h
    return (f'<transform name="to_world"><scale value="{_rgb(2 * h)}"/><translate value="{_rgb(lo)}"/>'
            f'</transform>')


def grid_xml(name: str, filename, to_world: str = "", filter_type: str = "trilinear", wrap: str = "clamp",
             extra: str = "") -> str:
    """A <volume type="gridvolume"> filling parameter `name` of a heterogeneous medium."""
    return (f'<volume type="gridvolume" name="{name}"><string name="filename" value="{filename}"/>'
            f'<string name="filter_type" value="{filter_type}"/><string name="wrap_mode" value="{wrap}"/>'
            f'{to_world}{extra}</volume>')


def heterogeneous_xml(sigma_t: str, albedo: str = '<float name="albedo" value="0.75"/>', scale: float = 1.0,
                      phase: str = '<phase type="isotropic"/>', mid: str = "", name: str = "") -> str:
    """A heterogeneous medium of the given sigma_t and albedo elements (a <volume> or a <float>/<rgb>)."""
    attrs = (f' name="{name}"' if name else "") + (f' id="{mid}"' if mid else "")
    return (f'<medium type="heterogeneous"{attrs}>{sigma_t}{albedo}<float name="scale" value="{scale:.9g}"/>'
            f'{phase}</medium>')


def ramp(n: int = 8, per_channel=(1.0, 0.5, 2.0)) -> np.ndarray:
    """A (n, 1, 1, 3) grid (z, y, x, c) whose values grow linearly with z: (0.1 + 0.2 k) times per_channel."""
    v = (0.1 + 0.2 * np.arange(n))[:, None] * np.asarray(per_channel, np.float64)
    return v.reshape(n, 1, 1, 3).astype(np.float32)


def ramp_optical_depth(grid: np.ndarray, height: float, t, scale: float = 1.0) -> np.ndarray:
    """Exactly, the integral of the trilinearly looked-up density of a (n, 1, 1, c) grid spanning `height` along z
    from its bottom face up to height t (an array): piecewise linear between the voxel centres, constant (clamped)
    in the half voxels at either end. Returns (len(t), c)."""
    v = grid.reshape(len(grid), -1).astype(np.float64)
    n = len(v)
    knots = np.concatenate([[0.0], (np.arange(n) + 0.5) / n * height, [height]])
    vals = np.concatenate([v[:1], v, v[-1:]])
    seg = np.diff(knots)[:, None] * (vals[1:] + vals[:-1]) / 2
    cum = np.concatenate([np.zeros((1, v.shape[1])), np.cumsum(seg, axis=0)])
    t = np.clip(np.atleast_1d(np.asarray(t, np.float64)), 0.0, height)
    k = np.clip(np.searchsorted(knots, t, side="right") - 1, 0, len(knots) - 2)
    frac = ((t - knots[k]) / np.diff(knots)[k])[:, None]
    at_t = vals[k] + frac * (vals[k + 1] - vals[k])
    return scale * (cum[k] + (t - knots[k])[:, None] * (vals[k] + at_t) / 2)
