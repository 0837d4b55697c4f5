/* Analytic spheres (clrender/shapes/sphere.py): the surface at a hit, and sampling of the visible cap.

   Row: first = the sphere's row of the `spheres` table (centre xyz, radius w); p.sphere.rot = its own frame's
   rotation (clrender/shapes/sphere.py); SHAPE_FLIP_NORMALS: normals point
   inward (Mitsuba's flip_normals; uv is unchanged); SHAPE_NEEDS_UV when its BSDF reads textures (uv = (atan2(n.y, n.x) / 2pi in [0,1), acos(n.z) / pi)
   with n in the sphere's own frame, and the shading frame follows dp/du (along phi there), as Mitsuba's; otherwise
   uv is (0, 0) and the frame is the normal's: atan2 and acos cost more than the rest of a hit);
   area = 4 pi r^2.
   Seen from outside (|ref - c| > r): uniform directions in the cone of half-angle asin(r / |ref - c|) about
   c - ref, density 1 / (2 pi (1 - cos theta_max)); the point is the near intersection of that direction with the
   sphere. From inside: uniform by area. */
#ifndef CLRENDER_SHAPES_SPHERE_H
#define CLRENDER_SHAPES_SPHERE_H
#include "common.h"

/* 1 - cos(theta_max) of the cone a sphere subtends, stable for small spheres: sin^2 / (1 + cos). */
INLINE float sphere_one_minus_cos(float r2, float d2) {
    float sin2 = r2 / d2;
    float cosm = safe_sqrt(1.0f - sin2);
    return sin2 / (1.0f + cosm);
}

/* v turned by the sphere's rotation rot (inverse: backwards), mirrored where w's sign bit says so. */
INLINE vec3 sphere_turn(float4 q, vec3 v, float inverse) {
    vec3 c = cross3(vxyz(q), v);
    v = vadd(vmad(c, 2.0f * inverse * fabs(q.w), v), vscale(cross3(vxyz(q), c), 2.0f));
    return (as_uint(q.w) >> 31) ? vneg(v) : v;
}

/* Mitsuba's dp/du at the unit normal n (direction only): along phi in the sphere's own frame. */
INLINE vec3 sphere_dpdu(__global const Shape* s, vec3 n) {
    float4 q = s->p.sphere.rot;
    vec3 l = sphere_turn(q, n, -1.0f);
    return sphere_turn(q, v3(-l.y, l.x, 0.0f), 1.0f);
}

#ifdef CLR_SURFACE_DERIVATIVES
/* Mitsuba's dp/du and dp/dv at the unit normal n, with their lengths: 2 pi r (-y, x, 0) and
   pi r (z cos phi, z sin phi, -sin theta) in the sphere's own frame, (1, 0, 0) for dp/dv at the poles. */
INLINE void sphere_derivatives(__global const Shape* s, float r, vec3 n, vec3* dpdu, vec3* dpdv) {
    float4 q = s->p.sphere.rot;
    vec3 l = sphere_turn(q, n, -1.0f);
    float rd = sqrt(l.x * l.x + l.y * l.y);
    vec3 dv = rd > 0.0f ? v3(l.z * l.x / rd, l.z * l.y / rd, -rd) : v3(1.0f, 0.0f, 0.0f);
    *dpdu = vscale(sphere_turn(q, v3(-l.y, l.x, 0.0f), 1.0f), 2.0f * M_PI_F_ * r);
    *dpdv = vscale(sphere_turn(q, dv, 1.0f), M_PI_F_ * r);
}
#endif

/* uv of the unit normal n (only where SHAPE_NEEDS_UV: atan2 and acos cost more than the rest of a hit), taken in
   the sphere's own frame: n turned back by the quaternion rot (w's sign bit: a mirrored frame). */
INLINE float2 sphere_uv(__global const Shape* s, vec3 n) {
    if (!(s->flags & SHAPE_NEEDS_UV)) return (float2)(0.0f);
    n = sphere_turn(s->p.sphere.rot, n, -1.0f);
    float u = atan2(n.y, n.x) * INV_TWOPI;
    return (float2)(u < 0.0f ? u + 1.0f : u, acos(clampf(n.z, -1.0f, 1.0f)) * INV_PI);
}

