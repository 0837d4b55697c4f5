"""Mitsuba 3's constvolume: its value (a float for every channel, or a colour; default 1), the <float>/<rgb>
shorthand of a heterogeneous medium's parameters, and its box: the medium has extinction only within to_world's
image of the unit cube, which for the shorthand is the unit cube itself (as in Mitsuba 3.9.1), seen through an
absorbing medium (per-pixel z-tests)."""
import numpy as np
import pytest

from clrender import plugins  # noqa: F401
from clrender.testing.stats import compare_mean_to_value, compare_to_value
from media.media_common import render_xml
from media.test_homogeneous import err, load

from .volume_common import look_down, pixel_points


def medium(body: str):
    return load(f'<shape type="sphere"><medium type="heterogeneous" name="interior">\n{body}</medium></shape>'
                ).shapes[0].interior


def test_values_and_defaults():
    v = medium('<volume type="constvolume" name="albedo"/>').albedo
    assert v.channels == 1 and np.all(v.value == 1) and v.max_value() == 1
    v = medium('<volume type="constvolume" name="sigma_t"><rgb name="value" value="0.5, 3, 2"/></volume>').sigma_t
    assert v.channels == 3 and v.max_value() == 3 and v.min_value() == 0.5
    np.testing.assert_array_equal(v.eval(np.zeros((2, 5, 3))), np.broadcast_to([0.5, 3, 2], (2, 5, 3)))
    m = medium('<rgb name="sigma_t" value="0.2, 0.4, 0.6"/><float name="albedo" value="0.5"/>')
    assert m.sigma_t.channels == 3 and m.albedo.channels == 1 and m.majorant == pytest.approx(0.6)
    np.testing.assert_array_equal(m.sigma_t.bbox()[0], 0) and np.testing.assert_array_equal(m.sigma_t.bbox()[1], 1)
    err('<shape type="sphere"><medium type="heterogeneous" name="interior">\n<volume type="constvolume" '
        'name="sigma_t"><float name="value" value="1"/><float name="scale" value="2"/></volume></medium></shape>',
        2, "scale")
    err('<shape type="sphere"><medium type="heterogeneous" name="interior">\n<volume type="constvolume" '
        'name="sigma_t"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1"/></transform>'
        '</volume></medium></shape>', 2, "invertible affine")


@pytest.mark.plugin("constvolume", "eval")
def test_a_colour_value_in_its_box(tmp_path):
    """A colour constvolume whose to_world spans the slab: every pixel is exp(-2 value) per channel."""
    value = np.array([0.3, 0.8, 1.6])
    xml = look_down('<volume type="constvolume" name="sigma_t"><rgb name="value" value="0.3, 0.8, 1.6"/>'
                    '<transform name="to_world"><scale value="40, 40, 2"/><translate value="-20, -20, -1"/>'
                    '</transform></volume>', spp=256)
    film = render_xml(tmp_path, xml)
    for r in (compare_to_value(film, np.exp(-2 * value)), compare_mean_to_value(film, np.exp(-2 * value))):
        assert r.passed, r.message


@pytest.mark.plugin("constvolume", "render")
def test_the_shorthands_box_is_the_unit_cube(tmp_path):
    """<float name="sigma_t"> in a medium filling a wide slab: only the unit cube [0, 1]^3 has extinction (Mitsuba
    3.9.1's constvolume box), so the pixels over x, y in [0, 1] see exp(-sigma_t) (the cube is 1 deep) and the
    others 1. The camera sees [-1, 1]^2 (pixels straddle no edge)."""
    film = render_xml(tmp_path, look_down('<float name="sigma_t" value="1.5"/>', half_width=1.0, spp=256))
    inside = np.all(pixel_points(half_width=1.0)[:, :, 0] > 0, axis=-1)
    expected = np.where(inside[..., None], np.exp(-1.5), 1.0) * np.ones(3)
    for r in (compare_to_value(film, expected), compare_mean_to_value(film, expected.mean(axis=(0, 1)))):
        assert r.passed, r.message
