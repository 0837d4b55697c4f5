"""Dask worker plugins (a module of their own: it imports distributed, which clrender does not need)."""
from __future__ import annotations

import signal
import threading

from distributed import WorkerPlugin


class IgnoreCtrlC(WorkerPlugin):
    """For LocalCluster workers: Ctrl-C in a terminal reaches the whole process group and would kill the
    workers under the client; the client alone decides what Ctrl-C does (cancel, keep what is finished,
    shut the workers down). Applied to workers restarted after a crash too."""

    def setup(self, worker):
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
