"""`camtask study ...` end to end on tiny runs: tables, JSON schema, plots, errors, Dask."""

import importlib
import json

import pytest

from testbed import cli


@pytest.fixture(autouse=True)
def only_study_command(monkeypatch):
    # Other command modules are developed in parallel; test this one on its own.
    monkeypatch.setattr(cli, "COMMANDS", ("testbed.commands.study",))


def run_json(capsys, *argv):
    code = cli.main(["study", *argv, "--json", "--no-progress"])
    out = capsys.readouterr().out
    assert code == 0
    return json.loads(out)


CAMERAS = ("cameras", "--objects", "1,3", "--cameras", "2,4,8,9", "--trials", "3", "--seed", "5")
STATIC = ("static", "--objects", "3", "--k", "2,3", "--candidates", "8", "--trials", "2",
          "--taskers", "uniform,clustering,optimal,greedy")
MOVING = ("moving", "--objects", "3", "--k", "2,3", "--candidates", "8", "--trials", "2",
          "--steps", "4", "--update-every", "1,2")


def test_cameras_json_schema_and_plot(capsys, tmp_path):
    png = tmp_path / "cameras.png"
    doc = run_json(capsys, *CAMERAS, "--workers", "0", "--plot", str(png))
    assert png.stat().st_size > 1000
    assert doc["meta"]["seed"] == 5 and doc["meta"]["trials"] == 3
    assert doc["meta"]["arguments"]["objects"] == [1, 3]
    # the package the taskers come from, by its import name
    from testbed.studies import core
    assert importlib.import_module(doc["meta"]["tasking_backend"]).TASKERS is core.TASKERS
    recs = doc["records"]
    assert len(recs) == 2 * (4 + 1)
    for r in recs:
        assert {"objects", "cameras", "residual", "residual_raw", "trials", "limit"} <= set(r)
        assert r["trials"] == 3
        assert r["residual_raw"] >= r["residual"] - 1e-9
    lim1 = next(r for r in recs if r["objects"] == 1 and r["limit"])
    assert lim1["cameras"] is None and lim1["residual"] == 0.0
    # More cameras, tighter hull (same drops for every N).
    one = [r["residual"] for r in recs if r["objects"] == 1 and not r["limit"]]
    assert one == sorted(one, reverse=True)
    assert [f["objects"] for f in doc["fits"]] == [1, 3]


