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

Each aspect must also have a test in the default run (`pytest`, which leaves out tests marked slow), so that
marking a long suite slow never leaves a plugin untested by default; SLOW_ONLY lists the exceptions with reasons.
"""
import ast
from pathlib import Path

import pytest

from clrender.scene.registry import registered_classes
from clrender.testing.plugin_checks import ASPECTS

TESTS = Path(__file__).resolve().parent

#: folder (as in clrender/ and tests/) -> the registry tags of its plugins (Nori calls a shape <mesh>)
KINDS = {"bsdfs": ("bsdf",), "emitters": ("emitter",), "shapes": ("shape", "mesh"), "textures": ("texture",),
         "filters": ("rfilter",), "media": ("medium",), "phase": ("phase",), "volumes": ("volume",)}
NEEDS = {"bsdfs": ("sampling", "render"), "emitters": ("sampling", "render"), "shapes": ("sampling", "render"),
         "textures": ("eval", "render"), "filters": ("sampling", "render"),
         "media": ("render",), "phase": ("sampling", "render"), "volumes": ("eval", "render")}

#: (folder, plugin, aspect) -> why it is missing today
GAPS = {
    ("shapes", "instance", "sampling"): "an instance holds no emitter (refused, as in Mitsuba): nothing of it is sampled",
    ("shapes", "sdfgrid", "sampling"): "an SDF grid has no area and cannot emit (refused, as in Mitsuba): nothing of "
                                       "it is sampled",
}

_SLOW_BUILD = "its program alone takes 15-25 s to build on 2 cores; its sampling test is in the default run"
#: (folder, plugin, aspect) -> why the default run has no test of it (the slow suites have)
SLOW_ONLY = {
    ("bsdfs", "principled", "render"): _SLOW_BUILD,
    ("bsdfs", "principledthin", "render"): _SLOW_BUILD,
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


def _is_slow(node) -> bool:
    """`pytest.mark.slow`, alone or in a list or tuple of marks."""
    if isinstance(node, (ast.List, ast.Tuple)):
        return any(_is_slow(n) for n in node.elts)
    return isinstance(node, ast.Attribute) and node.attr == "slow" and isinstance(node.value, ast.Attribute) \
        and node.value.attr == "mark"


def _all_params_slow(deco) -> bool:
    """A `parametrize` whose values are a literal list of `pytest.param(..., marks=<slow>)`, every one slow (values
    given by a name, such as a module's CASE_PARAMS, count as in the default run: those lists keep default cases)."""
    if not (isinstance(deco, ast.Call) and isinstance(deco.func, ast.Attribute) and deco.func.attr == "parametrize"
            and len(deco.args) >= 2 and isinstance(deco.args[1], (ast.List, ast.Tuple))):
        return False
    return all(isinstance(v, ast.Call) and isinstance(v.func, ast.Attribute) and v.func.attr == "param"
               and any(k.arg == "marks" and _is_slow(k.value) for k in v.keywords) for v in deco.args[1].elts)


def _slow(decorators) -> bool:
    return any(_is_slow(d) or _all_params_slow(d) for d in decorators)


def declared(path: Path, default_run: bool = False) -> set[tuple]:
    """Every (plugin, aspect) the `plugin` markers of a test file's tests declare: on a test function (also in a
    test class) or in the module's `pytestmark`. With ``default_run``, only those of tests the default `pytest`
    runs: not marked slow on the function, its class or the module, nor only through slow parameters."""
    tree = ast.parse(path.read_text(), str(path))
    out = set()
    module_slow = False
    module_marks = set()
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "pytestmark" for t in node.targets):
            module_marks |= {a for n in ast.walk(node.value) if (a := _marker_args(n))}
            module_slow = module_slow or _is_slow(node.value)
    if default_run and module_slow:
        return set()

    def tests(body, slow=False):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test"):
                yield node, slow or _slow(node.decorator_list)
            elif isinstance(node, ast.ClassDef) and node.name.startswith("Test"):
                cls_slow = slow or _slow(node.decorator_list)
                yield node, cls_slow
                yield from tests(node.body, cls_slow)

    for node, slow in tests(tree.body):
        if not (default_run and slow):
            out |= {a for d in node.decorator_list if (a := _marker_args(d))}
    return out | module_marks


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
    if (folder, name, aspect) not in SLOW_ONLY:
        assert (name, aspect) in declared(path, default_run=True), \
            f"{folder[:-1]} plugin {name!r}: its {aspect} tests in tests/{folder}/test_{name}.py are all marked " \
            f"slow; the default run must keep one (or list it in SLOW_ONLY with the reason)"


def test_gaps_name_registered_plugins():
    """A GAPS or SLOW_ONLY line for a plugin or aspect that does not exist would hide nothing and mislead; a
    SLOW_ONLY line whose plugin has a default-run test again is stale."""
    for folder, name, aspect in {**GAPS, **SLOW_ONLY}:
        assert name in plugins(folder) and aspect in NEEDS[folder], (folder, name, aspect)
    for folder, name, aspect in SLOW_ONLY:
        assert (name, aspect) not in declared(TESTS / folder / f"test_{name}.py", default_run=True), \
            f"{folder}/{name}/{aspect} has a default-run test now: remove its SLOW_ONLY line"


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


def test_the_check_sees_slow_marks(tmp_path):
    """A test marked slow (itself, its class, or every one of its literal parameters) is not in the default run;
    one with some default parameters, or with parameters given by a name, is."""
    (tmp_path / "test_x.py").write_text(
        "import pytest\n"
        "@pytest.mark.plugin('a', 'render')\n@pytest.mark.slow\ndef test_a():\n    pass\n"
        "@pytest.mark.slow\nclass TestB:\n    @pytest.mark.plugin('b', 'render')\n    def test_b(self):\n"
        "        pass\n"
        "@pytest.mark.plugin('c', 'render')\n@pytest.mark.parametrize('x', [pytest.param(1, marks=pytest.mark.slow), "
        "pytest.param(2, marks=[pytest.mark.slow])])\ndef test_c(x):\n    pass\n"
        "@pytest.mark.plugin('d', 'render')\n@pytest.mark.parametrize('x', [pytest.param(1, marks=pytest.mark.slow), "
        "2])\ndef test_d(x):\n    pass\n"
        "@pytest.mark.plugin('e', 'sampling')\n@pytest.mark.parametrize('x', CASES)\ndef test_e(x):\n    pass\n")
    assert declared(tmp_path / "test_x.py", default_run=True) == {("d", "render"), ("e", "sampling")}
    assert {m[0] for m in declared(tmp_path / "test_x.py")} == set("abcde")
    (tmp_path / "test_y.py").write_text("import pytest\npytestmark = [pytest.mark.slow, pytest.mark.plugin('a', "
                                        "'render')]\n@pytest.mark.plugin('b', 'render')\ndef test_b():\n    pass\n")
    assert declared(tmp_path / "test_y.py", default_run=True) == set()


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
