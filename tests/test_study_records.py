"""What the studies compute from their trials: records (means, standard errors, scaled and
excess residuals, log-log slopes), tables, the residual itself and each trial's seed. The
trials are replaced by arrays built by hand where the aggregation is under test, and
recomputed from the documented seeding and `tasking` where the trials are."""

import numpy as np
import pytest

from scene.motion import random_drop, random_waypoint
from tasking import choose_cameras, polygon_centres, prune_small, visual_hull_of_discs
from testbed.studies import cameras, core, lab, moving, static

OBJ = np.pi * 0.1**2


def in_process(func, tasks, weights, desc):
    return [func(*t) for t in tasks]


def doc_rng(seed, *key):
    """A trial's generator as docs/studies.md states it."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=key))


def pruned_residual(xy, yaw, centers, r=0.1):
    """(raw, pruned) residual in object areas, from `tasking` directly."""
    room = core.circle_room()
    hull = visual_hull_of_discs(xy, yaw, np.pi, centers, r, room)
    obj = np.pi * r**2
    kept = prune_small(hull, obj)
    return (hull.area - len(centers) * obj) / obj, (sum(p.area for p in kept) - len(centers) * obj) / obj


# --- core --------------------------------------------------------------------------------


def test_residual_of_one_disc_between_two_opposite_cameras_is_the_rhombus_of_its_tangents():
    """Cameras at (1, 0) and (-1, 0) see a disc of radius r at the origin as two wedges of
    half-angle asin(r); their intersection is the rhombus with vertices (+-1, 0) and
    (0, +-tan asin r), of area 2 tan(asin r)."""
    xy, yaw = core.circle_cameras(2)
    raw, pruned, polys = core.hull_residual(xy, yaw, np.zeros((1, 2)), 0.1, core.circle_room())
    rhombus = 2 * 0.1 / np.sqrt(1 - 0.1**2)
    assert raw == pytest.approx((rhombus - OBJ) / OBJ, abs=1e-9)
    assert pruned == pytest.approx(raw, abs=1e-12) and len(polys) == 1
    # with a second disc the residual subtracts both discs' areas
    raw2, _, _ = core.hull_residual(xy, yaw, np.array([[0.0, 0.0], [0.0, 0.5]]), 0.1, core.circle_room())
    hull2 = visual_hull_of_discs(xy, yaw, np.pi, np.array([[0.0, 0.0], [0.0, 0.5]]), 0.1, core.circle_room())
    assert raw2 == pytest.approx((hull2.area - 2 * OBJ) / OBJ, abs=1e-12)


def test_circle_cameras_face_the_centre_on_a_circle_of_their_radius():
    xy, yaw = core.circle_cameras(6, radius=2.0)
    a = np.radians([0, 60, 120, 180, 240, 300])
    np.testing.assert_allclose(xy, 2.0 * np.column_stack([np.cos(a), np.sin(a)]), atol=1e-12)
    # each camera looks at the origin, with its yaw in [0, 2 pi)
    look = np.column_stack([np.cos(yaw), np.sin(yaw)])
    np.testing.assert_allclose(look, -xy / 2.0, atol=1e-12)
    assert np.all((yaw >= 0) & (yaw < 2 * np.pi))


def test_circle_room_is_a_720_gon_on_the_circle_of_its_radius():
    for radius in (1.0, 2.5):
        xy = np.asarray(core.circle_room(radius).exterior.coords)[:-1]
        assert len(xy) == 720
        np.testing.assert_allclose(np.hypot(xy[:, 0], xy[:, 1]), radius, atol=1e-12)


def test_the_trial_generator_is_the_documented_seed_sequence():
    for seed, key in ((0, (0, 3, 7)), (5, (2, 0, 1)), (2**32 - 1, (1, 4, 2, 9))):
        assert core.trial_rng(seed, *key).random(4).tolist() == doc_rng(seed, *key).random(4).tolist()
    assert core.trial_rng(1, 0, 2, 3).random() != core.trial_rng(1, 0, 3, 2).random()


def test_parse_ints_sorts_merges_and_bounds_ranges():
    assert core.parse_ints("k", "5, 2-4,3") == [2, 3, 4, 5]
    assert core.parse_ints("k", [8, 2, 3, 2]) == [2, 3, 8]          # a list, as --k defaults may be
    assert core.parse_ints("k", "7-7") == [7]
    assert len(core.parse_ints("k", "1-100000")) == 100_000         # MAX_RANGE values: allowed
    with pytest.raises(ValueError, match=r"^--k: a range of at most 100000 values, got '1-100001'$"):
        core.parse_ints("k", "1-100001")
    with pytest.raises(ValueError, match=r"^--k: a range of at most 100000 values, got '1-100001'$"):
        core.parse_ints("k", "2, 1-100001,5")                       # the range named alone
    for text in ("5-2", "3-2"):                                     # a range downwards, even by one
        with pytest.raises(ValueError, match=rf"^--k: expected integers like '2,3,4' or '2-8', got '{text}'$"):
            core.parse_ints("k", text)
    # a negative number is a number below the minimum, not a malformed range
    with pytest.raises(ValueError, match=r"^--k: expected integers >= 1, got -3$"):
        core.parse_ints("k", "2,-3")
    with pytest.raises(ValueError, match=r"^--k: expected integers >= 1, got -3$"):
        core.parse_ints("k", "2, -3")                               # after a space, too
    # of several numbers below the minimum, the error names the smallest
    with pytest.raises(ValueError, match=r"^--k: expected integers >= 1, got -7$"):
        core.parse_ints("k", "0,-7,-2,3")
    with pytest.raises(ValueError, match=r"^--cameras: expected integers >= 2, got 1$"):
        core.parse_ints("cameras", "1,3,5", minimum=2)
    assert core.parse_ints("cameras", "2", minimum=2) == [2]


def test_parse_names_keeps_order_drops_duplicates_and_refuses_an_empty_list():
    assert core.parse_names("taskers", " greedy,uniform, greedy ,", core.TASKERS) == ["greedy", "uniform"]
    with pytest.raises(ValueError, match=r"^--taskers: expected a comma-separated list, got ' , '$"):
        core.parse_names("taskers", " , ", core.TASKERS)
    with pytest.raises(ValueError, match=r"^--taskers: unknown value 'best'; expected one of uniform, "):
        core.parse_names("taskers", "greedy,best", core.TASKERS)


def test_crowding_renames_only_the_drops_errors():
    with pytest.raises(ValueError, match=r"^--objects 7 with --radius 0\.25: could not drop$"), core.crowding(7, 0.25):
        raise ValueError("radii: could not drop")
    # any other error passes unchanged
    with pytest.raises(ValueError, match=r"^speed: too fast$"), core.crowding(7, 0.25):
        raise ValueError("speed: too fast")
    with pytest.raises(ValueError, match=r"^speed: radii: too fast$"), core.crowding(7, 0.25):
        raise ValueError("speed: radii: too fast")


def test_mean_and_standard_error():
    mean, sem = core.mean_sem([1.0, 2.0, 3.0, 5.0])
    assert mean == pytest.approx(2.75)
    var = ((1 - 2.75) ** 2 + (2 - 2.75) ** 2 + (3 - 2.75) ** 2 + (5 - 2.75) ** 2) / 3
    assert sem == pytest.approx(np.sqrt(var / 4))
    assert core.mean_sem([4.5]) == (4.5, 0.0)


def test_bounds_of_the_shared_checks():
    assert core.check_cameras("cameras", 10_000) == 10_000
    with pytest.raises(ValueError, match="at most 10000 cameras, got 10001"):
        core.check_cameras("cameras", 10_001)
    # by area: a room of area 720/2 sin(2 pi/720) holds 99 discs of radius 0.1
    most = int(core.circle_room().area // OBJ)
    assert most == 99 and core.check_objects("objects", 99, 0.1) == 99
    with pytest.raises(ValueError, match="expected at most 99"):
        core.check_objects("objects", 100, 0.1)
    # the room is a 720-gon, a little smaller than the unit disc: 16 discs of radius 1/4 fill
    # the disc's area exactly, so they do not fit the polygon's
    assert core.check_objects("objects", 15, 0.25) == 15
    with pytest.raises(ValueError, match=r"16 discs of radius 0\.25 do not fit .*; expected at most 15$"):
        core.check_objects("objects", 16, 0.25)
    assert core.check_bounded("dt", 1000.0, 0.0, 1000.0, low_open=True) == 1000.0
    assert core.check_bounded("speed", 0.0, 0.0, 100.0) == 0.0
    for value, low_open in ((0.0, True), (1000.5, False), (-1e-9, False), (np.inf, False), (np.nan, False)):
        with pytest.raises(ValueError, match="^--dt: "):
            core.check_bounded("dt", value, 0.0, 1000.0, low_open=low_open)
    assert core.check_count("steps", 2, 2) == 2
    with pytest.raises(ValueError, match=r"^--steps: expected an integer >= 2, got 1$"):
        core.check_count("steps", 1, 2)
    for radius in (0.0, 0.5, -0.1):
        with pytest.raises(ValueError, match=r"^--radius: expected a number in \(0, 0\.5\)"):
            core.check_discs(1, radius)
    assert core.check_discs(1, 0.499) == 0.499
    assert core.check_discs(99, 0.1) == 0.1
    with pytest.raises(ValueError, match=r"^--objects: 100 discs of radius 0\.1 do not fit"):
        core.check_discs(100, 0.1)
    assert core.check_m(None, [3, 2]) == 1 and core.check_m(2, [3, 2]) == 2 and core.check_m(None, []) is None
    with pytest.raises(ValueError, match="smallest incremental k = 2, got 3"):
        core.check_m(3, [3, 2])
    assert core.check_period(None, 4, ["greedy"]) == 4 and core.check_period(2, 4, ["uniform", "greedy"]) == 2
    assert core.check_period(None, 4, ["uniform"]) is None
    with pytest.raises(ValueError, match=r"^--update-every: expected an integer >= 1, got 0$"):
        core.check_period(0, 4, ["greedy"])
    assert core.parse_k("2,4", 4, "the 4 candidates") == [2, 4]
    with pytest.raises(ValueError, match=r"^--k: 5 cameras exceed the 4 candidates$"):
        core.parse_k("2,5", 4, "the 4 candidates")
    with pytest.raises(ValueError, match=r"^--k: expected integers >= 1, got 0$"):
        core.parse_k("0,2", 4, "the 4 candidates")


def test_the_shared_checks_return_plain_python_numbers():
    """What they return goes into the records' JSON, which takes no numpy scalar."""
    for value in (core.check_bounded("speed", np.float32(0.5), 0.0, 100.0), core.check_bounded("dt", 2, 0.0, 1000.0),
                  core.check_discs(1, np.float32(0.25))):
        assert type(value) is float
    for value in (core.check_count("steps", np.int64(3)), core.check_m(np.int64(2), [3]),
                  core.check_period(np.int64(2), 4, ["greedy"])):
        assert type(value) is int


