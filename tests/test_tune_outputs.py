"""Where `camtask tune` may write: never over a dataset's own files."""

import json
import re

import pytest

from tests.test_pipeline_cli import camtask, small_render_dir


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    return small_render_dir(tmp_path_factory.mktemp("render"), 3, 4)


@pytest.fixture
def dataset(tmp_path):
    """A dataset's top folder: a camtask manifest beside an episode."""
    root = tmp_path / "ds"
    (root / "episode_0000").mkdir(parents=True)
    entry = {"index": 0, "name": "episode_0000", "frames": 1, "files": {}}
    (root / "manifest.json").write_text(json.dumps({"episodes": [entry], "episodes_planned": 1}))
    (root / "run_info.json").write_text("{}")
    return root


@pytest.mark.parametrize("argv", [
    ["--out", "{ds}/manifest.json"],                    # the dataset's checksums, replaced by YAML
    ["--out", "{ds}/run_info.json"],
    ["--out", "{ds}/episode_best.yaml"],                # taken for a stopped run's: --resume deletes it
    ["--out", "{tmp}/t.yaml", "--plot", "{ds}/episode_0001.png"],
])
def test_an_output_beside_a_datasets_manifest_is_refused(render_dir, dataset, tmp_path, argv):
    before = {p.name: p.read_bytes() for p in dataset.iterdir() if p.is_file()}
    argv = ["tune", str(render_dir), "--trials", "1"] + [a.format(ds=dataset, tmp=tmp_path) for a in argv]
    with pytest.raises(ValueError, match=r"^--(out|plot): .* is in the dataset .*ds, beside its manifest.json"):
        camtask(argv)
    assert {p.name: p.read_bytes() for p in dataset.iterdir() if p.is_file()} == before
    assert not (tmp_path / "t.yaml").exists()


def test_a_folder_with_another_manifest_json_is_no_dataset(render_dir, tmp_path):
    (tmp_path / "manifest.json").write_text('{"name": "a web extension"}')
    assert camtask(["tune", str(render_dir), "--trials", "1", "--out", str(tmp_path / "t.yaml"), "--json"]) == 0
    assert (tmp_path / "t.yaml").is_file()


def test_out_and_plot_naming_one_file_are_refused(render_dir, tmp_path):
    with pytest.raises(ValueError, match=r"^--out and --plot: both name .*t.png; expected two files"):
        camtask(["tune", str(render_dir), "--trials", "1", "--out", str(tmp_path / "t.png"),
                 "--plot", str(tmp_path / "t.png")])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", [
    ["scanlines", "{rd}", "--out", "{ds}/manifest.json"],        # replaced the checksums with an .npz
    ["run", "lab", "--frames", "1", "--video", "{ds}/episode_run.mp4"],
    ["study", "static", "--trials", "1", "--plot", "{ds}/run_info.png"],
])
def test_every_command_refuses_an_output_beside_a_datasets_manifest(render_dir, dataset, command, capsys):
    """Not only tune: `scanlines EP --out DS/manifest.json` destroyed the dataset's manifest."""
    from testbed import cli

    before = {p.name: p.read_bytes() for p in dataset.iterdir() if p.is_file()}
    assert cli.main([a.format(ds=dataset, rd=render_dir) for a in command]) == 2
    err = capsys.readouterr().err
    assert re.match(rf"^camtask {command[0]}: error: --(out|video|plot): .* is in the dataset .*ds, beside its "
                    r"manifest.json", err), err
    assert {p.name: p.read_bytes() for p in dataset.iterdir() if p.is_file()} == before


@pytest.mark.parametrize("command, default", [(["tune", "--trials", "1"], "tuned_params.yaml"),
                                              (["scanlines"], "scanlines.npz")])
def test_a_default_output_that_cannot_be_written_is_refused_before_any_work(render_dir, tmp_path, monkeypatch,
                                                                           command, default):
    """Without --out the file goes into DIR; a folder of that name was found only when the
    search (or run) was over: "cannot write DIR/tuned_params.yaml: Is a directory"."""
    import shutil

    import pipeline.tuning
    from pipeline.io import RenderDir

    def stop(*args, **kwargs):
        raise AssertionError("work started")
    monkeypatch.setattr(RenderDir, "frames", stop)
    monkeypatch.setattr(pipeline.tuning, "tune", stop)
    root = tmp_path / "r"
    shutil.copytree(render_dir, root)
    (root / default).mkdir()
    with pytest.raises(ValueError, match=rf"^--out: {re.escape(str(root / default))} is a folder; expected a file name$"):
        camtask([command[0], str(root)] + command[1:])


def test_ctrl_c_while_the_plot_is_drawn_leaves_the_earlier_files(render_dir, tmp_path, monkeypatch):
    """The YAML was written before the plot was drawn (~1.5 s): Ctrl-C then said
    "interrupted" and left this run's parameters beside the previous run's plot."""
    from testbed.commands import tune as tune_cmd

    out, plot = tmp_path / "t.yaml", tmp_path / "t.png"
    out.write_text("# an earlier search\n")
    plot.write_bytes(b"an earlier plot")

    def interrupted(f1):
        raise KeyboardInterrupt
    monkeypatch.setattr(tune_cmd, "history_figure", interrupted)
    with pytest.raises(KeyboardInterrupt):
        camtask(["tune", str(render_dir), "--trials", "2", "--out", str(out), "--plot", str(plot), "--json"])
    assert out.read_text() == "# an earlier search\n"
    assert plot.read_bytes() == b"an earlier plot"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.png", "t.yaml"]
