"""The --plot of `camtask tune`: every trial visible, gains near F1 1 visible, read as a researcher would."""

import numpy as np
import pytest

from testbed.commands.tune import history_figure


@pytest.fixture
def figure():
    """Draw the figure that tune --plot writes (history_png) and return it."""
    def draw(f1):
        fig = history_figure(f1)
        fig.canvas.draw()
        return fig
    yield draw
    import matplotlib.pyplot as plt
    plt.close("all")


def points(ax, f1):
    """Display coordinates of the trials."""
    return ax.transData.transform(np.column_stack([np.arange(1, len(f1) + 1), f1]))


def test_a_gain_near_f1_one_is_visible(figure):
    """0.9973 to 0.9986 halves the errors; on a linear axis down to the worst trial it was 2 pixels."""
    f1 = [0.9973, 0.89, 0.9986, 0.93]
    ax = figure(f1).axes[0]
    start, best = points(ax, f1)[[0, 2], 1]
    assert best - start > 30


@pytest.mark.parametrize("f1", [[0.9973, 0.89], [0.9973, 0.4, 0.95, 0.2, 0.999], [1.0, 0.0, 0.5]])
def test_every_trial_is_drawn_inside_the_axes_and_clear_of_the_legend(figure, f1):
    fig = figure(f1)
    ax = fig.axes[0]
    box = ax.get_window_extent()
    legend = ax.get_legend().get_window_extent()
    marks = np.concatenate([line.get_xydata() for line in ax.lines if line.get_label().startswith("trial")])
    assert sorted(marks[:, 0]) == list(range(1, len(f1) + 1))         # each trial once, 0 and 1 too
    for x, y in ax.transData.transform(marks):
        assert box.x0 <= x <= box.x1 and box.y0 <= y <= box.y1, (x, y)
        assert not (legend.x0 <= x <= legend.x1 and legend.y0 <= y <= legend.y1), (x, y)


@pytest.mark.parametrize("f1", [[0.9973, 0.89, 0.9986], [0.9973]])
def test_trials_are_counted_in_whole_numbers(figure, f1):
    """One trial (`--trials 1`) was drawn on an axis ticked 0.945, 0.960, ... 1.050."""
    ax = figure(f1).axes[0]
    ticks = [t for t in ax.get_xticks() if ax.get_xlim()[0] <= t <= ax.get_xlim()[1]]
    assert ticks and all(t == int(t) for t in ticks), ticks
    labels = [t.get_text() for t in ax.get_xticklabels() if t.get_text()]
    assert labels and all(text.isdigit() for text in labels), labels


def test_the_title_gives_the_result(figure):
    ax = figure([0.9973, 0.89, 0.9986]).axes[0]
    assert ax.get_title() == "best scanline F1 0.9986 (trial 3 of 3); start 0.9973"


def test_ticks_at_or_beyond_zero_and_one_have_no_label():
    """A logit axis has no point at F1 0 or 1: a tick there is left blank, not labelled."""
    from testbed.commands.tune import _decimal

    assert [_decimal(y) for y in (0.0, 1.0, -0.5, 1.5)] == ["", "", "", ""]
    assert [_decimal(y) for y in (1e-9, 1 - 1e-9)] == ["0.000000001", "0.999999999"]
