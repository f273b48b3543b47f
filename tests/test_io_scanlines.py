"""camtask scanlines: --video, --calibration and --background as their help and docs/pipeline.md say."""

import argparse
import re
from pathlib import Path

import numpy as np
import pytest

from pipeline.synthetic import synthetic_sequence, write_render_dir
from testbed.cli import UsageError
from testbed.commands import scanlines as scanlines_cmd
from tests.test_pipeline_cli import camtask, small_cameras


@pytest.fixture(scope="module")
def render_dir(tmp_path_factory):
    cams = small_cameras()
    bg, frames, labels = synthetic_sequence(cams, 4, np.random.default_rng(3))
    root = tmp_path_factory.mktemp("render")
    write_render_dir(root, cams, bg, frames, labels)
    return root


def video_args(render_dir, background, *extra):
    return ["scanlines", "--video", str(render_dir / "frames" / "cam01"), "--calibration",
            str(render_dir / "calibration" / "cam01.yaml"), "--background", str(background), *extra]


@pytest.mark.parametrize(("extra", "named"), [
    (["--background", "2"], "--background goes"),
    (["--calibration", "c.yaml", "--background", "2"], "--calibration and --background go"),
])
def test_video_options_given_with_a_render_directory_are_refused(render_dir, tmp_path, extra, named):
    """They were ignored without a word: the run used DIR's own background and calibration."""
    with pytest.raises(UsageError, match=f"^{named} with --video, not with DIR"):
        camtask(["scanlines", str(render_dir), "--out", str(tmp_path / "s.npz"), *extra])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("background", [4, 9])
def test_a_video_of_background_only_names_the_options(render_dir, tmp_path, background):
    """It said "frames: expected at least one frame after the background", naming no option."""
    with pytest.raises(ValueError, match=rf"^--background {background}: --video .*cam01 has 4 frames; "
                                         rf"expected more than the {background} background frames$"):
        camtask(video_args(render_dir, background, "--out", str(tmp_path / "s.npz")))
    assert list(tmp_path.iterdir()) == []


def test_frames_counts_the_frames_after_the_background(render_dir, tmp_path):
    for frames, expected in ((1, 1), (5, 2)):
        out = tmp_path / f"s{frames}.npz"
        assert camtask(video_args(render_dir, 2, "--frames", str(frames), "--out", str(out), "--json")) == 0
        assert np.load(out)["scanlines"].shape == (expected, 1, 160)


def test_help_usage_and_docs_name_the_same_arguments():
    parser = argparse.ArgumentParser(prog="camtask")
    scanlines_cmd.add_parser(parser.add_subparsers())
    text = " ".join(parser._subparsers._group_actions[0].choices["scanlines"].format_usage().split())
    usage = "--video FILE_OR_FOLDER --calibration cam.yaml --background N [--frames N] [--out FILE.npz]"
    for option in ("[--frames N]", "[--out FILE]", "[--video FILE_OR_FOLDER]", "[--calibration FILE]",
                   "[--background N]"):
        assert option in text
    docs = (Path(__file__).parents[1] / "docs" / "pipeline.md").read_text()
    assert f"camtask scanlines {usage}" in docs and f"camtask scanlines {usage}" in scanlines_cmd.__doc__
    assert not re.search(r"--(frames|background) (FRAMES|BACKGROUND)", docs + scanlines_cmd.__doc__)
