"""One call run on another thread while this one does something else; its result (or error) collected later.

The Renderer packs the scene (Python and numpy) on such a thread while its own builds the OpenCL program, which
leaves the GIL free. The thread is a daemon: a Ctrl-C that ends the program does not wait for it.
"""
from __future__ import annotations

import threading


class Background:
    """``fn(*args, **kwargs)`` started on a daemon thread now; ``result()`` waits for it and returns its value or
    raises its exception in the caller's thread."""

    def __init__(self, fn, *args, **kwargs):
        self._value = None
        self._error: BaseException | None = None

        def run():
            try:
                self._value = fn(*args, **kwargs)
            except BaseException as exc:  # handed to whoever asks for the result
                self._error = exc

        self._thread = threading.Thread(target=run, name=f"clrender-{getattr(fn, '__name__', 'background')}",
                                        daemon=True)
        self._thread.start()

    def wait(self) -> None:
        """Wait until the call has returned or raised (its error is kept for ``result()``)."""
        self._thread.join()

    def result(self):
        self._thread.join()
        if self._error is not None:
            error, self._error = self._error, None
            raise error
        return self._value