def test_tasker_table_rows_go_up_in_k():
    recs = [{"tasker": "uniform", "k": k, "residual": 1.0 / k} for k in (16, 2, 8)]
    rows = core.tasker_table(recs, "T:").splitlines()[2:]
    assert [int(row.split()[0]) for row in rows] == [2, 8, 16]
    assert [float(row.split()[1]) for row in rows] == [0.5, 0.125, 0.0625]


def test_tasker_table_is_k_by_tasker():
    recs = [{"tasker": t, "k": k, "residual": v} for t, k, v in
            (("uniform", 3, 1.5), ("greedy", 3, 0.25), ("uniform", 2, 2.0), ("greedy", 2, 1.125))]
    assert core.tasker_table(recs, "T:", digits=2).splitlines() == [
        "T:",
        "  k " + " " * 6 + "uniform" + " " * 7 + "greedy",
        "  2 " + " " * 9 + "2.00" + " " * 9 + "1.12",
        "  3 " + " " * 9 + "1.50" + " " * 9 + "0.25",
    ]


# --- cameras -------------------------------------------------------------------------------


def fake_camera_trials(pruned, raw=None):
    """A run_trials that returns, for object count m, the rows pruned[m][a:b] (per camera count
    and the limit last), with raw = pruned + raw[m] (default 1)."""
    def run_trials(m, a, b, cams, limit, radius, h, seed):
        p = np.asarray(pruned[m], float)[a:b]
        out = np.empty(p.shape + (2,))
        out[..., 1] = p
        out[..., 0] = p + (1.0 if raw is None else raw[m])
        return out
    return run_trials


