"""`_interrupt.stop_pool`: workers stopped and the pool's manager thread finished.

CI once printed "OSError: Bad file descriptor" after an interrupted transient maps build:
the interpreter's exit hook woke the pool's manager thread while that thread was
closing its wake-up pipe.  ``stop_pool`` must leave no manager thread running.
"""
from __future__ import annotations

import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor

from maglevkit._interrupt import stop_pool


def test_stop_pool_terminates_workers_and_joins_the_manager_thread() -> None:
    pool = ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn"))
    futures = [pool.submit(time.sleep, 30.0) for _ in range(4)]
    deadline = time.monotonic() + 30.0
    while not any(f.running() for f in futures) and time.monotonic() < deadline:
        time.sleep(0.05)
    procs = list(pool._processes.values())
    manager = pool._executor_manager_thread
    assert procs and manager is not None and manager.is_alive()
    started = time.monotonic()
    stop_pool(pool, timeout_s=5.0)
    took = time.monotonic() - started
    # the workers sleep 30 s: a stop that waited for them would take that long
    assert took < 10.0, took
    assert all(not p.is_alive() for p in procs)
    assert not manager.is_alive()          # was left running: shutdown() dropped its handle
    assert all(f.done() for f in futures)
