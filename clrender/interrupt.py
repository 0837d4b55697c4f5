"""Ctrl-C that always works: polling waits on the device, and the command line's interrupt guard.

Python runs signal handlers only between bytecodes of the main thread, so a main thread blocked in
clFinish (or in a long C call) cannot react to Ctrl-C until the call returns. `wait_for` waits on the
queue in short sleeps instead. `CtrlC` is what `clrender render` installs around its whole run: the first
press raises KeyboardInterrupt wherever the program is, and remembers it, so that code which swallows
the exception (a library's broad ``except``) cannot make the program carry on as if nothing happened.
"""
from __future__ import annotations

import abc
import signal
import threading
import time

POLL_SECONDS = 0.002


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


class CtrlC(SigintHandler):
    """SIGINT raises KeyboardInterrupt and is remembered in `pressed`."""

    def __init__(self):
        self.pressed = 0

    def _handle(self, signum, frame):
        self.pressed += 1
        raise KeyboardInterrupt

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed, even if someone swallowed the first one."""
        if self.pressed:
            raise KeyboardInterrupt