def test_cameras_records_means_scaled_excess_and_slopes(monkeypatch):
    # rows: trials; columns: N = 8, 16, then the limit (pruned residuals)
    pruned = {1: [[0.3, 0.0, 0.0]] * 3,
              2: [[0.5, 0.2, 0.1], [0.7, 0.2, 0.1], [0.9, 0.2, 0.1]]}
    monkeypatch.setattr(cameras, "run_trials", fake_camera_trials(pruned, raw={1: 0.0, 2: 1.0}))
    opts = {"objects": [1, 2], "cameras": [8, 16], "limit_cameras": None, "radius": 0.1, "quadrature": 0.002,
            "fit_min": 8}
    result = cameras.run(opts, 3, 0, in_process)
    recs = {(r["objects"], r["cameras"], r["limit"]): r for r in result["records"]}
    assert [(r["objects"], r["cameras"]) for r in result["records"]] == [(1, 8), (1, 16), (1, None),
                                                                        (2, 8), (2, 16), (2, None)]
    r = recs[(2, 8, False)]
    assert r["residual"] == pytest.approx(0.7) and r["residual_sem"] == pytest.approx(0.2 / np.sqrt(3))
    assert r["residual_raw"] == pytest.approx(1.7)
    assert r["scaled"] == pytest.approx(7.0) and r["excess"] == pytest.approx(0.6) and r["trials"] == 3
    assert recs[(2, 16, False)]["excess"] == pytest.approx(0.1) and recs[(2, 16, False)]["scaled"] == pytest.approx(2)
    lim = recs[(2, None, True)]
    assert lim["method"] == "exact" and lim["residual"] == pytest.approx(0.1)
    assert lim["residual_sem"] == pytest.approx(0, abs=1e-12)
    assert lim["residual_raw"] == pytest.approx(1.1) and lim["scaled"] == 1.0 and lim["excess"] == 0.0
    # one object: the limit is 0, so nothing is scaled by it
    assert recs[(1, 8, False)]["scaled"] is None and recs[(1, None, True)]["scaled"] is None
    assert recs[(1, 8, False)]["residual_raw"] == pytest.approx(0.3)
    one, two = result["fits"]
    assert two == {"objects": 2, "fit_cameras": [8, 16], "slope": pytest.approx(np.log(0.2 / 0.7) / np.log(2)),
                   "slope_excess": pytest.approx(np.log(0.1 / 0.6) / np.log(2))}
    # a residual of 0 at N = 16 has no logarithm: no slopes, but the N range is still given
    assert one == {"objects": 1, "fit_cameras": [8, 16], "slope": None, "slope_excess": None}


