"""Nori's checkerboard_color texture (clrender/textures/checkerboard_color.py, kernels/textures/
checkerboard_color.h) as a BSDF's parameter on the device: its values at uv against the host's eval and at
hand-checked points, read through diffuse's albedo (eval, albedo and sample weights), a rendered plane, and the
scene errors."""
import numpy as np
import pytest

from clrender.device.dispatch import flag_defines, tag_of
from clrender.errors import SceneError
from clrender.testing.plugin_checks import bsdf_from_xml, bsdf_pdf_eval_batch, bsdf_sample_batch, check_texture_render

CHECKER_XML = """<scene><mesh type="obj"><string name="filename" value="x.obj"/>
  <bsdf type="{kind}">
    <texture type="checkerboard_color" name="{name}">
      <color name="value1" value="0.8, 0.1, 0.1"/>
      <color name="value2" value="0.1, 0.2, 0.7"/>
      <point name="delta" value="0.05, -0.1"/>
      <vector name="scale" value="0.25 0.5"/>
    </texture>{extra}
  </bsdf></mesh></scene>"""


@pytest.mark.plugin("checkerboard_color", "eval")
def test_checkerboard_texture(ctx, queue):
    bsdf = bsdf_from_xml(CHECKER_XML.format(kind="diffuse", name="albedo", extra=""))
    row = bsdf.pack()
    assert row["flags"] & flag_defines()["BSDF_UV"] and row["diffuse"]["albedo_tex"] == 0
    tex = bsdf.textures_table
    assert len(tex) == 1 and tex[0]["type"] == tag_of(type(bsdf.texture))
    rng = np.random.default_rng(9)
    uv = rng.uniform(-2, 2, (4000, 2))
    # stay away from the cell edges, where float32 and float64 may disagree
    fr = np.stack([(uv[:, 0] - 0.05) / 0.25, (uv[:, 1] + 0.1) / 0.5], 1)
    uv = uv[np.all(np.abs(fr - np.round(fr)) > 1e-4, axis=1)]
    ref = bsdf.texture.eval(uv)
    assert 0.3 < np.mean(ref[:, 0] == 0.8) < 0.7
    pdf, f, alb = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), np.tile([0.0, 0.0, 1.0], (len(uv), 1)), uv=uv,
                                      with_albedo=True, textures=tex)
    np.testing.assert_allclose(alb, ref, rtol=1e-6)
    np.testing.assert_allclose(f, ref / np.pi, rtol=1e-6)
    s = bsdf_sample_batch(ctx, queue, row, (0, 0, 1), len(uv), 3, uv=uv, textures=tex)
    np.testing.assert_allclose(s.weight, ref, rtol=1e-6)
    # a few hand-checked points: cell (0,0) is value1, its neighbours value2
    pts = np.array([[0.1, 0.0], [0.35, 0.0], [0.1, 0.45], [0.35, 0.45], [-0.1, 0.0]])
    _, _, alb = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), np.tile([0.0, 0.0, 1.0], (5, 1)), uv=pts,
                                    with_albedo=True, textures=tex)
    v1, v2 = [0.8, 0.1, 0.1], [0.1, 0.2, 0.7]
    np.testing.assert_allclose(alb, [v1, v2, v2, v1, v2], rtol=1e-6)


def test_checkerboard_errors():
    with pytest.raises(SceneError):
        bsdf_from_xml(CHECKER_XML.format(kind="diffuse", name="kd", extra=""))
    with pytest.raises(SceneError):
        bsdf_from_xml(CHECKER_XML.format(kind="diffuse", name="albedo",
                                         extra='<color name="albedo" value="0.5"/>'))
    with pytest.raises(SceneError):
        bsdf_from_xml(CHECKER_XML.format(kind="mirror", name="albedo", extra=""))


@pytest.mark.plugin("checkerboard_color", "render")
def test_furnace_render(tmp_path):
    """A diffuse plane with a checkerboard_color albedo in a constant environment of radiance 1 shows the cell's
    colour at its uv."""
    check_texture_render(tmp_path, '<texture type="checkerboard_color" name="albedo"><color name="value1" '
                                   'value="0.8, 0.1, 0.1"/><color name="value2" value="0.1, 0.2, 0.7"/>'
                                   '<point name="delta" value="0.05, -0.1"/><vector name="scale" value="0.25 0.5"/>'
                                   '</texture>')
