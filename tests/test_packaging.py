"""Every Python package under clrender/ is listed in setup.cfg (a missing one installs without error and
then fails to import on users' machines)."""
import configparser
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_every_package_is_listed():
    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    listed = {ln.strip() for ln in cfg["options"]["packages"].splitlines() if ln.strip()}
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "clrender").rglob("__init__.py")}
    assert found - listed == set(), f"packages missing from setup.cfg: {sorted(found - listed)}"
    assert "clrender.kernels" in listed


def test_every_kernel_file_is_package_data():
    """An OpenCL file under kernels/ that no package_data pattern names is missing from the installed package,
    and the program that includes it fails to build there (not in a checkout)."""
    import glob

    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    kernels = ROOT / "kernels"
    shipped = set()
    for pattern in cfg["options.package_data"]["clrender.kernels"].split(","):
        shipped |= set(glob.glob(pattern.strip(), root_dir=kernels))
    files = {p.relative_to(kernels).as_posix() for p in kernels.rglob("*") if p.suffix in (".cl", ".h")}
    assert files - shipped == set(), f"kernel files setup.cfg does not ship: {sorted(files - shipped)}"


# Import name -> distribution name, for the modules whose names differ.
_DIST = {"PIL": "Pillow", "OpenEXR": "OpenEXR", "pocl_binary_distribution": "pocl-binary-distribution"}
# Imported only inside a feature that names its extra when the module is missing.
_OPTIONAL = {"matplotlib": "plot", "dask": "cluster", "distributed": "cluster", "bokeh": "cluster",
             "pyoidn": "denoise"}


def test_every_runtime_import_is_a_dependency():
    """A shipped command must not die with ModuleNotFoundError after a plain `pip install .` (it once did for
    scipy in `clrender test`): every third-party module clrender imports is in install_requires or is an
    optional feature's module."""
    import ast
    import re
    import sys

    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    required = {re.split(r"[<>=!~\s\[]", ln.strip())[0].lower()
                for ln in cfg["options"]["install_requires"].splitlines() if ln.strip() and not ln.strip().startswith("#")}
    missing = {}
    for path in (ROOT / "clrender").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top in sys.stdlib_module_names or top == "clrender" or top in _OPTIONAL:
                    continue
                if _DIST.get(top, top).lower() not in required:
                    missing.setdefault(top, str(path.relative_to(ROOT)))
    assert not missing, f"imported but not in install_requires: {missing}"


# Where a floor in setup.cfg once let in releases that broke clrender or warned at users (checked by installing them).
_FLOORS = {
    "openexr": ((3, 3), "OpenEXR.File: with 3.2, `clrender render` died writing its EXR"),
    "pyopencl": ((2024, 2, 6), "the fix for pytools' UserWarning about safe_sync, printed by every render"),
}


def test_floors_exclude_releases_known_to_fail_us():
    import re

    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "setup.cfg")
    floors = {}
    for ln in cfg["options"]["install_requires"].splitlines():
        m = re.fullmatch(r"\s*([A-Za-z0-9_.-]+)\s*>=\s*([0-9.]+)\s*", ln)
        if m:
            floors[m[1].lower()] = tuple(int(x) for x in m[2].split("."))
    for dist, (oldest, why) in _FLOORS.items():
        assert dist in floors, f"{dist} has no >= floor in install_requires"
        assert floors[dist] >= oldest, f"{dist}>={'.'.join(map(str, floors[dist]))} admits releases without {why}"