def test_cameras_fit_only_over_n_from_fit_min(monkeypatch):
    # N = 2, 4, 8: residual 1 / N^2 above a limit of 0.01; fit over N >= 4 alone
    pruned = {3: [[0.25 + 0.01, 1 / 16 + 0.01, 1 / 64 + 0.01, 0.01]]}
    monkeypatch.setattr(cameras, "run_trials", fake_camera_trials(pruned))
    opts = {"objects": [3], "cameras": [2, 4, 8], "limit_cameras": 64, "radius": 0.1, "quadrature": None,
            "fit_min": 4}
    result = cameras.run(opts, 1, 0, in_process)
    (fit,) = result["fits"]
    assert fit["fit_cameras"] == [4, 8] and fit["slope_excess"] == pytest.approx(-2.0)
    assert fit["slope"] == pytest.approx(np.log((1 / 64 + 0.01) / (1 / 16 + 0.01)) / np.log(2))
    lim = result["records"][-1]
    assert lim["limit"] and lim["cameras"] == 64 and lim["method"] == "cameras"
    assert cameras.run({**opts, "fit_min": 8}, 1, 0, in_process)["fits"][0] == {
        "objects": 3, "fit_cameras": None, "slope": None, "slope_excess": None}


def test_cameras_trials_are_put_back_in_order_per_object_count(monkeypatch):
    """25 trials are two tasks per object count (20 + 5); each object count gets its own."""
    pruned = {m: [[100 * m + t, 0.0] for t in range(25)] for m in (1, 4)}
    monkeypatch.setattr(cameras, "run_trials", fake_camera_trials(pruned))
    tasks = []

    def runner(func, args, weights, desc):
        tasks.extend((a[0], a[1], a[2]) for a in args)
        assert weights == [20, 5, 20, 5]
        return [func(*a) for a in args]

    opts = {"objects": [1, 4], "cameras": [2], "limit_cameras": None, "radius": 0.1, "quadrature": 0.002,
            "fit_min": 8}
    recs = cameras.run(opts, 25, 0, runner)["records"]
    assert tasks == [(1, 0, 20), (1, 20, 25), (4, 0, 20), (4, 20, 25)]
    assert recs[0]["residual"] == pytest.approx(100 + 12) and recs[2]["residual"] == pytest.approx(400 + 12)
    assert recs[0]["residual_sem"] == pytest.approx(np.std(np.arange(25), ddof=1) / 5)


def test_cameras_table_text():
    recs = [{"objects": m, "cameras": n, "limit": False, "residual": v}
            for m, n, v in ((1, 4, 0.5), (1, 8, 0.125), (3, 4, 2.25), (3, 8, 1.0))]
    recs += [{"objects": 1, "cameras": 2000, "limit": True, "residual": 0.0},
             {"objects": 3, "cameras": 2000, "limit": True, "residual": 0.75}]
    fits = [{"objects": 1, "fit_cameras": [4, 8], "slope": -2.0, "slope_excess": None},
            {"objects": 3, "fit_cameras": None, "slope": None, "slope_excess": None}]
    assert cameras.format_table({"records": recs, "fits": fits}).splitlines() == [
        "Residual of the visual hull in object areas (after removing polygons < one object):",
        "N\\objects " + " " * 8 + "1" + " " * 8 + "3",
        " " * 8 + "4 " + "   0.5000" + "   2.2500",
        " " * 8 + "8 " + "   0.1250" + "   1.0000",
        " " * 5 + "2000 " + "   0.0000" + "   0.7500",
        "",
        "log-log slope of residual vs N (and of residual - limit), paper: -2 for one object:",
        "  objects= 1  N in [4, 8]: slope -2.00   excess slope n/a",
        "  objects= 3  fewer than two N >= --fit-min: slope n/a   excess slope n/a",
    ]
    recs[-2:] = [{**r, "cameras": None} for r in recs[-2:]]
    assert cameras.format_table({"records": recs, "fits": fits}).splitlines()[4] == (
        " " * 6 + "inf " + "   0.0000" + "   0.7500")


