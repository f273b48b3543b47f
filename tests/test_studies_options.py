"""`camtask study`: options several studies share, --fit-min, the worker count, --trials,
what the progress bar counts and the JSON's keys."""

import contextlib
import json
import re

import pytest

from testbed import cli, memory
from testbed.commands import study as study_command
from testbed.studies import cameras, lab, moving, static, tracking

STUDIES = ("cameras", "static", "moving", "lab", "tracking")
STUDY_MODULES = {"static": static, "moving": moving}


@pytest.fixture(autouse=True)
def only_study_command(monkeypatch):
    monkeypatch.setattr(cli, "COMMANDS", ("testbed.commands.study",))


def one_line_error(capsys, *argv):
    assert cli.main(["study", *argv, "--workers", "0", "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("camtask study: error: ") and "\n" not in err
    return err.removeprefix("camtask study: error: ")


def option_help(capsys, name, monkeypatch):
    """{option: its help text, joined onto one line} of ``camtask study NAME --help``."""
    monkeypatch.setenv("COLUMNS", "200")
    with pytest.raises(SystemExit):
        cli.main(["study", name, "--help"])
    out = capsys.readouterr().out
    return {m[0]: " ".join(m[1].split()) for m in re.findall(r"^  (--[\w-]+)(?: \S+)?\s+(.*)$", out, re.MULTILINE)}


def test_a_shared_option_has_one_help_in_every_study(capsys, monkeypatch):
    """--radius was 'object radius, metres' in three studies, 'disc radius, room units' in
    tracking; --m 'cameras swapped per update' there; --update-every 'incremental' where it
    re-tasks greedy too; --taskers did not say which taskers a study takes."""
    helps = {name: option_help(capsys, name, monkeypatch) for name in STUDIES}
    for option in ("--radius", "--m", "--objects", "--k", "--candidates", "--speed", "--steps"):
        texts = {re.sub(r"\(default [^)]*\)", "", h[option]) for name, h in helps.items()
                 if option in h and (name, option) != ("cameras", "--objects")}    # a list there
        assert len(texts) == 1, (option, texts)
    assert "metres" in helps["tracking"]["--radius"] and "m/s" in helps["tracking"]["--speed"]
    assert helps["tracking"]["--steps"].endswith("(default 150, 20 s)")
    assert "every tasker but uniform" in helps["tracking"]["--update-every"]
    assert "every tasker but uniform" in helps["lab"]["--update-every"]
    assert "incremental" in helps["moving"]["--update-every"]
    assert "lazy_greedy, incremental (default" in helps["moving"]["--taskers"]
    assert "optimal" not in helps["lab"]["--taskers"] and "incremental" not in helps["static"]["--taskers"]
    # the options of every study are in one group, unchanged
    for h in helps.values():
        assert {"--trials", "--seed", "--json", "--plot", "--no-progress", "--workers", "--scheduler"} <= set(h)


@pytest.mark.parametrize("name", ["cameras", "static", "moving", "tracking"])
def test_a_shared_option_has_one_error_in_every_study(capsys, name):
    assert one_line_error(capsys, name, "--radius", "0.7") == "--radius: expected a number in (0, 0.5), got 0.7"


@pytest.mark.parametrize("argv", [
    # ran: --m 0 was checked only with incremental
    ("moving", "--taskers", "uniform,greedy", "--m", "0", "--k", "2", "--steps", "2", "--trials", "1"),
    ("tracking", "--pairs", "uniform:4", "--m", "0"),
])
def test_m_is_at_least_one_in_every_study(capsys, argv):
    assert one_line_error(capsys, *argv) == (
        "--m: the cameras incremental greedy swaps per update; no incremental tasker runs (got --m 0)")
    with_incremental = [a.replace("uniform:4", "incremental:4").replace("uniform,greedy", "incremental")
                        for a in argv]
    assert one_line_error(capsys, *with_incremental) == "--m: expected an integer >= 1, got 0"


def test_m_larger_than_k_is_refused_alike_where_incremental_runs(capsys):
    # moving said "expected an integer in [1, min(k) = 2], got 3", tracking as below
    for argv in (("moving", "--k", "2,4", "--m", "3"), ("tracking", "--pairs", "incremental:2,uniform:4", "--m", "3")):
        assert one_line_error(capsys, *argv) == "--m: expected at most the smallest incremental k = 2, got 3"


def parsed(*argv):
    args = cli.build_parser().parse_args(["study", *argv])
    return args


def test_lab_m_is_incremental_greedys_alone():
    """lab refused --m 7 with k = 6 greedy, as if greedy swapped cameras; --m is bounded by incremental's
    k alone, and refused where no incremental runs."""
    with pytest.raises(ValueError, match=r"^--m: the cameras incremental greedy swaps per update; no incremental"):
        lab.parse(parsed("lab", "--k", "6", "--taskers", "uniform,greedy", "--m", "7"))
    with pytest.raises(ValueError, match=r"^--m: expected at most the smallest incremental k = 6, got 7$"):
        lab.parse(parsed("lab", "--k", "6,8", "--taskers", "greedy,incremental", "--m", "7"))
    assert lab.parse(parsed("lab", "--k", "6,8", "--taskers", "greedy,incremental", "--m", "6"))["m"] == 6


@pytest.mark.render
def test_lab_runs_greedy_without_an_m(capsys):
    """No incremental tasker: m is null in meta.arguments, and greedy runs with its one swap set."""
    assert cli.main(["study", "lab", "--people", "1", "--k", "2", "--taskers", "greedy", "--json",
                     "--frames", "2", "--trials", "1", "--workers", "0", "--no-progress"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["meta"]["arguments"]["m"] is None and {r["tasker"] for r in doc["records"]} == {"greedy"}


@pytest.mark.parametrize("value", ["-5", "0", "1", "9", "16", "10000000000000000000000"])
def test_fit_min_out_of_range_is_one_line(capsys, value):
    """--fit-min 16 of --cameras 4,8,16 ran the study and printed 'N in None: slope n/a'; -5 fitted
    over N >= -5; both are refused before any trial."""
    err = one_line_error(capsys, "cameras", "--objects", "2", "--cameras", "4,8,16", "--trials", "1",
                         f"--fit-min={value}")
    assert err == f"--fit-min: expected an integer in [2, 8] (at least two --cameras from it on), got {value}"


def test_fit_min_needs_two_camera_counts(capsys):
    err = one_line_error(capsys, "cameras", "--objects", "2", "--cameras", "4", "--trials", "1", "--fit-min", "4")
    assert err == "--fit-min: the slope needs at least two --cameras, got 4 alone"


def test_fit_min_at_its_bounds_and_the_default_without_a_slope(capsys):
    for value, fitted in (("2", [4, 16]), ("8", [8, 16])):
        assert cli.main(["study", "cameras", "--objects", "2", "--cameras", "4,8,16", "--trials", "1",
                         "--fit-min", value, "--workers", "0", "--no-progress", "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["fits"][0]["fit_cameras"] == fitted
    # the default (8) with cameras below it: the study runs, and the table says why there is no slope
    assert cli.main(["study", "cameras", "--objects", "2", "--cameras", "4", "--trials", "1",
                     "--workers", "0", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "None" not in out and "fewer than two N >= --fit-min: slope n/a" in out


@pytest.fixture
def clusters(monkeypatch):
    """The worker counts the study asked open_client for (the trials run in this process)."""
    asked = []

    @contextlib.contextmanager
    def fake_open_client(workers=None, scheduler=None):
        asked.append(workers)
        yield None

    monkeypatch.setattr(study_command, "open_client", fake_open_client)
    monkeypatch.setattr(study_command, "default_workers", lambda: 2)
    return asked


@pytest.mark.parametrize("argv, workers, started", [
    # 8 workers for one task of 4 trials (static chunks 10): 8.6 s against 1.3 s in this process
    (("static", "--k", "2", "--taskers", "uniform", "--trials", "4"), "8", 0),
    (("tracking", "--pairs", "uniform:4", "--steps", "3", "--trials", "3"), "8", 3),   # one task per trial
    (("tracking", "--pairs", "uniform:4", "--steps", "3", "--trials", "3"), "1", 1),
    (("tracking", "--pairs", "uniform:4", "--steps", "3", "--trials", "1"), None, 0),  # default: cores
    (("tracking", "--pairs", "uniform:4", "--steps", "3", "--trials", "3"), None, 2),
    (("cameras", "--objects", "1,2", "--cameras", "4", "--trials", "3"), "8", 2),      # a task per object count
    (("moving", "--k", "2", "--steps", "3", "--trials", "3"), "0", 0),
])
def test_no_more_workers_than_tasks(capsys, clusters, argv, workers, started):
    extra = () if workers is None else ("--workers", workers)
    assert cli.main(["study", *argv, *extra, "--no-progress", "--json"]) == 0
    assert clusters == [started]
    capsys.readouterr()


def test_no_cluster_before_the_arguments_are_checked(capsys, clusters):
    one_line_error(capsys, "static", "--k", "99")
    assert clusters == []


def test_trials_bounded_before_any_work(capsys, monkeypatch):
    """--trials 10**12 made every chunk's arguments first: the machine killed the run."""
    def refuse(*args):
        raise AssertionError("the study ran")

    monkeypatch.setattr(static, "run", refuse)
    for value in ("1000000000000", "100001", "0"):
        assert one_line_error(capsys, "static", "--trials", value) == (
            f"--trials: expected an integer >= 1 and at most 100000, got {value}")


def in_process(calls):
    def runner(func, tasks, weights, desc):
        calls.append((list(weights), desc))
        return [func(*t) for t in tasks]
    return runner


@pytest.mark.parametrize("mod, argv, trials, counted", [
    (cameras, ("cameras", "--objects", "1,2", "--cameras", "4"), 3, 6),     # each object count its drops
    (static, ("static", "--k", "2", "--taskers", "uniform", "--candidates", "4"), 12, 12),
    (moving, ("moving", "--k", "2", "--steps", "2", "--candidates", "4", "--taskers", "uniform"), 3, 3),
    (tracking, ("tracking", "--pairs", "uniform:4", "--steps", "2"), 3, 3),
])
def test_the_progress_bar_counts_trials(mod, argv, trials, counted):
    calls = []
    mod.run(mod.parse(parsed(*argv)), trials, 0, in_process(calls))
    ((weights, desc),) = calls
    assert sum(weights) == counted and desc == argv[0]


def test_the_lab_bar_counts_trials_not_frames():
    """study lab weighted each trial by its frames: 2 trials of 3 frames showed '6/6'."""
    calls = []

    def runner(func, tasks, weights, desc):
        calls.append(list(weights))
        return [{"areas": {"uniform:6": 2.0}, "min_full": 1.0, "mean_full": 1.5, "cameras": 16}] * len(tasks)

    opts = lab.parse(parsed("lab", "--k", "6", "--taskers", "uniform", "--frames", "3"))
    lab.run(opts, 2, 0, runner)
    assert calls == [[1, 1]]


def test_tracking_json_keeps_seed_and_arguments_in_meta_alone(capsys, tmp_path):
    """tracking repeated meta.seed and meta.arguments as top-level 'seed' and 'opts'."""
    png = tmp_path / "fig14.png"
    assert cli.main(["study", "tracking", "--pairs", "uniform:4", "--steps", "4", "--trials", "1", "--seed", "3",
                     "--workers", "0", "--no-progress", "--json", "--plot", str(png)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert set(doc) == {"records", "figure_trial", "meta"}
    assert doc["meta"]["seed"] == 3 and doc["meta"]["arguments"]["pairs"] == [["uniform", 4]]
    assert png.stat().st_size > 5000


def test_quadrature_scales_with_the_radius(capsys):
    """--quadrature took any spacing up to 0.05 m whatever --radius: with --radius 0.01 a row
    every 0.01 m (one row per disc) gave a limit 4x low (0.0020 against 0.0088 object areas)."""
    err = one_line_error(capsys, "cameras", "--radius", "0.01", "--quadrature", "0.01", "--objects", "2",
                         "--cameras", "4", "--trials", "1")
    assert err == ("--quadrature: expected a number in [radius / 1000, radius / 2] = [1e-05, 0.005], "
                   "got 0.01")
    # the paper's radius keeps its bounds: 0.05 = 0.1 / 2
    assert cli.main(["study", "cameras", "--quadrature", "0.05", "--objects", "2", "--cameras", "4",
                     "--trials", "1", "--workers", "0", "--no-progress"]) == 0
    capsys.readouterr()



def test_quadrature_is_refused_with_a_camera_limit(capsys):
    """--quadrature with --limit-cameras N was silently unused, and meta.arguments recorded it."""
    err = one_line_error(capsys, "cameras", "--limit-cameras", "64", "--quadrature", "0.001", "--objects", "2",
                         "--cameras", "4", "--trials", "1")
    assert err == ("--quadrature: the row spacing of the exact limit (--limit-cameras inf); "
                   "--limit-cameras 64 takes none")
    assert cli.main(["study", "cameras", "--limit-cameras", "64", "--objects", "2", "--cameras", "4",
                     "--trials", "1", "--workers", "0", "--no-progress", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["meta"]["arguments"]["quadrature"] is None


@pytest.mark.parametrize("value", ["0", "-5"])
def test_max_subsets_is_at_least_one(capsys, value):
    """--max-subsets -5 ran, and meta.arguments recorded the limit -5."""
    for taskers in ("uniform,greedy", "optimal"):
        assert one_line_error(capsys, "static", "--taskers", taskers, "--max-subsets", value, "--k", "2",
                              "--trials", "1") == f"--max-subsets: expected an integer >= 1, got {value}"


def test_max_subsets_is_optimals_alone(capsys):
    """--max-subsets without optimal was silently unused, and meta.arguments recorded it."""
    err = one_line_error(capsys, "static", "--taskers", "uniform,greedy", "--max-subsets", "10", "--k", "2",
                         "--trials", "1")
    assert err == "--max-subsets: the limit of optimal's subsets; --taskers uniform,greedy runs no optimal"
    for taskers, recorded in (("uniform,greedy", None), ("optimal", 200_000)):
        assert cli.main(["study", "static", "--taskers", taskers, "--k", "2", "--candidates", "4", "--objects", "1",
                         "--trials", "1", "--workers", "0", "--no-progress", "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["meta"]["arguments"]["max_subsets"] == recorded


def test_update_every_is_incrementals_alone_in_moving(capsys):
    """moving's --update-every without incremental was silently unused, and meta.arguments recorded it."""
    err = one_line_error(capsys, "moving", "--taskers", "uniform,greedy", "--update-every", "2,4", "--k", "2",
                         "--steps", "2", "--trials", "1")
    assert err == ("--update-every: incremental's re-tasking periods; --taskers uniform,greedy runs no "
                   "incremental")
    for taskers, recorded in (("uniform,greedy", None), ("incremental", [1, 3, 5, 7])):
        assert cli.main(["study", "moving", "--taskers", taskers, "--k", "2", "--candidates", "4", "--objects", "1",
                         "--steps", "2", "--trials", "1", "--workers", "0", "--no-progress", "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["meta"]["arguments"]["update_every"] == recorded


def test_tracking_refuses_an_episode_longer_than_the_memory(monkeypatch, capsys):
    """--steps 10**9 walked for hours (py-motmetrics keeps every step's events), then filled
    the memory; it is refused before any trial, by the memory available and --objects."""
    monkeypatch.setattr(memory, "available_memory", lambda: 2_000_000_000)
    monkeypatch.setattr(tracking, "run_trial", lambda *a: pytest.fail("a trial ran"))
    per_step = tracking.STEP_BYTES + 6 * tracking.OBJECT_BYTES
    err = one_line_error(capsys, "tracking", "--steps", str(10**9), "--trials", "1")
    assert err == (f"--steps: 1000000000 steps would hold about {memory.gigabytes(10**9 * per_step)} of memory in "
                   "each episode (the walk, its tracks and py-motmetrics' events of every step), more than the 2 GB "
                   f"available; expected at most {2_000_000_000 // per_step} steps here")
    most = 2_000_000_000 // (tracking.STEP_BYTES + 30 * tracking.OBJECT_BYTES)
    assert f"expected at most {most} steps" in one_line_error(capsys, "tracking", "--steps", str(most + 1),
                                                              "--objects", "30", "--trials", "1")
    args = parsed("tracking", "--steps", str(most), "--objects", "30")
    assert tracking.parse(args)["steps"] == most
    # the documented runs (docs/results.md: 150 steps) are far from the bound
    assert tracking.parse(parsed("tracking"))["steps"] == 150 < most


@pytest.mark.parametrize("argv", [("cameras", "--cameras", "4"), ("static", "--k", "2"),
                                  ("moving", "--k", "2", "--steps", "2"), ("tracking", "--steps", "2")])
def test_a_crowded_drop_names_objects_and_radius(capsys, argv):
    """60 discs of radius 0.1 pass the area check (at most 100) but no random drop places them:
    the error said 'radii: could not drop ...', naming no option."""
    err = one_line_error(capsys, *argv, "--objects", "60", "--radius", "0.1", "--trials", "1")
    assert re.fullmatch(r"--objects 60 with --radius 0\.1: could not drop 60 non-overlapping discs in the room "
                        r"\(gave up on disc \d+ after 2000 tries\); the room is too crowded", err), err


def test_update_every_is_refused_where_every_tasker_is_uniform(capsys):
    """lab's and tracking's --update-every with uniform alone (which never re-tasks) was silently
    unused, and meta.arguments recorded it."""
    for argv, taskers in ((("lab", "--taskers", "uniform"), "uniform"),
                          (("tracking", "--pairs", "uniform:4,uniform:6"), "uniform")):
        assert one_line_error(capsys, *argv, "--update-every", "3", "--trials", "1") == (
            f"--update-every: the re-tasking period of every tasker but uniform; {taskers} alone never re-tasks")
    assert lab.parse(parsed("lab", "--taskers", "uniform"))["update_every"] is None
    assert lab.parse(parsed("lab", "--taskers", "uniform,greedy", "--update-every", "3"))["update_every"] == 3
    assert lab.parse(parsed("lab"))["update_every"] == 1
    assert tracking.parse(parsed("tracking", "--pairs", "uniform:4"))["update_every"] is None
    assert tracking.parse(parsed("tracking", "--pairs", "greedy:4", "--update-every", "2"))["update_every"] == 2
    assert cli.main(["study", "tracking", "--pairs", "uniform:4", "--steps", "3", "--trials", "1", "--workers", "0",
                     "--no-progress", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["meta"]["arguments"]["update_every"] is None


def test_m_is_refused_where_no_tasker_is_incremental(capsys):
    """--m with no incremental tasker was silently unused, and meta.arguments recorded it as the swaps made."""
    for argv in (("moving", "--k", "2,4", "--taskers", "uniform,greedy", "--steps", "3"),
                 ("tracking", "--pairs", "greedy:3,uniform:4", "--steps", "5"),
                 ("lab", "--taskers", "uniform,greedy", "--frames", "2")):
        assert one_line_error(capsys, *argv, "--m", "3", "--trials", "1") == (
            "--m: the cameras incremental greedy swaps per update; no incremental tasker runs (got --m 3)")
    assert moving.parse(parsed("moving", "--taskers", "uniform,greedy"))["m"] is None
    assert moving.parse(parsed("moving"))["m"] == 1
    assert moving.parse(parsed("moving", "--m", "2"))["m"] == 2
    assert tracking.parse(parsed("tracking", "--pairs", "greedy:4"))["m"] is None
    assert tracking.parse(parsed("tracking", "--pairs", "incremental:4", "--m", "3"))["m"] == 3
    assert lab.parse(parsed("lab", "--taskers", "greedy"))["m"] is None
    assert lab.parse(parsed("lab"))["m"] == 1
    # still bounded by the smallest incremental k, and at least 1
    assert one_line_error(capsys, "moving", "--k", "2,4", "--m", "3", "--trials", "1") == (
        "--m: expected at most the smallest incremental k = 2, got 3")
    assert one_line_error(capsys, "moving", "--m", "0", "--trials", "1") == "--m: expected an integer >= 1, got 0"


def test_the_lab_tables_reference_line_names_one_camera_as_one():
    """A one-camera scene's table ended 'all 1 cameras: ...'."""
    records = [{"tasker": "greedy", "k": 1, "residual": 1.0, "std": 0.0}]
    for n, line in ((1, "the one camera: 1.000"), (16, "all 16 cameras: 1.000")):
        table = lab.format_table({"records": records, "cameras": n, "scene": "s", "all_cameras_residual": 1.0})
        assert table.splitlines()[-1] == line


def test_tracking_refuses_feedback_where_every_network_is_uniform(capsys):
    """--feedback tracks with uniform pairs alone was silently unused, and meta.arguments recorded it."""
    assert one_line_error(capsys, "tracking", "--pairs", "uniform:4,uniform:6", "--feedback", "tracks",
                          "--trials", "1") == (
        "--feedback: the estimates the taskers re-task from; uniform alone never re-tasks")
    assert tracking.parse(parsed("tracking", "--pairs", "uniform:4"))["feedback"] is None
    assert tracking.parse(parsed("tracking", "--pairs", "uniform:4,greedy:3"))["feedback"] == "hull"
    assert tracking.parse(parsed("tracking", "--pairs", "greedy:3", "--feedback", "tracks"))["feedback"] == "tracks"


def test_max_subsets_bounds_the_k_of_most_subsets_and_allows_exactly_its_count():
    """C(16, 8) = 12870 is the most subsets of --k 2,8,12 (C(16, 12) = 1820); C(8, 4) = 70
    subsets pass --max-subsets 70."""
    with pytest.raises(ValueError, match=r"C\(16, 8\) = 12870 subsets .* more than --max-subsets 5000$"):
        static.parse(parsed("static", "--k", "2,8,12", "--taskers", "optimal", "--max-subsets", "5000"))
    assert static.parse(parsed("static", "--k", "2,12", "--taskers", "optimal", "--max-subsets", "5000"))["k"] == [2, 12]
    assert static.parse(parsed("static", "--k", "4", "--candidates", "8", "--taskers", "optimal",
                               "--max-subsets", "70"))["max_subsets"] == 70
    with pytest.raises(ValueError, match=r"C\(8, 4\) = 70 subsets .* more than --max-subsets 69$"):
        static.parse(parsed("static", "--k", "4", "--candidates", "8", "--taskers", "optimal", "--max-subsets", "69"))


@pytest.mark.parametrize("name", ["static", "moving"])
def test_candidates_are_at_least_two(name):
    with pytest.raises(ValueError, match=r"^--candidates: expected an integer >= 2, got 1$"):
        STUDY_MODULES[name].parse(parsed(name, "--candidates", "1", "--k", "1"))
    assert STUDY_MODULES[name].parse(parsed(name, "--candidates", "2", "--k", "1,2"))["candidates"] == 2


def test_moving_needs_two_steps():
    """Frame 0 is the uniform set's; the residual averages frames 1..steps-1, none with one step."""
    with pytest.raises(ValueError, match=r"^--steps: expected an integer >= 2, got 1$"):
        moving.parse(parsed("moving", "--steps", "1"))
    assert moving.parse(parsed("moving", "--steps", "2"))["steps"] == 2
