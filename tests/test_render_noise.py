"""Sensor degradation without OpenGL: the noise pool, the gain and noise pass, ``degrade``."""

import numpy as np
import pytest

from render.noise import BIAS, POOL_EXTRA, POOL_SEED, degrade, draw_gains_offsets, noise_pool, sense


def test_the_pool_is_rounded_clipped_gaussian_samples_of_its_seed():
    """The whole pool, every chunk of it: one stream of N(0, 1) from the fixed seed, scaled,
    rounded, biased and clipped to 0..255 (a std of 100 clips ~10 % at each end)."""
    pool = noise_pool(100.0, 3000)
    z = np.random.default_rng(POOL_SEED).standard_normal(3000 + POOL_EXTRA, dtype=np.float32)
    expected = np.clip(np.rint(z * np.float32(100.0)) + BIAS, 0, 255).astype(np.uint8)
    assert pool.shape == (3000 + POOL_EXTRA,) and pool.dtype == np.uint8
    assert np.array_equal(pool, expected)
    signed = pool.astype(int) - BIAS
    assert signed.min() == -128 and signed.max() == 127                # the documented range
    assert not pool.flags.writeable
    with pytest.raises(ValueError):
        pool[0] = 1


def test_sense_by_hand():
    """dst = saturate(round(src * gain) + noise - BIAS): 150 + 1, 300 - 2 -> 255, 6 - 7 -> 0."""
    src = np.array([[100, 200, 4]], np.uint8)
    noise = np.array([[BIAS + 1, BIAS - 2, BIAS - 7]], np.uint8)
    dst = np.zeros_like(src)
    sense(dst, src, 1.5, noise)
    assert dst.tolist() == [[151, 255, 0]]
    sense(dst, src, 1.5, None)                       # no noise: the gain alone, saturated
    assert dst.tolist() == [[150, 255, 6]]
    sense(dst, src, 2.0, None)
    assert dst.tolist() == [[200, 255, 8]]
    sense(dst, src, 0.0, None)                       # a gain clipped at 0: black
    assert dst.tolist() == [[0, 0, 0]]
    sense(dst, src, 1.0, None)                       # neither: a copy
    assert dst.tolist() == [[100, 200, 4]] and src.tolist() == [[100, 200, 4]]
    sense(src, src, 0.5, noise)                      # in place
    assert src.tolist() == [[51, 98, 0]]


def test_gains_are_one_plus_jitter_clipped_at_zero_and_offsets_in_the_pool():
    g, o = draw_gains_offsets(2000, 1.0, np.random.default_rng(4))
    rng = np.random.default_rng(4)
    z = rng.standard_normal(2000)
    np.testing.assert_array_equal(g, np.maximum(0.0, 1.0 + z))   # the gains are drawn first
    assert (g == 0).sum() > 200                                   # P(z < -1) ~ 16 %
    assert o.shape == (2000,) and o.min() >= 0 and o.max() <= POOL_EXTRA
    assert o.max() > 0.99 * POOL_EXTRA and o.min() < 0.01 * POOL_EXTRA


def test_degrade_takes_each_cameras_pool_window_at_its_offset():
    """Camera i: saturate(round(rgb * gain_i) + pool[offset_i: offset_i + H W 3] - BIAS),
    the window laid out row by row over (H, W, 3)."""
    rng = np.random.default_rng(0)
    rgb = rng.integers(0, 256, (3, 4, 5, 3), dtype=np.uint8)
    pool = rng.integers(BIAS - 6, BIAS + 7, 60 + POOL_EXTRA, dtype=np.uint8)
    gains, offsets = draw_gains_offsets(3, 0.1, np.random.default_rng(9))
    expected = []
    for i in range(3):
        window = pool[offsets[i]:offsets[i] + 60].reshape(4, 5, 3).astype(float)
        expected.append(np.clip(np.rint(rgb[i] * gains[i]) + window - BIAS, 0, 255))
    out = degrade(rgb.copy(), 2.0, 0.1, np.random.default_rng(9), pool=pool)
    np.testing.assert_allclose(out, np.array(expected), atol=1)       # round(x.5) either way
    assert np.mean(out == np.array(expected)) > 0.99


def test_degrade_without_noise_applies_the_gain_alone_in_place():
    rgb = np.random.default_rng(1).integers(0, 256, (2, 3, 4, 3), dtype=np.uint8)
    gains, _ = draw_gains_offsets(2, 0.3, np.random.default_rng(2))
    out = rgb.copy()
    assert degrade(out, 0.0, 0.3, np.random.default_rng(2)) is out
    expected = np.clip(np.rint(rgb * gains[:, None, None, None]), 0, 255)
    np.testing.assert_allclose(out, expected, atol=1)
    same = rgb.copy()
    degrade(same, 0.0, 0.0, np.random.default_rng(2))
    assert np.array_equal(same, rgb)


