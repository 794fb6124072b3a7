"""Shared helpers of the Python package's tests."""
import threading
import time

import pytest


def assert_releases_the_gil(work):
    """Runs work() while another thread counts once a millisecond. Holding the GIL, the
    C++ code would stop the counter for the whole call (it ticks only in the Python
    around it); free, it ticks about once a millisecond -- asked here for one per 5 ms,
    room for a loaded machine."""
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.01)
    start = time.perf_counter()
    work()
    elapsed = time.perf_counter() - start
    done.set()
    t.join()
    during = [x for x in ticks if start <= x <= start + elapsed]
    if elapsed < 0.05:
        pytest.skip(f"the call took {elapsed:.3f} s: too short to tell")
    assert len(during) >= max(5, elapsed / 0.005), f"{len(during)} ticks in {elapsed:.2f} s"
