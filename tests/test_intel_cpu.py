"""Intel's OpenCL CPU runtime (the ``intel-cpu`` extra) as the fallback device.

The .icd rewriting and the device preference run everywhere, on fake files and fake devices with the build
probe mocked (this machine's PoCL compiles, so "PoCL cannot compile for this CPU" is injected). The renders
on the real runtime run only where the extra is installed: CI does not install its ~280 MB download."""
import types
from pathlib import Path

import numpy as np
import pytest

from clrender.device import context, intel_cpu
from clrender.errors import DeviceError

UNKNOWN_CPU = "error: unknown target CPU 'generic'"


# ---------------------------------------------------------------------------------------------------------
# .icd rewriting
# ---------------------------------------------------------------------------------------------------------
def fake_install(tmp_path):
    """A wheel's files as importlib.metadata locates them: the .icd carries conda's placeholder path."""
    prefix = tmp_path / "venv"
    (prefix / "etc/OpenCL/vendors").mkdir(parents=True)
    (prefix / "lib").mkdir()
    (prefix / "etc/OpenCL/vendors/intel-cpu.icd").write_text("/opt/anaconda1anaconda2anaconda3/lib/libintelocl.so\n")
    (prefix / "etc/OpenCL/vendors/intel-fpga_emu.icd").write_text(
        "/opt/anaconda1anaconda2anaconda3/lib/libintelocl_emu.so\n")   # not shipped
    (prefix / "lib/libintelocl.so").write_bytes(b"")
    files = {p.name: p for p in prefix.rglob("*") if p.is_file()}
    return prefix, files


def test_icd_points_at_the_installed_library(tmp_path):
    prefix, files = fake_install(tmp_path)
    assert intel_cpu.corrected_icds(files) == {"clrender-intel-cpu.icd": str(prefix / "lib/libintelocl.so")}


def test_existing_entries_follow_ocl_icd_rules(tmp_path, monkeypatch):
    system = tmp_path / "etc-vendors"
    system.mkdir()
    (system / "pocl.icd").write_text("libpocl.so.2\n")
    (system / "README").write_text("not an icd")
    monkeypatch.setattr(intel_cpu, "SYSTEM_VENDORS", str(system))
    assert intel_cpu.existing_vendor_entries(None) == {"pocl.icd": "libpocl.so.2\n"}
    assert intel_cpu.existing_vendor_entries("") == {"pocl.icd": "libpocl.so.2\n"}
    user = tmp_path / "user-vendors"
    user.mkdir()
    (user / "nvidia.icd").write_text("libnvidia-opencl.so.1\n")
    assert intel_cpu.existing_vendor_entries(str(user)) == {"nvidia.icd": "libnvidia-opencl.so.1\n"}
    lib = tmp_path / "libmine.so"
    lib.write_bytes(b"")
    assert intel_cpu.existing_vendor_entries(str(lib)) == {"user-library.icd": f"{lib}\n"}
    monkeypatch.setattr(intel_cpu, "SYSTEM_VENDORS", str(tmp_path / "absent"))
    assert intel_cpu.existing_vendor_entries(None) == {}


def test_vendor_folder_is_named_by_content_and_rewritten_in_place(tmp_path):
    a = intel_cpu.write_vendor_dir({"x.icd": "/a/libx.so\n", "y.icd": "liby.so\n"}, tmp_path)
    assert sorted(p.name for p in a.iterdir()) == ["x.icd", "y.icd"]
    assert (a / "x.icd").read_text() == "/a/libx.so\n"
    assert intel_cpu.write_vendor_dir({"y.icd": "liby.so\n", "x.icd": "/a/libx.so\n"}, tmp_path) == a
    b = intel_cpu.write_vendor_dir({"x.icd": "/b/libx.so\n"}, tmp_path)
    assert b != a and (a / "x.icd").read_text() == "/a/libx.so\n"   # another install never clobbers ours


def test_preload_reports_what_it_cannot_load(tmp_path):
    (tmp_path / "libimf.so").write_bytes(b"not an ELF file")
    missing = intel_cpu._preload({"libimf.so": tmp_path / "libimf.so"})
    assert missing[0] == "libintlc.so.5" and missing[1].startswith("libimf.so (")
    assert len(missing) == len(intel_cpu.PRELOAD)


