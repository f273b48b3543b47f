"""`camtask run` and `demo` refuse a --frames that cannot fit in memory, in one line naming
it, before the walk (which took hours for 10**8 frames, then the results filled the memory)."""

import pytest

from testbed import cli, memory
from testbed.commands import run as run_command


@pytest.mark.parametrize("command", [["run", "lab"], ["demo"]])
def test_frames_beyond_any_memory_are_refused_naming_the_flag(command, tmp_path, capsys):
    out = tmp_path / "demo"
    argv = [*command, "--frames", str(10**12)] + (["--out", str(out)] if command == ["demo"] else [])
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"camtask {command[0]}: error: --frames: 1000000000000 frames would hold about ")
    assert "available; expected at most " in err and err.count("\n") == 1
    assert not out.exists()


def test_the_bound_follows_the_memory_available_cameras_and_people(monkeypatch, capsys):
    monkeypatch.setattr(memory, "available_memory", lambda: 2_000_000_000)
    per_frame = run_command.FRAME_BYTES + 6 * (run_command.CAMERA_BYTES + 640) + 3 * run_command.PERSON_BYTES
    most = 2_000_000_000 // per_frame
    run_command.check_frames_fit(most, 6, 3)
    with pytest.raises(ValueError, match=f"^--frames: {most + 1} frames would hold about 2 GB .* "
                                         f"expected at most {most} frames here$"):
        run_command.check_frames_fit(most + 1, 6, 3)
    assert cli.main(["run", "lab", "--k", "6", "--people", "3", "--frames", str(most + 1)]) == 2
    assert f"expected at most {most} frames here" in capsys.readouterr().err
    more_people = 2_000_000_000 // (per_frame + 10 * run_command.PERSON_BYTES)
    with pytest.raises(ValueError, match=f"expected at most {more_people} frames"):
        run_command.check_frames_fit(most, 6, 13)


def test_study_lab_refuses_a_trial_longer_than_the_memory(monkeypatch, capsys):
    """Each lab trial keeps every camera's scanlines: --frames 10**8 sat at 0/1 trials for
    hours, then filled the memory."""
    monkeypatch.setattr(memory, "available_memory", lambda: 2_000_000_000)
    assert cli.main(["study", "lab", "--frames", str(10**8), "--trials", "1", "--workers", "0"]) == 2
    err = capsys.readouterr().err
    per_frame = 2 * 16 * 640 + 16 * 3
    assert err == (f"camtask study: error: --frames: 100000000 frames would hold about 2,053 GB of memory in each "
                   f"trial (every camera's scanlines of every frame), more than the 2 GB available; expected at "
                   f"most {2_000_000_000 // per_frame} frames here\n")


WIDE = """\
room: {shape: rectangle, width: 6.0, depth: 5.0, height: 3.0}
cameras:
  intrinsics: {resolution: [6400, 4800], hfov_deg: 60, distortion: [0, 0, 0, 0, 0]}
  poses:
    - {number: 1, position: [0.1, 0.1, 2.5], yaw_deg: 40, pitch_deg: 20}
people: {count: 3, radius: 0.25}
"""


def test_the_bound_counts_each_scanline_column(monkeypatch, capsys, tmp_path):
    """A frame's results hold each tasked camera's scanline, one byte a column: a scene of
    6400-pixel-wide cameras was given the bound of the lab's 640."""
    import testbed.episode

    def walked(*args, **kwargs):
        raise AssertionError("the walk was drawn: the bound let the run start")

    monkeypatch.setattr(testbed.episode, "walk", walked)
    monkeypatch.setattr(memory, "available_memory", lambda: 2_000_000_000)
    per_frame = run_command.FRAME_BYTES + (run_command.CAMERA_BYTES + 6400) + 3 * run_command.PERSON_BYTES
    most = 2_000_000_000 // per_frame
    scene = tmp_path / "wide.yaml"
    scene.write_text(WIDE)
    assert cli.main(["run", str(scene), "--k", "1", "--frames", str(most + 1)]) == 2
    assert f"expected at most {most} frames here" in capsys.readouterr().err


def test_check_fits_takes_all_the_memory_available_and_no_more(monkeypatch):
    monkeypatch.setattr(memory, "available_memory", lambda: 1000)
    memory.check_fits("--n", 10, "things", 100, "in all")                 # exactly what is available
    with pytest.raises(ValueError) as info:
        memory.check_fits("--n", 11, "things", 100, "in all")
    assert str(info.value) == ("--n: 11 things would hold about 1.1e-06 GB of memory in all, more than the 1e-06 GB "
                               "available; expected at most 10 things here")


def test_check_fits_leaves_what_the_rest_of_the_run_holds(monkeypatch):
    monkeypatch.setattr(memory, "available_memory", lambda: 3_000_000_000)
    memory.check_fits("--n", 10, "things", 100_000_000, "in all", reserved=2_000_000_000)
    with pytest.raises(ValueError) as info:
        memory.check_fits("--n", 11, "things", 100_000_000, "in all", reserved=2_000_000_000, beside=" beside X")
    assert str(info.value) == ("--n: 11 things would hold about 1.1 GB of memory in all, more than the 1 GB available "
                               "beside X; expected at most 10 things here")
    with pytest.raises(ValueError, match=r"more than the 0 GB available; expected at most 0 things here$"):
        memory.check_fits("--n", 1, "things", 1, "in all", reserved=4_000_000_000)   # the rest alone is too much


def test_sizes_just_under_a_terabyte_are_not_printed_in_exponent_notation():
    """999.6 GB was printed '1e+03 GB' (three significant digits round it up to 1000)."""
    assert [memory.gigabytes(n) for n in (999.4e9, 999.6e9, 1e12, 2.5e9)] == ["999 GB", "1,000 GB", "1,000 GB",
                                                                              "2.5 GB"]
