"""The hull-centre tracker and its ground-truth metrics."""

import warnings

import numpy as np
import pytest

from tasking.track_metrics import tracking_metrics
from tasking.tracker import Tracker, TrackerParams


def _walk(n_frames, dt, starts, velocities):
    t = np.arange(n_frames)[:, None, None] * dt
    return np.asarray(starts)[None] + t * np.asarray(velocities)[None]


def test_two_objects_keep_their_ids_and_positions():
    params = TrackerParams(dt=0.1)
    truth = _walk(40, 0.1, [[0.0, 0.0], [2.0, 1.0]], [[0.5, 0.2], [-0.3, 0.4]])
    rng = np.random.default_rng(0)
    tracker = Tracker(params)
    seen = {}
    for t, xy in enumerate(truth):
        ids, est = tracker.step(xy + rng.normal(0, 0.02, xy.shape))
        for i, p in zip(ids, est):
            obj = int(np.argmin(np.linalg.norm(xy - p, axis=1)))
            seen.setdefault(int(i), set()).add(obj)
            assert np.linalg.norm(xy[obj] - p) < 0.1
    assert len(seen) == 2 and all(len(v) == 1 for v in seen.values())


def test_phantoms_without_temporal_support_are_never_confirmed():
    rng = np.random.default_rng(1)
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=3))
    real = np.array([[1.0, 1.0]])
    for _ in range(30):
        phantom = rng.uniform(2, 6, (1, 2))  # a different place every frame
        ids, est = tracker.step(np.vstack([real, phantom]))
        assert len(ids) <= 1
    assert len(ids) == 1 and np.allclose(est, real, atol=0.05)
    assert len(tracker.estimates()) == 1


def test_a_track_survives_a_short_gap_and_ends_after_max_missed():
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2, max_missed=3))
    for t in range(5):
        ids, _ = tracker.step([[0.1 * t, 0.0]])
    first = ids.tolist()
    tracker.step(np.zeros((0, 2)))
    ids, est = tracker.step([[0.6, 0.0]])
    assert ids.tolist() == first and np.allclose(est, [[0.6, 0.0]], atol=0.05)
    for _ in range(3):
        tracker.step(np.zeros((0, 2)))
    assert len(tracker.ids) == 0