def test_cameras_trials_are_the_documented_drops_and_hulls():
    """Trial t of m objects drops from SeedSequence(seed, spawn_key=(0, m, t)); its columns are
    the N-camera hulls and the limit, [raw, pruned] in object areas; a chunk's trials are the
    same wherever the chunk starts."""
    out = cameras.run_trials(2, 1, 3, [3, 5], 40, 0.1, None, 9)
    assert out.shape == (2, 3, 2)
    for row, t in zip(out, (1, 2)):
        centers = random_drop(core.circle_room(), np.full(2, 0.1), doc_rng(9, 0, 2, t))
        for col, n in zip(row, (3, 5, 40)):
            np.testing.assert_allclose(col, pruned_residual(*core.circle_cameras(n), centers), atol=1e-12)
    np.testing.assert_array_equal(cameras.run_trials(2, 2, 3, [3, 5], 40, 0.1, None, 9)[0], out[1])


def test_cameras_exact_limit_column_is_in_object_areas():
    from testbed.studies.limit import limit_residual

    out = cameras.run_trials(5, 0, 1, [4], None, 0.1, 0.004, 2)
    centers = random_drop(core.circle_room(), np.full(5, 0.1), doc_rng(2, 0, 5, 0))
    raw, pruned = limit_residual(centers, 0.1, h=0.004, min_area=OBJ)
    assert raw > pruned > 0                                   # this drop has a piece to prune
    np.testing.assert_allclose(out[0, -1], [raw / OBJ, pruned / OBJ], rtol=1e-12)
    # a 400-camera hull contains the limit hull and is close to it
    assert out[0, -1, 0] <= pruned_residual(*core.circle_cameras(400), centers)[0] + 0.01


def test_limit_cameras_below_two_is_refused():
    import argparse

    p = argparse.ArgumentParser()
    cameras.add_arguments(p)
    for value in ("1", "-3", "0"):
        with pytest.raises(ValueError, match=rf"^--limit-cameras: expected an integer >= 2 or 'inf', got {value}$"):
            cameras.parse(p.parse_args(["--limit-cameras", value, "--cameras", "2"]))
    opts = cameras.parse(p.parse_args(["--limit-cameras", " Exact ", "--cameras", "2,3"]))
    assert opts["limit_cameras"] is None and opts["quadrature"] == pytest.approx(0.002)
    assert cameras.parse(p.parse_args(["--limit-cameras", "4", "--cameras", "2,3"]))["limit_cameras"] == 4
    assert cameras.parse(p.parse_args(["--radius", "0.2", "--quadrature", "0.1"]))["quadrature"] == 0.1
    assert cameras.parse(p.parse_args(["--radius", "0.2", "--quadrature", "0.0002"]))["quadrature"] == 0.0002
    assert cameras.parse(p.parse_args(["--cameras", "2,4,8", "--fit-min", "4"]))["fit_min"] == 4


# --- static --------------------------------------------------------------------------------


def test_static_records_per_tasker_and_k(monkeypatch):
    """run_trials gives (trials, taskers, k): record (tasker i, k j) averages [:, i, j]."""
    def run_trials(a, b, opts, seed):
        t = np.arange(a, b, dtype=float)[:, None, None]
        return t + 10 * np.arange(2)[None, :, None] + 100 * np.arange(3)[None, None, :]

    monkeypatch.setattr(static, "run_trials", run_trials)
    opts = {"objects": 2, "k": [2, 3, 5], "candidates": 8, "taskers": ["greedy", "uniform"], "radius": 0.1,
            "max_subsets": None}
    weights = []

    def runner(func, tasks, w, desc):
        weights.extend(w)
        return [func(*t) for t in tasks]

    recs = static.run(opts, 12, 0, runner)["records"]
    assert weights == [10, 2]                                  # ten trials a task
    assert [(r["tasker"], r["k"]) for r in recs] == [("greedy", 2), ("greedy", 3), ("greedy", 5),
                                                     ("uniform", 2), ("uniform", 3), ("uniform", 5)]
    assert [r["residual"] for r in recs] == pytest.approx([5.5, 105.5, 205.5, 15.5, 115.5, 215.5])
    assert recs[0]["residual_sem"] == pytest.approx(np.std(np.arange(12), ddof=1) / np.sqrt(12))
    assert all(r["trials"] == 12 for r in recs)


