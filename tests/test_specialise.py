"""Render programs built for the scene's own plugin set (clrender/device/dispatch.py PluginSet).

pack_scene records which plugins the packed rows use; the Renderer passes them as CLR_USE_* defines, so the
generated switches hold only those cases. Tags do not depend on the set: a specialised and a full program give
the same image, bit for bit, on the same tables, and a tag outside the set takes the method's default body.
"""
import dataclasses
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

from clrender.device import codegen, dispatch, layout
from clrender.scene.registry import create
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.textures.texture import TextureTable

SCENES = Path(__file__).resolve().parent / "mitsuba" / "scenes"
COMPOSITES = SCENES / "composites.xml"


def _composites(res=16):
    import clrender

    return clrender.load_scene(COMPOSITES, res=res)


def _diffuse_only(scene):
    """The composites scene with every composite BSDF replaced by the walls' diffuse: one BSDF plugin."""
    walls = scene.shapes[0].bsdf
    for sh in scene.shapes:
        if getattr(sh.bsdf, "bsdfs", None):
            sh.bsdf = walls
    return scene


def _bsdf_prefixes(defines):
    return sorted(k[len("CLR_USE_BSDF_"):].lower() for k in defines if k.startswith("CLR_USE_BSDF_"))


def test_the_packed_plugin_set_is_what_the_tables_use():
    from clrender.pack import pack_scene

    full = pack_scene(_composites()).plugins.defines()
    assert _bsdf_prefixes(full) == ["blendbsdf", "diffuse", "mask", "plastic", "roughplastic", "twosided"]
    assert full["BSDF_COMPOSITE_LEVELS"] == 3      # mask(twosided(blendbsdf(...)))
    assert {"CLR_PLUGIN_SET", "CLR_USE_SHAPE_MESH", "CLR_USE_EMITTER_AREA", "CLR_USE_RFILTER_BOX"} <= set(full)
    assert not any(k.startswith("CLR_USE_TEXTURE_") for k in full)

    diffuse = pack_scene(_diffuse_only(_composites())).plugins.defines()
    assert _bsdf_prefixes(diffuse) == ["diffuse"]
    assert diffuse["BSDF_COMPOSITE_LEVELS"] == 0
    assert sorted(k for k in diffuse if k.startswith("CLR_USE_")) == [
        "CLR_USE_BSDF_DIFFUSE", "CLR_USE_EMITTER_AREA", "CLR_USE_RFILTER_BOX", "CLR_USE_SHAPE_MESH"]


def test_a_texture_is_in_the_set_but_its_texel_rows_are_not():
    import clrender
    from clrender.pack import pack_scene

    buffers = pack_scene(clrender.load_scene(SCENES / "bitmap_plane.xml"))
    assert len(buffers.textures) > 1                 # the bitmap's row and its texels
    assert [k for k in buffers.plugins.defines() if k.startswith("CLR_USE_TEXTURE_")] == ["CLR_USE_TEXTURE_BITMAP"]


def test_the_generated_header_guards_every_plugin_and_level():
    src = codegen.dispatch_source(dispatch.BSDF)
    for cls in dispatch.plugins("bsdf"):
        use = dispatch.use_define(dispatch.BSDF, dispatch.prefix_of(cls))
        guard = f"#if defined(CLR_USE_ALL_PLUGINS) || defined({use})"
        # each of the plugin's includes and cases sits right under its guard
        lines = src.splitlines()
        for i, line in enumerate(lines):
            if re.search(rf"\b{dispatch.prefix_of(cls)}_\w+\(|\"{re.escape(cls.kernel)}\"", line):
                assert lines[i - 1] == guard, (cls.kernel, line)
    assert "#if CLR_BSDF_LEVELS >= 3" in src
    # without CLR_PLUGIN_SET a program holds every plugin (unit-test kernels, tools)
    assert "#if !defined(CLR_PLUGIN_SET) && !defined(CLR_USE_ALL_PLUGINS)\n#define CLR_USE_ALL_PLUGINS 1" in src


def test_unknown_tags_and_depths_are_refused():
    n = len(dispatch.plugins("bsdf"))
    with pytest.raises(ValueError, match="not a registered plugin"):
        dispatch.PluginSet.from_tags({"bsdf": {n}})
    with pytest.raises(ValueError, match="nested 4 deep"):
        dispatch.PluginSet.from_tags({"bsdf": {0}}, {"bsdf": 4}).defines()


def test_bench_and_cluster_workers_build_the_renderers_program():
    """`clrender bench` times Renderer.defines; a cluster worker makes its Renderer from the pickled buffers
    (files='ship') or by packing the same scene (files='shared'): all three give the same defines."""
    from clrender.cluster_worker import ShippedScene
    from clrender.pack import pack_scene
    from clrender.renderer import render_defines

    scene = _composites()
    buffers = pack_scene(scene)
    local = render_defines(scene, buffers)
    shipped = ShippedScene("k", pickle.loads(pickle.dumps(buffers)), scene.integrator.kernel, scene.width,
                           scene.height, scene.sample_count)
    assert render_defines(shipped.scene(), shipped.buffers) == local
    assert render_defines(scene, pack_scene(scene)) == local
    assert local["BSDF_COMPOSITE_LEVELS"] == 3 and "CLR_USE_BSDF_TWOSIDED" in local


