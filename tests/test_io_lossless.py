"""testbed.lossless.read_video: one ffmpeg per video, frames and errors as before."""

import gc
import os
import re
import subprocess
import threading
import time

import numpy as np
import pytest

from testbed.lossless import VideoWriter, read_video


def write(path, frames, fps=7.5):
    w = VideoWriter(path, frames[0].shape[1], frames[0].shape[0], fps)
    for f in frames:
        w.write(f)
    w.close()
    return path


def clip(n, h=30, w=41, seed=1):
    rng = np.random.default_rng(seed)
    return [rng.integers(0, 256, (h, w, 3), dtype=np.uint8) for _ in range(n)]


def spawned_processes(monkeypatch) -> list:
    """The subprocesses started from now on (the ffmpegs), as a list that fills as they start."""
    procs = []
    real = subprocess.Popen

    def popen(cmd, *args, **kwargs):
        procs.append(real(cmd, *args, **kwargs))
        return procs[-1]

    monkeypatch.setattr(subprocess, "Popen", popen)
    return procs


def test_one_ffmpeg_per_video(tmp_path, monkeypatch):
    """Opening the file once to read its size and again to decode it cost as much as the decoding."""
    frames = clip(3)
    path = write(tmp_path / "v.mkv", frames)
    spawned = spawned_processes(monkeypatch)
    back = list(read_video(path, 3))
    assert len(spawned) == 1
    assert len(back) == 3
    for a, b in zip(frames, back, strict=True):
        np.testing.assert_array_equal(a, b)


def test_odd_sizes_and_one_frame_round_trip(tmp_path):
    for h, w in ((7, 3), (3, 7), (2, 2)):
        frames = clip(1, h, w)
        back = list(read_video(write(tmp_path / f"v{h}x{w}.mkv", frames), 1))
        assert len(back) == 1 and back[0].shape == (h, w, 3)
        np.testing.assert_array_equal(frames[0], back[0])


def test_another_frame_count_is_refused_after_the_frames(tmp_path):
    path = write(tmp_path / "v.mkv", clip(2))
    got = []
    with pytest.raises(ValueError, match=r"v.mkv' holds 2 frames; expected 3$"):
        got.extend(read_video(path, 3))
    assert len(got) == 2
    with pytest.raises(ValueError, match=r"v1.mkv' holds 1 frame; expected 2$"):   # said "1 frames"
        list(read_video(write(tmp_path / "v1.mkv", clip(1)), 2))
    with pytest.raises(ValueError, match=r"v1.mkv' holds 1 frame; expected 0$"):
        list(read_video(tmp_path / "v1.mkv", 0))


def test_not_a_video_names_the_file_and_ffmpeg_s_reason(tmp_path):
    bad = tmp_path / "junk.mkv"
    bad.write_bytes(b"\x00" * 5000)
    with pytest.raises(ValueError, match=r"^video: cannot read .*junk.mkv'.*Invalid data") as err:
        list(read_video(bad))
    assert "\n" not in str(err.value) and str(err.value).endswith("(not a video ffmpeg can open, or corrupt)")


def test_a_closed_reader_stops_its_ffmpeg(tmp_path, monkeypatch):
    path = write(tmp_path / "v.mkv", clip(5, 128, 128))     # more than a pipe holds: ffmpeg waits to write
    procs = spawned_processes(monkeypatch)
    gen = read_video(path, 5)
    next(gen)
    closing = threading.Thread(target=gen.close)
    closing.start()
    closing.join(10)                          # a reader that waited for ffmpeg to finish would wait forever
    hung = closing.is_alive()
    for p in procs:
        p.kill()                              # (lets a hung close return)
    closing.join()
    assert not hung and procs and all(p.returncode is not None and p.stdout.closed for p in procs)


