"""review54a: regressions found reviewing 9bb79da … 48663a5."""

import numpy as np
import pytest

import graybox as gb


def _cannot_be_made_writeable(a, name):
    for target in (a, a.base):
        if isinstance(target, np.ndarray):
            with pytest.raises(ValueError, match="WRITEABLE"):
                target.flags.writeable = True
    assert not a.flags.writeable, name


def test_arrays_of_selections_curves_surfaces_cluster_maps_and_plant_runs_cannot_be_made_writeable_again():
    """4a5f8bb locked Records', Models' and StaticPoints' arrays, but a Selection's θ and ERR, a StaticCurve's or
    StaticSurface's coefficients, cluster_map's R (shared by every later call: lru_cache), a plant run's samples and
    PE_LAMBDAS / SE_LAMBDAS were still read-only arrays owning their memory: ``a.flags.writeable = True`` then an edit
    changed the frozen value (and, for R and the λ grids, every later caller's)."""
    rng = np.random.default_rng(0)
    u = rng.uniform(0.0, 1.0, 60)
    y = np.zeros(60)
    for k in range(1, 60):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.2 * u[k - 1] ** 2
    sel = gb.frols(gb.Candidates(ny=1, nu=1, degree=2), gb.Record(u, y), n_terms=3)
    curve = gb.StaticCurve([1.0, 2.0, 0.5])
    surface = gb.StaticSurface.fit(gb.StaticPoints(rng.uniform(0.0, 1.0, (8, 2)), rng.uniform(0.0, 1.0, 8),
                                                   input_names=["a", "b"]), degree=1)
    cmap = gb.cluster_map(gb.parse_structure(["y(k-1)", "u(k-1)", "u(k-1)^2", "1"]))
    run = gb.datasets.PumpingPlant().simulate(np.full(5, 1000.0), seed=0)
    arrays = {f"Selection.{n}": getattr(sel, n) for n in ("err", "theta", "err_evaluated", "rss", "criterion_curve",
                                                        "subset_rss")}
    arrays |= {"StaticCurve.coefficients": curve.coefficients, "StaticSurface.coefficients": surface.coefficients,
               "ClusterMap.R": cmap.R, "PlantRun.y": run.y, "PlantRun.t": run.t, "PE_LAMBDAS": gb.PE_LAMBDAS,
               "SE_LAMBDAS": gb.SE_LAMBDAS}
    # (hunt54c found the same, and these besides: the surfaces' cluster map, the two-input plant's run, a run's fields)
    two = gb.datasets.TwoSpeedPumpingPlant().simulate(np.full((5, 2), 1200.0), seed=0)
    arrays |= {"surface_cluster_map.R": gb.surface_cluster_map(gb.parse_structure(["y(k-1)", "a(k-1)", "b(k-1)"])).R}
    arrays |= {f"{type(r).__name__}.{n}": getattr(r, n) for r in (run, two) for n in ("u", "speed", "flow", "surge")}
    for name, a in arrays.items():
        _cannot_be_made_writeable(a, name)


@pytest.mark.parametrize("col", ["t [2h]", "t [1hr]", "t [0.5d]", "t [1 x 10^-3 s]", "t [s/1e3]", "t [1/1e3 s]",
                                 "t [10usec]"])
def test_a_time_column_in_ticks_of_any_named_unit_or_a_written_power_is_refused(tmp_path, col):
    """d24eecb: a tick's unit came from a shorter list than a bare unit's, so 't [2 h]' was refused but 't [2h]',
    't [1hr]', 't [0.5d]' were read as seconds (Ts = 1 s for 2 hours, without a word); an ASCII 'x' for the
    multiplication ('1 x 10^-3 s') and a fraction written as a power ('s/1e3') were not read either."""
    p = tmp_path / "r.csv"
    p.write_text(f"{col};u;y\n" + "".join(f"{k};{k % 3};{0.5 * k}\n" for k in range(8)), encoding="utf-8")
    with pytest.raises(ValueError, match="but time stamps are read as seconds"):
        gb.load_record_csv(p, u="u", y="y", time=col)


def _tiny_input_record():
    rng = np.random.default_rng(0)
    u = rng.uniform(0.5, 1.5, 60)
    y = np.zeros(60)
    for k in range(1, 60):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.3 * u[k - 1] ** 2
    return gb.Record(u * 1e-160, y + 0.01 * rng.standard_normal(60), name="tiny input")