def _rows(*dicts):
    table = TextureTable()
    return np.array([r for d in dicts for r in create(spec_from_dict(d)).pack_rows(table)], layout.dtype("Bsdf"))


def test_a_tag_outside_the_set_takes_the_default(ctx, queue):
    """A program for {diffuse} has no plastic code: a plastic row samples as the default (weight 0, wo = +z);
    the diffuse row gives exactly the samples of the program for both rows' plugins (the test kernels' default)."""
    from clrender.testing.kernels import bsdf_sample_batch

    rows = _rows({"type": "diffuse"}, {"type": "plastic"})
    only_diffuse = dispatch.PluginSet.from_tags({"bsdf": {int(rows[0]["type"])}}, {"bsdf": 0}).defines()
    n = 256
    idx = np.arange(n, dtype=np.uint32) % 2
    spec = bsdf_sample_batch(ctx, queue, rows, (0.3, 0.2, 0.9), n, seed=5, row_index=idx, defines=only_diffuse)
    both = bsdf_sample_batch(ctx, queue, rows, (0.3, 0.2, 0.9), n, seed=5, row_index=idx)
    plastic = idx == 1
    assert np.all(both.weight[plastic].max(axis=1) > 0)          # the rows' own program has plastic
    assert np.all(spec.weight[plastic] == 0)
    assert np.all(spec.wo[plastic] == (0.0, 0.0, 1.0))
    for a, b in zip((spec.wo, spec.weight, spec.pdf, spec.f), (both.wo, both.weight, both.pdf, both.f)):
        assert np.array_equal(a[~plastic], b[~plastic])


def _set(defines):
    return sorted(k[len("CLR_USE_"):].lower() for k in defines if k.startswith("CLR_USE_"))


def test_the_test_kernels_hold_the_plugins_of_their_rows(tmp_path):
    """clrender.testing.kernels builds its programs for the plugins the rows reach: a composite's children and its
    depth, the textures of the side table (not its texel rows). pack_rows knows the exact depth; rows alone give a
    bound that is never below it."""
    from PIL import Image

    from clrender.testing.kernels import pack_rows, rows_plugins
    from clrender.testing.plugin_checks import mitsuba_bsdf_with_checkers

    nested = create(spec_from_dict({"type": "twosided", "a": {"type": "blendbsdf", "weight": 0.3,
                                                                "a": {"type": "diffuse"},
                                                                "b": {"type": "roughplastic"}}}))
    rows = pack_rows(nested)
    exact = rows_plugins(rows).defines()
    assert _set(exact) == ["bsdf_blendbsdf", "bsdf_diffuse", "bsdf_roughplastic", "bsdf_twosided"]
    assert exact["BSDF_COMPOSITE_LEVELS"] == 2
    assert rows_plugins(np.asarray(rows)).defines() == exact       # the bound: two composite rows, two levels
    both = np.concatenate([np.asarray(rows), np.asarray(pack_rows(nested))])
    assert rows_plugins(both).defines()["BSDF_COMPOSITE_LEVELS"] == 3   # four composite rows: at most 3 levels

    checkers = mitsuba_bsdf_with_checkers("diffuse", ["reflectance"])
    row = checkers.pack()
    assert _set(rows_plugins(row, checkers.textures_table).defines()) == ["bsdf_diffuse", "texture_checkerboard_color"]
    assert _set(rows_plugins(row).defines()) == ["bsdf_diffuse"]
    assert _set(rows_plugins(pack_rows(checkers)).defines()) == ["bsdf_diffuse", "texture_checkerboard_color"]

    # the one zero row of an empty texture table is no texture (its tag would read as a bitmap's)
    plain = create(spec_from_dict({"type": "diffuse"}))
    row = plain.pack()
    assert len(plain.textures_table) == 1 and _set(rows_plugins(row, plain.textures_table).defines()) == ["bsdf_diffuse"]
    # a bitmap's texel rows follow its own
    img = np.zeros((4, 8, 3), np.uint8)
    img[0, 0] = 200
    Image.fromarray(img).save(tmp_path / "t.png")
    bsdf = create(spec_from_dict({"type": "diffuse", "reflectance": {"type": "bitmap",
                                                                     "filename": str(tmp_path / "t.png")}}))
    row = bsdf.pack()
    assert len(bsdf.textures_table) > 1
    assert _set(rows_plugins(row, bsdf.textures_table).defines()) == ["bsdf_diffuse", "texture_bitmap"]


