"""Small synthetic sequences for tests, benchmarks and tuning demos (no renderer needed).

People are upright cylinders projected through the real calibration (with distortion):
the convex hull of points on each cylinder is filled, far people first, in both the
frame (a flat clothing colour with texture) and the label image (person id + 1). The
background is a smooth random texture. :func:`degrade` makes darker, noisier copies.
"""

from __future__ import annotations

import cv2
import numpy as np


def _texture(rng: np.random.Generator, shape: tuple[int, int], sigma: float) -> np.ndarray:
    noise = rng.normal(0.0, 1.0, shape + (3,)).astype(np.float32)
    smooth = cv2.GaussianBlur(noise, (0, 0), sigma)
    return smooth / (smooth.std() + 1e-9)


def synthetic_background(cameras, rng: np.random.Generator) -> np.ndarray:
    """(n_cams, H, W, 3) uint8 RGB empty-room images: mid-grey walls with smooth texture."""
    out = []
    for cam in cameras:
        base = rng.uniform(110, 170, 3)
        tex = _texture(rng, (cam.height, cam.width), max(cam.width / 40, 1.0))
        out.append(np.clip(base + 18 * tex, 0, 255).astype(np.uint8))
    return np.stack(out)


def _cylinder_points(xy, radius: float, height: float, n: int = 24) -> np.ndarray:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([xy[0] + radius * np.cos(a), xy[1] + radius * np.sin(a)], 1)
    zs = np.linspace(0, height, 8)
    return np.concatenate([np.column_stack([ring, np.full(n, z)]) for z in zs])


def render_people(cameras, background: np.ndarray, people_xy: np.ndarray, colours: np.ndarray,
                  rng: np.random.Generator, radius: float = 0.25, height: float = 1.75,
                  noise_std: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Frame and labels of people standing at ``people_xy``.

    people_xy : (n_people, 2) float, metres, world frame; colours : (n_people, 3) uint8 RGB
    Returns frames (n_cams, H, W, 3) uint8 RGB and labels (n_cams, H, W) int32.
    """
    frames, labels = background.astype(np.float32).copy(), np.zeros(background.shape[:3], np.int32)
    for i, cam in enumerate(cameras):
        dist = np.linalg.norm(people_xy - cam.xy, axis=1)
        for j in np.argsort(-dist):
            pts = _cylinder_points(people_xy[j], radius, height)
            pc = pts @ cam.R.T + cam.t
            pts = pts[pc[:, 2] > 0.1]
            if len(pts) < 3:
                continue
            rvec, _ = cv2.Rodrigues(cam.R)
            uv, _ = cv2.projectPoints(pts, rvec, cam.t, cam.K, cam.dist)
            uv = uv.reshape(-1, 2)
            if np.abs(uv).max() > 1e5:
                continue
            hull = cv2.convexHull(np.round(uv * 16).astype(np.int32))
            m = np.zeros(labels.shape[1:], np.uint8)
            cv2.fillConvexPoly(m, hull, 1, lineType=cv2.LINE_8, shift=4)
            sel = m.astype(bool)
            labels[i][sel] = j + 1
            shade = 1 + rng.normal(0.0, 0.06, (int(sel.sum()), 1)).astype(np.float32)
            frames[i][sel] = colours[j] * shade
    frames += rng.normal(0.0, noise_std, frames.shape).astype(np.float32)
    return np.clip(np.rint(frames), 0, 255).astype(np.uint8), labels


def synthetic_sequence(cameras, n_frames: int, rng: np.random.Generator, n_people: int = 3,
                       room=(6.7056, 5.7912), speed_per_frame: float = 0.13, noise_std: float = 2.0):
    """Background, frames and labels of people walking straight, bouncing off the walls.

    Returns background (n_cams, H, W, 3) uint8, frames (n_frames, n_cams, H, W, 3) uint8,
    labels (n_frames, n_cams, H, W) int32.
    """
    background = synthetic_background(cameras, rng)
    lo, hi = np.array([0.8, 0.8]), np.array(room) - 0.8
    xy = rng.uniform(lo, hi, (n_people, 2))
    heading = rng.uniform(-np.pi, np.pi, n_people)
    vel = speed_per_frame * np.stack([np.cos(heading), np.sin(heading)], 1)
    colours = rng.integers(20, 235, (n_people, 3)).astype(np.float32)
    frames, labels = [], []
    for _ in range(n_frames):
        f, lab = render_people(cameras, background, xy, colours, rng, noise_std=noise_std)
        frames.append(f); labels.append(lab)
        xy = xy + vel
        bounce = (xy < lo) | (xy > hi)
        vel[bounce] *= -1
        xy = np.clip(xy, lo, hi)
    return background, np.stack(frames), np.stack(labels)


def degrade(frames, rng: np.random.Generator, gain: float = 0.35, noise_std: float = 8.0) -> np.ndarray:
    """Darker, noisier copy of uint8 frames: ``clip(gain * frames + N(0, noise_std))``."""
    f = np.asarray(frames, np.float32) * gain
    f += rng.normal(0.0, noise_std, f.shape).astype(np.float32)
    return np.clip(np.rint(f), 0, 255).astype(np.uint8)


def write_render_dir(root, cameras, background, frames, labels) -> None:
    """Write a sequence in the render-directory layout of ``camtask render`` (for tests).

    background : (n_cams, H, W, 3) uint8 RGB; frames : (n_frames, n_cams, H, W, 3) uint8 RGB;
    labels : (n_frames, n_cams, H, W) int
    """
    from pathlib import Path

    root = Path(root)
    for sub in ("calibration", "background"):
        (root / sub).mkdir(parents=True, exist_ok=True)
    for i, cam in enumerate(cameras):
        fs = cv2.FileStorage(str(root / "calibration" / f"{cam.name}.yaml"), cv2.FILE_STORAGE_WRITE)
        fs.write("camera_matrix", cam.K)
        fs.write("distortion_coefficients", cam.dist.reshape(1, 5))
        fs.write("rvec", cv2.Rodrigues(cam.R)[0])
        fs.write("tvec", cam.t.reshape(3, 1))
        fs.write("image_width", cam.width)
        fs.write("image_height", cam.height)
        fs.release()
        cv2.imwrite(str(root / "background" / f"{cam.name}.png"), cv2.cvtColor(background[i], cv2.COLOR_RGB2BGR))
        (root / "frames" / cam.name).mkdir(parents=True, exist_ok=True)
        (root / "masks" / cam.name).mkdir(parents=True, exist_ok=True)
        for t in range(len(frames)):
            cv2.imwrite(str(root / "frames" / cam.name / f"{t:06d}.png"),
                        cv2.cvtColor(frames[t, i], cv2.COLOR_RGB2BGR))
            cv2.imwrite(str(root / "masks" / cam.name / f"{t:06d}.png"), labels[t, i].astype(np.uint8))
