"""The tasked network loop, `camtask run` and `camtask demo`."""

import json
from itertools import pairwise

import numpy as np
import pytest
from shapely.geometry import Point

from scene import load_scene
from tasking import visual_hull_of_scanlines
from testbed.cli import main
from testbed.episode import walk, with_people
from testbed.loop import LoopConfig, PrecomputedSource, run_loop, summarise


def _disc_scanlines(scene, truth, bearings):
    """Exact scanlines of discs: a column is occupied when any part of it sees a disc."""
    xy, _, _ = scene.floor_poses()
    r = scene.people.radius
    out = np.zeros((len(truth), len(xy), bearings.shape[1]), bool)
    for t, pos in enumerate(truth):
        d = pos[None] - xy[:, None]                          # (n_cams, people, 2)
        centre = np.arctan2(d[..., 1], d[..., 0])
        half = np.arcsin(np.clip(r / np.linalg.norm(d, axis=-1), 0, 1))
        diff = np.angle(np.exp(1j * (bearings[:, :, None] - centre[:, None, :])))
        step = np.abs(np.gradient(bearings, axis=1))[:, :, None] / 2      # half a column
        out[t] = (np.abs(diff) <= half[:, None, :] + step).any(axis=-1)
    return out


@pytest.fixture(scope="module")
def lab_episode():
    from pipeline.rectify import Rectifier

    scene = load_scene("lab")
    truth = walk(scene, 12, np.random.default_rng(5))
    bearings = Rectifier.build(scene.cameras).bearings
    return scene, truth, PrecomputedSource(_disc_scanlines(scene, truth, bearings), bearings)


@pytest.mark.parametrize("tasker", ["uniform", "greedy", "lazy_greedy", "incremental", "clustering"])
def test_loop_hull_contains_every_person_seen_by_a_tasked_camera(lab_episode, tasker):
    import shapely

    scene, truth, source = lab_episode
    results = list(run_loop(scene, LoopConfig(tasker, 8), truth, source))
    assert len(results) == len(truth)
    for r in results:
        assert len(r.tasked) == 8 and len(set(r.tasked)) == 8
        assert r.bits_sent > 0 and r.hull_area > 0
        union = shapely.union_all(r.polygons)
        for p in r.truth:  # exact scanlines: the pruned hull still holds every person
            disc = shapely.Point(p).buffer(scene.people.radius)
            assert disc.difference(union).area < 1e-4 * disc.area
    summary = summarise(results, scene)
    assert summary["frames"] == len(truth) and summary["residual"] > 0
    assert 0 <= summary["tracking"]["idf1"] <= 1


def test_greedy_beats_uniform_on_average(lab_episode):
    scene, truth, source = lab_episode
    mean = {t: np.mean([r.hull_area for r in run_loop(scene, LoopConfig(t, 6), truth, source)])
            for t in ("uniform", "greedy")}
    assert mean["greedy"] <= mean["uniform"]


def test_incremental_swaps_m_cameras_per_update(lab_episode):
    scene, truth, source = lab_episode
    results = list(run_loop(scene, LoopConfig("incremental", 6, m=1, update_every=3), truth, source))
    for a, b in pairwise(results):
        changed = len(set(b.tasked) - set(a.tasked))
        assert changed <= 1
        if b.index % 3 != 0:
            assert changed == 0


def spy_on_tasker(monkeypatch, record):
    """Call ``record(args)`` with the positional arguments of every choose_cameras call of the loop."""
    import testbed.loop

    real = testbed.loop.choose_cameras
    monkeypatch.setattr(testbed.loop, "choose_cameras", lambda *a, **kw: record(a) or real(*a, **kw))


@pytest.mark.parametrize("update_every", [1, 3])
def test_the_tasker_runs_only_for_frames_that_follow(lab_episode, monkeypatch, update_every):
    """Cameras are chosen for the next frame: none after the last one."""
    scene, truth, source = lab_episode
    calls = []
    spy_on_tasker(monkeypatch, lambda a: calls.append(1))
    n = len(list(run_loop(scene, LoopConfig("greedy", 6, update_every=update_every), truth, source)))
    assert len(calls) == 1 + (n - 1) // update_every  # the first frame is uniform


def test_bad_loop_arguments(lab_episode):
    scene, truth, source = lab_episode
    with pytest.raises(ValueError, match="k: expected at most 16 cameras"):
        next(run_loop(scene, LoopConfig("greedy", 17), truth, source))
    with pytest.raises(ValueError, match="tasker: unknown value 'best'; expected one of uniform"):
        next(run_loop(scene, LoopConfig("best", 4), truth, source))
    with pytest.raises(ValueError, match="m: expected at most k = 2"):
        next(run_loop(scene, LoopConfig("incremental", 2, m=3), truth, source))
    xy, _, _ = scene.floor_poses()
    with pytest.raises(ValueError, match="scanlines"):
        visual_hull_of_scanlines(xy[:2], source.all[0, :2, :600] * 0 + 0.1, np.zeros((2, 640), bool),
                                 scene.room.polygon)


def test_more_or_fewer_people_keep_the_scene_s_colours_and_add_the_defaults():
    from scene.config import default_colours

    lab = load_scene("lab")
    more, fewer = with_people(lab, 5), with_people(lab, 2)
    assert (more.people.count, fewer.people.count) == (5, 2)
    np.testing.assert_array_equal(more.people.colours, np.r_[lab.people.colours, default_colours(5)[3:]])
    np.testing.assert_array_equal(fewer.people.colours, lab.people.colours[:2])


def test_a_walk_starts_where_the_scene_places_people_and_walks_one_person_or_none():
    import dataclasses

    lab = load_scene("lab")
    rng = np.random.default_rng(0)
    placed = np.array([[1.0, 1.0], [3.0, 2.0], [5.0, 4.0]])
    path = walk(dataclasses.replace(lab, people=dataclasses.replace(lab.people, positions=placed)), 4, rng)
    assert path.shape == (4, 3, 2) and np.array_equal(path[0], placed)
    one = walk(with_people(lab, 1), 4, rng)
    assert one.shape == (4, 1, 2) and lab.room.polygon.contains(Point(one[0, 0]))
    assert walk(with_people(lab, 0), 4, rng).shape == (4, 0, 2)


