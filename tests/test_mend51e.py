"""Results that should not depend on the zero or the units of the signals (mend51e): each test fits the same data
at two zeros (or units) and compares the results to a relative tolerance justified beside it."""

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

import graybox as gb
from graybox.reference import STRUCTURE_15
from graybox.selection._centring import closure


def _pumping_at(c: float, data=None):
    """The bundled plant's identification record and static points with c added to the output."""
    data = gb.load_pumping() if data is None else data
    r = data.ident
    return gb.Record(r.u, r.y + c, name=r.name), gb.StaticPoints(data.static.ubar, data.static.ybar + c)


# -- 1. starts="pe" ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("offset", [1e4, 1e6])
def test_pe_starts_of_a_centred_problem_do_not_depend_on_the_output_zero(offset):
    # was: _pe_members solved PE's closed form on the raw records, so the starts of the GA and the gradient
    # (starts="pe") carried y's zero: in the optimisers' coordinates z the starts of the ℓ = 2 structure's closure
    # moved by 5e-8 of their norm at y + 1e4 and 1.7e-7 at y + 1e6 (the closed form's round-off on a constant of
    # 1e4 against a spread of 5), and a GA's result with them by 2e-10
    from graybox.estimation._simulation_error import SEProblem, _pe_starts

    data = gb.load_pumping()
    st = closure(STRUCTURE_15)
    p0, p1 = (SEProblem(st, *_pumping_at(c, data)) for c in (0.0, offset))
    z0, z1 = (p.to_z(np.array(_pe_starts(p))) for p in (p0, p1))
    # the optimisers' coordinates z are those of the centred signals, the same at every offset: the starts agree
    # there to the round-off of centring and of the map back from θ, eps·offset relative to y's spread of ~5
    # (measured 1e-12 at 1e4, 1.5e-10 at 1e6); 1e-8 leaves that 60 times at 1e6 and fails the raw closed form
    assert z0.shape == z1.shape == (4, len(st))
    err = np.linalg.norm(z1 - z0, axis=1) / np.linalg.norm(z0, axis=1)
    assert np.all(err < 1e-8), err



# -- 2. a closed structure at y + 1e6 refused as not identifiable --------------------------------------------------
_QUADRATIC_IN_Y = ["1", "y(k-1)", "y(k-2)", "y(k-1)y(k-2)", "y(k-1)^2", "y(k-2)^2", "u(k-1)"]


def test_a_closed_structure_at_y_plus_1e6_is_identified_as_at_y():
    # was: ELS and the SE problem judged identifiability on the raw regressors, where at y + 1e6 the quadratic
    # columns in y(k-1), y(k-2) differ from the constant and the linear ones by (spread / level)² ≈ 2.5e-11 only: the
    # stacked regression read as rank 6 of 7 and both were refused ("not identifiable from the identification
    # records"), while at y + 0 they fit. A closed structure's rank is the same at every offset; both now judge the
    # centred regression they fit on (ELS's, SEProblem's z_psi with its centred static points)
    from graybox.estimation._simulation_error import SEProblem

    data = gb.load_pumping()
    st = gb.parse_structure(_QUADRATIC_IN_Y)
    fits, problems = [], []
    for c in (0.0, 1e6):
        rec, points = _pumping_at(c, data)
        fits.append(gb.els(st, rec, noise=0))  # its least squares: the same identifiability rule, no iteration
        problems.append(SEProblem(st, rec, points))
        problems[-1].check_identified()
    x0, x1 = (np.concatenate(f.residuals) for f in fits)
    # fitted centred, the two see signals that differ by the round-off of y + 1e6, 1e6 eps ≈ 2.2e-10 output units,
    # 5e-11 of y's spread of 5 (measured 3.8e-11): 1e-9 of it
    sd = np.std(data.ident.y)
    assert np.max(np.abs(x1 - x0)) <= 1e-9 * sd
    # the SE problem's least squares in its (centred) coordinates, the same: measured 3e-11 of its norm
    z0, z1 = (p.ls_z() for p in problems)
    assert np.linalg.norm(z1 - z0) <= 1e-9 * np.linalg.norm(z0)


# -- 3. a triple root's verdict ----------------------------------------------------------------------------------
_CUBIC = ["1", "y(k-1)", "y(k-2)", "y(k-1)^2", "y(k-1)^3", "u(k-1)"]


def _triple_root_theta(r: float, c: float, b: float, k: float, m: float) -> np.ndarray:
    """θ of _CUBIC whose static equation at ū = m is c (ȳ − r)³ = 0 in y's units times k and u's times m (b: the
    share of y(k-2) in the linear term, so that the linearisation has two lags)."""
    lin = 1.0 + 3.0 * r * r * c
    return np.array([k * (-c * r**3 - 0.5), lin - b, b, -3.0 * r * c / k, c / k**2, k * 0.5 / m])


@settings(max_examples=200, deadline=None)
@given(r=st.floats(-3, 3), c=st.floats(-2, 0), sign=st.sampled_from([-1.0, 1.0]), b=st.floats(-0.5, 0.5),
       k=st.sampled_from([1.0, 1e-3, 3.7, 1e3]), m=st.sampled_from([1.0, 1e4]))
