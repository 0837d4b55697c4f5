/* bumpmap: the child in the frame of the normal that the height texture's slope gives (kernels/bsdfs/perturb.h):
   with (gu, gv) = scale * the bitmap's uv gradient (bitmap_grad, Mitsuba's eval_1_grad), dp/du and dp/dv get gu
   and gv as their components along the shading normal, n = dp/du x dp/dv, turned to the geometric normal's side.
   Needs the derivatives in the query (kernels/derivatives.h). Row: p.bumpmap = tex (the height bitmap's float
   view, a row of the textures table), scale, child (offset of the child's row), options. Included once per nesting
   level (see twosided.h). */
#ifndef CLRENDER_BSDFS_BUMPMAP_H
#define CLRENDER_BSDFS_BUMPMAP_H
#include "perturb.h"
#include "textures/bitmap.h"
INLINE Frame bumpmap_frame(__global const Bsdf* b, const BsdfQuery* q) {
    float2 g = b->p.bumpmap.scale * bitmap_grad(q->textures + b->p.bumpmap.tex, q->uv);
    vec3 du = v3(q->dpdu.x, q->dpdu.y, g.x), dv = v3(q->dpdv.x, q->dpdv.y, g.y);
    vec3 n = cross3(du, dv);
    if (dot3(q->ng, n) < 0.0f) n = vneg(n);
    return perturbed_frame(n, q->wi, q->dpdu_world, b->p.bumpmap.options);
}
#endif

PERTURB_WRAPPER(bumpmap)