def test_errors_give_ffmpeg_s_reason_without_its_pointer_addresses(tmp_path):
    """read_video quoted ffmpeg's last stderr line verbatim: ``[ffv1 @ 0x55d0...] slice CRC
    mismatch`` and, for a file cut after its header, ``[out#0/image2pipe @ 0x...] Nothing was
    written into output file``, a consequence, not the reason (``File ended prematurely``)."""
    data = write(tmp_path / "v.mkv", clip(3, 48, 64)).read_bytes()
    corrupt = bytearray(data)
    corrupt[len(data) // 2] ^= 0xFF
    cases = {"head.mkv": (data[:1000], "File ended prematurely"),
             "cut.mkv": (data[: len(data) * 2 // 3], "File ended prematurely"),
             "crc.mkv": (bytes(corrupt), "slice CRC mismatch"),
             "junk.mkv": (b"\x00" * 5000, "Error opening input files: Invalid data found when processing input")}
    for name, (content, reason) in cases.items():
        (tmp_path / name).write_bytes(content)
        with pytest.raises(ValueError) as err:
            list(read_video(tmp_path / name, 3))
        message = str(err.value)
        assert f"{name}'" in message and reason in message, message
        assert " @ 0x" not in message and "[" not in message and "\n" not in message, message


def test_a_writer_s_error_gives_ffmpeg_s_reason_without_its_pointer_addresses(tmp_path):
    from testbed.lossless import _message

    log = tmp_path / "log"            # what ffmpeg wrote when the disk filled as it closed the file
    log.write_bytes(b"[out#0/matroska @ 0x564c7e74d440] Error writing trailer: No space left on device\n"
                    b"[out#0/matroska @ 0x564c7e74d440] Error closing file: No space left on device\n")
    with log.open("rb") as f:
        assert _message(f) == "Error writing trailer: No space left on device"


def test_a_render_directory_of_videos_reads_as_its_png_twin(tmp_path):
    """RenderDir refused frames/camNN.mkv (`render --format video`): `scanlines DIR` and `tune`
    could not read a video episode. Frames come in any order; a video of another length than
    the masks, or missing, is one line naming it."""
    import shutil

    import scene
    from pipeline.io import RenderDir
    from pipeline.synthetic import synthetic_sequence, write_render_dir

    cams = [scene.Camera.from_pose(i + 1, [x, 0.05, 2.2], np.radians(90 + d), np.radians(15), 41, 30,
                                   np.radians(49), [-0.18, 0.06, 0, 0, 0])
            for i, (x, d) in enumerate([(1.5, -20), (5.0, 20)])]
    bg, frames, labels = synthetic_sequence(cams, 4, np.random.default_rng(5))
    png, video = tmp_path / "png", tmp_path / "video"
    write_render_dir(png, cams, bg, frames, labels)
    shutil.copytree(png, video)
    for i, cam in enumerate(cams):
        shutil.rmtree(video / "frames" / cam.name)
        write(video / "frames" / f"{cam.name}.mkv", list(frames[:, i]))
    a, b = RenderDir(png), RenderDir(video)
    assert b.frame_names == a.frame_names and len(b) == 4
    b.check_complete(4)
    for i in (0, 1, 3, 2, 0, -1):
        np.testing.assert_array_equal(b.frames(i), a.frames(i), err_msg=f"frame {i}")
        np.testing.assert_array_equal(b.frames(i), frames[i])
    b.close()
    for n, problem in ((3, r"holds 3 frames; expected 4"), (5, r"holds more than 4 frames; expected 4, as masks/cam02 has")):
        write(video / "frames" / "cam02.mkv", [frames[f % 4, 1] for f in range(n)])
        with pytest.raises(ValueError, match=rf"^video: '.*video/frames/cam02.mkv' {problem}$"):
            [RenderDir(video).frames(i) for i in range(4)]
    write(video / "frames" / "cam02.mkv", [frames[f, 1] for f in range(3)])
    short = RenderDir(video)                    # cam02 has 3 frames: frame 3 cannot be read, each time
    for _ in range(2):                          # the second time said StopIteration: the decoders were kept
        with pytest.raises(ValueError, match=r"cam02.mkv' holds 3 frames; expected 4$"):
            short.frames(3)
    np.testing.assert_array_equal(short.frames(1), frames[1])
    (video / "frames" / "cam02.mkv").unlink()
    with pytest.raises(ValueError, match=r"^DIR: .* lacks 1 file of its first 1 frame: frames/cam02.mkv$"):
        RenderDir(video).check_complete(1)


def test_a_video_frame_read_again_is_not_decoded_again(tmp_path, monkeypatch):
    """Reading the frame just read started every camera's ffmpeg again from frame 0."""
    import scene
    from pipeline.io import RenderDir
    from pipeline.synthetic import synthetic_sequence, write_render_dir
    from testbed import lossless

    cam = scene.Camera.from_pose(1, [1.5, 0.05, 2.2], np.radians(70), np.radians(15), 41, 30, np.radians(49),
                                 [0, 0, 0, 0, 0])
    bg, frames, labels = synthetic_sequence([cam], 3, np.random.default_rng(5))
    write_render_dir(tmp_path, [cam], bg, frames, labels)
    import shutil

    shutil.rmtree(tmp_path / "frames" / cam.name)
    write(tmp_path / "frames" / f"{cam.name}.mkv", list(frames[:, 0]))
    opened = []
    real = lossless.read_video
    monkeypatch.setattr(lossless, "read_video", lambda *a, **k: opened.append(a[0]) or real(*a, **k))
    r = RenderDir(tmp_path)
    got = [r.frames(i) for i in (0, 1, 1, 2, 2, -1)]
    for g, i in zip(got, (0, 1, 1, 2, 2, 2)):
        np.testing.assert_array_equal(g, frames[i])
    got[3][:] = 0                               # the callers' copies, decoded and read again: the next
    got[4][:] = 0                               # read is the frame's own
    np.testing.assert_array_equal(r.frames(2), frames[2])
    assert len(opened) == 1
    r.frames(0)                                 # an earlier frame: decoded from the start
    assert len(opened) == 2
    r.close()


def video_render_dir(root, frames, numbers=(1,)):
    """``root`` made a render directory of cameras ``numbers`` whose ``frames`` frames are
    frames/camNN.mkv; returns the frames, (frames, cameras, H, W, 3) in the order of ``numbers``."""
    import shutil

    import scene
    from pipeline.synthetic import synthetic_sequence, write_render_dir

    cams = [scene.Camera.from_pose(n, [1.5 + 0.5 * i, 0.05, 2.2], np.radians(70), np.radians(15), 41, 30,
                                   np.radians(49), [0, 0, 0, 0, 0]) for i, n in enumerate(numbers)]
    bg, images, labels = synthetic_sequence(cams, frames, np.random.default_rng(5))
    write_render_dir(root, cams, bg, images, labels)
    for i, cam in enumerate(cams):
        shutil.rmtree(root / "frames" / cam.name)
        write(root / "frames" / f"{cam.name}.mkv", list(images[:, i]))
    return images


def test_videos_of_cameras_numbered_past_99_are_read_in_number_order(tmp_path):
    """cam100.mkv sorts before cam11.mkv as text: each camera's frames are its own video's."""
    from pipeline.io import RenderDir

    frames = video_render_dir(tmp_path, 2, (100, 11))
    r = RenderDir(tmp_path)
    assert [c.number for c in r.cameras] == [11, 100]
    np.testing.assert_array_equal(r.frames(1), frames[1, ::-1])
    r.close()


def test_the_videos_decoders_are_stopped_before_others_start_and_by_close(tmp_path, monkeypatch):
    """An earlier frame starts the videos again: the ffmpeg decoding them before stops first,
    not once collected; close() stops the last ones."""
    from pipeline.io import RenderDir
    from testbed import lossless

    frames = video_render_dir(tmp_path, 3)
    decoders = []
    real = lossless.read_video

    def read_video(*args, **kwargs):
        assert all(d.gi_frame is None for d in decoders), "a decoder still runs"
        decoders.append(real(*args, **kwargs))
        return decoders[-1]

    monkeypatch.setattr(lossless, "read_video", read_video)
    r = RenderDir(tmp_path)
    np.testing.assert_array_equal(r.frames(1), frames[1])
    np.testing.assert_array_equal(r.frames(0), frames[0])
    assert len(decoders) == 2 and decoders[1].gi_frame is not None
    r.close()
    assert decoders[1].gi_frame is None


def test_a_video_read_interrupted_is_read_again_from_its_start(tmp_path, monkeypatch):
    """Ctrl-C while decoding (a KeyboardInterrupt, no Exception) leaves the decoders between
    frames: the next read starts them again."""
    from pipeline.io import RenderDir
    from testbed import lossless

    frames = video_render_dir(tmp_path, 3)
    opened = []
    real = lossless.read_video

    def read_video(*args, **kwargs):
        opened.append(args[0])
        decoder = real(*args, **kwargs)
        yield next(decoder)
        if len(opened) == 1:
            decoder.close()
            raise KeyboardInterrupt
        yield from decoder

    monkeypatch.setattr(lossless, "read_video", read_video)
    r = RenderDir(tmp_path)
    with pytest.raises(KeyboardInterrupt):
        r.frames(1)
    np.testing.assert_array_equal(r.frames(1), frames[1])
    assert len(opened) == 2
    r.close()


@pytest.mark.parametrize(("script", "status"), [("exit 1", "failed with exit status 1"),
                                                ("kill -9 $$", "was killed by signal 9")])
def test_an_ffmpeg_that_fails_without_a_word_does_not_blame_the_video(tmp_path, monkeypatch, script, status):
    """ffmpeg killed (out of memory) or broken said 'no message (not a video ffmpeg can open, or
    corrupt)' of a sound video: a user would throw away good data."""
    path = write(tmp_path / "v.mkv", clip(2))
    fake = tmp_path / "ffmpeg"
    fake.write_text(f"#!/bin/sh\n{script}\n")
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    with pytest.raises(OSError) as err:
        list(read_video(path, 2))
    assert str(err.value) == f"video: cannot read {str(path)!r}: ffmpeg ({fake}) {status} without a message"


@pytest.mark.parametrize(("script", "error", "says"), [
    ("kill -9 $$", OSError, "ffmpeg ({fake}) was killed by signal 9 without a message"),
    ("exit 0", ValueError, "frame 0 ends early"),
])
def test_a_frame_cut_short_is_never_yielded(tmp_path, monkeypatch, script, error, says):
    """ffmpeg stopped in the middle of a frame (killed: out of memory): its bytes are no frame."""
    path = write(tmp_path / "v.mkv", clip(2))
    fake = tmp_path / "ffmpeg"
    fake.write_text(f"#!/bin/sh\nprintf 'P6\\n2 2\\n255\\nabcdefghij'\n{script}\n")   # 10 of a frame's 12 bytes
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    got = []
    with pytest.raises(error) as err:
        got.extend(read_video(path))
    assert got == [] and str(err.value).endswith(says.format(fake=fake))


@pytest.mark.parametrize(("h", "w"), [(1, 1), (1, 8), (8, 1), (480, 1)])
def test_a_frame_one_pixel_wide_or_high_is_refused_before_ffmpeg_starts(tmp_path, monkeypatch, h, w):
    """FFV1 (4 slices) fails on such frames only once the first frame is written."""
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: pytest.fail("ffmpeg started"))
    with pytest.raises(ValueError) as err:
        VideoWriter(tmp_path / "thin.mkv", w, h, 7.5)
    assert str(err.value) == (f"cannot write {tmp_path / 'thin.mkv'}: a lossless video needs frames at least "
                              f"2 pixels wide and high; got {w} x {h}")
    assert not (tmp_path / "thin.mkv").exists()


def test_a_video_holding_more_frames_than_expected_is_refused_after_them(tmp_path):
    got = []
    with pytest.raises(ValueError, match=r"v.mkv' holds 3 frames; expected 2$"):
        got.extend(read_video(write(tmp_path / "v.mkv", clip(3)), 2))
    assert len(got) == 3


def test_the_frame_rate_is_stored_exactly(tmp_path):
    """Frames at 7.5 Hz, not rounded to 8: 3 of them last 0.4 s (Matroska's DURATION tag);
    at 2.4 Hz, 1.25 s; a rate of numpy's float32 is taken too."""
    for i, (fps, duration) in enumerate(((7.5, b"00:00:00.400000000"), (2.4, b"00:00:01.250000000"),
                                         (np.float32(7.5), b"00:00:00.400000000"))):
        data = write(tmp_path / f"{i}.mkv", clip(3), fps).read_bytes()
        assert duration in data, fps


def test_a_frame_of_another_shape_is_refused_and_a_second_close_does_nothing(tmp_path):
    w = VideoWriter(tmp_path / "v.mkv", 41, 30, 7.5)
    with pytest.raises(ValueError, match=r"^frame: expected shape \(30, 41, 3\), got \(41, 30, 3\)$"):
        w.write(np.zeros((41, 30, 3), np.uint8))
    for shape in ((30, 41, 4), (30, 41)):
        with pytest.raises(ValueError, match=rf"^frame: expected shape \(30, 41, 3\), got {re.escape(str(shape))}$"):
            w.write(np.zeros(shape, np.uint8))
    w.write(clip(1)[0])
    w.close()
    w.close()
    assert len(list(read_video(tmp_path / "v.mkv", 1))) == 1


def _fake_ffmpeg(tmp_path, monkeypatch, script):
    fake = tmp_path / "ffmpeg"
    fake.write_text(f"#!/bin/sh\n{script}\n")
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    return fake


@pytest.mark.parametrize(("frames", "script", "says"), [
    (1, "cat > /dev/null\nexit 3", "failed after 1 frame (exit status 3: no message)"),
    (0, "cat > /dev/null\nexit 3", "failed after 0 frames (exit status 3: no message)"),
    (2, "cat > /dev/null\nkill -9 $$", "failed after 2 frames (killed by signal 9: no message)"),
])
def test_a_writer_s_failure_says_its_frames_and_how_ffmpeg_ended(tmp_path, monkeypatch, frames, script, says):
    _fake_ffmpeg(tmp_path, monkeypatch, script)
    w = VideoWriter(tmp_path / "v.mkv", 41, 30, 7.5)
    for f in clip(frames):
        w.write(f)
    with pytest.raises(OSError) as err:
        w.close()
    assert str(err.value) == f"cannot write {tmp_path / 'v.mkv'}: ffmpeg {says}"


def test_an_error_after_one_frame_says_one_frame(tmp_path, monkeypatch):
    """ffmpeg gives one 2 x 2 frame, then (once it is taken) fails with a message."""
    path = write(tmp_path / "v.mkv", clip(2))
    go = tmp_path / "go"
    _fake_ffmpeg(tmp_path, monkeypatch, f"printf 'P6\\n2 2\\n255\\nabcdefghijkl'\n"
                                        f"while [ ! -e {go} ]; do sleep 0.01; done\necho 'slice CRC mismatch' >&2\nexit 1")
    frames = read_video(path)
    assert next(frames).tobytes() == b"abcdefghijkl"
    go.touch()
    with pytest.raises(ValueError) as err:
        next(frames)
    assert str(err.value) == f"video: cannot read {str(path)!r} after 1 frame: slice CRC mismatch (truncated or corrupt)"


def open_fds():
    """Open file descriptors of this process, once the garbage of earlier tests is collected
    (a file an earlier test dropped, closed by the collector mid-test, made one fewer)."""
    gc.collect()
    return len(os.listdir("/proc/self/fd"))


def test_a_writer_whose_ffmpeg_stops_reading_is_ended_and_says_at_which_frame(tmp_path, monkeypatch):
    """An ffmpeg that closed its input and hangs is killed, not waited for. (Frames larger than
    the pipe's buffer, so that each write reaches ffmpeg at once.)"""
    go = tmp_path / "go"
    _fake_ffmpeg(tmp_path, monkeypatch, f"head -c {480 * 640 * 3} > /dev/null\nexec 0<&-\ntouch {go}\nexec sleep 30")
    w = VideoWriter(tmp_path / "v.mkv", 640, 480, 7.5)
    frames = clip(2, 480, 640)
    w.write(frames[0])
    deadline = time.monotonic() + 30
    while not go.exists():
        assert time.monotonic() < deadline, "the fake ffmpeg never read the first frame"
        time.sleep(0.01)
    with pytest.raises(OSError) as err:
        w.write(frames[1])
    assert str(err.value) == f"cannot write {tmp_path / 'v.mkv'}: ffmpeg stopped at frame 1 (killed by signal 9: no message)"


def test_a_writer_whose_ffmpeg_exited_says_how_it_ended(tmp_path, monkeypatch):
    """Exit status 0 is not a signal; a small frame still buffered when ffmpeg is gone is no BrokenPipeError."""
    _fake_ffmpeg(tmp_path, monkeypatch, "exit 0")
    w = VideoWriter(tmp_path / "v.mkv", 640, 480, 7.5)
    w._proc.wait()
    with pytest.raises(OSError) as err:
        w.write(clip(1, 480, 640)[0])
    assert str(err.value) == f"cannot write {tmp_path / 'v.mkv'}: ffmpeg stopped at frame 0 (exit status 0: no message)"
    _fake_ffmpeg(tmp_path, monkeypatch, "exit 3")
    w = VideoWriter(tmp_path / "v.mkv", 2, 2, 7.5)
    w._proc.wait()
    w.write(clip(1, 2, 2)[0])                        # 12 bytes: held in the pipe's buffer until close
    with pytest.raises(OSError) as err:
        w.close()
    assert str(err.value) == f"cannot write {tmp_path / 'v.mkv'}: ffmpeg failed after 1 frame (exit status 3: no message)"


def test_a_full_disk_gives_ffmpeg_s_reason(tmp_path):
    """ffmpeg's own error, not the first line of its banner."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    full = tmp_path / "full.mkv"
    full.symlink_to("/dev/full")
    with pytest.raises(OSError) as err:
        write(full, clip(3))
    assert re.fullmatch(rf"cannot write {re.escape(str(full))}: ffmpeg failed after 3 frames \(exit status \d+: "
                        r"Error writing trailer: No space left on device\)", str(err.value)), str(err.value)


def test_frames_that_are_views_or_of_another_integer_type_are_written_as_their_uint8_values(tmp_path):
    frames = clip(3)
    given = [frames[0][:, ::-1], frames[1][..., ::-1], frames[2].astype(np.int64)]
    back = list(read_video(write(tmp_path / "v.mkv", given), 3))
    for f, (a, b) in enumerate(zip(given, back, strict=True)):
        np.testing.assert_array_equal(a, b, err_msg=f"frame {f}")


def test_a_closed_writer_leaves_no_file_open(tmp_path, monkeypatch):
    before = open_fds()
    w = VideoWriter(tmp_path / "v.mkv", 41, 30, 7.5)
    w.write(clip(1)[0])
    w.close()
    assert open_fds() == before
    _fake_ffmpeg(tmp_path, monkeypatch, "cat > /dev/null\nexit 3")
    w = VideoWriter(tmp_path / "v.mkv", 41, 30, 7.5)
    with pytest.raises(OSError):
        w.close()
    assert open_fds() == before


def test_a_close_interrupted_while_ffmpeg_finishes_kills_it(tmp_path, monkeypatch):
    """Ctrl-C while close waits: ffmpeg (in a session of its own, so not reached by it) is ended."""
    _fake_ffmpeg(tmp_path, monkeypatch, "exec sleep 30")
    before = open_fds()
    w = VideoWriter(tmp_path / "v.mkv", 41, 30, 7.5)
    proc, real_wait = w._proc, w._proc.wait

    def interrupted(*args, **kwargs):
        proc.wait = real_wait
        raise KeyboardInterrupt

    proc.wait = interrupted
    with pytest.raises(KeyboardInterrupt):
        w.close()
    assert proc.returncode == -9 and open_fds() == before


def test_ffmpeg_runs_in_a_session_of_its_own(tmp_path, monkeypatch):
    """Ctrl-C at the terminal reaches camtask alone, which ends its ffmpegs itself."""
    path = write(tmp_path / "v.mkv", clip(5, 128, 128))     # more than a pipe holds: the reader's ffmpeg waits
    procs = spawned_processes(monkeypatch)
    w = VideoWriter(tmp_path / "w.mkv", 41, 30, 7.5)
    frames = read_video(path, 5)
    next(frames)
    try:
        assert len(procs) == 2 and all(os.getsid(p.pid) == p.pid != os.getsid(0) for p in procs)
    finally:
        frames.close()
        w.write(clip(1)[0])
        w.close()


def test_a_missing_video_or_a_folder_is_named_before_ffmpeg_starts(tmp_path, monkeypatch):
    monkeypatch.setattr(subprocess, "Popen", lambda *a, **k: pytest.fail("ffmpeg started"))
    with pytest.raises(FileNotFoundError, match=r"^frames/cam01: no such file '.*v.mkv'$"):
        next(read_video(tmp_path / "v.mkv", name="frames/cam01"))
    with pytest.raises(ValueError, match=r"^video: '.*' is a folder, not a file$"):
        next(read_video(tmp_path))


def test_the_first_video_stream_is_read(tmp_path):
    """Of a file of two video streams, the first; not the one ffmpeg picks unless told (the
    default one, here the second)."""
    from testbed.lossless import ffmpeg_exe

    small, large = clip(2, 30, 41, seed=1), clip(2, 48, 64, seed=2)
    a, b, both = write(tmp_path / "a.mkv", small), write(tmp_path / "b.mkv", large), tmp_path / "both.mkv"
    subprocess.run([ffmpeg_exe(), "-v", "error", "-i", str(a), "-i", str(b), "-map", "0", "-map", "1", "-c", "copy",
                    "-disposition:v:0", "0", "-disposition:v:1", "default", str(both)], check=True)
    back = list(read_video(both, 2))
    for f, (want, got) in enumerate(zip(small, back, strict=True)):
        np.testing.assert_array_equal(want, got, err_msg=f"frame {f}")


@pytest.mark.parametrize("out", [r"P5\n2 2\n255\n", r"P6\n2 2\n65535\n", r"P6\n0 0\n255\n", r"P6\n-2 2\n255\n",
                                 r"P6\nx\n255\n"])
def test_output_that_is_no_rgb_frame_is_never_yielded_and_is_read_to_its_end(tmp_path, monkeypatch, out):
    """Not 8-bit RGB, no size or a size of no pixels: no frame; the rest of ffmpeg's output is
    read (ffmpeg waiting to write it would never end)."""
    path = write(tmp_path / "v.mkv", clip(1))
    _fake_ffmpeg(tmp_path, monkeypatch, f"printf '{out}'\n"
                                        "timeout 10 head -c 200000 /dev/zero || { echo 'output not read' >&2; exit 1; }")
    got = []
    with pytest.raises(ValueError) as err:
        got.extend(read_video(path))
    assert got == [] and str(err.value) == f"video: {str(path)!r}: frame 0 ends early"


def test_a_corrupt_frame_early_in_a_long_video_ends_ffmpeg(tmp_path, monkeypatch):
    """ffmpeg goes on decoding after a slice's CRC error: the reader stops it, not waits for
    frames it will not take (more than a pipe holds)."""
    data = bytearray(write(tmp_path / "v.mkv", clip(8, 128, 128)).read_bytes())
    data[len(data) // 10] ^= 0xFF
    bad = tmp_path / "bad.mkv"
    bad.write_bytes(bytes(data))
    errors = []

    def read():
        try:
            list(read_video(bad))
        except ValueError as exc:
            errors.append(str(exc))

    procs = spawned_processes(monkeypatch)
    reading = threading.Thread(target=read)
    reading.start()
    reading.join(10)
    hung = reading.is_alive()
    for p in procs:
        p.kill()                              # (lets a hung reader return)
    reading.join()
    assert not hung and len(errors) == 1 and "bad.mkv" in errors[0] and "CRC" in errors[0], errors
