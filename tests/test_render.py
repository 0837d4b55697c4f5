"""Whole renders: a `normals` image against a numpy ray-cast of the same scene, determinism across pass
splits, av/ao against analytic values, and the output files."""
import numpy as np
import pytest

import clrender
from clrender import renderer as render_mod
from clrender.errors import ClrenderError
from clrender.film import read_exr
from nori_camera import nori_reference

W, H = 48, 36
OBJ = """# a tilted quad with per-vertex normals that differ from the face normal
v -1.5 -1 0.5
v 1.5 -1 -0.5
v 1.5 1.2 -0.5
v -1.5 1.2 0.5
vn 0 0 1
vn 0.3 0 0.954
vn 0.3 0.3 0.905
vn 0 0.3 0.954
f 1//1 2//2 3//3 4//4
"""


def scene_xml(integrator="normals", extra="", filt='<rfilter type="box"><float name="radius" value="0.001"/></rfilter>'):
    return f"""<?xml version="1.0"?>
<scene>
  <integrator type="{integrator}">{extra}</integrator>
  <sampler type="independent"><integer name="sampleCount" value="4"/></sampler>
  <camera type="perspective">
    <integer name="width" value="{W}"/><integer name="height" value="{H}"/><float name="fov" value="60"/>
    <transform name="toWorld"><scale value="-1,1,1"/><lookat origin="0.3,0.2,4" target="0,0,0" up="0,1,0"/></transform>
    {filt}
  </camera>
  <mesh type="obj"><string name="filename" value="quad.obj"/></mesh>
  <mesh type="sphere"><point name="center" value="0.4,-0.1,1.2"/><float name="radius" value="0.5"/></mesh>
</scene>"""


@pytest.fixture()
def scene_dir(tmp_path):
    (tmp_path / "quad.obj").write_text(OBJ)
    return tmp_path


def write_scene(d, **kw):
    p = d / "scene.xml"
    p.write_text(scene_xml(**kw))
    return p


def numpy_normals(cam):
    """Ray-cast the same scene in float64: |shading normal| at the closest hit, 0 on a miss.
    Also returns a mask of pixels whose hit is not within a hair of a silhouette or the quad's diagonal."""
    ys, xs = np.mgrid[0:H, 0:W]
    pos = np.c_[xs.ravel() + 0.5, ys.ravel() + 0.5]
    o, d, tmin, tmax = nori_reference(W, H, 60.0, 1e-4, 1e4, cam.to_world.matrix, pos)
    v = np.array([[-1.5, -1, 0.5], [1.5, -1, -0.5], [1.5, 1.2, -0.5], [-1.5, 1.2, 0.5]])
    vn = np.array([[0, 0, 1], [0.3, 0, 0.954], [0.3, 0.3, 0.905], [0, 0.3, 0.954]])
    best_t = np.full(len(d), np.inf)
    col = np.zeros((len(d), 3))
    ok = np.ones(len(d), bool)
    for tri in ((0, 1, 2), (0, 2, 3)):
        p0, p1, p2 = v[list(tri)]
        e1, e2 = p1 - p0, p2 - p0
        pv = np.cross(d, e2)
        det = pv @ e1
        tv = o - p0
        u = np.sum(tv * pv, 1) / det
        qv = np.cross(tv, e1)
        w = (d @ np.zeros(3)) + np.sum(d * qv, 1) / det
        t = (qv @ e2) / det
        hit = (u >= 0) & (w >= 0) & (u + w <= 1) & (t > tmin) & (t < tmax) & (t < best_t)
        n = (1 - u - w)[:, None] * vn[tri[0]] + u[:, None] * vn[tri[1]] + w[:, None] * vn[tri[2]]
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        col[hit] = np.abs(n[hit])
        best_t[hit] = t[hit]
        ok &= ~((np.minimum(np.minimum(u, w), 1 - u - w) > -1e-3) & (np.minimum(np.minimum(u, w), 1 - u - w) < 1e-3))
    c, r = np.array([0.4, -0.1, 1.2]), 0.5
    oc = o - c
    b = np.sum(oc * d, 1)
    disc = b * b - (np.sum(oc * oc, 1) - r * r)
    t = -b - np.sqrt(np.maximum(disc, 0))
    hit = (disc > 0) & (t > tmin) & (t < best_t)
    n = (o + t[:, None] * d - c) / r
    col[hit] = np.abs(n[hit])
    ok &= np.abs(disc) > 1e-3
    return col.reshape(H, W, 3), ok.reshape(H, W)


def test_normals_match_numpy_raycast(scene_dir):
    scene = clrender.load_scene(write_scene(scene_dir))
    film = clrender.render(scene, spp=2, seed=3)
    ref, ok = numpy_normals(scene.camera)
    img = film.image
    assert ok.mean() > 0.9
    assert (ref[ok].sum(axis=1) > 0).mean() > 0.3, "the test scene should cover a good part of the image"
    np.testing.assert_allclose(img[ok], ref[ok], atol=2e-3)


