/* Mitsuba 3's bitmap texture (clrender/textures/bitmap.py gives the conventions, checked against Mitsuba).
   Row: p.bitmap.dims = (W, H, filter: 0 bilinear / 1 nearest, wrap: 0 repeat / 1 mirror / 2 clamp);
   to_uv[0..1].xyz = rows of the 2-D affine uv map. The W*H pixels (float4, row by row, row 0 at t = 0) follow the
   row in the textures table: a texture's eval sees that table only. */
#ifndef CLRENDER_TEXTURES_BITMAP_H
#define CLRENDER_TEXTURES_BITMAP_H

INLINE vec3 bitmap_texel(__global const Texture* t, int x, int y) {
    __global const float4* px = (__global const float4*)(t + 1);
    return vrow(px[y * (int)t->p.bitmap.dims.x + x]);
}

/* The four texels around a (bilinear) lookup at texture coordinates (s, tt) and their weights a (along x) and b. */
typedef struct { int xa, xb, ya, yb; float a, b; } BitmapTaps;

INLINE BitmapTaps bitmap_taps(uint4 d, float s, float tt) {
    int w = (int)d.x, h = (int)d.y;
    float fx = s * (float)w - 0.5f, fy = tt * (float)h - 0.5f;
    float x0f = floor(fx), y0f = floor(fy);
    BitmapTaps k;
    k.a = fx - x0f;
    k.b = fy - y0f;
    int x0 = floor_index(x0f), y0 = floor_index(y0f);
    k.xa = wrap_index(x0, w, d.w);
    k.xb = wrap_index(x0 + 1, w, d.w);
    k.ya = wrap_index(y0, h, d.w);
    k.yb = wrap_index(y0 + 1, h, d.w);
    return k;
}

INLINE vec3 bitmap_eval(__global const Texture* t, float2 uv) {
    uint4 d = t->p.bitmap.dims;
    int w = (int)d.x, h = (int)d.y;
    float4 r0 = t->p.bitmap.to_uv[0], r1 = t->p.bitmap.to_uv[1];
    float s = r0.x * uv.x + r0.y * uv.y + r0.z, tt = r1.x * uv.x + r1.y * uv.y + r1.z;
    if (d.z == 1u)
        return bitmap_texel(t, wrap_index(floor_index(s * (float)w), w, d.w),
                            wrap_index(floor_index(tt * (float)h), h, d.w));
    BitmapTaps k = bitmap_taps(d, s, tt);
    vec3 top = vmad(bitmap_texel(t, k.xa, k.ya), 1.0f - k.a, vscale(bitmap_texel(t, k.xb, k.ya), k.a));
    vec3 bot = vmad(bitmap_texel(t, k.xa, k.yb), 1.0f - k.a, vscale(bitmap_texel(t, k.xb, k.yb), k.a));
    return vmad(top, 1.0f - k.b, vscale(bot, k.b));
}

/* The uv gradient of the first channel as Mitsuba 3.9's eval_1_grad takes it (bumpmap's height): the derivative of
   the bilinear interpolation in pixel units, taken through the transpose of to_uv's linear part and scaled by the
   resolution afterwards ((W, H) times it: not the chain rule's W and H inside the sum, which differs only for a
   to_uv that turns a non-square image); `nearest` has none (0). */
INLINE float2 bitmap_grad(__global const Texture* t, float2 uv) {
    uint4 d = t->p.bitmap.dims;
    if (d.z == 1u) return (float2)(0.0f);
    float4 r0 = t->p.bitmap.to_uv[0], r1 = t->p.bitmap.to_uv[1];
    float s = r0.x * uv.x + r0.y * uv.y + r0.z, tt = r1.x * uv.x + r1.y * uv.y + r1.z;
    BitmapTaps k = bitmap_taps(d, s, tt);
    float a = k.a, b = k.b;
    float f00 = bitmap_texel(t, k.xa, k.ya).x, f10 = bitmap_texel(t, k.xb, k.ya).x;
    float f01 = bitmap_texel(t, k.xa, k.yb).x, f11 = bitmap_texel(t, k.xb, k.yb).x;
    float dx = (1.0f - b) * (f10 - f00) + b * (f11 - f01);
    float dy = (1.0f - a) * (f01 - f00) + a * (f11 - f10);
    return (float2)((float)d.x * (r0.x * dx + r1.x * dy), (float)d.y * (r0.y * dx + r1.y * dy));
}

#endif
