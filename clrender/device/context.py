"""OpenCL platform/device listing and choice.

A device is chosen by a SPEC: an index into ``list_devices()`` ("0"), ``cpu`` or ``gpu`` (the first of that
kind), ``intel`` (Intel's OpenCL CPU runtime, below), or a case-insensitive substring of "platform / device"
names. The default is a PoCL CPU device that can actually compile kernels (newest PoCL first), falling back to
Intel's CPU runtime, then to any such CPU device, then the first device.

Why "can actually compile": PoCL asks its LLVM for the host CPU's name and passes it to clang. PoCL 3.0 (the
pocl-binary-distribution wheel, LLVM 14) does not know CPUs newer than its LLVM (e.g. AMD Zen 5, family 1Ah),
gets "generic", and clang rejects that: every build fails with "unknown target CPU 'generic'". PoCL >= 3.1
(e.g. Debian/Ubuntu's pocl-opencl-icd) reads POCL_LLVM_CPU_NAME, which we set for such CPUs; the wheel's
PoCL 3.0 has no such option. Where no PoCL compiles, Intel's OpenCL CPU runtime from PyPI (the ``intel-cpu``
extra, see ``intel_cpu.py``) is the fallback: a PoCL that compiles > Intel's CPU runtime > any other CPU
device. The SPEC ``intel`` names that runtime (a name substring would also match PoCL's "pthread-Intel(R)
Xeon" device on Intel hosts). Its platform is listed after all others, so indices and ``cpu`` keep meaning
what they meant before the extra was installed.
"""
from __future__ import annotations

import functools
import os
import warnings

from ..errors import DeviceError
from . import intel_cpu


def _host_cpu_override() -> str | None:
    """An LLVM CPU name for hosts that LLVM <= 15 cannot name (see the module docstring), else None."""
    try:
        with open("/proc/cpuinfo") as f:
            text = f.read(8192)
    except OSError:
        return None
    info = {}
    for line in text.splitlines():
        if ":" in line:
            k, v = line.split(":", 1)
            info.setdefault(k.strip(), v.strip())
        if not line.strip() and info:
            break
    try:
        family = int(info.get("cpu family", "0"))
    except ValueError:
        return None
    if info.get("vendor_id") == "AuthenticAMD" and family >= 0x1A:
        flags = set(info.get("flags", "").split())
        if "avx512f" in flags:
            return "x86-64-v4"
        return "x86-64-v3" if "avx2" in flags else "x86-64"
    return None


def _cannot_write(folder: str) -> str | None:
    """None if the folder exists or can be made and a file can be written in it (what PoCL and pyopencl will do),
    else why not."""
    import tempfile

    try:
        os.makedirs(folder, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=folder)
        os.close(fd)
        os.unlink(probe)
        return None
    except OSError as e:
        return e.strerror or str(e)


def _writable(*folders: str) -> bool:
    return not any(_cannot_write(f) for f in folders)


def _temp_cache_root() -> str:
    """Where the caches go when the home's cannot be written (a container run as another user)."""
    import tempfile

    return os.path.join(tempfile.gettempdir(), f"clrender-cache-{os.getuid()}")


def _default_pocl_cache() -> str:
    """~/.cache/clrender/pocl, or a folder in the temporary directory where the home is not writable: PoCL
    without a writable cache does not load at all."""
    home = os.path.join(os.path.expanduser("~"), ".cache", "clrender", "pocl")
    return home if _writable(home) else os.path.join(_temp_cache_root(), "clrender", "pocl")


@functools.lru_cache(maxsize=None)   # once per process: pyopencl reads the environment when imported
def _pyopencl_caches() -> None:
    """Give pyopencl caches it can write, or none. It keeps built binaries (for drivers without a cache of their
    own: Intel's CPU runtime, not PoCL) and, through pytools' PersistentDict, the kernel-argument setters of the
    first launch under $XDG_CACHE_HOME (default ~/.cache). Where that cannot be written its fallback is itself a
    traceback (pyopencl 2026.1 reads os.environ["PYOPENCL_CACHE_FAILURE_FATAL"], a KeyError unless set) and the
    invoker cache fails on the first launch: so point $XDG_CACHE_HOME at the temporary folder, and where that is
    not writable either turn pyopencl's caches off (PYOPENCL_NO_CACHE, read when pyopencl is imported) with a
    warning. Every device then renders; each build just compiles again."""
    if os.environ.get("PYOPENCL_NO_CACHE"):
        return
    xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    if _writable(os.path.join(xdg, "pyopencl"), os.path.join(xdg, "pytools")):
        return
    root = _temp_cache_root()
    if _writable(os.path.join(root, "pyopencl"), os.path.join(root, "pytools")):
        os.environ["XDG_CACHE_HOME"] = root
        return
    import logging

    os.environ["PYOPENCL_NO_CACHE"] = "1"
    logging.getLogger("clrender").warning(
        "neither %s nor %s can be written: pyopencl's caches are off (every program compiles again); set "
        "XDG_CACHE_HOME to a writable folder to keep them", xdg, root)