def test_bad_parameters():
    with pytest.raises(ValueError, match="tracker.gate: expected a finite number > 0"):
        TrackerParams(gate=0)
    with pytest.raises(ValueError, match="tracker.confirm_hits: expected an integer >= 1"):
        TrackerParams(confirm_hits=0)
    with pytest.raises(ValueError, match=r"detections: expected shape \(n, 2\), got \(3,\)"):
        Tracker().step([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="detections: expected finite numbers"):
        Tracker().step(np.full((1, 2), np.nan))


def test_metrics_on_a_hand_computed_case():
    truth_ids = [[0, 1], [0, 1], [0, 1]]
    truth_xy = [[[0, 0], [1, 0]]] * 3
    # frame 0: both matched (errors 0.1 and 0.2); frame 1: object 1 missed;
    # frame 2: a false track far away as well
    track_ids = [[7, 8], [7], [7, 8, 9]]
    track_xy = [[[0.1, 0], [1.2, 0]], [[0.1, 0]], [[0.1, 0], [1.2, 0], [5, 5]]]
    m = tracking_metrics(truth_ids, truth_xy, track_ids, track_xy, max_distance=0.5)
    assert m["matches"] == 5
    assert m["mse"] == pytest.approx((3 * 0.01 + 2 * 0.04) / 5)
    assert m["motp"] == pytest.approx((3 * 0.1 + 2 * 0.2) / 5)
    assert m["mota"] == pytest.approx(1 - (1 + 1) / 6)   # one miss, one false positive
    with pytest.raises(ValueError, match="same number of frames"):
        tracking_metrics(truth_ids, truth_xy, track_ids[:2], track_xy, 0.5)


@pytest.mark.parametrize("short", range(4))
def test_metrics_refuse_any_argument_with_another_number_of_frames(short):
    """Two frames each, one argument cut to its first frame: zip would compare fewer frames."""
    args = [[[0], [0]], [[[0.0, 0.0]], [[0.0, 0.0]]], [[7], [7]], [[[0.1, 0.0]], [[0.1, 0.0]]]]
    args[short] = args[short][:1]
    with pytest.raises(ValueError, match="same number of frames in every argument"):
        tracking_metrics(*args, max_distance=0.5)


def test_metrics_gate_is_a_distance_not_a_squared_distance():
    # 0.6 m away with max_distance 0.5 m: no match (0.36 m^2 is below 0.5, above 0.25)
    m = tracking_metrics([[0]], [[[0.0, 0.0]]], [[7]], [[[0.6, 0.0]]], 0.5)
    assert m["matches"] == 0 and m["mota"] == -1.0 and np.isnan(m["mse"])


def test_a_track_exactly_max_distance_away_still_matches():
    """Only a track farther than max_distance cannot match: one exactly 0.5 m away (0.25 m^2,
    exact in binary) matches, with mse 0.25 m^2 and motp 0.5 m."""
    m = tracking_metrics([[0]], [[[1.0, 2.0]]], [[7]], [[[1.5, 2.0]]], 0.5)
    assert m["matches"] == 1 and m["misses"] == 0 and m["false_positives"] == 0
    assert (m["mse"], m["motp"], m["mota"]) == (0.25, 0.5, 1.0)


def test_no_match_gives_nan_errors_without_a_warning():
    """With no matched object-frame, mse and motp are NaN, not the mean of an empty array
    (NumPy's "Mean of empty slice" RuntimeWarning)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        m = tracking_metrics([[0]], [[[0.0, 0.0]]], [[7]], [[[0.6, 0.0]]], 0.5)
    assert m["matches"] == 0 and np.isnan(m["mse"]) and np.isnan(m["motp"])


def test_metrics_with_a_miss_and_an_identity_switch():
    # one object over 4 frames: tracked by 7, 7, missed, then by 8 (a switch)
    z = [[0.0, 0.0]]
    m = tracking_metrics([[0]] * 4, [z] * 4, [[7], [7], [], [8]], [[[0.1, 0.0]], [[0.1, 0.0]], [], [[0.2, 0.0]]], 0.5)
    assert m["switches"] == 1
    assert m["mse"] == pytest.approx((0.01 + 0.01 + 0.04) / 3)      # the switch frame is matched too
    assert m["motp"] == pytest.approx(0.4 / 3)
    assert m["mota"] == pytest.approx(1 - (1 + 1) / 4)              # 1 miss, 1 switch, 4 objects
    assert m["idf1"] == pytest.approx(2 * 2 / (2 * 2 + 1 + 2))     # IDTP 2 (0<->7), IDFP 1, IDFN 2


def test_a_track_is_confirmed_on_its_confirm_hits_th_consecutive_match():
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=3))
    assert [len(tracker.step([[1.0, 1.0]])[0]) for _ in range(4)] == [0, 0, 1, 1]


def test_a_tentative_track_that_misses_once_is_dropped():
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2, max_missed=3))
    tracker.step([[1.0, 1.0]])
    tracker.step(np.zeros((0, 2)))
    assert tracker.ids.size == 0


def test_estimates_are_next_frame_predictions():
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2))
    for t in range(30):
        tracker.step([[0.1 * t, 0.0]])              # 1 m/s along x
    np.testing.assert_allclose(tracker.estimates(), [[3.0, 0.0]], atol=0.01)


def test_metrics_count_false_positives_and_misses():
    """MOTA's terms are reported: one phantom track-frame and one missed object-frame."""
    from tasking.track_metrics import tracking_metrics
    truth_ids = [[0], [0]]
    truth_xy = [[[0.0, 0.0]], [[0.0, 0.0]]]
    track_ids = [[1, 2], []]
    track_xy = [[[0.05, 0.0], [3.0, 3.0]], np.zeros((0, 2))]
    m = tracking_metrics(truth_ids, truth_xy, track_ids, track_xy, 0.5)
    assert m["false_positives"] == 1 and m["misses"] == 1 and m["matches"] == 1
    assert m["mota"] == 1 - (m["false_positives"] + m["misses"] + m["switches"]) / 2


def test_false_positives_and_misses_are_not_taken_for_each_other():
    """Two phantom track-frames and no miss, then one miss and no phantom: the counts differ."""
    z = [[0.0, 0.0]]
    m = tracking_metrics([[0], [0]], [z, z], [[7, 8, 9], []], [[[0.1, 0.0], [3.0, 3.0], [4.0, 0.0]], []], 0.5)
    assert (m["false_positives"], m["misses"], m["matches"], m["switches"]) == (2, 1, 1, 0)
    assert m["mota"] == pytest.approx(1 - (2 + 1) / 2)


def test_matches_count_the_switch_frames_that_mse_averages_over():
    """``matches`` left out the frames of an identity switch (py-motmetrics' num_matches),
    though ``mse`` and ``motp`` average over them: matches + misses != object-frames."""
    z = [[0.0, 0.0]]
    m = tracking_metrics([[0]] * 4, [z] * 4, [[7], [7], [], [8]], [[[0.1, 0.0]], [[0.1, 0.0]], [], [[0.2, 0.0]]], 0.5)
    assert m["switches"] == 1 and m["misses"] == 1
    assert m["matches"] == 3                              # frames 0, 1 and the switch frame 3
    assert m["matches"] + m["misses"] == 4                # every object-frame is one or the other


def test_a_constant_velocity_walk_is_tracked_without_lag():
    """Exact detections of a person walking at constant velocity, far from the origin: the
    constant-velocity filter's error dies out (no lag, no bias) and estimates() is where
    the person will be at the next frame."""
    dt = 1 / 7.5
    truth = _walk(80, dt, [[4.0, 3.0]], [[0.6, -0.4]])
    tracker = Tracker(TrackerParams(dt=dt))
    for xy in truth[:-1]:
        _, est = tracker.step(xy)
    np.testing.assert_allclose(est, truth[-2], atol=1e-4)
    np.testing.assert_allclose(tracker.estimates(), truth[-1], atol=1e-4)


@pytest.mark.parametrize("accel_std, meas_std", [(0.3, 0.05), (2.0, 0.08), (None, None)])
def test_the_filter_settles_to_the_steady_state_of_the_constant_velocity_model(accel_std, meas_std):
    """After many updates a track's covariance is the textbook steady state of the
    discrete white-noise-acceleration model (Kalata's tracking index lam = accel_std dt^2 /
    meas_std gives the alpha-beta gains; Bar-Shalom et al., Estimation with Applications to
    Tracking, 6.5), per axis, with the axes uncorrelated. None: the defaults, 7.5 Hz (the
    paper's frame rate), 2 m/s^2 and 0.08 m."""
    dt = 1 / 7.5
    if accel_std is None:
        tracker, accel_std, meas_std = Tracker(), 2.0, 0.08
    else:
        tracker = Tracker(TrackerParams(dt=dt, accel_std=accel_std, meas_std=meas_std))
    for _ in range(300):
        tracker.step([[3.0, 2.0]])
    lam = accel_std * dt**2 / meas_std
    root = np.sqrt(lam**2 + 8 * lam)
    alpha = -(lam**2 + 8 * lam - (lam + 4) * root) / 8
    beta = (lam**2 + 4 * lam - lam * root) / 4
    axis = meas_std**2 * np.array([[alpha, beta / dt],
                                   [beta / dt, beta * (alpha - beta / 2) / ((1 - alpha) * dt**2)]])
    want = np.zeros((4, 4))
    want[np.ix_([0, 2], [0, 2])] = want[np.ix_([1, 3], [1, 3])] = axis     # state x, y, vx, vy
    np.testing.assert_allclose(tracker.P[0], want, rtol=1e-6, atol=1e-12)


def test_a_confirmed_track_lives_through_max_missed_minus_one_misses():
    """Hysteresis: a confirmed track ends on its max_missed-th consecutive miss, not before;
    seen again after max_missed - 1 misses it goes on under its id."""
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2, max_missed=3))
    for _ in range(3):
        ids, _ = tracker.step([[1.0, 1.0]])
    for _ in range(2):
        tracker.step(np.zeros((0, 2)))
    assert tracker.step([[1.0, 1.0]])[0].tolist() == ids.tolist()


