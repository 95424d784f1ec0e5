"""Bug hunt 44e: static constraints, infeasible sets and the diagnostics of trust."""

import numpy as np
import pytest

import graybox as gb
from graybox.experiments._spec import SpecError, build_constraint, constraint_from_object


# --------------------------------------------------------------------------------------------
# a grid's equality table from a CurveEquality on a StaticSurface
# --------------------------------------------------------------------------------------------
def test_grid_equality_of_a_one_input_surface_keeps_its_powers():
    # 1 + 3ū² as a surface of one input: its coefficients are by exponent, (0,) and (2,); read as an
    # ascending curve they said 1 + 3ū, and the grid imposed that curve instead
    s = gb.StaticSurface(exponents=((0,), (2,)), coefficients=[1.0, 3.0], input_names=("u",))
    (table,) = constraint_from_object(gb.CurveEquality(s))
    curve = build_constraint(table).curve
    ub = np.array([0.5, 2.0, 7.0])
    np.testing.assert_allclose(curve(ub), s(ub[:, None]), rtol=1e-14)


def test_grid_equality_of_a_surface_of_several_inputs_is_refused_by_name():
    pts = gb.StaticPoints(np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 1], [1, 2]], float),
                          np.array([1, 2, 3, 4, 5, 6.0]))
    surf = gb.StaticSurface.fit(pts, degree=1)
    with pytest.raises(SpecError, match="surface"):
        constraint_from_object(gb.CurveEquality(surf))
