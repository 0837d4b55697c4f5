"""Intel's OpenCL CPU runtime from PyPI (the ``intel-cpu`` extra) as a fallback device.

``pip install "clrender[intel-cpu]"`` installs ``intel-opencl-rt`` (the runtime, with its own LLVM, which
knows every x86-64 CPU) and ``intel-cmplr-lib-rt`` (libimf/libsvml/libirng/libintlc, which the runtime needs
but does not declare). Neither makes the runtime visible to an OpenCL loader by itself:

- the wheel's ``etc/OpenCL/vendors/intel-cpu.icd`` names ``/opt/anaconda1anaconda2anaconda3/lib/...``, a
  conda placeholder that only conda's post-link script rewrites. We write a corrected copy into a folder we
  own, next to copies of every other .icd the loader would have read (``/etc/OpenCL/vendors`` or the user's
  ``OCL_ICD_VENDORS``), and point ``OCL_ICD_VENDORS`` at it. pyopencl's bundled ocl-icd still adds its own
  ``.libs/pocl.icd`` (the wheel's PoCL) through ``PYOPENCL_HOME``, so nothing disappears.
- the runtime's libraries come from several wheels, possibly in different prefixes, and the loader would
  need ``LD_LIBRARY_PATH``, which the dynamic linker reads only at process start. We load them with
  ``RTLD_GLOBAL`` first, so the runtime's ``DT_NEEDED`` entries resolve to the already loaded copies.

The ICD loader reads its environment once, at the first platform query of the process, so :func:`prepare`
must run before it (``clrender.device.context`` calls it first thing). It costs one metadata lookup when the
extra is not installed.

The runtime's default vectoriser makes our kernels about 4x slower than PoCL (measured on AMD Zen 5: 0.26x);
``CL_CONFIG_CPU_VECTORIZER_MODE=1`` brings it to about 1.1x, so we set it unless the user did.

``CLRENDER_ICD_DIR`` overrides where the vendors folder goes (default ``~/.cache/clrender/opencl-vendors``).
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import tempfile
from pathlib import Path

DIST = "intel-opencl-rt"
LIB_DISTS = ("intel-cmplr-lib-rt", "tbb")
EXTRA_HINT = 'pip install "clrender[intel-cpu]"'
PLATFORM_PREFIX = "intel(r) opencl"  # the CPU runtime; Intel's GPU runtime says "Intel(R) OpenCL Graphics"
SYSTEM_VENDORS = "/etc/OpenCL/vendors"
# Libraries libintelocl.so needs from the other wheels, each after the ones it needs itself.
PRELOAD = ("libintlc.so.5", "libimf.so", "libsvml.so", "libirng.so", "libtbb.so.12")

# What prepare() did, for `clrender devices` and error messages: None until it runs, then a dict.
state: dict | None = None


def is_intel_cpu_runtime(platform_name: str) -> bool:
    name = platform_name.strip().lower()
    return name.startswith(PLATFORM_PREFIX) and "graphics" not in name and "fpga" not in name


def _dist_files(name: str) -> dict[str, Path] | None:
    """basename -> absolute path of every file a distribution installed, or None if it is not installed."""
    from importlib import metadata

    try:
        dist = metadata.distribution(name)
    except metadata.PackageNotFoundError:
        return None
    out = {}
    for f in dist.files or ():
        out.setdefault(f.name, Path(dist.locate_file(f)).resolve())
    return out


def corrected_icds(files: dict[str, Path]) -> dict[str, str]:
    """.icd file name -> the library path it should name, for each .icd of the runtime whose library exists
    (the wheel also carries an FPGA-emulator .icd whose library it does not ship)."""
    out = {}
    for name, path in files.items():
        if not name.endswith(".icd"):
            continue
        try:
            lib = Path(path.read_text().strip()).name
        except OSError:
            continue
        if lib in files and files[lib].is_file():
            out["clrender-" + name] = str(files[lib])
    return out


def existing_vendor_entries(ocl_icd_vendors: str | None) -> dict[str, str]:
    """.icd name -> content of every entry the loader would read without us (ocl-icd's rules: a directory
    in OCL_ICD_VENDORS replaces /etc/OpenCL/vendors; a file there is a single library or .icd)."""
    src = ocl_icd_vendors or SYSTEM_VENDORS
    p = Path(src)
    if p.is_dir():
        out = {}
        for f in sorted(p.glob("*.icd")):
            try:
                out[f.name] = f.read_text()
            except OSError:
                continue
        return out
    if ocl_icd_vendors and p.is_file():
        if p.suffix == ".icd":
            return {p.name: p.read_text()}
        return {"user-library.icd": str(p) + "\n"}
    return {}


def write_vendor_dir(entries: dict[str, str], root: Path) -> Path:
    """Write ``entries`` (.icd name -> content) into a folder under ``root`` named by their hash and return
    it. Named by content, so processes with different installs never overwrite each other's folder, and
    each file is replaced atomically, so a concurrent reader never sees half a file."""
    digest = hashlib.sha256(repr(sorted(entries.items())).encode()).hexdigest()[:16]
    folder = root / digest
    folder.mkdir(parents=True, exist_ok=True)
    for name, content in entries.items():
        target = folder / name
        try:
            if target.read_text() == content:
                continue
        except OSError:
            pass
        fd, tmp = tempfile.mkstemp(dir=folder, suffix=".tmp")
        with os.fdopen(fd, "w") as f:
            f.write(content)
        os.replace(tmp, target)
    return folder


def _cache_root() -> Path:
    if os.environ.get("CLRENDER_ICD_DIR"):
        return Path(os.environ["CLRENDER_ICD_DIR"])
    return Path(os.path.expanduser("~")) / ".cache" / "clrender" / "opencl-vendors"


def _preload(lib_files: dict[str, Path]) -> list[str]:
    """Load each library of PRELOAD globally; return the names that could not be found or loaded."""
    missing = []
    for name in PRELOAD:
        path = lib_files.get(name)
        if path is None:
            missing.append(name)
            continue
        try:
            ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
        except OSError as exc:
            missing.append(f"{name} ({exc})")
    return missing


def prepare(environ=os.environ) -> dict:
    """Make the runtime from the ``intel-cpu`` extra visible to the ICD loader, if it is installed. Runs
    once per process; returns (and keeps in ``state``) {"installed": bool, "vendors": the folder
    OCL_ICD_VENDORS now names, or None, "problem": why the runtime is not registered, or None}."""
    global state
    if state is not None:
        return state
    state = {"installed": False, "vendors": None, "problem": None}
    files = _dist_files(DIST)
    if files is None:
        return state
    state["installed"] = True
    environ.setdefault("CL_CONFIG_CPU_VECTORIZER_MODE", "1")
    icds = corrected_icds(files)
    if not icds:
        state["problem"] = f"{DIST} is installed but ships no .icd whose library exists"
        return state
    existing = existing_vendor_entries(environ.get("OCL_ICD_VENDORS") or None)
    ours = {Path(lib).name for lib in icds.values()}
    if any(Path(c.strip()).name in ours for n, c in existing.items() if n not in icds):
        return state  # a system-wide install of the same runtime is registered already: loading two clashes
    lib_files = dict(files)
    for name in LIB_DISTS:
        lib_files.update(_dist_files(name) or {})
    missing = _preload(lib_files)
    if missing:
        state["problem"] = (f"{DIST} is installed but not its libraries {', '.join(missing)} "
                            f"(`{EXTRA_HINT}` installs them)")
        return state
    # Rewriting from a folder we wrote earlier (a child process inherits OCL_ICD_VENDORS) gives the same
    # entries, hence the same folder.
    entries = dict(existing)
    entries.update({name: lib + "\n" for name, lib in icds.items()})
    try:
        folder = write_vendor_dir(entries, _cache_root())
    except OSError:
        folder = write_vendor_dir(entries, Path(tempfile.gettempdir()) / f"clrender-{os.getuid()}-vendors")
    environ["OCL_ICD_VENDORS"] = str(folder)
    state["vendors"] = str(folder)
    return state
