"""review44f: what the reviewed hunts (44b, 44c, 44e) left wrong."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

import graybox as gb


def test_a_checkpoint_write_of_another_host_is_not_swept_while_fresh(tmp_path):
    # a checkpoint in a folder two hosts share (NFS): a write's file named by its pid alone was swept as a killed
    # writer's whenever that pid is no process of *this* host, so the other host's os.replace found nothing
    from graybox.core._files import writer_tag
    from graybox.estimation._simulation_error import checkpoint_path, save_npz

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    path = tmp_path / "sel.npz"
    other = tmp_path / f"sel.npz.otherhost-{gone.pid}-0badc0de.tmp"  # a live write on another host
    mine = tmp_path / f"sel.npz.{writer_tag().rsplit('-', 1)[0]}-{gone.pid}-1badc0de.tmp"  # this host's, its writer gone
    untold = tmp_path / f"sel.npz.{gone.pid}-2badc0de.tmp"  # no host named: which host's process is not known
    for f in (other, mine, untold):
        f.write_bytes(b"half")
    checkpoint_path(path)
    assert other.exists() and untold.exists() and not mine.exists()
    save_npz(path, x=np.zeros(2))
    assert other.exists() and untold.exists()
    an_hour_ago = time.time() - 3600
    import os
    for f in (other, untold):
        os.utime(f, (an_hour_ago, an_hour_ago))
    checkpoint_path(path)  # once old, any host's is a killed writer's
    assert sorted(f.name for f in tmp_path.iterdir()) == ["sel.npz"]


def _rig(n, seed):
    rng = np.random.default_rng(seed)
    a = np.repeat(rng.uniform(-1, 1, n // 20 + 1), 20)[:n]
    b = np.repeat(rng.uniform(-1, 1, n // 30 + 1), 30)[:n]
    y = 0.5 * a + 0.2 * a * b + 0.1 * b
    return gb.Record(np.c_[1000 + 500 * a, 50 + 40 * b], y, Ts=0.1, input_names=("speed", "valve"))


def test_a_surface_fitted_in_the_records_order_keeps_the_fingerprint_stores_hold():
    # data_fingerprint (part of every cell's key and of the store's data set hashes) began hashing a surface's
    # monomials and inputs: a store run before on a data set with a StaticSurface (extra['static_curve'], the
    # surface a fit gives) then refused that same data set ('reads other data than the data set in the store')
    from types import SimpleNamespace

    from graybox.experiments._spec import data_fingerprint
    rec, box = _rig(100, 0), ((500.0, 1500.0), (10.0, 90.0))
    surf = gb.StaticSurface(((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)), [0.1, 1e-3, -5e-3, 1e-7, 2e-6, 3e-5], domain=box, input_names=("speed", "valve"))
    before = SimpleNamespace(coefficients=surf.coefficients, domain=surf.domain)  # what the hash read before
    prints = [data_fingerprint(gb.Dataset(rec, rec, extra={"static_curve": s})) for s in (surf, before)]
    assert prints[0] == prints[1]
    # and surfaces a hash of coefficients alone cannot tell apart are still told apart
    for other in (gb.StaticSurface(tuple(reversed(surf.exponents)), surf.coefficients, domain=box,
                                   input_names=("speed", "valve")),  # the coefficients on other monomials
                  gb.StaticSurface(surf.exponents, surf.coefficients, domain=box, input_names=("valve", "speed"))):
        assert data_fingerprint(gb.Dataset(rec, rec, extra={"static_curve": other})) != prints[0]


def _transient_model():
    """A one-input plant's model with a transient input u_tau3 (zero at every operating point)."""
    st = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "u_tau3(k-1)"])
    return gb.Model(st, np.array([0.1, 0.6, 0.002, 1e-6, -0.5]), input_names=("u", "u_tau3"), Ts=0.5)


def test_two_values_for_a_one_input_plants_model_with_a_transient_input_are_not_read_by_their_values():
    # steady_levels read a 1-D ū of length m as one point when its transient entries are 0 and as levels of u
    # otherwise: levels [1200, 0] gave one value (the point (1200, z̄ = 0)) where [1200, 100] gave two, and a
    # full point [1200, 5] (z̄ = 5), one point before, silently became two levels
    model = _transient_model()
    for ub in ([1200.0, 0.0], [1200.0, 5.0], np.array([0.0, 1200.0])):
        with pytest.raises(ValueError, match=r"ubar.*'u', 'u_tau3'.*shape \(M, 1\).*shape \(1, 2\)"):
            model.static_curve(ub)
        with pytest.raises(ValueError, match="ubar"):
            gb.operating_curve(model, ub)
    # said apart by their shape, each is read as meant
    levels = np.array([[1200.0], [0.0]])
    np.testing.assert_allclose(model.static_curve(levels), model.static_curve([[1200.0, 0.0], [0.0, 0.0]]))
    assert model.static_curve([[1200.0, 0.0]]).shape == (1,)
    assert len(gb.operating_curve(model, [800.0, 1000.0, 1200.0]).ubar) == 3  # levels of another count
    assert gb.local_model(model, [1200.0, 0.0]).ybar == gb.local_model(model, 1200.0).ybar  # one point taken


