"""review48g: check_count, frozen values, ParetoSet's fitting records, SEMP's budget warning."""

import numpy as np
import pytest

import graybox as gb
from graybox.core._validation import check_count


# 1. check_count: a count too large for a float (> 1.8e308) ended in a bare OverflowError naming nothing

@pytest.mark.parametrize("make, name", [
    (lambda: gb.GAOptions(population=10**400), "population"),
    (lambda: gb.design_input("prbs", 10**400, low=0.0, high=1.0, hold=2), "n_samples"),
    (lambda: check_count(10**400, "c"), "c"),
    (lambda: check_count(10**300, "c", item_bytes=10**300), "c"),
])
def test_a_count_beyond_any_float_is_refused_by_name(make, name):
    with pytest.raises(ValueError, match=f"{name}=10+ is too large"):
        make()


def test_check_count_still_takes_what_fits():
    assert check_count(10**6, "population") == 10**6
    assert check_count(10**8, "n_samples", item_bytes=8) == 10**8


# 2. select_graybox reads SEMP's path, not the structure its criterion chose: semp's warning that this choice came
# after the pruning budget ran out escaped to the caller (an error under filterwarnings=error) about a choice
# select_graybox never makes

def test_select_graybox_does_not_pass_on_semps_warning_about_its_own_choice(monkeypatch):
    import warnings

    import graybox.selection._simulation_error_pruning as sp
    from graybox.experiments import select_graybox

    monkeypatch.setattr(sp, "_prune_budget", lambda limit: 1)  # the budget spent at the first addition
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(0.5, 2.0, 80), 5)
    m = gb.Model(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], [0.2, 0.6, 0.3, 0.05])
    y = m.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size)
    n = u.size // 2
    ds = gb.Dataset(gb.Record(u[:n], y[:n], name="ident"), gb.Record(u[n:], y[n:], name="valid"))
    cands = gb.Structure(["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "u(k-1)y(k-1)", "y(k-1)^2"])
    with pytest.warns(RuntimeWarning, match="pruning stopped"):  # semp itself still says it
        gb.semp(cands, ds.ident, criterion="bic", max_terms=8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sel = select_graybox(cands, ds, estimator="ls", sources=("semp",))
    assert len(sel.table) >= 1


# 3. frozen_value: a DataFrame or Series a FrozenMap holds is handed out fresh at each read, but one inside a list
# or tuple of the map (Dataset.extra = {"tables": [df]}) was handed out as the stored copy: a reader's change stuck

Point = __import__("collections").namedtuple("Point", "table level")


def test_a_table_inside_a_list_or_tuple_of_dataset_extra_is_handed_out_fresh():
    import pandas as pd

    r = gb.Record(np.arange(20.0), 2 * np.arange(20.0), name="a")
    df, s = pd.DataFrame({"x": [1.0, 2.0]}), pd.Series([1.0, 2.0])
    ds = gb.Dataset(r, r, extra={"list": [df, s], "tuple": (df, 1), "named": Point(df, 2.0),
                                 "deep": [[df]], "plain": [1.0, 2.0], "arr": np.arange(3.0)})
    got = [ds.extra["list"][0], ds.extra["tuple"][0], ds.extra["named"].table, ds.extra["deep"][0][0]]
    for t in got:  # a reader changes the table it was given (held by a name: no chained assignment)
        t.loc[0, "x"] = 99.0
    series = ds.extra["list"][1]
    series.iloc[0] = 99.0
    for t in (ds.extra["list"][0], ds.extra["tuple"][0], ds.extra["named"].table, ds.extra["deep"][0][0]):
        assert t["x"].tolist() == [1.0, 2.0]
    assert ds.extra["list"][1].tolist() == [1.0, 2.0]
    assert type(ds.extra["named"]) is Point and isinstance(ds.extra["list"], list)
    # what holds no table is the one frozen value, as before
    assert ds.extra["plain"] is ds.extra["plain"] and ds.extra["arr"] is ds.extra["arr"]
    assert not ds.extra["arr"].flags.writeable
    import pickle

    back = pickle.loads(pickle.dumps(ds))
    t = back.extra["list"][0]
    t.loc[0, "x"] = 99.0
    assert back.extra["list"][0]["x"].tolist() == [1.0, 2.0]


# 4. _memory_bytes: os.sysconf answers -1 for a value it does not know; the physical memory then counted as -4096
# bytes and the swap alone (1 MB here) became the machine's memory, refusing a population of 10**6

def test_an_unknown_physical_memory_is_not_counted_as_negative(monkeypatch):
    import io

    import graybox.core._validation as v

    real = v.os.sysconf
    monkeypatch.setattr(v.os, "sysconf", lambda name: -1 if name == "SC_PHYS_PAGES" else real(name))
    monkeypatch.setattr(v, "open", lambda *a, **k: io.StringIO("MemTotal: 1 kB\nSwapTotal: 1024 kB\n"), raising=False)
    assert v._memory_bytes() >= 2**40  # not known: no limit any real count meets
    assert check_count(10**6, "GAOptions: population") == 10**6


# 5. semp's budget warning named its budget "6·max_terms + 10" and advised "a smaller max_terms" for a search by
# n_terms too, which takes no max_terms (passing one with n_terms is an error): its limit there is 2·n_terms + 4

def test_semps_budget_warning_speaks_of_the_limit_the_search_had(monkeypatch):
    import warnings

    import graybox.selection._simulation_error_pruning as sp

    monkeypatch.setattr(sp, "_prune_budget", lambda limit: 1)
    rng = np.random.default_rng(3)
    u = np.repeat(rng.uniform(0.5, 2.0, 40), 5)
    m = gb.Model(["1", "y(k-1)", "u(k-1)", "u(k-1)^2"], [0.2, 0.6, 0.3, 0.05])
    rec = gb.Record(u, m.simulate(u, np.zeros(1)) + 0.01 * rng.standard_normal(u.size), name="ident")
    cands = ["1", "y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)", "u(k-1)^2", "u(k-1)y(k-1)", "y(k-1)^2"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gb.semp(cands, rec, n_terms=3)
    said = [str(w.message) for w in caught if "pruning stopped" in str(w.message)]
    assert said and "max_terms" not in said[0] and "size limit 8" in said[0]  # min(8 candidates, 2·3 + 4)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gb.semp(cands, rec, criterion="bic", max_terms=5)
    said = [str(w.message) for w in caught if "pruning stopped" in str(w.message)]
    assert said and "size limit 5 " in said[0] and "a smaller max_terms" in said[0]