@pytest.fixture()
def fresh_state(monkeypatch):
    monkeypatch.setattr(intel_cpu, "state", None)


def mock_install(monkeypatch, tmp_path, files, libs_present=True):
    """prepare() against a fake install: metadata, the system vendors folder, the cache and the preload."""
    system = tmp_path / "etc-vendors"
    system.mkdir(exist_ok=True)
    (system / "pocl.icd").write_text("libpocl.so.2\n")
    monkeypatch.setattr(intel_cpu, "SYSTEM_VENDORS", str(system))
    monkeypatch.setattr(intel_cpu, "_dist_files", lambda name: files if name == intel_cpu.DIST else None)
    loaded = []

    def preload(lib_files):
        loaded.append(sorted(lib_files))
        return [] if libs_present else ["libimf.so", "libsvml.so"]

    monkeypatch.setattr(intel_cpu, "_preload", preload)
    monkeypatch.setenv("CLRENDER_ICD_DIR", str(tmp_path / "cache"))
    return loaded


def test_prepare_registers_the_runtime_beside_every_other_icd(tmp_path, monkeypatch, fresh_state):
    prefix, files = fake_install(tmp_path)
    loaded = mock_install(monkeypatch, tmp_path, files)
    env = {"CL_CONFIG_CPU_VECTORIZER_MODE": "2"}
    st = intel_cpu.prepare(env)
    assert st == {"installed": True, "vendors": env["OCL_ICD_VENDORS"], "problem": None} and loaded
    folder = env["OCL_ICD_VENDORS"]
    assert folder.startswith(str(tmp_path / "cache"))
    icds = {p.name: p.read_text() for p in Path(folder).iterdir()}
    assert icds == {"pocl.icd": "libpocl.so.2\n", "clrender-intel-cpu.icd": f"{prefix / 'lib/libintelocl.so'}\n"}
    assert env["CL_CONFIG_CPU_VECTORIZER_MODE"] == "2"   # the user's choice stands
    assert intel_cpu.prepare({}) is st                  # once per process
    # A child process inherits OCL_ICD_VENDORS = our folder and ends up with the very same folder.
    monkeypatch.setattr(intel_cpu, "state", None)
    child = {"OCL_ICD_VENDORS": folder}
    intel_cpu.prepare(child)
    assert child["OCL_ICD_VENDORS"] == folder and child["CL_CONFIG_CPU_VECTORIZER_MODE"] == "1"


def test_prepare_does_nothing_without_the_extra(monkeypatch, fresh_state):
    monkeypatch.setattr(intel_cpu, "_dist_files", lambda name: None)
    env = {}
    assert intel_cpu.prepare(env) == {"installed": False, "vendors": None, "problem": None}
    assert env == {}


def test_prepare_names_missing_libraries(tmp_path, monkeypatch, fresh_state):
    _, files = fake_install(tmp_path)
    mock_install(monkeypatch, tmp_path, files, libs_present=False)
    env = {}
    st = intel_cpu.prepare(env)
    assert "OCL_ICD_VENDORS" not in env   # a registered runtime that cannot load would only confuse
    assert "libimf.so" in st["problem"] and 'clrender[intel-cpu]' in st["problem"]


def test_prepare_leaves_a_system_wide_runtime_alone(tmp_path, monkeypatch, fresh_state):
    _, files = fake_install(tmp_path)
    mock_install(monkeypatch, tmp_path, files)
    (tmp_path / "etc-vendors/intel64.icd").write_text("/opt/intel/oclcpu/lib/libintelocl.so\n")
    env = {}
    intel_cpu.prepare(env)
    assert "OCL_ICD_VENDORS" not in env


# ---------------------------------------------------------------------------------------------------------
# Device preference, with fake platforms and the build probe mocked
# ---------------------------------------------------------------------------------------------------------
class FakePlatform:
    def __init__(self, name, version=""):
        self.name, self.version = name, version

    def __repr__(self):
        return self.name