def test_as_many_people_as_uint8_labels_hold_are_renderable_and_no_more():
    import dataclasses

    from render.raster import MAX_PEOPLE
    from scene.config import default_colours
    from testbed.episode import check_people_renderable

    lab = load_scene("lab")
    crowd = lambda n: dataclasses.replace(lab, people=dataclasses.replace(
        lab.people, count=n, colours=default_colours(n).astype(np.uint8)))
    check_people_renderable(crowd(MAX_PEOPLE), "--people")
    with pytest.raises(ValueError, match=f"--people: expected at most {MAX_PEOPLE} people"):
        check_people_renderable(crowd(MAX_PEOPLE + 1), "--people")


def test_people_validation():
    lab = load_scene("lab")
    with pytest.raises(ValueError, match="--people: 400 people of radius 0.25 m do not fit"):
        with_people(lab, 400)
    with pytest.raises(ValueError, match="--people: expected a number >= 0"):
        with_people(lab, -1)


@pytest.mark.parametrize("argv, match", [
    (["--k", "20"], "k: expected at most 16 cameras"),
    (["--tasker", "best"], "tasker: unknown value 'best'; expected one of uniform"),
    (["--people", "0"], "--people: expected at least 1 person"),
    (["--people", "500"], "do not fit in the room"),
    (["--frames", "0"], "--frames: expected a number >= 1"),
    (["--seed", "-1"], "--seed: expected an integer in 0..4294967295, got -1"),
    (["--video", "x.gif"], "--video: expected a .mp4 file name, got 'x.gif'"),
])
def test_run_bad_input_is_one_line(capsys, argv, match):
    assert main(["run", "lab", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0]


def test_optimal_with_too_many_subsets_is_refused_before_the_first_frame():
    """C(24, 12) subsets failed after the first frame, naming an internal parameter."""
    from tasking.taskers import MAX_SUBSETS

    assert LoopConfig("optimal", 8).check(16).k == 8                  # C(16, 8) = 12870
    assert LoopConfig("optimal", 1).check(MAX_SUBSETS).k == 1         # C(n, 1) = n: the limit itself is allowed
    with pytest.raises(ValueError, match=r"C\(200001, 1\) = 200001 subsets"):
        LoopConfig("optimal", 1).check(MAX_SUBSETS + 1)
    with pytest.raises(ValueError, match=r"--tasker: optimal would compare C\(24, 12\) = 2704156 subsets of "
                                         r"cameras each frame, more than 200000; choose greedy or incremental"):
        LoopConfig("optimal", 12).check(24, as_options=True)


def test_a_run_too_long_for_memory_is_one_line(capsys):
    assert main(["run", "lab", "--frames", str(10**12)]) == 2         # refused before the walk
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("camtask run: error: --frames: 1000000000000 frames would hold about ")


@pytest.mark.parametrize("out, match", [
    ("afile", "--out: {tmp}/afile exists and is not a folder"),
    ("afile/sub", "--out: cannot make the folder {tmp}/afile/sub (Not a directory)"),
])
def test_demo_out_that_cannot_be_a_folder_is_named(tmp_path, capsys, out, match):
    (tmp_path / "afile").write_text("x")
    assert main(["demo", "--out", str(tmp_path / out)]) == 2
    assert capsys.readouterr().err.strip() == "camtask demo: error: " + match.format(tmp=tmp_path)


def test_run_refuses_the_circle_scene(capsys):
    assert main(["run", "circle"]) == 2
    assert "floor-plane cameras only" in capsys.readouterr().err


@pytest.mark.render
def test_run_end_to_end_json_and_video(tmp_path, capsys):
    video = tmp_path / "run.mp4"
    assert main(["run", "lab", "--frames", "4", "--k", "6", "--seed", "2", "--json", "--video", str(video)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["frames"]) == 4
    f = doc["frames"][0]
    assert len(f["tasked"]) == 6 and f["bits_sent"] > 0 and len(f["truth"]) == 3
    assert {"hull_area", "residual", "estimates", "tracks"} <= set(f)
    assert {"residual", "bits_per_frame", "tracking"} <= set(doc["summary"])
    assert video.stat().st_size > 1000
    assert not list(tmp_path.glob(".*partial*"))
    assert doc["summary"]["feedback"] == "hull" and doc["summary"]["near_field"] is True


def test_ctrl_c_while_the_video_is_finished_leaves_no_partial_file(tmp_path):
    """ffmpeg takes a moment to finish the file: an interrupt then left .run.partial.mp4."""
    import numpy as np

    from testbed.video import VideoWriter

    class Interrupted:
        """ffmpeg's generator, interrupted as it finishes the file."""

        def __init__(self, gen):
            self.gen = gen

        def close(self):
            self.gen.close()
            raise KeyboardInterrupt

    writer = VideoWriter(tmp_path / "run.mp4", fps=5)
    writer.write(np.zeros((32, 32, 3), np.uint8))
    writer._gen = Interrupted(writer._gen)
    with pytest.raises(KeyboardInterrupt):
        writer.close(ok=True)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.render
def test_run_json_is_strict_json_before_any_track_is_confirmed(tmp_path, capsys):
    def no_nan(name):
        raise AssertionError(f"{name} in the JSON document")

    video = tmp_path / "new" / "run.mp4"                       # its folder is made
    assert main(["run", "lab", "--frames", "2", "--k", "1", "--json", "--video", str(video)]) == 0
    tracking = json.loads(capsys.readouterr().out, parse_constant=no_nan)["summary"]["tracking"]
    assert tracking["mse"] is None and tracking["motp"] is None and tracking["matches"] == 0
    assert video.stat().st_size > 1000


@pytest.mark.render
def test_interrupted_run_leaves_no_video(tmp_path, monkeypatch):
    from testbed import loop

    real, calls = loop.visual_hull_of_scanlines, []

    def interrupt_third_frame(*a, **k):   # Ctrl-C after two frames went into the video
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*a, **k)
    monkeypatch.setattr(loop, "visual_hull_of_scanlines", interrupt_third_frame)
    video = tmp_path / "run.mp4"
    assert main(["run", "lab", "--frames", "3", "--video", str(video)]) == 130
    assert list(tmp_path.iterdir()) == []


@pytest.mark.render
def test_demo_writes_its_video_summary_and_top_view_and_same_seed_same_summary(tmp_path, capsys):
    # what `make demo` runs, on fewer frames
    for out in (tmp_path / "a", tmp_path / "b"):
        assert main(["demo", "--out", str(out), "--frames", "3"]) == 0
        assert (out / "run.mp4").stat().st_size > 1000 and (out / "topview.png").stat().st_size > 1000
        assert sorted(p.name for p in out.iterdir()) == ["run.mp4", "summary.json", "topview.png"]
    doc = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert len(doc["frames"]) == 3 and doc["summary"]["seed"] == 1                   # the default seed
    assert (tmp_path / "a" / "summary.json").read_bytes() == (tmp_path / "b" / "summary.json").read_bytes()
    assert "mean residual" in capsys.readouterr().out


def test_the_near_field_switch_chooses_where_cameras_carve(lab_episode):
    """With blind radii the hull only grows (each camera carves less); near_field=False
    is the hull of radii 0, the paper's."""
    scene, truth, source = lab_episode
    near = PrecomputedSource(source.all, np.array(list(source.bearings.values())), np.full(16, 0.8))
    plain = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", 6), truth, source)]
    carved_late = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", 6), truth, near)]
    switched_off = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", 6, near_field=False), truth, near)]
    assert switched_off == plain
    assert all(a >= b - 1e-9 for a, b in zip(carved_late, plain)) and sum(carved_late) > sum(plain)


def _estimates_with_tracks_feedback(monkeypatch, frames):
    """The object estimates given to greedy (k = 8, --feedback tracks) on each frame of a
    lab walk of ``frames`` frames seen by exact disc scanlines, and the loop's results."""
    from pipeline.rectify import Rectifier

    scene = load_scene("lab")
    truth = walk(scene, frames, np.random.default_rng(5))
    bearings = Rectifier.build(scene.cameras).bearings
    source = PrecomputedSource(_disc_scanlines(scene, truth, bearings), bearings)
    given = []
    spy_on_tasker(monkeypatch, lambda a: given.append(np.array(a[5])))
    results = list(run_loop(scene, LoopConfig("greedy", 8, feedback="tracks"), truth, source))
    return given, results


def test_feedback_tracks_tasks_from_the_trackers_predictions(monkeypatch):
    """docs/network.md: with --feedback tracks "the tracker's confirmed tracks are the
    estimates instead" of the hull's polygon centres. No test ran feedback="tracks"."""
    given, results = _estimates_with_tracks_feedback(monkeypatch, 8)
    passed = given[1:]                                     # given[0]: the first frame's uniform set
    assert len(passed) == len(results) - 1
    confirmed = [i for i, r in enumerate(results[:-1]) if len(r.track_ids)]
    assert confirmed, "no track confirmed in 8 frames"
    for i in confirmed:
        centres = results[i].estimates
        # predictions of the confirmed tracks, not the polygon centres
        assert not (passed[i].shape == centres.shape and np.allclose(passed[i], centres))


def test_feedback_tracks_tasks_from_a_tracker_of_the_people_s_size_fed_the_hull_centres(monkeypatch):
    """Each frame's tracks are those of tracker_params' tracker stepped with the frame's polygon
    centres, and the tasker gets its next-frame predictions of the confirmed tracks (the
    centres while there is none), not the positions just seen."""
    from tasking.tracker import Tracker
    from testbed.loop import tracker_params

    given, results = _estimates_with_tracks_feedback(monkeypatch, 8)
    tracker = Tracker(tracker_params(load_scene("lab")))
    moved = 0
    for r, passed in zip(results[:-1], given[1:], strict=True):
        ids, xy = tracker.step(r.estimates)
        np.testing.assert_array_equal(r.track_ids, ids)
        np.testing.assert_allclose(r.track_xy, xy, rtol=0, atol=1e-12)
        predicted = tracker.estimates()
        np.testing.assert_allclose(passed, predicted if len(predicted) else r.estimates, rtol=0, atol=1e-12)
        moved += len(predicted) > 0 and not (predicted.shape == xy.shape and np.allclose(predicted, xy))
    assert moved


def test_more_people_than_labels_are_refused_before_the_walk(capsys, tmp_path, monkeypatch):
    """100000 people of 1 mm fit the floor, and `run` spent minutes dropping them before the
    renderer refused more than 254 (uint8 labels)."""
    import testbed.episode

    def walk(*args, **kwargs):
        raise AssertionError("walked before the people count was checked")

    monkeypatch.setattr(testbed.episode, "walk", walk)
    text = load_scene_text().replace("radius: 0.25 ", "radius: 0.01 ").replace("count: 3", "count: 300")
    (tmp_path / "crowd.yaml").write_text(text)
    assert main(["run", str(tmp_path / "crowd.yaml"), "--frames", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "people.count of" in err[0] and "expected at most 254 people (uint8 labels), got 300" in err[0]
    assert main(["run", "lab", "--people", "300", "--frames", "1"]) == 2      # the lab's 0.25 m: by area first
    assert "do not fit in the room" in capsys.readouterr().err


def load_scene_text():
    from scene import scene_path

    return scene_path("lab").read_text()


@pytest.mark.parametrize("command", [["run", "lab"], ["study", "lab", "--workers", "0", "--frames", "2"]])
def test_a_column_threshold_no_column_reaches_is_refused_before_the_walk(command, capsys, tmp_path, monkeypatch):
    """Every scanline would be empty: run printed a hull of the whole room, frame after frame."""
    import testbed.episode

    def walk(*args, **kwargs):
        raise AssertionError("walked before the parameters were checked")

    monkeypatch.setattr(testbed.episode, "walk", walk)
    (tmp_path / "p.yaml").write_text("column_threshold: 100000\n")
    assert main([*command, "--params", str(tmp_path / "p.yaml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--params: column_threshold 100000 is not below the 552 pixels of a rectified column" in err[0]


@pytest.mark.render
def test_demo_stopped_after_its_video_keeps_the_earlier_demo_whole(tmp_path, monkeypatch):
    """Ctrl-C while the demo drew its top view (after the video was finished) left a new
    run.mp4 beside the summary.json and topview.png of the earlier demo (another seed)."""
    from testbed import topview

    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--frames", "2", "--seed", "1"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    real, calls = topview.TopView.draw, []

    def interrupted(self, *a, **k):            # the video's two frames drawn, then Ctrl-C
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(self, *a, **k)
    monkeypatch.setattr(topview.TopView, "draw", interrupted)
    assert main(["demo", "--out", str(out), "--frames", "2", "--seed", "2"]) == 130
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before     # no new video, no staged file


def test_the_summary_says_which_counts_are_track_frames_and_which_person_frames():
    """The summary said '(track-frames, ...)' after false positives, misses and id
    switches alike: misses are person-frames."""
    from testbed.commands.run import format_summary

    summary = {"scene": "lab", "people": 3, "frames": 2, "tasker": "incremental", "k": 6, "m": 1,
               "update_every": 1, "hull_area": 1.0, "residual": 0.5, "bits_per_frame": 200.0,
               "camera_switches": 2,
               "tracking": {"mse": None, "mota": 0.0, "motp": None, "idf1": 0.0, "switches": 0, "matches": 0,
                            "false_positives": 4, "misses": 6, "max_distance": 0.75}}
    text = format_summary(summary)
    assert "false positives 4 track-frames" in text
    assert "misses 6 person-frames" in text
    assert "matched within 0.75 m" in text


def test_demo_empty_out_is_refused_not_the_current_folder(tmp_path, capsys, monkeypatch):
    """--out '' wrote run.mp4, summary.json and topview.png into the current folder."""
    monkeypatch.chdir(tmp_path)
    assert main(["demo", "--out", "", "--frames", "2"]) == 2
    assert capsys.readouterr().err.strip() == "camtask demo: error: --out: expected a folder name, got ''"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", ["run.mp4", "topview.png", "summary.json"])
def test_demo_refuses_a_folder_in_the_place_of_one_of_its_files_before_any_work(tmp_path, capsys, name):
    """A folder named run.mp4 or topview.png in --out failed the demo at its very end,
    after summary.json (and topview.png) had been replaced: not the three files together."""
    (tmp_path / name).mkdir()
    assert main(["demo", "--out", str(tmp_path), "--frames", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"camtask demo: error: --out: {tmp_path / name} is a folder; expected a file name"
    assert [p.name for p in tmp_path.iterdir()] == [name]


OFF_CENTRE = """\
room: {shape: rectangle, width: 5.0, depth: 4.0, height: 3.0}
cameras:
  intrinsics: {resolution: [320, 240], hfov_deg: 60, principal: [40.0, 120.0], distortion: [-0.15, 0.02, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.1, 0.1, 2.5], yaw_deg: 60, pitch_deg: 20}
    - {number: 2, position: [4.9, 3.9, 2.5], yaw_deg: -120, pitch_deg: 20}
    - {number: 3, position: [4.9, 0.1, 2.5], yaw_deg: 150, pitch_deg: 20}
people: {count: 2, radius: 0.25}
"""


def test_the_tasker_models_each_camera_by_the_view_of_its_scanline(monkeypatch):
    """Tasking predicts what a camera sees from its floor-plane view: that of its
    scanline's columns. The optical axis and the pinhole's field of view (53.6 degrees) put
    the view of a camera whose principal point is 40 px from its image's left edge 20.4
    degrees off, and 3.3 degrees narrower than its barrel lens's."""
    from pipeline.rectify import Rectifier
    from scene import Scene

    scene = Scene.from_text(OFF_CENTRE, "off_centre.yaml")
    truth = walk(scene, 3, np.random.default_rng(2))
    bearings = Rectifier.build(scene.cameras).bearings
    source = PrecomputedSource(_disc_scanlines(scene, truth, bearings), bearings)
    given = []
    spy_on_tasker(monkeypatch, lambda a: given.append((np.array(a[3]), np.array(a[4]))))
    list(run_loop(scene, LoopConfig("greedy", 1), truth, source))
    yaw, fov = given[-1]
    step = np.abs(np.diff(bearings, axis=1)).max()          # one column
    for i, b in enumerate(bearings):
        off = np.angle(np.exp(1j * (b - yaw[i])))            # each column's bearing from the view's centre
        assert np.all(np.abs(off) <= fov[i] / 2)             # the view holds every column
        assert off.max() > fov[i] / 2 - step and off.min() < -fov[i] / 2 + step   # and no more


@pytest.mark.parametrize("argv, message", [
    (["--tasker", "greedy", "--m", "3"],
     "--m: the cameras incremental greedy swaps per update; --tasker greedy swaps none (got --m 3)"),
    (["--tasker", "uniform", "--k", "6", "--m", "7"],
     "--m: the cameras incremental greedy swaps per update; --tasker uniform swaps none (got --m 7)"),
    (["--tasker", "uniform", "--update-every", "5"],
     "--update-every: the re-tasking period of every tasker but uniform; --tasker uniform never re-tasks"),
    (["--tasker", "uniform", "--update-every", "0"], "--update-every: expected an integer >= 1, got 0"),
])
def test_run_refuses_a_loop_option_its_tasker_does_not_use(capsys, monkeypatch, argv, message):
    """--m with greedy and --update-every with uniform were silently unused, yet the summary
    (and --json) recorded them as the run's swaps and period; the studies refuse them."""
    import testbed.episode

    monkeypatch.setattr(testbed.episode, "walk", lambda *a, **kw: pytest.fail("the walk was drawn"))
    assert main(["run", "lab", "--frames", "1", *argv]) == 2
    assert capsys.readouterr().err.strip() == f"camtask run: error: {message}"


@pytest.mark.render
def test_run_records_null_for_the_loop_options_its_tasker_does_not_use(capsys):
    for tasker, m, update_every in (("uniform", None, None), ("greedy", None, 1), ("incremental", 1, 1)):
        assert main(["run", "lab", "--tasker", tasker, "--k", "1", "--frames", "1", "--json"]) == 0
        summary = json.loads(capsys.readouterr().out)["summary"]
        assert (summary["m"], summary["update_every"]) == (m, update_every), tasker
    from testbed.commands.run import format_summary

    assert "tasker uniform k=1\n" in format_summary(summary | {"tasker": "uniform", "m": None, "update_every": None})


def test_run_refuses_feedback_with_uniform_which_never_re_tasks(capsys, monkeypatch):
    """--tasker uniform --feedback tracks ran uniform, which tasks from no estimates, and the
    summary recorded feedback: tracks."""
    import testbed.episode

    monkeypatch.setattr(testbed.episode, "walk", lambda *a, **kw: pytest.fail("the walk was drawn"))
    assert main(["run", "lab", "--frames", "1", "--tasker", "uniform", "--feedback", "tracks"]) == 2
    assert capsys.readouterr().err.strip() == (
        "camtask run: error: --feedback: the estimates the tasker re-tasks from; --tasker uniform never re-tasks")


@pytest.mark.render
def test_run_records_null_feedback_for_uniform(capsys):
    for tasker, feedback in (("uniform", None), ("greedy", "hull")):
        assert main(["run", "lab", "--tasker", tasker, "--k", "1", "--frames", "1", "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["summary"]["feedback"] == feedback, tasker


SMALL_IMAGES = """\
room: {shape: rectangle, width: 6.0, depth: 5.0, height: 3.0}
cameras:
  intrinsics: {resolution: [64, 40], hfov_deg: 60, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.1, 0.1, 2.5], yaw_deg: 40, pitch_deg: 20}
    - {number: 2, position: [5.9, 4.9, 2.5], yaw_deg: -140, pitch_deg: 20}
people: {count: 2, radius: 0.25}
"""


@pytest.mark.parametrize("command", [["run", "SCENE", "--k", "1"], ["render", "SCENE", "--out", "OUT"],
                                     ["study", "lab", "--scene", "SCENE", "--k", "1", "--workers", "0"]])
def test_a_default_column_threshold_too_high_says_it_is_the_default(command, capsys, tmp_path):
    """Cameras 40 pixels tall have 50-pixel rectified columns, below the default
    column_threshold 55: the error said '--params: ...' of a run given no --params."""
    scene = tmp_path / "small.yaml"
    scene.write_text(SMALL_IMAGES)
    names = {"SCENE": str(scene), "OUT": str(tmp_path / "out")}
    assert main([names.get(a, a) for a in command] + ["--frames", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith(
        "error: --params (not given: the default assets/pipeline/default.yaml): column_threshold 55 is not below "
        "the 50 pixels of a rectified column; every scanline would be empty"), err
    assert not (tmp_path / "out").exists()


def test_scanline_views_read_increasing_bearings_as_the_same_view():
    """A source whose bearings increase left to right (hand-made; the pipeline's decrease)
    got a negative field of view, refused later as "fov must be in (0, 2*pi)"."""
    from testbed.loop import scanline_views

    b = np.radians(np.linspace(20.0, -29.0, 50))
    yaw, fov = scanline_views([b, b[::-1]])
    assert yaw[1] == yaw[0] and fov[1] == fov[0] and np.degrees(fov[0]) == pytest.approx(50.0)


def test_run_video_with_no_ffmpeg_is_one_line_naming_it_before_any_frame(tmp_path, monkeypatch, capsys):
    """IMAGEIO_FFMPEG_EXE naming no program gave ``[Errno 2] No such file or directory: '...'``
    once the first frame had been rendered and tasked."""
    missing = tmp_path / "bin" / "ffmpeg"
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(missing))
    video = tmp_path / "run.mp4"
    assert main(["run", "lab", "--frames", "2", "--k", "1", "--json", "--video", str(video)]) == 1
    captured = capsys.readouterr()
    assert captured.err.strip() == (f"camtask run: error: ffmpeg: {str(missing)!r} (IMAGEIO_FFMPEG_EXE) is not an "
                                    "executable file; install imageio-ffmpeg's binaries or point "
                                    "IMAGEIO_FFMPEG_EXE at an ffmpeg")
    assert captured.out == "" and list(tmp_path.iterdir()) == []


def _fake_ffmpeg(tmp_path, monkeypatch, body):
    """IMAGEIO_FFMPEG_EXE pointed at a shell script standing in for ffmpeg (its last argument
    is the output file)."""
    exe = tmp_path / "bin" / "ffmpeg"
    exe.parent.mkdir()
    exe.write_text('#!/bin/sh\neval out=\\"\\${$#}\\"\n' + body + "\n")
    exe.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(exe))
    return tmp_path / "video"


def test_ffmpeg_dying_while_frames_are_written_is_one_line_and_leaves_no_file(tmp_path, monkeypatch):
    """ffmpeg that exits (after starting its file) takes no more frames: the writer names the
    video, not imageio-ffmpeg's whole command line, and removes what ffmpeg left."""
    from testbed.video import VideoWriter

    out = _fake_ffmpeg(tmp_path, monkeypatch, 'printf started > "$out"; exit 1')
    # 1.5 MB a frame: more than a pipe holds, so the write meets the closed pipe
    with pytest.raises(OSError) as info, VideoWriter(out / "run.mp4", fps=5) as writer:
        writer.write(np.zeros((720, 720, 3), np.uint8))
    assert str(info.value) == f"--video: ffmpeg stopped writing {out / 'run.mp4'} (OSError)"
    assert info.value.__cause__ is None and info.value.__suppress_context__
    assert list(out.iterdir()) == []                   # its folder was made; ffmpeg's file removed


@pytest.mark.parametrize("body", ['cat > /dev/null', 'cat > /dev/null; : > "$out"'],
                         ids=["no file", "empty file"])
def test_ffmpeg_writing_nothing_is_a_failure_and_leaves_no_file(tmp_path, monkeypatch, body):
    """imageio-ffmpeg does not report ffmpeg's exit status: an ffmpeg that took every frame
    and wrote nothing (or an empty file) is an error, not an empty run.mp4."""
    from testbed.video import VideoWriter

    out = _fake_ffmpeg(tmp_path, monkeypatch, body)
    writer = VideoWriter(out / "run.mp4", fps=5)
    writer.write(np.zeros((32, 32, 3), np.uint8))
    with pytest.raises(OSError, match=f"^--video: ffmpeg wrote nothing to {out / 'run.mp4'}$"):
        writer.close()
    assert list(out.iterdir()) == []


def test_a_video_given_no_frame_is_not_written_nor_started(tmp_path, monkeypatch):
    """No frame, no ffmpeg and no file, whether the run ended cleanly or not."""
    from testbed.video import VideoWriter

    out = _fake_ffmpeg(tmp_path, monkeypatch, 'printf x > "$out"; touch "$0.ran"')
    with VideoWriter(out / "a.mp4", fps=5):
        pass
    with pytest.raises(KeyboardInterrupt), VideoWriter(out / "b.mp4", fps=5):
        raise KeyboardInterrupt
    assert not out.exists() and not (tmp_path / "bin" / "ffmpeg.ran").exists()


def test_a_video_closed_cleanly_appears_under_its_name_whole(tmp_path):
    """Frames of another size than the first are cropped or padded (white) to it; the file
    appears under its name only, holding every frame."""
    import imageio_ffmpeg

    from testbed.video import VideoWriter

    path = tmp_path / "run.mp4"
    with VideoWriter(path, fps=5) as writer:
        writer.write(np.zeros((33, 47, 3), np.uint8))      # odd sizes: 46 x 32 pixels
        writer.write(np.zeros((64, 64, 3), np.uint8))      # cropped
        writer.write(np.zeros((10, 10, 3), np.uint8))      # padded with white
    assert [p.name for p in tmp_path.iterdir()] == ["run.mp4"]
    reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    meta = next(reader)
    frames = [np.frombuffer(f, np.uint8).reshape(32, 46, 3) for f in reader]
    assert tuple(meta["size"]) == (46, 32) and len(frames) == 3
    assert frames[0].max() < 20 and frames[1].max() < 20             # black, lossy
    assert frames[2][:8, :8].max() < 20 and frames[2][16:, 16:].min() > 235


def _runs_bits(scanline):
    """Run-length bits of one scanline by hand: runs alternate from a run of False (empty when
    it starts True), each coded in ceil(log2(W + 1)) bits."""
    from itertools import groupby

    runs = len(list(groupby(scanline.tolist()))) + bool(scanline[0])
    return runs * int(np.ceil(np.log2(len(scanline) + 1)))


def test_each_frame_records_what_was_sent_switched_and_true(lab_episode):
    """Frames are counted from 0; each records its own true positions, the scanlines its tasked
    cameras sent, their run-length bits, the cameras switched on and off since the frame
    before (none before the first) and the residual against 3 people's discs."""
    scene, truth, source = lab_episode
    seen = []
    results = []
    for r in run_loop(scene, LoopConfig("greedy", 6, update_every=2), truth, source, on_frame=seen.append):
        assert seen == results + [r]                        # on_frame has it before it is yielded
        results.append(r)
    assert [r.index for r in results] == list(range(len(truth)))
    occupied = 3 * np.pi * 0.25**2
    for r in results:
        np.testing.assert_array_equal(r.truth, truth[r.index])
        np.testing.assert_array_equal(r.scanlines, source.all[r.index][[n - 1 for n in r.tasked]])
        assert r.bits_sent == sum(_runs_bits(s) for s in r.scanlines)
        assert r.residual == pytest.approx(r.hull_area / occupied - 1, rel=1e-12)
    assert results[0].switched_on == () and results[0].switched_off == ()
    for a, b in pairwise(results):
        assert b.switched_on == tuple(sorted(set(b.tasked) - set(a.tasked)))
        assert b.switched_off == tuple(sorted(set(a.tasked) - set(b.tasked)))
        if b.index % 2:                                      # re-tasked only before frames 2, 4, ...
            assert b.tasked == a.tasked
    assert any(r.switched_on for r in results)              # the hull steered greedy somewhere else


def test_the_summary_averages_the_frames_and_counts_every_switch(lab_episode):
    import dataclasses

    scene, truth, source = lab_episode
    results = list(run_loop(scene, LoopConfig("greedy", 6), truth, source))
    s = summarise(results, scene)
    n = len(truth)
    assert s["frames"] == n
    assert s["hull_area"] == pytest.approx(sum(r.hull_area for r in results) / n, rel=1e-12)
    assert s["residual"] == pytest.approx(sum(r.residual for r in results) / n, rel=1e-12)
    assert s["bits_per_frame"] == pytest.approx(sum(r.bits_sent for r in results) / n, rel=1e-12)
    switches = sum(len(set(b.tasked) ^ set(a.tasked)) for a, b in pairwise(results))
    assert switches > 0 and s["camera_switches"] == switches
    assert s["tracking"]["max_distance"] == pytest.approx(0.75)          # 3 radii of the lab's people
    assert s["tracking"]["matches"] + s["tracking"]["misses"] == 3 * n
    smaller = dataclasses.replace(scene, people=dataclasses.replace(scene.people, radius=0.2))
    assert summarise(results, smaller)["tracking"]["max_distance"] == pytest.approx(0.6)


def test_hull_feedback_tasks_from_the_centres_of_the_frame_just_seen(lab_episode, monkeypatch):
    scene, truth, source = lab_episode
    given, radii = [], []
    spy_on_tasker(monkeypatch, lambda a: given.append(np.array(a[5])) or radii.append(a[6]))
    results = list(run_loop(scene, LoopConfig("greedy", 8), truth, source))
    assert len(given) == len(results) and len(given[0]) == 0              # the first frame: uniform, no estimates
    for r, estimates in zip(results, given[1:]):
        assert len(r.estimates) and np.array_equal(estimates, r.estimates)
    assert radii == [scene.people.radius] * len(results)                 # estimates: discs of the people's radius


def test_a_summary_of_no_frames_or_nobody_has_no_tracking():
    lab = load_scene("lab")
    s = summarise([], lab)
    assert s["frames"] == 0 and s["camera_switches"] == 0 and s["bits_per_frame"] == 0.0 and s["tracking"] == {}
    assert np.isnan(s["hull_area"]) and np.isnan(s["residual"])
    empty = np.zeros((3, 0, 2))
    bearings = np.tile(np.linspace(0.4, -0.4, 640), (16, 1))
    results = list(run_loop(lab, LoopConfig("uniform", 6), empty, PrecomputedSource(np.zeros((3, 16, 640)), bearings)))
    s = summarise(results, lab)
    assert s["frames"] == 3 and s["tracking"] == {}                     # no max_distance without metrics
    # nobody to occupy: the residual is against one person's disc
    assert results[0].residual == pytest.approx(results[0].hull_area / (np.pi * 0.25**2) - 1, rel=1e-12)


def test_uniform_never_re_tasks(lab_episode, monkeypatch):
    scene, truth, source = lab_episode
    calls = []
    spy_on_tasker(monkeypatch, lambda a: calls.append(a[0]))
    results = list(run_loop(scene, LoopConfig("uniform", 6), truth, source))
    assert calls == ["uniform"] and len({r.tasked for r in results}) == 1


def test_incremental_swaps_up_to_m_cameras(lab_episode):
    scene, truth, source = lab_episode
    results = list(run_loop(scene, LoopConfig("incremental", 6, m=2), truth, source))
    changed = [len(set(b.tasked) - set(a.tasked)) for a, b in pairwise(results)]
    assert max(changed) == 2


def test_feedback_tracks_falls_back_to_the_hull_before_a_track_is_confirmed(monkeypatch):
    given, results = _estimates_with_tracks_feedback(monkeypatch, 4)
    unconfirmed = [i for i, r in enumerate(results[:-1]) if not len(r.track_ids)]
    assert unconfirmed
    for i in unconfirmed:
        assert len(results[i].estimates) and np.array_equal(given[1 + i], results[i].estimates)


def test_loop_config_bounds_and_option_names():
    assert LoopConfig("greedy", 16).check(16).k == 16
    assert LoopConfig("incremental", 3, m=3).check(16).m == 3
    assert LoopConfig("greedy", 1, update_every=1).check(1).update_every == 1
    for config, message in [
        (LoopConfig("greedy", 0), "k: expected an integer >= 1, got 0"),
        (LoopConfig("incremental", 3, m=0), "m: expected an integer >= 1, got 0"),
        (LoopConfig("greedy", 3, update_every=0), "update_every: expected an integer >= 1, got 0"),
        (LoopConfig("greedy", 3, feedback="truth"), "feedback: unknown value 'truth'; expected one of hull, tracks"),
    ]:
        with pytest.raises(ValueError) as info:
            config.check(16)
        assert str(info.value).startswith(message), str(info.value)
        with pytest.raises(ValueError) as info:
            config.check(16, as_options=True)
        assert str(info.value).startswith("--" + message.replace("_", "-")), str(info.value)


def test_a_frame_in_json_rounds_positions_to_a_tenth_of_a_millimetre():
    from testbed.loop import FrameResult

    r = FrameResult(index=4, tasked=(3, 1), scanlines=np.zeros((2, 8), bool), polygons=[], hull_area=1.5,
                    residual=0.25, bits_sent=40, switched_on=(3,), switched_off=(2,),
                    estimates=np.array([[1.23456, 2.00004]]), truth=np.array([[0.00006, 5.5]]),
                    track_ids=np.array([7]), track_xy=np.array([[3.14159, 2.71828]]))
    assert r.to_json() == {"frame": 4, "tasked": [3, 1], "hull_area": 1.5, "residual": 0.25, "bits_sent": 40,
                           "switched_on": [3], "switched_off": [2], "estimates": [[1.2346, 2.0]],
                           "truth": [[0.0001, 5.5]], "tracks": [{"id": 7, "xy": [3.1416, 2.7183]}]}


def test_a_precomputed_source_serves_the_cameras_asked_for_by_number():
    scans = np.arange(2 * 4 * 3).reshape(2, 4, 3) % 3 == 0
    bearings = np.tile([0.1, 0.0, -0.1], (4, 1))
    source = PrecomputedSource(scans, bearings)
    assert source.near == {1: 0.0, 2: 0.0, 3: 0.0, 4: 0.0} and source.far == dict.fromkeys((1, 2, 3, 4), np.inf)
    source.close()                                          # nothing to release: it still serves
    got, rgb = source.scanlines(1, None, (4, 2))
    np.testing.assert_array_equal(got, scans[1, [3, 1]])
    assert rgb is None and list(source.bearings) == [1, 2, 3, 4]
    placed = PrecomputedSource(scans, bearings, near=[0.5, 0.6, 0.7, 0.8], far=[9, 8, 7, 6])
    assert placed.near == {1: 0.5, 2: 0.6, 3: 0.7, 4: 0.8} and placed.far == {1: 9.0, 2: 8.0, 3: 7.0, 4: 6.0}


def test_a_live_source_renders_only_the_tasked_cameras_and_resets_a_node_switched_on(monkeypatch):
    """Each tasked camera's frame goes to its own node, built on its own camera's background
    and sight range for a person of the scene's height and width; a node starts a fresh
    temporal filter only when it is switched on, not while it stays on."""
    import render
    from testbed import loop

    lab = load_scene("lab")
    rendered, reset, processed, built, asked = [], [], [], [], []

    class Renderer:
        def __init__(self, scene):
            self.n = len(scene.cameras)

        def background(self):
            return type("F", (), {"rgb": np.stack([np.full((2, 4, 3), 100 + c, np.uint8) for c in range(1, self.n + 1)])})

        def render(self, positions, cameras, rng):
            rendered.append(tuple(cameras))
            return type("F", (), {"rgb": np.stack([np.full((2, 4, 3), c, np.uint8) for c in cameras])})

        def close(self):
            rendered.append("closed")

    class Pipeline:
        def __init__(self, cameras, params, background):
            self.number = cameras[0].number
            built.append((self.number, background.shape, int(background[0, 0, 0, 0])))
            self.bearings = np.array([[0.2, 0.1, 0.0, -0.1]])

        def sight_range(self, height, object_width):
            asked.append((height, object_width))
            return np.array([0.1 * self.number]), np.array([10.0 + self.number])

        def reset(self):
            reset.append(self.number)

        def process(self, frames):
            processed.append((self.number, int(frames[0, 0, 0, 0])))
            return np.array([[self.number % 2 == 0] * 4])

    monkeypatch.setattr(render, "Renderer", Renderer)
    monkeypatch.setattr(loop, "Pipeline", Pipeline)
    source = loop.LiveSource(lab, None, np.random.default_rng(0))
    assert source.near[5] == pytest.approx(0.5) and source.far[5] == pytest.approx(15.0)
    assert built == [(c, (1, 2, 4, 3), 100 + c) for c in range(1, 17)]
    assert asked == [(1.75, 0.5)] * 16
    first, rgb = source.scanlines(0, np.zeros((3, 2)), (3, 4))
    second, _ = source.scanlines(1, np.zeros((3, 2)), (4, 6))
    source.scanlines(2, np.zeros((3, 2)), (3, 6))
    source.close()
    assert rgb is None and rendered == [(3, 4), (4, 6), (3, 6), "closed"]
    assert reset == [3, 4, 6, 3]                     # 4 and then 6 stayed on; 3, off in frame 1, is on again
    assert processed == [(3, 3), (4, 4), (4, 4), (6, 6), (3, 3), (6, 6)]     # each frame to its own node
    np.testing.assert_array_equal(first, [[False] * 4, [True] * 4])
    np.testing.assert_array_equal(second, [[True] * 4, [True] * 4])
    assert source.seconds["render"] > 0 and source.seconds["pipeline"] > 0
    kept = loop.LiveSource(lab, None, np.random.default_rng(0), keep_frames=True)
    assert kept.scanlines(0, np.zeros((3, 2)), (7,))[1][0, 0, 0, 0] == 7


def test_scanline_views_agree_with_scanline_intervals_on_every_lab_camera(lab_episode):
    """Cameras 6 and 8 of the lab look across +-180 degrees: their bearings wrap in the
    row, and the view must still be the one scanline_intervals gives."""
    from tasking.cones import scanline_intervals
    from testbed.loop import scanline_views

    _, _, source = lab_episode
    bearings = np.array(list(source.bearings.values()))
    assert (np.abs(np.diff(bearings, axis=1)) > np.pi).any(axis=1).sum() == 2
    yaw, fov = scanline_views(bearings)
    expected_yaw, expected_fov, _, _ = scanline_intervals(bearings, np.zeros(bearings.shape, bool))
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - expected_yaw))), 0, atol=1e-12)
    np.testing.assert_allclose(fov, expected_fov, rtol=1e-12)
    np.testing.assert_allclose(fov, fov[0], rtol=1e-9)          # one lens for all: one width


def test_the_loop_tracks_with_the_tracking_study_s_settings_at_the_scene_s_frame_rate():
    """The loop's tracker is the tracking study's for people of the scene's radius and speed,
    stepping at the scene's frame rate."""
    import dataclasses

    from testbed.loop import tracker_params
    from testbed.studies import tracking

    lab = load_scene("lab")
    assert tracker_params(lab) == tracking.tracker_params(0.25, 1.0)
    other = dataclasses.replace(lab, frame_rate=15.0, people=dataclasses.replace(lab.people, radius=0.2, speed=1.5))
    assert tracker_params(other) == dataclasses.replace(tracking.tracker_params(0.2, 1.5), dt=1 / 15)


def test_hull_polygons_smaller_than_one_person_are_dropped(lab_episode, monkeypatch):
    """A frame keeps exactly the hull's polygons of at least one person's disc: some dropped
    ones had more than half of it, some kept ones less than 1.2 times it."""
    from tasking import prune_small
    from testbed import loop

    scene, truth, source = lab_episode
    real, hulls = loop.visual_hull_of_scanlines, []
    monkeypatch.setattr(loop, "visual_hull_of_scanlines", lambda *a: hulls.append(real(*a)) or hulls[-1])
    results = list(run_loop(scene, LoopConfig("uniform", 6), truth, source))
    disc = np.pi * 0.25**2
    dropped = []
    for r, hull in zip(results, hulls, strict=True):
        parts = sorted(p.area for p in prune_small(hull, 0))
        assert sorted(p.area for p in r.polygons) == [a for a in parts if a >= disc]
        dropped += [a for a in parts if a < disc]
    assert any(disc / 2 < a < disc for a in dropped)
    assert any(a < 1.2 * disc for r in results for a in (p.area for p in r.polygons))


def test_cameras_carve_only_within_their_sight_radius(lab_episode):
    """With sight radii the hull only grows (a camera carves nothing beyond it); near_field=False
    carves to the walls."""
    scene, truth, source = lab_episode
    bearings = np.array(list(source.bearings.values()))
    short = PrecomputedSource(source.all, bearings, far=np.full(16, 2.0))
    plain = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", 6), truth, source)]
    carved_near = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", 6), truth, short)]
    switched_off = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", 6, near_field=False), truth, short)]
    assert switched_off == plain
    assert all(a >= b - 1e-9 for a, b in zip(carved_near, plain)) and sum(carved_near) > sum(plain)


def _everything_seen(frames, people=1):
    """A lab source whose cameras see something in every column: the hull is the whole room."""
    bearings = np.tile(np.linspace(0.4, -0.4, 64), (16, 1))
    return np.full((frames, people, 2), 3.0), PrecomputedSource(np.ones((frames, 16, 64), bool), bearings)


def test_uniform_and_clustering_without_directions_task_the_scene_s_own_sets():
    """The lab's paper sets where it has one for k (6, 8, 10), uniform_select's otherwise;
    clustering with one estimate (no pair of them to take a direction from) re-tasks the same."""
    from tasking import uniform_select

    lab = load_scene("lab")
    truth, source = _everything_seen(3)
    spread = {k: tuple(int(i) + 1 for i in uniform_select(16, k)) for k in (4, 6, 10)}
    assert lab.uniform_sets[6] != spread[6] and lab.uniform_sets[10] != spread[10]
    for tasker, k, expected in [("uniform", 6, lab.uniform_sets[6]), ("clustering", 10, lab.uniform_sets[10]),
                                ("uniform", 4, spread[4])]:
        results = list(run_loop(lab, LoopConfig(tasker, k), truth, source))
        assert [len(r.estimates) for r in results] == [1, 1, 1]
        assert [r.tasked for r in results] == [tuple(expected)] * 3, tasker


def test_the_loop_adds_its_time_per_stage_to_the_seconds_given():
    lab = load_scene("lab")
    truth, source = _everything_seen(3)
    seconds = {"hull": 100.0, "other": 1.0}
    list(run_loop(lab, LoopConfig("greedy", 4), truth, source, seconds=seconds))
    assert seconds["hull"] > 100.0 and seconds["other"] == 1.0
    assert seconds["tracker"] > 0 and seconds["tasker"] > 0
    before = dict(seconds)
    list(run_loop(lab, LoopConfig("greedy", 4), truth, source, seconds=seconds))
    assert all(seconds[s] > before[s] for s in ("hull", "tracker", "tasker"))


def test_each_frame_keeps_the_rgb_frames_its_source_gave():
    class Framed(PrecomputedSource):
        def scanlines(self, index, positions_xy, numbers):
            return super().scanlines(index, positions_xy, numbers)[0], np.full((len(numbers), 2, 2, 3), index)

    lab = load_scene("lab")
    truth, source = _everything_seen(3)
    framed = Framed(source.all, np.array(list(source.bearings.values())))
    results = list(run_loop(lab, LoopConfig("greedy", 4), truth, framed))
    assert [r.rgb.shape for r in results] == [(4, 2, 2, 3)] * 3
    assert [int(r.rgb.max()) for r in results] == [0, 1, 2]


def test_a_summary_before_any_track_is_confirmed_has_null_mean_errors():
    """Two frames confirm no track (three matches do): nothing matched, so mse and motp
    are None (JSON has no NaN), and every person-frame is a miss."""
    lab = load_scene("lab")
    truth, source = _everything_seen(2)
    results = list(run_loop(lab, LoopConfig("greedy", 4), truth, source))
    tracking = summarise(results, lab)["tracking"]
    assert tracking["mse"] is None and tracking["motp"] is None
    assert tracking["matches"] == 0 and tracking["misses"] == 2
    assert all(v is not None for k, v in tracking.items() if k not in ("mse", "motp"))
