"""The root <scene> of either format: where its children go, and the located errors for a misplaced area emitter
or a second single object (camera, integrator, sampler; Mitsuba: integrator; of several Mitsuba sensors the first is
rendered)."""
import logging

import pytest

import clrender.plugins  # noqa: F401
from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_string

NORI_CAMERA = '<camera type="perspective"><integer name="width" value="4"/><integer name="height" value="3"/></camera>'
MI_SENSOR = ('<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>'
             '<integer name="height" value="3"/></film></sensor>')
AREA = '<emitter type="area"><color name="radiance" value="1"/></emitter>'
POINT = '<emitter type="point"><color name="power" value="1"/></emitter>'
MI_AREA = '<emitter type="area"><rgb name="radiance" value="1"/></emitter>'
MI_POINT = '<emitter type="point"><rgb name="intensity" value="1"/></emitter>'


def scene_error(text: str) -> SceneError:
    with pytest.raises(SceneError) as e:
        create(parse_string(text, "s.xml"))
    return e.value


def test_nori_children_sorted():
    scene = create(parse_string(f'<scene><integrator type="normals"/>{NORI_CAMERA}{POINT}'
                                f'<mesh type="sphere">{AREA}</mesh><mesh type="sphere"/>'
                                f'<sampler type="independent"/></scene>'))
    assert len(scene.shapes) == 2 and len(scene.emitters) == 1 and scene.sampler is not None
    assert (scene.width, scene.height) == (4, 3)


@pytest.mark.parametrize("second", ['<integrator type="normals"/>', NORI_CAMERA, '<sampler type="independent"/>'])
def test_nori_second_single_object(second):
    tag = second[1:second.index(" ")]
    e = scene_error(f'<scene><integrator type="normals"/>{NORI_CAMERA}<sampler type="independent"/>\n{second}'
                    f'</scene>')
    assert str(e) == f"s.xml:2:1: a scene can have only one <{tag}>"


def test_nori_area_emitter_at_top_level():
    e = scene_error(f'<scene><integrator type="normals"/>{NORI_CAMERA}\n  {AREA}</scene>')
    assert str(e) == "s.xml:2:3: an area emitter must be nested in a <mesh>"


def test_mitsuba_children_sorted():
    scene = create(parse_string(f'<scene version="3.0.0">{MI_SENSOR}{MI_POINT}<bsdf type="diffuse" id="w"/>'
                                f'<shape type="sphere">{MI_AREA}</shape><shape type="sphere"><ref id="w"/></shape>'
                                f'</scene>'))
    assert len(scene.shapes) == 2 and len(scene.emitters) == 1
    assert scene.integrator is not None and scene.sampler is scene.camera.sampler


def test_mitsuba_second_integrator():
    e = scene_error(f'<scene version="3.0.0"><integrator type="path"/>{MI_SENSOR}\n<integrator type="path"/></scene>')
    assert str(e) == "s.xml:2:1: clrender renders one <integrator> per scene; this is a second one"


def test_mitsuba_several_sensors_render_the_first(caplog):
    """A multi-view file (inverse rendering's sensors around an object; sapo17/BachelorThesis has one of 60): Mitsuba
    3.9.1 reads it and its render() renders sensor 0; clrender renders the first and warns that the others are not."""
    other = MI_SENSOR.replace('"4"', '"6"').replace('"3"', '"5"')
    with caplog.at_level(logging.WARNING, logger="clrender"):
        scene = create(parse_string(f'<scene version="3.0.0">\n{MI_SENSOR}{MI_POINT}\n{other}\n{other}</scene>',
                                    "s.xml"))
    assert (scene.width, scene.height) == (4, 3) and len(scene.cameras) == 3 and scene.camera is scene.cameras[0]
    assert ("s.xml:2:1: the scene has 3 sensors: clrender renders this first one, as Mitsuba's render() does unless "
            "told another (the others, from s.xml:3:1 on, are not rendered)") in caplog.text


def test_mitsuba_area_emitter_at_top_level():
    e = scene_error(f'<scene version="3.0.0">{MI_SENSOR}\n  {MI_AREA}</scene>')
    assert str(e) == "s.xml:2:3: an area emitter must be nested in a <shape>"


def test_mitsuba_area_emitter_declared_at_top_level_for_a_ref():
    """Mitsuba's own Cornell boxes declare the area light at the top level, after the shape that refers to it:
    Mitsuba 3.9.1 lists it through that shape only, and so does clrender (one emitter, the shape's)."""
    from clrender.scene.registry import create
    from clrender.scene.xmlparser import parse_string

    scene = create(parse_string(f'<scene version="3.0.0">{MI_SENSOR}<shape type="sphere"><ref id="light"/></shape>'
                                f'<emitter type="area" id="light"/></scene>', "s.xml"))
    assert [s.spec.type for s in scene.shapes] == ["sphere"] and scene.emitters == []
    assert scene.shapes[0].emitter is not None and scene.shapes[0].emitter.spec.type == "area"
