"""`camtask study tracking` and `camtask study lab` on tiny runs."""

import json

import numpy as np
import pytest

from testbed.cli import main
from testbed.studies import tracking


def run_json(capsys, *argv):
    assert main(["study", *argv, "--json", "--no-progress"]) == 0
    return json.loads(capsys.readouterr().out)


def test_tracking_records_and_figure(capsys, tmp_path):
    png = tmp_path / "fig14.png"
    doc = run_json(capsys, "tracking", "--pairs", "incremental:4,uniform:6", "--steps", "12",
                   "--trials", "2", "--workers", "0", "--plot", str(png))
    assert [(r["tasker"], r["k"]) for r in doc["records"]] == [("incremental", 4), ("uniform", 6)]
    for r in doc["records"]:
        assert r["trials"] == 2 and r["mse"] >= 0 and r["mota"] <= 1 and 0 <= r["idf1"] <= 1
    assert png.stat().st_size > 5000


def test_tracking_mse_only_over_trials_with_a_matched_position(capsys):
    # one step: no track is confirmed yet, so no position is matched and there is no MSE
    doc = run_json(capsys, "tracking", "--pairs", "uniform:6", "--steps", "1", "--objects", "1",
                   "--trials", "2", "--workers", "0")
    (r,) = doc["records"]
    assert r["mse"] is None and r["mse_sem"] is None and r["mse_trials"] == 0 and r["mota"] <= 0
    assert main(["study", "tracking", "--pairs", "uniform:6", "--steps", "1", "--objects", "1",
                 "--trials", "2", "--workers", "0", "--no-progress"]) == 0
    table = capsys.readouterr().out
    assert "1 walking disc (mean" in table and "MSE over the 0 of 2 trials with a matched position" in table


def test_tracking_same_numbers_for_any_worker_count(capsys):
    args = ("tracking", "--pairs", "incremental:3,uniform:5", "--steps", "8", "--trials", "2", "--seed", "3")
    a = run_json(capsys, *args, "--workers", "0")["records"]
    b = run_json(capsys, *args, "--workers", "2")
    assert b["meta"]["workers"] == 2                        # 2 trials, 2 tasks: really in workers
    assert a == b["records"]


def test_both_networks_see_the_same_walk():
    opts = {"objects": 4, "steps": 6, "update_every": 1, "m": 1, "radius": 0.1, "speed": 0.3}
    a = tracking.run_episode("uniform", 6, opts, 7, 0)
    b = tracking.run_episode("incremental", 4, opts, 7, 0)
    np.testing.assert_array_equal(a["truth"], b["truth"])


