"""Mend 32: options a call cannot use are refused, not ignored (select_graybox's folds and blocks);
defaults that follow the data (frols' and semp's max_terms on short records); a band message that
says what it accepts; value objects that compare and hash; from_repeats' uncertainty per measurement."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import graybox as gb

CAND = gb.Candidates(ny=1, nu=1, degree=2)


def first_order(n, seed, noise=0.01):
    """y = 0.6 y + 0.3 u + 0.05 u² + 0.1 under a staircase of random levels held 10 samples."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 2.0, n // 10 + 1), 10)[:n]
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.6 * y[k - 1] + 0.3 * u[k - 1] + 0.05 * u[k - 1] ** 2 + 0.1
    return gb.Record(u, y + noise * rng.standard_normal(n), name=f"r{seed}")


def black_box(data, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.SelectionWarning)
        return gb.select_graybox(CAND, data, sizes=[2, 3], sources=("frols",), estimator="ls", **kw)


# -- 1. select_graybox: folds without folds, blocks without blocks ---------------------------------

@pytest.mark.parametrize("how", ["dataset", "validation="])
def test_folds_with_a_validation_record_is_refused_naming_it(how):
    # was: folds was silently ignored (the choice is on blocks of the validation record)
    ident, valid = first_order(200, 1), first_order(200, 2)
    data, kw = (gb.Dataset(ident, valid), {}) if how == "dataset" else (ident, {"validation": valid})
    with pytest.raises(ValueError, match="folds.*validation record"):
        black_box(data, folds=4, **kw)


def test_blocks_without_a_validation_record_is_refused_naming_it():
    # was: blocks was silently ignored (the choice is on folds of the one record)
    with pytest.raises(ValueError, match="blocks.*no validation record"):
        black_box(first_order(200, 1), blocks=4)


def test_the_defaults_are_the_values_they_were():
    """None means blocks=5 with a validation record and folds=3 without: the same tables."""
    ident, valid = first_order(200, 1), first_order(200, 2)
    cols = ["source", "n_terms", "estimator", "JS_valid", "vs_best", "vs_best_se", "rank"]
    a, b = black_box(gb.Dataset(ident, valid)), black_box(gb.Dataset(ident, valid), blocks=5)
    assert a.table[cols].equals(b.table[cols])
    assert not a.table[cols].equals(black_box(gb.Dataset(ident, valid), blocks=2).table[cols])
    a, b = black_box(ident), black_box(ident, folds=3)
    assert a.table[cols].equals(b.table[cols])
    assert not a.table[cols].equals(black_box(ident, folds=2).table[cols])


# -- 2. frols and semp: the default max_terms follows the record ------------------------------------

WIDE = gb.Candidates(ny=2, nu=2, degree=3)  # 34 process candidates: more than a short record's rows


@pytest.mark.parametrize("select", [gb.frols, gb.semp], ids=["frols", "semp"])
def test_the_default_max_terms_is_what_a_short_record_carries(select):
    # was: frols asked to "lower max_terms" and semp found "20 samples … too few for 30 terms",
    # though nobody passed max_terms
    rec = first_order(22, 3)
    rows = len(rec) - WIDE.process.max_lag
    assert rows < len(WIDE.process) and rows < 30
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing said: nobody asked for more than the rows carry
        warnings.simplefilter("ignore", gb.CandidateWarning)  # a short staircase repeats some columns
        res = select(WIDE, rec, criterion="bic")
    assert 1 <= len(res.structure) < rows


@pytest.mark.parametrize("select", [gb.frols, gb.semp], ids=["frols", "semp"])
def test_an_explicit_max_terms_the_rows_cannot_carry_is_an_error_naming_it(select):
    rec = first_order(22, 3)
    rows = len(rec) - WIDE.process.max_lag
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gb.CandidateWarning)
        with pytest.raises(ValueError, match="max_terms"):
            select(WIDE, rec, criterion="bic", max_terms=rows)
        assert len(select(WIDE, rec, criterion="bic", max_terms=rows - 1).structure) < rows


