"""A closed room made of many meshes, as interiors like Crytek Sponza are built: walls, floor and ceiling cut into
separate panels, pillars that stand through the floor, beams that run through the pillars, all of them shapes of
one Mitsuba `.serialized` file, and a small sphere. Every surface is diffuse with albedo RHO and emits LE toward the
room, so radiance is LE / (1 - RHO) everywhere (the furnace: emission plus the reflection of the same radiance from
every direction), whatever the geometry, as long as no path leaks out of the room, re-hits its own surface from
behind, or is weighted wrongly at a bounce or by Russian roulette. `write_room` writes the file and the scene XML.
"""
from __future__ import annotations

import numpy as np

from clrender.shapes.meshdata import MeshData
from clrender.shapes.serializedfile import write_serialized

RHO = 0.8
LE = 1.0


def quad_mesh(quads):
    """MeshData of quads (each 4 corners, counter-clockwise seen from the side its normal faces): every quad has
    vertices of its own, so its vertex normals are its face normal (a box's shared corners would average them)."""
    quads = np.asarray(quads, np.float64).reshape(-1, 4, 3)
    n = np.cross(quads[:, 1] - quads[:, 0], quads[:, 2] - quads[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    positions = quads.reshape(-1, 3)
    normals = np.repeat(n, 4, axis=0)
    base = 4 * np.arange(len(quads))[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]])
    return MeshData(positions=positions, normals=normals, uvs=None, faces=faces.astype(np.int64))


def box_quads(lo, hi, inward=False):
    """The six faces of the box [lo, hi], normals outward (or inward)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    c = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]])
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (3, 7, 6, 2), (0, 4, 7, 3), (1, 2, 6, 5)]
    quads = np.array([[c[i] for i in f] for f in faces])
    return quads[:, ::-1] if inward else quads


def panels(lo, hi, cuts):
    """The inside of the room [lo, hi] as separate meshes: each face cut into cuts x cuts panels whose shared
    edges have the very same coordinates (one linspace per axis)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    grid = [np.linspace(lo[a], hi[a], cuts + 1) for a in range(3)]
    meshes = []
    for quad in box_quads(lo, hi, inward=True):
        axis = int(np.flatnonzero(np.ptp(quad, axis=0) == 0)[0])
        u, v = [a for a in range(3) if a != axis]
        e1, e2 = quad[1] - quad[0], quad[3] - quad[0]
        for i in range(cuts):
            for j in range(cuts):
                def corner(a, b):
                    p = quad[0] + e1 * a + e2 * b
                    q = p.copy()     # snap to the grid so neighbours agree to the bit
                    for k in (u, v):
                        q[k] = grid[k][int(round((p[k] - lo[k]) / (hi[k] - lo[k]) * cuts))]
                    return q
                s0, s1, t0, t1 = i / cuts, (i + 1) / cuts, j / cuts, (j + 1) / cuts
                meshes.append(quad_mesh([[corner(s0, t0), corner(s1, t0), corner(s1, t1), corner(s0, t1)]]))
    return meshes


def room_meshes(scale=1.0, cuts=3):
    """Panels of the room [-2, 2] x [0, 2] x [-3, 3] (times scale), two rows of three pillars standing through
    the floor, a beam through each row's tops (interpenetrating solids, like an arcade's)."""
    s = scale
    meshes = panels((-2 * s, 0, -3 * s), (2 * s, 2 * s, 3 * s), cuts)
    for x in (-1.2, 1.2):
        for z in (-1.5, 0.0, 1.5):
            meshes.append(quad_mesh(box_quads((s * (x - 0.15), -0.1 * s, s * (z - 0.15)),
                                              (s * (x + 0.15), 1.3 * s, s * (z + 0.15)))))
        meshes.append(quad_mesh(box_quads((s * (x - 0.2), 1.2 * s, -1.8 * s), (s * (x + 0.2), 1.45 * s, 1.8 * s))))
    return meshes


def write_room(folder, scale=1.0, sampler="independent", spp=64, width=48, height=48, integrator=None):
    """room.serialized + room.xml (Mitsuba 3 format) in folder; returns the XML's path. Camera at one end, looking
    down the room past the pillars; a small sphere (radius 0.05 scale) under the ceiling."""
    meshes = room_meshes(scale)
    write_serialized(folder / "room.serialized", [(f"m{i}", m) for i, m in enumerate(meshes)])
    surface = (f'<bsdf type="diffuse"><rgb name="reflectance" value="{RHO}"/></bsdf>'
               f'<emitter type="area"><rgb name="radiance" value="{LE}"/></emitter>')
    shapes = "".join(f'<shape type="serialized"><string name="filename" value="room.serialized"/>'
                     f'<integer name="shape_index" value="{i}"/>{surface}</shape>' for i in range(len(meshes)))
    s = scale
    integrator = integrator or '<integrator type="path"/>'
    xml = (f'<scene version="3.0.0">{integrator}{shapes}'
           f'<shape type="sphere"><point name="center" x="0" y="{1.7 * s}" z="{-1.0 * s}"/>'
           f'<float name="radius" value="{0.05 * s}"/>{surface}</shape>'
           f'<sensor type="perspective"><float name="fov" value="75"/>'
           f'<transform name="to_world"><lookat origin="{0.3 * s},{1.0 * s},{2.7 * s}" '
           f'target="{-0.2 * s},{0.8 * s},{-3 * s}" up="0,1,0"/></transform>'
           f'<sampler type="{sampler}"><integer name="sample_count" value="{spp}"/></sampler>'
           f'<film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/>'
           f'<rfilter type="box"/></film></sensor></scene>')
    path = folder / "room.xml"
    path.write_text(xml)
    return path