def test_frols_refuses_a_parameter_beyond_the_float_range_naming_its_term_as_els_and_semp_do():
    """An input of about 1e-160 (u(k-1)^2 about 1e-320) beside an output of 1: ELS, semp, CLS and PE refuse the
    θ of about 1e320 with beyond_float_range (f53f10c, 7d9347f), naming the term, but frols chose the term and failed
    in its Selection on 'theta has non-finite values at [2]', naming an index and no remedy."""
    rec = _tiny_input_record()
    with pytest.raises(ValueError, match=r"frols: .*\['u\(k-1\)\^2'\] are beyond the float range .*rescale"):
        gb.frols(gb.Candidates(ny=1, nu=1, degree=2), rec, n_terms=3)
    with pytest.raises(ValueError, match=r"\['u\(k-1\)\^2'\] are beyond the float range"):
        gb.els(["y(k-1)", "u(k-1)", "u(k-1)^2"], rec)


def test_an_object_array_in_a_dataset_s_extra_cannot_be_edited_through_a_read():
    """locked() copies an object array read-only (its memory cannot be a bytes buffer), and a read-only array that owns
    its memory is made writeable by ``a.flags.writeable = True``: an edit of Dataset.extra['tags'] then changed the
    frozen value. A FrozenMap hands such an array out as a fresh read-only copy at each read, as it does a table."""
    rec = gb.Record(np.linspace(0.0, 1.0, 12), np.linspace(1.0, 2.0, 12), name="r")
    data = gb.Dataset(rec, rec, extra={"tags": np.array(["a", 1], dtype=object),
                                       "nested": [np.array([None, "b"], dtype=object)]})
    for read in (lambda: data.extra["tags"], lambda: data.extra["nested"][0]):
        a = read()
        assert not a.flags.writeable
        if not a.flags.owndata and a.base is not None:
            continue
        a.flags.writeable = True  # allowed on an array owning its memory: the edit must not reach the value
        first = a[0]
        a[0] = "changed"
        assert read()[0] == first


def test_values_pickled_or_deep_copied_keep_their_arrays_locked():
    """numpy pickles and deep-copies an array as a fresh writeable one, and a frozen value restores its fields as
    given: a Record or Model through pickle (a process pool, a Dask worker) or copy.deepcopy had writeable arrays,
    ``copy.deepcopy(model).theta[0] = 5`` an edit of a frozen value without even a flag."""
    import copy
    import pickle

    rec = gb.Record(np.linspace(0.0, 1.0, 12), np.linspace(1.0, 2.0, 12), name="r")
    data = gb.Dataset(rec, rec, static=gb.StaticPoints([1.0, 2.0], [3.0, 4.0], uncertainty=[0.1, 0.2]))
    model = gb.Model(["y(k-1)", "u(k-1)"], [0.5, 1.0])
    curve = gb.StaticCurve([1.0, 2.0, 0.5])
    for how in (lambda o: pickle.loads(pickle.dumps(o)), copy.deepcopy):
        d2, m2, c2 = how(data), how(model), how(curve)
        arrays = {"Record.y": d2.ident.y, "Record.u": d2.valid.u, "StaticPoints.ybar": d2.static.ybar,
                  "StaticPoints.uncertainty": d2.static.uncertainty, "Model.theta": m2.theta,
                  "StaticCurve.coefficients": c2.coefficients}
        for name, a in arrays.items():
            _cannot_be_made_writeable(a, name)
        assert np.array_equal(m2.theta, model.theta) and np.array_equal(d2.ident.y, rec.y)


def test_a_parameter_below_the_float_range_is_refused_not_set_to_zero():
    """7d9347f maps θ back from the power-of-two scaled fit with ldexp, which leaves 0 where θ falls below the float
    range: u(k-1)^2 of an input of about 1e153 (1e306) beside an output of about 1e-20 has a θ of about 3e-327, and
    ELS and frols gave θ = 0 for it without a word (the model's one-step error 38 % of the output's scale where the
    fit's was 1 %). Refused as a θ above the range is, naming the term."""
    rec = _tiny_input_record()
    rec = gb.Record(rec.u * 1e160 * 1e153, rec.y * 1e-20, name="huge input")  # u about 1e153
    st = ["y(k-1)", "u(k-1)", "u(k-1)^2"]
    with pytest.raises(ValueError, match=r"ELS: the parameter\(s\) of \['u\(k-1\)\^2'\] are beyond the float range"):
        gb.els(st, rec)
    with pytest.raises(ValueError, match=r"frols: the parameter\(s\) of \['u\(k-1\)\^2'\] are beyond the float range"):
        gb.frols(gb.parse_structure(st), rec, n_terms=3)
