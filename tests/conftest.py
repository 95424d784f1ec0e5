import numpy as np
import pytest
from hypothesis import settings

# Property tests draw the same examples on every run: CI must not pass or fail by luck. Run with
# HYPOTHESIS_PROFILE=explore to search new examples.
settings.register_profile("deterministic", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile(__import__("os").environ.get("HYPOTHESIS_PROFILE", "deterministic"))

from graybox import Record


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def steps_input(n: int, rng, lo: float = 750.0, hi: float = 1650.0, hold: int = 60) -> np.ndarray:
    """A piecewise-constant input in rpm, changing every ``hold`` samples."""
    levels = rng.uniform(lo, hi, size=n // hold + 1)
    return np.repeat(levels, hold)[:n]


@pytest.fixture
def paper_record(rng):
    """A record simulated from the paper's ELS model (15) under step inputs."""
    from graybox import reference

    m = reference.paper_model(15)
    u = steps_input(1200, rng)
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    y = m.simulate(u, y0)
    return Record(u, y, Ts=0.05, name="sim15")


def assert_csv_pair_matches(dyn, sta, committed, ncols: tuple[int, int]) -> None:
    """Regenerated bundled CSVs equal the committed ones: same header and rows, every column but the
    last (pressure) exactly, the pressure to one unit of its 4th decimal (a last-ulp difference on
    another platform can flip the printed rounding by that unit, never more)."""
    for new, old, n in ((dyn, committed / "dynamic.csv", ncols[0]), (sta, committed / "static.csv", ncols[1])):
        new_lines = new.read_text().splitlines()
        old_lines = old.read_text().splitlines()
        assert new_lines[0] == old_lines[0]
        assert len(new_lines) == len(old_lines)
        a = np.loadtxt(new_lines[1:], delimiter=",")
        b = np.loadtxt(old_lines[1:], delimiter=",")
        assert a.shape == b.shape and a.shape[1] == n
        np.testing.assert_array_equal(a[:, :-1], b[:, :-1])
        np.testing.assert_allclose(a[:, -1], b[:, -1], rtol=0, atol=1.01e-4)


def edited_json(value, **fields) -> str:
    """``value`` saved as JSON with the given fields of its object replaced: a hand-edited file."""
    import json

    from graybox import to_json

    doc = json.loads(to_json(value))
    doc["object"].update(fields)
    return json.dumps(doc)
