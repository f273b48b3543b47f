"""testbed.lossless: a failed ffmpeg is an error, not a short video; corrupt or truncated videos do not read."""

import resource
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from testbed.cli import main
from testbed.lossless import VideoWriter, read_video


def frames(n, seed=0):
    rng = np.random.default_rng(seed)
    base = rng.integers(0, 256, (48, 64, 3), dtype=np.uint8)
    return [np.roll(base, i, axis=1) for i in range(n)]


@pytest.fixture()
def video(tmp_path):
    path = tmp_path / "v.mkv"
    w = VideoWriter(path, 64, 48, 7.5)
    for f in frames(6):
        w.write(f)
    w.close()
    return path


def test_round_trip(video):
    back = list(read_video(video, 6))
    assert len(back) == 6
    for a, b in zip(frames(6), back):
        np.testing.assert_array_equal(a, b)


def test_truncated_video_is_an_error(video, tmp_path):
    data = video.read_bytes()
    cut = tmp_path / "cut.mkv"
    cut.write_bytes(data[: int(len(data) * 0.9)])
    with pytest.raises(ValueError, match="cut.mkv.*truncated or corrupt"):
        list(read_video(cut))


def test_corrupt_slice_is_an_error(video, tmp_path):
    data = bytearray(video.read_bytes())
    data[len(data) // 2] ^= 0xFF
    bad = tmp_path / "bad.mkv"
    bad.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="bad.mkv.*CRC"):
        list(read_video(bad))


@pytest.mark.parametrize("where", [0.25, 0.5, 0.75])
def test_a_corrupt_frame_is_never_yielded(video, tmp_path, where):
    """The slice's CRC error was raised only at the end: the corrupt frame and those after it
    were yielded first, and ``next(read_video(...))`` returned a corrupt first frame silently."""
    data = bytearray(video.read_bytes())
    data[int(len(data) * where)] ^= 0xFF
    bad = tmp_path / "bad.mkv"
    bad.write_bytes(bytes(data))
    good = frames(6)
    got = []
    with pytest.raises(ValueError, match="bad.mkv.*CRC"):
        got.extend(read_video(bad))                  # keeps the frames taken before the error
    for f, rgb in enumerate(got):
        np.testing.assert_array_equal(rgb, good[f], err_msg=f"frame {f}")


def test_next_does_not_take_a_corrupt_first_frame(video, tmp_path):
    data = bytearray(video.read_bytes())
    data[int(len(data) * 0.1)] ^= 0xFF              # in frame 0's slices
    bad = tmp_path / "bad.mkv"
    bad.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="bad.mkv.*CRC"):
        next(read_video(bad))


def test_not_a_video_is_one_line(tmp_path):
    bad = tmp_path / "junk.mkv"
    bad.write_bytes(b"\x00" * 5000)
    with pytest.raises(ValueError) as err:
        list(read_video(bad))
    assert "\n" not in str(err.value) and "junk.mkv" in str(err.value)


def test_ffmpeg_failing_at_close_is_an_error(tmp_path):
    # a file size limit kills ffmpeg when the muxer flushes: the old writer returned normally
    script = textwrap.dedent(f"""
        import numpy as np
        from testbed.lossless import VideoWriter
        rng = np.random.default_rng(0)
        w = VideoWriter({str(tmp_path / 'big.mkv')!r}, 640, 480, 7.5)
        for i in range(4):
            w.write(rng.integers(0, 256, (480, 640, 3), dtype=np.uint8))
        w.close()
    """)
    limit = lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (500_000, 500_000))
    run = subprocess.run([sys.executable, "-c", script], preexec_fn=limit, capture_output=True, text=True, check=False)
    assert run.returncode != 0
    assert "cannot write" in run.stderr and "big.mkv" in run.stderr


