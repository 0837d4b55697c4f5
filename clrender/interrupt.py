"""Ctrl-C that always works: polling waits on the device, and the command line's interrupt guard.

Python runs signal handlers only between bytecodes of the main thread, so a main thread blocked in
clFinish (or in a long C call) cannot react to Ctrl-C until the call returns. `wait_for` waits on the
queue in short sleeps instead. `CtrlC` is what `clrender render` installs around its whole run: the first
press raises KeyboardInterrupt wherever the program is, and remembers it, so that code which swallows
the exception (a library's broad ``except``) cannot make the program carry on as if nothing happened.

While `CtrlC` is installed, no KeyboardInterrupt is raised inside the initialisation of a native extension module:
nanobind (pyopencl) and pybind11 (OpenEXR) call Python code while they set a module up (nanobind builds its enums
with Python's `enum`), and an exception raised there is fatal ("Critical nanobind error", SIGABRT) instead of
propagating. A Ctrl-C in that window is recorded and raised as soon as the module is set up (`signals_deferred`).
Calls into the OpenCL driver need no such guard: Python runs the handler only between bytecodes, so a Ctrl-C during
a driver call raises after the call has returned to Python.
"""
from __future__ import annotations

import abc
import importlib.machinery
import os
import signal
import sys
import threading
import time
from contextlib import contextmanager

POLL_SECONDS = 0.002

#: A test hook, MODULE[@FILE]: a SIGINT is sent inside the initialisation of that extension module (`_test_hook`).
TEST_SIGINT_ENV = "CLRENDER_TEST_SIGINT_IN_INIT"

_deferring = 0          # depth of the sections in which CtrlC only records a SIGINT


def wait_for(queue) -> None:
    """queue.finish(), but with Python signal handlers running while the device works."""
    import pyopencl as cl

    marker = cl.enqueue_marker(queue)
    queue.flush()
    complete = cl.command_execution_status.COMPLETE
    delay = 0.0002
    while True:
        status = marker.command_execution_status
        if status == complete:
            return
        if status < 0:  # the driver reports a failed command as a negative status
            queue.finish()  # raises the driver's error
            return
        time.sleep(delay)
        delay = min(delay * 2, POLL_SECONDS)


class SigintHandler(abc.ABC):
    """Context manager installing `_handle` for SIGINT (main thread only) and restoring the old handler."""

    _old = None

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self._old = signal.signal(signal.SIGINT, self._handle)
        return self

    def __exit__(self, *exc):
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
        return False

    @abc.abstractmethod
    def _handle(self, signum, frame):
        """What a Ctrl-C does while this handler is installed."""


@contextmanager
def signals_deferred():
    """A section in which `CtrlC` records a SIGINT without raising; it raises KeyboardInterrupt at the section's
    end instead (at the outermost one's, when nested)."""
    global _deferring
    before = CtrlC.active.pressed if CtrlC.active is not None else 0
    _deferring += 1
    try:
        yield
    finally:
        _deferring -= 1
    if _deferring == 0 and CtrlC.active is not None and CtrlC.active.pressed > before:
        raise KeyboardInterrupt


class _GuardedExtensionLoader(importlib.machinery.ExtensionFileLoader):
    """An extension module's loader that sets the module up with SIGINT deferred."""

    def create_module(self, spec):
        with signals_deferred():
            _test_hook(self.name)
            return super().create_module(spec)

    def exec_module(self, module):
        with signals_deferred():
            _test_hook(self.name)
            super().exec_module(module)


class _NativeImportGuard:
    """A meta path finder in front of the standard PathFinder: it finds what PathFinder finds, and loads
    extension modules with `_GuardedExtensionLoader`."""

    @classmethod
    def find_spec(cls, name, path=None, target=None):
        spec = importlib.machinery.PathFinder.find_spec(name, path, target)
        if spec is not None and type(spec.loader) is importlib.machinery.ExtensionFileLoader:
            spec.loader = _GuardedExtensionLoader(spec.loader.name, spec.loader.path)
        return spec

    @classmethod
    def install(cls) -> None:
        if cls not in sys.meta_path:
            at = sys.meta_path.index(importlib.machinery.PathFinder) \
                if importlib.machinery.PathFinder in sys.meta_path else len(sys.meta_path)
            sys.meta_path.insert(at, cls)

    @classmethod
    def remove(cls) -> None:
        if cls in sys.meta_path:
            sys.meta_path.remove(cls)


_test_hook_sent = set()


def _test_hook(name: str) -> None:
    """Test hook: $CLRENDER_TEST_SIGINT_IN_INIT = MODULE[@FILE] sends SIGINT from the first Python function (in a file
    whose name starts with FILE) that the native initialisation of MODULE calls: for pyopencl._cl@enum.py, nanobind
    building an enum with Python's `enum` (in the multi-phase initialisation's exec step), the window in which an
    unguarded KeyboardInterrupt is fatal."""
    target, _, where = os.environ.get(TEST_SIGINT_ENV, "").partition("@")
    if target != name or name in _test_hook_sent:
        return
    in_native = False

    def profile(frame, event, arg):
        nonlocal in_native
        if event == "c_call" and getattr(arg, "__name__", "") in ("create_dynamic", "exec_dynamic"):
            in_native = True
        elif event == "call" and in_native and os.path.basename(frame.f_code.co_filename).startswith(where):
            sys.setprofile(None)
            _test_hook_sent.add(name)
            print(f"clrender: test hook: SIGINT sent inside the initialisation of {name} "
                  f"({frame.f_code.co_name} in {os.path.basename(frame.f_code.co_filename)})", file=sys.stderr)
            os.kill(os.getpid(), signal.SIGINT)
        elif event == "c_return" and in_native and getattr(arg, "__name__", "") in ("create_dynamic", "exec_dynamic"):
            sys.setprofile(None)   # this step called no Python code: no window in it
    sys.setprofile(profile)


class CtrlC(SigintHandler):
    """SIGINT raises KeyboardInterrupt and is remembered in `pressed`; inside `signals_deferred` (around every
    extension module's initialisation while installed) it is only remembered, and raised at the section's end."""

    active = None   # the installed instance

    def __init__(self):
        self.pressed = 0

    def __enter__(self):
        super().__enter__()
        if self._old is not None:
            CtrlC.active = self
            _NativeImportGuard.install()
        return self

    def __exit__(self, *exc):
        if CtrlC.active is self:
            CtrlC.active = None
            _NativeImportGuard.remove()
        return super().__exit__(*exc)

    def _handle(self, signum, frame):
        self.pressed += 1
        if not _deferring:
            raise KeyboardInterrupt

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed, even if someone swallowed the first one."""
        if self.pressed:
            raise KeyboardInterrupt


class Interrupted(Exception):
    """Raised when the user pressed Ctrl-C twice."""


class PassFlag(SigintHandler):
    """First Ctrl-C: ask the loop to stop after the pass in flight (and say so, if `notice` is given: a pass
    can take seconds, and a Ctrl-C that seems ignored gets pressed again). Second: abort."""

    def __init__(self, notice: str | None = None):
        self.requested = False
        self.notice = notice

    def _handle(self, signum, frame):
        if self.requested:
            raise Interrupted("aborted by a second Ctrl-C")
        self.requested = True
        if self.notice:
            try:  # os.write, not print: the handler may run inside a write to sys.stderr (the progress bar)
                os.write(2, self.notice.encode())
            except OSError:
                pass
