"""camtask render datasets: layout, manifest checksums, same bytes for any worker count or on an existing cluster,
resume after a kill, exact silhouettes, ground-truth hulls, lossless video, bad input."""

import hashlib
import json
import shutil

import blake3
import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from testbed.cli import main
from testbed.dataset import read_people

pytestmark = pytest.mark.render

ARGS = ["render", "lab", "--episodes", "2", "--frames", "2", "--seed", "4", "--cameras", "2,7,11"]


def files_of(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(root.rglob("*"))
            if p.is_file() and p.name != "run_info.json"}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    out = tmp_path_factory.mktemp("ds") / "data"
    assert main(ARGS + ["--out", str(out), "--workers", "0"]) == 0
    return out


def test_layout_and_manifest(dataset, lab):
    m = json.loads((dataset / "manifest.json").read_text())
    assert [e["name"] for e in m["episodes"]] == ["episode_0000", "episode_0001"]
    assert m["config"]["seed"] == 4 and m["config"]["frames"] == 2 and m["episodes_planned"] == 2
    assert m["format_version"] == 2 and m["episode_layout"] == 3 and m["checksum"] == "blake3"
    for e in m["episodes"]:
        ep = dataset / e["name"]
        assert e["frames"] == 2 and e["spawn_key"] == [e["index"]] and e["seed"] == 4
        on_disk = sorted(p.relative_to(ep).as_posix() for p in ep.rglob("*") if p.is_file())
        assert on_disk == sorted(e["files"])
        for rel, digest in e["files"].items():
            assert blake3.blake3((ep / rel).read_bytes()).hexdigest() == digest
        for sub in ("frames", "masks", "silhouettes"):
            assert sorted(p.name for p in (ep / sub / "cam07").iterdir()) == ["000000.png", "000001.png"]
        assert {"calibration/cam11.yaml", "background/cam02.png", "people.csv", "meta.json", "scanlines.npz",
                "pipeline.yaml", "gt_hull.json"} <= set(e["files"])
        with np.load(ep / "scanlines.npz") as z:
            assert z["scanlines"].shape == z["gt_scanlines"].shape == (2, 3, 640)
            assert z["scanlines"].dtype == bool and z["bearings"].shape == (3, 640)
            assert z["camera_numbers"].tolist() == [2, 7, 11]
    assert not list(dataset.glob(".*tmp")) and not list(dataset.glob(".*lock"))   # the run's lock removed
    info = json.loads((dataset / "run_info.json").read_text())
    assert "started" in info and "versions" in info
    # different episodes walk differently
    a, b = (read_people(dataset / n / "people.csv") for n in ("episode_0000", "episode_0001"))
    assert not np.array_equal(a["x"], b["x"])


def test_gt_hull_contains_every_person(dataset, lab):
    from tasking import visual_hull_of_scanlines

    ep = dataset / "episode_0001"
    hull = json.loads((ep / "gt_hull.json").read_text())
    people = read_people(ep / "people.csv")
    scan = np.load(ep / "scanlines.npz")
    index = {c.number: i for i, c in enumerate(lab.cameras)}
    xy = lab.floor_poses()[0][[index[n] for n in scan["camera_numbers"]]]
    assert [f["frame"] for f in hull["frames"]] == [0, 1]
    for rec in hull["frames"]:
        # docs/dataset.md: the hull of the true scanlines beyond each camera's blind radius
        again = visual_hull_of_scanlines(xy, scan["bearings"], scan["gt_scanlines"][rec["frame"]],
                                         lab.room.polygon, near=scan["gt_blind_radius"])
        assert again.area == pytest.approx(rec["area"], abs=1e-9)
        polys = shapely.MultiPolygon([shapely.Polygon(p["exterior"], p["holes"]) for p in rec["polygons"]])
        # the area is the hull's; its vertices are stored rounded to 1e-6 m
        assert polys.area == pytest.approx(rec["area"], abs=polys.length * 1e-6)
        for row in people[people["frame"] == rec["frame"]]:
            assert polys.buffer(1e-6).contains(shapely.Point(row["x"], row["y"]))
            disc = shapely.Point(row["x"], row["y"]).buffer(row["radius"], quad_segs=64)
            assert disc.difference(polys).area < 5e-5                  # column quantisation


def test_silhouettes_equal_each_person_rendered_alone(dataset, lab):
    import cv2

    from testbed.episodes import EpisodeConfig, _renderer, load_episode_scene

    config = EpisodeConfig("lab", None, (2, 7, 11), 2, 4)
    renderer = _renderer(config, load_episode_scene(config))
    ep = dataset / "episode_0000"
    people = read_people(ep / "people.csv")
    for f in (0, 1):
        rows = people[people["frame"] == f]
        pos = np.column_stack([rows["x"], rows["y"]]).astype(float)
        for n in (2, 7, 11):
            sil = cv2.imread(str(ep / "silhouettes" / f"cam{n:02d}" / f"{f:06d}.png"), cv2.IMREAD_UNCHANGED)
            labels = cv2.imread(str(ep / "masks" / f"cam{n:02d}" / f"{f:06d}.png"), cv2.IMREAD_UNCHANGED)
            for i in range(len(pos)):
                alone = np.full_like(pos, np.nan)
                alone[i] = pos[i]
                want = renderer.render(alone, cameras=[n], clean=True).labels[0] > 0
                np.testing.assert_array_equal((sil >> i) & 1 == 1, want)
                assert not ((labels == i + 1) & ~want).any()


def test_silhouettes_exact_when_people_overlap(lab):
    """Two people one behind the other: the occluded one's silhouette is still whole."""
    from testbed.episodes import EpisodeConfig, _renderer, load_episode_scene, silhouettes

    config = EpisodeConfig("lab", None, (2, 7, 11), 1, 0)
    r = _renderer(config, load_episode_scene(config))
    pos = np.array([[2.0, 2.0], [2.3, 2.9], [4.0, 4.0]])
    fr = r.render(pos, clean=True)
    sil = silhouettes(r, pos, fr.labels)
    for i in range(3):
        alone = np.full_like(pos, np.nan)
        alone[i] = pos[i]
        np.testing.assert_array_equal((sil >> i) & 1 == 1, r.render(alone, clean=True).labels > 0)
    assert any(((sil >> i) & 1).sum() > (fr.labels == i + 1).sum() for i in range(3))   # someone is occluded


@pytest.mark.parametrize("gap", [0.0, 0.005, 0.0199, 0.0201, 0.05, 0.5])
def test_silhouettes_exact_for_people_close_together(lab, gap):
    """Two people ``gap`` metres apart (disc to disc), in every camera: where the nearer
    one is taken from the labels (gap > APART) and where both are re-rendered."""
    from testbed.episodes import EpisodeConfig, _renderer, load_episode_scene, silhouettes

    config = EpisodeConfig("lab", None, None, 1, 0)
    scene = load_episode_scene(config)
    r = _renderer(config, scene)
    d = 2 * scene.people.radius + gap
    pos = np.array([[3.0, 2.5], [3.0 + d * np.cos(0.7), 2.5 + d * np.sin(0.7)], [np.nan, np.nan]])
    labels = r.labels(pos)
    sil = silhouettes(r, pos, labels)
    for i in range(2):
        alone = np.full_like(pos, np.nan)
        alone[i] = pos[i]
        np.testing.assert_array_equal((sil >> i) & 1 == 1, r.labels(alone) > 0)
    assert not (sil >> 2).any()
    assert any(((sil >> i) & 1).sum() > (labels == i + 1).sum() for i in range(2))   # someone is occluded