def test_static_trials_are_the_documented_drops_and_taskers():
    """Trial t drops from SeedSequence(seed, spawn_key=(1, 0, t)); a tasker's own draws
    (clustering's k-means) are keyed by the tasker (its place in tasking's TASKERS), k and t."""
    opts = {"objects": 3, "k": [2, 4], "candidates": 8, "taskers": ["uniform", "greedy", "optimal", "clustering"],
            "radius": 0.1, "max_subsets": 100}
    out = static.run_trials(1, 3, opts, 4)
    assert out.shape == (2, 4, 2)
    xy, yaw = core.circle_cameras(8)
    room = core.circle_room()
    for row, t in zip(out, (1, 2)):
        centers = random_drop(room, np.full(3, 0.1), doc_rng(4, 1, 0, t))
        for i, tasker in enumerate(opts["taskers"]):
            for j, k in enumerate(opts["k"]):
                rng = doc_rng(4, 1, 1 + core.TASKERS.index(tasker), k, t)
                S = choose_cameras(tasker, k, xy, yaw, np.pi, centers, 0.1, room, rng=rng)
                assert row[i, j] == pytest.approx(pruned_residual(xy[S], yaw[S], centers)[1], abs=1e-12)
    # optimal is the best raw hull: on these drops its pruned residual is no worse either
    assert np.all(out[:, 2] <= out[:, 0] + 1e-9)
    # --max-subsets reaches optimal: C(8, 4) = 70 subsets pass a limit of 70, not 69
    assert static.run_trials(1, 2, {**opts, "max_subsets": 70}, 4).shape == (1, 4, 2)
    with pytest.raises(ValueError):
        static.run_trials(1, 2, {**opts, "max_subsets": 69}, 4)


def test_static_clustering_draws_from_its_own_key():
    """Clustering's k-means draws from SeedSequence(seed, spawn_key=(1, 1 + its place in
    tasking's TASKERS, k, t)); on drop 19 (seed 0) other draws choose other cameras."""
    opts = {"objects": 5, "k": [4, 6], "candidates": 16, "taskers": ["clustering"], "radius": 0.1,
            "max_subsets": None}
    out = static.run_trials(19, 20, opts, 0)
    xy, yaw = core.circle_cameras(16)
    room = core.circle_room()
    centers = random_drop(room, np.full(5, 0.1), doc_rng(0, 1, 0, 19))
    chosen = {tuple(choose_cameras("clustering", 4, xy, yaw, np.pi, centers, 0.1, room,
                                   rng=np.random.default_rng(s)).tolist()) for s in range(4)}
    assert len(chosen) > 1                                    # the draw matters here
    for j, k in enumerate(opts["k"]):
        rng = doc_rng(0, 1, 1 + core.TASKERS.index("clustering"), k, 19)
        S = choose_cameras("clustering", k, xy, yaw, np.pi, centers, 0.1, room, rng=rng)
        assert out[0, 0, j] == pytest.approx(pruned_residual(xy[S], yaw[S], centers)[1], abs=1e-12)


def test_static_table_text():
    recs = [{"tasker": t, "k": k, "residual": v, "residual_sem": 0.0, "trials": 1}
            for t, k, v in (("uniform", 2, 3.0), ("uniform", 4, 1.25), ("greedy", 2, 2.5), ("greedy", 4, 0.0625))]
    assert static.format_table({"records": recs}).splitlines() == [
        "Residual (object areas) with static objects, by tasker and k:",
        "  k " + " " * 6 + "uniform" + " " * 7 + "greedy",
        "  2 " + " " * 7 + "3.0000" + " " * 7 + "2.5000",
        "  4 " + " " * 7 + "1.2500" + " " * 7 + "0.0625",
    ]


# --- moving --------------------------------------------------------------------------------


def test_moving_settings_and_records(monkeypatch):
    opts = {"objects": 2, "k": [2, 3], "candidates": 6, "taskers": ["uniform", "incremental", "greedy"],
            "update_every": [1, 4], "m": 1, "steps": 3, "dt": 0.1, "speed": 0.5, "radius": 0.1}
    sets = [("uniform", 2, 1), ("uniform", 3, 1), ("incremental", 2, 1), ("incremental", 3, 1),
            ("incremental", 2, 4), ("incremental", 3, 4), ("greedy", 2, 1), ("greedy", 3, 1)]
    assert moving.settings(opts) == sets

    def run_trials(a, b, o, seed):
        return np.arange(a, b, dtype=float)[:, None] + 10 * np.arange(len(sets))[None, :]

    monkeypatch.setattr(moving, "run_trials", run_trials)
    weights = []

    def runner(func, tasks, w, desc):
        weights.extend(w)
        return [func(*t) for t in tasks]

    recs = moving.run(opts, 5, 0, runner)["records"]
    assert weights == [2, 2, 1]                                     # two trials a task
    assert [(r["tasker"], r["k"], r["update_every"]) for r in recs] == sets
    assert [r["residual"] for r in recs] == pytest.approx([2 + 10 * s for s in range(len(sets))])
    assert recs[3]["residual_sem"] == pytest.approx(np.std(np.arange(5), ddof=1) / np.sqrt(5))
    assert all(r["trials"] == 5 and r["steps"] == 3 for r in recs)


