/* What normalmap and bumpmap share (Mitsuba 3.9's perturbed-frame adapters): the frame the perturbed normal gives,
   the query restated in it, and the terminator's shadowing term. The perturbed normal n comes in the local frame
   (z = the shading normal), unnormalised. Checked against Mitsuba 3.9.1 itself (tests/test_mitsuba_perturbed.py):
   - flip_invalid_normals (default on): where wi.z (wi . n) <= 0, n's tangential part is mirrored (-x, -y, z), so
     the perturbed normal faces wi (Schuessler et al. 2017); then n is normalised ((0, 0, 1) if it cannot be);
   - s = `tangent` made orthogonal to n (Gram-Schmidt), t = n x s: normalmap takes the local x axis (the shading
     frame's dp/du direction), bumpmap Mitsuba's world dp/du read as if it were local (what 3.9.1 does; it only turns
     the frame about n, which an isotropic BSDF does not see); where that fails, the x axis, then the y axis;
   - a direction is only reflected where it lies on the same side of both frames (wo.z and its perturbed z agree):
     elsewhere eval, pdf and the sample's weight are 0; Mitsuba's eval holds the child's cosine, of wo in the
     perturbed frame, where ours holds none and the integrators multiply by |cos| in the shading frame: eval is the
     child's times |cos_perturbed / cos| (the sample's weight, f cos / pdf, is the child's as it is);
   - use_shadowing_function (default on): eval and the sample's weight are scaled by Conty Estevez et al. 2019's
     G = 2 / (1 + sqrt(1 + a2 tan^2 theta_o)), a2 = min(tan^2 theta_n / 8, 1), theta_o of wo in the original frame
     (the pdf is not: weight == eval cos / pdf still holds). */
#ifndef CLRENDER_BSDFS_PERTURB_H
#define CLRENDER_BSDFS_PERTURB_H
#include "common.h"
#include "frame.h"

#define PERTURB_FLIP 1u      /* options: flip_invalid_normals */
#define PERTURB_SHADOW 2u    /* options: use_shadowing_function */

INLINE vec3 perturb_unit_or(vec3 v, vec3 fallback) {
    float l2 = dot3(v, v);
    float inv = 1.0f / sqrt(l2);
    return l2 > 0.0f && isfinite(inv) ? vscale(v, inv) : fallback;
}

INLINE Frame perturbed_frame(vec3 n, vec3 wi, vec3 tangent, uint options) {
    if ((options & PERTURB_FLIP) && wi.z * dot3(wi, n) <= 0.0f) n = v3(-n.x, -n.y, n.z);
    Frame f;
    f.n = perturb_unit_or(n, v3(0.0f, 0.0f, 1.0f));
    vec3 x = v3(1.0f, 0.0f, 0.0f);
    f.s = perturb_unit_or(vsub(tangent, vscale(f.n, dot3(f.n, tangent))),
                          perturb_unit_or(vsub(x, vscale(f.n, f.n.x)), v3(0.0f, 1.0f, 0.0f)));
    f.t = cross3(f.n, f.s);
    return f;
}

/* q restated in the frame f (wi, wo and the surface's derivatives, so that a wrapper nested inside sees what
   Mitsuba's perturbed interaction holds); whether wo lies on the same side of both frames. */
INLINE bool perturb_query(const Frame* f, const BsdfQuery* q, BsdfQuery* c) {
    *c = *q;
    c->wi = to_local(f, q->wi);
    c->wo = to_local(f, q->wo);
#ifdef CLR_SURFACE_DERIVATIVES
    c->dpdu = to_local(f, q->dpdu);
    c->dpdv = to_local(f, q->dpdv);
    c->ng = to_local(f, q->ng);
#endif
    return q->wo.z * c->wo.z > 0.0f;
}

INLINE float perturb_tan2(vec3 v) { return maxf(0.0f, 1.0f - v.z * v.z) / (v.z * v.z); }

INLINE float perturb_shadowing(uint options, const Frame* f, vec3 wo) {
    if (!(options & PERTURB_SHADOW)) return 1.0f;
    float a2 = minf(0.125f * perturb_tan2(f->n), 1.0f);
    return 2.0f / (1.0f + sqrt(1.0f + a2 * perturb_tan2(wo)));
}

/* The methods of a perturbed-frame wrapper NAME (normalmap, bumpmap), for one nesting level (COMPOSITE_FN,
   CHILD_FN): its frame comes from NAME##_frame(b, q), its row holds p.NAME.child and p.NAME.options.
   eval: the child's f holds no cosine, which the integrators take of wo in this frame, not the child's.
   normal: the perturbed normal (aov's sh_normal), a wrapper's own, not its child's (Mitsuba 3.9's sh_frame). */
#define PERTURB_WRAPPER(NAME)                                                                                    \
INLINE vec3 COMPOSITE_FN(NAME##_eval)(__global const Bsdf* b, const BsdfQuery* q) {                              \
    Frame f = NAME##_frame(b, q);                                                                                \
    BsdfQuery c;                                                                                                 \
    if (!perturb_query(&f, q, &c)) return v3s(0.0f);                                                             \
    return vscale(CHILD_FN(eval)(b + b->p.NAME.child, &c),                                                       \
                  fabs(c.wo.z) / fabs(q->wo.z) * perturb_shadowing(b->p.NAME.options, &f, q->wo));               \
}                                                                                                                \
INLINE float COMPOSITE_FN(NAME##_pdf)(__global const Bsdf* b, const BsdfQuery* q) {                              \
    Frame f = NAME##_frame(b, q);                                                                                \
    BsdfQuery c;                                                                                                 \
    if (!perturb_query(&f, q, &c)) return 0.0f;                                                                  \
    return CHILD_FN(pdf)(b + b->p.NAME.child, &c);                                                               \
}                                                                                                                \
INLINE vec3 COMPOSITE_FN(NAME##_sample)(__global const Bsdf* b, BsdfQuery* q, float2 u) {                        \
    Frame f = NAME##_frame(b, q);                                                                                \
    BsdfQuery c;                                                                                                 \
    perturb_query(&f, q, &c);                                                                                    \
    vec3 w = CHILD_FN(sample)(b + b->p.NAME.child, &c, u);                                                       \
    q->wo = to_world(&f, c.wo);                                                                                  \
    q->eta = c.eta;                                                                                              \
    q->measure = c.measure;                                                                                      \
    if (!(c.wo.z * q->wo.z > 0.0f)) return v3s(0.0f);                                                            \
    return vscale(w, perturb_shadowing(b->p.NAME.options, &f, q->wo));                                           \
}                                                                                                                \
INLINE vec3 COMPOSITE_FN(NAME##_albedo)(__global const Bsdf* b, const BsdfQuery* q) {                            \
    return CHILD_FN(albedo)(b + b->p.NAME.child, q);                                                             \
}                                                                                                                \
INLINE vec3 COMPOSITE_FN(NAME##_normal)(__global const Bsdf* b, const BsdfQuery* q) {                            \
    return NAME##_frame(b, q).n;                                                                                 \
}

#endif