def test_silhouettes_exact_with_sixteen_bit_masks():
    """Ten people (uint16 bitmasks, a look-up table per camera plus re-rendered overlaps)."""
    from testbed.episode import walk
    from testbed.episodes import EpisodeConfig, _renderer, load_episode_scene, silhouettes

    config = EpisodeConfig("lab", 10, (2, 7, 11), 1, 0)
    scene = load_episode_scene(config)
    r = _renderer(config, scene)
    pos = walk(scene, 1, np.random.default_rng(5))[0]
    sil = silhouettes(r, pos, r.labels(pos))
    assert sil.dtype == np.uint16
    for i in range(10):
        alone = np.full_like(pos, np.nan)
        alone[i] = pos[i]
        np.testing.assert_array_equal((sil >> i) & 1 == 1, r.labels(alone) > 0)
    assert sil.any()


class BoxRig:
    """What :func:`testbed.episodes.silhouettes` asks of a renderer, made by hand: one camera
    above the floor's origin, each person's canvas box and what rendering them alone gives
    (a boolean image); ``rendered`` records who was rendered alone."""

    def __init__(self, boxes, alone, radius=0.1):
        from types import SimpleNamespace

        self.numbers = [1]
        self.cameras = [SimpleNamespace(center_world=np.array([0.0, 0.0, 2.2]))]
        self.scene = SimpleNamespace(people=SimpleNamespace(radius=radius))
        self.boxes, self.alone, self.rendered = np.asarray(boxes, float), alone, []

    def _rects(self, idx, pos):
        return self.boxes[None].copy()

    def labels(self, pos, cameras):
        (i,) = np.flatnonzero(np.isfinite(pos).all(axis=1))
        self.rendered.append(i)
        return (self.alone[i] * (i + 1)).astype(np.uint8)[None]


def _two_side_by_side(gap, front_label):
    """Person 0 at 1 m from the camera, person 1 behind them ``gap`` metres further (disc to
    disc); alone, person 0 covers columns 0-5 and person 1 columns 5-11, so their boxes share
    column 5, which the frame's labels give to ``front_label``."""
    alone = np.zeros((2, 4, 12), bool)
    alone[0, :, :6] = alone[1, :, 5:] = True
    labels = np.where(alone[0], 1, 0) + np.where(alone[1] & ~alone[0], 2, 0)
    labels[:, 5] = front_label
    rig = BoxRig([[0, 0, 5, 3], [5, 0, 11, 3]], alone)
    pos = np.array([[1.0, 0.0], [1.0 + 0.2 + gap, 0.0]])
    return rig, pos, labels.astype(np.uint8)[None], alone


def _bits(sil, i):
    return (sil[0] >> i) & 1 == 1


@pytest.mark.parametrize("gap", [0.0, 0.01, 0.0199, -0.05])
def test_silhouettes_rerender_people_closer_than_apart(gap):
    """Within 2 radius + APART the frame's labels may give the farther person a pixel of
    the nearer one (depths too close to resolve): both are rendered alone, even where their
    boxes only share one column."""
    from testbed.episodes import silhouettes

    rig, pos, labels, alone = _two_side_by_side(gap, front_label=2)
    sil = silhouettes(rig, pos, labels)
    assert sil.dtype == np.uint8
    for i in range(2):
        np.testing.assert_array_equal(_bits(sil, i), alone[i])
    assert sorted(rig.rendered) == [0, 1]


def test_silhouettes_take_the_nearer_persons_labels_beyond_apart():
    """2 radius + APART apart the nearer person's labels are exact: only the one behind is rendered alone."""
    from testbed.episodes import silhouettes

    rig, pos, labels, alone = _two_side_by_side(0.0201, front_label=1)
    sil = silhouettes(rig, pos, labels)
    for i in range(2):
        np.testing.assert_array_equal(_bits(sil, i), alone[i])
    assert rig.rendered == [1]


def test_silhouettes_render_nobody_alone_whose_boxes_meet_no_one():
    """Boxes in the same columns but rows apart: each person's labels are their silhouette."""
    from testbed.episodes import silhouettes

    alone = np.zeros((2, 8, 12), bool)
    alone[0, :3, 2:9] = alone[1, 5:, 4:11] = True
    labels = (alone[0] * 1 + alone[1] * 2).astype(np.uint8)[None]
    rig = BoxRig([[2, 0, 8, 2], [4, 5, 10, 7]], alone)
    sil = silhouettes(rig, np.array([[2.0, 0.0], [1.0, 0.0]]), labels)   # person 1 the nearer
    for i in range(2):
        np.testing.assert_array_equal(_bits(sil, i), alone[i])
    assert rig.rendered == []


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 12), st.integers(1, 37), st.booleans(), st.floats(0.0, 1.0), st.integers(0, 2**32 - 1))
def test_or_lookup_equals_a_look_up_table_and_a_masked_or(h, w, wide, fill, seed):
    """The silhouettes' compiled look-up: table[label] ORed in where the label is not 0,
    the rest left alone, for any width (not only multiples of 8) and 16-bit masks."""
    from testbed.label_kernel import or_lookup

    rng = np.random.default_rng(seed)
    dtype = np.uint16 if wide else np.uint8
    labels = np.where(rng.random((h, w)) < fill, rng.integers(1, 256, (h, w)), 0).astype(np.uint8)
    table = rng.integers(0, 65536 if wide else 256, 256).astype(dtype)
    out = rng.integers(0, 65536 if wide else 256, (h, w)).astype(dtype)
    want = np.where(labels != 0, out | table[labels], out)
    assert or_lookup(labels, table, out) is out
    np.testing.assert_array_equal(out, want)
    with pytest.raises(ValueError, match="table: expected"):
        or_lookup(labels, table.astype(np.uint32), out)


def test_background_pngs_are_encoded_once_per_renderer(tmp_path, monkeypatch):
    """A process's later episodes write the background PNGs encoded for its first (same
    bytes); a renderer made anew (another process, an evicted cache) encodes its own."""
    from collections import OrderedDict

    from testbed import episodes

    encoded = []
    real = episodes.encode_png
    monkeypatch.setattr(episodes, "encode_png", lambda img: encoded.append(1) or real(img))
    monkeypatch.setattr(episodes, "_BACKGROUNDS", OrderedDict())
    config = episodes.EpisodeConfig("lab", 1, (2, 7), 1, 3)
    runs = []
    for index in range(2):
        runs.append(episodes.render_episode(config, index, str(tmp_path))["files"])
    assert len(encoded) == 2                                   # two cameras, once
    fresh = OrderedDict()
    with monkeypatch.context() as m:
        m.setattr(episodes, "_RENDERERS", fresh)
        runs.append(episodes.render_episode(config, 2, str(tmp_path))["files"])
    for r in fresh.values():
        r.close()
    assert len(encoded) == 4
    for cam in ("cam02", "cam07"):
        assert len({files[f"background/{cam}.png"] for files in runs}) == 1
        assert (tmp_path / "episode_0000" / "background" / f"{cam}.png").read_bytes() == \
            (tmp_path / "episode_0002" / "background" / f"{cam}.png").read_bytes()


