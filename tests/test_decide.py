"""D_SF (eq. (14)): min J_S subject to J_SF in B = [0, band]."""

import numpy as np
import pytest

from graybox import Model, reference
from graybox.estimation._decisions import decide_dsf
from graybox.estimation._pareto import ParetoSet
from conftest import first_order_signals

S15 = reference.STRUCTURE_15
B = 0.031  # a band for these tests (output units²); decide_dsf has no default


def front(js, jsf, lambdas=None):
    k = len(js)
    th = np.tile(reference.TABLE_II["ELS"], (k, 1)) * (1 + 0.01 * np.arange(k))[:, None]
    lam = np.linspace(1.0, 0.1, k) if lambdas is None else lambdas
    return ParetoSet(S15, th, lam, np.zeros(k), np.asarray(js, float), np.asarray(jsf, float), "PE")


def test_picks_min_js_inside_the_band():
    ps = front([1.0, 2.0, 3.0, 4.0], [0.5, 0.03, 0.01, 0.0])
    _d = decide_dsf(ps, band=B)
    m, i = _d.model, _d.index
    assert i == 1 and isinstance(m, Model)
    np.testing.assert_array_equal(m.theta, ps.thetas[1])
    assert "D_SF" in m.name
    assert isinstance(decide_dsf(ps, band=B).model, Model)
    # the band's edge is inside: B is closed
    assert decide_dsf(front([1.0, 2.0], [0.031, 0.0]), band=B).index == 0


def test_ties_and_divergent_members():
    ps = front([2.0, 2.0, np.inf], [0.02, 0.01, 0.001])
    # the diverging member (J_S = inf) is never chosen; among equal J_S the smaller J_SF wins
    assert decide_dsf(ps, band=B).index == 1


def test_band_as_interval():
    ps = front([1.0, 2.0, 3.0], [0.02, 0.01, 0.001])
    assert decide_dsf(ps, band=(0.005, 0.015)).index == 1


def test_no_member_in_the_band_is_an_error_unless_a_fallback_is_named():
    ps = front([1.0, 2.0, 3.0], [0.5, 0.2, 0.1])
    with pytest.raises(ValueError, match=r"no member .* J_SF in B = \[0, 0.031\].*smallest J_SF is 0.1.*fallback"):
        decide_dsf(ps, band=B)
    _d = decide_dsf(ps, band=B, fallback="min_jsf")
    m, i = _d.model, _d.index
    assert i == 2 and "no member in B" in m.name
    with pytest.raises(ValueError, match="fallback must be"):
        decide_dsf(ps, band=B, fallback="nearest")


@pytest.mark.parametrize("band", [-0.1, 0.0, np.nan, np.inf, (0.02, 0.01), (-1.0, 0.1), (0.1, 0.1), (0.0, 0.1, 0.2)])
def test_bad_band(band):
    with pytest.raises(ValueError, match="band"):
        decide_dsf(front([1.0], [0.0]), band=band)


@pytest.mark.parametrize("band", ["0.031", True, None])
def test_band_of_the_wrong_type_or_missing(band):
    # a band has no unit-free default: leaving it out says what to pass
    err = ValueError if band is None else TypeError
    with pytest.raises(err, match="band"):
        decide_dsf(front([1.0], [0.0]), band=band)


def test_bad_input():
    with pytest.raises(TypeError, match="ParetoSet"):
        decide_dsf([1, 2, 3], band=B)
    empty = ParetoSet(S15, np.zeros((0, 17)), [], [], [], [], "x")
    with pytest.raises(ValueError, match="empty"):
        decide_dsf(empty, band=B)
    with pytest.raises(ValueError, match="every member"):
        decide_dsf(front([1.0, 2.0], [np.inf, np.inf]), band=B, fallback="min_jsf")


def test_on_a_pe_front():
    """On a real PE sweep: the choice is in the band and no in-band member simulates better."""
    from graybox import Record
    from graybox.estimation._prediction_error import pe_pareto

    rng = np.random.default_rng(2)
    m = reference.paper_model(15)
    u = np.repeat(rng.uniform(750, 1650, 40), 40)[:1600]
    u[:40], u[40:80] = 750.0, 1650.0
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    rec = Record(u, m.simulate(u, y0) + 0.05 * rng.standard_normal(1600), Ts=0.05)
    ps = pe_pareto(S15, rec, reference.eq1_points(), lambdas=np.logspace(-6, 0, 30), solver="closed")
    i = decide_dsf(ps, band=B).index
    inside = ps.JSF <= B
    assert inside[i] and ps.JS[i] == ps.JS[inside].min()
    assert not inside.all()  # the band did select: λ1 near 1 keeps the data's static error


