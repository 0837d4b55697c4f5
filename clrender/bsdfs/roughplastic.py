"""Mitsuba 3's rough plastic: a diffuse base under a rough dielectric coating (a microfacet specular lobe plus a
diffuse lobe scaled by the coating's rough transmittance in and out).

```xml
<bsdf type="roughplastic">
    <string name="distribution" value="beckmann"/>   <!-- beckmann (default) or ggx -->
    <float name="alpha" value="0.1"/>                 <!-- roughness, default 0.1 -->
    <boolean name="sample_visible" value="true"/>     <!-- visible-normal sampling (GGX), default true -->
    <rgb name="diffuse_reflectance" value="0.5"/>     <!-- default 0.5; may be a <texture> -->
    <rgb name="specular_reflectance" value="1"/>      <!-- default 1; may be a <texture> -->
    <float name="int_ior" value="1.49"/>              <!-- or a name: default "polypropylene" -->
    <float name="ext_ior" value="1.000277"/>          <!-- or a name: default "air" -->
    <boolean name="nonlinear" value="false"/>
</bsdf>
```
    f = specular D(h) F(wi.h) G1(wi,h) G1(wo,h) / (4 cos_i cos_o)
      + d' T(cos_i) T(cos_o) / (pi eta^2),   d' = d / (1 - R_int)  (nonlinear: d / (1 - d R_int))
T(mu) is the rough coating's transmittance for light arriving at cos theta = mu from outside, R_int the coating's
cosine-weighted reflectance seen from inside. Both are integrals over the microfacet distribution that Mitsuba
precomputes; `coating_tables` computes them the same way (T on 64 uniform mu nodes, read with linear
interpolation; R_int = 2 mean(mu R(mu, 1/eta)) over the same nodes), here by Gauss-Legendre quadrature over the
distribution of normals. Sampling: the specular lobe with probability (1 - T(cos_i)) s / ((1 - T) s + T (1 - s)),
s as in plastic. Visible-normal sampling for GGX; Beckmann normals are sampled from D cos (sample_visible only
changes noise, never the image). Anisotropic roughness is an error, as in Mitsuba.
"""
import functools

import numpy as np

from ..device import layout
from ..errors import SceneError
from ..scene.registry import register
from .plastic import CoatedBase

TABLE_RES = layout.BSDF_TABLE_SIZE  # T(mu) is one row of the scene's bsdf_tables
DISTRIBUTIONS = ("beckmann", "ggx")