def test_same_bytes_with_two_workers(dataset, tmp_path):
    out = tmp_path / "two"
    assert main(ARGS + ["--out", str(out), "--workers", "2"]) == 0
    a, b = files_of(dataset), files_of(out)
    assert sorted(a) == sorted(b)
    assert [k for k in a if a[k] != b[k]] == []


def test_same_bytes_on_an_existing_cluster(dataset, tmp_path):
    from testbed.parallel import open_client

    out = tmp_path / "sched"
    # a cluster of this process, reached by its address (a plain LocalCluster would leave
    # Dask's MALLOC_TRIM_THRESHOLD_ in os.environ for every later cluster of the session)
    with open_client(1) as client:
        assert main(ARGS + ["--out", str(out), "--scheduler", client.scheduler.address]) == 0
    a, b = files_of(dataset), files_of(out)
    assert sorted(a) == sorted(b)
    assert [k for k in a if a[k] != b[k]] == []


def test_overlapped_writing_gives_the_same_files(tmp_path):
    """Frames consumed on a second thread (in-process runs on several cores) or inline: same bytes."""
    from testbed.episodes import EpisodeConfig, render_episode

    config = EpisodeConfig("lab", None, (2, 7), 3, 9)
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
    counts = {True: [], False: []}
    a = render_episode(config, 0, str(tmp_path / "a"), counts[True].append, overlap=True)
    b = render_episode(config, 0, str(tmp_path / "b"), counts[False].append, overlap=False)
    assert a == b
    assert counts[True] == counts[False] == [1, 1, 1]            # every frame counted once


def test_closing_the_videos_closes_each_and_raises_the_first_failure():
    """Every writer is closed even when one fails; the first failure is raised, none while
    another exception is under way (it would hide the one that stopped the episode)."""
    from testbed.episodes import _Frames

    closed = []

    class Writer:
        def __init__(self, name, error=None):
            self.name, self.error = name, error

        def close(self):
            closed.append(self.name)
            if self.error:
                raise OSError(self.error)

    frames = object.__new__(_Frames)
    frames.videos = [Writer("cam01"), Writer("cam02", "No space left on device"), Writer("cam03", "second")]
    with pytest.raises(OSError, match="^No space left on device$"):
        frames.close_videos()
    assert closed == ["cam01", "cam02", "cam03"]
    closed.clear()
    with pytest.raises(KeyError):
        try:
            raise KeyError("render failed")
        finally:
            frames.close_videos()
    assert closed == ["cam01", "cam02", "cam03"]


def test_each_parameter_set_gets_its_own_pipeline_on_one_rig():
    """A process keeps a pipeline per rig and parameter set: an episode of other params is not
    processed by the pipeline of the last ones."""
    from pipeline import PipelineParams
    from testbed import episodes

    made = {}
    for threshold in (55.0, 40.0, 55.0):
        config = episodes.with_scene_text(episodes.EpisodeConfig("lab", 1, (2,), 1, 0,
                                                                 params={"column_threshold": threshold}))
        scene = episodes.load_episode_scene(config)
        params = PipelineParams.from_mapping(config.params)
        pipe = episodes._episode_pipeline(config, scene, episodes._renderer(config, scene), params)
        assert pipe.params.column_threshold == threshold
        made.setdefault(threshold, pipe)
        assert made[threshold] is pipe                      # the same parameters: the pipeline kept


def test_an_episode_of_every_camera_names_them_in_the_scene_files_order(tmp_path, lab):
    """Cameras left out: meta.json, scanlines.npz and gt_hull.json name all 16, in the lab file's order."""
    from testbed.episodes import EpisodeConfig, render_episode

    render_episode(EpisodeConfig("lab", 1, None, 1, 0), 0, str(tmp_path))
    ep = tmp_path / "episode_0000"
    numbers = [c.number for c in lab.cameras]
    assert numbers == list(range(1, 17))
    assert json.loads((ep / "meta.json").read_text())["cameras"] == numbers
    assert json.loads((ep / "gt_hull.json").read_text())["cameras"] == numbers
    with np.load(ep / "scanlines.npz") as z:
        assert z["camera_numbers"].tolist() == numbers


def test_an_episode_rendered_again_replaces_its_folder(tmp_path):
    """A retried task whose first run got as far as the rename: the second run's folder replaces it."""
    from testbed.episodes import EpisodeConfig, render_episode

    config = EpisodeConfig("lab", 1, (2,), 1, 3)
    first = render_episode(config, 0, str(tmp_path))
    (tmp_path / "episode_0000" / "stale.txt").write_text("left by the first run")
    again = render_episode(config, 0, str(tmp_path))
    assert again == first
    assert sorted(p.relative_to(tmp_path / "episode_0000").as_posix()
                  for p in (tmp_path / "episode_0000").rglob("*") if p.is_file()) == sorted(first["files"])
    assert [p.name for p in tmp_path.iterdir()] == ["episode_0000"]


def test_stage_seconds_add_up_over_episodes(tmp_path):
    """One ``seconds`` dict given to several episodes sums every stage, the total included."""
    from testbed.episodes import EpisodeConfig, render_episode

    config = EpisodeConfig("lab", None, (2, 7), 1, 9)
    secs: dict = {}
    render_episode(config, 0, str(tmp_path), seconds=secs)
    first = dict(secs)
    render_episode(config, 1, str(tmp_path), seconds=secs)
    assert set(secs) == set(first) == {"render", "silhouettes", "write", "pipeline", "hull", "finish", "total"}
    assert all(secs[k] > first[k] for k in first)
    assert secs["total"] >= sum(v for k, v in secs.items() if k != "total")   # inline: the stages are parts of it


@pytest.mark.parametrize("overlap", [True, False])
def test_a_failure_mid_episode_leaves_nothing(tmp_path, monkeypatch, overlap):
    from testbed import episodes

    calls = {"n": 0}
    real = episodes.write_png

    def failing(path, image):
        calls["n"] += 1
        if calls["n"] == 12:                      # 2 backgrounds, then 6 images a frame: frame 1 of 0-2
            raise OSError(f"cannot write {path}: No space left on device")
        return real(path, image)

    monkeypatch.setattr(episodes, "write_png", failing)
    with pytest.raises(OSError, match="No space left"):
        episodes.render_episode(episodes.EpisodeConfig("lab", None, (2, 7), 3, 9), 0, str(tmp_path),
                                overlap=overlap)
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_mid_run_is_one_line_and_keeps_the_finished_episodes(tmp_path, monkeypatch, capsys):
    from testbed import episodes

    real = episodes.write_png

    def failing(path, image):
        if "episode_0001" in str(path):
            raise OSError(f"cannot write {path}: No space left on device")
        return real(path, image)

    monkeypatch.setattr(episodes, "write_png", failing)
    out = tmp_path / "data"
    assert main(["render", "lab", "--episodes", "3", "--frames", "1", "--cameras", "2", "--out", str(out),
                 "--workers", "0"]) == 1
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("camtask render: error: cannot write ") and err.endswith(
        f"No space left on device; stopped with 1 of 3 episodes finished, listed in {out / 'manifest.json'} "
        "(--resume finishes the run)")
    assert sorted(p.name for p in out.iterdir()) == ["episode_0000", "manifest.json", "run_info.json"]
    monkeypatch.setattr(episodes, "write_png", real)
    assert main(["render", "lab", "--episodes", "3", "--frames", "1", "--cameras", "2", "--out", str(out),
                 "--workers", "0", "--resume"]) == 0
    assert main(["verify", str(out)]) == 0


