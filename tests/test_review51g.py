"""review51g: a grid spec's lambdas = {logspace = [a, b, n]} with an exponent beyond the float range."""
import warnings

import pytest

from graybox.experiments import Grid
from graybox.experiments._spec import SpecError

SPEC = '''name = "t"
[[data]]
name = "p"
bundled = "pumping"
[[structures]]
name = "s"
terms = ["y(k-1)", "u(k-1)", "1"]
[[variants]]
name = "PE"
estimator = "pe"
lambdas = {logspace = %s}
'''


@pytest.mark.parametrize("args, key", [("[0, 400, 3]", "stop"), ("[-400, 0, 3]", "start")])
def test_a_logspace_exponent_beyond_the_float_range_is_a_spec_error_naming_it_without_numpys_warning(args, key):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's 'overflow encountered in power' leaked through
        with pytest.raises(SpecError, match=rf"logspace.*{key}.*float range"):
            Grid.from_toml_text(SPEC % args)


def test_a_logspace_within_the_range_is_its_values():
    assert Grid.from_toml_text(SPEC % "[-3, 0, 3]").variants[0].lambdas == pytest.approx((1e-3, 10 ** -1.5, 1.0))