def _pocl_cache_problem() -> str | None:
    """Why PoCL may have failed to load: its cache folder cannot be written."""
    d = os.environ.get("POCL_CACHE_DIR")
    why = _cannot_write(d) if d else None
    return f"PoCL needs a writable POCL_CACHE_DIR, and '{d}' is not ({why})" if why else None


def _cl():
    # Importing pyopencl lazily keeps `clrender --help` fast and lets us word a missing driver clearly.
    # PoCL reads its environment when it initialises, so this must happen before the first platform query.
    if "POCL_CACHE_DIR" not in os.environ:
        os.environ["POCL_CACHE_DIR"] = _default_pocl_cache()
    _pyopencl_caches()
    if "POCL_LLVM_CPU_NAME" not in os.environ:
        cpu = _host_cpu_override()
        if cpu:
            os.environ["POCL_LLVM_CPU_NAME"] = cpu
    intel_cpu.prepare()
    import pyopencl as cl

    return cl


def list_devices():
    """All OpenCL devices as (platform, device) pairs, in a stable order."""
    cl = _cl()
    try:
        platforms = cl.get_platforms()
    except cl.LogicError as exc:  # no ICD / no platform at all
        raise DeviceError(f"no OpenCL platform found ({exc}); install pocl-binary-distribution") from exc
    # sorted() is stable: the Intel CPU runtime goes last, everything else keeps the loader's order.
    platforms = sorted(platforms, key=lambda p: intel_cpu.is_intel_cpu_runtime(p.name))
    out = []
    for p in platforms:
        try:
            devs = p.get_devices()
        except cl.Error:
            continue
        out.extend((p, d) for d in devs)
    return out


def describe(platform, device) -> str:
    return f"{platform.name.strip()} / {device.name.strip()}"


_PROBE_SRC = "__kernel void clrender_probe(__global float* a) { a[get_global_id(0)] = 1.0f; }"


@functools.lru_cache(maxsize=None)
def _build_check(device_key) -> str | None:
    """None if the device compiles a trivial kernel, else the compiler's complaint."""
    cl = _cl()
    for p, d in list_devices():
        if (p.name, d.name, d.int_ptr) == device_key:
            try:
                with warnings.catch_warnings():  # a chatty build log (Intel's runtime) is not a failure
                    warnings.simplefilter("ignore", cl.CompilerWarning)
                    cl.Program(cl.Context([d]), _PROBE_SRC).build()
                return None
            except cl.Error as exc:
                lines = [ln.strip() for ln in str(exc).splitlines() if "error" in ln.lower()]
                return lines[-1] if lines else str(exc).strip().splitlines()[0]
    return "device vanished"


def build_check(platform, device) -> str | None:
    return _build_check((platform.name, device.name, device.int_ptr))


def _unknown_cpu_hint() -> str:
    st = intel_cpu.state or {}
    if not st.get("installed"):
        intel = (f"install Intel's OpenCL CPU runtime from PyPI, no root needed: `{intel_cpu.EXTRA_HINT}` "
                 "(clrender then uses it by itself)")
    elif st.get("problem"):
        intel = f"Intel's OpenCL CPU runtime did not load: {st['problem']}"
    else:
        intel = "Intel's OpenCL CPU runtime (installed) did not build either, see above"
    return ("PoCL cannot compile for this CPU (its LLVM does not know it). Either " + intel + "; or install "
            "a newer PoCL, e.g. `sudo apt-get install pocl-opencl-icd` (Debian/Ubuntu, PoCL >= 3.1), which "
            "clrender prefers and sets POCL_LLVM_CPU_NAME for. See `clrender devices`.")


def _is_intel_cpu(cl, p, d) -> bool:
    return intel_cpu.is_intel_cpu_runtime(p.name) and bool(d.type & cl.device_type.CPU)


def _pocl_version(platform) -> tuple:
    import re

    m = re.search(r"PoCL (\d+)\.(\d+)", platform.version)
    return (int(m.group(1)), int(m.group(2))) if m else (0, 0)


