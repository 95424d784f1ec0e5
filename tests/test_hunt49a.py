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