def test_moving_table_text():
    recs = [{"tasker": t, "k": k, "update_every": u, "residual": v}
            for t, u, k, v in (("uniform", 1, 2, 4.0), ("uniform", 1, 3, 2.0),
                               ("incremental", 1, 2, 1.5), ("incremental", 1, 3, 0.75),
                               ("incremental", 3, 2, 2.5), ("incremental", 3, 3, 1.25),
                               ("greedy", 1, 2, 1.0), ("greedy", 1, 3, 0.5))]
    assert moving.format_table({"records": recs}).splitlines() == [
        "Time-averaged residual (object areas) with moving objects (incremental/u: re-tasked every u frames):",
        "  k " + " " * 8 + "uniform" + " " * 2 + "incremental/1" + " " * 2 + "incremental/3" + " " * 9 + "greedy",
        "  2 " + " " * 9 + "4.0000" + " " * 9 + "1.5000" + " " * 9 + "2.5000" + " " * 9 + "1.0000",
        "  3 " + " " * 9 + "2.0000" + " " * 9 + "0.7500" + " " * 9 + "1.2500" + " " * 9 + "0.5000",
    ]


MOVING = {"objects": 3, "k": [3], "candidates": 8, "taskers": ["uniform"], "update_every": None, "m": None,
          "steps": 3, "dt": 0.1, "speed": 0.5, "radius": 0.1}


def test_moving_uniform_residual_is_the_average_over_frames_after_the_first():
    out = moving.run_trials(1, 2, MOVING, 6)
    room = core.circle_room()
    traj = random_waypoint(room, np.full(3, 0.1), 3, 0.1, 0.5, doc_rng(6, 2, 0, 1))
    xy, yaw = core.circle_cameras(8)
    S = choose_cameras("uniform", 3, xy, yaw, np.pi, traj[0], 0.1, room)
    frames = [pruned_residual(xy[S], yaw[S], traj[f])[1] for f in (1, 2)]
    assert out.shape == (1, 1) and out[0, 0] == pytest.approx(np.mean(frames), abs=1e-12)


def test_moving_retasks_from_the_previous_frames_estimates_at_1_1_plus_u(monkeypatch):
    """incremental with u = 3 over 8 frames re-tasks at frames 1, 4, 7 with --m swaps; greedy every
    frame with 1; each from the centres of the previous frame's pruned hull."""
    calls = []
    real_choose = core.choose_cameras

    def spy(tasker, k, xy, yaw, fov, estimates, r, room, **kw):
        calls.append((tasker, np.array(estimates), kw.get("current"), kw.get("m")))
        return real_choose(tasker, k, xy, yaw, fov, estimates, r, room, **kw)

    monkeypatch.setattr(core, "choose_cameras", spy)
    opts = {**MOVING, "k": [4], "taskers": ["incremental", "greedy"], "update_every": [3], "m": 2, "steps": 8}
    moving.run_trials(0, 1, opts, 1)
    inc = [c for c in calls if c[0] == "incremental"]
    greedy = [c for c in calls if c[0] == "greedy"]
    assert [c[0] for c in calls[:1 + len(inc)]] == ["uniform"] + ["incremental"] * 3
    assert len(inc) == 3 and all(c[3] == 2 for c in inc)
    assert len(greedy) == 7 and all(c[3] == 1 for c in greedy)
    # the estimates are the previous frame's pruned-hull centres of the cameras in use
    room = core.circle_room()
    traj = random_waypoint(room, np.full(3, 0.1), 8, 0.1, 0.5, doc_rng(1, 2, 0, 0))
    xy, yaw = core.circle_cameras(8)
    uniform = real_choose("uniform", 4, xy, yaw, np.pi, traj[0], 0.1, room)
    first = polygon_centres(prune_small(visual_hull_of_discs(xy[uniform], yaw[uniform], np.pi, traj[0], 0.1, room),
                                        OBJ))
    np.testing.assert_allclose(inc[0][1], first)
    np.testing.assert_array_equal(inc[0][2], uniform)
    prev = uniform
    for f, (_, est, current, _) in enumerate(greedy, start=1):
        hull = visual_hull_of_discs(xy[prev], yaw[prev], np.pi, traj[f - 1], 0.1, room)
        np.testing.assert_allclose(est, polygon_centres(prune_small(hull, OBJ)))
        np.testing.assert_array_equal(current, prev)
        prev = real_choose("greedy", 4, xy, yaw, np.pi, est, 0.1, room, current=prev, m=1)