@example(r=-1.7333392876770972, c=np.log10(0.16297323908735661),
         sign=-1.0, b=0.1710470741424237, k=3.7, m=1.0)
@example(r=-2.4911322246840424, c=np.log10(0.09753496420782931), sign=-1.0, b=-0.14225186042740134, k=1e3, m=1.0)
@example(r=1.6830498697490466, c=np.log10(0.7018945408677355), sign=-1.0, b=-0.15826986472145133, k=1.0, m=1.0)
def test_a_triple_root_is_one_fold_in_any_units(r, c, sign, b, k, m):
    # was: Kahan's monotone Newton iteration of the cubic solver stepped on F's rounding near a triple root (F, F'
    # and F'' all ~ 0 there) and went far past it: the one real root came out 1.6 % off, not a root, and the fold was
    # called a stable equilibrium, in some units of y or u only (25 of 3000 drawn triple roots; the verdict changed
    # between k = 1 and 3.7 or 1e3, or between m = 1 and 1e4). The law: a triple root, to the rounding of θ, is one
    # equilibrium (its three roots within the coefficients' slack are one), not stable (a fold: a pole at z = 1)
    assume(abs(r) > 0.05)
    th = _triple_root_theta(r, sign * 10.0**c, b, k, m)
    eq = gb.equilibria(gb.parse_structure(_CUBIC), th, m)
    assert len(eq) == 1 and not eq[0].stable, eq
    # where: a triple root's computed value is good to ~ (eps · the terms' sizes / |c|)^(1/3) only (6e-6 for unit
    # sizes; |c| down to 0.01 and terms up to 30 make it ~1e-4 of |r|): 1e-3 of |r| says the root is that root
    assert abs(eq[0].ybar / k - r) <= 1e-3 * abs(r)


# -- 4. ELS's MA part at y + 1e4 ---------------------------------------------------------------------------------
def _narmax(n: int = 2000, seed: int = 3) -> gb.Record:
    """y = 0.5 + 0.6 y1 + 0.3 u1 − 0.05 u1² + 0.02 y1 u1 + e + 0.4 e1 − 0.2 e2 + 0.1 e1 u1, e of std 0.05."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    e = 0.05 * rng.standard_normal(n)
    y = np.zeros(n)
    for k in range(2, n):
        y[k] = (0.5 + 0.6 * y[k - 1] + 0.3 * u[k - 1] - 0.05 * u[k - 1] ** 2 + 0.02 * y[k - 1] * u[k - 1] + e[k]
                + 0.4 * e[k - 1] - 0.2 * e[k - 2] + 0.1 * e[k - 1] * u[k - 1])
    return gb.Record(u, y)


@pytest.mark.parametrize("plant", ["narmax", "pumping"])
@pytest.mark.parametrize("noise", [2, ["e(k-1)", "e(k-2)", "e(k-1)u(k-1)"], ["e(k-1)", "e(k-1)y(k-1)"]])
def test_els_with_its_ma_part_is_the_same_model_at_y_plus_1e4(plant, noise):
    # was: an MA part with products (e(k-1)u(k-1), e(k-1)y(k-1)) kept ELS on the raw signals, where at y + 1e4 the
    # residuals came out 1.6e-9 to 2.7e-9 of their spread apart from those at y (an MA part of plain lags, fitted on
    # the centred signals, agreed to 5e-11)
    from graybox.selection._centring import shift_map

    if plant == "narmax":
        st, rec = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2", "y(k-1)u(k-1)"]), _narmax()
    else:
        st, rec = gb.parse_structure(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]), gb.load_pumping().ident
    fits = [gb.els(st, gb.Record(rec.u, rec.y + c), noise=noise) for c in (0.0, 1e4)]
    assert fits[0].n_iter == fits[1].n_iter and fits[0].converged == fits[1].converged
    x0, x1 = (np.concatenate(f.residuals) for f in fits)
    # centred, the two fits see signals that differ by the round-off of y + 1e4, 1e4 eps ≈ 2.2e-12 (output units),
    # ~4e-11 of the residuals' spread (0.05 to 0.14); measured 1.3e-11 to 5.9e-11: 3e-10 leaves it 5 times
    assert np.max(np.abs(x1 - x0)) <= 3e-10 * np.std(x0)
    # the same model: the process and MA parameters at y mapped to y + 1e4 (e(k-1)y(k-1)'s MA coefficient moves
    # 1e4 times itself onto e(k-1)'s), to 1e-11 of the largest scaled parameter (θ_j times its regressor's RMS;
    # measured 1e-15 to 1.1e-13)
    full = gb.Structure(list(st) + list(fits[0].model.noise_structure))
    A, t = shift_map(full, {"y": 1e4, "u": 0.0})
    mapped = A @ np.r_[fits[0].model.theta, fits[0].model.noise_theta] + t
    got = np.r_[fits[1].model.theta, fits[1].model.noise_theta]
    e = np.r_[np.zeros(rec.y.size - x1.size), x1]  # the residuals from the first regression row on
    rms = np.sqrt(np.mean(gb.regressor_matrix(full, rec.u, rec.y + 1e4, e=e) ** 2, axis=0))
    assert np.max(np.abs(mapped - got) * rms) <= 1e-11 * np.max(np.abs(got) * rms)
