"""Study ``lab``: taskers on the rendered lab (the paper's figure 13).

Each trial draws a walk of ``--people`` people in the lab (or ``--scene``), renders all
its cameras (16 in the lab) every frame and turns every frame into a scanline with the
node pipeline (nodes process all the time; only tasked nodes *send*). Every tasker and k then runs the closed loop on
exactly these scanlines. The residual is the paper's: the time-averaged hull area
(after removing polygons smaller than one person) divided by the minimum hull area
reached with all the cameras over the run. The result's ``scene`` is the scene's ``name``.
"""

from __future__ import annotations

import numpy as np

from . import core

STUDY_ID = 5
DEFAULT_TRIALS = 2


#: The taskers this study can compare (optimal would compare C(16, k) subsets every frame).
TASKERS = tuple(t for t in core.TASKERS if t != "optimal")


def add_arguments(p) -> None:
    p.add_argument("--scene", default="lab", help="calibrated scene file or built-in name (default lab)")
    p.add_argument("--people", type=int, default=3, help="people walking (default 3, as the paper)")
    core.add_k(p, "6,8,10")
    core.add_taskers(p, "uniform,greedy,incremental", TASKERS)
    p.add_argument("--frames", type=int, default=40, help="frames per trial (default 40, 5.3 s)")
    core.add_update(p, 1)
    p.add_argument("--params", metavar="FILE", help="pipeline parameters YAML (default assets/pipeline/default.yaml)")
    p.add_argument("--no-near-field", dest="near_field", action="store_false",
                   help="carve the hulls from each camera's centre, not only beyond its blind radius")


def parse(args) -> dict:
    from pipeline import load_params
    from pipeline.params import params_option
    from pipeline.rectify import check_column_threshold
    from scene import load_scene
    from testbed.episode import check_people_renderable, check_renderable, with_people
    from testbed.memory import check_fits

    scene = with_people(load_scene(args.scene), args.people)
    check_renderable(scene, "--scene")
    core.check_count("people", args.people)
    check_people_renderable(scene, "--people")
    ks = core.parse_k(args.k, len(scene.cameras), f"the scene's {len(scene.cameras)}")
    taskers = core.parse_names("taskers", args.taskers, TASKERS)
    core.check_count("frames", args.frames)
    update_every = core.check_period(args.update_every, 1, taskers)
    m = core.check_m(args.m, ks if "incremental" in taskers else [])
    check_column_threshold(load_params(args.params, "--params").column_threshold, scene.cameras,
                           params_option(args.params))
    # a trial keeps every camera's scanline of every frame (stacked: twice, for a moment)
    check_fits("--frames", args.frames, "frames", 2 * sum(c.width for c in scene.cameras) + 16 * args.people,
               "in each trial (every camera's scanlines of every frame)")
    return {"scene": args.scene, "people": args.people, "k": ks, "taskers": taskers,
            "frames": args.frames, "m": m, "update_every": update_every, "params": args.params,
            "near_field": args.near_field}


def render_scanlines(scene, params, truth: np.ndarray, rng) -> tuple:
    """All cameras' scanlines over the walk: (frames, n_cams, W) bool, bearings (n_cams, W)
    radians, blind and sight radii (n_cams,) metres each."""
    from pipeline import Pipeline
    from render import Renderer

    with Renderer(scene) as renderer:
        pipe = Pipeline(scene.cameras, params, background=renderer.background().rgb)
        scans = np.stack([pipe.process(renderer.render(p, rng=rng).rgb) for p in truth])
    return scans, pipe.bearings, *pipe.sight_range(scene.people.height, object_width=2 * scene.people.radius)


def run_trial(trial: int, opts: dict, seed: int) -> dict:
    """One walk: mean hull area per (tasker, k) and the minimum all-camera hull area."""
    from pipeline import load_params
    from scene import load_scene
    from testbed.episode import walk, with_people
    from testbed.loop import LoopConfig, PrecomputedSource, run_loop

    scene = with_people(load_scene(opts["scene"]), opts["people"])
    motion_rng, sensor_rng = core.trial_rng(seed, STUDY_ID, trial).spawn(2)
    truth = walk(scene, opts["frames"], motion_rng)
    scans, bearings, near, far = render_scanlines(scene, load_params(opts["params"], "--params"), truth, sensor_rng)
    source = PrecomputedSource(scans, bearings, near, far)
    n = len(scene.cameras)
    near_field = opts.get("near_field", True)
    full = [r.hull_area for r in run_loop(scene, LoopConfig("uniform", n, near_field=near_field), truth, source)]
    areas = {}
    for tasker in opts["taskers"]:
        for k in opts["k"]:
            m = opts["m"] if tasker == "incremental" else 1           # --m: incremental's alone
            config = LoopConfig(tasker, k, m, opts["update_every"] or 1, near_field=near_field)   # uniform: None
            areas[f"{tasker}:{k}"] = float(np.mean([r.hull_area for r in run_loop(scene, config, truth, source)]))
    return {"areas": areas, "min_full": float(np.min(full)), "mean_full": float(np.mean(full)), "cameras": n}


def run(opts: dict, trials: int, seed: int, runner) -> dict:
    from scene import load_scene

    per_trial = runner(run_trial, [(t, opts, seed) for t in range(trials)], [1] * trials, "lab")
    empty = [i for i, t in enumerate(per_trial) if t["min_full"] <= 0]
    if empty:                                   # the residual's denominator
        raise ValueError(f"--scene: the hull of all its cameras was empty in a frame of trial {empty[0]}, so the "
                         "residual (hull area / the smallest all-camera hull) is undefined")
    records = []
    for tasker in opts["taskers"]:
        for k in opts["k"]:
            values = [t["areas"][f"{tasker}:{k}"] / t["min_full"] for t in per_trial]
            mean, sem = core.mean_sem(values)
            records.append({"tasker": tasker, "k": k, "residual": mean, "residual_sem": sem, "trials": trials})
    full = float(np.mean([t["mean_full"] / t["min_full"] for t in per_trial]))
    return {"records": records, "all_cameras_residual": full, "cameras": per_trial[0]["cameras"],
            "scene": load_scene(opts["scene"]).name}


def every_camera(n: int) -> str:
    """``all 16 cameras``, or ``the one camera`` of a one-camera scene."""
    return "the one camera" if n == 1 else f"all {n} cameras"


def format_table(result: dict) -> str:
    n = result["cameras"]
    title = f"Normalised residual hull area on {result['scene']} (hull area / min {n}-camera area):"
    return (core.tasker_table(result["records"], title, digits=3)
            + f"\n{every_camera(n)}: {result['all_cameras_residual']:.3f}")


def plot(result: dict, path: str) -> None:
    n = result["cameras"]
    core.plot_taskers(result["records"], path, f"Fig. 13: taskers on the rendered {result['scene']}",
                      f"hull area / min {n}-camera area",
                      reference=(result["all_cameras_residual"], every_camera(n)))
