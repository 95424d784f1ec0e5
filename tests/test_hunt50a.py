"""hunt50a: a newcomer's first hour (README, docs, notebooks) and one's own CSV files."""

from __future__ import annotations

import codecs

import numpy as np
import pytest

import graybox as gb

TEXT = "t;u;y\n0;1,5;2\n0,5;2;3\n1;2;4\n"


@pytest.mark.parametrize("bom, codec, wrong", [
    (codecs.BOM_UTF16_LE, "utf-16-le", "utf-16-be"),
    (codecs.BOM_UTF16_BE, "utf-16-be", "utf-16-le"),
    (codecs.BOM_UTF32_LE, "utf-32-le", "utf-32-be"),
    (codecs.BOM_UTF32_BE, "utf-32-be", "utf-32-le"),
])
def test_encoding_of_the_other_byte_order_than_the_mark_is_refused(tmp_path, bom, codec, wrong):
    # the docstring: "an encoding that contradicts the file's byte-order mark is an error"; a UTF-16 file with a
    # little-endian mark read as encoding='utf-16-be' was decoded as mojibake ("no column 'u' … ['\ufffe琀㬀…']")
    path = tmp_path / "run.csv"
    path.write_bytes(bom + TEXT.encode(codec))
    with pytest.raises(ValueError, match="byte-order mark") as err:
        gb.load_record_csv(path, u="u", y="y", time="t", encoding=wrong)
    assert ("little-endian" if codec.endswith("le") else "big-endian") in str(err.value)
    # the encoding the mark says, with or without its byte order, reads the file
    for enc in (codec, codec.rsplit("-", 1)[0], None):
        rec = gb.load_record_csv(path, u="u", y="y", time="t", encoding=enc)
        np.testing.assert_array_equal(rec.u, [1.5, 2.0, 2.0])


def test_notebook_06_states_the_input_lags_its_candidates_have():
    # notebook 06 said "Candidates with both inputs (lags 2–3 each, delay=2 …)" above
    # Candidates(ny=2, nu={"u1": 2, "u2": 2}, delay=2, …), whose input lags run from the delay to nu: lag 2 only
    import json
    import re
    from pathlib import Path

    cells = json.loads((Path(__file__).parents[1] / "notebooks" / "06_miso.ipynb").read_text("utf-8"))["cells"]
    i = next(i for i, c in enumerate(cells) if c["cell_type"] == "markdown"
             and "Candidates with both inputs" in "".join(c["source"]))
    text = "".join(cells[i]["source"])
    code = next(c for c in cells[i + 1:] if c["cell_type"] == "code")
    call = next(line for line in code["source"] if line.startswith("candidates = gb.Candidates("))
    space = {}
    exec(call, {"gb": gb}, space)
    lags = sorted({lag for t in space["candidates"].process for name, lag in
                   re.findall(r"(u\d)\(k-(\d+)\)", str(t))})
    said = re.search(r"\(lags? (\d)(?:–(\d))? each", text)
    assert said is not None, text
    claimed = [str(k) for k in range(int(said.group(1)), int(said.group(2) or said.group(1)) + 1)]
    assert claimed == lags, (text, lags)


def test_notebook_05_quotes_the_full_grid_of_the_17_term_structure(tmp_path):
    # "What the grid says" quotes the full grids (QUICK = False); it said the 17-term structure's qualifying models
    # sit at J_S valid 1.31–1.70 and SE's own D_SF member at 1.82 with J_SF 0.0009, where the full grid gives
    # 1.31–1.38 and SE's member 1.38 with J_SF 0.0056 (numbers from before the SE fits' stability margin)
    import json
    import re
    from pathlib import Path

    from graybox import experiments as gx

    cells = json.loads((Path(__file__).parents[1] / "notebooks" / "05_constraint_variants.ipynb").read_text("utf-8"))
    text = " ".join("".join(c["source"]) for c in cells["cells"] if c["cell_type"] == "markdown")
    text = re.sub(r"\s+", " ", text)
    said = re.search(r"17-term structure is the worst place to start: its (?:best )?qualifying models sit at J_S "
                     r"valid ([\d.]+)–([\d.]+) mlc².{0,40}SE's own D_SF (?:member on it: |picked on it \(J_S valid )"
                     r"([\d.]+).{0,40}(?:with J_SF|static error of) ([\d.]+)", text)
    assert said is not None, "the notebook's sentence on the 17-term structure changed: update this test"
    lo, hi, se_js, se_jsf = (float(g.rstrip(".")) for g in said.groups())
    # the notebook's full grid for that structure (n_pe, n_band, n_se = 30, 10, 10), the variants that qualify
    grid = gx.Grid(
        name="pumping constraint variants",
        data=[gx.DataSpec("pumping", bundled="pumping")],
        structures=[gx.StructureSpec("FROLS 17 (lags 6)", candidates={"ny": 6, "nu": 6, "degree": 2, "max_y_power": 1},
                                     n_terms=17, include=["1"])],
        variants=[
            gx.Variant("CLS eq.(22)", "cls", constraints=[{"type": "equality", "curve": "fit"}],
                       options={"reference": "els"}),
            gx.Variant("PE", "pe", lambdas=np.logspace(-6, 0, 30), options={"solver": "closed"}),
            gx.Variant("PE band", "pe", lambdas=np.logspace(-4, 0, 10), constraints=gb.StaticBand(0.175)),
            gx.Variant("SE gradient", "se-gradient", lambdas=np.logspace(-2, 0, 10), options={"max_nfev": 30}),
        ],
    )
    store = tmp_path / "grid.sqlite"
    gx.run_grid(grid, store)
    results = gb.load_results(store)
    board = gx.leaderboard(results).dropna(subset=["rank"])
    assert (round(board.JS_valid.min(), 2), round(board.JS_valid.max(), 2)) == (lo, hi)
    se = results[results.variant == "SE gradient"].iloc[0]
    assert round(se.JS_valid, 2) == se_js
    assert float(f"{se.JSF:.1g}") == se_jsf


