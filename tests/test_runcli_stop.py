"""A run on local Dask workers stopped by Ctrl-C, SIGTERM or an error returns at once: the
busy workers are killed, not waited for (Dask's nanny let one finish its task for 4 s)."""

import os
import time

import psutil
import pytest

from testbed.parallel import open_client


def test_a_stopped_run_kills_its_busy_local_workers_at_once():
    with pytest.raises(KeyboardInterrupt), open_client(1) as client:
        pids = list(client.run(os.getpid).values())
        episode = client.submit(time.sleep, 60, pure=False)   # an episode that takes a while
        deadline = time.monotonic() + 60
        while episode.key not in set().union(*client.processing().values()) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.3)                                     # running on the worker's thread
        start = time.monotonic()
        raise KeyboardInterrupt
    took = time.monotonic() - start
    assert took < 2.5, f"the cluster took {took:.1f} s to close"
    assert pids and not any(psutil.pid_exists(pid) for pid in pids)
