/* Warping functions: map uniform samples in [0,1)^2 to a distribution, each with its density.
   Densities are with respect to area (square, disk, tent, triangle) or solid angle (directions). */
#ifndef CLRENDER_WARP_H
#define CLRENDER_WARP_H
#include "math.h"

INLINE float2 square_to_uniform_square(float2 u) { return u; }
INLINE float square_to_uniform_square_pdf(float2 p) {
    return (p.x >= 0.0f && p.x <= 1.0f && p.y >= 0.0f && p.y <= 1.0f) ? 1.0f : 0.0f;
}

/* Tent on [-1,1]: density 1-|x| per axis. */
INLINE float tent_1d(float u) { return u < 0.5f ? sqrt(2.0f * u) - 1.0f : 1.0f - sqrt(2.0f - 2.0f * u); }
INLINE float2 square_to_tent(float2 u) { return (float2)(tent_1d(u.x), tent_1d(u.y)); }
INLINE float square_to_tent_pdf(float2 p) {
    float a = 1.0f - fabs(p.x), b = 1.0f - fabs(p.y);
    return (a > 0.0f && b > 0.0f) ? a * b : 0.0f;
}

/* Concentric (Shirley-Chiu) map: low distortion, so stratification survives. */
INLINE float2 square_to_uniform_disk(float2 u) {
    float a = 2.0f * u.x - 1.0f, b = 2.0f * u.y - 1.0f;
    float r, phi;
    if (a * a > b * b) { r = a; phi = (M_PI_F_ / 4.0f) * (b / a); }
    else { r = b; phi = (M_PI_F_ / 2.0f) - (M_PI_F_ / 4.0f) * (a / b); }
    /* the centre by selects, not an early return: two float2 results merged after a branch stay a vector-typed
       phi, which keeps a stage kernel's work-item loop scalar (kernels/math.h) */
    bool centre = a == 0.0f && b == 0.0f;
    float2 sc = sin_cos(centre ? 0.0f : phi);
    return (float2)(centre ? 0.0f : r * sc.y, centre ? 0.0f : r * sc.x);
}
INLINE float square_to_uniform_disk_pdf(float2 p) { return (p.x * p.x + p.y * p.y <= 1.0f) ? INV_PI : 0.0f; }

INLINE vec3 square_to_uniform_sphere(float2 u) {
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrt(1.0f - z * z);
    float phi = 2.0f * M_PI_F_ * u.y;
    float2 sc = sin_cos(phi);
    return v3(r * sc.y, r * sc.x, z);
}
INLINE float square_to_uniform_sphere_pdf(vec3 v) { return INV_FOURPI; }

INLINE vec3 square_to_uniform_hemisphere(float2 u) {
    float z = u.x;
    float r = safe_sqrt(1.0f - z * z);
    float phi = 2.0f * M_PI_F_ * u.y;
    float2 sc = sin_cos(phi);
    return v3(r * sc.y, r * sc.x, z);
}
INLINE float square_to_uniform_hemisphere_pdf(vec3 v) { return v.z > 0.0f ? INV_TWOPI : 0.0f; }

INLINE vec3 square_to_cosine_hemisphere(float2 u) {
    float2 d = square_to_uniform_disk(u);
    float z = safe_sqrt(1.0f - d.x * d.x - d.y * d.y);
    return v3(d.x, d.y, z);
}
INLINE float square_to_cosine_hemisphere_pdf(vec3 v) { return v.z > 0.0f ? v.z * INV_PI : 0.0f; }

/* Uniform directions in the cone of half-angle acos(cos_max) about +z. */
INLINE vec3 square_to_uniform_cone(float2 u, float cos_max) {
    float z = 1.0f - u.x * (1.0f - cos_max);
    float r = safe_sqrt(1.0f - z * z);
    float phi = 2.0f * M_PI_F_ * u.y;
    float2 sc = sin_cos(phi);
    return v3(r * sc.y, r * sc.x, z);
}
INLINE float square_to_uniform_cone_pdf(vec3 v, float cos_max) {
    return (v.z >= cos_max && cos_max < 1.0f) ? 1.0f / (2.0f * M_PI_F_ * (1.0f - cos_max)) : 0.0f;
}

/* Uniform barycentrics (b1, b2) on a triangle, by the square-root map. */
INLINE float2 square_to_uniform_triangle(float2 u) {
    float s = sqrt(u.x);
    return (float2)(1.0f - s, u.y * s);
}
INLINE float square_to_uniform_triangle_pdf(float2 b) {
    return (b.x >= 0.0f && b.y >= 0.0f && b.x + b.y <= 1.0f) ? 2.0f : 0.0f;
}

/* Beckmann microfacet normals, density D(h) cos(theta_h) over solid angle (integrates to 1). */
INLINE vec3 square_to_beckmann(float2 u, float alpha) {
    float tan2 = -alpha * alpha * log(1.0f - u.x);
    float cos_t = 1.0f / sqrt(1.0f + tan2);
    float sin_t = safe_sqrt(1.0f - cos_t * cos_t);
    float phi = 2.0f * M_PI_F_ * u.y;
    float2 sc = sin_cos(phi);
    return v3(sin_t * sc.y, sin_t * sc.x, cos_t);
}
INLINE float beckmann_d(vec3 h, float alpha) {
    /* D(h) itself (without the cos), zero below the surface. */
    float c = h.z;
    if (c <= 0.0f) return 0.0f;
    float c2 = c * c;
    float tan2 = (1.0f - c2) / c2;
    float a2 = alpha * alpha;
    float e = exp(-tan2 / a2);
    /* near the horizon cos^4 underflows to 0 (0/0 = NaN) long after exp() has reached 0 */
    return e > 0.0f ? e / (M_PI_F_ * a2 * c2 * c2) : 0.0f;
}
INLINE float square_to_beckmann_pdf(vec3 h, float alpha) { return beckmann_d(h, alpha) * h.z; }

#endif
