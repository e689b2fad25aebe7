"""The GIL is released while the library works: Python runs beside a decode. (How much
two threads gain is a timing, measured by benches/python_threads.py, not asserted here.)"""

import subprocess
import sys
import textwrap
import threading
import time

import numpy as np

import mra
from conftest import field


def test_python_code_runs_while_another_thread_decodes():
    a = field((32, 256, 256), np.uint16)
    data = mra.encode(a, max_error=1)
    done = threading.Event()
    ticks = []

    def work():
        mra.decode(data)
        done.set()

    t = threading.Thread(target=work)
    start = time.perf_counter()
    t.start()
    # pure-Python ticks: they advance only while the decoding thread does not hold the GIL
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    elapsed = time.perf_counter() - start
    assert elapsed > 0.05, "decode too fast to observe"
    # gaps between ticks stay short: no stretch of a whole decode without Python running
    gaps = np.diff([start] + ticks)
    assert len(ticks) > 10 and gaps.max() < 0.5 * elapsed, (len(ticks), gaps.max(), elapsed)
