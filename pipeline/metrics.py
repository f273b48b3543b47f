"""CDnet-2014 metrics of a binary detection against ground truth.

recall = TP / (TP + FN), precision = TP / (TP + FP), F = 2 P R / (P + R),
PWC = 100 (FN + FP) / (TP + FN + FP + TN), specificity = TN / (TN + FP).
Empty denominators: recall (no positives to find) and precision (nothing claimed) are 1,
specificity likewise; F is 0 when P + R = 0.

>>> m = cdnet_metrics(tp=8, fp=2, fn=2, tn=88)
>>> (m["recall"], m["precision"], round(m["f1"], 3), m["pwc"])
(0.8, 0.8, 0.8, 4.0)
"""

from __future__ import annotations

import numpy as np


def confusion(pred, truth, axis=None) -> dict:
    """TP, FP, FN, TN counts of bool arrays (summed over ``axis``; all axes by default)."""
    p, t = np.asarray(pred, bool), np.asarray(truth, bool)
    if p.shape != t.shape:
        raise ValueError(f"pred: expected the shape of the ground truth {t.shape}, got {p.shape}")
    tp = np.count_nonzero(p & t, axis=axis)
    fp = np.count_nonzero(p & ~t, axis=axis)
    fn = np.count_nonzero(~p & t, axis=axis)
    tn = np.count_nonzero(~p & ~t, axis=axis)
    return {"tp": tp, "fp": fp, "fn": fn, "tn": tn}


def _ratio(num, den):
    num, den = np.asarray(num, float), np.asarray(den, float)
    return np.where(den > 0, num / np.where(den > 0, den, 1), 1.0)


def cdnet_metrics(tp, fp, fn, tn) -> dict:
    """Recall, precision, F-measure, PWC and specificity; scalars or arrays alike."""
    recall = _ratio(tp, np.add(tp, fn))
    precision = _ratio(tp, np.add(tp, fp))
    s = recall + precision
    f1 = np.where(s > 0, 2 * recall * precision / np.where(s > 0, s, 1), 0.0)
    total = np.add(np.add(tp, fp), np.add(fn, tn))
    pwc = np.where(total > 0, 100.0 * np.add(fn, fp) / np.where(total > 0, total, 1), 0.0)
    out = {"recall": recall, "precision": precision, "f1": f1, "pwc": pwc,
           "specificity": _ratio(tn, np.add(tn, fp))}
    return {k: (float(v) if np.ndim(v) == 0 else v) for k, v in out.items()}


def evaluate(pred, truth, camera_axis: int) -> dict:
    """Overall and per-camera metrics of ``pred`` vs ``truth`` (bool arrays, same shape).

    camera_axis : the axis indexing cameras. Returns a JSON-ready dict:
    ``{"tp", "fp", "fn", "tn", "recall", "precision", "f1", "pwc", "specificity",
    "per_camera": [{...}, ...]}``.
    """
    p, t = np.asarray(pred, bool), np.asarray(truth, bool)
    total = confusion(p, t)
    axes = tuple(a for a in range(p.ndim) if a != camera_axis % p.ndim)
    per = confusion(p, t, axis=axes)
    result = {k: int(v) for k, v in total.items()} | cdnet_metrics(**total)
    per_metrics = cdnet_metrics(**per)
    result["per_camera"] = [
        {k: int(per[k][i]) for k in per} | {k: float(per_metrics[k][i]) for k in per_metrics}
        for i in range(p.shape[camera_axis])
    ]
    return result
