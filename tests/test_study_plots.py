"""The --plot figures of `camtask study`: what is drawn and how it is labelled, read from the
figure's artists (not its pixels)."""

import re

import pytest

from testbed.studies import cameras


@pytest.fixture
def drawn(monkeypatch):
    """Figures a study's plot() would save, drawn (ticks and labels resolved), not written."""
    figures = []

    def keep(fig, path):
        fig.canvas.draw()
        figures.append(fig)

    monkeypatch.setattr(cameras, "save_figure", keep)
    yield figures
    import matplotlib.pyplot as plt
    plt.close("all")


def cameras_result(objects=(1, 2, 3), ns=range(2, 17)):
    """Records as `study cameras` makes them: residual ~ 2 / N^2 + limit, limit m^2 / 200."""
    recs = []
    for m in objects:
        lim = (m - 1) ** 2 / 200
        for n in ns:
            res = 2 * m / n**2 + lim
            recs.append({"objects": m, "cameras": n, "limit": False, "residual": res, "residual_sem": 0.01,
                         "residual_raw": res, "scaled": res / lim if lim else None, "excess": res - lim, "trials": 5})
        recs.append({"objects": m, "cameras": None, "limit": True, "method": "exact", "residual": lim,
                     "residual_sem": 0.001, "residual_raw": lim, "scaled": 1.0 if lim else None, "excess": 0.0,
                     "trials": 5})
    return {"records": recs}


def visible_tick_labels(axis):
    """The texts of the labelled ticks (major and minor) inside the axis' view."""
    lo, hi = sorted(axis.get_view_interval())
    ticks = [*axis.get_major_ticks(), *axis.get_minor_ticks()]
    return [t.label1.get_text() for t in ticks
            if t.label1.get_visible() and t.label1.get_text() and lo <= t.get_loc() <= hi]


@pytest.mark.parametrize("ns", [range(2, 17), [2, 4, 8, 9], range(4, 257, 4)])
def test_camera_count_axes_are_labelled_with_plain_numbers(drawn, ns):
    """N is a count on a log axis: figure 6 and the excess panel labelled it '2x10^0', '3x10^0',
    '4x10^0', '6x10^0', '10^1' (the middle ones running into each other at the committed size)."""
    cameras.plot(cameras_result(ns=ns), "unused.png")
    fig, = drawn
    for ax in fig.axes[1:]:
        assert ax.get_xscale() == "log" and ax.get_xlabel() == "number of cameras N"
        labels = visible_tick_labels(ax.xaxis)
        assert len(labels) >= 2, labels
        assert all(re.fullmatch(r"\d+", text) for text in labels), labels


def integer_only(ax):
    ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
    return ticks and all(t == int(t) for t in ticks) and labels and all(s.isdigit() for s in labels)


def test_one_k_or_one_object_count_is_ticked_in_whole_numbers(drawn, monkeypatch):
    """`--k 4` (static, lab), `--k 3` (moving) or `--objects 5` (cameras, figure 5) put a single
    value on a count axis, ticked 3.80, 3.85, ... 4.20."""
    from testbed.studies import core, moving, static

    for module in (core, moving):
        monkeypatch.setattr(module, "save_figure", lambda fig, path: (fig.canvas.draw(), drawn.append(fig)))
    recs = [{"tasker": t, "k": 4, "residual": r, "residual_sem": 0.1, "trials": 3}
            for t, r in (("uniform", 2.9), ("greedy", 1.9))]
    static.plot({"records": recs}, "unused.png")
    moving.plot({"records": [{**r, "update_every": 1, "steps": 3} for r in recs]}, "unused.png")
    cameras.plot(cameras_result(objects=(5,)), "unused.png")
    panels = [*drawn[0].axes, *drawn[1].axes, drawn[2].axes[0]]
    assert [ax.get_xlabel() for ax in panels] == ["number of cameras tasked k"] * 3 + ["number of objects"]
    for ax in panels:
        assert integer_only(ax), (ax.get_title(), ax.get_xticks(), [t.get_text() for t in ax.get_xticklabels()])


def test_tracking_title_counts_its_objects(monkeypatch, tmp_path):
    """One walking object was titled "one of 1 objects"."""
    from testbed.cli import main
    from testbed.studies import tracking

    titles = []
    monkeypatch.setattr(tracking, "save_figure", lambda fig, path: titles.append(fig.get_suptitle()))
    for n in (1, 3):
        assert main(["study", "tracking", "--objects", str(n), "--trials", "1", "--steps", "6", "--workers", "0",
                     "--pairs", "uniform:4", "--plot", str(tmp_path / "t.png")]) == 0
    assert titles == ["Fig. 14: the object, true and estimated tracks",
                      "Fig. 14: one of 3 objects, true and estimated tracks"]