def test_default_parameters_confirm_on_the_third_match_and_end_on_the_third_miss():
    """The loop and the studies keep the defaults confirm_hits = 3 and max_missed = 3."""
    tracker = Tracker()
    assert [len(tracker.step([[1.0, 1.0]])[0]) for _ in range(4)] == [0, 0, 1, 1]
    for _ in range(2):
        tracker.step(np.zeros((0, 2)))
    assert tracker.ids.tolist() == [0]                 # two misses: still alive
    tracker.step(np.zeros((0, 2)))
    assert tracker.ids.size == 0                       # the third ends it


def test_default_gate_is_half_a_metre():
    """A stationary track (its prediction exactly where it was) matches a detection 0.5 m
    away but not one 0.55 m away, which starts a new track instead."""
    for dist, same in ((0.5, True), (0.55, False)):
        tracker = Tracker()
        tracker.step([[1.0, 1.0]])
        tracker.step([[1.0 + dist, 1.0]])
        assert tracker.ids.tolist() == ([0] if same else [1])


@pytest.mark.parametrize("field, value", [("dt", 0.0), ("dt", -0.1), ("dt", np.inf), ("gate", -1.0),
                                          ("accel_std", 0.0), ("meas_std", 0.0), ("max_missed", 0)])
def test_every_parameter_is_checked(field, value):
    with pytest.raises(ValueError, match=f"tracker.{field}"):
        TrackerParams(**{field: value})


