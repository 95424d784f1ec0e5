"""hunt48b: statics and free runs."""

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("domain", [None, (0.0, 10.0)])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_static_curve_refuses_non_finite_levels(domain, bad):
    # StaticCurve(NaN) returned NaN (a NaN lies outside no range, so the domain's check let it pass) where
    # StaticSurface refuses it: a bad level is said, not evaluated
    c = gb.StaticCurve.polynomial([1.0, 2.0, 3.0], domain=domain)
    for f in (c, c.gain):
        with pytest.raises(ValueError, match="non-finite"):
            f([1.0, bad])
        with pytest.raises(ValueError, match="non-finite"):
            f(bad)
    assert c([1.0, 2.0]).tolist() == [6.0, 17.0]
    assert c.gain(2.0) == 14.0


def _documented_parameters(f):
    """The names a numpydoc ``Parameters`` section lists (``a : type`` or ``a, b``)."""
    import inspect
    import re

    doc = inspect.getdoc(f) or ""
    m = re.search(r"^Parameters\n-+\n(.*?)(?:\n\n[A-Z][a-z]+\n-+|\Z)", doc, re.S | re.M)
    names = []
    for line in (m.group(1).splitlines() if m else []):
        if line.strip() and not line.startswith(" "):
            names += [n.strip() for n in line.split(" : ")[0].split(",") if n.strip()]
    return names


@pytest.mark.parametrize("f", [gb.static_curve, gb.static_gain, gb.static_surface, gb.static_surface_gain,
                               gb.equilibria, gb.surface_equilibria, gb.simulate, gb.predict, gb.simulate_many,
                               gb.evaluate, gb.evaluate_thetas, gb.jsf, gb.j1, gb.js, gb.surface_cluster_map],
                         ids=lambda f: f.__name__)
def test_documented_parameters_are_parameters(f):
    # static_surface_gain's docstring listed a parameter ``inputs`` it does not take (TypeError when passed)
    import inspect

    names = _documented_parameters(f)
    assert names, f"{f.__name__} documents no parameters"
    assert set(names) <= set(inspect.signature(f).parameters), names


def test_model_simulate_default_bound_is_the_one_its_docstring_gives():
    # Model.simulate's docstring gave the default bound as 1e6 × max(max|y0|, the inputs' push): 1e6 here. The run
    # y(k) = 2 y(k-1) - 1e-9 y(k-1)² from y0 = 1 settles at its stable equilibrium 1e9 and is (rightly) no divergence:
    # the bound also counts the size at which the output feedback matters (1e9), as graybox.simulate says
    m = gb.Model(["y(k-1)", "y(k-1)^2", "u(k-1)"], [2.0, -1e-9, 0.0])
    y = m.simulate(np.zeros(200), [1.0])
    assert np.isfinite(y).all() and y[-1] == pytest.approx(1e9)
    assert np.abs(y).max() > 1e6 * 1.0  # beyond what the docstring's rule allowed
    assert "feedback" in " ".join(gb.Model.simulate.__doc__.split())


def test_surface_cluster_map_made_by_hand_is_immutable_and_checked():
    # SurfaceClusterMap kept the R it was given, writable (cm.R[0, 0] = 5 changed the map), and of any shape
    # (one key, a 3 × 3 R); surface_cluster_map's own R is read-only
    R = np.eye(2)
    cm = gb.SurfaceClusterMap(("u1", "u2"), ((0, 1, 0), (1, 0, 0)), R)
    with pytest.raises(ValueError):
        cm.R[0, 0] = 5.0
    R[0, 0] = 7.0  # the caller's array is not the map's
    assert cm.R[0, 0] == 1.0
    with pytest.raises(ValueError, match="one row per cluster"):
        gb.SurfaceClusterMap(("u1", "u2"), ((0, 1, 0),), np.eye(3))
    built = gb.surface_cluster_map(gb.parse_structure(["y(k-1)", "u1(k-1)", "u2(k-1)"]))
    assert not built.R.flags.writeable and built.R.shape == (3, 3)


def test_static_curve_points_take_a_column_or_one_level():
    # StaticCurve.points of a column of levels (M, 1) said "ybar must be 1-D, got shape (2, 1)", of a ybar the caller
    # never gave, and of one level "ubar must be 1-D ... got 0-D"; Model.static_curve and StaticSurface take both
    c = gb.StaticCurve.polynomial([1.0, 2.0, 3.0])
    p = c.points([[1.0], [2.0]])
    assert p.ubar.tolist() == [1.0, 2.0] and p.ybar.tolist() == [6.0, 17.0]
    assert c.points(1.0).ybar.tolist() == [6.0]
    with pytest.raises(ValueError, match=r"ubar must be levels of the one input.*\(1, 2\)"):
        c.points([[1.0, 2.0]])
