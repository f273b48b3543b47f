"""The top view draws each tasked camera's occluded cone where its scanline says."""

import numpy as np

from scene import load_scene
from testbed.loop import FrameResult
from testbed.topview import BACKGROUND, TopView


def _frame(camera: int, scan: np.ndarray) -> FrameResult:
    return FrameResult(0, (camera,), scan[None], [], 0.0, 0.0, 0, (), (), np.zeros((0, 2)),
                       np.zeros((0, 2)), np.zeros(0, int), np.zeros((0, 2)))


def test_cone_crossing_pi_is_the_narrow_wedge():
    # lab camera 7 looks along -170.5 deg: its bearings jump from -pi to pi inside the image
    scene = load_scene("lab")
    width = 200
    b = np.radians(np.linspace(-145.0, -196.0, width))
    b = np.arctan2(np.sin(b), np.cos(b))                    # wrapped into (-pi, pi] as the pipeline gives them
    jump = int(np.flatnonzero(np.abs(np.diff(b)) > np.pi)[0])
    scan = np.zeros(width, bool)
    scan[jump - 3: jump + 3] = True                         # a narrow run straight across the wrap
    bearings = {n: b for n in range(1, len(scene.cameras) + 1)}
    img = TopView(scene, width=400).draw(_frame(7, scan), bearings, title=" ")
    view = TopView(scene, width=400)
    shaded = np.any(img != BACKGROUND, axis=2) & (view.inside > 0)
    assert shaded.mean() < 0.2                              # a thin wedge, not the rest of the circle


def test_two_video_writers_to_one_path_do_not_share_a_temporary_file(tmp_path):
    """Two runs given one --video: each writes its own temporary file; the last to finish wins whole."""
    import imageio_ffmpeg

    from testbed.video import VideoWriter

    a, b = VideoWriter(tmp_path / "v.mp4", fps=5), VideoWriter(tmp_path / "v.mp4", fps=5)
    assert a.tmp != b.tmp
    for _ in range(3):
        a.write(np.zeros((32, 32, 3), np.uint8))
        b.write(np.full((32, 32, 3), 255, np.uint8))
    a.close()
    b.close()                                          # used to fail: "ffmpeg wrote nothing"
    reader = imageio_ffmpeg.read_frames(str(tmp_path / "v.mp4"))
    next(reader)
    frames = [np.frombuffer(f, np.uint8) for f in reader]
    assert len(frames) == 3 and all(f.mean() > 200 for f in frames)   # b's white frames, not a's
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.mp4"]
