/* gridvolume (clrender/volumes/gridvolume.py): voxels of a Mitsuba .vol file, looked up as Mitsuba 3.9.1's does
   (Dr.Jit's Texture3f): the point is taken to the grid's unit cube by to_local, voxel centres sit at
   (i + 0.5) / res; trilinear interpolation between the eight nearest, or the nearest one; indices outside the grid
   wrapped by the wrap mode. Row: p.gridvolume.to_local[0..2] (rows of the affine map world -> unit cube),
   .res (xres, yres, zres, channels: 1 or 3), .offset (first voxel value in sd->grid_data), .filter (0 trilinear,
   1 nearest), .wrap (0 repeat, 1 mirror, 2 clamp). The lookups are kernels/grid.h's. */
#ifndef CLRENDER_VOLUMES_GRIDVOLUME_H
#define CLRENDER_VOLUMES_GRIDVOLUME_H
#include "../grid.h"

INLINE vec3 gridvolume_eval(const SceneData* sd, __global const Volume* v, vec3 p) {
    uint4 r = v->p.gridvolume.res;
    uint wrap = v->p.gridvolume.wrap;
    __global const float* data = sd->grid_data + v->p.gridvolume.offset;
    int n[3] = {(int)r.x, (int)r.y, (int)r.z};
    float u[3];
    for (int k = 0; k < 3; ++k) {
        float4 row = v->p.gridvolume.to_local[k];
        u[k] = (row.x * p.x + row.y * p.y + row.z * p.z + row.w) * (float)n[k];
    }
    if (v->p.gridvolume.filter == 1u)
        return grid_value(data, r, wrap_index(floor_index(u[0]), n[0], wrap), wrap_index(floor_index(u[1]), n[1], wrap),
                          wrap_index(floor_index(u[2]), n[2], wrap));
    /* voxel centres at (i + 0.5) / res: value i at index coordinate u - 0.5 = i */
    return grid_trilinear(data, r, v3(u[0] - 0.5f, u[1] - 0.5f, u[2] - 0.5f), wrap);
}
#endif
