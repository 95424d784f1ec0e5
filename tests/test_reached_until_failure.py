"""reached_equilibria(until_failure=True), J_SF's question: does a member reach every point, and where?

A member's runs stop once one of its points is not reached. What holds: a member that reaches every
point gets exactly the full answer; one that misses a point misses one in both; every point run to its
end (not "not evaluated") has the full answer's status and ȳ. So J_SF is the same number.
"""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from graybox import Record, StaticPoints
from graybox.estimation._simulation_error import SEProblem
from graybox.static._analysis import NONE_STABLE, REACHED, SKIPPED, reached_equilibria
from test_reached import CUBIC, ONE_STABLE, TWO_STABLE


@st.composite
def members_and_points(draw):
    thetas = np.stack([b.theta * np.array([draw(st.floats(0.8, 1.2)), 1.0, draw(st.floats(0.5, 1.5)), 1.0])
                       for b in draw(st.lists(st.sampled_from([ONE_STABLE, TWO_STABLE]), min_size=1, max_size=4))])
    m = draw(st.integers(1, 5))
    ubar = np.array(draw(st.lists(st.floats(-1500.0, 1500.0), min_size=m, max_size=m)))
    y0 = np.array(draw(st.lists(st.floats(-2.5, 2.5), min_size=m, max_size=m)))
    return thetas, ubar, y0


def assert_answers_jsf_as(part, full) -> None:
    """``part`` (until_failure) says what ``full`` says of J_SF: which members reach every point, and every point
    run to its end the same; a point is left unevaluated only in a member that misses another."""
    every = full.ok.all(axis=1)
    np.testing.assert_array_equal(part.ok.all(axis=1), every)
    np.testing.assert_array_equal(part.status[every], full.status[every])
    np.testing.assert_array_equal(part.ybar[every], full.ybar[every])
    ran = part.status != SKIPPED
    np.testing.assert_array_equal(part.status[ran], full.status[ran])
    np.testing.assert_array_equal(part.ybar[ran], full.ybar[ran])
    assert not (part.status == SKIPPED)[every].any()


@given(members_and_points())
@settings(max_examples=60, deadline=None)
def test_property_until_failure_answers_jsf_as_the_full_analysis(case):
    thetas, ubar, y0 = case
    full = reached_equilibria(CUBIC, thetas, ubar, y0)
    part = reached_equilibria(CUBIC, thetas, ubar, y0, until_failure=True)
    assert_answers_jsf_as(part, full)


def test_a_point_with_no_stable_equilibrium_leaves_the_members_other_points_unrun():
    # ONE_STABLE has no stable equilibrium at ū = 3000
    ubar, y0 = np.array([100.0, 3000.0]), np.array([0.2, 0.2])
    thetas = ONE_STABLE.theta[None]
    full = reached_equilibria(CUBIC, thetas, ubar, y0)
    part = reached_equilibria(CUBIC, thetas, ubar, y0, until_failure=True)
    assert full.status[0].tolist() == [REACHED, NONE_STABLE]
    assert part.status[0].tolist() == [SKIPPED, NONE_STABLE]
    assert "not evaluated" in part.explain(0)[0]
    both = reached_equilibria(CUBIC, np.stack([ONE_STABLE.theta, TWO_STABLE.theta]), [100.0, 100.0], [0.2, 0.5],
                              until_failure=True)
    assert both.ok.all()  # nothing is skipped where every point is reached


def test_se_problem_scored_outputs_do_not_stand_in_for_the_full_ones():
    # J_SF is inf either way; the per-point outputs asked afterwards (the solver's memo of one θ) are the full ones
    rng = np.random.default_rng(0)
    rec = Record(rng.uniform(0.0, 200.0, 200), rng.uniform(0.0, 0.5, 200))
    pts = StaticPoints([100.0, 3000.0], [0.2, 0.2])
    prob = SEProblem(CUBIC, rec, pts)
    th = ONE_STABLE.theta[None]
    assert prob.jsf(th)[0] == np.inf
    full = reached_equilibria(CUBIC, th, pts.ubar, pts.ybar).ybar
    np.testing.assert_array_equal(prob.static_outputs(th), full)
    assert np.isfinite(prob.static_outputs(th)[0, 0])




@st.composite
def surface_members_and_points(draw):
    P = draw(st.integers(1, 4))
    thetas = np.array([[draw(st.floats(0.2, 0.9)), draw(st.floats(-0.3, 0.3)), draw(st.floats(-1.0, 1.0)),
                        draw(st.floats(-1.0, 1.0))] for _ in range(P)])
    M = draw(st.integers(1, 5))
    ubar = np.array([[draw(st.floats(-2.0, 2.0)), draw(st.floats(-2.0, 2.0))] for _ in range(M)])
    y0 = np.array(draw(st.lists(st.floats(-3.0, 3.0), min_size=M, max_size=M)))
    return thetas, ubar, y0


@given(surface_members_and_points())
@settings(max_examples=60, deadline=None)
def test_property_until_failure_on_a_static_surface_answers_jsf_as_the_full_analysis(case):
    from graybox import Structure
    from graybox.static._surface_analysis import reached_surface

    thetas, ubar, y0 = case
    structure = Structure(["y(k-1)", "y(k-1)^2", "u1(k-1)", "u2(k-1)"])
    full = reached_surface(structure, thetas, ubar, y0)
    part = reached_surface(structure, thetas, ubar, y0, until_failure=True)
    assert_answers_jsf_as(part, full)


def test_a_surface_member_missing_one_point_leaves_its_other_points_unrun_and_not_the_other_members():
    from graybox import Structure
    from graybox.static._surface_analysis import reached_surface

    structure = Structure(["y(k-1)", "y(k-1)^2", "u1(k-1)", "u2(k-1)"])
    # equilibria: b ȳ² − (1 − a) ȳ + c u1 + d u2 = 0; member 0 has none at u1 = 3 (discriminant < 0)
    thetas = np.array([[0.5, 0.2, 1.0, 0.0], [0.5, 0.0, 1.0, 0.0]])
    ubar = np.array([[0.0, 0.0], [3.0, 0.0], [-0.1, 0.0]])
    y0 = np.zeros(3)
    full = reached_surface(structure, thetas, ubar, y0)
    part = reached_surface(structure, thetas, ubar, y0, until_failure=True)
    assert not full.ok[0, 1] and full.ok[0, 0] and full.ok[1].all()
    assert part.status[0, 0] == SKIPPED and part.status[0, 2] == SKIPPED and part.status[0, 1] == full.status[0, 1]
    np.testing.assert_array_equal(part.ybar[1], full.ybar[1])


def test_a_local_model_is_never_not_evaluated(tmp_path):
    # "not evaluated" is a status of J_SF's partial analysis only; a local model evaluates its one point, so a
    # file that says it is refused (Reached.STATUS gained it, and LocalModel checked its status against all of them)
    import json

    import graybox as gb
    from graybox.control import local_model

    lm = local_model(gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]), 1.0, Ts=1.0)
    gb.save(lm, tmp_path / "lm.json")
    doc = json.loads((tmp_path / "lm.json").read_text())
    doc["object"].update(status="not evaluated", ybar=None, reason="ū = 1: not evaluated")
    (tmp_path / "lm.json").write_text(json.dumps(doc))
    with pytest.raises(gb.GrayboxFileError, match="status must be one of"):
        gb.load(tmp_path / "lm.json")
