"""Review of session 46 (d): the SE problem's free runs on the centred signals (b0deb6a) and what came with it."""

from __future__ import annotations

import itertools
import json
import tracemalloc

import numpy as np
import pytest

import graybox as gb
from graybox.estimation._simulation_error import SEProblem


def _closed_problem_data(N: int = 60000):
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1.0, 1.0, N // 50), 50) + 5.0
    e = 0.01 * rng.standard_normal(N)
    y = np.zeros(N)
    for k in range(2, N):
        y[k] = 0.5 * y[k - 1] + 0.2 * y[k - 2] + 0.3 * u[k - 1] + 0.05 * (u[k - 2] - 5.0) ** 2 + e[k]
    lin = ["y(k-1)", "y(k-2)", "y(k-3)", "u(k-1)", "u(k-2)"]
    quad = [f"{a}{b}" if a != b else f"{a}^2" for a, b in itertools.combinations_with_replacement(lin, 2)]
    return gb.parse_structure(["1"] + lin + quad[:14]), gb.Record(u, y + 100.0, Ts=1.0)


def test_a_centred_se_problem_holds_the_raw_input_products_only_when_asked():
    # the centred free runs (b0deb6a) made their own input products beside the raw ones, which only residuals()
    # (se_dsf, se_uncertainty) reads: a second N × n array held through every sweep (+31 MB at N = 200000, n = 20)
    st, rec = _closed_problem_data()
    P = SEProblem(st, [rec], gb.StaticPoints([4.5, 5.0, 5.5], [101.0, 102.0, 103.0]))
    assert P.run_scale is not None  # the centred case
    one = P.run_U[0].nbytes
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        raw = P.U
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown >= 0.9 * one  # made now, not held since the problem was built
    assert raw[0].shape == P.run_U[0].shape
    # and the raw residuals read them as before: the same errors as the centred runs
    th = P.ls_theta()
    e = P.residuals(th, jacobian=False)[0]
    np.testing.assert_allclose(np.mean(e ** 2), P.js(th[None])[0], rtol=1e-9)


def _fingerprint_before_4567ec5(problem: SEProblem) -> str:
    """SEProblem.fingerprint as graybox wrote it before 4567ec5 (no margin, no ridge): the structure and the arrays."""
    import hashlib

    h = hashlib.sha256()
    h.update(str(problem.structure).encode())
    for a in [x for r in problem.records for x in (r.u, r.y)] + [problem.static.ubar, problem.static.ybar]:
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def test_a_checkpoint_of_named_inputs_written_before_the_names_were_recorded(tmp_path):
    # 4567ec5 hashed the inputs' names (other than u1 … um) into the problem's fingerprint: a checkpoint of such
    # records written before was refused as 'written for another problem (differs in: problem)', also by another
    # graybox version, whose checkpoints the docstring says are started over with a warning
    miso = gb.load_pumping_miso()
    names = ("speed", "valve")
    ren = lambda r: gb.Record(r.u, r.y, Ts=r.Ts, input_names=names, units=r.units, name=r.name)
    s = miso.static
    data = gb.Dataset(ren(miso.ident), ren(miso.valid),
                      gb.StaticPoints(s.ubar, s.ybar, uncertainty=s.uncertainty, input_names=names, units=s.units))
    st = ["1", "y(k-1)", "y(k-2)", "speed(k-2)", "valve(k-2)", "speed(k-2)^2", "speed(k-2)valve(k-2)", "valve(k-2)^2",
          "speed(k-2)y(k-1)"]
    kw = dict(lambdas=[1.0, 0.1], method="ga", margin=None, options=gb.GAOptions(population=10, generations=2),
              theta0=None)
    ck = tmp_path / "front.npz"
    fresh = gb.se_pareto(st, data, checkpoint=ck, **kw)
    with np.load(ck, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["meta"]))
    meta["problem"] = _fingerprint_before_4567ec5(SEProblem(st, [data.ident], data.static))
    meta.pop("inputs", None)
    np.savez(ck, **{**arrays, "meta": json.dumps(meta)})
    # by this version: its fingerprint, without the arrays' shapes, is an older algorithm's (641f5053), so the file is
    # one of another version, started over with a warning, never resumed with its inputs unknown
    with pytest.warns(UserWarning, match="left out its arrays' shapes.*starts over"):
        same = gb.se_pareto(st, data, checkpoint=ck, **kw)
    np.testing.assert_array_equal(same.thetas, fresh.thetas)
    np.savez(ck, **{**arrays, "meta": json.dumps(meta)})
    # by another version: started over with a warning, as any checkpoint of another version
    np.savez(ck, **{**arrays, "meta": json.dumps({**meta, "graybox": "0.2.7"})})
    with pytest.warns(UserWarning, match="starts over"):
        again = gb.se_pareto(st, data, checkpoint=ck, **kw)
    np.testing.assert_array_equal(again.thetas, fresh.thetas)


def test_the_ga_does_not_stop_for_a_stall_when_its_first_finite_cost_is_an_improvement():
    # GAOptions(stall=k) stops 'when the best cost has not improved by a relative 1e-9 for k generations'; a run whose
    # initial population had no finite cost stopped at generation k whatever it found since: inf − c ≤ 1e-9 · inf
    from graybox.estimation._simulation_error import _ga_run

    class Improving:  # no finite cost at first, then a better best at every generation
        z_map = None
        calls = 0

        def cost(self, pop, lam1, threads=1):
            self.calls += 1
            return np.full(len(pop), np.inf if self.calls == 1 else 10.0 / self.calls)

    init = np.random.default_rng(0).standard_normal((10, 3))
    _, c, g = _ga_run(Improving(), 1.0, init, gb.GAOptions(population=10, generations=8, stall=2),
                      np.random.default_rng(1), 1)
    assert g == 8 and np.isfinite(c)


def test_an_input_held_to_round_off_over_the_records_is_left_at_its_level_as_one_held_exactly():
    # was: held judged bit for bit here, by the rank rule in the centring: 7.3 in one record and 73 * 0.1 in another
    # (a converted unit) was centred, its centred terms round-off of zero scaling z by nothing the units set. A held
    # input is now centred by its static points (SEProblem._held_offset) while y is centred, the same for both
    st = gb.Structure(["1", "y(k-1)", "u(k-1)"])
    rng = np.random.default_rng(0)
    recs = [gb.Record(np.full(60, level), 5.0 + rng.standard_normal(60), name=f"r{i}")
            for i, level in enumerate((7.3, 73 * 0.1))]
    assert recs[0].u[0] != recs[1].u[0]
    sp = gb.StaticPoints([6.0, 7.3, 8.0], [1.0, 2.0, 3.0])
    exact = SEProblem(st, [recs[0], gb.Record(recs[0].u, recs[1].y, name="r1")], sp)
    rounded = SEProblem(st, recs, sp)
    for p in (exact, rounded):  # 7.3 less the RMS distance of the points' levels from it: 7.3 on the records
        assert p.offsets["u"] == pytest.approx(7.3 - np.sqrt(np.mean((np.array([6.0, 7.3, 8.0]) - 7.3) ** 2)))
    np.testing.assert_allclose(rounded.z_map, exact.z_map, rtol=1e-12)
