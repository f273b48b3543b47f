"""A run on local Dask workers stopped by Ctrl-C, SIGTERM or an error kills its busy
workers: Dask's nanny let one finish its task (for up to 4 s) before it was stopped."""

import functools
import os
import time

import psutil
import pytest

from testbed.parallel import open_client

#: An episode that writes its file after 3 s: within the 4 s a nanny would wait for it.
EPISODE = "import pathlib, time\ntime.sleep(3)\npathlib.Path(done).write_text('finished')\n"


def test_a_stopped_run_kills_its_busy_local_workers(tmp_path):
    done = tmp_path / "done"
    with pytest.raises(KeyboardInterrupt), open_client(1) as client:
        pids = list(client.run(os.getpid).values())
        episode = client.submit(functools.partial(exec, EPISODE, {"done": str(done)}), pure=False)
        deadline = time.monotonic() + 60
        while episode.key not in set().union(*client.processing().values()) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.3)                                     # running on the worker's thread
        raise KeyboardInterrupt
    assert pids and not any(psutil.pid_exists(pid) for pid in pids)
    assert not done.exists()                               # killed, not left to finish its task