def test_a_column_named_as_the_input_is_its_levels_with_a_transient_input():
    # a named Series (df["u"]: its name the input's, its labels the samples') was read by its values, and two of
    # them refused as ambiguous (levels of u or one point (u, z̄)), where its name says they are levels of u
    import pandas as pd

    model = _transient_model()
    df = pd.DataFrame({"u": [1200.0, 0.0], "p": [1.0, 2.0]})
    levels = np.array([[1200.0], [0.0]])
    np.testing.assert_array_equal(model.static_curve(df["u"]), model.static_curve(levels))
    np.testing.assert_array_equal(model.static_gain(df["u"]), model.static_gain(levels))
    np.testing.assert_array_equal(gb.operating_curve(model, df["u"]).ybar, gb.operating_curve(model, levels).ybar)
    assert gb.local_model(model, df["u"].iloc[:1]).ybar == gb.local_model(model, 1200.0).ybar
    with pytest.raises(ValueError, match="only some of the inputs"):  # levels of the transient input alone: no
        model.static_curve(pd.Series([0.0, 1.0], name="u_tau3"))
    with pytest.raises(ValueError, match=r"shape \(M, 1\)"):  # bare values still say nothing of what they are
        model.static_curve(df["u"].to_numpy())
    # and two levels of one input of a two-input model were one point (u, v) = (1200, 0): refused, naming v
    two = gb.Model(["y(k-1)", "u(k-1)", "v(k-1)"], [0.5, 1.0, 1.0])
    with pytest.raises(ValueError, match=r"inputs without a column: \['v'\]"):
        two.static_curve(df["u"])


@pytest.mark.parametrize("fn", ["cls", "pe"])
@pytest.mark.parametrize("units", [dict(), dict(u_offset=1e4), dict(u_scale=1e3, y_offset=-1e4)])
def test_an_equality_the_model_breaks_is_refused_in_any_units(fn, units):
    # hunt44e judged an inequality's activity in the solvers' metric (not against 1e-6 ‖θ ⊙ s‖, which grows with
    # the offsets) but left the equalities' check on the old rule: at u = 1e4 ± 1 a model missing the point it is
    # said to pass through by 0.3 (of outputs of order 1) was accepted, its covariance that of another problem
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from test_hunt44e import S, _plant

    d = _plant(**units)
    ys, yo = units.get("y_scale", 1.0), units.get("y_offset", 0.0)
    pts = gb.StaticPoints(d.static.ubar, d.static.ybar + ys * 0.05 * np.array([1, -1, 1, -1, 1, -1]))
    one = gb.PassesThrough(gb.StaticPoints(d.static.ubar[2:3], d.static.ybar[2:3] + 0.3 * ys))
    with pytest.raises(ValueError, match="does not satisfy static function passes through 1 static points"):
        if fn == "cls":
            gb.cls_uncertainty(gb.cls(S, d.ident, pts, how="context"), d.ident, pts, constraints=one, how="context")
        else:
            member = gb.pe_pareto(S, d.ident, pts, lambdas=[0.5]).member_model(0)
            gb.pe_uncertainty(member, d.ident, pts, lambda1=0.5, constraints=one)
    # the model estimated with it is taken, in these units too
    if fn == "cls":
        fit = gb.cls(S, d.ident, pts, constraints=one, how="context")
        unc = gb.cls_uncertainty(fit, d.ident, pts, constraints=one, how="context")
    else:
        member = gb.pe_pareto(S, d.ident, pts, constraints=one, lambdas=[0.5]).member_model(0)
        unc = gb.pe_uncertainty(member, d.ident, pts, lambda1=0.5, constraints=one)
    assert np.all(np.isfinite(unc.cov))


def test_a_checkpoint_behind_a_link_is_checked_where_its_file_is_written(tmp_path):
    # save_npz writes through a symbolic link (its file beside the file the link names), but checkpoint_path checked
    # the link's folder: a link in a writable folder to a file in a read-only one passed, and the first write failed
    # after the first fit (what checkpoint_path refuses before any fit for a plain path)
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from test_hunt44b import read_only

    from graybox.estimation._simulation_error import checkpoint_path

    (tmp_path / "runs").mkdir()
    (tmp_path / "runs" / "a.npz").write_bytes(b"")
    link = tmp_path / "latest.npz"
    link.symlink_to(tmp_path / "runs" / "a.npz")
    with read_only(tmp_path / "runs"):
        with pytest.raises(ValueError, match=r"checkpoint: the folder .*runs cannot be written in"):
            checkpoint_path(link)
    assert checkpoint_path(link) == link


