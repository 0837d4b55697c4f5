/* What every BSDF kernel shares: the query record and small helpers (Fresnel, reflection).
   Everything is in the local shading frame (z = shading normal). */
#ifndef CLRENDER_BSDFS_COMMON_H
#define CLRENDER_BSDFS_COMMON_H
#include "math.h"
#include "derivatives.h"

#define MEASURE_SOLID_ANGLE 0u
#define MEASURE_DISCRETE 1u

/* wi points toward where the path came from (= -ray.d); wo is the sampled / queried direction.
   eta: relative index of refraction of the sampled event, eta_t / eta_i (the index on wo's side over the
   index on wi's side): intIOR/extIOR when a dielectric refracts into the object, extIOR/intIOR when it
   refracts out of it, 1 for every reflection. */
typedef struct {
    vec3 wi;
    vec3 wo;
    float eta;
    uint measure;
    float2 uv;
    __global const Texture* textures;  /* the scene's texture table, for parameters that refer to a texture */
    __global const BsdfTable* tables;  /* the scene's bsdf_tables, for BSDFs' lookup tables (roughplastic's T) */
#ifdef CLR_SURFACE_DERIVATIVES
    /* Mitsuba's si.dp_du, si.dp_dv and geometric normal si.n in this (local) frame, and dp_du in world space (what
       bumpmap needs: kernels/bsdfs/perturb.h) */
    vec3 dpdu, dpdv, ng, dpdu_world;
#endif
} BsdfQuery;

/* Unpolarised Fresnel reflectance of a smooth dielectric interface. cos_i is measured against the normal
   on the ext side: cos_i < 0 means the ray arrives from inside (the indices swap). Returns 1 under total
   internal reflection; *cos_t receives |cos| of the refracted direction (0 under TIR). */
INLINE float fresnel_dielectric(float cos_i, float eta_ext, float eta_int, float* cos_t_out) {
    float eta_i = eta_ext, eta_t = eta_int;
    if (cos_i < 0.0f) { eta_i = eta_int; eta_t = eta_ext; cos_i = -cos_i; }
    float eta = eta_i / eta_t;
    float sin2_t = eta * eta * maxf(0.0f, 1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f) { *cos_t_out = 0.0f; return 1.0f; }
    float cos_t = sqrt(1.0f - sin2_t);
    *cos_t_out = cos_t;
    float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

INLINE vec3 reflect_local(vec3 w) { return v3(-w.x, -w.y, w.z); }

/* The weight f |cos| / pdf of a direction sampled from a BSDF's non-delta part, given eval (f) and pdf there;
   0 where the pdf is 0 or NaN: no sample lands there, and f may be infinite or NaN. */
INLINE vec3 bsdf_sample_weight(vec3 f, float cos_o, float pdf) {
    return pdf > 0.0f ? vscale(f, fabs(cos_o) / pdf) : v3s(0.0f);
}

#endif