def test_same_seed_same_image_however_split(scene_dir, monkeypatch):
    scene = clrender.load_scene(write_scene(scene_dir, filt=""))
    r = render_mod.Renderer(scene)
    monkeypatch.setattr(render_mod, "TARGET_LAUNCH_SECONDS", 1e-9)  # one sample per pass
    many = r.render(spp=6, seed=5)
    assert many.stats.passes == 6
    monkeypatch.setattr(render_mod, "TARGET_LAUNCH_SECONDS", 1e9)   # as few passes as possible
    few = r.render(spp=6, seed=5)
    assert few.stats.passes < 6
    a = r.render(spp=2, seed=5)
    b = r.render(spp=4, seed=5, start_sample=2)
    np.testing.assert_allclose(many.sum_wl, few.sum_wl, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(many.sum_wl, a.sum_wl + b.sum_wl, rtol=1e-5, atol=1e-6)
    other = r.render(spp=6, seed=6)
    assert np.abs(other.sum_wl - many.sum_wl).max() > 1e-3, "a different seed must give different samples"


def test_av_and_ao_are_analytic_on_an_open_plane(tmp_path):
    """Camera looking at a lone square: av with a short length and ao both see an unoccluded hemisphere
    (value 1), except ao/av rays that hit nothing also give 1; a box over the plane changes that."""
    (tmp_path / "quad.obj").write_text("v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n")
    (tmp_path / "a.xml").write_text(f"""<scene><integrator type="av"><float name="length" value="2"/></integrator>
      <camera type="perspective"><integer name="width" value="8"/><integer name="height" value="8"/>
      <transform name="toWorld"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform></camera>
      <mesh type="obj"><string name="filename" value="quad.obj"/></mesh></scene>""")
    film = clrender.render(clrender.load_scene(tmp_path / "a.xml"), spp=16)
    assert np.all(film.image == 1.0)


def test_av_between_two_disks(tmp_path):
    """Two parallel coaxial disks of radius r at distance d: seen from the centre of one, the fraction of
    uniform hemisphere directions that escape past the other within length L > d is 1 - (1 - d/sqrt(d²+r²))
    -> av = d / sqrt(d² + r²) (NORI_FORMAT.md)."""
    r, d = 1.0, 0.5
    k = 96
    ang = np.linspace(0, 2 * np.pi, k, endpoint=False)
    rim = np.c_[r * np.cos(ang), r * np.sin(ang)]
    lines = [f"v {x:.7f} {y:.7f} {d}" for x, y in rim] + ["v 0 0 0.5"]
    lines += [f"f {i + 1} {(i + 1) % k + 1} {k + 1}" for i in range(k)]
    (tmp_path / "disk.obj").write_text("\n".join(lines) + "\n")
    (tmp_path / "floor.obj").write_text("v -0.05 -0.05 0\nv 0.05 -0.05 0\nv 0.05 0.05 0\nv -0.05 0.05 0\nf 1 2 3 4\n")
    (tmp_path / "a.xml").write_text("""<scene><integrator type="av"><float name="length" value="100"/></integrator>
      <camera type="perspective"><integer name="width" value="4"/><integer name="height" value="4"/>
        <float name="fov" value="0.5"/><float name="nearClip" value="0.2"/>
        <transform name="toWorld"><lookat origin="0,0,0.3" target="0,0,0" up="0,1,0"/></transform>
        <rfilter type="box"/></camera>
      <mesh type="obj"><string name="filename" value="floor.obj"/></mesh>
      <mesh type="obj"><string name="filename" value="disk.obj"/></mesh></scene>""")
    # The camera sits between the disks looking down at the floor's centre (the disk's hole is the camera
    # itself: the upper disk is hit only by av rays, which start on the floor).
    film = clrender.render(clrender.load_scene(tmp_path / "a.xml"), spp=4096, seed=1)
    img = film.image[..., 0]
    polygon_r = r * np.cos(np.pi / k)  # the polygon's inscribed radius bounds the disk's
    lo, hi = d / np.sqrt(d * d + r * r), d / np.sqrt(d * d + polygon_r ** 2)
    se = np.sqrt(film.variance()[..., 0]).mean()
    assert lo - 5 * se < img.mean() < hi + 5 * se, (img.mean(), lo, hi, se)


def test_outputs_and_metadata(scene_dir, tmp_path):
    from clrender.cli import main

    out = tmp_path / "out" / "img.exr"
    assert main(["render", str(write_scene(scene_dir)), "-o", str(out), "--spp", "3", "--seed", "9", "-q"]) == 0
    img, header = read_exr(out)
    assert img.shape == (H, W, 3) and img.dtype == np.float32
    assert header["clrender.spp"] == "3" and header["clrender.seed"] == "9"
    assert "clrender.device" in header and "clrender.version" in header and "clrender.render_seconds" in header
    from PIL import Image

    png = np.asarray(Image.open(out.with_suffix(".png")))
    assert png.shape == (H, W, 3)
    assert not list(out.parent.glob(".*")), "no temporary files may be left behind"


def test_partial_films_are_the_renders_of_their_samples(scene_dir, monkeypatch):
    """render(partial=(seconds, cb)) hands cb the film so far between passes: each is exactly the render of the
    samples it says it holds (the same numbered samples, so a fresh render of that many spp agrees), marked
    partial; the last pass gets none, and the final film is the whole render."""
    scene = clrender.load_scene(write_scene(scene_dir, filt=""))
    r = render_mod.Renderer(scene)
    monkeypatch.setattr(render_mod, "TARGET_LAUNCH_SECONDS", 1e-9)  # one sample per pass
    films = []
    final = r.render(spp=4, seed=7, partial=(0.0, films.append))
    assert [f.spp for f in films] == [1, 2, 3]
    assert all(f.metadata["partial"] is True for f in films) and "partial" not in final.metadata
    for f in films + [final]:
        ref = r.render(spp=f.spp, seed=7)
        np.testing.assert_allclose(f.sum_wl, ref.sum_wl, rtol=1e-5, atol=1e-6)
        assert f.stats.samples == f.spp * W * H
    assert final.spp == 4
    none = []
    r.render(spp=3, seed=7, partial=(1e9, none.append))
    assert none == [], "no partial film before its interval has passed"


def spy_on_partials(monkeypatch, read):
    """Wraps Renderer.render's partial callback: after each partial write, read() what is on disk. Returns the
    list of those readings and the real Renderer.render."""
    seen, real = [], render_mod.Renderer.render

    def spy(self, *a, **k):
        every, cb = k["partial"]

        def wrapped(film):
            cb(film)
            seen.append(read())
        return real(self, *a, **{**k, "partial": (every, wrapped)})

    monkeypatch.setattr(render_mod.Renderer, "render", spy)
    return seen, real


def test_cli_partial_every_writes_the_image_so_far(scene_dir, tmp_path, monkeypatch):
    """--partial-every SEC: during the render, the output holds the image so far (EXR metadata: its samples and
    partial); at the end, the whole render."""
    from clrender.cli import main

    monkeypatch.setattr(render_mod, "TARGET_LAUNCH_SECONDS", 1e-9)
    out = tmp_path / "img.exr"
    seen, _ = spy_on_partials(monkeypatch, lambda: read_exr(out)[1])
    assert main(["render", str(write_scene(scene_dir)), "-o", str(out), "--spp", "3", "-q",
                 "--partial-every", "0.000001"]) == 0
    assert [h["clrender.spp"] for h in seen] == ["1", "2"] and all(h["clrender.partial"] == "True" for h in seen)
    header = read_exr(out)[1]
    assert header["clrender.spp"] == "3" and "clrender.partial" not in header
    assert not list(tmp_path.glob(".*")), "no temporary files may be left behind"
    with pytest.raises(SystemExit) as e:
        main(["render", str(write_scene(scene_dir)), "--partial-every", "0"])
    assert e.value.code == 2


def test_options_the_cluster_path_lacks_are_refused(scene_dir, capsys):
    from clrender.cli import main

    scene = str(write_scene(scene_dir))
    assert main(["render", scene, "--sample-range", "0:1", "-q", "--emitter-selection", "power"]) == 2
    assert "--emitter-selection power is not supported with --cluster or --sample-range" in capsys.readouterr().err


def test_cli_partial_every_with_a_sample_range_writes_the_part_so_far(scene_dir, tmp_path, monkeypatch):
    """--partial-every with --sample-range (farm mode): the part on disk holds the samples done so far, with its
    true counts, so `merge --partial` can use the work of a job that dies; at the end, the whole part."""
    from clrender.cli import main
    from clrender.parts import merge_parts, read_part

    monkeypatch.setattr(render_mod, "TARGET_LAUNCH_SECONDS", 1e-9)  # one sample per pass
    out = tmp_path / "part.exr"
    seen, real = spy_on_partials(monkeypatch, lambda: read_part(out))
    scene = write_scene(scene_dir)
    assert main(["render", str(scene), "-o", str(out), "--sample-range", "5:3", "--seed", "4", "-q",
                 "--partial-every", "0.000001"]) == 0
    assert [(p.start, p.stop, int(p.film.count.min()), int(p.film.count.max())) for p in seen] == \
        [(5, 8, 1, 1), (5, 8, 2, 2)]
    final = read_part(out)
    assert (final.start, final.stop) == (5, 8) and (final.film.count == 3).all()
    # the snapshot is exactly the render of the samples it holds
    r = render_mod.Renderer(clrender.load_scene(scene))
    ref = real(r, spp=2, seed=4, start_sample=5)
    np.testing.assert_allclose(seen[1].film.sum_wl, ref.sum_wl, rtol=1e-5, atol=1e-6)
    with pytest.raises(ClrenderError, match="holds only 2 of its 3 samples"):
        merge_parts([seen[1]])
    assert (merge_parts([seen[1]], allow_missing=True).count == 2).all()
    assert not list(tmp_path.glob(".*")), "no temporary files may be left behind"