def choose_device(spec: str | int | None = None):
    """Return (platform, device) for a device SPEC (see module docstring)."""
    cl = _cl()
    devices = list_devices()
    if not devices:
        hint = _pocl_cache_problem()
        raise DeviceError("no OpenCL device found; " + (hint if hint else
                                                        "install pocl-binary-distribution for a CPU device"))
    if spec is None or spec == "":
        spec = os.environ.get("CLRENDER_DEVICE", "")
    if spec is None or spec == "":
        pocl = [(p, d) for p, d in devices
                if "portable computing language" in p.name.lower() and d.type & cl.device_type.CPU]
        pocl.sort(key=lambda pd: _pocl_version(pd[0]), reverse=True)
        intel = [(p, d) for p, d in devices if _is_intel_cpu(cl, p, d)]
        others = [(p, d) for p, d in devices  # a real CPU: not the Oclgrind simulator (see _is_only)
                  if _is_only(d, cl.device_type.CPU) and (p, d) not in pocl and (p, d) not in intel]
        problems = []
        for p, d in pocl + intel + others:
            why = build_check(p, d)
            if why is None:
                if not pocl and (hint := _pocl_cache_problem()):   # the user's POCL_CACHE_DIR kept PoCL away
                    import logging

                    logging.getLogger("clrender").warning("%s: PoCL did not load; rendering on %s instead", hint,
                                                          describe(p, d))
                return p, d
            problems.append(f"{describe(p, d)}: {why}")
        if any("unknown target cpu" in w.lower() for w in problems):
            raise DeviceError("no CPU OpenCL device can compile kernels here (" + "; ".join(problems) + "). "
                              + _unknown_cpu_hint())
        # No CPU device builds: a real GPU or accelerator, never a simulator (Oclgrind reports itself as every
        # kind, and would otherwise be chosen silently, rendering a thousand times slower)
        for p, d in devices:
            if _is_only(d, cl.device_type.GPU) or _is_only(d, cl.device_type.ACCELERATOR):
                return p, d
        what = "; ".join(problems + [_pocl_cache_problem() or ""]).strip("; ") or "there is no CPU or GPU device"
        names = ", ".join(f"[{i}] {describe(p, d)}" for i, (p, d) in enumerate(devices))
        raise DeviceError(f"no OpenCL device to render on by default ({what}); available: {names}. Choose one "
                          f"with --device (a simulator such as Oclgrind only by name)")
    s = str(spec).strip()
    if s.isdigit():
        i = int(s)
        if i >= len(devices):
            raise DeviceError(f"device index {i} out of range: {len(devices)} device(s); see `clrender devices`")
        return devices[i]
    if s.lower() == "intel":
        for p, d in devices:
            if _is_intel_cpu(cl, p, d):
                return p, d
        st = intel_cpu.state or {}
        why = st.get("problem") or ("" if st.get("installed") else f"install it with `{intel_cpu.EXTRA_HINT}`")
        raise DeviceError(f"Intel's OpenCL CPU runtime is not available ({why or 'its platform did not load'}); "
                          "see `clrender devices`")
    if s.lower() in ("cpu", "gpu"):
        want = cl.device_type.CPU if s.lower() == "cpu" else cl.device_type.GPU
        for p, d in devices:
            if _is_only(d, want):
                return p, d
        raise DeviceError(f"no {s.upper()} OpenCL device found; see `clrender devices`")
    for p, d in devices:
        if s.lower() in describe(p, d).lower():
            return p, d
    names = ", ".join(f"[{i}] {describe(p, d)}" for i, (p, d) in enumerate(devices))
    raise DeviceError(f"no OpenCL device matches '{s}'; available: {names}")


def is_simulator(device) -> bool:
    """Reports itself as more than one kind of device, as the Oclgrind simulator does (CPU, GPU and accelerator)."""
    cl = _cl()
    kinds = int(device.type) & int(cl.device_type.CPU | cl.device_type.GPU | cl.device_type.ACCELERATOR)
    return bin(kinds).count("1") > 1


def _is_only(device, kind) -> bool:
    """The device is of `kind` and of no other kind: a simulator such as Oclgrind, which reports itself as
    CPU, GPU and accelerator at once, is neither `cpu` nor `gpu` (choose it by name)."""
    cl = _cl()
    kinds = cl.device_type.CPU | cl.device_type.GPU | cl.device_type.ACCELERATOR
    return (device.type & kinds) == kind


@functools.lru_cache(maxsize=None)
def _context_for(device_key):
    cl = _cl()
    for p, d in list_devices():
        if (p.name, d.name, d.int_ptr) == device_key:
            ctx = cl.Context([d])
            return ctx, cl.CommandQueue(ctx)
    raise DeviceError("device vanished")


def get_context(spec: str | int | None = None):
    """A cached (context, queue) for a device SPEC; one per device per process."""
    p, d = choose_device(spec)
    return _context_for((p.name, d.name, d.int_ptr))