def test_the_second_frame_is_one_textbook_kalman_update_from_the_birth_prior():
    """Born at z0 with covariance diag(meas_std^2, 1 (m/s)^2) per axis and no velocity, then
    one predict and one update with z1, written out per axis in scalars: prior P = F P0 F' +
    Q with Q = accel_std^2 [[dt^4/4, dt^3/2], [dt^3/2, dt^2]], gain K = P[:, 0] / (P00 +
    meas_std^2)."""
    dt, a, s = 0.2, 1.5, 0.1
    tracker = Tracker(TrackerParams(dt=dt, accel_std=a, meas_std=s, confirm_hits=2))
    z0, z1 = np.array([2.0, 1.0]), np.array([2.12, 0.95])
    tracker.step([z0])
    ids, xy = tracker.step([z1])
    p00 = s**2 + dt**2 + a**2 * dt**4 / 4
    p01 = dt + a**2 * dt**3 / 2
    k0, k1 = p00 / (p00 + s**2), p01 / (p00 + s**2)
    pos, vel = z0 + k0 * (z1 - z0), k1 * (z1 - z0)
    assert ids.tolist() == [0]
    np.testing.assert_allclose(xy, [pos], rtol=0, atol=1e-12)
    np.testing.assert_allclose(tracker.x[0, 2:], vel, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tracker.estimates(), [pos + dt * vel], rtol=0, atol=1e-12)


def test_a_confirmed_track_is_not_reported_on_a_frame_it_misses():
    """tracks() are the confirmed tracks seen this frame: a coasting track is alive but absent."""
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2, max_missed=3))
    for _ in range(2):
        tracker.step([[1.0, 1.0]])
    ids, xy = tracker.step(np.zeros((0, 2)))
    assert ids.size == 0 and xy.shape == (0, 2) and tracker.ids.tolist() == [0]