def test_resume_redoes_only_unfinished_episodes(dataset, tmp_path):
    out = tmp_path / "killed"
    shutil.copytree(dataset, out)
    kept = out / "episode_0000" / "frames" / "cam02" / "000000.png"
    before = kept.stat().st_mtime_ns
    shutil.rmtree(out / "episode_0001")                       # killed before episode 1 was renamed...
    shutil.copytree(out / "episode_0000", out / ".episode_0001.abcd.tmp")   # ...with its temp folder left
    shutil.rmtree(out / ".episode_0001.abcd.tmp" / "masks")
    assert main(ARGS + ["--out", str(out), "--workers", "0"]) == 2          # refused without --resume
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 0
    assert kept.stat().st_mtime_ns == before                   # episode 0 was not redone
    assert files_of(out) == files_of(dataset)
    # a corrupt file is caught by its checksum and its episode redone
    (out / "episode_0001" / "people.csv").write_text("garbage")
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 0
    assert kept.stat().st_mtime_ns == before
    assert files_of(out) == files_of(dataset)
    # other arguments are refused
    assert main(["render", "lab", "--episodes", "2", "--frames", "3", "--seed", "4", "--cameras", "2,7,11",
                 "--out", str(out), "--workers", "0", "--resume"]) == 2


def test_resume_with_more_episodes_extends_a_run_to_the_bytes_of_a_longer_one(dataset, tmp_path, capsys):
    out, fresh = tmp_path / "extended", tmp_path / "fresh"
    shutil.copytree(dataset, out)
    more = [a if a != "2" or i != 3 else "3" for i, a in enumerate(ARGS)]       # --episodes 3
    assert more[2:4] == ["--episodes", "3"]
    assert main(more + ["--out", str(out), "--workers", "0", "--resume"]) == 0
    assert main(more + ["--out", str(fresh), "--workers", "0"]) == 0
    assert files_of(out) == files_of(fresh)
    capsys.readouterr()
    fewer = more[:3] + ["1"] + more[4:]
    assert main(fewer + ["--out", str(out), "--workers", "0", "--resume"]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == (
        "camtask render: error: --resume: --episodes 1, but the run planned 3: it can extend a run, not shrink it")


def test_resume_reports_its_verification_per_episode(dataset, tmp_path):
    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import prepare_output, read_manifest

    out = tmp_path / "data"
    shutil.copytree(dataset, out)
    m = read_manifest(out)
    calls = []
    config = EpisodeConfig("lab", None, (2, 7, 11), 2, 4, "png", load_params().to_dict())   # as ARGS
    keep = prepare_output(out, config, 2, True, False, lambda files, total: calls.append((files, total)))
    sizes = [len(e["files"]) for e in m["episodes"]]
    assert sorted(keep) == [0, 1] and calls == [(n, sum(sizes)) for n in sizes]


def test_resume_keeps_the_episodes_of_a_sha256_manifest(dataset, tmp_path, capsys):
    """sha256 digests (no ``checksum`` key) of this layout: intact episodes kept, their checksums renewed;
    a real format-1 manifest (no ``episode_layout`` either) is verified but not resumed."""
    out = tmp_path / "old"
    shutil.copytree(dataset, out)
    m = json.loads((out / "manifest.json").read_text())
    old = {k: v for k, v in m.items() if k != "checksum"} | {"format_version": 1}
    for e in old["episodes"]:
        e["files"] = {rel: hashlib.sha256((out / e["name"] / rel).read_bytes()).hexdigest() for rel in e["files"]}
    (out / "manifest.json").write_text(json.dumps(old))
    kept = out / "episode_0000" / "frames" / "cam02" / "000000.png"
    before = kept.stat().st_mtime_ns
    (out / "episode_0001" / "people.csv").write_text("garbage")    # caught by its sha256
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 0
    assert kept.stat().st_mtime_ns == before                       # episode 0 kept, not redone
    assert files_of(out) == files_of(dataset)                      # episode 1 redone; manifest of format 2
    old["checksum"] = "md5"
    (out / "manifest.json").write_text(json.dumps(old))
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 2
    del old["checksum"], old["episode_layout"]
    for e in old["episodes"]:
        e["files"] = {rel: hashlib.sha256((out / e["name"] / rel).read_bytes()).hexdigest() for rel in e["files"]}
    (out / "manifest.json").write_text(json.dumps(old))
    capsys.readouterr()
    assert main(["verify", str(out)]) == 0 and "2 episodes intact" in capsys.readouterr().out
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 2
    assert "are of layout 1 (an earlier camtask)" in capsys.readouterr().err


def test_verify_names_what_differs_from_the_manifest(dataset, tmp_path, capsys):
    out = tmp_path / "copy"
    shutil.copytree(dataset, out)
    assert main(["verify", str(out)]) == 0
    assert "2 episodes intact" in capsys.readouterr().out
    ep = out / "episode_0001"
    (ep / "people.csv").write_text("garbage")
    (ep / "masks" / "cam07" / "000001.png").unlink()
    (ep / "notes.txt").write_text("mine")
    shutil.copytree(ep / "calibration", out / ".episode_0002.abcd.tmp")
    assert main(["verify", str(out)]) == 1
    text = capsys.readouterr().out
    assert ("episode_0001: 1 missing (masks/cam07/000001.png); 1 changed (people.csv); 1 extra (notes.txt)"
            in text)
    assert not any(line.startswith("episode_0000") for line in text.splitlines())   # intact: not named
    assert ".episode_0002.abcd.tmp" in text and "1 of 2 episodes differ" in text
    for text, problem in (("[]", "expected a JSON object, got list"), ("null", "expected a JSON object, got null"),
                          ('{"episodes": [{"index": 0}]}', "episodes[0] lacks an integer index")):
        (out / "manifest.json").write_text(text)                 # valid JSON, not a manifest: one line
        assert main(["verify", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and f"(not a camtask manifest: {problem}" in err
    (out / "manifest.json").unlink()
    assert main(["verify", str(out)]) == 2
    assert "no manifest.json" in capsys.readouterr().err


@pytest.mark.parametrize("change, problem", [
    ({"episodes_planned": None}, "episodes_planned is None, expected an integer >= 0"),
    ({"episodes_planned": "many"}, "episodes_planned is 'many', expected an integer >= 0"),
    ({"episode_layout": [3]}, "episode_layout is [3], expected an integer >= 1"),
    ({"name": "../elsewhere"}, "episodes[0] is named '../elsewhere', expected 'episode_0000' for its index"),
    ({"name": "/etc"}, "episodes[0] is named '/etc', expected 'episode_0000' for its index"),
    ({"index": 1, "name": "episode_0001"}, "episodes[1]: index 1 listed twice"),
    ({"index": -1}, "episodes[0]: index -1, expected >= 0"),
])
def test_a_manifest_with_wrong_values_is_one_line_for_verify_and_resume(dataset, tmp_path, capsys, change, problem):
    """A manifest's names are folders of DIR: never a path elsewhere (verify hashed /etc, resume skipped work)."""
    out = tmp_path / "copy"
    shutil.copytree(dataset, out)
    m = json.loads((out / "manifest.json").read_text())
    top = {k: v for k, v in change.items() if k in m}
    m.update(top)
    m["episodes"][0].update({k: v for k, v in change.items() if k not in top})
    (out / "manifest.json").write_text(json.dumps(m))
    for argv in (["verify", str(out)], ARGS + ["--out", str(out), "--workers", "0", "--resume"]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and err.endswith(f"(not a camtask manifest: {problem})")
    assert files_of(out) == files_of(dataset) | {"manifest.json": files_of(out)["manifest.json"]}


def test_video_format_is_lossless(dataset, tmp_path, capsys):
    import cv2

    from testbed.lossless import read_video

    out = tmp_path / "video"
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--format", "video", "--episodes", "1"]) == 0
    ep, png = out / "episode_0000", dataset / "episode_0000"
    assert not (ep / "frames" / "cam07").exists()
    for n in (2, 7, 11):
        frames = list(read_video(ep / "frames" / f"cam{n:02d}.mkv"))
        assert len(frames) == 2
        for f, rgb in enumerate(frames):
            want = cv2.cvtColor(cv2.imread(str(png / "frames" / f"cam{n:02d}" / f"{f:06d}.png")), cv2.COLOR_BGR2RGB)
            np.testing.assert_array_equal(rgb, want)
    assert (ep / "masks" / "cam02" / "000001.png").read_bytes() == (png / "masks" / "cam02" / "000001.png").read_bytes()
    again = tmp_path / "video2"
    assert main(ARGS + ["--out", str(again), "--workers", "0", "--format", "video", "--episodes", "1"]) == 0
    assert files_of(out) == files_of(again)


def test_scanlines_and_tune_read_a_video_episode_as_its_png_twin(dataset, tmp_path, capsys):
    """They refused a --format video episode ("this reads PNG frames: render with --format png"):
    its scanlines.npz could not be made again, nor its parameters tuned, without rendering it again."""
    out = tmp_path / "video"
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--format", "video", "--episodes", "1"]) == 0
    results = {}
    for name, ep in (("png", dataset / "episode_0000"), ("video", out / "episode_0000")):
        npz, yaml = tmp_path / f"{name}.npz", tmp_path / f"{name}.yaml"
        assert main(["scanlines", str(ep), "--params", str(ep / "pipeline.yaml"), "--out", str(npz), "--json"]) == 0
        assert main(["tune", str(ep), "--trials", "2", "--frames", "2", "--out", str(yaml), "--json"]) == 0
        tuned = json.loads(capsys.readouterr().out.splitlines()[-1])
        with np.load(npz) as z, np.load(ep / "scanlines.npz") as recorded:
            assert z.files == recorded.files
            for key in ("scanlines", "gt_scanlines"):   # the render's own, bit for bit (docs/dataset.md)
                np.testing.assert_array_equal(z[key], recorded[key], err_msg=f"{name} {key}")
            results[name] = ({k: z[k] for k in z.files}, tuned["best_f1"], tuned["start_f1"], tuned["params"])
    for key, value in results["png"][0].items():
        np.testing.assert_array_equal(results["video"][0][key], value, err_msg=key)
    assert results["video"][1:] == results["png"][1:]


def test_disk_estimate_covers_an_episode(dataset, lab):
    from testbed.episodes import EpisodeConfig
    from testbed.generate import estimate_bytes

    used = sum(p.stat().st_size for p in (dataset / "episode_0000").rglob("*") if p.is_file())
    estimate = estimate_bytes(EpisodeConfig("lab", None, (2, 7, 11), 2, 4), lab, 1)
    assert used <= estimate <= 1.5 * used


def test_too_little_disk_for_the_run_warns_and_renders(tmp_path, capsys, monkeypatch):
    import collections

    from testbed import generate

    one = 2 * 1 * 640 * 480 * 3 * generate.DISK_FRACTION        # one episode: a frame and the background
    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(generate.shutil, "disk_usage", lambda path: usage(10**12, 0, int(1.5 * one)))
    out = tmp_path / "ds"
    argv = ["render", "lab", "--episodes", "2", "--frames", "1", "--cameras", "3", "--workers", "0", "--out", str(out)]
    assert main(argv) == 0
    err = capsys.readouterr().err
    assert "warning: --out: 1.66 MB free on" in err and "2 episodes need about 2.21 MB" in err
    assert len(json.loads((out / "manifest.json").read_text())["episodes"]) == 2


def test_saved_radii_are_the_pipelines_and_the_truths_for_a_persons_width(dataset, lab):
    """scanlines.npz: blind and sight radii of the pipeline's scanlines, and the (wider) ones
    of the true scanlines, for a person 1.75 m high and 0.5 m across (the lab's people)."""
    from pipeline import Pipeline, PipelineParams

    with np.load(dataset / "episode_0000" / "scanlines.npz") as z:
        radii = {k: z[k] for k in ("blind_radius", "sight_radius", "gt_blind_radius", "gt_sight_radius")}
    cams = [c for c in lab.cameras if c.number in (2, 7, 11)]
    pipe = Pipeline(cams, PipelineParams())
    for truth, near, far in ((False, "blind_radius", "sight_radius"), (True, "gt_blind_radius", "gt_sight_radius")):
        want = pipe.sight_range(1.75, truth=truth, object_width=0.5)
        np.testing.assert_array_equal(radii[near], want[0])
        np.testing.assert_array_equal(radii[far], want[1])
    assert (radii["gt_blind_radius"] < radii["blind_radius"]).all()     # the truth needs one row, not several
    assert (radii["gt_sight_radius"] > radii["sight_radius"]).all()


def test_people_walk_on_the_first_stream_of_their_episodes_seed(dataset, lab):
    """docs/dataset.md: episode e of seed S walks on default_rng(SeedSequence(S).spawn(E)[e]).spawn(2)[0]."""
    from testbed.episode import walk

    motion = np.random.default_rng(np.random.SeedSequence(4).spawn(2)[1]).spawn(2)[0]
    track = walk(lab, 2, motion)
    people = read_people(dataset / "episode_0001" / "people.csv")
    for f in (0, 1):
        rows = people[people["frame"] == f]
        np.testing.assert_array_equal(np.column_stack([rows["x"], rows["y"]]), track[f])


def test_meta_json_records_the_scene_as_rendered(dataset, lab):
    """meta.json: the people and cameras rendered (the lab's 3 people when --people is left
    out), the seed's spawn key, the frame step, the scene file's text and the silhouettes' PNG type."""
    from scene.config import scene_path

    meta = json.loads((dataset / "episode_0001" / "meta.json").read_text())
    assert (meta["episode"], meta["seed"], meta["spawn_key"], meta["frames"]) == (1, 4, [1], 2)
    assert (meta["people"], meta["cameras"], meta["scene"], meta["format"]) == (3, [2, 7, 11], "lab", "png")
    assert meta["dt"] == lab.dt and meta["scene_yaml"] == scene_path("lab").read_text()
    assert meta["silhouettes"] == "bit i = person i, uint8 PNG"


def test_each_cameras_background_png_is_its_own_empty_room(dataset):
    import cv2

    from testbed.episodes import EpisodeConfig, _renderer, load_episode_scene

    config = EpisodeConfig("lab", None, (2, 7, 11), 2, 4)
    background = _renderer(config, load_episode_scene(config)).background().rgb
    for k, n in enumerate((2, 7, 11)):
        png = cv2.imread(str(dataset / "episode_0000" / "background" / f"cam{n:02d}.png"), cv2.IMREAD_COLOR)
        np.testing.assert_array_equal(png[..., ::-1], background[k])
    assert not np.array_equal(background[0], background[1])


def test_saved_scanlines_come_from_the_saved_frames_and_masks(dataset):
    """The episode is self-consistent: its frames, masks, background and pipeline.yaml
    give its scanlines and ground-truth scanlines through the public Pipeline API."""
    from pipeline import Pipeline, load_params
    from pipeline.io import RenderDir

    ep = dataset / "episode_0001"
    r = RenderDir(ep)
    pipe = Pipeline(r.cameras, load_params(ep / "pipeline.yaml"), r.background())
    with np.load(ep / "scanlines.npz") as z:
        saved, saved_gt, bearings = z["scanlines"], z["gt_scanlines"], z["bearings"]
    for f in range(len(r)):
        np.testing.assert_array_equal(pipe.process(r.frames(f)), saved[f])
        np.testing.assert_array_equal(pipe.ground_truth(r.labels(f))[1], saved_gt[f])
    np.testing.assert_allclose(pipe.bearings, bearings, rtol=0, atol=1e-12)   # calibration YAML round trip
    assert saved_gt.any()


def test_scanlines_and_tune_leave_an_episode_as_its_manifest_says(dataset, tmp_path, capsys, monkeypatch):
    """On an episode of a dataset, `camtask scanlines` and `camtask tune` need --out (a
    replaced scanlines.npz failed `camtask verify`); with it, the episode stays intact."""
    ep = dataset / "episode_0000"
    before = files_of(dataset)
    capsys.readouterr()
    assert main(["scanlines", str(ep)]) == 2
    assert main(["tune", str(ep), "--trials", "1"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert [line.count(f"{ep} is an episode of the dataset {dataset}") for line in err] == [1, 1]
    assert "give --out FILE to write scanlines.npz elsewhere" in err[0]
    assert "give --out FILE to write tuned_params.yaml elsewhere" in err[1]
    assert main(["tune", str(dataset), "--trials", "1"]) == 2               # two episodes: which one?
    assert f"{dataset} is a dataset of 2 episodes" in capsys.readouterr().err
    monkeypatch.chdir(ep)                                                     # the episode named "."
    assert main(["scanlines", "."]) == 2 and main(["tune", ".", "--trials", "1"]) == 2
    assert capsys.readouterr().err.count(f". is an episode of the dataset {dataset.resolve()}") == 2
    monkeypatch.chdir(tmp_path)
    assert main(["scanlines", str(ep), "--out", str(tmp_path / "s.npz"), "--json"]) == 0
    assert files_of(dataset) == before
    assert main(["verify", str(dataset)]) == 0
    with np.load(tmp_path / "s.npz") as new, np.load(ep / "scanlines.npz") as saved:
        np.testing.assert_array_equal(new["scanlines"], saved["scanlines"])   # same frames, same parameters


def test_resuming_a_finished_run_needs_no_disk_space(dataset, tmp_path, capsys, monkeypatch):
    import collections

    from testbed import generate

    out = tmp_path / "done"
    shutil.copytree(dataset, out)
    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(generate.shutil, "disk_usage", lambda path: usage(10**12, 10**12, 0))
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 0
    assert "all 2 episodes already finished" in capsys.readouterr().err
    m = json.loads((out / "manifest.json").read_text())
    (out / "manifest.json").write_text(json.dumps(m | {"episodes": []}))   # both to be redone: refused
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 2
    assert "--out: 0 MB free on" in capsys.readouterr().err


def test_two_scene_files_of_one_text_keep_their_own_names(tmp_path):
    """A scene without ``name`` is named after its file (meta.json's "scene"): a process that
    parsed one copy first still names the other after its own file, as a fresh process would."""
    from scene.config import scene_path
    from testbed.episodes import EpisodeConfig, load_episode_scene

    text = "\n".join(line for line in scene_path("lab").read_text().splitlines() if not line.startswith("name:"))
    for name in ("room_a", "room_b"):
        (tmp_path / f"{name}.yaml").write_text(text)
    names = [load_episode_scene(EpisodeConfig(str(tmp_path / f"{n}.yaml"), 1, (2,), 1, 5)).name
             for n in ("room_a", "room_b", "room_a")]
    assert names == ["room_a", "room_b", "room_a"]


def test_a_scene_file_edited_between_runs_is_rendered_as_edited(tmp_path, monkeypatch):
    """A process keeps its renderers from run to run (the workers of a long-lived cluster):
    they are keyed by the scene file's text, not its path. A run reads the text once."""
    from collections import OrderedDict

    from scene.config import scene_path
    from testbed import episodes

    text = scene_path("lab").read_text()
    edited = text.replace("yaw_deg: 70.5", "yaw_deg: 60.0")      # camera 2 turned
    assert edited != text
    scene = tmp_path / "room.yaml"
    scene.write_text(text)
    config = episodes.EpisodeConfig(str(scene), 1, (2,), 1, 5)
    started = episodes.with_scene_text(config)                  # a run started before the edit

    def run(name, cfg):
        (tmp_path / name).mkdir()
        return episodes.render_episode(cfg, 0, str(tmp_path / name))["files"]

    before = run("before", config)
    scene.write_text(edited)
    after = run("after", config)
    assert run("started", started) == before                    # the text read when its run started
    fresh = OrderedDict()
    with monkeypatch.context() as m:                            # the edited scene in a new process's caches
        for name in ("_SCENES", "_RECTIFIERS", "_PIPELINES"):
            m.setattr(episodes, name, OrderedDict())
        m.setattr(episodes, "_RENDERERS", fresh)
        want = run("fresh", config)
    for r in fresh.values():
        r.close()
    assert after == want
    for rel in ("frames/cam02/000000.png", "background/cam02.png", "calibration/cam02.yaml", "meta.json"):
        assert after[rel] != before[rel]


def test_resume_refuses_a_scene_file_edited_since(tmp_path, capsys):
    from scene.config import scene_path

    text = scene_path("lab").read_text()
    scene = tmp_path / "room.yaml"
    scene.write_text(text)
    out = tmp_path / "ds"
    argv = ["render", str(scene), "--episodes", "2", "--frames", "1", "--cameras", "3", "--people", "1",
            "--workers", "0", "--out", str(out)]
    assert main(argv) == 0
    shutil.rmtree(out / "episode_0001")                           # as if the run had been killed
    m = (out / "manifest.json").read_bytes()
    scene.write_text(text.replace("noise_std: 2.0", "noise_std: 3.0"))
    capsys.readouterr()
    assert main(argv + ["--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]       # after the bar of the episode verified
    assert err == (f"camtask render: error: --resume: {scene} is not the scene episode_0000 was rendered from "
                   "(its meta.json's scene_yaml); restore it, or use --overwrite to start again")
    assert (out / "manifest.json").read_bytes() == m and (out / "episode_0000").is_dir()
    scene.write_text(text)
    assert main(argv + ["--resume"]) == 0
    assert len(json.loads((out / "manifest.json").read_text())["episodes"]) == 2


def test_process_caches_keep_the_most_recent_and_close_the_rest():
    from collections import OrderedDict

    from testbed.episodes import _cached

    closed = []

    class Thing:
        def __init__(self, name):
            self.name = name

        def close(self):
            closed.append(self.name)

    cache = OrderedDict()
    made = [_cached(cache, k, lambda k=k: Thing(k), keep=2).name for k in ("a", "b", "a", "c")]
    assert made == ["a", "b", "a", "c"] and list(cache) == ["a", "c"] and closed == ["b"]   # "a" was used last
    assert _cached(cache, "a", lambda: Thing("new")).name == "a"                            # kept, not remade


def test_files_under_lists_and_sorts_like_rglob(tmp_path):
    from testbed.episodes import files_under

    for rel in ("b", "a-b/x", "a/b", "a/c/d", "a.b", "a/c-d", "A", "a/c/e/f"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(rel)
    (tmp_path / "empty").mkdir()
    (tmp_path / "a" / "link").symlink_to(tmp_path / "b")
    want = [p.relative_to(tmp_path).as_posix() for p in sorted(tmp_path.rglob("*")) if p.is_file()]
    assert files_under(tmp_path) == want
    assert want.index("a/c/e/f") < want.index("a/c-d") < want.index("a-b/x")   # by component, not by string


def test_files_under_does_not_follow_a_link_to_a_folder_and_sorts_the_others(tmp_path):
    """A link to a folder is not walked into: it is one of the other entries, which come
    sorted by path components like the files."""
    from testbed.episodes import files_under

    for rel in ("a/c/f", "a-b/g", "d/h"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(rel)
    (tmp_path / "a-b" / "to_d").symlink_to(tmp_path / "d", target_is_directory=True)
    (tmp_path / "a" / "c" / "gone").symlink_to(tmp_path / "nowhere")
    (tmp_path / "a" / "x").symlink_to(tmp_path / "nowhere")
    others = []
    assert files_under(tmp_path, others) == ["a/c/f", "a-b/g", "d/h"]
    assert others == ["a/c/gone", "a/x", "a-b/to_d"]                    # "a/..." before "a-b/...": by component


def test_checksums_take_the_known_digests_and_read_the_rest(tmp_path):
    from testbed.episodes import checksums

    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "a.png").write_bytes(b"written")
    (tmp_path / "b.csv").write_bytes(b"frame\n")
    got = checksums(tmp_path, {"sub/a.png": "f" * 64})
    assert got == {"b.csv": blake3.blake3(b"frame\n").hexdigest(), "sub/a.png": "f" * 64}
    assert list(got) == ["b.csv", "sub/a.png"]
    assert checksums(tmp_path, algorithm="sha256")["sub/a.png"] == hashlib.sha256(b"written").hexdigest()


def test_episode_config_to_dict_is_the_manifests_config(tmp_path):
    """docs/dataset.md: config holds scene, people, cameras, frames, seed, format and the pipeline
    params; the cameras in number order, the params a copy."""
    from testbed.episodes import EpisodeConfig

    params = {"threshold": 0.3}
    config = EpisodeConfig("lab", 2, (11, 2, 7), 3, 5, "video", params, scene_yaml="name: x\n")
    d = config.to_dict()
    assert d == {"scene": "lab", "people": 2, "cameras": [2, 7, 11], "frames": 3, "seed": 5, "format": "video",
                 "params": {"threshold": 0.3}}
    d["params"]["threshold"] = 0.5
    assert config.params == {"threshold": 0.3}
    assert EpisodeConfig("lab", None, None, 1, 0).to_dict()["cameras"] is None


def test_save_npz_exact_is_a_compressed_npz_of_fixed_dates(tmp_path):
    import zipfile

    from testbed.episodes import save_npz_exact

    zeros, ramp = np.zeros((64, 640), bool), np.arange(12.0).reshape(3, 4)
    save_npz_exact(tmp_path / "a.npz", big=zeros, ramp=ramp)
    with np.load(tmp_path / "a.npz") as z:
        assert z.files == ["big", "ramp"]
        np.testing.assert_array_equal(z["big"], zeros)
        np.testing.assert_array_equal(z["ramp"], ramp)
    with zipfile.ZipFile(tmp_path / "a.npz") as zf:
        for info in zf.infolist():
            assert info.date_time == (1980, 1, 1, 0, 0, 0)
            assert info.compress_type == zipfile.ZIP_DEFLATED
        assert zf.getinfo("big.npy").compress_size < zeros.size // 20          # 40960 bytes of zeros, deflated


@pytest.mark.parametrize(("people", "dtype"), [(0, np.uint8), (8, np.uint8), (9, np.uint16), (16, np.uint16)])
def test_silhouette_dtype_holds_one_bit_per_person(people, dtype):
    from testbed.episodes import silhouette_dtype

    assert silhouette_dtype(people) is dtype
    assert np.iinfo(dtype).bits >= people


def test_silhouette_dtype_refuses_more_than_sixteen_people():
    from testbed.episodes import silhouette_dtype

    with pytest.raises(ValueError, match=r"^--count: silhouettes store one bit per person in a 16-bit PNG; "
                                         r"expected at most 16, got 17$"):
        silhouette_dtype(17, "--count")


def test_resume_keeps_the_earlier_runs_record_and_warns_of_other_versions(dataset, tmp_path, capsys):
    import numpy

    out = tmp_path / "resumed"
    shutil.copytree(dataset, out)
    shutil.rmtree(out / "episode_0001")
    info = json.loads((out / "run_info.json").read_text())
    info["versions"]["numpy"] = "1.0.0"                   # as if rendered with another numpy
    (out / "run_info.json").write_text(json.dumps(info))
    capsys.readouterr()
    assert main(ARGS + ["--out", str(out), "--workers", "0", "--resume"]) == 0
    err = capsys.readouterr().err
    assert (f"warning: --resume: other package versions than the run before (numpy 1.0.0 then, "
            f"{numpy.__version__} now): the episodes it rendered may differ from this run's in their bytes") in err
    now = json.loads((out / "run_info.json").read_text())
    assert now["earlier_runs"] == [info]
    assert list(now["episode_hosts"]) == ["episode_0001"] and list(info["episode_hosts"]) == [
        "episode_0000", "episode_0001"]
    assert files_of(out) == files_of(dataset)


def test_datasets_and_exports_get_the_permissions_of_the_umask(tmp_path):
    """No 0700 folder or 0600 file: others on a shared machine read what the umask lets them."""
    import os
    import stat

    data, wild = tmp_path / "data", tmp_path / "wild"
    old = os.umask(0o022)
    try:
        assert main(["render", "lab", "--frames", "1", "--cameras", "3", "--out", str(data), "--workers", "0"]) == 0
        assert main(["export", "wildtrack", str(data), str(wild)]) == 0
    finally:
        os.umask(old)
    for root in (data, wild):
        modes = {p.relative_to(tmp_path).as_posix(): stat.S_IMODE(p.stat().st_mode)
                 for p in [root, *root.rglob("*")]}
        assert "data/manifest.json" in modes or "wild/grid.json" in modes
        wrong = {k: oct(m) for k, m in modes.items() if m != (0o755 if (tmp_path / k).is_dir() else 0o644)}
        assert wrong == {}


def test_overwrite_replaces_a_dataset(dataset, tmp_path):
    out = tmp_path / "data"
    shutil.copytree(dataset, out)
    assert main(["render", "lab", "--frames", "1", "--seed", "5", "--cameras", "2", "--out", str(out), "--workers", "0",
                 "--overwrite"]) == 0
    m = json.loads((out / "manifest.json").read_text())
    assert [e["name"] for e in m["episodes"]] == ["episode_0000"] and m["config"]["seed"] == 5
    assert sorted(p.name for p in out.iterdir()) == ["episode_0000", "manifest.json", "run_info.json"]
    assert main(["verify", str(out)]) == 0


def test_the_loading_example_of_the_docs_runs(dataset):
    """docs/dataset.md's five lines, as written, on a dataset (camera 3 -> one it has)."""
    from pathlib import Path

    text = (Path(__file__).resolve().parent.parent / "docs" / "dataset.md").read_text()
    code = text.split("## Loading an episode", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    scope = {}
    exec(code.replace("DIR", str(dataset)).replace("cam03", "cam02"), scope)  # noqa: S102 (our own docs)
    assert scope["meta"]["cameras"] == [2, 7, 11] and scope["rgb"].shape == (480, 640, 3)
    assert scope["sil"].shape == (480, 640) and scope["sil"].dtype == np.uint8
    assert {"scanlines", "gt_scanlines", "bearings"} <= set(scope["scan"].files)


def test_the_order_of_the_cameras_given_does_not_matter(dataset, tmp_path):
    out = tmp_path / "reordered"
    reordered = [a if a != "2,7,11" else "11,2,7" for a in ARGS]
    assert main(reordered + ["--out", str(out), "--workers", "0"]) == 0
    assert files_of(out) == files_of(dataset)


def test_no_more_worker_processes_than_episodes(tmp_path):
    # one episode runs in this process (--help: "0, or a single episode to render, runs in this process")
    out = tmp_path / "data"
    assert main(["render", "lab", "--frames", "1", "--cameras", "2", "--workers", "6", "--out", str(out)]) == 0
    assert json.loads((out / "run_info.json").read_text())["workers"] == 0
    out = tmp_path / "two"
    assert main(["render", "lab", "--episodes", "2", "--frames", "1", "--cameras", "2", "--workers", "6",
                 "--out", str(out)]) == 0
    assert json.loads((out / "run_info.json").read_text())["workers"] == 2


def test_a_resume_starts_no_more_worker_processes_than_episodes_left(tmp_path, monkeypatch):
    """The count came from --episodes: extending a run by one episode started a local
    cluster of W processes (4.0 s against 1.9 s in this process), and resuming a finished
    run started one only to say that it was finished."""
    from testbed import parallel

    out = tmp_path / "data"
    args = ["render", "lab", "--frames", "1", "--cameras", "2", "--out", str(out), "--workers", "6"]
    assert main(args) == 0
    asked = []
    real = parallel.open_client

    def spy(workers=None, scheduler=None, **kw):
        asked.append(workers)
        return real(workers, scheduler, **kw)

    monkeypatch.setattr(parallel, "open_client", spy)
    assert main(args + ["--episodes", "2", "--resume"]) == 0                    # one episode left
    assert json.loads((out / "run_info.json").read_text())["workers"] == 0 and asked == [0]
    asked.clear()
    assert main(args + ["--episodes", "2", "--resume"]) == 0                    # none left
    assert not any(asked)


def test_resume_refuses_the_episodes_of_an_earlier_layout(dataset, tmp_path, capsys):
    """Episodes without blind radii (layout 1: no ``episode_layout`` in the manifest) are not
    mixed with this layout's: a resume is refused in one line, nothing touched."""
    out = tmp_path / "old"
    shutil.copytree(dataset, out)
    m = json.loads((out / "manifest.json").read_text())
    del m["episode_layout"]
    (out / "manifest.json").write_text(json.dumps(m))
    before = files_of(out)
    capsys.readouterr()
    assert main(ARGS + ["--episodes", "3", "--out", str(out), "--workers", "0", "--resume"]) == 2
    assert "are of layout 1 (an earlier camtask), this camtask writes layout 3" in capsys.readouterr().err
    assert files_of(out) == before


def test_the_scenes_own_people_and_cameras_given_are_the_run_without_them(tmp_path, capsys):
    """--people 3 on the lab's 3 people, --cameras of all 16: the same episodes, so the same run (manifest
    bytes equal) and --resume takes either; an earlier manifest that recorded people: 3 is resumed too."""
    base = ["render", "lab", "--frames", "1", "--seed", "2", "--workers", "0"]
    plain, given = tmp_path / "plain", tmp_path / "given"
    assert main(base + ["--episodes", "1", "--out", str(plain)]) == 0
    every = ",".join(str(n) for n in range(16, 0, -1))
    assert main(base + ["--episodes", "1", "--people", "3", "--cameras", every, "--out", str(given)]) == 0
    assert files_of(given) == files_of(plain)
    assert json.loads((given / "manifest.json").read_text())["config"]["people"] is None
    assert main(base + ["--episodes", "2", "--people", "3", "--out", str(plain), "--resume"]) == 0
    # a manifest written with people: 3 and every camera listed
    m = json.loads((given / "manifest.json").read_text())
    m["config"] |= {"people": 3, "cameras": list(range(1, 17))}
    (given / "manifest.json").write_text(json.dumps(m))
    assert main(base + ["--episodes", "2", "--out", str(given), "--resume"]) == 0
    assert files_of(given) == files_of(plain)
    # other people are another run, named as before
    capsys.readouterr()
    assert main(base + ["--episodes", "2", "--people", "2", "--out", str(given), "--resume"]) == 2
    assert "people: None then, 2 now" in capsys.readouterr().err
