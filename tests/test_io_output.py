"""testbed.output.made_folder: the folders made for an output, removed again when the command stops."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from testbed.output import check_output_file, made_folder


def test_made_folders_stay_when_the_block_succeeds(tmp_path):
    with made_folder("OUT", tmp_path / "a" / "b") as f:
        assert f == tmp_path / "a" / "b" and f.is_dir()
    assert (tmp_path / "a" / "b").is_dir()


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_made_folders_go_when_the_block_fails_and_nothing_else_does(tmp_path, error):
    (tmp_path / "a").mkdir()
    with pytest.raises(error), made_folder("OUT", tmp_path / "a" / "b" / "c"):
        raise error
    assert os.listdir(tmp_path / "a") == []              # b and c made here: gone; a was there: kept


def test_a_folder_something_else_wrote_into_is_kept(tmp_path):
    with pytest.raises(RuntimeError), made_folder("OUT", tmp_path / "a" / "b"):
        (tmp_path / "a" / "other").write_text("x")
        raise RuntimeError
    assert os.listdir(tmp_path) == ["a"] and os.listdir(tmp_path / "a") == ["other"]


def test_without_keep_the_folders_go_in_any_case(tmp_path):
    with made_folder("--out", tmp_path / "a" / "b", keep=False):
        pass
    assert os.listdir(tmp_path) == []


def test_a_folder_that_cannot_be_made_is_one_line_naming_the_option(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match=r"^--plot: cannot make the folder .*afile/sub \(") as err, \
            made_folder("--plot", tmp_path / "afile" / "sub"):
        pass
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match=r"^OUT: cannot make the folder .*/new/x+ \(File name too long\)$"), \
            made_folder("OUT", tmp_path / "new" / ("x" * 300)):
        pass
    assert sorted(os.listdir(tmp_path)) == ["afile"]


def test_a_folder_that_cannot_be_looked_at_is_not_removed_nor_a_traceback(tmp_path, monkeypatch):
    """On a network file system even root may be refused a look (EACCES): that is not a missing folder."""
    real = Path.exists
    hidden = tmp_path / "hidden"
    hidden.mkdir()

    def exists(self, *args, **kwargs):
        if self == hidden:
            raise PermissionError(13, "Permission denied", str(self))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, "exists", exists)
    assert check_output_file("--out", hidden / "new" / "s.npz") == hidden / "new" / "s.npz"
    monkeypatch.undo()
    assert hidden.is_dir() and os.listdir(hidden) == []


def test_export_and_check_output_file_leave_no_folders(tmp_path, monkeypatch):
    """Both go through the helper: a checked output file and a failed export leave no folders."""
    from testbed.wildtrack import export_episode

    assert check_output_file("--out", tmp_path / "a" / "b" / "x.npz").name == "x.npz"
    assert os.listdir(tmp_path) == []
    episode = tmp_path / "ep"
    episode.mkdir()
    lab = (Path(__file__).parents[1] / "assets" / "scenes" / "lab.yaml").read_text()
    (episode / "meta.json").write_text(json.dumps({"cameras": [1], "frames": 1, "people": 0, "scene_yaml": lab}))
    seen = []
    calibration = {"K": np.eye(3), "dist": np.zeros(5), "rvec": np.zeros(3), "tvec": np.zeros(3),
                   "width": 4, "height": 3}

    def unwritable(path, **mats):               # the first file written once the folders are made
        seen.append((tmp_path / "deep" / "er").is_dir())
        raise OSError(f"cannot write {path}")

    monkeypatch.setattr("testbed.wildtrack.read_calibrations", lambda ep, numbers: {1: calibration})
    monkeypatch.setattr("testbed.wildtrack._write_fs", unwritable)
    with pytest.raises(OSError, match="intr_C1.xml"):
        export_episode(episode, tmp_path / "deep" / "er" / "wt")
    assert seen == [True] and os.listdir(tmp_path) == ["ep"]


def test_an_output_in_a_file_taken_for_a_folder_is_one_line(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match=r"^--out: cannot write to .*afile \(not a folder\)$"):
        check_output_file("--out", tmp_path / "afile" / "x.npz")
    assert check_output_file("--out", tmp_path / "x.npz") == tmp_path / "x.npz"      # the folder exists
    assert check_output_file("--plot", tmp_path / "X.PNG", ".png") == tmp_path / "X.PNG"
    assert os.listdir(tmp_path) == ["afile"]


def _dataset(root: Path, manifest: str) -> Path:
    (root / "episode_0000").mkdir(parents=True)
    (root / "manifest.json").write_text(manifest)
    return root


def test_the_episode_of_a_path_is_a_folder_named_episode_beside_a_manifest(tmp_path):
    from testbed.output import episode_of

    ds = _dataset(tmp_path / "ds", "{}")
    episode = ds / "episode_0000"
    assert episode_of(episode / "frames" / "x.png") == episode
    assert episode_of(episode) is None and episode_of(episode, itself=True) == episode
    assert episode_of(ds / "episode_0001.png") is None                  # beside the episodes, not in one
    (ds / "other").mkdir()
    assert episode_of(ds / "other" / "x.png") is None                   # beside the manifest, not an episode
    (tmp_path / "episode_0007").mkdir()
    assert episode_of(tmp_path / "episode_0007" / "x.png") is None      # no manifest beside it


def test_a_damaged_manifest_beside_episodes_is_a_dataset_and_another_manifest_is_not(tmp_path):
    from testbed.output import check_outside_dataset

    ds = _dataset(tmp_path / "ds", "{not json")
    with pytest.raises(ValueError, match=r"^--out: .*x.png is in the dataset .*ds, beside its manifest.json"):
        check_outside_dataset("--out", ds / "x.png")
    (tmp_path / "web").mkdir()
    (tmp_path / "web" / "manifest.json").write_text("{not json")
    check_outside_dataset("--out", tmp_path / "web" / "x.png")            # no episodes: not a dataset


def test_figures_are_written_whole_at_their_dpi_and_closed(tmp_path):
    """A 2 x 1 inch figure at the default 80 dpi is 160 x 80 pixels."""
    import cv2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from testbed.output import figure_png, save_figure

    fig = plt.figure(figsize=(2, 1))
    png = figure_png(fig)
    assert not plt.fignum_exists(fig.number)
    assert cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_UNCHANGED).shape[:2] == (80, 160)
    fig = plt.figure(figsize=(2, 1))
    save_figure(fig, tmp_path / "new" / "f.png")
    assert not plt.fignum_exists(fig.number)
    assert cv2.imread(str(tmp_path / "new" / "f.png")).shape[:2] == (80, 160)
    assert os.listdir(tmp_path / "new") == ["f.png"]


def test_counts_are_ticked_in_whole_numbers_also_for_one_value():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from testbed.output import count_axis

    fig, ax = plt.subplots()
    ax.plot([4], [0.5], "o")
    count_axis(ax.xaxis)
    fig.canvas.draw()
    lo, hi = ax.get_xlim()
    ticks = [t for t in ax.get_xticks() if lo <= t <= hi]
    plt.close(fig)
    assert ticks and all(t == round(t) for t in ticks)


def test_an_output_that_is_a_folder_is_named_a_folder(tmp_path):
    (tmp_path / "plots").mkdir()
    with pytest.raises(ValueError, match=r"^--out: .*plots is a folder; expected a file name$"):
        check_output_file("--out", tmp_path / "plots")


def test_an_output_beside_a_datasets_manifest_is_refused(tmp_path):
    ds = _dataset(tmp_path / "ds", json.dumps({"format_version": 2, "episodes": []}))
    with pytest.raises(ValueError, match=r"^--out: .*run_info.json is in the dataset .*ds, beside its manifest.json"):
        check_output_file("--out", ds / "run_info.json")
    assert check_output_file("--out", tmp_path / "run_info.json") == tmp_path / "run_info.json"


def test_an_output_reached_through_a_link_to_an_episode_is_refused(tmp_path):
    """The episode is found where the path leads, not by the names written in it."""
    from testbed.output import episode_of

    episode = _dataset(tmp_path / "ds", "{}") / "episode_0000"
    (tmp_path / "link").symlink_to(episode, target_is_directory=True)
    assert episode_of(tmp_path / "link" / "x.npz") == episode
    with pytest.raises(ValueError, match=r"^--out: .*link/x.npz is inside .*episode_0000, an episode of the dataset"):
        check_output_file("--out", tmp_path / "link" / "x.npz")
    # and a path that names an episode but leaves it again is not in it
    assert episode_of(episode / ".." / "x.npz") is None


def test_only_folders_named_episode_underscore_beside_a_manifest_file_are_episodes(tmp_path):
    from testbed.output import episode_of

    ds = _dataset(tmp_path / "ds", "{}")
    (ds / "episodes").mkdir()
    assert episode_of(ds / "episodes" / "x.png") is None
    (tmp_path / "other" / "manifest.json").mkdir(parents=True)       # a folder of that name is no manifest
    (tmp_path / "other" / "episode_0000").mkdir()
    assert episode_of(tmp_path / "other" / "episode_0000" / "x.png") is None


def test_a_stale_probe_file_of_this_process_is_reused_and_removed(tmp_path):
    """A killed run can leave its probe file behind; a new process of the same id writes over it."""
    from testbed.output import PROBE, check_writable

    (tmp_path / f"{PROBE}write-test.{os.getpid()}").write_text("stale")
    check_writable("--out", tmp_path)
    assert os.listdir(tmp_path) == []


def test_figures_are_saved_at_the_dpi_given(tmp_path):
    """A 2 x 1 inch figure at 40 dpi is 80 x 40 pixels."""
    import cv2
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from testbed.output import save_figure

    save_figure(plt.figure(figsize=(2, 1)), tmp_path / "f.png", dpi=40)
    assert cv2.imread(str(tmp_path / "f.png")).shape[:2] == (40, 80)


def test_the_reasons_a_folder_is_refused_are_the_systems_words_alone(tmp_path):
    """No errno, no path twice, and no OSError chained below the one line."""
    from testbed.output import check_writable

    with pytest.raises(ValueError, match=r"^--out: cannot write to /proc \([A-Z][a-z ]+\)$") as err:
        check_writable("--out", "/proc")
    assert err.value.__suppress_context__
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ValueError, match=r"^OUT: cannot make the folder .*afile/sub \(Not a directory\)$") as err, \
            made_folder("OUT", tmp_path / "afile" / "sub"):
        pass
    assert err.value.__suppress_context__


def test_an_output_through_a_link_to_a_file_of_a_dataset_is_refused(tmp_path):
    """A link is written through (its target replaced), so where it leads is what counts."""
    ds = _dataset(tmp_path / "ds", json.dumps({"format_version": 2, "episodes": []}))
    (tmp_path / "m.json").symlink_to(ds / "manifest.json")
    with pytest.raises(ValueError, match=r"^--out: .*m.json is in the dataset .*ds, beside its manifest.json"):
        check_output_file("--out", tmp_path / "m.json")
    (tmp_path / "x.npz").symlink_to(ds / "episode_0000" / "x.npz")          # dangling: x.npz is not made yet
    with pytest.raises(ValueError, match=r"^--out: .*/x.npz is inside .*episode_0000, an episode of the dataset"):
        check_output_file("--out", tmp_path / "x.npz")
    assert sorted(os.listdir(tmp_path)) == ["ds", "m.json", "x.npz"] and os.listdir(ds / "episode_0000") == []


def test_the_episode_of_a_dataset_inside_an_episode_is_the_nearest(tmp_path):
    from testbed.output import episode_of

    outer = _dataset(tmp_path / "ds", "{}") / "episode_0000"
    inner = _dataset(outer / "copy", "{}") / "episode_0000"
    assert episode_of(inner / "x.png") == inner and episode_of(outer / "x.png") == outer


def test_beside_a_damaged_manifest_only_episode_folders_make_a_dataset(tmp_path):
    """A file named episode_* is no episode; a folder of a five-digit episode is."""
    from testbed.output import check_outside_dataset

    (tmp_path / "manifest.json").write_text("{not json")
    (tmp_path / "episode_notes.txt").write_text("x")
    check_outside_dataset("--out", tmp_path / "x.png")
    (tmp_path / "episode_12345").mkdir()
    with pytest.raises(ValueError, match=r"^--out: .*x.png is in the dataset "):
        check_outside_dataset("--out", tmp_path / "x.png")


def test_a_figure_is_png_whatever_format_matplotlib_saves_by_default():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from testbed.output import figure_png

    with matplotlib.rc_context({"savefig.format": "pdf"}):
        png = figure_png(plt.figure(figsize=(1, 1)))
    assert png.startswith(b"\x89PNG\r\n\x1a\n")


def test_a_figure_that_cannot_be_drawn_is_closed_all_the_same(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from testbed.output import save_figure

    fig = plt.figure(figsize=(1, 1))
    fig.text(0.5, 0.5, r"$\nosuchsymbol$")                  # mathtext fails as the figure is drawn
    with pytest.raises(ValueError, match="nosuchsymbol"):
        save_figure(fig, tmp_path / "f.png")
    assert not plt.fignum_exists(fig.number) and os.listdir(tmp_path) == []
