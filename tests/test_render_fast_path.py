"""The fast production path equals the whole-image reference bit for bit; pooled noise statistics."""

from statistics import NormalDist

import numpy as np
import pytest

pytestmark = pytest.mark.render


def _reference(r, positions, cameras=None):
    """Whole-canvas draw, whole-image remap of RGB and labels: the unoptimised path."""
    idx = r._indices(cameras)
    canvases = r.raster.draw(r.view_projs[idx], positions, bands=idx).copy()
    return r._distort(canvases, idx)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_clean_frames_equal_the_whole_image_reference(lab, lab_renderer, seed):
    rng = np.random.default_rng(seed)
    positions = rng.uniform(0.3, 5.7, (lab.people.count, 2))
    if seed == 1:
        positions[0] = np.nan                                 # a hidden person
    cameras = None if seed != 2 else [2, 5, 9, 16]            # a subset, drawn in its own bands
    f = lab_renderer.render(positions, cameras=cameras, clean=True)
    rgb, labels = _reference(lab_renderer, positions, cameras)
    assert np.array_equal(f.rgb, rgb)
    assert np.array_equal(f.labels, labels)


def test_person_near_a_camera_is_still_exact(lab, lab_renderer):
    cam = lab.cameras[0]
    centre = -cam.R.T @ cam.t                                   # camera 1's position, world frame
    positions = np.array([[2.0, 2.0], [4.5, 3.0], [3.0, 4.3]])
    positions[0] = centre[:2] + 0.3 * (np.array([3.0, 3.0]) - centre[:2]) / np.linalg.norm(centre[:2] - 3.0)
    f = lab_renderer.render(positions, cameras=[1, 2], clean=True)
    rgb, labels = _reference(lab_renderer, positions, [1, 2])
    assert np.array_equal(f.rgb, rgb) and np.array_equal(f.labels, labels)


def _residual(noisy, clean):
    """Noise samples of one camera away from saturation, and the fitted gain."""
    clean, noisy = clean.astype(float), noisy.astype(float)
    inside = (clean > 20) & (clean < 230)
    c, x = clean[inside], noisy[inside]
    gain = (c * x).sum() / (c * c).sum()                       # least squares
    r = np.full(clean.shape, np.nan)
    r[inside] = x - np.rint(c * gain)
    return r, gain


def test_noise_is_gaussian_with_the_configured_std(lab, lab_renderer, three_people):
    clean = lab_renderer.render(three_people, cameras=[4], clean=True).rgb[0]
    noisy = lab_renderer.render(three_people, cameras=[4], rng=np.random.default_rng(11)).rgb[0]
    r, gain = _residual(noisy, clean)
    r = r[np.isfinite(r)]
    std = lab.render.noise_std
    assert abs(gain - 1) < 4 * lab.render.gain_jitter
    assert abs(r.std() - np.sqrt(std**2 + 1 / 12)) < 0.15      # rounded Gaussian
    assert abs(r.mean()) < 0.15
    within = 2 * NormalDist(0, std).cdf(2.5) - 1                # P(|round(z)| <= 2)
    assert abs(np.mean(np.abs(r) <= 2) - within) < 0.03


def test_noise_differs_between_frames_and_cameras(lab_renderer, three_people):
    rng = np.random.default_rng(3)
    clean = lab_renderer.render(three_people, cameras=[5, 6], clean=True).rgb
    f1 = lab_renderer.render(three_people, cameras=[5, 6], rng=rng).rgb
    f2 = lab_renderer.render(three_people, cameras=[5, 6], rng=rng).rgb
    a = [_residual(f1[k], clean[k])[0] for k in range(2)]
    b = [_residual(f2[k], clean[k])[0] for k in range(2)]
    for x, y in ((a[0], b[0]), (a[1], b[1]), (a[0], a[1])):   # frame to frame, camera to camera
        ok = np.isfinite(x) & np.isfinite(y)
        c = np.corrcoef(x[ok], y[ok])[0, 1]
        assert abs(c) < 0.02, c


def test_pool_offsets_and_gains_come_from_the_rng():
    from render.noise import POOL_EXTRA, draw_gains_offsets

    g1, o1 = draw_gains_offsets(16, 0.02, np.random.default_rng(0))
    g2, o2 = draw_gains_offsets(16, 0.02, np.random.default_rng(0))
    _, o3 = draw_gains_offsets(16, 0.02, np.random.default_rng(1))
    assert np.array_equal(g1, g2) and np.array_equal(o1, o2)
    assert not np.array_equal(o1, o3)
    assert o1.min() >= 0 and o1.max() <= POOL_EXTRA
    with pytest.raises(ValueError, match="rng"):
        draw_gains_offsets(2, 0.02, 5)
