/* gridvolume (clrender/volumes/gridvolume.py): voxels of a Mitsuba .vol file, looked up as Mitsuba 3.9.1's does
   (Dr.Jit's Texture3f): the point is taken to the grid's unit cube by to_local, voxel centres sit at
   (i + 0.5) / res; trilinear interpolation between the eight nearest, or the nearest one; indices outside the grid
   wrapped by the wrap mode. Row: p.gridvolume.to_local[0..2] (rows of the affine map world -> unit cube),
   .res (xres, yres, zres, channels: 1 or 3), .offset (first voxel value in sd->grid_data), .filter (0 trilinear,
   1 nearest), .wrap (0 repeat, 1 mirror, 2 clamp). */
#ifndef CLRENDER_VOLUMES_GRIDVOLUME_H
#define CLRENDER_VOLUMES_GRIDVOLUME_H

INLINE vec3 gridvolume_voxel(const SceneData* sd, __global const Volume* v, int x, int y, int z) {
    uint4 r = v->p.gridvolume.res;
    __global const float* g = sd->grid_data + v->p.gridvolume.offset +
                              (((uint)z * r.y + (uint)y) * r.x + (uint)x) * r.w;
    return r.w == 1u ? v3s(g[0]) : v3(g[0], g[1], g[2]);
}

INLINE vec3 gridvolume_eval(const SceneData* sd, __global const Volume* v, vec3 p) {
    uint4 r = v->p.gridvolume.res;
    uint wrap = v->p.gridvolume.wrap;
    int n[3] = {(int)r.x, (int)r.y, (int)r.z};
    float u[3];
    for (int k = 0; k < 3; ++k) {
        float4 row = v->p.gridvolume.to_local[k];
        u[k] = (row.x * p.x + row.y * p.y + row.z * p.z + row.w) * (float)n[k];
    }
    if (v->p.gridvolume.filter == 1u)
        return gridvolume_voxel(sd, v, wrap_index(floor_index(u[0]), n[0], wrap),
                                wrap_index(floor_index(u[1]), n[1], wrap),
                                wrap_index(floor_index(u[2]), n[2], wrap));
    int i0[3], i1[3];
    float f[3];
    for (int k = 0; k < 3; ++k) {
        float c = u[k] - 0.5f, c0 = floor(c);
        f[k] = c - c0;
        int i = floor_index(c0);
        i0[k] = wrap_index(i, n[k], wrap);
        i1[k] = wrap_index(i + 1, n[k], wrap);
    }
    vec3 acc = v3s(0.0f);
    for (int c = 0; c < 8; ++c) {
        bool bx = (c & 1) != 0, by = (c & 2) != 0, bz = (c & 4) != 0;
        float w = (bx ? f[0] : 1.0f - f[0]) * (by ? f[1] : 1.0f - f[1]) * (bz ? f[2] : 1.0f - f[2]);
        if (w > 0.0f)
            acc = vmad(gridvolume_voxel(sd, v, bx ? i1[0] : i0[0], by ? i1[1] : i0[1], bz ? i1[2] : i0[2]), w, acc);
    }
    return acc;
}
#endif