def test_every_unmatched_detection_starts_a_track_with_a_new_id():
    """Ids are never reused: three people at once get 0, 1, 2, and two later ones 3, 4."""
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=1))
    ids, xy = tracker.step([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    assert ids.tolist() == [0, 1, 2]                  # confirm_hits = 1: confirmed at birth
    np.testing.assert_array_equal(xy, [[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    ids, _ = tracker.step([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0], [0.0, 3.0], [3.0, 3.0]])
    assert ids.tolist() == [0, 1, 2, 3, 4]


def test_no_detections_may_be_an_empty_list():
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=1))
    tracker.step([[1.0, 1.0]])
    ids, xy = tracker.step([])
    assert ids.size == 0 and xy.shape == (0, 2) and tracker.missed.tolist() == [1]


def test_a_detection_exactly_at_the_gate_matches_though_a_farther_one_comes_first():
    """Gated matching: 0.6 m is outside the 0.5 m gate and 0.5 m (exact in binary) inside,
    whatever the detections' order."""
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=1))
    tracker.step([[1.0, 1.0]])                         # stationary: predicted at (1, 1) exactly
    ids, xy = tracker.step([[1.6, 1.0], [1.5, 1.0]])
    assert ids.tolist() == [0, 1]                      # 0 took (1.5, 1); (1.6, 1) is a new track
    assert 1.0 < xy[0, 0] < 1.5 and xy[1].tolist() == [1.6, 1.0]


@pytest.mark.parametrize("scale", [1.0, 1000.0])
def test_matching_first_maximises_the_matches_inside_the_gate(scale):
    """Tracks A at (0, 0) and B at (3, 0), gate 2; detections (1.5, 0) (1.5 m from both) and
    (-1.5, 0) (1.5 m from A, 4.5 m from B). Both tracks match (A the second, B the first),
    though A to the first alone would be cheaper. Scaled by 1000 (a 2 km gate, A to the
    first alone 1.5 km against the two matches' 3 km), the same: the penalty that keeps
    pairs out of the gate does not cap the matching."""
    tracker = Tracker(TrackerParams(dt=0.1, gate=2.0 * scale, confirm_hits=1))
    tracker.step([[0.0, 0.0], [3.0 * scale, 0.0]])
    ids, xy = tracker.step([[1.5 * scale, 0.0], [-1.5 * scale, 0.0]])
    assert ids.tolist() == [0, 1] and tracker.missed.tolist() == [0, 0]
    assert xy[0, 0] < 0 and 1.5 * scale < xy[1, 0] < 3 * scale


def test_a_confirmed_track_wins_a_detection_within_a_micrometre_over_a_tentative_one():
    """Confirmed tracks get first pick: A confirmed at (1, 1), B tentative at (2, 1), a
    detection 1e-7 m nearer B than the midpoint goes to A (B is dropped: a tentative miss)."""
    tracker = Tracker(TrackerParams(dt=0.1, gate=0.75, confirm_hits=2))
    tracker.step([[1.0, 1.0]])
    tracker.step([[1.0, 1.0], [2.0, 1.0]])             # A confirmed, B born
    assert tracker.confirmed.tolist() == [True, False]
    ids, _ = tracker.step([[1.5 + 1e-7, 1.0]])
    assert ids.tolist() == [0] and tracker.ids.tolist() == [0]


def test_the_gate_is_a_euclidean_distance():
    """(0.4, 0.4) m from a stationary track is 0.566 m away, outside the 0.5 m gate though
    each coordinate is inside it: a new track; (0.3, 0.3) m is 0.424 m away: a match."""
    for offset, same in ((0.4, False), (0.3, True)):
        tracker = Tracker()
        tracker.step([[1.0, 1.0]])
        tracker.step([[1.0 + offset, 1.0 + offset]])
        assert tracker.ids.tolist() == ([0] if same else [1])