def _g1(v, m, alpha, ggx):
    """Smith's masking of direction(s) v for normal(s) m (Beckmann: the rational fit Mitsuba uses)."""
    xy2 = alpha * alpha * (v[..., 0] ** 2 + v[..., 1] ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        tan2 = xy2 / (v[..., 2] ** 2)
        if ggx:
            g = 2.0 / (1.0 + np.sqrt(1.0 + tan2))
        else:
            a = 1.0 / np.sqrt(tan2)
            g = np.where(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
    g = np.where(xy2 == 0, 1.0, g)
    return np.where(np.sum(v * m, -1) * v[..., 2] <= 0, 0.0, g)


def _fresnel(cos_i, eta):
    """Unpolarised Fresnel reflectance at relative index eta for cos_i > 0 (1 under total internal reflection)."""
    sin2_t = np.maximum(0.0, 1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return np.where(sin2_t >= 1.0, 1.0, 0.5 * (rs * rs + rp * rp)), cos_t


def _normals(alpha, ggx, n_u, n_phi):
    """Gauss-Legendre nodes over the distribution of normals D(m) cos(m), on the half space y >= 0 (the integrands
    below are symmetric about the plane of incidence y = 0): (m (k,3), weights (k,)) summing to 1."""
    x, w = np.polynomial.legendre.leggauss(n_u)
    # u = 1 - v^2: the integrands grow like 1 / cos(m) ~ 1 / sqrt(1 - u) in GGX's long tail (u -> 1), which the
    # substitution's Jacobian 2v cancels
    v = 0.5 * (x + 1)
    u, wu = 1 - v * v, w * v
    if ggx:
        tan2 = alpha * alpha * u / (1 - u)
    else:
        tan2 = -alpha * alpha * np.log1p(-u)
    cos_t = 1 / np.sqrt(1 + tan2)
    sin_t = np.sqrt(np.maximum(0, 1 - cos_t * cos_t))
    xp, wp = np.polynomial.legendre.leggauss(n_phi)
    phi = 0.5 * np.pi * (xp + 1)
    m = np.stack([np.outer(sin_t, np.cos(phi)), np.outer(sin_t, np.sin(phi)), np.outer(cos_t, np.ones_like(phi))],
                 -1).reshape(-1, 3)
    return m, np.outer(wu, 0.5 * wp).reshape(-1)


@functools.lru_cache(maxsize=64)
def coating_tables(alpha: float, eta: float, ggx: bool, n_u: int = 96, n_phi: int = 48):
    """(T on TABLE_RES uniform nodes of mu = cos theta_i in [0, 1], R_int) for a rough interface of relative index
    eta (inside over outside). With normals m distributed as the visible normals of wi,
        T(mu) = E[(1 - F(wi.m)) G1(wt, m)]  (wt: wi refracted through m, must cross the surface)
        R(mu, 1/eta) = E[F(wi.m) G1(wo, m)]   (wo: wi reflected about m, must stay outside)
    integrated over m ~ D(m) cos(m) (an n_u x n_phi Gauss-Legendre rule over half the normals) with the visible-normal density's ratio
    G1(wi,m) max(0, wi.m) / (cos_i cos_m). Converged to ~1e-5 at the default nodes;
    Mitsuba's own coarser quadrature differs from these by up to ~1 % at grazing angles."""
    mus = np.maximum(1e-6, np.linspace(0, 1, TABLE_RES))
    m, w = _normals(alpha, ggx, n_u, n_phi)
    wi = np.stack([np.sqrt(1 - mus * mus), np.zeros_like(mus), mus], -1)[:, None, :]   # (mu, 1, 3)
    mm = m[None, :, :]                                                                  # (1, k, 3)
    c = np.sum(wi * mm, -1)                                                             # (mu, k)
    ratio = _g1(wi, mm, alpha, ggx) * np.maximum(c, 0) / (mus[:, None] * m[None, :, 2])
    front = c > 0
    cc = np.maximum(c, 1e-12)

    F, cos_t = _fresnel(cc, eta)
    wt = -wi / eta + ((cc / eta - cos_t)[..., None]) * mm
    val = (1 - F) * _g1(wt, mm, alpha, ggx)
    T = np.sum(np.where(front & (wt[..., 2] < 0), val * ratio, 0.0) * w, -1)

    F, _ = _fresnel(cc, 1.0 / eta)
    wo = 2 * cc[..., None] * mm - wi
    val = F * _g1(wo, mm, alpha, ggx)
    R = np.sum(np.where(front & (wo[..., 2] > 0), val * ratio, 0.0) * w, -1)
    return T, float(np.mean(R * mus) * 2.0)


@register("bsdf", "roughplastic", fmt="mitsuba")
class RoughPlastic(CoatedBase):
    kernel = "bsdfs/roughplastic.h"
    PARAMS = [("diffuse", "texture"), ("specular", "texture"), ("eta", "float"), ("spec_weight", "float"),
              ("nonlinear", "uint"), ("alpha", "float"), ("ggx", "uint"), ("sample_visible", "uint"),
              ("int_refl", "float"), ("table", "uint")]
    FLAGS = ("GLOSSY", "DIFFUSE")
    METHODS = ("eval", "pdf", "sample", "albedo")
    owner = '<bsdf type="roughplastic">'

    def __init__(self, props, children, spec):
        self.read_common(props, children)
        dist = props.get_string("distribution", "beckmann")
        if dist not in DISTRIBUTIONS:
            raise SceneError(f"distribution must be one of {', '.join(DISTRIBUTIONS)}, got {dist!r}",
                             props.location("distribution"))
        self.ggx = dist == "ggx"
        for name in ("alpha_u", "alpha_v"):
            if props.has(name):
                raise SceneError(f"{self.owner} does not support anisotropic roughness ('{name}'), as in Mitsuba",
                                 props.location(name))
        self.alpha = float(props.get_float("alpha", 0.1))
        if not 1e-4 <= self.alpha <= 10:
            raise SceneError(f"alpha must be in [1e-4, 10], got {self.alpha}", props.location("alpha"))
        self.sample_visible = bool(props.get_bool("sample_visible", True))
        self.trans, self.int_refl = coating_tables(self.alpha, self.eta, self.ggx)
        self.trans = self.trans.copy()

    def fill(self, p, row, textures):
        p["alpha"], p["ggx"], p["sample_visible"] = self.alpha, int(self.ggx), int(self.sample_visible)
        p["int_refl"] = self.int_refl
        p["table"] = textures.add_bsdf_table(self.trans)   # T(mu), a row of the scene's bsdf_tables
        return self.fill_common(p, textures)
