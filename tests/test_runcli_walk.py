"""The walk `camtask run` draws before its first frame has a progress bar of its own (a
million frames took minutes without a word)."""

import argparse

import numpy as np

from scene.motion import circle_polygon, random_waypoint
from testbed.commands import run as run_command


def test_the_walk_reports_each_step_and_stays_the_same_walk():
    room = circle_polygon(1.0, 256)
    steps = []
    with_bar = random_waypoint(room, [0.1] * 4, 30, 0.1, 0.5, np.random.default_rng(5), progress=steps.append)
    assert steps == [1] * 29                # the first position is the drop, not a step
    assert np.array_equal(with_bar, random_waypoint(room, [0.1] * 4, 30, 0.1, 0.5, np.random.default_rng(5)))


def test_run_shows_the_walk_as_it_is_drawn(monkeypatch, capsys):
    monkeypatch.setattr(run_command, "WALK_BAR_DELAY", 0)
    ns = argparse.Namespace(scene="lab", tasker="incremental", k=6, m=1, update_every=1, feedback="hull",
                            near_field=True, frames=50, people=3, params=None, seed=0, video=None)
    truth = run_command.prepare(ns)[3]
    assert truth.shape == (50, 3, 2)
    err = capsys.readouterr().err
    assert "\rwalk: " in err and "/50 [" in err        # shown, then cleared for the frames' bar


def test_the_walk_s_bar_counts_every_frame_and_is_cleared(monkeypatch, capsys):
    """The bar starts at the first frame (the people's drop) and counts each step after it."""
    import tqdm

    ended = []

    class Counted(tqdm.tqdm):
        def close(self):
            ended.append((self.n, self.total))
            super().close()

    monkeypatch.setattr(tqdm, "tqdm", Counted)
    monkeypatch.setattr(run_command, "WALK_BAR_DELAY", 0)
    ns = argparse.Namespace(scene="lab", tasker="incremental", k=6, m=1, update_every=1, feedback="hull",
                            near_field=True, frames=40, people=2, params=None, seed=3, video=None)
    run_command.prepare(ns)
    assert ended[0] == (40, 40)
    err = capsys.readouterr().err
    assert err.endswith("\r") and "\n" not in err          # cleared, its line left to the frames' bar