def test_frame_rate_above_a_millisecond_is_refused(tmp_path, capsys):
    from pathlib import Path
    text = (Path(__file__).parents[1] / "assets" / "scenes" / "lab.yaml").read_text()
    scene = tmp_path / "fast.yaml"
    scene.write_text(text.replace("frame_rate: 7.5", "frame_rate: 2000", 1))
    assert main(["render", str(scene), "--frames", "2", "--cameras", "1", "--format", "video",
                 "--out", str(tmp_path / "out")]) == 2
    assert "at most 1000 frames per second" in capsys.readouterr().err


def test_an_episode_whose_third_video_fails_to_start_closes_the_two_started(tmp_path, monkeypatch):
    """The writers were made in one list: a failure at the third left the first two ffmpeg processes open."""
    from testbed import lossless
    from testbed.episodes import EpisodeConfig, render_episode

    real, started = lossless.VideoWriter, []

    class Flaky(real):
        def __init__(self, *args, **kwargs):
            if len(started) == 2:
                raise OSError("cannot start ffmpeg: no room")
            super().__init__(*args, **kwargs)
            started.append(self._proc)

    monkeypatch.setattr(lossless, "VideoWriter", Flaky)
    config = EpisodeConfig("lab", 1, (1, 2, 3), 1, 0, fmt="video")
    with pytest.raises(OSError, match="no room"):
        render_episode(config, 0, str(tmp_path))
    assert len(started) == 2 and all(proc.poll() is not None for proc in started)    # ffmpeg ended
    assert list(tmp_path.iterdir()) == []


