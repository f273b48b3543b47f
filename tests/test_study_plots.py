"""The --plot figures of `camtask study`: what is drawn and how it is labelled, read from the
figure's artists (not its pixels)."""

import re

import numpy as np
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


def legend_labels(ax):
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend else []


def test_moving_figures_9_and_10_hold_their_series(drawn, monkeypatch):
    """Fig. 9: uniform, greedy and incremental at its smallest period; fig. 10: incremental at
    every period, with uniform for reference. Greedy alone leaves fig. 10 empty, and it says why."""
    from testbed.studies import moving

    monkeypatch.setattr(moving, "save_figure", lambda fig, path: (fig.canvas.draw(), drawn.append(fig)))
    recs = [{"tasker": t, "k": k, "update_every": u, "residual": 1.0 + k + u, "residual_sem": 0.1, "trials": 2,
             "steps": 3} for t, u in (("uniform", 1), ("greedy", 1), ("incremental", 5), ("incremental", 2))
            for k in (2, 3)]
    moving.plot({"records": recs}, "unused.png")
    moving.plot({"records": [r for r in recs if r["tasker"] == "greedy"]}, "unused.png")
    (fig9, fig10), (greedy9, greedy10) = drawn[0].axes, drawn[1].axes
    assert legend_labels(fig9) == ["uniform", "greedy", "incremental/2"]
    assert legend_labels(fig10) == ["uniform", "incremental/5", "incremental/2"]
    assert legend_labels(greedy9) == ["greedy"] and greedy10.get_legend() is None
    assert [t.get_text() for t in greedy10.texts] == ["no incremental or uniform\nin --taskers"]
    assert list(fig9.texts) == [] and list(fig10.texts) == []
    # each series keeps its colour in both panels
    colours9, colours10 = ({c.get_label(): c.lines[0].get_color() for c in ax.containers} for ax in (fig9, fig10))
    assert colours9["uniform"] == colours10["uniform"] and colours9["incremental/2"] == colours10["incremental/2"]


def test_one_object_leaves_figure_6_empty_and_says_why(drawn):
    """One object's exact limit is 0: nothing to scale by, so figure 6 has no curve."""
    cameras.plot(cameras_result(objects=(1,)), "unused.png")
    fig, = drawn
    assert not fig.axes[1].has_data()
    assert [t.get_text() for t in fig.axes[1].texts] == ["no object count\nwith a nonzero limit"]
    cameras.plot(cameras_result(objects=(1, 2)), "unused.png")
    assert drawn[1].axes[1].has_data() and list(drawn[1].axes[1].texts) == []
    assert legend_labels(drawn[1].axes[1]) == ["2"]


def test_static_and_lab_figures_draw_each_tasker_and_the_all_camera_reference(drawn, monkeypatch):
    """static (figure 8): residual vs k per tasker on a log scale; lab (figure 13): linear, with
    the all-camera residual as a dashed reference line."""
    from testbed.studies import core, lab, static

    monkeypatch.setattr(core, "save_figure", lambda fig, path: (fig.canvas.draw(), drawn.append(fig)))
    recs = [{"tasker": t, "k": k, "residual": r / k, "residual_sem": 0.1, "trials": 3}
            for t, r in (("uniform", 6.0), ("greedy", 3.0)) for k in (2, 4)]
    static.plot({"records": recs}, "unused.png")
    lab.plot({"records": recs, "cameras": 16, "scene": "lab", "all_cameras_residual": 1.25}, "unused.png")
    (fig8,), (fig13,) = drawn[0].axes, drawn[1].axes
    assert fig8.get_yscale() == "log" and fig13.get_yscale() == "linear"
    assert legend_labels(fig8) == ["uniform", "greedy"]
    assert sorted(legend_labels(fig13)) == ["all 16 cameras", "greedy", "uniform"]
    greedy = next(c for c in fig8.containers if c.get_label() == "greedy")
    assert greedy.lines[0].get_xdata().tolist() == [2, 4] and greedy.lines[0].get_ydata().tolist() == [1.5, 0.75]
    # each point's bar spans one standard error either side
    (bars,) = greedy.lines[2]
    np.testing.assert_allclose([seg[:, 1] for seg in bars.get_segments()], [[1.4, 1.6], [0.65, 0.85]])
    assert (fig8.get_title(), fig8.get_ylabel()) == ("Fig. 8: taskers with static objects", "residual / object area")
    (reference,) = [line for line in fig13.get_lines() if line.get_label() == "all 16 cameras"]
    assert reference.get_linestyle() == "--" and set(reference.get_ydata()) == {1.25}


def test_the_excess_panel_leaves_off_what_has_no_excess_and_guides_with_n_to_the_minus_2(drawn):
    """A residual at the limit (excess 0) has no place on the log axis: its N is left off. The
    guide falls as N^-2 from the first object count's largest excess at the smallest N."""
    result = cameras_result(objects=(2, 3), ns=(2, 4, 8))
    for r in result["records"]:
        if r["objects"] == 3 and r["cameras"] == 8:
            r["excess"] = 0.0
    cameras.plot(result, "unused.png")
    fig, = drawn
    lines = {line.get_label(): line for line in fig.axes[2].get_lines()}
    assert lines["2"].get_xdata().tolist() == [2, 4, 8] and lines["3"].get_xdata().tolist() == [2, 4]
    guide = lines["N^-2"]
    assert guide.get_xdata().tolist() == [2, 8]
    np.testing.assert_allclose(guide.get_ydata(), [2 * 2 / 2**2, 2 * 2 / 2**2 / 16])
