"""A task for the tests of the fan-out (pipeline/fanout.py, pipeline/cluster.py), module-level so that a
dask worker can unpickle it.
"""

from __future__ import annotations

import threading
import time




def square(x: int) -> tuple[int, int, str]:
    time.sleep(0.01)  # long enough for a second thread to pick up work
    return x, x * x, threading.current_thread().name
