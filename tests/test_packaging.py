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
