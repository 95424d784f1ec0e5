import numpy as np
import pytest

from graybox import DivergenceError, Model, reference, simulate_many
from graybox.core._simulation_kernels import encode, simulate_batch


def python_free_run(model: Model, u, y0):
    """Plain-Python reference: the model's equation evaluated term by term."""
    L = model.max_lag
    y = list(y0[:L])
    for k in range(L, len(u)):
        acc = 0.0
        for th, term in zip(model.theta, model.structure):
            v = th
            for s, lag, p in term.factors:
                v *= (y[k - lag] if s == "y" else u[k - lag]) ** p
            acc += v
        y.append(acc)
    return np.array(y)


@pytest.mark.parametrize("eq", [15, 17])
def test_free_run_equals_python_loop(eq, rng):
    from conftest import steps_input

    m = reference.paper_model(eq)
    u = steps_input(3200, rng)
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    ref = python_free_run(m, u, y0)
    got = m.simulate(u, y0)
    assert np.max(np.abs(got - ref) / np.abs(ref)) < 1e-12


def test_batch_equals_single_runs(paper_record, rng):
    m = reference.paper_model(15)
    thetas = m.theta * (1 + 0.01 * rng.standard_normal((7, m.n_params)))
    Y = simulate_many(m.structure, thetas, paper_record)
    Y2 = simulate_many(m.structure, thetas, paper_record, threads=2)
    assert Y.shape == (7, len(paper_record))
    for i, th in enumerate(thetas):
        ref = Model(m.structure, th).simulate(paper_record, on_diverge="nan")
        np.testing.assert_allclose(Y[i], ref, rtol=1e-13)
        np.testing.assert_allclose(Y2[i], ref, rtol=1e-13)


def test_diverging_member_is_flagged_not_raised(paper_record):
    m = reference.paper_model(15)
    bad = m.theta.copy()
    bad[0] = 3.0  # y(k-1) coefficient far outside the unit circle
    Y = simulate_many(m.structure, np.vstack([m.theta, bad]), paper_record)
    assert np.all(np.isfinite(Y[0]))
    assert not np.all(np.isfinite(Y[1])) or np.max(np.abs(Y[1])) > 1e100
    with pytest.raises(DivergenceError, match="diverged at sample"):
        m.with_theta(bad).simulate(paper_record)
    y = m.with_theta(bad).simulate(paper_record, on_diverge="nan")
    assert np.isnan(y[-1]) and np.isfinite(y[0])


def test_predict_is_regressors_times_theta(paper_record):
    from graybox import regressor_matrix

    m = reference.paper_model(15)
    yhat = m.predict(paper_record)
    L = m.max_lag
    np.testing.assert_allclose(yhat[L:], regressor_matrix(m.structure, paper_record.u, paper_record.y) @ m.theta)
    np.testing.assert_array_equal(yhat[:L], paper_record.y[:L])
    # noise-free data from the model itself: one-step prediction is exact
    np.testing.assert_allclose(yhat, paper_record.y, rtol=1e-10)


def test_kernel_batch_shape_and_initial_conditions(rng):
    m = reference.paper_model(15)
    u = rng.uniform(750, 1650, 50)
    y0 = rng.uniform(2, 20, 6)
    Y = simulate_batch(encode(m.structure), np.tile(m.theta, (3, 1)), u, y0, 6)
    assert Y.shape == (3, 50)
    np.testing.assert_array_equal(Y[:, :6], np.tile(y0, (3, 1)))


def test_a_kernel_compiles_once_whether_its_arrays_are_read_only_or_not(paper_record):
    """A model's θ and a record's samples are read-only arrays, a caller's own are writable: numba compiles a kernel
    once per argument type, so the wrappers hand every kernel one kind (kernel_array), and a second kind of caller
    costs no second compilation (0.5–3 s each, in every process of a cold cache)."""
    from graybox.core import _simulation_kernels as K

    m = reference.paper_model(15)
    code = encode(m.structure)
    u, y = paper_record.u[:200], paper_record.y[:200]
    theta = np.array(m.theta, dtype=float)  # writable
    frozen = theta.copy()
    frozen.flags.writeable = False
    strided = np.repeat(u, 2)[::2]  # not contiguous

    def runs(th, uu, yy):
        K.simulate_one(code, th, uu, yy[:3], 3, None)
        K.predict_ahead(code, th, uu, yy, 3, 5, None)
        K.batch_sse(code, th[None, :], uu, yy, 3)
        K.batch_sse(code, np.vstack([th] * 8), uu, yy, 3, threads=2)

    runs(theta, u, y)
    kernels = (K._one, K._ahead, K._batch_sse, K._batch_sse_parallel, K._input_products)
    before = [len(k.signatures) for k in kernels]
    assert all(before)
    runs(frozen, strided, np.array(y))
    runs(theta, np.array(u), y)
    assert [len(k.signatures) for k in kernels] == before


