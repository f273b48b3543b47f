"""Tracking accuracy against ground truth: MSE of matched positions and CLEAR-MOT/IDF1.

py-motmetrics computes MOTA, MOTP and IDF1 from per-frame distance matrices. Its
``distances`` helpers call ``np.asfarray`` (removed in numpy 2), so distances are
computed here and only the accumulator is used.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def tracking_metrics(truth_ids: Sequence, truth_xy: Sequence, track_ids: Sequence, track_xy: Sequence,
                     max_distance: float) -> dict:
    """Compare tracks with ground truth over frames.

    truth_ids, track_ids : per frame, (m_t,) and (n_t,) int ids
    truth_xy, track_xy : per frame, (m_t, 2) and (n_t, 2) float, metres, world frame
    max_distance : metres; a track farther than this from a true object cannot match it
    Returns ``mse`` (mean squared error of matched positions, square metres), ``mota``,
    ``motp`` (mean matched distance, metres), ``idf1``, ``switches`` (identity switches),
    ``matches`` (object-frames matched to a track, the frames of an identity switch
    included: what ``mse`` and ``motp`` average over), ``false_positives`` (track-frames
    matched to no object) and ``misses`` (object-frames matched to no track):
    matches + misses = object-frames, and
    MOTA = 1 - (false_positives + misses + switches) / object-frames.

    >>> m = tracking_metrics([[0]], [[[0.0, 0.0]]], [[5]], [[[0.1, 0.0]]], 0.5)
    >>> round(m["mse"], 6), m["mota"], round(m["motp"], 6)
    (0.01, 1.0, 0.1)
    """
    import motmetrics as mm

    if not (len(truth_ids) == len(truth_xy) == len(track_ids) == len(track_xy)):
        raise ValueError("tracking_metrics: expected the same number of frames in every argument")
    acc = mm.MOTAccumulator(auto_id=True)
    for gid, gxy, hid, hxy in zip(truth_ids, truth_xy, track_ids, track_xy):
        gxy = np.asarray(gxy, float).reshape(-1, 2)
        hxy = np.asarray(hxy, float).reshape(-1, 2)
        d = np.linalg.norm(gxy[:, None] - hxy[None], axis=-1) ** 2
        d[d > max_distance**2] = np.nan
        acc.update(list(np.asarray(gid).tolist()), list(np.asarray(hid).tolist()), d)
    summary = mm.metrics.create().compute(
        acc, metrics=["mota", "motp", "idf1", "num_switches",
                      "num_false_positives", "num_misses"], name="run")
    row = summary.iloc[0]
    events = acc.mot_events
    matched = events[events["Type"].isin(["MATCH", "SWITCH"])]["D"].to_numpy(float)
    mse = float(np.mean(matched)) if matched.size else float("nan")
    return {
        "mse": mse,
        "mota": float(row["mota"]),
        "motp": float(np.mean(np.sqrt(matched))) if matched.size else float("nan"),
        "idf1": float(row["idf1"]),
        "switches": int(row["num_switches"]),
        "matches": int(matched.size),        # py-motmetrics' num_matches leaves out the switches
        "false_positives": int(row["num_false_positives"]),
        "misses": int(row["num_misses"]),
    }