def fake_devices(cl, *names):
    cpu = cl.device_type.CPU
    table = {
        "wheel-pocl": (FakePlatform("Portable Computing Language", "OpenCL 3.0 PoCL 3.0-rc2"), "pthread-AMD Ryzen"),
        "distro-pocl": (FakePlatform("Portable Computing Language", "OpenCL 3.0 PoCL 5.0+debian"), "cpu-znver5"),
        "intel": (FakePlatform("Intel(R) OpenCL"), "AMD Ryzen 9 9950X"),
        "oclgrind": (FakePlatform("Oclgrind"), "Oclgrind Simulator"),
    }
    return [(table[n][0], types.SimpleNamespace(name=table[n][1], type=cpu, key=n)) for n in names]


def inject(monkeypatch, devices, failing=(), intel_state=None):
    monkeypatch.setattr(context, "list_devices", lambda: devices)
    monkeypatch.setattr(context, "build_check", lambda p, d: UNKNOWN_CPU if d.key in failing else None)
    monkeypatch.setattr(intel_cpu, "state", intel_state or {"installed": True, "vendors": "/x", "problem": None})
    monkeypatch.delenv("CLRENDER_DEVICE", raising=False)


@pytest.fixture()
def cl():
    return context._cl()


def chosen(spec=None):
    return context.choose_device(spec)[1].key


def test_intel_runtime_is_the_fallback_when_no_pocl_compiles(cl, monkeypatch):
    inject(monkeypatch, fake_devices(cl, "wheel-pocl", "oclgrind", "intel"), failing={"wheel-pocl"})
    assert chosen() == "intel"


def test_a_pocl_that_compiles_comes_first(cl, monkeypatch):
    inject(monkeypatch, fake_devices(cl, "intel", "wheel-pocl", "distro-pocl"), failing={"wheel-pocl"})
    assert chosen() == "distro-pocl"
    inject(monkeypatch, fake_devices(cl, "intel", "wheel-pocl", "distro-pocl"))
    assert chosen() == "distro-pocl"   # the newer PoCL, as before
    inject(monkeypatch, fake_devices(cl, "intel", "wheel-pocl"))
    assert chosen() == "wheel-pocl"


def test_the_error_names_both_remedies(cl, monkeypatch):
    inject(monkeypatch, fake_devices(cl, "wheel-pocl"), failing={"wheel-pocl"},
           intel_state={"installed": False, "vendors": None, "problem": None})
    with pytest.raises(DeviceError) as e:
        context.choose_device(None)
    msg = str(e.value)
    assert 'pip install "clrender[intel-cpu]"' in msg and "pocl-opencl-icd" in msg and "generic" in msg
    assert msg.index("clrender[intel-cpu]") < msg.index("pocl-opencl-icd")   # the no-root route first


def test_the_error_says_why_an_installed_runtime_is_missing(cl, monkeypatch):
    problem = "intel-opencl-rt is installed but not its libraries libimf.so"
    inject(monkeypatch, fake_devices(cl, "wheel-pocl"), failing={"wheel-pocl"},
           intel_state={"installed": True, "vendors": None, "problem": problem})
    with pytest.raises(DeviceError, match="libimf.so"):
        context.choose_device(None)
    with pytest.raises(DeviceError, match="libimf.so"):
        context.choose_device("intel")


def test_spec_intel_names_the_runtime_not_pocl_on_an_intel_host(cl, monkeypatch):
    devs = fake_devices(cl, "wheel-pocl", "intel")
    devs[0][1].name = "pthread-Intel(R) Xeon(R) Processor"
    inject(monkeypatch, devs)
    assert chosen("intel") == "intel"
    assert chosen("0") == "wheel-pocl"


def test_the_runtime_is_listed_last(cl, monkeypatch):
    plats = [FakePlatform("Intel(R) OpenCL"), FakePlatform("Portable Computing Language"),
             FakePlatform("Intel(R) OpenCL Graphics"), FakePlatform("Oclgrind")]
    for p in plats:
        p.get_devices = (lambda name: lambda: [name])(p.name)
    fake_cl = types.SimpleNamespace(get_platforms=lambda: plats, LogicError=cl.LogicError, Error=cl.Error)
    monkeypatch.setattr(context, "_cl", lambda: fake_cl)
    assert [d for _, d in context.list_devices()] == [
        "Portable Computing Language", "Intel(R) OpenCL Graphics", "Oclgrind", "Intel(R) OpenCL"]