@pytest.mark.skipif(not __import__("os").path.exists("/proc/self/stat"), reason="zombies are told by /proc")
def test_a_killed_checkpoint_writer_not_yet_reaped_is_gone(tmp_path):
    # the checkpoint's sweep asked os.kill(pid, 0) alone, which a killed process its parent has not reaped (a
    # zombie) still answers: its write's file stayed for LEFTOVER_SECONDS; the store's run check, a copy of the same
    # question, already told a zombie from a live process
    from graybox.core._files import writer_tag
    from graybox.estimation._simulation_error import checkpoint_path

    zombie = subprocess.Popen([sys.executable, "-c", "pass"])
    try:
        for _ in range(200):  # until it has exited (not reaped: no wait)
            with open(f"/proc/{zombie.pid}/stat", "rb") as f:
                if f.read().rsplit(b")", 1)[1].split()[0] == b"Z":
                    break
            time.sleep(0.05)
        left = tmp_path / f"sel.npz.{writer_tag().rsplit('-', 1)[0]}-{zombie.pid}-0badc0de.tmp"
        left.write_bytes(b"half")
        checkpoint_path(tmp_path / "sel.npz")
        assert not left.exists()
    finally:
        zombie.wait()


def test_selection_uncertainty_builds_an_equality_table_with_a_static_curve_as_the_selection_did():
    # .uncertainty built tables into constraints with the static points given or the data set's, but a StaticCurve
    # given as static= (which select_graybox samples into points) left none: TypeError "object of type 'NoneType'
    # has no len()" naming nothing, for the table select_graybox had taken with that very curve
    import warnings

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from test_hunt44e import _plant

    d, other = _plant(n=300), _plant(n=300, seed=7)
    curve = gb.StaticCurve.fit(d.static, degree=2)
    table = {"type": "equality", "curve": "fit"}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the selection's notes on these small data are not what is tested
        sel = gb.select_graybox(gb.Candidates(ny=2, nu=1, degree=2, max_y_power=1), d.ident, static=curve,
                                validation=other.ident, band=0.1, estimator="pe", constraints=[table], lambdas=[0.3, 0.9],
                                sizes=[4, 5], sources=("frols",), progress=False)
        # the table is built on the curve's points as the selection built it: the member then meets them exactly,
        # which pe_uncertainty says by name (a static_sigma is needed), no longer a TypeError naming nothing
        with pytest.raises(ValueError, match="meets its 10 static points exactly.*static_sigma"):
            sel.uncertainty(d.ident, static=curve, constraints=[table])
        # which it now takes, as pe_uncertainty does (it had no way to pass one)
        unc = sel.uncertainty(d.ident, static=curve, constraints=[table], static_sigma=0.05)
        direct = gb.pe_uncertainty(sel.decision, d.ident, curve, static_sigma=0.05,
                                   constraints=sel._constraint_objects((table,), d.ident, curve))
        np.testing.assert_allclose(unc.cov, direct.cov, rtol=1e-12, atol=0)
        assert unc.static_sigma2 == pytest.approx(0.05**2)
    with pytest.raises(ValueError, match="static_sigma applies to a gray box"):
        gb.select_graybox(gb.Candidates(ny=1, nu=1, degree=1), d.ident, validation=other.ident, estimator="ls",
                          sizes=[2], sources=("frols",), progress=False).uncertainty(d.ident, static_sigma=0.05)


def test_a_labelled_point_of_every_input_is_one_point_with_transient_inputs():
    # a pandas Series labelled by the inputs (a DataFrame's row) is one point ū wherever inputs are read, yet for a
    # one-input plant's model with a transient input steady_levels read its values: (u = 1200, z̄ = 5) became the
    # two levels 1200 and 5 (review44f now refuses bare values there: a labelled point says what it is)
    import pandas as pd

    model = _transient_model()
    for z in (0.0, 5.0):
        row = pd.DataFrame([[z, 1200.0]], columns=["u_tau3", "u"]).iloc[0]  # labels in another order
        np.testing.assert_allclose(model.static_curve(row), model.static_curve([[1200.0, z]]))
        if z == 0.0:
            np.testing.assert_array_equal(gb.operating_curve(model, row).ubar, [[1200.0, z]])
        else:  # one point (1200, z̄ = 5), refused as such: a transient input is 0 at every operating point (mend60g)
            with pytest.raises(ValueError, match="transient input.*u_tau3 a level other than 0"):
                gb.operating_curve(model, row)


def test_solver_options_are_checked_where_cvxpy_lists_no_solve_keywords(monkeypatch):
    # the option names are read from the solver's settings and cvxpy's private Problem._solve: only the solver's
    # were read under a guard, so a cvxpy whose _solve is gone or another kind broke every call with options
    # (AttributeError) instead of leaving the check to the solver, as the docstring says
    import cvxpy as cp

    from graybox.estimation._prediction_error import _solver_settings

    assert "max_iter" in _solver_settings("clarabel")
    monkeypatch.delattr(cp.Problem, "_solve")
    assert _solver_settings("clarabel") is None and _solver_settings("osqp") is None
