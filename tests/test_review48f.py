"""review48f: the diagnostics' validation (e2e8206, e444035), residuals of one magnitude (2dc0b09) and the grid
commits of hunt48c, held to what graybox itself makes and saved."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import graybox as gb
from conftest import first_order_signals


def test_a_residual_tests_file_with_a_0_over_0_test_from_the_previous_graybox_still_loads(tmp_path):
    # graybox before 2dc0b09 kept φ_(u²)'ξ² of residuals ±c as NaN at every lag (0/0), 'FAIL (max |φ| = nan)'; the
    # new CorrelationTest check 'phi must hold correlations, finite' refused every such file graybox had written
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 300)
    y = np.r_[0.0, u[:-1]] + rng.choice([-0.5, 0.5], 300)
    with pytest.warns(UserWarning, match="u2_xi2"):
        r = gb.residual_tests(gb.Model(gb.Structure(["u(k-1)"]), [1.0]), gb.Record(u, y))
    path = tmp_path / "r.json"
    gb.save(r, path)
    doc = json.loads(path.read_text(encoding="utf-8"))
    # as the previous graybox wrote it: the test made, NaN ('nan') at each lag, failed, nothing undefined
    t = dict(doc["object"]["tests"]["xi_xi"])
    lags = list(range(-20, 21))
    # (its limit that of 41 lags, as φ_uξ's: φ_ξξ's is of 20)
    t.update(name="u2_xi2", label="φ_(u²)'ξ²(τ)", kind="nonlinear", lags=lags, phi=["nan"] * len(lags),
             outside=[], passed=False, **{k: doc["object"]["tests"]["u_xi"][k] for k in ("limit", "excess_kurtosis",
                                                                                          "skewness")})
    doc["object"]["tests"]["u2_xi2"] = t
    doc["object"]["undefined"] = {}
    path.write_text(json.dumps(doc), encoding="utf-8")
    old = gb.load(path)
    assert not old.passed and old.failed == ["u2_xi2"]
    assert np.all(np.isnan(old["u2_xi2"].phi))
    # a φ partly NaN, or NaN yet passed, is no file graybox wrote
    with pytest.raises(ValueError, match="phi"):
        gb.CorrelationTest("u_xi", "φ_uξ(τ)", "linear", np.arange(-1, 2), np.array([np.nan, 0.1, 0.0]), 0.2, 0.3,
                           np.array([], int), False)


def test_residuals_proportional_to_a_balanced_two_level_input_leave_phi_xi_xiu_out_not_crash():
    # ξ = c·u' with u' = ±1 (a balanced two-level input the model misses at lag 0): ξ·u' is constant and
    # φ_ξ(ξu) 0/0; residual_tests itself raised 'phi must hold correlations, finite and in [-1, 1]'
    rng = np.random.default_rng(1)
    u = np.r_[1.0, rng.permutation(np.repeat([1.0, -1.0], 100))]
    y = np.r_[0.0, u[:-1]] + 0.5 * u
    with pytest.warns(UserWarning, match="xi_xiu"):
        r = gb.residual_tests(gb.Model(gb.Structure(["u(k-1)"]), [1.0]), gb.Record(u, y))
    assert "xi_xiu" in r.undefined and "xi_xiu" not in r.tests
    assert all(np.all(np.isfinite(t.phi)) for t in r.tests.values())
    assert not r.passed and "u_xi" in r.failed  # ξ is the input: φ_uξ(0) = 1


@pytest.mark.parametrize("A, c", [(1.0, 1e-7), (1e-3, 1e-10), (1e3, 1e-4)])
def test_residuals_of_one_magnitude_are_judged_against_the_round_off_of_the_output(A, c):
    # ξ = ±c with y spanning A ≫ c: ξ carries round-off of y's size, so ξ² varies by ~eps·A/c of itself, which the
    # check 'ptp(ξ²) <= 1e-9 max ξ²' missed at A/c = 1e7: φ_(u²)'ξ² was made of round-off and failed the model
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 400)
    y = A * np.r_[0.0, u[:-1]] + c * rng.choice([-1.0, 1.0], 400)
    with pytest.warns(UserWarning, match="u2_xi2"):
        r = gb.residual_tests(gb.Model(gb.Structure(["u(k-1)"]), [A]), gb.Record(u, y))
    assert list(r.undefined) == ["u2_xi2"]
    assert r.passed


@pytest.mark.parametrize("scale", [1e-100, 1e-160, 1e154])
def test_the_correlations_do_not_depend_on_the_output_units(scale):
    # φ's denominator was sqrt(Σa² · Σb²): with y in units 1e-100 of the usual ones Σξ² · Σξ² underflowed to 0
    # (φ_ξξ NaN, a failed test), at 1e154 it overflowed; the same data in other units must give the same φ
    u, y = first_order_signals()
    ref = gb.residual_tests(gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [0.5, 1.0]), gb.Record(u, y))
    r = gb.residual_tests(gb.Model(gb.Structure(["y(k-1)", "u(k-1)"]), [0.5, scale]), gb.Record(u, y * scale))
    assert list(r.tests) == list(ref.tests) and not r.undefined
    for k, t in ref.tests.items():
        np.testing.assert_allclose(r[k].phi, t.phi, rtol=1e-6, atol=1e-9, err_msg=k)
        assert r[k].passed == t.passed


def test_cells_taken_by_another_run_count_every_grid_cell_of_their_row(tmp_path, monkeypatch):
    # 9700d10 counts a row two data set names share for both in ran, skipped and the progress bar, but the note on
    # rows another run wrote meanwhile still counted rows: '2 cells … 2 run now' beside '1 cell(s) run now were
    # written meanwhile by another run'
    from graybox import experiments as gx
    from graybox.experiments._store import ResultStore

    write = ResultStore.write

    def written_by_another(self, row, replace=False):  # the row lands, as if another run had written it first
        write(self, row, replace)
        return False

    monkeypatch.setattr(ResultStore, "write", written_by_another)
    g = gx.Grid([gx.DataSpec("a", bundled="pumping"), gx.DataSpec("b", bundled="pumping", band=0.05)],
                [gx.StructureSpec("first-order", terms=["y(k-1)", "u(k-1)", "1"])], [gx.Variant("LS", "ls")],
                name="twins")
    run = gx.run_grid(g, tmp_path / "s.sqlite")
    assert (run.cells, run.ran) == (2, 2)
    assert any(n.startswith("2 cell(s) run now were written meanwhile") for n in run.notes), run.notes