@pytest.mark.parametrize("n", [1, 2])
def test_a_record_shorter_than_the_lags_is_named_as_such_by_every_free_run(n):
    # gb.js(model, record) of a 1-sample record said "y0 has 1 samples, the structure needs max lag = 2", of an
    # argument the caller never passed, and of 2 samples "input has 2 samples", where gb.j1 says the record's name
    data = gb.load_pumping()
    model = gb.Model(gb.parse_structure(["1", "y(k-1)", "y(k-2)", "u(k-1)"]), [0.1, 0.5, 0.2, 1e-4])
    short = data.valid.slice(0, n, name="short run")
    calls = {"js": lambda: gb.js(model, short), "simulate": lambda: model.simulate(short),
             "evaluate": lambda: gb.evaluate({"m": model}, gb.Dataset(data.ident, short, data.static)),
             "plot_free_run": lambda: gb.plots.plot_free_run(short, {"m": model}),
             "j1": lambda: gb.j1(model, short)}
    for name, call in calls.items():
        with pytest.raises(ValueError) as err:
            call()
        assert "short run" in str(err.value) and f"has {n} samples" in str(err.value), (name, str(err.value))
        assert "y0" not in str(err.value), (name, str(err.value))


def _holds_and_steps(part):
    change = np.flatnonzero(np.diff(part) != 0) + 1
    holds = np.diff(np.r_[0, change, len(part)])[:-1]  # the last hold is cut by the part's end
    return holds, np.abs(np.diff(part[np.r_[0, change]]))


def test_speed_reference_docstring_says_what_the_forced_ends_do_to_holds_and_steps():
    # the docstring said "levels change every 4–9 s … by steps of three sizes (small 40–150 …)", but the two holds
    # forced to the range's ends can land on a neighbour's level (seed 41's identification part holds one level
    # 12.25 s) or step to it by 10–30 rpm (seed 12: 20 rpm; 68 of 600 parts over seeds 0–299)
    from graybox.datasets import speed_reference

    long_hold = small_step = False
    for seed in range(42):
        u = speed_reference(seed=seed)
        for part in (u[:3200], u[3200:]):
            holds, steps = _holds_and_steps(part)
            long_hold |= bool(holds.max() > 180)
            small_step |= bool(steps.min() < 40)
    assert long_hold and small_step
    doc = " ".join(speed_reference.__doc__.split())
    assert "as little as 10 rpm" in doc and "one longer hold" in doc, doc


def _heater(tmp_path, uncertainty=None):
    """The README's heater: two runs in 30–60 % and steady states over 0–100 % (no uncertainty unless given)."""
    rng = np.random.default_rng(1)
    f = lambda u: 150 * (1 - np.exp(-u / 50))  # noqa: E731
    recs = []
    for n in (1500, 600):
        u = np.repeat(rng.uniform(30, 60, n // 50 + 1), 50)[:n]
        y = np.full(n, 20 + f(u[0]))
        for k in range(2, n):
            y[k] = 1.2 * y[k - 1] - 0.3 * y[k - 2] + 0.1 * f(u[k - 1]) + 2.0
        recs.append(gb.Record(u, y + 0.2 * rng.standard_normal(n), Ts=0.5, units=("%", "°C")))
    levels = np.linspace(0, 100, 6)
    steady = gb.StaticPoints(levels, 20 + f(levels), units=("%", "°C"), uncertainty=uncertainty)
    return gb.Dataset(recs[0], recs[1], steady)


def test_select_graybox_without_a_band_does_not_say_the_static_points_shape_its_black_box(tmp_path):
    # steady states without an uncertainty and no band= make select_graybox a black box (LS, ELS, OE: the points
    # only score J_SF), yet its warning said "the model is extrapolated there by the static information"
    import warnings

    cand = gb.Candidates(2, 2, degree=2, max_y_power=1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sel = gb.select_graybox(cand, _heater(tmp_path), sizes=[4], estimator="ls")
    assert np.isinf(sel.band)
    said = [str(w.message) for w in caught if issubclass(w.category, gb.StaticRangeWarning)]
    assert len(said) == 1, said
    assert "extrapolated there by the static information" not in said[0], said[0]
    assert "black box" in said[0] and "band=" in said[0], said[0]
    # a gray box is extrapolated by them, and says so as before
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gb.select_graybox(cand, _heater(tmp_path, uncertainty=0.2), sizes=[4], estimator="pe", fallback="min_jsf")
    said = [str(w.message) for w in caught if issubclass(w.category, gb.StaticRangeWarning)]
    assert len(said) == 1 and "extrapolated there by the static information" in said[0], said
