"""What `camtask run` prints and records, and how it handles its source and video, on a
source that sees exact discs instead of rendering (no GL)."""

import json

import numpy as np
import pytest

from testbed import loop
from testbed.cli import main
from testbed.commands import run as run_command
from testbed.commands.run import format_summary

HALL = """\
name: hall
frame_rate: 5.0
room: {shape: rectangle, width: 5.0, depth: 4.0, height: 3.0}
cameras:
  intrinsics: {resolution: [320, 240], hfov_deg: 60, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.1, 0.1, 2.5], yaw_deg: 40, pitch_deg: 20}
    - {number: 2, position: [4.9, 3.9, 2.5], yaw_deg: -140, pitch_deg: 20}
    - {number: 3, position: [4.9, 0.1, 2.5], yaw_deg: 140, pitch_deg: 20}
people: {count: 2, radius: 0.25}
"""


SOURCES, WRITERS = [], []          # made by the run under test


class DiscSource:
    """Stands in for :class:`testbed.loop.LiveSource`: each tasked camera's scanline marks
    the columns that see a person's disc, and its frames, if kept, are blank."""

    def __init__(self, scene, params, rng, keep_frames=False):
        from pipeline.rectify import Rectifier

        self.scene, self.keep_frames, self.closed = scene, keep_frames, False
        self.bearings = {c.number: b for c, b in zip(scene.cameras, Rectifier.build(scene.cameras).bearings)}
        self.near = dict.fromkeys(self.bearings, 0.0)
        self.far = dict.fromkeys(self.bearings, np.inf)
        self.fail_at = None
        SOURCES.append(self)

    def scanlines(self, index, positions_xy, numbers):
        if index == self.fail_at:
            raise KeyboardInterrupt
        xy, _, _ = self.scene.floor_poses()
        r = self.scene.people.radius
        out = []
        for n in numbers:
            d = np.asarray(positions_xy) - xy[n - 1]
            centre, half = np.arctan2(d[:, 1], d[:, 0]), np.arcsin(np.clip(r / np.linalg.norm(d, axis=1), 0, 1))
            off = np.angle(np.exp(1j * (self.bearings[n][:, None] - centre[None])))
            out.append((np.abs(off) <= half[None]).any(axis=1))
        rgb = np.zeros((len(numbers), 4, 4, 3), np.uint8) if self.keep_frames else None
        return np.array(out), rgb

    def close(self):
        self.closed = True


class Writer:
    """Stands in for :class:`testbed.video.VideoWriter`: keeps what it is given."""

    def __init__(self, path, fps):
        self.path, self.fps, self.frames, self.closed_ok = path, fps, [], None
        WRITERS.append(self)

    def write(self, frame):
        self.frames.append(frame)

    def close(self, ok=True):
        self.closed_ok = ok


@pytest.fixture
def hall(tmp_path, monkeypatch):
    """The hall scene's file; `run` sees discs through DiscSource and writes video through Writer."""
    import testbed.video

    SOURCES.clear()
    WRITERS.clear()
    monkeypatch.setattr(loop, "LiveSource", DiscSource)
    monkeypatch.setattr(testbed.video, "VideoWriter", Writer)
    path = tmp_path / "hall.yaml"
    path.write_text(HALL)
    return str(path)


def test_run_json_records_the_options_the_seed_and_the_scene(hall, capsys):
    assert main(["run", hall, "--tasker", "greedy", "--k", "2", "--frames", "3", "--seed", "7",
                 "--no-near-field", "--json"]) == 0
    out = capsys.readouterr().out
    assert out.endswith("}\n")                          # one document, then a new line
    doc = json.loads(out)
    summary = doc["summary"]
    assert {k: summary[k] for k in ("scene", "people", "frames", "tasker", "k", "m", "update_every", "feedback",
                                    "near_field", "seed")} == {
        "scene": "hall", "people": 2, "frames": 3, "tasker": "greedy", "k": 2, "m": None, "update_every": 1,
        "feedback": "hull", "near_field": False, "seed": 7}
    assert [f["frame"] for f in doc["frames"]] == [0, 1, 2]
    assert all(len(f["tasked"]) == 2 and len(f["truth"]) == 2 for f in doc["frames"])