@pytest.mark.parametrize("select", [gb.frols, gb.semp], ids=["frols", "semp"])
def test_a_long_record_keeps_the_default_max_terms(select):
    """The cap only binds on short records: on a long one the default is what it was (frols 50, semp 30)."""
    rec = first_order(400, 4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = select(WIDE, rec, criterion="bic")
        b = select(WIDE, rec, criterion="bic", max_terms=min(len(WIDE.process), 50 if select is gb.frols else 30))
    assert a.structure == b.structure


# -- 3. select_graybox: the band message says what is accepted ---------------------------------------

@pytest.mark.parametrize("band", [np.nan, -np.inf, 0.0, -1.0])
def test_a_bad_band_is_refused_saying_that_inf_is_accepted(band):
    # was: "band must be a finite number" for nan, though band=inf is accepted (the black box)
    sp = gb.StaticPoints([0.5, 1.0, 1.5], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match=r"band must be a number B > 0 .*or inf .*black box"):
        black_box(first_order(200, 1), static=sp, band=band)


# -- 4. value objects compare and hash: the package's one agreement ----------------------------------

def _values():
    """One instance of each value type whose == raised (arrays inside) or whose hash failed."""
    from graybox.datasets import PumpingPlant, TwoSpeedPumpingPlant

    rec = first_order(40, 1)
    sp = gb.StaticPoints([0.5, 1.0, 1.5], [1.0, 2.0, 3.0], uncertainty=0.1)
    points2 = gb.StaticPoints(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]), [0.0, 1.0, 2.0, 3.0])
    return {
        "StaticCurve": gb.StaticCurve.polynomial([1, 2, 3]),
        "StaticSurface": gb.StaticSurface.fit(points2, 1),
        "StaticPoints": sp,
        "Record": rec,
        "Dataset": gb.Dataset(rec, first_order(40, 2), sp),
        "ClusterMap": gb.cluster_map(gb.Structure(["y(k-1)", "u(k-1)", "1"])),
        "SurfaceClusterMap": gb.surface_cluster_map(gb.Structure(["y(k-1)", "u1(k-1)", "u2(k-1)"])),
        "PlantRun": PumpingPlant().simulate(np.full(5, 1000.0), noise=False, process_noise=False),
        "TwoSpeedRun": TwoSpeedPumpingPlant().simulate(np.full((5, 2), 1000.0), noise=False, process_noise=False),
    }


@pytest.mark.parametrize("name", list(_values()))
def test_a_value_object_equals_itself_hashes_and_compares_without_raising(name):
    # was: two equal StaticCurves (any of these) raised "truth value … ambiguous" on ==, and hash raised
    import copy

    x = _values()[name]
    assert (x == x) is True and hash(x) == hash(x)
    y = copy.copy(x)
    assert (x == y) is False and (x != y) is True  # identity equality, as Model and the results have
    assert len({x, y, x}) == 2


#: Frozen dataclasses that keep value equality (hashable fields only, and equality relied on: Term and
#: Structure key the static analysis' lru_caches). Every other frozen dataclass of graybox is eq=False.
VALUE_EQUALITY = {"Term", "Structure", "StopRule", "_Form", "GAOptions", "Equilibrium", "PumpingPlant",
                  "TwoSpeedPumpingPlant", "PlantSurface", "DecimationAdvice"}


def _frozen_dataclasses():
    import dataclasses
    import importlib
    import inspect
    import pkgutil

    seen = {}
    for info in pkgutil.walk_packages(gb.__path__, "graybox."):
        if info.name.endswith(("__main__", "_cli")):
            continue
        for obj in vars(importlib.import_module(info.name)).values():
            if (inspect.isclass(obj) and obj.__module__.startswith("graybox") and dataclasses.is_dataclass(obj)
                    and obj.__dataclass_params__.frozen):
                seen[f"{obj.__module__}.{obj.__qualname__}"] = obj
    return seen


def test_every_frozen_dataclass_has_identity_equality_unless_its_value_equality_works():
    kept = sorted(k for k, c in _frozen_dataclasses().items() if c.__dataclass_params__.eq)
    assert sorted(k.rsplit(".", 1)[1] for k in kept) == sorted(VALUE_EQUALITY), kept


