"""A Dask worker killed in the middle of an episode: the episode is redone, not lost."""

import json
import os
import signal
import threading
import time

import pytest

from pipeline import load_params
from testbed.episodes import EpisodeConfig
from testbed.generate import generate, prepare_output
from testbed.parallel import open_client

pytestmark = pytest.mark.render


def test_killed_worker_episode_is_redone(tmp_path):
    config = EpisodeConfig("lab", None, (2, 7), 6, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    keep = prepare_output(out, config, 1, False, False)
    killed = []
    with open_client(1) as client:
        (pid,) = client.run(os.getpid).values()

        def kill_when_writing():
            deadline = time.time() + 60
            while time.time() < deadline:
                tmps = list(out.glob(".episode_0000.*.tmp/masks/cam02/*.png"))
                if tmps:
                    os.kill(pid, signal.SIGKILL)
                    killed.append(pid)
                    return
                time.sleep(0.02)

        t = threading.Thread(target=kill_when_writing)
        t.start()
        done = generate(config, 1, out, keep, client)
        t.join()
    assert killed, "the episode finished before the worker could be killed"
    assert sorted(done) == [0]
    m = json.loads((out / "manifest.json").read_text())
    assert [e["name"] for e in m["episodes"]] == ["episode_0000"]
    assert max(p.name for p in (out / "episode_0000" / "frames" / "cam07").iterdir()) == "000005.png"
    assert not list(out.glob(".*tmp"))