@pytest.mark.parametrize("argv, match", [
    (["tracking", "--pairs", "best:4"], "--pairs: expected TASKER:K"),
    # said only "expected TASKER:K items with TASKER uniform, greedy or incremental"
    (["tracking", "--pairs", "incremental:0"], "K an integer >= 1, got 'incremental:0'"),
    (["tracking", "--pairs", "uniform:six"], "K an integer >= 1, got 'uniform:six'"),
    (["tracking", "--pairs", "incremental:17"], "exceeds the 16 candidate cameras"),
    (["tracking", "--steps", "0"], "--steps: expected an integer >= 1"),
    (["tracking", "--pairs", "incremental:4,uniform:4", "--m", "5"],
     "--m: expected at most the smallest incremental k = 4, got 5"),
    (["lab", "--k", "17"], "--k: 17 cameras exceed the scene's 16"),
    (["lab", "--taskers", "optimal"], "--taskers: unknown value 'optimal'"),
    (["lab", "--people", "0"], "--people: expected an integer >= 1"),
    (["lab", "--scene", "circle"], "floor-plane cameras only"),
])
def test_bad_arguments(capsys, argv, match):
    assert main(["study", *argv, "--workers", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0]


@pytest.mark.render
def test_lab_study_normalised_by_all_cameras(capsys, tmp_path):
    png = tmp_path / "fig13.png"
    doc = run_json(capsys, "lab", "--people", "2", "--k", "4,8", "--taskers", "uniform,greedy",
                   "--frames", "3", "--trials", "1", "--workers", "0", "--plot", str(png))
    recs = {(r["tasker"], r["k"]): r["residual"] for r in doc["records"]}
    assert set(recs) == {("uniform", 4), ("uniform", 8), ("greedy", 4), ("greedy", 8)}
    # normalised by the smallest 16-camera hull: nothing tasked does better than 1
    assert all(v >= 1 - 1e-9 for v in recs.values())
    assert doc["all_cameras_residual"] >= 1
    assert png.stat().st_size > 5000


@pytest.mark.parametrize("feedback", ["hull", "tracks"])
def test_tracking_tasks_from_what_feedback_names(monkeypatch, feedback):
    """--feedback hull tasks from the hull's polygon centres; --feedback tracks from the
    tracker's predictions once it has tracks (both were the centres when tracks were ignored)."""
    centres, given = [], []
    real_centres, real_choose = tracking.core.polygon_centres, tracking.core.choose_cameras

    def spy_centres(polys):
        centres.append(real_centres(polys))
        return centres[-1]

    def spy_choose(tasker, k, xy, yaw, fov, estimates, *args, **kwargs):
        if len(given) < len(centres):             # the first call is the uniform start, before any hull
            given.append((len(centres) - 1, np.asarray(estimates, float)))
        return real_choose(tasker, k, xy, yaw, fov, estimates, *args, **kwargs)

    monkeypatch.setattr(tracking.core, "polygon_centres", spy_centres)
    monkeypatch.setattr(tracking.core, "choose_cameras", spy_choose)
    opts = {"objects": 3, "steps": 12, "update_every": 1, "m": 1, "radius": 0.1, "speed": 0.3, "feedback": feedback}
    tracking.run_episode("incremental", 6, opts, 7, 0)
    assert len(given) == opts["steps"]
    same = [c.shape == centres[t].shape and np.allclose(c, centres[t]) for t, c in given]
    assert all(same) if feedback == "hull" else not all(same)


def test_tracking_figure_titles_say_dash_not_nan_without_a_matched_position(monkeypatch):
    """A walk whose tracks never matched an object titled its panels '(all objects nan)'
    while the table says '-' for the same MSE."""
    titles = []
    monkeypatch.setattr(tracking, "save_figure", lambda fig, path: titles.extend(a.get_title() for a in fig.axes))
    opts = {"pairs": [("uniform", 6)], "objects": 2, "steps": 2, "update_every": 1, "m": 1, "radius": 0.1,
            "speed": 0.3, "feedback": "hull"}
    tracking.plot({"meta": {"arguments": opts, "seed": 0}, "figure_trial": 0}, "unused.png")
    assert titles == ["uniform k=6: this track's MSE -\n(all objects -)"]


SMALL_ROOM = """\
name: small room
room: {shape: circle, radius: 3.0, height: 3.0}
cameras:
  intrinsics: {resolution: [256, 192], hfov_deg: 90, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 2, position: [-2.8, 0.0, 2.5], yaw_deg: 0, pitch_deg: 30}
    - {number: 1, position: [2.8, 0.0, 2.5], yaw_deg: 180, pitch_deg: 30}
people: {count: 1, radius: 0.3}
"""


@pytest.mark.render
def test_lab_study_names_the_scene_by_its_name(capsys, tmp_path):
    """A scene file's ``name`` is the study's ``scene``, as `run` and `render` report it (it
    was the file's name)."""
    path = tmp_path / "my_room.yaml"
    path.write_text(SMALL_ROOM)
    doc = run_json(capsys, "lab", "--scene", str(path), "--people", "1", "--k", "1", "--taskers", "uniform",
                   "--frames", "1", "--trials", "1", "--workers", "0")
    assert doc["scene"] == "small room" and doc["cameras"] == 2
