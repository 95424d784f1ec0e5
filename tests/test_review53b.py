"""Review 53b: the text-formatting and column-scaling fixes of review52a/52b (percent_text, share_text, exact_text,
bound_text, range_text, unit_label, column_scales)."""

from __future__ import annotations

import sys
import warnings

import numpy as np
import pytest

import graybox as gb


@pytest.mark.parametrize("x", [sys.float_info.max, -sys.float_info.max])
def test_exact_text_of_the_largest_float_reads_back_without_a_warning(x):
    # 75c8de1 judged a text against 4 * np.spacing(|x|): the spacing of the largest float overflows to inf (numpy
    # warned 'overflow encountered in spacing', an error under warnings-as-errors), so any text passed and a local
    # model at ū = 1.7976931348623157e308 read 'ū = (1.79769e+308)', 4e302 off the point
    from graybox.core._reprs import exact_text

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        text = exact_text(x)
        model = gb.Model(gb.Structure(["y(k-1)", "u(k-1)", "1"]), [0.5, 0.4, 0.05])
        said = repr(gb.local_model(model, x, Ts=1.0))
    assert float(text) == x
    assert said.startswith(f"LocalModel(ū = ({text}), ")


@pytest.mark.parametrize("col", [[3e-162, 1e-162, 1e-162], [2e-160, 1e-160], [1.5e-162, 1e-200, 1.5e-162, 4e-162]])
def test_column_scales_of_a_tiny_column_whose_squares_are_subnormal(col):
    # e6da7aa measured a column through its largest |value| only where its mean square underflowed to 0: where the
    # squares fell among the subnormals without all reaching 0 the RMS kept their few bits ([3e-162, 1e-162, 1e-162]
    # read 2.22e-162 for 1.91e-162, 16 % off; up to 65 % in others)
    from graybox.core._least_squares import column_scales

    A = np.column_stack([col, np.arange(1.0, len(col) + 1)])
    want = 1e-162 * np.sqrt(np.mean((np.array(col) * 1e162) ** 2))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = column_scales(A)
    np.testing.assert_allclose(s, [want, np.sqrt(np.mean(A[:, 1] ** 2))], rtol=1e-14)


def test_column_scales_of_ordinary_columns_reads_them_no_more_than_their_rms(monkeypatch):
    # e6da7aa computed np.any(A) and np.all(np.isfinite(A)) over every column of every call, to flag the few columns
    # whose RMS overflows or underflows: 10× the RMS's own time on a 100000 × 30 regression (77 ms for 7), 14 % of an
    # ELS fit's time at N = 1e5; only the columns flagged by their RMS are read again
    import graybox.core._least_squares as least_squares

    sizes = []

    class Counted:
        def __getattr__(self, name):
            return getattr(np, name)

        def any(self, a, *args, **kw):
            sizes.append(np.size(a))
            return np.any(a, *args, **kw)

        def all(self, a, *args, **kw):
            sizes.append(np.size(a))
            return np.all(a, *args, **kw)

    monkeypatch.setattr(least_squares, "np", Counted())
    A = np.column_stack([np.linspace(1.0, 2.0, 50), np.zeros(50), np.full(50, 1e200)])
    s = least_squares.column_scales(A)
    assert max(sizes, default=0) <= 2 * A.shape[0]  # the all-zero and the large column, not all three
    np.testing.assert_allclose(s, [np.sqrt(np.mean(A[:, 0] ** 2)), 1.0, 1e200], rtol=1e-14)


def _positive_input_plant(n: int = 40, square: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """u uniform on [1, 2] and y(k) = 0.5 y(k-1) + 0.3 u(k-1) + square · u(k-1)² + 0.001 e(k) (seed 3)."""
    rng = np.random.default_rng(3)
    u = rng.uniform(1, 2, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + 0.3 * u[k - 1] + square * u[k - 1] ** 2 + 0.001 * rng.standard_normal()
    return u, y


def test_semp_takes_an_input_whose_square_is_subnormal_without_a_warning():
    # e6da7aa scaled a tiny candidate column by its true RMS where it had been a zero column (its squares underflowed):
    # an input about 1e-160 made u(k-1)^2 about 1e-320, whose θ (about 1e320) overflowed in the bordered fits, and
    # numpy warned 'overflow encountered in divide' from semp (an error under warnings-as-errors); such a candidate's
    # row is inf, scored as a run that diverges
    u, y = _positive_input_plant()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sel = gb.semp(gb.Candidates(1, 1, degree=2), gb.Record(u * 1e-160, y, Ts=1.0), n_terms=2)
    assert sorted(map(str, sel.structure)) == ["u(k-1)", "y(k-1)"]


def test_semp_refuses_an_included_term_whose_parameter_is_beyond_the_float_range():
    u, y = _positive_input_plant()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"cannot be used on these data: .*\['u\(k-1\)\^2'\] are beyond the float"):
            gb.semp(gb.Candidates(1, 1, degree=2), gb.Record(u * 1e-160, y, Ts=1.0), n_terms=2,
                    include=["u(k-1)^2"])


def test_els_of_a_term_whose_parameter_is_beyond_the_float_range_says_so_without_a_warning():
    # e6da7aa scaled a column of about 1e-320 (u(k-1)^2 of an input about 1e-160) by its RMS where it had been left
    # at 1 (its squares underflowed, and ELS refused the structure as not identifiable): its θ, about 5e318, overflowed
    # in scaled_lstsq's x / s, numpy warned 'overflow encountered in divide' and ELS failed on 'theta has non-finite
    # values at [2]'; scaled_lstsq refuses such a solve, saying why
    u, y = _positive_input_plant(30, square=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="beyond the float range"):
            gb.els(["y(k-1)", "u(k-1)", "u(k-1)^2"], gb.Record(u * 1e-160, y, Ts=1.0), noise=0)
        theta = gb.els(["y(k-1)", "u(k-1)", "u(k-1)^2"], gb.Record(u * 1e-150, y, Ts=1.0), noise=0).model.theta
    np.testing.assert_allclose(theta * [1, 1e-150, 1e-300], [0.5, 0.3, 0.05], atol=0.02)


@pytest.mark.parametrize("fit", ["cls", "pe"])
def test_cls_and_pe_of_a_term_whose_parameter_is_beyond_the_float_range_say_so_without_a_warning(fit):
    # review53b's left item: the same column of about 1e-320 in CLS and PE overflowed in the QP's θ (numpy warned
    # 'overflow encountered in divide', then 'theta has non-finite values at [2]'); refused as scaled_lstsq refuses it
    u, y = _positive_input_plant(30, square=0.05)
    rec = gb.Record(u * 1e-160, y, Ts=1.0)
    terms = ["y(k-1)", "u(k-1)", "u(k-1)^2"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"\['u\(k-1\)\^2'\] are beyond the float range"):
            if fit == "cls":
                gb.cls(terms, rec)
            else:
                gb.pe_pareto(terms, rec, gb.StaticPoints([1e-160, 2e-160], [1.0, 2.0]), lambdas=[0.5])
    # at 1e-150 θ is a float (about 5e298): fitted
    assert np.all(np.isfinite(gb.cls(terms, gb.Record(u * 1e-150, y, Ts=1.0)).model.theta))
