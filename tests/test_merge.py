"""Farm mode without Dask: `render --sample-range START:COUNT` parts, and `clrender merge` adding them into
the single-process image, refusing parts that do not belong together and naming missing ranges."""
import numpy as np
import pytest

import clrender
from clrender import version
from clrender.cli import main
from clrender.film import read_exr
from clrender.parts import read_part, write_part
from cluster_scene import write_scene

SEED = 7


@pytest.fixture(scope="module")
def farm(tmp_path_factory):
    """A scene, its 12-spp single-process film, and 4 parts of 3 samples rendered by separate commands."""
    d = tmp_path_factory.mktemp("farm")
    scene = write_scene(d)
    ref = clrender.render(clrender.load_scene(scene), spp=12, seed=SEED)
    parts = []
    for i in range(4):
        p = d / f"part{i}.exr"
        assert main(["render", str(scene), "--sample-range", f"{3 * i}:3", "--seed", str(SEED), "-o", str(p),
                     "-q"]) == 0
        parts.append(p)
    return d, scene, ref, parts


def test_parts_merge_into_the_single_process_image(farm, capsys):
    d, _, ref, parts = farm
    out = d / "frame.exr"
    assert main(["merge", *map(str, reversed(parts)), "-o", str(out), "--png"]) == 0
    img, header = read_exr(out)
    np.testing.assert_allclose(img, ref.image, rtol=1e-5, atol=1e-6)
    assert header["clrender.spp"] == "12" and header["clrender.seed"] == str(SEED)
    assert header["clrender.sample_ranges"] == "0..2, 3..5, 6..8, 9..11"
    assert (d / "frame.png").exists()
    assert "merged 4 part(s)" in capsys.readouterr().err


def test_a_part_holds_its_range_and_metadata(farm):
    _, scene, ref, parts = farm
    p = read_part(parts[1])
    assert (p.start, p.stop) == (3, 6) and (p.film.count == 3).all()
    assert p.meta["dialect"] == "upstream" and p.meta["seed"] == SEED and p.meta["version"] == clrender.__version__
    assert len(p.meta["scene_hash"]) == 32 and p.meta["integrator"] == "ao"
    one = clrender.render(clrender.load_scene(scene), spp=3, seed=SEED)   # samples 0..2: not this part
    assert np.abs(one.sum_wl - p.film.sum_wl).max() > 1e-3


def test_missing_ranges_are_named(farm, capsys):
    d, _, _, parts = farm
    out = d / "gap.exr"
    assert main(["merge", str(parts[0]), str(parts[3]), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "samples 3..8 are missing" in err and "--partial" in err and not out.exists()
    assert main(["merge", str(parts[0]), str(parts[3]), "-o", str(out), "--partial"]) == 0
    assert read_exr(out)[1]["clrender.missing"] == "3..8"


@pytest.mark.parametrize("how, message", [
    ("overlap", "overlaps"),
    ("seed", "seed is"),
    ("scene", "scene_hash is"),
    ("version", "version is"),
    ("size", "width is"),
    ("dialect", "dialect is"),
    ("image", "not an accumulator EXR"),
])
def test_parts_that_do_not_belong_together_are_refused(farm, tmp_path, capsys, how, message):
    d, scene, ref, parts = farm
    odd = tmp_path / "odd.exr"
    if how == "overlap":
        assert main(["render", str(scene), "--sample-range", "2:2", "--seed", str(SEED), "-o", str(odd), "-q"]) == 0
    elif how == "seed":
        assert main(["render", str(scene), "--sample-range", "12:1", "--seed", "8", "-o", str(odd), "-q"]) == 0
    elif how == "scene":   # the same file with another -D value is another scene
        assert main(["render", str(scene), "--sample-range", "12:1", "--seed", str(SEED), "-D", "w=41", "-o",
                     str(odd), "-q"]) == 0
    elif how == "size":
        small = clrender.render(clrender.load_scene(scene, w=20), spp=1, seed=SEED)
        write_part(small, odd, read_part(parts[0]).meta["scene_hash"], SEED, 12, 1)
    elif how == "version":   # a part written by another clrender version
        p = read_part(parts[0])
        old, version.__version__ = version.__version__, "0.0.1"
        try:
            write_part(p.film, odd, p.meta["scene_hash"], SEED, 12, 3)
        finally:
            version.__version__ = old
    elif how == "dialect":
        p = read_part(parts[0])
        write_part(p.film, odd, p.meta["scene_hash"], SEED, 12, 3, dialect="eth")
    else:
        ref.write_exr(odd)
    capsys.readouterr()
    assert main(["merge", *map(str, parts), str(odd), "-o", str(tmp_path / "m.exr")]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "m.exr").exists()


def test_an_interrupted_part_is_reported(farm, tmp_path, capsys):
    d, _, _, parts = farm
    p = read_part(parts[3])
    p.film.count[0, 0] -= 1   # as if the job stopped before finishing one pixel's samples
    odd = tmp_path / "short.exr"
    write_part(p.film, odd, p.meta["scene_hash"], SEED, 9, 3)
    assert main(["merge", *map(str, parts[:3]), str(odd), "-o", str(tmp_path / "m.exr")]) == 2
    assert "holds only 2 of its 3 samples" in capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["--sample-range", "3"], "START:COUNT"),
    (["--sample-range=-1:4"], "START >= 0"),
    (["--sample-range", "0:0"], "COUNT >= 1"),
    (["--sample-range", "0:4", "--spp", "4"], "leave out --spp"),
    (["--sample-range", "0:4", "-o", "part.png"], "accumulator EXR"),
    (["--tasks", "3", "--sample-range", "0:4"], "--cluster renders only"),
])
def test_bad_farm_arguments_are_clear_errors(farm, tmp_path, capsys, args, message):
    scene = farm[1]
    args = [a if a != "part.png" else str(tmp_path / a) for a in args]
    assert main(["render", str(scene), "-q", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_merge_of_a_missing_file_is_a_clear_error(tmp_path, capsys):
    assert main(["merge", str(tmp_path / "nope.exr"), "-o", str(tmp_path / "m.exr")]) == 2
    assert "nope.exr" in capsys.readouterr().err


def test_merge_refuses_to_write_over_one_of_its_parts(farm, capsys):
    # It used to write the merged plain image over part 0, losing that part's accumulators.
    d, _, _, parts = farm
    before = parts[0].read_bytes()
    assert main(["merge", *map(str, parts), "-o", str(parts[0])]) == 2
    assert "one of the parts" in capsys.readouterr().err
    assert parts[0].read_bytes() == before


def test_merge_names_an_unwritable_output_before_reading_the_parts(farm, capsys):
    _, _, _, parts = farm
    assert main(["merge", *map(str, parts), "-o", "/proc/clrender-merged.exr"]) == 2
    err = capsys.readouterr().err
    assert "'/proc/clrender-merged.exr'" in err and "/proc/.clrender" not in err, err  # not our temporary file