def test_cameras_table(capsys):
    assert cli.main(["study", *CAMERAS, "--workers", "0", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "slope" in out and "inf" in out


def test_cameras_limit_cameras_option(capsys):
    doc = run_json(capsys, "cameras", "--objects", "2", "--cameras", "4", "--trials", "1",
                   "--limit-cameras", "64", "--workers", "0")
    lim = [r for r in doc["records"] if r["limit"]]
    assert lim[0]["cameras"] == 64 and lim[0]["method"] == "cameras"


def test_static_and_moving_json_and_plots(capsys, tmp_path):
    doc = run_json(capsys, *STATIC, "--workers", "0", "--plot", str(tmp_path / "s.png"))
    assert {(r["tasker"], r["k"]) for r in doc["records"]} == {
        (t, k) for t in ("uniform", "clustering", "optimal", "greedy") for k in (2, 3)}
    by = {(r["tasker"], r["k"]): r["residual"] for r in doc["records"]}
    for k in (2, 3):  # optimal minimises the raw hull (docs/tasking.md); on these trials it is best pruned too
        assert by[("optimal", k)] <= min(by[(t, k)] for t in ("uniform", "greedy")) + 1e-9
    doc = run_json(capsys, *MOVING, "--workers", "0", "--plot", str(tmp_path / "m.png"))
    keys = {(r["tasker"], r["k"], r["update_every"]) for r in doc["records"]}
    assert ("incremental", 3, 2) in keys and ("greedy", 2, 1) in keys
    assert all(r["residual"] > 0 for r in doc["records"])
    assert (tmp_path / "s.png").exists() and (tmp_path / "m.png").exists()


@pytest.mark.slow
def test_same_numbers_with_two_workers(capsys):
    a = run_json(capsys, *CAMERAS, "--workers", "0")
    b = run_json(capsys, *CAMERAS, "--workers", "2")
    assert a["records"] == b["records"]
    assert b["meta"]["workers"] == 2
    c = run_json(capsys, *MOVING, "--workers", "0")
    d = run_json(capsys, *MOVING, "--workers", "2")
    assert c["records"] == d["records"]
    # clustering's k-means: the same twin in this process (OpenMP threads) as in a worker (one)
    clustering = ("static", "--k", "3", "--taskers", "clustering", "--trials", "20")   # 2 tasks of 10 trials
    in_workers = run_json(capsys, *clustering, "--workers", "2")
    assert in_workers["meta"]["workers"] == 2
    assert run_json(capsys, *clustering, "--workers", "0")["records"] == in_workers["records"]


def test_seed_changes_numbers(capsys):
    a = run_json(capsys, *CAMERAS, "--workers", "0")
    b = run_json(capsys, *CAMERAS[:-1], "6", "--workers", "0")
    assert a["records"] != b["records"]


@pytest.mark.parametrize("argv, message", [
    (("cameras", "--objects", "1,x"), "--objects: expected integers"),
    (("cameras", "--cameras", "1,2"), "--cameras: expected integers >= 2"),
    (("cameras", "--limit-cameras", "many"), "--limit-cameras"),
    (("cameras", "--trials", "0"), "--trials: expected an integer >= 1"),
    (("static", "--k", "2,17"), "--k: 17 cameras exceed the 16 candidates"),
    (("static", "--taskers", "uniform,best"), "--taskers: unknown value 'best'; expected one of"),
    (("moving", "--taskers", "optimal"), "--taskers: unknown value 'optimal'"),
    (("moving", "--update-every", "0"), "--update-every: expected integers >= 1"),
    (("static", "--plot", "fig.jpg"), "--plot: expected a .png"),
    (("static", "--seed", "-1"), "--seed: expected an integer in 0..4294967295, got -1"),
    (("static", "--plot", ".png"), "--plot: expected a .png file name, got '.png'"),
    (("static", "--k", "1-3000000"), "--k: a range of at most 100000 values, got '1-3000000'"),
    (("cameras", "--cameras", "2,4,8", "--limit-cameras", "8"),
     "--limit-cameras: expected more cameras than the largest --cameras (8), got 8"),
    # these failed after minutes of trials, naming an internal parameter
    (("static", "--candidates", "22"), ("--taskers: optimal would compare C(22, 8) = 319770 subsets of cameras per "
                                       "trial, more than --max-subsets 200000")),
    (("static", "--plot", ""), "--plot: expected a file name, got ''"),
])
def test_bad_input_is_one_line(capsys, argv, message):
    assert cli.main(["study", *argv, "--workers", "0", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camtask study: error: ") and message in err
    assert "\n" not in err


def test_m_larger_than_a_greedy_k_is_not_checked_against_it(capsys):
    """--m larger than a greedy k stopped the run inside a worker ("m must be <= 2"): it bounds only
    incremental's k. (Only tracking gives each tasker its own k: in moving and lab every tasker
    runs every --k, so --m is at most the smallest k of all.)"""
    doc = run_json(capsys, "tracking", "--pairs", "greedy:3,incremental:6", "--m", "5", "--steps", "5",
                   "--trials", "1", "--workers", "0")
    assert doc["meta"]["arguments"]["m"] == 5
    assert {(r["tasker"], r["k"]) for r in doc["records"]} == {("greedy", 3), ("incremental", 6)}


def test_unreachable_scheduler_fails_fast(capsys):
    code = cli.main(["study", "cameras", "--objects", "1", "--cameras", "2", "--trials", "1",
                     "--scheduler", "tcp://127.0.0.1:9", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.startswith("camtask study: error: scheduler: cannot reach a Dask scheduler")
    assert "\n" not in err


def test_a_plot_in_a_new_folder_is_made_whole_and_a_plot_under_a_file_refused_first(capsys, tmp_path):
    png = tmp_path / "figs" / "new" / "cameras.png"
    doc = run_json(capsys, *CAMERAS, "--workers", "0", "--plot", str(png))
    assert doc["records"] and png.stat().st_size > 1000
    assert [p.name for p in png.parent.iterdir()] == ["cameras.png"]        # no temporary file left
    (tmp_path / "file").write_text("x")
    assert cli.main(["study", *CAMERAS, "--workers", "0", "--plot", str(tmp_path / "file" / "c.png")]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.strip() == (
        f"camtask study: error: --plot: cannot write to {tmp_path / 'file'} (not a folder)")
    # a folder that cannot be made (a dangling link) is refused before the study too
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere" / "deeper")
    assert cli.main(["study", *CAMERAS, "--workers", "0", "--plot", str(tmp_path / "dangling" / "c.png")]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.startswith(
        f"camtask study: error: --plot: cannot make the folder {tmp_path / 'dangling'} (")


def test_clustering_draws_the_same_whatever_its_place_in_taskers(capsys):
    args = ("static", "--objects", "6", "--k", "2,4,6", "--trials", "4", "--workers", "0")
    alone = run_json(capsys, *args, "--taskers", "clustering")["records"]
    second = run_json(capsys, *args, "--taskers", "greedy,uniform,clustering")["records"]
    assert alone == [r for r in second if r["tasker"] == "clustering"]


def test_a_run_refused_on_another_argument_leaves_no_plot_folder(capsys, tmp_path):
    png = tmp_path / "new" / "deeper" / "c.png"
    assert cli.main(["study", "cameras", "--objects", "0", "--plot", str(png)]) == 2
    assert "--objects" in capsys.readouterr().err and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("argv, message", [
    # an OverflowError traceback from the tracker
    (("tracking", "--speed", "1e300"), "--speed: expected a finite number > 0 and at most 100, got 1e+300"),
    # "speed: expected finite numbers >= 0": the flag not named
    (("tracking", "--speed", "nan"), "--speed: expected a finite number > 0 and at most 100, got nan"),
    # ran, walking discs 1e300 m per frame
    (("moving", "--speed", "1e300"), "--speed: expected a finite number >= 0 and at most 100, got 1e+300"),
    (("moving", "--dt", "1e300"), "--dt: expected a finite number > 0 and at most 1000, got 1e+300"),
    # "radii: 1000 discs ... cannot fit" (10**9 filled the memory first)
    (("static", "--objects", "1000"), ("--objects: 1000 discs of radius 0.1 do not fit in the room of radius 1; "
                                       "expected at most 99")),
    (("cameras", "--objects", "1,200"), "--objects: 200 discs"),
    # ran (10**9 candidates: the machine killed the run)
    (("static", "--candidates", "20000", "--k", "2", "--taskers", "uniform"),
     "--candidates: expected at most 10000 cameras, got 20000"),
])
def test_extreme_numbers_are_one_line_naming_the_flag(capsys, argv, message):
    assert cli.main(["study", *argv, "--trials", "1", "--workers", "0", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camtask study: error: ") and message in err
    assert "\n" not in err
