"""Signals in the workers of fretwork's local dask cluster (:mod:`pipelines.parallel`).

Importing this module imports ``distributed``: :mod:`pipelines.parallel` does so only when a
local cluster starts.
"""

from __future__ import annotations

import signal
import threading

from distributed import WorkerPlugin


class IgnoreCtrlC(WorkerPlugin):
    """The local cluster's workers ignore SIGINT, also those a nanny starts anew after a worker
    process died. Those do not inherit the ignored signal that the cluster's start gave the
    first ones (``pipelines.parallel._workers_ignore_ctrl_c``): asyncio installs its own handler
    in them, and a Ctrl-C then printed a worker's KeyboardInterrupt traceback (measured: after
    ``Client.restart`` the workers' SIGINT handler is asyncio's, before it SIG_IGN). The
    scheduler hands the plugin to every worker that joins. Local clusters only: the workers of
    a user's own scheduler keep their Ctrl-C."""

    name = "fretwork-ignore-ctrl-c"

    def setup(self, worker) -> None:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
