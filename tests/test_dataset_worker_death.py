"""A Dask worker killed in the middle of an episode: the episode is redone, not lost; Ctrl-C on a run."""

import contextlib
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


@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_ctrl_c_or_sigterm_stops_the_run_in_one_line_and_resume_finishes_it(tmp_path, how):
    """Ctrl-C reaches the whole process group; SIGTERM (kill, a batch scheduler's time limit)
    the client: both stop the run cleanly."""
    import subprocess
    import sys

    out = tmp_path / "data"
    args = [sys.executable, "-m", "testbed.cli", "render", "lab", "--episodes", "4", "--frames", "12",
            "--cameras", "2,7", "--seed", "3", "--workers", "2", "--out", str(out)]
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, start_new_session=True)

    def listed():
        with contextlib.suppress(OSError, ValueError):
            return [e["name"] for e in json.loads((out / "manifest.json").read_text())["episodes"]]
        return []

    deadline = time.time() + 120
    while not listed() and proc.poll() is None and time.time() < deadline:
        time.sleep(0.02)
    if how == "ctrl-c":
        os.killpg(proc.pid, signal.SIGINT)                 # as Ctrl-C in a terminal: every process
    else:
        proc.send_signal(signal.SIGTERM)
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == (130 if how == "ctrl-c" else 143), err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.rstrip().endswith("camtask render: " + ("interrupted" if how == "ctrl-c" else "terminated"))
    assert 1 <= len(listed()) < 4                          # finished episodes listed, not all
    # nothing else: no temporary folders, no episode that finished after the manifest's last write
    assert sorted(p.name for p in out.iterdir()) == sorted(listed() + ["manifest.json", "run_info.json"])
    subprocess.run(args + ["--resume"], check=True, capture_output=True, timeout=300)
    m = json.loads((out / "manifest.json").read_text())
    assert [e["name"] for e in m["episodes"]] == [f"episode_{i:04d}" for i in range(4)]


def test_the_cluster_lets_go_of_each_finished_episode(tmp_path):
    """An episode's result (its manifest entry: a checksum per file, ~3 MB for 300 frames of
    16 cameras) is dropped from the cluster once listed, not held until the run ends."""
    config = EpisodeConfig("lab", None, (2,), 1, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    keep = prepare_output(out, config, 4, False, False)
    held = []
    with open_client(1) as client:

        def in_memory(dask_scheduler):
            return sum(ts.state == "memory" for ts in dask_scheduler.tasks.values())

        def progress(frames):
            time.sleep(0.3)                          # the client's releases reach the scheduler
            held.append(client.run_on_scheduler(in_memory))

        done = generate(config, 4, out, keep, client, progress=progress)
    assert sorted(done) == [0, 1, 2, 3] and len(held) == 4
    assert held[-1] == 0, held                       # the last one listed, none is held any more


def test_an_episode_whose_workers_keep_dying_stops_the_run_in_one_line(tmp_path):
    import subprocess
    import sys

    import psutil

    out = tmp_path / "data"
    args = [sys.executable, "-m", "testbed.cli", "render", "lab", "--episodes", "3", "--frames", "6",
            "--cameras", "2", "--seed", "3", "--workers", "1", "--out", str(out)]
    env = os.environ | {"DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES": "0"}   # the first death is fatal
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.time() + 120
    while not list(out.glob(".episode_0001.*.tmp/masks/cam02/*.png")) and time.time() < deadline:
        time.sleep(0.02)
    for child in psutil.Process(proc.pid).children():
        if "spawn_main" in " ".join(child.cmdline()):      # the worker process (its nanny is in proc)
            child.kill()
    err = proc.communicate(timeout=120)[1]
    assert proc.returncode == 1, err
    assert "Traceback" not in err, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("camtask render: error: episode 1: 1 worker process died running it (the last at "), last
    assert last.endswith(f"stopped with 1 of 3 episodes finished, listed in {out / 'manifest.json'} "
                         "(--resume finishes the run)"), last
    subprocess.run(args + ["--resume"], check=True, capture_output=True, timeout=300)
    assert [e["name"] for e in json.loads((out / "manifest.json").read_text())["episodes"]] == [
        "episode_0000", "episode_0001", "episode_0002"]
