/* Values on a 3-D grid, stored flat in a scene table (sd->grid_data): what the gridvolume volume
   (kernels/volumes/gridvolume.h) and the sdfgrid shape (kernels/shapes/sdfgrid.h) both look up.

   A grid of res = (xres, yres, zres, channels: 1 or 3) holds value (x, y, z, c) at ((z yres + y) xres + x) channels + c
   of `data`, x fastest (a Mitsuba .vol file's order). */
#ifndef CLRENDER_GRID_H
#define CLRENDER_GRID_H
#include "math.h"

/* Value (x, y, z), indices inside the grid: a colour, or one channel in all three. */
INLINE vec3 grid_value(__global const float* data, uint4 res, int x, int y, int z) {
    __global const float* g = data + (((uint)z * res.y + (uint)y) * res.x + (uint)x) * res.w;
    return res.w == 1u ? v3s(g[0]) : v3(g[0], g[1], g[2]);
}

/* The trilinear interpolation at index coordinates c (value (x, y, z) at c = (x, y, z)) between the eight nearest
   values, indices outside the grid wrapped by `wrap` (wrap_index: 0 repeat, 1 mirror, 2 clamp). */
INLINE vec3 grid_trilinear(__global const float* data, uint4 res, vec3 c, uint wrap) {
    int n[3] = {(int)res.x, (int)res.y, (int)res.z};
    float u[3] = {c.x, c.y, c.z};
    int i0[3], i1[3];
    float f[3];
    for (int k = 0; k < 3; ++k) {
        float c0 = floor(u[k]);
        f[k] = u[k] - c0;
        int i = floor_index(c0);
        i0[k] = wrap_index(i, n[k], wrap);
        i1[k] = wrap_index(i + 1, n[k], wrap);
    }
    vec3 acc = v3s(0.0f);
    for (int k = 0; k < 8; ++k) {
        bool bx = (k & 1) != 0, by = (k & 2) != 0, bz = (k & 4) != 0;
        float w = (bx ? f[0] : 1.0f - f[0]) * (by ? f[1] : 1.0f - f[1]) * (bz ? f[2] : 1.0f - f[2]);
        if (w > 0.0f)
            acc = vmad(grid_value(data, res, bx ? i1[0] : i0[0], by ? i1[1] : i0[1], bz ? i1[2] : i0[2]), w, acc);
    }
    return acc;
}

#endif
