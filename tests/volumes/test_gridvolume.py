"""Mitsuba 3's gridvolume: the .vol reader (a file written here reads back exactly; each malformed header, a
truncated or missing file is an error naming the file and the XML line), and the kernel's lookups seen through an
absorbing medium: one voxel per pixel (nearest, three channels), and trilinear lookups of a rotated grid where
every wrap mode decides the corners, against the host's reference lookup (per-pixel z-tests)."""
import struct

import numpy as np
import pytest

from clrender import plugins  # noqa: F401
from clrender.testing.stats import compare_mean_to_value, compare_to_value
from clrender.volumes.gridvolume import read_vol, write_vol
from media.media_common import grid_xml, render_xml
from media.test_homogeneous import err, load

from .volume_common import SIZE, look_down, pixel_points


@pytest.mark.parametrize("channels", [1, 3])
def test_a_written_file_reads_back_exactly(tmp_path, channels):
    rng = np.random.default_rng(3)
    data = rng.random((3, 5, 4, channels), np.float32) * 7
    write_vol(tmp_path / "g.vol", data, bbox=(-1, 0.5, 2, 3, 4.5, 6))
    back, bbox = read_vol(tmp_path / "g.vol")
    assert back.dtype == np.float32 and back.shape == (3, 5, 4, channels)
    np.testing.assert_array_equal(back, data)
    np.testing.assert_array_equal(bbox, [-1, 0.5, 2, 3, 4.5, 6])
    # x fastest, as Mitsuba's data[((z yres + y) xres + x) channels + c]
    raw = (tmp_path / "g.vol").read_bytes()
    assert raw[:4] == b"VOL\x03" and struct.unpack_from("<5i", raw, 4) == (1, 4, 5, 3, channels)
    assert struct.unpack_from("<f", raw, 48 + 4 * ((2 * 5 + 1) * 4 + 3) * channels)[0] == data[2, 1, 3, 0]
    s = load('<shape type="sphere"><medium type="heterogeneous" name="interior">\n'
             f'{grid_xml("sigma_t", tmp_path / "g.vol")}</medium></shape>')
    vol = s.shapes[0].interior.sigma_t
    assert vol.resolution() == (4, 5, 3) and vol.channels == channels and vol.max_value() == data.max()


#: what a repository that keeps a file in Git LFS holds in its place (a clone without LFS, a `git archive`)
LFS_POINTER = (b"version https://git-lfs.github.com/spec/v1\noid sha256:" + b"0" * 64 + b"\nsize 78780\n")


def _header(*, magic=b"VOL", version=3, encoding=1, res=(2, 2, 2), channels=1, values=None) -> bytes:
    n = int(np.prod(res)) * channels if values is None else values
    return (magic + bytes([version]) + struct.pack("<5i", encoding, *res, channels) + struct.pack("<6f", 0, 0, 0, 1,
            1, 1) + np.ones(n, "<f4").tobytes())


@pytest.mark.parametrize("content,fragment", [
    (_header(magic=b"VOX"), "expected b'VOL'"), (_header(version=2), "version 2; expected 3"),
    (_header(encoding=2), "encoding 2; expected 1"), (_header(channels=2), "2 channels; expected 1"),
    (_header(res=(2, 0, 2)), "at least 1 voxel"), (_header(values=7), "truncated: 2 x 2 x 2 x 1"),
    (b"VOL\x03\x01\x00", "shorter than the 48-byte header"),
    (_header()[:48] + np.array([1, 1, np.nan, 1, 1, 1, 1, 1], "<f4").tobytes(), "NaN"),
    (None, "not found"), (LFS_POINTER, "a Git LFS pointer, not the file")],
    ids=["magic", "version", "encoding", "channels", "resolution", "truncated", "header", "nan", "missing", "lfs"])
def test_bad_files_are_located(tmp_path, content, fragment):
    path = tmp_path / "bad.vol"
    if content is not None:
        path.write_bytes(content)
    e = err('<shape type="sphere"><medium type="heterogeneous" name="interior">\n'
            f'{grid_xml("sigma_t", path)}</medium></shape>', 2, fragment)
    assert "bad.vol" in str(e)


