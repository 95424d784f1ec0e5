"""plot_selection: the picture of a select_graybox choice (the rule's panel, the static error, the test record)."""

import warnings

import numpy as np
import pytest
from matplotlib.figure import Figure

import graybox as gb
from graybox.experiments import plot_selection

pytestmark = pytest.mark.filterwarnings("ignore::graybox.StaticRangeWarning")

TRUE = gb.Structure(["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"])
THETA = np.array([0.6, 0.2, 0.3, 0.05, 0.4])


def _record(seed, n=800):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
    return gb.Record(u, gb.Model(TRUE, THETA).simulate(u, np.zeros(2)) + 0.02 * rng.standard_normal(n))


@pytest.fixture(scope="module")
def selections():
    ub = np.linspace(0.0, 3.0, 7)
    data = gb.Dataset(_record(1), _record(2), gb.StaticPoints(ub, gb.Model(TRUE, THETA).static_curve(ub)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cand = gb.Candidates(3, 3, ne=0, degree=2)
        gray = gb.select_graybox(cand, data, band=1e-3, sizes=[3, 5], test=_record(3))
        black = gb.select_graybox(cand, gb.Dataset(data.ident, data.valid), band=np.inf, sizes=[3, 5],
                                  estimator=("ls",))
    return gray, black


def _points(ax):
    """(x, y) of every marker line drawn on ``ax`` (error bars' markers included), the chosen ring apart."""
    pts, ring = [], []
    for line in ax.lines:
        x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)
        # markers only: not the error bars' caps ("_")
        if line.get_linestyle() in ("None", "none", "") and line.get_marker() not in ("_", "|", "None") and x.size:
            (ring if line.get_label() == "chosen" else pts).append(np.column_stack([x, y]))
    return (np.vstack(pts) if pts else np.zeros((0, 2))), (np.vstack(ring) if ring else np.zeros((0, 2)))


def test_the_rule_panel_draws_each_row_at_its_ratio_to_the_best_and_rings_the_choice(selections):
    gray, _ = selections
    fig = plot_selection(gray)
    assert isinstance(fig, Figure) and len(fig.axes) == 3  # rule, static error, test record
    t = gray.table
    ok = np.isfinite(t["vs_best"].to_numpy(float))
    pts, ring = _points(fig.axes[0])
    want = np.column_stack([t["n_terms"][ok], np.exp(t["vs_best"][ok])])
    # every drawn row is a row of the table at (terms, its J_S over the best row's), and every row is drawn
    assert len(pts) == ok.sum()
    for p in want:
        assert np.any(np.all(np.isclose(pts, p, rtol=1e-12), axis=1))
    c = gray.chosen
    np.testing.assert_allclose(ring, [[c["n_terms"], np.exp(c["vs_best"])]])
    # the test panel's ring sits at the chosen row's test J_S, and its title gives the regret
    _, ring = _points(fig.axes[2])
    np.testing.assert_allclose(ring, [[c["n_terms"], c["JS_test"]]])
    assert f"{c['JS_test'] / t['JS_test'].min():.3g}×" in fig.axes[2].get_title()


def test_eligible_rows_are_filled_and_the_others_hollow(selections):
    gray, _ = selections
    fig = plot_selection(gray)
    drawn = {True: 0, False: 0}
    for c in fig.axes[0].containers:  # one error-bar group per estimator and eligibility
        label, line = c.get_label(), c.lines[0]
        yes = "(eligible)" in label
        assert yes or "(not eligible)" in label
        assert (line.get_markerfacecolor() != "none") == yes
        drawn[yes] += len(line.get_xdata())
    t = gray.table
    ok = np.isfinite(t["vs_best"].to_numpy(float))
    assert drawn[True] == int((t["eligible"] & ok).sum()) >= 1
    assert drawn[False] == int((~t["eligible"] & ok).sum())


def test_a_black_box_without_static_points_or_test_record_has_one_panel(selections):
    _, black = selections
    fig = plot_selection(black)
    assert len(fig.axes) == 1


def test_bad_arguments_are_named(selections):
    gray, _ = selections
    with pytest.raises(TypeError, match="selection must be a GrayboxSelection"):
        plot_selection(gray.table)
    fig = Figure()
    with pytest.raises(ValueError, match="axes must hold 3"):
        plot_selection(gray, axes=fig.subplots(1, 2))
    axs = Figure().subplots(1, 3)
    assert plot_selection(gray, axes=list(axs)) is axs[0].figure


def test_drawn_into_the_caller_s_axes_the_figure_keeps_its_own_title_unless_one_is_given(selections):
    gray, _ = selections
    fig = Figure()
    fig.suptitle("my dashboard")
    plot_selection(gray, axes=list(fig.subplots(1, 3)))
    assert fig.get_suptitle() == "my dashboard"  # was replaced by "chosen: …"
    plot_selection(gray, axes=list(Figure().subplots(1, 3)), title="mine")
    own = plot_selection(gray)
    assert own.get_suptitle().startswith("chosen: ")
