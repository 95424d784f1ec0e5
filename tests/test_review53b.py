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