def test_an_ffmpeg_that_is_not_there_is_named_before_any_work(tmp_path, monkeypatch, capsys):
    """IMAGEIO_FFMPEG_EXE naming no program (imageio-ffmpeg takes it untested) gave
    ``[Errno 2] No such file or directory: '...'`` once the first frame had rendered, and left
    a manifest of a run that had finished nothing."""
    missing = tmp_path / "bin" / "ffmpeg"
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(missing))
    out = tmp_path / "out"
    assert main(["render", "lab", "--frames", "1", "--cameras", "1", "--format", "video", "--workers", "0",
                 "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert err == (f"camtask render: error: ffmpeg: {str(missing)!r} (IMAGEIO_FFMPEG_EXE) is not an executable "
                   "file; install imageio-ffmpeg's binaries or point IMAGEIO_FFMPEG_EXE at an ffmpeg")
    assert not out.exists()
    (tmp_path / "v.mkv").write_bytes(b"\x00")
    with pytest.raises(OSError, match=r"^ffmpeg: .*bin/ffmpeg' \(IMAGEIO_FFMPEG_EXE\) is not an executable file"):
        next(read_video(tmp_path / "v.mkv"))


def test_frame_rates_from_below_1_hz_to_1000_hz_are_taken_and_no_others():
    from testbed.lossless import check_frame_rate

    assert [check_frame_rate("video", fps) for fps in (0.5, 7.5, 1000)] == [0.5, 7.5, 1000.0]
    for fps in (0, -7.5, 1000.5):
        with pytest.raises(ValueError, match="at most 1000 frames per second"):
            check_frame_rate("video", fps)


def test_a_writer_closed_without_a_frame_is_an_error(tmp_path):
    """ffmpeg writes a video of no frames and exits 0 (no reader takes it)."""
    w = VideoWriter(tmp_path / "none.mkv", 64, 48, 7.5)
    with pytest.raises(OSError) as err:
        w.close()
    assert str(err.value) == (f"cannot write {tmp_path / 'none.mkv'}: closed before any frame was written "
                              "(a video holds at least one)")


def test_a_writer_s_error_counts_the_frames_it_took(tmp_path, monkeypatch):
    fake = tmp_path / "ffmpeg"
    fake.write_text("#!/bin/sh\ncat > /dev/null\nexit 3\n")      # takes every frame, then fails
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    w = VideoWriter(tmp_path / "v.mkv", 64, 48, 7.5)
    for f in frames(2):
        w.write(f)
    with pytest.raises(OSError) as err:
        w.close()
    assert str(err.value) == f"cannot write {tmp_path / 'v.mkv'}: ffmpeg failed after 2 frames (exit status 3: no message)"


def test_the_same_frames_give_the_same_bytes_without_dates_or_versions(tmp_path):
    """Written a second apart to other names, the files are identical: the muxer writes
    neither the date nor its version (``Lavf`` alone, not ``Lavf63.1.102``)."""
    import re
    import time

    paths = []
    for name in ("a.mkv", "b.mkv"):
        w = VideoWriter(tmp_path / name, 64, 48, 7.5)
        for f in frames(3):
            w.write(f)
        w.close()
        paths.append(tmp_path / name)
        time.sleep(1.1)
    a, b = (p.read_bytes() for p in paths)
    assert a == b
    assert b"Lavf" in a and not re.search(rb"Lavf\d", a) and not re.search(rb"Lavc\d", a)


def test_an_ffmpeg_that_is_not_executable_is_refused(tmp_path, monkeypatch):
    """A file that is there but cannot be run is named as IMAGEIO_FFMPEG_EXE's, before any work."""
    from testbed.lossless import ffmpeg_exe

    fake = tmp_path / "ffmpeg"
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(0o644)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    with pytest.raises(OSError, match=r"^ffmpeg: .*ffmpeg' \(IMAGEIO_FFMPEG_EXE\) is not an executable file"):
        ffmpeg_exe()


def test_ffmpeg_s_message_loses_every_context_prefix_and_blank_line():
    import io

    from testbed.lossless import _message

    log = io.BytesIO(b"\n[matroska,webm @ 0x55d0c4a8b740] [ffv1 @ 0x7f00aa] slice CRC mismatch\nlater\n")
    assert _message(log) == "slice CRC mismatch"
    assert _message(io.BytesIO(b"\n  \n")) == "no message"
    log = io.BytesIO(b"[in#0 @ 0xabc] moov atom not found\n\nError opening input files: Invalid data\n")
    assert _message(log) == "Error opening input files: Invalid data"


def test_an_ffmpeg_imageio_ffmpeg_cannot_find_or_names_but_lacks_is_one_line(tmp_path, monkeypatch):
    """imageio-ffmpeg's error is folded onto one line; a binary it names itself (not
    IMAGEIO_FFMPEG_EXE) that is gone is not put down to the variable."""
    import imageio_ffmpeg

    from testbed.lossless import ffmpeg_exe

    def none():
        raise RuntimeError("No ffmpeg exe could be found.\n  Install ffmpeg on your system.")

    monkeypatch.delenv("IMAGEIO_FFMPEG_EXE", raising=False)
    monkeypatch.setattr(imageio_ffmpeg, "get_ffmpeg_exe", none)
    with pytest.raises(OSError) as err:
        ffmpeg_exe()
    assert str(err.value) == "ffmpeg: not found (No ffmpeg exe could be found. Install ffmpeg on your system.)"
    gone = tmp_path / "binaries" / "ffmpeg-linux-x86_64"
    monkeypatch.setattr(imageio_ffmpeg, "get_ffmpeg_exe", lambda: str(gone))
    with pytest.raises(OSError) as err:
        ffmpeg_exe()
    assert str(err.value) == (f"ffmpeg: {str(gone)!r} is not an executable file; install imageio-ffmpeg's binaries "
                              "or point IMAGEIO_FFMPEG_EXE at an ffmpeg")


def test_ffmpeg_s_message_keeps_brackets_inside_it_and_bytes_that_are_not_utf8():
    """Only the context at the start of a line goes: a file name in the message keeps its
    brackets, and one in Latin-1 is no UnicodeDecodeError."""
    import io

    from testbed.lossless import _message

    log = io.BytesIO(b"[in#0 @ 0x5a] Error opening input file /data/[cam @ 0x1] caf\xe9.mkv.\n")
    assert _message(log) == "Error opening input file /data/[cam @ 0x1] caf\ufffd.mkv."
