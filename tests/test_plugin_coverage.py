"""Every registered plugin has its test file, and that file holds a sampling test and a render test (issue 26).

A plugin of the kinds below, `clrender/<folder>/<name>.py`, is tested in `tests/<folder>/test_<name>.py`; a test
declares what it covers with ``@pytest.mark.plugin("<name>", "<aspect>")`` (tests/conftest.py registers the
marker). A plugin needs, in its own file:

- "sampling": a test of its sampling routine against its own density (a chi-square in the kernel, or for a delta
  plugin its exact events), for the kinds that sample; a texture, which samples nothing, an "eval" test instead;
- "render": the plugin in a rendered scene checked against an expectation (an analytic value, a quadrature,
  another integrator or Mitsuba's image).

The markers are read from the source with `ast` (no test file is imported or run here). What is not yet there is
listed in GAPS with its reason, and those cases are strict xfails: a gap that gets filled fails as XPASS until its
line is removed, so the list only shrinks.
"""
import ast
from pathlib import Path

import pytest

from clrender.scene.registry import registered_classes
from clrender.testing.plugin_checks import ASPECTS

TESTS = Path(__file__).resolve().parent

#: folder (as in clrender/ and tests/) -> the registry tags of its plugins (Nori calls a shape <mesh>)
KINDS = {"bsdfs": ("bsdf",), "emitters": ("emitter",), "shapes": ("shape", "mesh"), "textures": ("texture",),
         "filters": ("rfilter",)}
NEEDS = {"bsdfs": ("sampling", "render"), "emitters": ("sampling", "render"), "shapes": ("sampling", "render"),
         "textures": ("eval", "render"), "filters": ("sampling", "render")}

#: (folder, plugin, aspect) -> why it is missing today
GAPS = {
    ("shapes", "instance", "sampling"): "an instance holds no emitter (refused, as in Mitsuba): nothing of it is sampled",
}


def plugins(folder: str) -> list[str]:
    """The plugin files of a kind: `clrender/<folder>/<name>.py` of every registered class."""
    names = set()
    for tag in KINDS[folder]:
        for cls in registered_classes(tag):
            parts = cls.__module__.split(".")
            if parts[:2] == ["clrender", folder]:   # a plugin the tests register themselves lives elsewhere
                names.add(parts[-1])
    return sorted(names)


def _marker_args(node) -> tuple | None:
    """("name", "aspect") of a `pytest.mark.plugin("name", "aspect")` call, else None."""
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "plugin":
        base = node.func.value
        if isinstance(base, ast.Attribute) and base.attr == "mark":
            return tuple(a.value if isinstance(a, ast.Constant) else None for a in node.args)
    return None


def declared(path: Path) -> set[tuple]:
    """Every (plugin, aspect) the `plugin` markers of a test file's tests declare: on a test function (also in a
    test class) or in the module's `pytestmark`."""
    tree = ast.parse(path.read_text(), str(path))
    out = set()

    def tests(body):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test"):
                yield node
            elif isinstance(node, ast.ClassDef) and node.name.startswith("Test"):
                yield node
                yield from tests(node.body)

    for node in tests(tree.body):
        out |= {a for d in node.decorator_list if (a := _marker_args(d))}
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "pytestmark" for t in node.targets):
            out |= {a for n in ast.walk(node.value) if (a := _marker_args(n))}
    return out


def _cases():
    for folder in KINDS:
        for name in plugins(folder):
            for aspect in NEEDS[folder]:
                gap = GAPS.get((folder, name, aspect))
                marks = pytest.mark.xfail(strict=True, reason=gap) if gap else ()
                yield pytest.param(folder, name, aspect, id=f"{folder}/{name}/{aspect}", marks=marks)


@pytest.mark.parametrize("folder,name,aspect", list(_cases()))
def test_every_plugin_has_its_tests(folder, name, aspect):
    path = TESTS / folder / f"test_{name}.py"
    assert path.is_file(), f"{folder[:-1]} plugin {name!r} (clrender/{folder}/{name}.py) has no test file " \
                           f"tests/{folder}/test_{name}.py"
    assert (name, aspect) in declared(path), \
        f"{folder[:-1]} plugin {name!r}: no {aspect} test in tests/{folder}/test_{name}.py " \
        f"(a test marked @pytest.mark.plugin({name!r}, {aspect!r}))"


def test_gaps_name_registered_plugins():
    """A GAPS line for a plugin or aspect that does not exist would hide nothing and mislead."""
    for folder, name, aspect in GAPS:
        assert name in plugins(folder) and aspect in NEEDS[folder], (folder, name, aspect)


def test_markers_name_registered_plugins_and_known_aspects():
    """A marker naming no plugin (a typo) or an unknown aspect would count for nothing: every marker under tests/
    must name a registered plugin of some kind and one of ASPECTS, as two string constants."""
    known = {n for folder in KINDS for n in plugins(folder)}
    for path in sorted(TESTS.rglob("test_*.py")):
        for marker in declared(path):
            assert len(marker) == 2 and marker[0] in known and marker[1] in ASPECTS, \
                f"{path.relative_to(TESTS)}: @pytest.mark.plugin{marker}: expected a registered plugin's name " \
                f"and one of {', '.join(ASPECTS)}"


def test_the_check_finds_what_is_missing(tmp_path):
    """The reader sees markers on functions, in classes and in pytestmark, and nothing else (a marker on a helper
    that is no test, a bare mention in a string)."""
    (tmp_path / "test_x.py").write_text(
        "import pytest\n"
        "pytestmark = [pytest.mark.plugin('a', 'render')]\n"
        "@pytest.mark.plugin('b', 'sampling')\n@pytest.mark.parametrize('x', [1])\ndef test_one(x):\n    pass\n"
        "class TestC:\n    @pytest.mark.plugin('c', 'eval')\n    def test_two(self):\n        pass\n"
        "@pytest.mark.plugin('d', 'sampling')\ndef helper():\n    '''pytest.mark.plugin(\"e\", \"render\")'''\n")
    assert declared(tmp_path / "test_x.py") == {("a", "render"), ("b", "sampling"), ("c", "eval")}


def test_sidak_families_count_their_files_cases():
    """plugin_checks.FAMILIES keeps the chi-square families of the modules the BSDF files came from; each must still
    count its files' cases (a case added to one file must grow its family, else the others' thresholds move)."""
    import importlib

    from clrender.testing.plugin_checks import FAMILIES

    for family, files in (("nori-bsdf-chi2", ("diffuse", "microfacet")),
                          ("mitsuba-rough-chi2", ("roughconductor", "roughdielectric")),
                          ("coated-chi2", ("plastic", "roughplastic", "blendbsdf", "mask", "twosided")),
                          ("principled-chi2", ("principled", "principledthin"))):
        cases = sum(len(importlib.import_module(f"bsdfs.test_{name}").CASES) for name in files)
        assert FAMILIES[family] == cases, (family, FAMILIES[family], cases)