# --- lab ------------------------------------------------------------------------------------


def test_lab_residual_is_each_trials_area_over_its_smallest_all_camera_hull(monkeypatch):
    per_trial = [{"areas": {"uniform:4": 3.0, "greedy:4": 2.0}, "min_full": 1.0, "mean_full": 1.5, "cameras": 16},
                 {"areas": {"uniform:4": 8.0, "greedy:4": 5.0}, "min_full": 4.0, "mean_full": 4.4, "cameras": 16}]
    opts = {"scene": "lab", "taskers": ["uniform", "greedy"], "k": [4]}
    result = lab.run(opts, 2, 0, lambda func, tasks, weights, desc: per_trial)
    uniform, greedy = result["records"]
    assert (uniform["tasker"], greedy["tasker"]) == ("uniform", "greedy")
    assert uniform["residual"] == pytest.approx(2.5) and uniform["residual_sem"] == pytest.approx(0.5)
    assert greedy["residual"] == pytest.approx(1.625) and greedy["residual_sem"] == pytest.approx(0.375)
    assert result["all_cameras_residual"] == pytest.approx((1.5 + 1.1) / 2)
    assert result["cameras"] == 16 and result["scene"] == "lab" and uniform["trials"] == 2
    empty = [per_trial[0], {**per_trial[1], "min_full": 0.0}]
    with pytest.raises(ValueError, match=r"^--scene: the hull of all its cameras was empty in a frame of trial 1,"):
        lab.run(opts, 2, 0, lambda func, tasks, weights, desc: empty)


def test_lab_table_text():
    recs = [{"tasker": "uniform", "k": 6, "residual": 1.5}, {"tasker": "greedy", "k": 6, "residual": 1.25}]
    table = lab.format_table({"records": recs, "cameras": 16, "scene": "lab", "all_cameras_residual": 1.0625})
    assert table.splitlines() == [
        "Normalised residual hull area on lab (hull area / min 16-camera area):",
        "  k " + " " * 6 + "uniform" + " " * 7 + "greedy",
        "  6 " + " " * 8 + "1.500" + " " * 8 + "1.250",
        "all 16 cameras: 1.062",
    ]


def test_lab_trial_runs_each_tasker_and_k_on_the_walks_scanlines(monkeypatch):
    """run_trial with the rendering and the closed loop replaced by fakes: the walk is drawn from
    the trial's first spawned generator (docs/studies.md's seeding) and rendered with the second;
    the reference run tasks all 16 cameras; --m reaches incremental alone, --no-near-field every
    run; min_full / mean_full are the smallest and the mean all-camera frame area."""
    from types import SimpleNamespace

    import testbed.loop
    from scene import load_scene
    from testbed.episode import walk, with_people
    from testbed.loop import LoopConfig

    seen, configs = {}, []

    def render(scene, params, truth, rng):
        seen["truth"], seen["sensor"] = truth, rng.random(3)
        return np.zeros((len(truth), 16, 4), bool), np.zeros((16, 4)), np.zeros(16), np.ones(16)

    def run_loop(scene, config, truth, source):
        configs.append(config)
        assert source.all.shape == (3, 16, 4) and len(truth) == 3
        frames = [3.0, 1.0, 2.0] if len(configs) == 1 else [config.k + 10 * config.m + i for i in range(3)]
        return [SimpleNamespace(hull_area=a) for a in frames]

    monkeypatch.setattr(lab, "render_scanlines", render)
    monkeypatch.setattr(testbed.loop, "run_loop", run_loop)
    opts = {"scene": "lab", "people": 2, "frames": 3, "taskers": ["uniform", "greedy", "incremental"], "k": [4, 6],
            "m": 2, "update_every": 3, "params": None, "near_field": False}
    out = lab.run_trial(1, opts, 7)
    motion, sensor = doc_rng(7, 5, 1).spawn(2)
    np.testing.assert_array_equal(seen["truth"], walk(with_people(load_scene("lab"), 2), 3, motion))
    np.testing.assert_array_equal(seen["sensor"], sensor.random(3))
    assert configs[0] == LoopConfig("uniform", 16, near_field=False)
    assert configs[1:] == [LoopConfig(t, k, m, 3, near_field=False)
                           for t, m in (("uniform", 1), ("greedy", 1), ("incremental", 2)) for k in (4, 6)]
    assert out == {"areas": {"uniform:4": 15.0, "uniform:6": 17.0, "greedy:4": 15.0, "greedy:6": 17.0,
                             "incremental:4": 25.0, "incremental:6": 27.0},
                   "min_full": 1.0, "mean_full": 2.0, "cameras": 16}