def test_the_value_equality_kept_works():
    """Equal values compare equal and hash alike (copies), different ones differ."""
    import copy

    from graybox.datasets import PumpingPlant, TwoSpeedPumpingPlant
    from graybox.datasets._pumping_miso import PlantSurface
    from graybox.experiments._select import _Form
    from graybox.selection._stopping import stop_rule

    pairs = {
        "Term": (gb.Structure(["u(k-1)^2"])[0], gb.Structure(["u(k-2)"])[0]),
        "Structure": (gb.Structure(["y(k-1)", "1"]), gb.Structure(["y(k-1)"])),
        "StopRule": (stop_rule(None, None, "bic", curve_default="aic"), stop_rule(3, None, None, curve_default="aic")),
        "_Form": (_Form(2, ("u",)), _Form(1, ("u",))),
        "GAOptions": (gb.GAOptions(population=30), gb.GAOptions(population=40)),
        "Equilibrium": (gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).equilibria(1.0)[0],
                        gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0]).equilibria(2.0)[0]),
        "PumpingPlant": (PumpingPlant(), PumpingPlant(noise_std=0.5)),
        "TwoSpeedPumpingPlant": (TwoSpeedPumpingPlant(), TwoSpeedPumpingPlant(PumpingPlant(noise_std=0.5))),
        "PlantSurface": (PlantSurface(TwoSpeedPumpingPlant(), ((800.0, 1600.0), (800.0, 1600.0)), "s"),
                         PlantSurface(TwoSpeedPumpingPlant(), ((800.0, 1600.0), (800.0, 1500.0)), "s")),
        "DecimationAdvice": (gb.decimation_advice(gb.Record(np.zeros(4000), np.sin(np.arange(4000) / 30))),
                             gb.decimation_advice(gb.Record(np.zeros(4000), np.sin(np.arange(4000) / 60)))),
    }
    assert set(pairs) == VALUE_EQUALITY
    for name, (a, b) in pairs.items():
        c = copy.deepcopy(a)
        assert c is not a and c == a and hash(c) == hash(a), name
        assert a != b, name


# -- 5. from_repeats: one δ per measurement, combined per level as the mean is -----------------------

def test_a_per_level_uncertainty_is_refused_its_order_being_ambiguous():
    # was: [0.1, 0.5] was paired with the levels sorted (1000 -> 0.1), not as written (3000 -> 0.1)
    with pytest.raises(ValueError, match=r"uncertainty.*one δ per measurement \(4, as ybar\).*with_uncertainty"):
        gb.StaticPoints.from_repeats([3000, 3000, 1000, 1000], [1.0, 1.2, 3.0, 3.4], uncertainty=[0.1, 0.5])


def test_one_uncertainty_per_measurement_is_paired_as_written_and_averaged_per_level():
    sp = gb.StaticPoints.from_repeats([3000, 3000, 1000, 1000], [1.0, 1.2, 3.0, 3.4],
                                      uncertainty=[0.1, 0.1, 0.5, 0.3])
    assert sp.ubar.tolist() == [1000, 3000]
    assert sp.ybar == pytest.approx([3.2, 1.1]) and sp.uncertainty == pytest.approx([0.4, 0.1])
    # no repeats: the δ stay with their measurements, whatever the order of the levels
    sp = gb.StaticPoints.from_repeats([3000, 1000], [1.0, 3.0], uncertainty=[0.1, 0.5])
    assert sp.uncertainty.tolist() == [0.5, 0.1]
    assert gb.StaticPoints.from_repeats([3000, 1000, 1000], [1.0, 3.0, 3.2], uncertainty=0.2).uncertainty.tolist() == [0.2, 0.2]


def test_a_measurement_without_uncertainty_is_refused_though_its_level_mean_is_positive():
    with pytest.raises(ValueError, match=r"uncertainty must be > 0"):
        gb.StaticPoints.from_repeats([1000, 1000], [3.0, 3.2], uncertainty=[0.0, 0.4])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([1.0, 2.0, 3.0]), st.floats(-5, 5), st.floats(0.01, 1.0)),
                min_size=1, max_size=8), st.randoms(use_true_random=False))
def test_the_points_do_not_depend_on_the_order_the_measurements_are_listed(rows, rnd):
    """(ū, ȳ, δ) of each measurement travel together: any order gives the same points."""
    shuffled = list(rows)
    rnd.shuffle(shuffled)
    a, b = (gb.StaticPoints.from_repeats([u for u, _, _ in r], [y for _, y, _ in r], uncertainty=[d for _, _, d in r])
            for r in (rows, shuffled))
    assert a.ubar.tolist() == b.ubar.tolist()
    np.testing.assert_allclose(a.ybar, b.ybar, atol=1e-12)
    np.testing.assert_allclose(a.uncertainty, b.uncertainty, rtol=1e-12)
    levels = {u for u, _, _ in rows}
    assert len(a) == len(levels)
    for u, d in zip(a.ubar, a.uncertainty):
        assert d == pytest.approx(np.mean([dd for uu, _, dd in rows if uu == u]))