def test_min_correlation_picks_least_correlated_member():
    from graybox import Record, reference
    from graybox.estimation._decisions import decide_min_correlation
    from graybox.estimation._pareto import ParetoSet

    rng = np.random.default_rng(4)
    m = reference.paper_model(15, "PE")
    u = np.repeat(rng.uniform(750, 1650, 12), 60)
    y0 = np.full(6, float(m.static_curve([u[0]])[0]))
    rec = Record(u, m.simulate(u, y0) + 0.05 * rng.standard_normal(u.size), Ts=reference.TS)
    thetas = np.vstack([m.theta, m.theta * (1 + 0.02 * rng.standard_normal(17)), m.theta * 1.001])
    ps = ParetoSet.from_thetas(m.structure, thetas, [1.0, 0.5, 0.1], rec, reference.eq1_points())
    _d = decide_min_correlation(ps, rec)
    best, i = _d.model, _d.index
    # recompute ρ by hand for every member
    L = 6
    rhos = []
    for th in thetas:
        mm = m.with_theta(th)
        xi = rec.y[L:] - mm.predict(rec)[L:]
        ys = mm.simulate(rec)[L:]
        rhos.append(abs(np.corrcoef(xi, ys)[0, 1]))
    assert i == int(np.argmin(rhos))
    assert "min-corr" in best.name
    with pytest.raises(ValueError, match="output must be"):
        decide_min_correlation(ps, rec, output="sideways")


def test_min_correlation_on_a_long_record_works_in_member_blocks():
    """1.5e6 samples: the members are scored in blocks (bounded memory); ρ as computed by hand."""
    from graybox import Model, Record, Structure
    from graybox.estimation._decisions import decide_min_correlation
    from graybox.estimation._pareto import ParetoSet

    rng = np.random.default_rng(7)
    n = 1_500_000
    st = Structure(["y(k-1)", "u(k-1)", "1"])
    u = np.repeat(rng.uniform(0.0, 1.0, n // 500), 500)
    truth = Model(st, np.array([0.8, 0.5, 0.1]))
    rec = Record(u, truth.simulate(u, np.zeros(1)) + 0.05 * rng.standard_normal(n))
    thetas = truth.theta * (1 + 0.05 * rng.standard_normal((5, 3)))
    thetas[2] = truth.theta
    ps = ParetoSet(st, thetas, np.linspace(1, 0.2, 5), np.zeros(5), np.zeros(5), np.zeros(5), "test")
    d = decide_min_correlation(ps, rec)
    rhos = []
    for th in thetas:
        m = truth.with_theta(th)
        xi = rec.y[1:] - m.predict(rec)[1:]
        rhos.append(abs(np.corrcoef(xi, m.simulate(rec)[1:])[0, 1]))
    assert d.index == int(np.argmin(rhos))
    assert d.score == pytest.approx(min(rhos), rel=1e-9)


@pytest.mark.parametrize("js, jsf, said", [([0.5, np.nan, 2.0], [0.01, 0.01, 0.01], "member 1 .*J_S NaN"),
                                           ([0.5, 1.0, 2.0], [0.01, np.nan, 0.01], "member 1 .*J_SF NaN")])
def test_a_member_of_nan_objective_is_refused_by_index_not_skipped(js, jsf, said):
    """A hand-built set whose member 1 has J_S (or J_SF) NaN: D_SF chose member 0 without a word."""
    ps = front(js, jsf)
    with pytest.raises(ValueError, match=said):
        decide_dsf(ps, band=B)
    with pytest.raises(ValueError, match=said):
        decide_dsf(front([5.0, *js[1:]], jsf), band=1e-9, fallback="min_jsf")


@pytest.mark.parametrize("e", [300, 600, -300, -600])
def test_min_correlation_has_no_units(e):
    """ρ is units-free: at y × 2^300 every member's ρ read 0 (the product of the sums of squares, about 2^1200,
    overflowed), at 2^±600 and 2^-300 every member was refused as on 'a record that does not move'."""
    import graybox as gb

    u, y = first_order_signals(400, 0, noise=0.1)
    st = gb.parse_structure(["y(k-1)", "u(k-1)"])
    th = np.array([[0.5, 1.0], [0.45, 1.1], [0.3, 0.9]])
    out = []
    for k in (0, e):
        s = 2.0**k
        ps = ParetoSet.from_thetas(st, th * [1, s], [0.5, 0.7, 0.9], gb.Record(u[:200], y[:200] * s, Ts=1.0), None)
        valid = gb.Record(u[200:], y[200:] * s, Ts=1.0)
        out.append([gb.decide_min_correlation(ps, valid, output=o) for o in ("one-step", "free-run")])
    for base, far in zip(*out):
        assert far.index == base.index and far.score == pytest.approx(base.score, rel=1e-12) and base.score > 0.01


def test_min_correlation_with_a_square_of_the_output_at_y_times_2_to_the_512():
    """At y × 2^512 a set of y(k-1), u(k-1), y(k-1)² held J's that are floats (about 2^1018), but
    decide_min_correlation refused it: the regressor y(k-1)² (about 2^1026) overflowed in the data's own units.
    ρ has no units: the member and its ρ are those of ordinary units."""
    import graybox as gb

    u, y = first_order_signals(200, 0, noise=0.1)
    st = gb.parse_structure(["y(k-1)", "u(k-1)", "y(k-1)^2"])
    got = []
    for e in (0, 512):
        th = np.array([[0.5, 1.0, 0.01], [0.45, 1.1, 0.0], [0.4, 1.0, 0.05]]) * [1, 2.0**e, 2.0**-e]
        rec = gb.Record(u, y * 2.0**e, Ts=1.0)
        got.append(gb.decide_min_correlation(ParetoSet.from_thetas(st, th, [0.5, 0.7, 0.9], rec, None), rec))
    assert got[1].index == got[0].index
    assert got[1].score == pytest.approx(got[0].score, rel=1e-9)
