"""Review 47h: the bug hunts 47a (plots and reports) and 47c (a newcomer's first hour)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import graybox as gb


def _front(jsf) -> gb.ParetoSet:
    s = gb.parse_structure(["y(k-1)", "u(k-1)", "1"])
    return gb.ParetoSet(s, np.array([[0.9, 0.01, 0.1]] * 3), np.array([0.01, 0.1, 1.0]), np.ones(3),
                        np.array([1.0, 2.0, 3.0]), np.asarray(jsf, float), method="PE")


@pytest.mark.parametrize("log", [True, False])
def test_plot_pareto_keeps_its_range_for_a_band_among_the_members(log):
    # a302fff brought a band below every member into the panel, but also zoomed out for a band already inside it:
    # J_SF 100.2 … 100.8 and B = 100.4 drew the members in a sliver of a panel from 0 (linear) or 33 (log)
    from graybox.plots import plot_pareto

    ps = _front([100.8, 100.5, 100.2])
    bare = plot_pareto(ps, log=log).axes[0].get_ylim()
    lo, hi = plot_pareto(ps, band=100.4, log=log).axes[0].get_ylim()
    assert lo == pytest.approx(bare[0]) and hi == pytest.approx(bare[1])
    lo, hi = plot_pareto(ps, band=10.0, log=log).axes[0].get_ylim()  # below every member: still brought in
    assert lo < 10.0 and hi >= 100.8


@pytest.fixture(scope="module")
def boot():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gb.bootstrap_decision(gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]),
                                     gb.load_pumping(), n_boot=4, lambdas=np.logspace(-3, 0, 4))


def test_plot_decision_bootstrap_keeps_its_range_for_a_band_among_the_replicates(boot):
    # 4f68da7 lowered the panel's bottom to B/3 for any band from 0, also one whose top lies among the replicates
    from graybox.plots import plot_decision_bootstrap

    jsf = boot.JSF[boot.ok]
    top = float(np.max(jsf)) * 10  # above every replicate: the range the replicates give
    bare = plot_decision_bootstrap(dataclasses.replace(boot, band=top)).axes[1].get_ylim()
    inside = float(np.median(jsf))
    lo, _ = plot_decision_bootstrap(dataclasses.replace(boot, band=inside)).axes[1].get_ylim()
    assert lo == pytest.approx(bare[0])
    low = float(np.min(jsf)) / 100  # below every replicate: still brought in
    assert plot_decision_bootstrap(dataclasses.replace(boot, band=low)).axes[1].get_ylim()[0] < low