def test_run_json_records_incremental_swaps_period_and_feedback(hall, capsys):
    assert main(["run", hall, "--k", "3", "--m", "2", "--update-every", "2", "--feedback", "tracks",
                 "--frames", "2", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)["summary"]
    assert (summary["tasker"], summary["m"], summary["update_every"], summary["feedback"]) == (
        "incremental", 2, 2, "tracks")
    assert summary["near_field"] is True and summary["seed"] == 0


def test_run_prints_the_summary_and_the_frames_bar(hall, capsys):
    assert main(["run", hall, "--tasker", "uniform", "--k", "2", "--frames", "2"]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("hall: 2 people, 2 frames, tasker uniform k=2\n")
    assert "uniform k=2: 100%" in captured.err           # the loop's progress bar
    assert "video:" not in captured.err


def test_run_without_video_keeps_no_frames_and_closes_its_source(hall, capsys):
    assert main(["run", hall, "--k", "1", "--frames", "2"]) == 0
    (source,) = SOURCES
    assert not source.keep_frames and source.closed
    assert WRITERS == []


def test_run_video_is_written_at_the_scene_s_rate_and_the_frames_let_go(hall, capsys, monkeypatch, tmp_path):
    painted = []

    def painter(scene, source):
        def paint(result):
            painted.append(result.rgb.shape)
            return np.full((2, 2, 3), result.index, np.uint8)
        return paint

    monkeypatch.setattr(run_command, "_painter", painter)
    video = tmp_path / "out.mp4"
    assert main(["run", hall, "--k", "2", "--frames", "3", "--json", "--video", str(video)]) == 0
    captured = capsys.readouterr()
    assert len(json.loads(captured.out)["frames"]) == 3            # stdout holds the document alone
    assert captured.err.endswith(f"video: {video}\n")
    (writer,) = WRITERS
    (source,) = SOURCES
    assert writer.fps == 5.0 and writer.closed_ok is True and source.keep_frames and source.closed
    assert [int(f[0, 0, 0]) for f in writer.frames] == [0, 1, 2]
    assert painted == [(2, 4, 4, 3)] * 3


def test_execute_drops_each_frame_s_images_once_in_the_video(hall, monkeypatch, tmp_path):
    from scene import load_scene
    from testbed.loop import LoopConfig

    monkeypatch.setattr(run_command, "_painter", lambda scene, source: lambda r: np.zeros((2, 2, 3), np.uint8))
    scene = load_scene(hall)
    truth = np.tile([[1.0, 1.0], [3.5, 2.5]], (2, 1, 1))
    results, summary, bearings = run_command.execute(scene, LoopConfig("uniform", 2), None, truth,
                                                     np.random.default_rng(0), str(tmp_path / "v.mp4"))
    assert [r.rgb for r in results] == [None, None]
    assert bearings is SOURCES[0].bearings
    assert (summary["m"], summary["update_every"], summary["feedback"]) == (None, None, None)


def test_an_interrupted_run_discards_its_video_and_closes_its_source(hall, monkeypatch, tmp_path):
    monkeypatch.setattr(run_command, "_painter", lambda scene, source: lambda r: np.zeros((2, 2, 3), np.uint8))
    real = DiscSource.__init__

    def failing(self, *a, **k):
        real(self, *a, **k)
        self.fail_at = 1

    monkeypatch.setattr(DiscSource, "__init__", failing)
    assert main(["run", hall, "--k", "1", "--frames", "3", "--video", str(tmp_path / "out.mp4")]) == 130
    (writer,) = WRITERS
    assert len(writer.frames) == 1 and writer.closed_ok is False and SOURCES[0].closed


@pytest.mark.parametrize("argv, message", [
    (["--video", ""], "--video: expected a file name, got ''"),
    (["--video", "x.gif"], "--video: expected a .mp4 file name, got 'x.gif'"),
    (["--tasker", "best", "--m", "2"], "--tasker: unknown value 'best'; expected one of "),
    (["--k", "20"], "--k: expected at most 3 cameras (the scene has 3), got 20"),
    (["--k", "2", "--m", "3"], "--m: expected at most k = 2, got 3"),
    (["--k", "1", "--params", "missing.yaml"], "--params: "),
])
def test_run_refuses_bad_options_before_the_walk_naming_them(hall, capsys, monkeypatch, argv, message):
    import testbed.episode

    monkeypatch.setattr(testbed.episode, "walk", lambda *a, **kw: pytest.fail("the walk was drawn"))
    assert main(["run", hall, "--frames", "1", *argv]) == 2
    assert capsys.readouterr().err.startswith(f"camtask run: error: {message}")


def test_run_s_defaults_are_those_its_help_gives():
    import argparse
    import re

    parser = argparse.ArgumentParser()
    commands = parser.add_subparsers()
    run_command.add_parser(commands)
    args = parser.parse_args(["run", "lab"])
    said = {a.dest: found.group(1) for a in commands.choices["run"]._actions
            if (found := re.search(r"\(default ([\w.]+)[,;)]", a.help or ""))}
    assert {"tasker", "k", "m", "update_every", "frames", "seed"} <= set(said)
    m, update_every, feedback = run_command.loop_options(args)       # None in args: the loop's own
    for dest, value in said.items():
        assert str({"m": m, "update_every": update_every}.get(dest, getattr(args, dest))) == value, dest
    assert feedback == "hull" and args.near_field is True and args.json is False and args.video is None
    assert parser.parse_args(["run", "lab", "--m", "2", "--update-every", "3"]).m == 2


SUMMARY = {"scene": "lab", "people": 3, "frames": 4, "tasker": "incremental", "k": 6, "m": 2, "update_every": 3,
           "hull_area": 1.23456, "residual": 0.98765, "bits_per_frame": 211.6, "camera_switches": 5,
           "tracking": {"mse": 0.012345, "mota": 0.5, "motp": 0.1234, "idf1": 0.875, "switches": 1, "matches": 9,
                        "false_positives": 4, "misses": 6, "max_distance": 0.75}}


def test_the_summary_text_gives_each_mean_and_metric_rounded():
    assert format_summary(SUMMARY).splitlines() == [
        "lab: 3 people, 4 frames, tasker incremental k=6 m=2 update every 3",
        "  mean hull area      1.235 m^2",
        "  mean residual       0.988  (hull area / occupied area - 1)",
        "  bits per frame      212  (run-length coded scanlines)",
        "  camera switches     5",
        "  tracking            MSE 0.0123 m^2  MOTA 0.500  MOTP 0.123 m  IDF1 0.875",
        ("                      false positives 4 track-frames  misses 6 person-frames  id switches 1  "
         "(matched within 0.75 m)")]


def test_the_summary_text_shows_missing_metrics_as_dashes_and_no_tracking_line_without_tracking():
    tracking = SUMMARY["tracking"] | {"mse": None, "motp": None}
    assert "MSE - m^2  MOTA 0.500  MOTP - m  IDF1 0.875" in format_summary(SUMMARY | {"tracking": tracking})
    lines = format_summary(SUMMARY | {"tracking": {}, "update_every": None, "m": None}).splitlines()
    assert lines[0] == "lab: 3 people, 4 frames, tasker incremental k=6" and len(lines) == 5