@pytest.mark.parametrize("terms", [
    None,  # the paper's model (15): single past outputs through the inputs, lags to 6
    ["y(k-1)", "y(k-2)", "u(k-1)", "1"],  # constant linear feedback
    ["y(k-1)^2", "y(k-2)u(k-1)^2", "y(k-1)y(k-3)", "u(k-1)"],  # output power 2 only, with and without inputs
    ["u(k-1)", "u(k-2)^2", "1"],  # no output at all
])
def test_the_codes_bound_facts_are_the_structures(terms):
    # the default bound reads these plain-int facts at every call in place of the code's arrays: they must say what
    # the terms say (recounted here from the terms' own factors)
    from graybox import parse_structure

    st = reference.paper_model(15).structure if terms is None else parse_structure(terms)
    code = encode(st)
    ypow = [sum(p for s, _, p in t.factors if s == "y") for t in st]
    single = [(i, next(l for s, l, _ in t.factors if s == "y")) for i, t in enumerate(st) if ypow[i] == 1]
    assert list(code.single) == single
    assert code.single_inputs == any(any(s != "y" for s, _, _ in st[i].factors) for i, _ in single)
    assert list(code.nonlinear) == [(i, p) for i, p in enumerate(ypow) if p >= 2]


def test_free_run_fast_paths_give_the_checked_paths_numbers(paper_record):
    # a finite float64 θ skips check_theta's conversions and a record's own first outputs skip y0's: the run must be
    # bit-identical to the one through the full conversions (θ a list, u an array, y0 given), and a θ the fast path
    # must not take is still refused
    from graybox import simulate

    m = reference.paper_model(15)
    L = m.max_lag
    fast = m.simulate(paper_record)
    slow = simulate(m.structure, m.theta.tolist(), np.array(paper_record.u), np.array(paper_record.y[:L]).tolist())
    np.testing.assert_array_equal(fast, slow)
    np.testing.assert_array_equal(simulate(m.structure, np.array(m.theta), paper_record), fast)
    bad = np.array(m.theta)
    bad[3] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        simulate(m.structure, bad, paper_record)
    with pytest.raises(ValueError, match="values but the structure has"):
        simulate(m.structure, np.append(m.theta, 0.0), paper_record)
    with pytest.raises(ValueError, match="bound"):
        simulate(m.structure, m.theta, paper_record, bound=-1.0)


def test_a_population_stops_where_each_members_own_run_does(paper_record):
    # the batch kernel tests the bound with a loop that stores nothing and only then updates the members: members
    # that diverge at different samples (some never) beside stable ones, before and after the first stop, must stop
    # at the very sample their own free runs stop, and the others run on as their own runs do
    m = reference.paper_model(15)
    thetas = np.tile(m.theta, (6, 1))
    thetas[:, 0] = [m.theta[0], 1.02, m.theta[0] * 0.999, 1.3, m.theta[0] * 1.001, 3.0]  # the y(k-1) coefficient
    Y = simulate_many(m.structure, thetas, paper_record)
    stops = []
    for i, th in enumerate(thetas):
        own = Model(m.structure, th).simulate(paper_record, on_diverge="nan")
        np.testing.assert_array_equal(np.isnan(Y[i]), np.isnan(own))
        np.testing.assert_allclose(Y[i][np.isfinite(own)], own[np.isfinite(own)], rtol=1e-12)
        stops.append(int(np.argmax(np.isnan(own))) if np.isnan(own).any() else None)
    assert stops[0] is None and stops[2] is None and stops[4] is None
    assert len({s for s in stops if s is not None}) == 3  # three members stop, each at a sample of its own


def test_a_populations_bounded_sse_is_each_members_own_runs(paper_record):
    # batch_sse's bound is tested as simulate_many's (a loop that stores nothing first): members stopping at samples
    # of their own have no finite J_S, the others exactly their own free run's squared error
    from graybox.core._simulation_kernels import batch_sse

    m = reference.paper_model(15)
    thetas = np.tile(m.theta, (5, 1))
    thetas[:, 0] = [m.theta[0], 1.02, m.theta[0] * 0.999, 1.3, 3.0]
    L, r = m.max_lag, paper_record
    sse = batch_sse(encode(m.structure), thetas, r.u, r.y, L, bounded=True)
    for i, th in enumerate(thetas):
        own = Model(m.structure, th).simulate(r, on_diverge="nan")
        if np.isnan(own).any():
            assert not np.isfinite(sse[i])
        else:
            np.testing.assert_allclose(sse[i], np.sum((own[L:] - r.y[L:]) ** 2), rtol=1e-10, atol=1e-18)
    assert np.isfinite(sse).sum() == 2