def test_a_detection_outside_every_gate_does_not_steer_the_matching():
    """Tracks A at (0, 0) and B at (3, 0), gate 2; detections (1.4, 0) (1.4 m from A, 1.6 m
    from B) and (-5, 0) (outside both gates). A takes the first: pairing B with it and A
    with the far one costs less in total (1.6 + 5 < 1.4 + 8), but that pair is no match."""
    tracker = Tracker(TrackerParams(dt=0.1, gate=2.0, confirm_hits=1))
    tracker.step([[0.0, 0.0], [3.0, 0.0]])
    ids, xy = tracker.step([[1.4, 0.0], [-5.0, 0.0]])
    assert ids.tolist() == [0, 2] and tracker.missed.tolist() == [0, 1, 0]
    assert 0 < xy[0, 0] < 1.4 and xy[1].tolist() == [-5.0, 0.0]


def test_hits_count_consecutive_matches_and_restart_after_a_miss():
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2, max_missed=3))
    for _ in range(3):
        tracker.step([[1.0, 1.0]])
    assert tracker.hits.tolist() == [3]
    tracker.step(np.zeros((0, 2)))
    assert tracker.hits.tolist() == [0] and tracker.missed.tolist() == [1]
    tracker.step([[1.0, 1.0]])
    assert tracker.hits.tolist() == [1] and tracker.missed.tolist() == [0]


def test_a_track_born_beside_an_established_one_starts_from_the_birth_prior():
    """B is born at z0 while A has been tracked for 10 frames; B's second frame is still the
    textbook one-step update of test_the_second_frame_is_one_textbook_kalman_update_from_the_birth_prior
    (B gets the birth covariance, A keeps its own)."""
    dt, a, s = 0.2, 1.5, 0.1
    tracker = Tracker(TrackerParams(dt=dt, accel_std=a, meas_std=s, confirm_hits=2))
    far = [5.0, 5.0]
    for _ in range(10):
        tracker.step([far])
    z0, z1 = np.array([2.0, 1.0]), np.array([2.12, 0.95])
    tracker.step([far, z0])
    np.testing.assert_allclose(tracker.P[1], np.diag([s**2, s**2, 1.0, 1.0]), rtol=0, atol=0)
    ids, xy = tracker.step([far, z1])
    p00 = s**2 + dt**2 + a**2 * dt**4 / 4
    p01 = dt + a**2 * dt**3 / 2
    k0, k1 = p00 / (p00 + s**2), p01 / (p00 + s**2)
    assert ids.tolist() == [0, 1]
    np.testing.assert_allclose(xy[1], z0 + k0 * (z1 - z0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(tracker.x[1, 2:], k1 * (z1 - z0), rtol=0, atol=1e-12)


def test_the_gate_is_measured_from_the_prediction_not_the_last_position():
    """A person walking 0.4 m a frame along x, tracked for 30 frames: the next detection,
    0.7 m beyond the last one (outside the 0.5 m gate) but 0.3 m beyond where the track
    predicts it, still matches the track."""
    tracker = Tracker(TrackerParams(dt=0.1))
    for t in range(30):
        ids, _ = tracker.step([[0.4 * t, 1.0]])
    ids_next, _ = tracker.step([[0.4 * 29 + 0.7, 1.0]])
    assert ids.tolist() == [0] and ids_next.tolist() == [0] and tracker.ids.tolist() == [0]


def test_estimates_keep_a_confirmed_track_that_missed_a_frame():
    """A confirmed track coasting through a miss still gives tasking its prediction: the
    stationary person at (1, 2) is still expected there."""
    tracker = Tracker(TrackerParams(dt=0.1, confirm_hits=2, max_missed=3))
    for _ in range(5):
        tracker.step([[1.0, 2.0]])
    tracker.step(np.zeros((0, 2)))
    np.testing.assert_allclose(tracker.estimates(), [[1.0, 2.0]], rtol=0, atol=1e-9)