TO_SLAB = ('<transform name="to_world"><scale value="1, 1, 2"/><translate value="-0.5, -0.5, -1"/>{}'
           '</transform>')
# a 0.6 wide square turned 45 degrees: its bounding box (+-0.42) leaves the view's edges (+-0.5) without extinction,
# and within the box, its corners lie up to two voxels outside the turned cube
TURNED = ('<transform name="to_world"><scale value="0.6, 0.6, 2"/><translate value="-0.3, -0.3, -1"/>'
          '<rotate z="1" angle="45"/></transform>')


@pytest.mark.plugin("gridvolume", "eval")
def test_one_voxel_per_pixel(tmp_path):
    """A 3-channel 8 x 8 x 1 grid, looked up nearest, spans the camera's view, one voxel per pixel: each pixel is
    exp(-2 value) of its voxel (x to the right, y up), so every voxel's place and channels are checked."""
    rng = np.random.default_rng(5)
    grid = (0.1 + rng.random((1, SIZE, SIZE, 3)) * 1.4).astype(np.float32)
    write_vol(tmp_path / "v.vol", grid)
    film = render_xml(tmp_path, look_down(grid_xml("sigma_t", tmp_path / "v.vol", TO_SLAB.format(""),
                                                   filter_type="nearest"), spp=1024))
    expected = np.exp(-2 * grid[0, ::-1])     # image rows go down, y up
    for r in (compare_to_value(film, expected), compare_mean_to_value(film, expected.mean(axis=(0, 1)))):
        assert r.passed, r.message


def turned_grid(tmp_path, wrap: str):
    """The turned 4 x 4 x 1 grid's element and its expected image: each pixel the mean of exp(-2 scale value) over
    its footprint, the value from the host's lookup (GridVolume.eval, 16 x 16 points a pixel)."""
    rng = np.random.default_rng(9)
    write_vol(tmp_path / "v.vol", (rng.random((1, 4, 4)) * 1.5).astype(np.float32))
    xml = grid_xml("sigma_t", tmp_path / "v.vol", TURNED, wrap=wrap)
    vol = load(f'<shape type="sphere"><medium type="heterogeneous" name="interior">{xml}</medium></shape>'
               ).shapes[0].interior.sigma_t
    pts = pixel_points(sub=16)
    v = vol.eval(np.concatenate([pts, np.zeros(pts.shape[:-1] + (1,))], -1))
    inside = np.all(np.abs(pts) <= 0.3 * np.sqrt(2), axis=-1)[..., None]   # the bounding box
    return xml, np.exp(-2 * SCALE * np.where(inside, v, 0.0)).mean(axis=2)


SCALE = 0.7


@pytest.mark.plugin("gridvolume", "eval")
@pytest.mark.plugin("gridvolume", "render")
@pytest.mark.parametrize("wrap", ["clamp", "repeat", "mirror"])
def test_trilinear_lookups_and_wrap_modes(tmp_path, wrap):
    """A 1-channel 4 x 4 x 1 grid, trilinear, turned 45 degrees about z (TURNED): the corners of its bounding box
    (where the medium has extinction) lie outside the turned cube, so the wrap mode decides them; outside the box
    the medium has none (per-pixel z-test against turned_grid's expected image)."""
    xml, expected = turned_grid(tmp_path, wrap)
    film = render_xml(tmp_path, look_down(xml, scale=SCALE))
    for r in (compare_to_value(film, expected), compare_mean_to_value(film, expected.mean(axis=(0, 1)))):
        assert r.passed, f"{wrap}: {r.message}"


def test_the_wrap_modes_differ_on_the_corners(tmp_path):
    """What the test above tells apart: the three wrap modes' expected images differ (in the corners) by far more
    than its renders' noise (a pixel's standard error is about 0.02)."""
    images = [turned_grid(tmp_path, wrap)[1] for wrap in ("clamp", "repeat", "mirror")]
    for a, b in ((0, 1), (0, 2), (1, 2)):
        assert np.abs(images[a] - images[b]).max() > 0.1, (a, b, np.abs(images[a] - images[b]).max())
