"""Small scenes whose images are known in closed form (shared by the integrator tests)."""
import numpy as np

RHO = np.array([0.5, 0.3, 0.8])
X0 = np.array([0.2, -0.1, 0.0])          # the plane point every camera ray hits
PLANE = "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n"
QUAD_LIGHT = np.array([[-0.3, -0.5, 1.0], [0.7, -0.5, 1.0], [0.7, 0.2, 1.0], [-0.3, 0.2, 1.0]])
LE = np.array([4.0, 5.0, 6.0])


def camera(width=2, height=2, fov=0.05, target=X0, origin=(2.5, 0.1, 1.5)):
    t = ",".join(f"{v:.9g}" for v in target)
    o = ",".join(f"{v:.9g}" for v in origin)
    return (f'<camera type="perspective"><integer name="width" value="{width}"/>'
            f'<integer name="height" value="{height}"/><float name="fov" value="{fov}"/>'
            f'<transform name="toWorld"><lookat origin="{o}" target="{t}" up="0,0,1"/></transform>'
            f'<rfilter type="box"/></camera>')


def plane_mesh(path):
    path.write_text(PLANE)
    rho = ",".join(map(str, RHO))
    return (f'<mesh type="obj"><string name="filename" value="{path.name}"/>'
            f'<bsdf type="diffuse"><color name="albedo" value="{rho}"/></bsdf></mesh>')


def polygon_light_scene(d, integrator):
    # Wound clockwise seen from above, so the face normal points down at the plane.
    q = QUAD_LIGHT[::-1]
    (d / "light.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in q) + "f 1 2 3 4\n")
    return (f'<scene><integrator type="{integrator}"/>{camera()}{plane_mesh(d / "plane.obj")}'
            f'<mesh type="obj"><string name="filename" value="light.obj"/><bsdf type="diffuse">'
            f'<color name="albedo" value="0"/></bsdf><emitter type="area"><color name="radiance" '
            f'value="{",".join(map(str, LE))}"/></emitter></mesh></scene>')


def polygon_irradiance(x, verts, n=np.array([0.0, 0.0, 1.0])):
    """Lambert: E = (1/2) Σ Θ_i (Γ_i · n) per unit radiance, for a polygon seen from x."""
    v = verts - x
    total = 0.0
    for i in range(len(v)):
        a, b = v[i], v[(i + 1) % len(v)]
        theta = np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1))
        g = np.cross(a, b)
        total += theta * (g / np.linalg.norm(g)) @ n
    return abs(total) / 2.0


def polygon_light_value():
    return RHO / np.pi * LE * polygon_irradiance(X0, QUAD_LIGHT)


POINT_POS = np.array([0.3, -0.2, 2.0])
POWER = np.array([50.0, 60.0, 70.0])


def point_light_scene(d, integrator):
    p = ",".join(map(str, POINT_POS))
    extra = ""
    if integrator == "simple":
        return (f'<scene><integrator type="simple"><point name="position" value="{p}"/>'
                f'<color name="energy" value="{",".join(map(str, POWER))}"/></integrator>{camera()}'
                f'{plane_mesh(d / "plane.obj")}</scene>')
    return (f'<scene><integrator type="{integrator}"/>{camera()}{plane_mesh(d / "plane.obj")}{extra}'
            f'<emitter type="point"><point name="position" value="{p}"/>'
            f'<color name="power" value="{",".join(map(str, POWER))}"/></emitter></scene>')


def point_light_value(simple=False):
    v = POINT_POS - X0
    d2 = v @ v
    cos = v[2] / np.sqrt(d2)
    if simple:
        return POWER / (4 * np.pi ** 2) * cos / d2
    return RHO / np.pi * POWER / (4 * np.pi) * cos / d2


DIST_DIR = np.array([0.3, 0.2, -1.0]) / np.linalg.norm([0.3, 0.2, -1.0])
IRR = np.array([2.0, 3.0, 4.0])


def distant_light_scene(d, integrator):
    return (f'<scene><integrator type="{integrator}"/>{camera()}{plane_mesh(d / "plane.obj")}'
            f'<emitter type="distant"><vector name="direction" value="{",".join(map(str, DIST_DIR))}"/>'
            f'<color name="irradiance" value="{",".join(map(str, IRR))}"/></emitter></scene>')


def distant_light_value():
    return RHO / np.pi * IRR * abs(DIST_DIR[2])


def furnace_scene(d, integrator, rho=0.5, le=1.0):
    """A closed cube, inward normals, every wall diffuse rho and emitting le; the camera inside."""
    c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    inward = []
    for f in faces:  # wind every face so its normal points into the cube (emission side)
        n = np.cross(c[f[1]] - c[f[0]], c[f[2]] - c[f[0]])
        inward.append(f if n @ c[list(f)].mean(axis=0) < 0 else f[::-1])
    lines = [f"v {x:g} {y:g} {z:g}" for x, y, z in c]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in inward]
    (d / "cube.obj").write_text("\n".join(lines) + "\n")
    cam = camera(width=4, height=4, fov=100, target=(0.3, 0.2, -1), origin=(0.1, -0.2, 0.3))
    return (f'<scene><integrator type="{integrator}"/>{cam}<mesh type="obj"><string name="filename" '
            f'value="cube.obj"/><bsdf type="diffuse"><color name="albedo" value="{rho}"/></bsdf>'
            f'<emitter type="area"><color name="radiance" value="{le}"/></emitter></mesh></scene>')