# ---------------------------------------------------------------------------------------------------------
# The real runtime (only where the extra is installed)
# ---------------------------------------------------------------------------------------------------------
def intel_device_or_skip():
    context._cl()
    st = intel_cpu.state
    if not st["installed"]:
        pytest.skip(f"Intel's OpenCL CPU runtime is not installed (`{intel_cpu.EXTRA_HINT}`, a ~280 MB "
                    "download that CI does not install)")
    assert st["problem"] is None, st["problem"]
    try:
        return context.choose_device("intel")
    except DeviceError as exc:
        pytest.fail(f"the extra is installed but its device is missing: {exc}")


def block_z(a, b, block=32):
    """z score of each block x channel of mean(a) - mean(b), from the films' per-pixel variances."""
    def blocks(x):
        h, w = x.shape[:2]
        return x[: h - h % block, : w - w % block].reshape(h // block, block, w // block, block, -1).sum(axis=(1, 3))
    d = blocks(a.image.astype(np.float64) - b.image)
    v = blocks(a.variance() + b.variance())
    return d / np.sqrt(np.maximum(v, 1e-30))


def test_default_scene_on_the_intel_runtime_matches_pocl(monkeypatch):
    import clrender
    from clrender.renderer import Renderer

    p, d = intel_device_or_skip()
    assert context.build_check(p, d) is None
    pocl = [pd for pd in context.list_devices()
            if "portable computing language" in pd[0].name.lower() and context.build_check(*pd) is None]
    if not pocl:
        pytest.skip("no PoCL here compiles kernels, nothing to compare the Intel runtime with")
    # Inject the Zen 5 failure into every PoCL: the default device must become the Intel runtime.
    real = context.build_check
    monkeypatch.setattr(context, "build_check",
                        lambda p, d: UNKNOWN_CPU if "portable" in p.name.lower() else real(p, d))
    assert context.choose_device(None)[1].int_ptr == d.int_ptr
    monkeypatch.undo()

    scene = clrender.load_scene(Path(__file__).resolve().parents[1] / "scenes" / "default.xml")
    on_intel = Renderer(scene, device="intel")
    assert on_intel.device_name.startswith("Intel(R) OpenCL")
    on_pocl = Renderer(scene, device=str(context.list_devices().index(pocl[0])))
    # Same seed: the same random numbers, so the images agree up to float rounding (libm ulps).
    a, b = on_intel.render(spp=4, seed=3), on_pocl.render(spp=4, seed=3)
    assert np.abs(a.image - b.image).max() < 1e-3 * max(float(b.image.max()), 1.0)
    # Independent seeds: equal within noise, over the whole image (catches a 2 % bias) and block by block
    # (64 blocks x 3 channels; |z| < 4.5 has a family-wise false alarm rate of about 0.1 %).
    a, b = on_intel.render(spp=8, seed=11), on_pocl.render(spp=8, seed=12)
    whole = block_z(a, b, block=256)
    assert np.abs(whole).max() < 4, f"whole-image z = {whole.ravel()}"
    z = block_z(a, b)
    assert np.abs(z).max() < 4.5, f"max |z| = {np.abs(z).max():.2f}"
    assert 0.5 < (z ** 2).mean() < 2.0


def test_a_program_built_again_still_names_its_arguments():
    """Kernel arguments are set by name, which Intel's runtime reports only for programs built from source: one
    made from pyopencl's cached binary (the second build of a source, e.g. every render after the first process's)
    has none, so the build must not go through that cache there."""
    from clrender.device.kernelargs import KernelArgs
    from clrender.device.program import build_program

    p, d = intel_device_or_skip()
    import pyopencl as pcl

    ctx = pcl.Context([d])
    src = "__kernel void named(__global float* out, uint count) { if (get_global_id(0) < count) out[0] = 1.0f; }"
    for _ in range(2):   # the second build is the one a binary cache would serve
        prg = build_program(ctx, src, with_types=False, use_cache=False)
        assert KernelArgs(pcl.Kernel(prg, "named")).names() == ["out", "count"]
