/* Microfacet normal distributions of Mitsuba 3's rough BSDFs: Beckmann and GGX, anisotropic (alpha_u along the
   local x axis, alpha_v along y), sampled either over all normals (D(m) cos(theta_m)) or over the normals
   visible from wi (D_wi(m) = G1(wi) max(0, wi.m) D(m) / cos(theta_i), Heitz and d'Eon 2014).
   Two shadowing terms: mf_g1 is Mitsuba's (for Beckmann the rational fit of Walter et al. 2007), used in f so that
   images converge to Mitsuba's; mf_g1_exact is Smith's exact term, used to normalise the visible-normal density so
   that the pdf is the density the sampler really draws from (the fit is off by up to ~0.3%).
   Also: complex-IOR Fresnel and refraction about a microfacet. */
#ifndef CLRENDER_BSDFS_DISTRIBUTION_H
#define CLRENDER_BSDFS_DISTRIBUTION_H
#include "common.h"
#include "../texture.h"

#define MF_BECKMANN 0u
#define MF_GGX 1u
#define INV_SQRT_PI 0.56418958354775628695f

typedef struct {
    uint type;
    float ax, ay;
    bool visible;
} MfDist;

INLINE MfDist mf_make(const BsdfQuery* q, uint type, float au, uint au_tex, float av, uint av_tex, uint visible) {
    MfDist d;
    d.type = type;
    /* textures may hold 0: keep the lobe a (very narrow) distribution rather than 0/0 */
    d.ax = maxf(param_float(q, au, au_tex), 1e-4f);
    d.ay = maxf(param_float(q, av, av_tex), 1e-4f);
    d.visible = visible != 0u;
    return d;
}

/* D(m), zero below the surface. */
INLINE float mf_d(MfDist d, vec3 m) {
    if (m.z <= 0.0f) return 0.0f;
    float c2 = m.z * m.z;
    float sx = m.x / d.ax, sy = m.y / d.ay;
    float r;
    if (d.type == MF_BECKMANN) {
        float e = exp(-(sx * sx + sy * sy) / c2);
        r = e / (M_PI_F_ * d.ax * d.ay * c2 * c2);
    } else {
        float t = sx * sx + sy * sy + c2;
        r = 1.0f / (M_PI_F_ * d.ax * d.ay * t * t);
    }
    /* near the horizon cos^4 underflows long after the numerator: no NaN, no 1e-30 specks */
    return (isfinite(r) && r * m.z > 1e-20f) ? r : 0.0f;
}

/* alpha^2 tan^2(theta) of v for the roughness projected onto v's azimuth */
INLINE float mf_tan2_alpha(MfDist d, vec3 v) {
    float xy = d.ax * d.ax * v.x * v.x + d.ay * d.ay * v.y * v.y;
    return xy / (v.z * v.z);
}