@pytest.mark.slow   # the full render program (every plugin) takes about 2 minutes to build cold
@pytest.mark.parametrize("which", ["diffuse_only", "composites"])
def test_specialised_and_full_programs_render_the_same_image(which):
    """Same tables, same seed: the accumulators of the specialised program equal the full program's bit for bit
    (the full program: buffers with no plugin set, as any build without one)."""
    from clrender.pack import pack_scene
    from clrender.renderer import Renderer

    scene = _composites()
    if which == "diffuse_only":
        scene = _diffuse_only(scene)
    buffers = pack_scene(scene)
    spec = Renderer(scene, buffers=buffers)
    full = Renderer(scene, buffers=dataclasses.replace(buffers, plugins=None))
    assert "CLR_PLUGIN_SET" in spec.defines and "CLR_PLUGIN_SET" not in full.defines
    a = spec.render(spp=4, seed=11)
    b = full.render(spp=4, seed=11)
    assert a.sum_w.sum() > 0 and np.count_nonzero(a.sum_wl) > a.sum_wl.size // 2
    assert np.array_equal(a.sum_wl, b.sum_wl) and np.array_equal(a.sum_w, b.sum_w)


@pytest.mark.slow   # one small program per plugin (~1 min)
def test_every_plugin_builds_alone(ctx):
    """A specialised program holds one plugin's header without the others': each must include what it uses."""
    from clrender.device.program import build_program

    src = r"""
#include "scene.h"
#include "bsdf.h"
#include "emitter.h"
#include "filter.h"
__kernel void k(SCENE_ARGS, __global const Camera* cam, __global float4* out) {
    SCENE_INIT(sd);
    BsdfQuery q; q.wi = v3(0.0f, 0.0f, 1.0f); q.wo = q.wi; q.uv = (float2)(0.5f); q.textures = sd.textures; q.tables = sd.bsdf_tables;
    q.eta = 1.0f; q.measure = MEASURE_SOLID_ANGLE;
    vec3 r = vadd(bsdf_sample(sd.bsdfs, &q, (float2)(0.5f)), bsdf_eval(sd.bsdfs, &q));
    r = vadd(r, bsdf_albedo(sd.bsdfs, &q));
    EmitterQuery e; e.ref = v3s(0.0f);
    r = vadd(r, emitter_row_sample(&sd, sd.emitters, &e, (float2)(0.5f)));
    out[0] = vf4(r, bsdf_pdf(sd.bsdfs, &q) + filter_profile_eval(cam, 0.1f)
                    + texture_eval(sd.textures, (float2)(0.5f)).x);
}
"""
    for kind in (dispatch.BSDF, dispatch.EMITTER, dispatch.TEXTURE, dispatch.RFILTER, dispatch.SHAPE):
        for cls in dispatch.plugins(kind.tag):
            levels = {"bsdf": 1 if dispatch.is_composite(cls) else 0}
            defines = dispatch.PluginSet.from_tags({kind.tag: {dispatch.tag_of(cls)}}, levels).defines()
            build_program(ctx, src, defines=defines)


@pytest.mark.slow   # the test program with every plugin: several minutes to build cold on 2 cores
def test_every_plugin_in_one_test_program(ctx, queue):
    """The test kernels' ALL_PLUGINS program (every BSDF and texture, composites three levels deep) builds, and on
    a row of each BSDF plugin draws exactly the samples of the program for that row's own plugins."""
    from bsdfs.perturbed_common import DATA, rows_of
    from clrender.testing.kernels import ALL_PLUGINS, bsdf_sample_batch, pack_rows, rows_plugins
    from clrender.testing.plugin_checks import bsdf_from_xml, mitsuba_bsdf_with_checkers

    dicts = [{"type": t} for t in ("diffuse", "conductor", "dielectric", "thindielectric", "plastic", "roughplastic",
                                   "roughconductor", "roughdielectric", "principled", "principledthin")]
    dicts += [{"type": "twosided", "a": {"type": "diffuse"}},
              {"type": "blendbsdf", "weight": 0.3, "a": {"type": "diffuse"}, "b": {"type": "conductor"}},
              {"type": "mask", "opacity": 0.4, "a": {"type": "roughplastic"}}]
    cases = [pack_rows(create(spec_from_dict(d))) for d in dicts]
    cases += [rows_of(DATA["cases"][name]["dict"])[0] for name in ("normalmap-of-bumpmap", "blend-normalmap-bumpmap")]
    cases += [pack_rows(bsdf_from_xml(f'<bsdf type="{t}"/>')) for t in ("microfacet", "mirror")]
    cases.append(pack_rows(mitsuba_bsdf_with_checkers("roughplastic", ["diffuse_reflectance"])))
    covered = {p for rows in cases for k, p in rows_plugins(rows).used if k == "bsdf"}
    assert covered == {dispatch.prefix_of(c) for c in dispatch.plugins("bsdf")}, "a BSDF plugin has no row here"
    for rows in cases:
        wi = (0.3, 0.2, 0.9)
        own = bsdf_sample_batch(ctx, queue, rows, wi, 4096, seed=3)
        every = bsdf_sample_batch(ctx, queue, rows, wi, 4096, seed=3, defines=ALL_PLUGINS)
        assert np.any(own.weight != 0)
        for a, b in zip((own.wo, own.weight, own.pdf, own.f), (every.wo, every.weight, every.pdf, every.f)):
            assert np.array_equal(a, b), sorted(rows_plugins(rows).used)