INLINE bool sphere_surface(const SceneData* sd, __global const Shape* s, const Ray* r, const Hit* h,
                           Intersection* its) {
    float4 sp = sd->spheres[s->first];
    vec3 p = vmad(r->d, h->t, r->o);
    vec3 n = normalize3(vsub(p, vxyz(sp)));
    its->p = vmad(n, sp.w, vxyz(sp)); /* re-project: the hit point lies on the sphere to float precision */
    its->off = SPAWN_OFFSET * (max3(vabs(vxyz(sp))) + sp.w);
    its->po = its->p;
    vec3 nf = (s->flags & SHAPE_FLIP_NORMALS) ? vneg(n) : n;
    its->ng = nf;
    its->sh = (s->flags & SHAPE_NEEDS_UV) ? frame_from_tangent(nf, sphere_dpdu(s, n)) : frame_from_normal(nf);
    its->uv = sphere_uv(s, n);
#ifdef CLR_SURFACE_DERIVATIVES
    its->dpdu = its->dpdv = v3s(0.0f);
    if (s->flags & SHAPE_NEEDS_UV) sphere_derivatives(s, sp.w, n, &its->dpdu, &its->dpdv);
#endif
    its->tri = NONE;
    return true;
}

INLINE float sphere_sample(const SceneData* sd, __global const Shape* s, vec3 ref, float2 u, ShapeSample* ss) {
    float4 sp = sd->spheres[s->first];
    vec3 oc = vsub(vxyz(sp), ref);
    float d2 = dot3(oc, oc), r2 = sp.w * sp.w;
    if (d2 > r2) {
        /* Cone sampling about the axis toward the centre; 1 - cos theta is formed directly (no cancellation for
           distant spheres). */
        float d = sqrt(d2);
        vec3 axis = vscale(oc, 1.0f / d);
        float omc_max = sphere_one_minus_cos(r2, d2);
        float omc = u.x * omc_max;
        float cos_t = 1.0f - omc;
        float sin2 = omc * (2.0f - omc);
        float sin_t = safe_sqrt(sin2);
        float phi = 2.0f * M_PI_F_ * u.y;
        Frame f = frame_from_normal(axis);
        float2 sc = sin_cos(phi);
        vec3 wi = normalize3(to_world(&f, v3(sin_t * sc.y, sin_t * sc.x, cos_t)));
        /* near intersection: t = d cos - sqrt(r^2 - d^2 sin^2) */
        float t = d * cos_t - safe_sqrt(r2 - d2 * sin2);
        vec3 n = normalize3(vsub(vmad(wi, t, ref), vxyz(sp)));
        vec3 p = vmad(n, sp.w, vxyz(sp));
        ss->uv = sphere_uv(s, n);
        if (s->flags & SHAPE_FLIP_NORMALS) n = vneg(n);
        ss->wi = wi;
        ss->p = p;
        ss->n = n;
        ss->ng = n;
        ss->dist = len3(vsub(p, ref));
        return 1.0f / (2.0f * M_PI_F_ * omc_max);
    }
    /* inside: uniform on the sphere */
    vec3 n = square_to_uniform_sphere(u);
    vec3 nf = (s->flags & SHAPE_FLIP_NORMALS) ? vneg(n) : n;
    float pdf = shape_point_sample(ss, ref, vmad(n, sp.w, vxyz(sp)), nf, nf, 1.0f / s->area);
    ss->uv = sphere_uv(s, n);
    return pdf;
}

INLINE float sphere_pdf(const SceneData* sd, __global const Shape* s, vec3 ref, vec3 p, vec3 ng, vec3 wi) {
    float4 sp = sd->spheres[s->first];
    vec3 oc = vsub(vxyz(sp), ref);
    float d2 = dot3(oc, oc), r2 = sp.w * sp.w;
    if (d2 > r2) {
        /* the direction must meet the sphere: in front, closest approach within r (relative slack for rays that
           hit exactly at the silhouette) */
        vec3 c = cross3(wi, oc);
        if (dot3(wi, oc) <= 0.0f || dot3(c, c) > r2 * 1.0001f) return 0.0f;
        return 1.0f / (2.0f * M_PI_F_ * sphere_one_minus_cos(r2, d2));
    }
    return shape_solid_angle_pdf(1.0f / s->area, ref, p, ng, wi);
}

#endif
