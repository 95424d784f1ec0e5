"""hunt49a: simulation-error estimation (GA, gradient, se_dsf), output error and the neural model."""

import warnings

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._simulation_error import GAOptions, se_pareto

OE_STRUCT = gb.Structure(["y(k-1)", "u(k-1)", "u(k-2)^2", "u(k-1)y(k-1)"])
OE_THETA = np.array([0.7, 0.25, 0.1, -0.05])


def oe_record(seed: int = 1, N: int = 400, noise: float = 0.15, name: str = "oe") -> gb.Record:
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1.0, 1.0, N // 8 + 1), 8)[:N]
    x = gb.Model(OE_STRUCT, OE_THETA).simulate(u, np.zeros(2))
    return gb.Record(u, x + noise * rng.standard_normal(N), name=name)


def oe_static() -> gb.StaticPoints:
    ub = np.array([-0.8, -0.3, 0.2, 0.7])
    return gb.StaticPoints(ub, np.array([-0.52307692, -0.23157895, 0.17419355, 0.66865672]))


@pytest.mark.parametrize("failures", ["[]", "[1, 2]", "5", "null", '"x"', '{"0": null}', '{"0": 3}'])
def test_a_checkpoint_whose_failed_members_are_no_mapping_of_reasons_is_refused_by_name(tmp_path, failures):
    # the sweep writes {"member": "reason"}; a list was read by .items(): a bare AttributeError
    ck = tmp_path / "front.npz"
    kw = dict(lambdas=[1.0, 0.5], options=GAOptions(population=10, generations=2), checkpoint=ck, margin=None)
    r, sp = oe_record(), oe_static()
    se_pareto(OE_STRUCT, r, sp, **kw)
    arrays = dict(np.load(ck))
    arrays["failures"] = np.array(failures)
    np.savez(ck, **arrays)
    with pytest.raises(ValueError, match="not a readable SE checkpoint"):
        se_pareto(OE_STRUCT, r, sp, **kw)


def test_se_dsf_from_a_diverging_theta0_says_so_without_a_numpy_overflow_warning():
    # the start's residuals were squared outside any errstate: "RuntimeWarning: overflow encountered in matmul"
    # came before (under -W error: instead of) the ValueError naming the start
    r = oe_record()
    sp = gb.StaticPoints(oe_static().ubar, oe_static().ybar, uncertainty=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"no start \(theta0\) has a bounded free run"):
            gb.se_dsf(OE_STRUCT, r, sp, theta0=[3.0, 0.0, 0.0, 0.0], margin=None)


#: A structure closed under shifts (every divisor of every term present): its SE problem is centred.
CLOSED = gb.Structure(["1", "y(k-1)", "u(k-1)", "u(k-2)", "u(k-2)^2", "u(k-1)y(k-1)", "y(k-1)^2"])


@pytest.mark.parametrize("offset", [1e4, -3e4, 1e5])
def test_the_optimisers_weighted_cost_does_not_depend_on_the_outputs_zero(offset):
    # J_SF was solved for the raw model at the raw points, whose polynomial holds the offsets' powers (a constant
    # of 1e8 at y + 1e4): at the same z the cost was 8e-9 (y + 1e4) to 9e-7 (y + 1e5) off relative, J_S 1e-12
    from graybox.estimation._simulation_error import SEProblem
    r0 = oe_record()
    sp0 = oe_static()
    p0 = SEProblem(CLOSED, r0, sp0)
    p1 = SEProblem(CLOSED, gb.Record(r0.u, r0.y + offset), gb.StaticPoints(sp0.ubar, sp0.ybar + offset))
    z = p0.to_z(p0.ls_theta())
    Z = z + 0.01 * np.random.default_rng(0).standard_normal((20, z.size)) * np.abs(z)
    c0 = p0.cost(p0.from_z(Z), 0.5, z=Z)
    c1 = p1.cost(p1.from_z(Z), 0.5, z=Z)
    assert np.all(np.isfinite(c0))
    np.testing.assert_allclose(c1, c0, rtol=1e-10)
    # the equilibria reached are still reported in output units, at the offset (raw θ itself, holding the offsets'
    # powers, is the model to some 1e-8 there)
    np.testing.assert_allclose(p1.static_outputs(p1.from_z(Z[:1])), p0.static_outputs(p0.from_z(Z[:1])) + offset,
                               rtol=0, atol=1e-6)


def test_se_dsf_reports_the_same_run_whatever_the_outputs_unit():
    # a step whose fall of J_S was the cost's rounding was kept or refused by that rounding: in mlc and in
    # thousandths of them the same model came with other counts of steps, another reason to stop and another start
    r = oe_record(N=600)
    sp = oe_static()
    band = 3e-4
    a = gb.se_dsf(OE_STRUCT, r, gb.StaticPoints(sp.ubar, sp.ybar + 0.01), band=band, margin=None)
    b = gb.se_dsf(OE_STRUCT, gb.Record(r.u, 1000.0 * r.y), gb.StaticPoints(sp.ubar, 1000.0 * (sp.ybar + 0.01)),
                  band=band * 1e6, margin=None)
    assert a.in_band and b.in_band
    assert (b.start, b.n_iter, b.message) == (a.start, a.n_iter, a.message)
    assert b.JS / 1e6 == pytest.approx(a.JS, rel=1e-12)
    np.testing.assert_allclose(b.model.theta[[0, 3]], a.model.theta[[0, 3]], rtol=1e-9)


def test_output_error_refuses_a_bad_name_or_theta0_before_any_fit(monkeypatch):
    """output_error checked name after every fit and theta0 after the least-squares and ELS starts (hunt49a's note):
    checked at the boundary, before ELS runs."""
    import graybox.estimation._output_error as oe

    def no_els(*args, **kwargs):
        raise AssertionError("ELS ran before the options were checked")

    monkeypatch.setattr(oe, "els", no_els)
    rec = gb.load_pumping().ident
    st = ["y(k-1)", "u(k-1)", "1"]
    with pytest.raises(TypeError, match="name must be a str"):
        gb.output_error(st, rec, name=3)
    with pytest.raises(ValueError, match="theta0"):
        gb.output_error(st, rec, theta0=[1.0, 2.0])
