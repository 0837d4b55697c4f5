"""The package's layers: the device layer reads the plugin registry it is given and imports no plugin; whoever
assembles the application (loader, CLI, testing, bench, a cluster worker, this test-suite's conftest) imports
clrender.plugins."""
import subprocess
import sys
import textwrap

# Packages and modules that hold plugins (a class registered for an XML tag), and the module importing them all.
PLUGIN_PACKAGES = ("clrender.bsdfs", "clrender.cameras", "clrender.emitters", "clrender.films", "clrender.filters",
                   "clrender.integrators", "clrender.samplers", "clrender.shapes", "clrender.textures")
PLUGIN_MODULES = ("clrender.plugins", "clrender.scene.scene")


def _fresh(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120)


def test_the_device_layer_imports_no_plugin():
    code = f"""
        import pkgutil, sys
        import clrender.device
        for m in pkgutil.iter_modules(clrender.device.__path__):
            __import__("clrender.device." + m.name)
        from clrender.device import dispatch, program
        # what used to import every plugin inside a function: the registry's walk and the generated headers
        for kind in dispatch.KINDS:
            dispatch.plugins(kind)
        dispatch.signature()
        program.build_options()
        plugins = sorted(m for m in sys.modules
                         if m.startswith({PLUGIN_PACKAGES!r}) or m in {PLUGIN_MODULES!r})
        print("device modules:", sorted(m for m in sys.modules if m.startswith("clrender.device.")))
        print("plugin modules:", plugins)
        sys.exit(1 if plugins else 0)
    """
    r = _fresh(code)
    assert r.returncode == 0, r.stdout + r.stderr
    # the walk saw the modules it is about (a renamed package would make the test pass vacuously)
    assert "clrender.device.layout" in r.stdout and "clrender.device.dispatch" in r.stdout


def test_rows_without_registered_plugins_are_an_error_naming_the_fix():
    # A program or a row laid out from an empty registry would hold no plugin and render black without a word.
    r = _fresh("""
        from clrender.device import layout
        try:
            layout.dtype("Bsdf")
        except RuntimeError as e:
            print(e)
        else:
            print("laid out", layout.dtype("Bsdf").names)
    """)
    assert r.returncode == 0, r.stderr
    assert "no device plugins are registered" in r.stdout and "clrender.plugins" in r.stdout, r.stdout


def test_importing_the_plugins_registers_the_rows():
    r = _fresh("""
        import clrender.plugins
        from clrender.device import layout
        print(layout.dtype("Bsdf").names)
    """)
    assert r.returncode == 0, r.stderr
    assert "'diffuse'" in r.stdout and "'microfacet'" in r.stdout, r.stdout
