"""Building OpenCL programs from the kernels shipped in ``clrender.kernels``.

Every program is built from a source string plus include paths (our ``kernels/`` folder and pyopencl's
Random123 headers) and ``-D`` defines. The struct header generated from ``layout.py`` (``codegen.c_header``) is
prepended so the kernels and the host share one definition of every table row. Built programs are cached per
context, source and options; PoCL's own disk cache (``POCL_CACHE_DIR``) makes a warm build take tens of ms.
"""
from __future__ import annotations

import contextlib
import functools
import os
import sys
import tempfile
import warnings
from pathlib import Path

from ..errors import DeviceError


#: The narrowest launch that runs PoCL's generic work-group function. PoCL compiles a kernel again, as a "smallgrid"
#: variant, for a launch narrower than 65535 work-items (seen in its cache: <local>-goffs0-smallgrid beside
#: <local>-goffs0); a program launched both ways is compiled twice (for the test programs, which hold every plugin,
#: minutes on 2 cores). Launches at least this wide keep one compiled variant; their extra work-items return at once.
MIN_GENERIC_GLOBAL = 1 << 16

@functools.lru_cache(maxsize=None)
def kernels_dir() -> Path:
    """The folder holding render.cl and its headers (installed package data, or the source tree)."""
    try:
        from importlib.resources import files

        p = Path(str(files("clrender.kernels")))
        if (p / "render.cl").is_file():
            return p
    except (ModuleNotFoundError, TypeError):
        pass
    # Running from a source checkout (clrender/ beside kernels/), e.g. `python -m pytest` in the repo.
    p = Path(__file__).resolve().parents[2] / "kernels"
    if (p / "render.cl").is_file():
        return p
    raise DeviceError("cannot find clrender's OpenCL kernels (clrender.kernels package data is missing)")


def pyopencl_include_dir() -> Path:
    import pyopencl

    return Path(pyopencl.__file__).parent / "cl"


def build_options(defines: dict | None = None, fast_math: bool = False) -> list[str]:
    from .codegen import generated_include_dir

    # kernels/, the dispatch headers generated from the registered plugins (gen/*.h), Random123
    # -cl-kernel-arg-info: the host sets arguments by name (clrender/device/kernelargs.py)
    opts = ["-I", str(kernels_dir()), "-I", generated_include_dir(), "-I", str(pyopencl_include_dir()),
            "-cl-std=CL1.2", "-cl-kernel-arg-info"]
    if fast_math:
        opts.append("-cl-fast-relaxed-math")
    for k, v in sorted((defines or {}).items()):
        opts.append(f"-D{k}" if v is None else f"-D{k}={v}")
    return opts


@contextlib.contextmanager
def _compiler_stderr():
    """Hold back what the driver's compiler prints on file descriptor 2 during a build.

    It is passed on after a successful build only when the user asked for build logs (``PYOPENCL_COMPILER_OUTPUT=1``,
    pyopencl's own switch); after a failure the error (with the build log) says it all, and after a Ctrl-C the
    compiler's "1 error generated." would only confuse."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield
        return
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        ok = False
        try:
            yield
            ok = True
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            if ok and _want_build_logs():
                held.seek(0)
                text = held.read()
                if text:
                    os.write(2, text)


def _want_build_logs() -> bool:
    return os.environ.get("PYOPENCL_COMPILER_OUTPUT", "") not in ("", "0")


_PROGRAMS: dict = {}


def is_pocl(ctx) -> bool:
    """Whether the context's device runs on PoCL (its platform is "Portable Computing Language")."""
    try:
        return "Portable Computing Language" in ctx.devices[0].platform.name
    except Exception:  # noqa: BLE001  (a context without a readable platform: build as for any driver)
        return False


def build_program(ctx, source: str, defines: dict | None = None, fast_math: bool = False,
                  with_types: bool = True, use_cache: bool = True):
    """Build (and cache) a program; ``source`` may ``#include`` any header under kernels/.

    ``use_cache=False`` bypasses (and does not fill) this in-memory cache, so the driver really builds the
    program again (PoCL still uses its disk cache): `clrender bench` times warm builds this way."""
    import pyopencl as cl

    if with_types:
        from .codegen import c_header

        source = c_header() + "\n" + source
    defines = dict(defines or {})
    if is_pocl(ctx):
        # kernels/builtins.h: PoCL leaves its builtins as calls; ours compile to the instructions
        defines.setdefault("CLRENDER_INLINE_BUILTINS", None)
    source = '#include "builtins.h"\n' + source
    opts = build_options(defines, fast_math)
    key = (ctx.int_ptr, source, tuple(opts))
    prg = _PROGRAMS.get(key) if use_cache else None
    if prg is not None:
        return prg
    try:
        with warnings.catch_warnings(), _compiler_stderr():
            # A successful build's log (NVIDIA's driver writes one for our kernels; Intel's CPU runtime logs
            # "Compilation started ... Done." every time) would reach the user as a CompilerWarning on every
            # render, telling them nothing they can act on: shown only with PYOPENCL_COMPILER_OUTPUT=1, where
            # pyopencl prints the log itself. A failed build still raises, with its log.
            if not _want_build_logs():
                warnings.simplefilter("ignore", cl.CompilerWarning)
            # pyopencl's own binary cache only for PoCL: a program that other drivers (Intel's CPU runtime, seen
            # here) create from a cached binary reports no kernel-argument names (clGetKernelArgInfo:
            # KERNEL_ARG_INFO_NOT_AVAILABLE), and every kernel's arguments are set by name (kernelargs.py)
            prg = cl.Program(ctx, source).build(options=opts, cache_dir=None if is_pocl(ctx) else False)
    except cl.RuntimeError as exc:
        raise DeviceError(f"OpenCL program failed to build:\n{exc}") from exc
    if use_cache:
        _PROGRAMS[key] = prg
    return prg