/* Mitsuba's Smith shadowing term for direction v and microfacet m (0 when v sees m's back). */
INLINE float mf_g1(MfDist d, vec3 v, vec3 m) {
    if (dot3(v, m) * v.z <= 0.0f) return 0.0f;
    float t2 = mf_tan2_alpha(d, v);
    if (!(t2 > 0.0f)) return 1.0f;
    if (d.type == MF_GGX) return 2.0f / (1.0f + sqrt(1.0f + t2));
    float a = 1.0f / sqrt(t2);
    if (a >= 1.6f) return 1.0f;
    return (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
}

/* Smith's exact G1 (Lambda of the Gaussian or GGX slope distribution), for normalising visible normals. */
INLINE float mf_g1_exact(MfDist d, vec3 v) {
    float t2 = mf_tan2_alpha(d, v);
    if (!(t2 > 0.0f)) return 1.0f;
    if (d.type == MF_GGX) return 2.0f / (1.0f + sqrt(1.0f + t2));
    float a = 1.0f / sqrt(t2);
    /* Lambda = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2; both terms vanish together for large a */
    float lambda = 0.5f * (exp(-a * a) * INV_SQRT_PI / a - erfc(a));
    return 1.0f / (1.0f + maxf(lambda, 0.0f));
}

/* Density of the sampled normal m over solid angle, given wi (above the surface). */
INLINE float mf_pdf(MfDist d, vec3 wi, vec3 m) {
    float D = mf_d(d, m);
    if (!d.visible) return D * m.z;
    float wm = dot3(wi, m);
    if (wm <= 0.0f || wi.z <= 0.0f) return 0.0f;
    return mf_g1_exact(d, wi) * wm * D / wi.z;
}

/* Inverse error function (Giles 2010, single-precision approximation). */
INLINE float mf_erfinv(float x) {
    float w = -log(maxf((1.0f - x) * (1.0f + x), 1e-30f)), p;
    if (w < 5.0f) {
        w -= 2.5f;
        p = 2.81022636e-08f;
        p = 3.43273939e-07f + p * w; p = -3.5233877e-06f + p * w; p = -4.39150654e-06f + p * w;
        p = 0.00021858087f + p * w; p = -0.00125372503f + p * w; p = -0.00417768164f + p * w;
        p = 0.246640727f + p * w; p = 1.50140941f + p * w;
    } else {
        w = sqrt(w) - 3.0f;
        p = -0.000200214257f;
        p = 0.000100950558f + p * w; p = 0.00134934322f + p * w; p = -0.00367342844f + p * w;
        p = 0.00573950773f + p * w; p = -0.0076224613f + p * w; p = 0.00943887047f + p * w;
        p = 1.00167406f + p * w; p = 2.83297682f + p * w;
    }
    return p * x;
}

/* Slopes of the unit-roughness Beckmann surface visible from a direction at cos(theta) in the xz-plane
   (Jakob 2014): slope x by inverting its CDF C(b) = N (1 + b + tan/sqrt(pi) exp(-erfinv(b)^2)), b = erf(x),
   with Newton steps kept inside a bisection bracket; slope y is an independent Gaussian. */
INLINE float2 mf_beckmann_visible_slopes(float cos_t, float2 u) {
    if (cos_t > 0.99999f) {
        float r = sqrt(-log(1.0f - u.x));
        float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
        return (float2)(r * sc.y, r * sc.x);
    }
    float sin_t = safe_sqrt(1.0f - cos_t * cos_t);
    float tan_t = sin_t / cos_t, cot_t = cos_t / sin_t;
    float lo = -1.0f, hi = erf(cot_t);
    float ux = maxf(u.x, 1e-6f);
    float norm = 1.0f / (1.0f + hi + INV_SQRT_PI * tan_t * exp(-cot_t * cot_t));
    /* a good first guess: a fit of the CDF's inverse in theta */
    float th = acos(cos_t);
    float fit = 1.0f + th * (-0.876f + th * (0.4265f - 0.0594f * th));
    float b = hi - (1.0f + hi) * pow(1.0f - ux, fit);
    for (int it = 0; it < 12; ++it) {
        if (!(b >= lo && b <= hi)) b = 0.5f * (lo + hi);
        float x = mf_erfinv(b);
        float value = norm * (1.0f + b + INV_SQRT_PI * tan_t * exp(-x * x)) - ux;
        if (fabs(value) < 1e-6f) break;
        if (value > 0.0f) hi = b; else lo = b;
        b -= value / (norm * (1.0f - x * tan_t));
    }
    return (float2)(mf_erfinv(b), mf_erfinv(2.0f * u.y - 1.0f));
}

/* Draw a microfacet normal (upper hemisphere) for wi (above the surface). */
INLINE vec3 mf_sample(MfDist d, vec3 wi, float2 u) {
    float2 s;
    if (!d.visible) {
        /* slopes of the whole surface: Gaussian (Beckmann) or r^2 = u/(1-u) (GGX) radially, then stretched */
        float r = d.type == MF_BECKMANN ? sqrt(-log(1.0f - u.x)) : sqrt(u.x / (1.0f - u.x));
        float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
        s = (float2)(r * sc.y * d.ax, r * sc.x * d.ay);
        return normalize3(v3(-s.x, -s.y, 1.0f));
    }
    /* to the unit-roughness configuration */
    vec3 v = normalize3(v3(d.ax * wi.x, d.ay * wi.y, wi.z));
    if (d.type == MF_GGX) {
        /* Heitz 2018: a point on the projected hemisphere seen from v, lifted back onto it */
        float l2 = v.x * v.x + v.y * v.y;
        vec3 t1 = l2 > 0.0f ? vscale(v3(-v.y, v.x, 0.0f), 1.0f / sqrt(l2)) : v3(1.0f, 0.0f, 0.0f);
        vec3 t2 = cross3(v, t1);
        float r = sqrt(u.x);
        float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
        float p1 = r * sc.y, p2 = r * sc.x;
        float h = 0.5f * (1.0f + v.z);
        p2 = (1.0f - h) * safe_sqrt(1.0f - p1 * p1) + h * p2;
        float p3 = safe_sqrt(1.0f - p1 * p1 - p2 * p2);
        vec3 n = vadd(vadd(vscale(t1, p1), vscale(t2, p2)), vscale(v, p3));
        return normalize3(v3(d.ax * n.x, d.ay * n.y, maxf(n.z, 1e-6f)));
    }
    float2 sl = mf_beckmann_visible_slopes(v.z, u);
    float l = sqrt(v.x * v.x + v.y * v.y);
    float cp = l > 0.0f ? v.x / l : 1.0f, sp = l > 0.0f ? v.y / l : 0.0f;
    s = (float2)(cp * sl.x - sp * sl.y, sp * sl.x + cp * sl.y);
    return normalize3(v3(-s.x * d.ax, -s.y * d.ay, 1.0f));
}

/* Unpolarised Fresnel reflectance of a conductor with complex index eta + i k (relative to the outside), per
   channel, for cos_i >= 0 (Moeller, Optics, 1988; also in pbrt). eta = 0, k = 1 reflects everything. */
INLINE float fresnel_conductor1(float c, float eta, float k) {
    float c2 = c * c, s2 = 1.0f - c2, s4 = s2 * s2;
    float t0 = eta * eta - k * k - s2;
    float a2b2 = safe_sqrt(t0 * t0 + 4.0f * eta * eta * k * k);
    float a = safe_sqrt(0.5f * (a2b2 + t0));
    float t1 = a2b2 + c2, t2 = 2.0f * c * a;
    float rs = (t1 - t2) / (t1 + t2);
    float t3 = a2b2 * c2 + s4, t4 = t2 * s2;
    float rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5f * (rs + rp);
}
INLINE vec3 fresnel_conductor(float c, vec3 eta, vec3 k) {
    return v3(fresnel_conductor1(c, eta.x, k.x), fresnel_conductor1(c, eta.y, k.y),
              fresnel_conductor1(c, eta.z, k.z));
}

/* Refraction of wi about the microfacet m: r = eta_i / eta_t (wi's side over wo's side), cos_t = |cos| of the
   refracted direction (from fresnel_dielectric). */
INLINE vec3 refract_about(vec3 wi, vec3 m, float r, float cos_t) {
    float c = dot3(wi, m);
    return vsub(vscale(m, r * c - (c >= 0.0f ? cos_t : -cos_t)), vscale(wi, r));
}

/* A third uniform number for a choice made after u drew the microfacet (the BSDF interface has two sample
   dimensions): a hash of u's bits (Wellons' lowbias32), independent of u's value for all practical purposes. */
INLINE float mf_extra_uniform(float2 u) {
    uint x = as_uint(u.x) * 0x9E3779B9u ^ as_uint(u.y);
    x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
    return (float)(x >> 8) * (1.0f / 16777216.0f);
}

#endif