def test_degrade_builds_the_pool_of_its_noise_std_for_one_camera():
    rgb = np.random.default_rng(5).integers(0, 256, (1, 3, 4, 3), dtype=np.uint8)
    built = degrade(rgb.copy(), 0.5, 0.02, np.random.default_rng(3))
    given_pool = degrade(rgb.copy(), 0.5, 0.02, np.random.default_rng(3), pool=noise_pool(0.5, 36))
    assert np.array_equal(built, given_pool)
    gain_only = degrade(rgb.copy(), 0.0, 0.02, np.random.default_rng(3))
    assert not np.array_equal(built, gain_only)


def test_sense_rounds_the_gain_product_without_offset():
    """A gain alone: saturate(src * gain), whole products staying whole (1 * 3, 3 * 3, 85 * 3 = 255)."""
    src = np.array([[1, 3, 85, 86]], np.uint8)
    dst = np.zeros_like(src)
    sense(dst, src, 3.0, None)
    assert dst.tolist() == [[3, 9, 255, 255]]


def test_offsets_are_uniform_over_every_window_of_the_pool_after_the_gains():
    """Offsets 0..POOL_EXTRA inclusive (the pool holds POOL_EXTRA + 1 windows of one frame), drawn
    after the n gains from the same stream."""
    n = 100_000
    _, o = draw_gains_offsets(n, 0.1, np.random.default_rng(11))
    rng = np.random.default_rng(11)
    rng.standard_normal(n)
    assert np.array_equal(o, rng.integers(0, POOL_EXTRA + 1, n))


@pytest.mark.parametrize("rng", [0, np.random.RandomState(0), None])
def test_gains_want_a_generator(rng):
    with pytest.raises(ValueError, match="rng: expected an np.random.Generator"):
        draw_gains_offsets(2, 0.1, rng)
    with pytest.raises(ValueError, match="rng"):
        degrade(np.zeros((2, 3, 4, 3), np.uint8), 2.0, 0.1, rng)


def test_degrade_without_noise_ignores_a_given_pool_and_builds_none(monkeypatch):
    """noise_std 0: the gain alone, even with a pool at hand, and no pool is built."""
    import render.noise

    rgb = np.random.default_rng(6).integers(0, 256, (2, 3, 4, 3), dtype=np.uint8)
    gains, _ = draw_gains_offsets(2, 0.2, np.random.default_rng(8))
    expected = np.clip(np.rint(rgb * gains[:, None, None, None]), 0, 255)
    pool = np.full(36 + POOL_EXTRA, BIAS + 50, np.uint8)           # +50 everywhere, if it were used
    out = degrade(rgb.copy(), 0.0, 0.2, np.random.default_rng(8), pool=pool)
    np.testing.assert_allclose(out, expected, atol=1)

    def no_pool(*args):
        raise AssertionError("noise_pool built for noise_std 0")

    monkeypatch.setattr(render.noise, "noise_pool", no_pool)
    out = degrade(rgb.copy(), 0.0, 0.2, np.random.default_rng(8))
    np.testing.assert_allclose(out, expected, atol=1)


@pytest.mark.parametrize("shape, index", [
    ((2, 4, 5, 4), np.s_[..., :3]),             # the RGB of an RGBA buffer
    ((2, 4, 5, 3), np.s_[..., ::-1]),           # a BGR view
    ((2, 4, 7, 3), np.s_[:, :, :5]),            # a crop
], ids=["rgb-of-rgba", "bgr", "crop"])
def test_degrade_modifies_a_view_in_place(shape, index):
    """Frames whose rows' bytes are not contiguous are degraded in place as a contiguous copy is (not
    returned clean), and the rest of their buffer is left alone."""
    buffer = np.random.default_rng(12).integers(0, 256, shape, dtype=np.uint8)
    rgb = buffer[index]
    expected = degrade(rgb.copy(), 2.0, 0.1, np.random.default_rng(3))
    assert not np.array_equal(expected, rgb)
    rest = buffer.copy()
    rest[index] = expected
    assert degrade(rgb, 2.0, 0.1, np.random.default_rng(3)) is rgb
    assert np.array_equal(buffer, rest)


def test_the_pool_is_built_once_per_noise_std_and_frame_size():
    """The pool degrade builds when none is given is cached: one (noise_std, size) gives the
    same array on every call (not 8 M fresh samples per frame), another noise_std another."""
    pool = noise_pool(1.5, 24)
    assert noise_pool(1.5, 24) is pool
    assert noise_pool(3.0, 24) is not pool
