"""review57d: regressions found reviewing the stability judgements of the free run's bound, the static analysis and
graybox.control."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.signal import lfilter

import graybox as gb


def _first_nan(y: np.ndarray) -> int:
    bad = ~np.isfinite(y)
    return int(np.argmax(bad)) if bad.any() else -1


def _resonator(r: float, L: int, through: bool) -> gb.Model:
    # y(k) = Σ_l a_l y(k−l) + u(k−1), the last lag's term fed back through v(k−1) (v held at 1) or constant: poles
    # r e^{±j(π − 0.01)} and 0.5 (L = 3; and −0.3, L = 4), by hand
    w = np.pi - 0.01
    a = -np.real(np.poly([r * np.exp(1j * w), r * np.exp(-1j * w), 0.5, -0.3][:L]))[1:]
    last = f"y(k-{L})v(k-1)" if through else f"y(k-{L})"
    return gb.Model([f"y(k-{l})" for l in range(1, L)] + [last, "u(k-1)"], [*a, 1.0],
                    input_names=("u", "v") if through else ("u",))


_N = 60_000
_U = np.column_stack([np.sin((np.pi - 0.01) * np.arange(_N)), np.ones(_N)])


@pytest.mark.parametrize("L", [3, 4])
def test_a_stable_feedback_through_a_second_input_beyond_lag_2_is_not_divergence_at_resonance(L):
    """9cdab12 reads the poles of each sample's feedback through the inputs for lags 1 and 2 only; beyond, the bound
    took the steady gain 1/D (D = 1 − Σa = 2 at L = 3): poles 0.9999999 e^{±j(π − 0.01)} and 0.5, fed back through
    y(k−3)·v(k−1) with v held at 1 and driven at the pair's frequency, build up to ~1e8 × the push and the run was
    called divergent at sample 30151, where the same recursion with a constant θ y(k−3) runs to its end."""
    from graybox.core._simulation_kernels import batch_sse, encode, record_inputs

    through, constant = _resonator(1 - 1e-7, L, True), _resonator(1 - 1e-7, L, False)
    rec = gb.Record(_U, np.zeros(_N), input_names=("u", "v"))
    y = through.simulate(rec)
    twin = constant.simulate(_U[:, 0], np.zeros(L))
    assert np.all(np.isfinite(twin)) and np.abs(twin).max() > 1e6  # beyond 1e6 × the steady level 1/D
    np.testing.assert_allclose(y, twin, rtol=1e-9, atol=1e-9 * np.abs(twin).max())
    for threads in (1, 2):
        runs = gb.simulate_many(through, np.vstack([through.theta] * 4), rec, threads=threads)
        assert [_first_nan(r) for r in runs] == [-1] * 4
        # the bounded sum of squares, as gb.js and the selection's scoring read it: finite, the run's own
        code = encode(through.structure, ("u", "v"))
        sse = batch_sse(code, np.vstack([through.theta] * 4), record_inputs(rec, ("u", "v")), rec.y, L, threads,
                        bounded=True)
        np.testing.assert_allclose(sse, np.sum(twin[L:] ** 2), rtol=1e-6)
    assert _first_nan(through.predict(rec, horizon=len(rec))) == -1


@pytest.mark.parametrize("L", [3, 4])
@pytest.mark.parametrize("threads", [1, 2])
def test_a_growing_feedback_through_a_second_input_beyond_lag_2_is_caught_where_its_constant_twin_is(threads, L):
    from graybox.core._simulation_kernels import batch_sse, encode, record_inputs

    through, constant = _resonator(1.001, L, True), _resonator(1.001, L, False)
    stop = _first_nan(constant.simulate(_U[:, 0], np.zeros(L), on_diverge="nan"))
    assert 0 < stop < 10_000
    rec = gb.Record(_U, np.zeros(_N), input_names=("u", "v"))
    assert _first_nan(through.simulate(rec, on_diverge="nan")) == stop
    runs = gb.simulate_many(through, np.vstack([through.theta] * 5), rec, threads=threads)
    assert [_first_nan(r) for r in runs] == [stop] * 5
    code = encode(through.structure, ("u", "v"))
    sse = batch_sse(code, np.vstack([through.theta] * 5), record_inputs(rec, ("u", "v")), rec.y, L, threads,
                    bounded=True)
    assert not np.any(np.isfinite(sse))
    assert _first_nan(through.predict(rec, horizon=len(rec))) == stop


@pytest.mark.parametrize("threads", [1, 2])
def test_a_population_mixing_resonant_growing_and_quiet_members_stops_each_where_its_own_run_does(threads):
    # the batch kernels judge every member by the steady gain first and re-run those it stops by the lattice
    # margin: each member of a mixed population must still end where its own free run does, and the others be
    # untouched by its re-run
    L = 3
    rec = gb.Record(_U[:40_000], np.zeros(40_000), input_names=("u", "v"))
    members = [_resonator(1 - 1e-7, L, True), _resonator(1.001, L, True), _resonator(0.5, L, True)]
    thetas = np.vstack([m.theta for m in members] * 2)
    own = [_first_nan(m.simulate(rec, on_diverge="nan")) for m in members] * 2
    assert own[:3] == [-1, own[1], -1] and 0 < own[1] < 10_000
    runs = gb.simulate_many(members[0], thetas, rec, threads=threads)
    assert [_first_nan(r) for r in runs] == own
    for r, m in zip(runs, members * 2):
        if _first_nan(r) < 0:
            np.testing.assert_allclose(r, m.simulate(rec), rtol=1e-9, atol=1e-9 * np.abs(r).max())


def test_linear_margins_marks_a_feedback_through_an_input_beyond_lag_2_for_the_lattice_pass_row_by_row():
    # −2 (judged by the steady gain first, by the lattice margin where that stops the run) for a finite θ, 1 for a
    # non-finite one: one run's path (floats) and several rows' (arrays) alike
    from graybox.core._simulation_kernels import encode, linear_margins

    code = encode(gb.parse_structure(["y(k-1)", "y(k-3)v(k-1)", "u(k-1)"]), ("u", "v"))
    rows = np.array([[0.5, 0.1, 1.0], [np.nan, 0.1, 1.0], [0.5, np.inf, 1.0], [0.0, 0.0, 0.0]])
    assert linear_margins(code, rows).tolist() == [-2.0, 1.0, 1.0, -2.0]
    assert [linear_margins(code, r)[0] for r in rows] == [-2.0, 1.0, 1.0, -2.0]
    lag2 = encode(gb.parse_structure(["y(k-1)", "y(k-2)v(k-1)", "u(k-1)"]), ("u", "v"))
    assert [linear_margins(lag2, r)[0] for r in rows] == [-1.0, 1.0, 1.0, -1.0]


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, 1.05), st.floats(0.0, np.pi), st.booleans()), min_size=1, max_size=4))
def test_property_the_lattice_margin_bounds_the_peak_to_peak_gain_of_any_order(parts):
    # lattice_margin stands in for 1 / Σ|h| where the feedback through the inputs reads a lag beyond 2 and the steady
    # gain stopped a run: at most 1 / Σ|h| (by the impulse response), at least the small-gain 1 − Σ|a_l|; 2 where a
    # pole is not inside (by numpy's roots)
    from graybox.core._simulation_kernels import lattice_margin

    poles = []
    for r, w, pair in parts:
        poles += [r * np.exp(1j * w), r * np.exp(-1j * w)] if pair else [r if w < np.pi / 2 else -r]
    A = np.real(np.poly(poles))
    a, L = -A[1:], len(poles)
    radii = np.abs(np.roots(A))
    assume(np.all(np.abs(radii - 1.0) > 1e-6))
    got = lattice_margin(a, np.empty(L))
    if np.all(radii < 1.0):
        assert got >= (1.0 - np.abs(a).sum()) * (1 - 1e-12)
        assume(radii.max() < 0.995)
        h = lfilter([1.0], A, np.r_[1.0, np.zeros(int(40 / (1 - radii.max())))])
        assert got <= 1.0 / np.abs(h).sum() * (1 + 1e-9)
    else:
        assert got == 2.0


def test_a_local_model_s_reason_names_its_equilibrium_as_it_is_at_an_offset():
    # 'linearised at the unstable ȳ = 10000' of the equilibrium 10000.01 (%g), as 00e9f2d's ū were
    m = gb.Model(["y(k-1)", "u(k-1)"], [1.5, 1.0], Ts=1.0)  # ȳ = −2ū, pole 1.5
    lm = gb.local_model(m, -5000.005)
    assert lm.ybar == pytest.approx(10000.01, rel=1e-15)
    assert "unstable ȳ = 10000.01 " in lm.reason
    # every ȳ an equilibrium (y(k) = y(k-1) + u(k-1) at ū = 0): linearised at y0, named as given
    lm = gb.local_model(gb.Model(["y(k-1)", "u(k-1)"], [1.0, 1.0], Ts=1.0), 0.0, y0=10000.01)
    assert lm.reason.endswith("ȳ = y0 = 10000.01")
