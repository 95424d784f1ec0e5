"""The bridge to python-control: local models as LTI systems, the whole model as a discrete nonlinear system.

python-control is an optional extra (``pip install graybox[control]``), imported only here and only
when a function needs it. (``import control`` inside :mod:`graybox.control` is an absolute import:
it reaches python-control, not this package.)

The nonlinear system
--------------------
A NARX model y(k) = F(y(k−1) … y(k−L_y), u_i(k−1) … u_i(k−L_ui)) becomes a discrete
``NonlinearIOSystem`` whose state at sample k holds the lagged outputs and inputs

    x(k) = [y(k−1) … y(k−L_y), u_1(k−1) … u_1(k−L_u1), …, u_m(k−1) … u_m(k−L_um)],

whose output is y(k) = F(x(k)) (no direct feedthrough: every input lag is at least 1, so it can be
closed with any controller without an algebraic loop) and whose update shifts the lags in, y(k)
and u(k) at the front. Started from the state the record's first L = max lag samples give
(:func:`narx_initial_state`) and fed the inputs u(L), u(L+1), …, its outputs are the free run
y(L), y(L+1), … of :meth:`graybox.Model.simulate`.

A transient input z of input u (:func:`graybox.transient_inputs`, named ``u_tau30`` …) is no
system input: it is a function of u's changes, z(k) = ρ z(k−1) + (1 − ρ)(u(k) − u(k−1))²,
ρ = exp(−Ts/τ), so the update computes it from u(k) and the lags z(k−1), u(k−1) the state holds
(at least one lag of each), as :func:`graybox.transient_inputs` computes it for a record. A
controller that sets u then drives it, as the plant's own changes did in the records.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np

from ..core._records import Record, check_period, frame_inputs, require_record
from ..core._simulation import DivergenceError
from ..core._terms import Structure, require_inputs
from ..core._transient import refuse_transient_levels, steady_levels
from ..core._validation import check_bool, check_int, check_real, check_str
from ..models._model import Model
from ._local import check_Ts, check_polynomial, input_levels, require_control, system_name, transient_sources

__all__ = ["narx_iosystem", "narx_initial_state", "narx_state_names", "narx_steady_state"]

# -- the whole model ------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Layout:
    """Where each lag sits in the state, and the exponents of every term in the state variables."""

    Ly: int
    Lu: tuple[int, ...]
    E: np.ndarray        # (n_terms, n_states): term t = ∏_j x_j^E[t, j]
    y_rows: np.ndarray   # state indices of y(k-1) … y(k-Ly)
    u_rows: tuple[np.ndarray, ...]
    fed: tuple[int, ...]  # the inputs the system takes (model order): all but the transient ones
    transient: tuple[tuple[int, int, float], ...]  # (transient input j, its source input i, τ in s), computed


@lru_cache(maxsize=256)
def _layout(structure: Structure, inputs: tuple[str, ...]) -> _Layout:
    Ly = max((l for t in structure for s, l, _ in t.factors if s == "y"), default=0)
    transient = transient_sources(inputs)
    lags = [structure.input_lag(n) for n in inputs]
    # a transient input the structure uses is computed: z(k) needs u(k−1), which the state holds even where F does
    # not use it; one it does not use is neither fed nor held
    computed = tuple((j, i, tau) for j, (i, tau) in transient.items() if lags[j])
    for _, i, _ in computed:
        lags[i] = max(lags[i], 1)
    Lu = tuple(lags)
    start = {"y": 0}
    pos = Ly
    for name, L in zip(inputs, Lu):
        start[name] = pos
        pos += L
    E = np.zeros((len(structure), pos))
    for j, term in enumerate(structure):
        for s, l, p in term.factors:
            E[j, start[s] + l - 1] += p
    E.setflags(write=False)
    u_rows = tuple(np.arange(start[n], start[n] + L) for n, L in zip(inputs, Lu))
    fed = tuple(j for j in range(len(inputs)) if j not in transient)
    return _Layout(Ly, Lu, E, np.arange(Ly), u_rows, fed, computed)


#: The name of the noise input e(k) of :func:`narx_iosystem` with ``noise=True``, and of its lags in the state.
NOISE_INPUT = "noise"


def _noise_coefficients(model: Model) -> np.ndarray:
    """c_l of the linear MA part Σ c_l e(k−l), shape (n_e,); ``ValueError`` for any other noise term."""
    ne = model.noise_structure.max_lag
    c = np.zeros(ne)
    for cj, t in zip(model.noise_theta, model.noise_structure):
        if not (len(t.factors) == 1 and t.factors[0][2] == 1):
            raise ValueError(f"noise=True takes a linear MA part (terms e(k-l)); the model has the noise term {t}")
        c[t.factors[0][1] - 1] += cj
    return c


def narx_state_names(model: Model, *, noise: bool = False) -> list[str]:
    """The state names of :func:`narx_iosystem`'s system: ``y[k-1]`` … then each input's ``u[k-1]`` …

    (An input with a transient input the model uses has at least its lag ``u[k-1]``: the update computes the
    transient input from it.)

    Parameters
    ----------
    model : Model
        A polynomial NARX model.
    noise : bool
        As for :func:`narx_iosystem`: the noise lags ``noise[k-1]`` … come last.

    Returns
    -------
    list of str
        One name per state, in the state vector's order.
    """
    model = check_polynomial(model, "narx_state_names")
    noise = check_bool(noise, "noise")
    lay = _layout(model.structure, model.input_names)
    names = [f"y[k-{l}]" for l in range(1, lay.Ly + 1)]
    for n, L in zip(model.input_names, lay.Lu):
        names += [f"{n}[k-{l}]" for l in range(1, L + 1)]
    if noise:
        names += [f"{NOISE_INPUT}[k-{l}]" for l in range(1, _noise_coefficients(model).size + 1)]
    return names


def narx_initial_state(model: Model, record: Record, *, start: int | None = None, noise: bool = False,
                       Ts: float | None = None) -> np.ndarray:
    """The state of :func:`narx_iosystem`'s system at sample ``start`` of a record: its lagged outputs and inputs.

    Parameters
    ----------
    model : Model
        A polynomial NARX model.
    record : Record
        Measured data with the model's inputs (taken by name; its transient inputs too, as
        :func:`graybox.transient_inputs` gives them, as for :meth:`graybox.Model.simulate`), sampled at
        the system's period ``Ts`` (a record at another one is refused, as :meth:`graybox.Model.simulate`
        refuses one at another than the model's).
    start : int, optional
        The sample the system starts at (at least the model's max lag L: the state holds
        y(start−1) … and u(start−1) …; default L, and with ``noise`` the first sample of the
        one-step residuals, the largest lag of the process and noise terms). From ``start = L`` and
        inputs ``u[L:]`` the system's free run is ``model.simulate(record)[L:]``.
    noise : bool
        As for :func:`narx_iosystem`: the noise lags e(start−1) … are then appended, the model's
        one-step residuals on the record (:func:`graybox.one_step_residuals`; 0 before their first
        sample, as there), so that the system fed the residuals from ``start`` on reproduces
        ``record.y[start:]`` (from any start at or after the residuals' first sample).
    Ts : float, optional
        The period (s) :func:`narx_iosystem`'s system runs at, as given to it: default the model's own
        (``model.Ts``); another than the model's refused but over its 1 s, the period of records made without
        ``Ts=`` (a model fitted on such records, run at the real period, starts from a record at that period).

    Returns
    -------
    ndarray, shape (n_states,)
        In the order of :func:`narx_state_names`.
    """
    model = check_polynomial(model, "narx_initial_state")
    noise = check_bool(noise, "noise")
    require_record(record)  # a Dataset: told to pass data.ident or data.valid
    if Ts is not None:  # the system's period, as narx_iosystem takes it: the record's lags are its samples
        Ts = check_Ts(Ts, None, model, takes_data=False)
        check_period(Ts, f"Ts = {Ts:.9g} s: the system runs", record)
        model = replace(model, Ts=Ts)  # its one-step residuals (noise=True) are read at that period too
    elif model.Ts == 1.0 and record.Ts != 1.0:  # a model fitted on records made without Ts=: the real period is Ts=
        check_period(model.Ts, f"model {model.name!r} was identified on records sampled", record,
                     f"; if its records were made without Ts= and {record.name!r} is sampled at their real period, "
                     f"give that period: Ts={record.Ts:.9g}, as to narx_iosystem")
    model.check_record(record)  # the system runs at its period and the model's units: so must the lags it starts from
    lay = _layout(model.structure, model.input_names)
    # the inputs whose lags the state holds, with Model.simulate's hint for a missing one (a transient input's)
    require_inputs([n for n, Lu in zip(model.input_names, lay.Lu) if Lu], record.input_names,
                   "but the record's inputs are", prefix=f"{record.name}: ")
    L = model.max_lag
    if len(record) < L:  # no start has its lags in the record
        raise ValueError(f"{record.name}: the record has {len(record)} samples, fewer than the {L} the state holds (the "
                         "model's max lag)")
    ne = _noise_coefficients(model).size if noise else 0
    # the residuals' first sample: ξ = 0 before it (the MA recursion's start); the system fed them starts there
    Le = max(L, model.noise_structure.max_lag) if noise else L
    k = min(Le, len(record)) if start is None else check_int(start, "start", low=0)
    if k < L or k > len(record):
        raise ValueError(f"start must lie in [{L}, {len(record)}] (the model's max lag to the record's length), got {start!r}")
    parts = [record.y[k - lay.Ly: k][::-1] if lay.Ly else np.zeros(0)]
    for n, Lu in zip(model.input_names, lay.Lu):
        if Lu:
            parts.append(record.input(n)[k - Lu: k][::-1])
    if ne:
        e = np.zeros(ne)
        if k > Le:  # e(k−1) … e(k−n_e): the one-step residuals there, zeros before Le
            from ..diagnostics._residuals import one_step_residuals  # here: only a start past Le needs it

            xi = np.concatenate([np.zeros(Le), one_step_residuals(model, record)[0]])
            e = np.array([xi[k - l] if k - l >= 0 else 0.0 for l in range(1, ne + 1)])
        parts.append(e)
    return np.concatenate(parts).astype(float)


def narx_steady_state(model: Model, ubar: float | np.ndarray, ybar: float, *, noise: bool = False) -> np.ndarray:
    """The state of :func:`narx_iosystem`'s system settled at (ū, ȳ): every output lag ȳ, every input lag ū.

    Parameters
    ----------
    model : Model
        A polynomial NARX model.
    ubar : float or array_like, shape (m,)
        The constant input (input units), one value per input in ``model.input_names`` order (a
        dict by input name, or a pandas Series labelled by the inputs, e.g. a DataFrame's row, is read by
        its labels;
        transient inputs left out are 0, their level at every steady state, and any other level of one the
        model uses is refused: :func:`narx_iosystem` computes it, and it decays there).
    ybar : float
        The output level (output units), e.g. :attr:`graybox.LocalModel.ybar` at ū.
    noise : bool
        As for :func:`narx_iosystem`: the noise lags are appended, as zeros.

    Returns
    -------
    ndarray, shape (n_states,)
        In the order of :func:`narx_state_names`.
    """
    model = check_polynomial(model, "narx_steady_state")
    noise = check_bool(noise, "noise")
    ub = input_levels(frame_inputs(ubar, model.input_names, "ubar", steady=True))  # a Series by name
    ub = np.atleast_1d(steady_levels(ub, model.input_names, one_point=True)).ravel()  # transient inputs: z̄ = 0
    if ub.size != model.n_inputs or not np.all(np.isfinite(ub)):
        raise ValueError(f"ubar must be {model.n_inputs} finite value(s) {model.input_names}, got {ubar!r}")
    yb = check_real(ybar, "ybar")
    lay = _layout(model.structure, model.input_names)
    refuse_transient_levels(ub, model.input_names)  # narx_iosystem computes them: at any other level they decay
    ne = _noise_coefficients(model).size if noise else 0
    return np.concatenate([np.full(lay.Ly, yb)] + [np.full(L, u) for u, L in zip(ub, lay.Lu)] + [np.zeros(ne)])


def narx_iosystem(model: Model, *, Ts: float | None = None, noise: bool = False, name: str | None = None) -> Any:
    """The whole NARX model as a discrete ``control.NonlinearIOSystem`` (dt = Ts).

    State, update and output as in the module docstring: the state holds the lagged outputs and
    inputs (:func:`narx_state_names`), the output is the model's one-step map y(k) = F(x(k)) and
    the update shifts y(k) and u(k) in. Every model input is a system input (named after
    ``model.input_names``) but its transient inputs (``u_tau30`` …, :func:`graybox.transient_inputs`),
    which the update computes from their source inputs (module docstring), so that a controller
    setting u drives them; the output is ``"y"``. Connect it with a controller by
    ``control.interconnect`` and simulate with ``control.input_output_response`` (times
    ``Ts * arange(N)``, initial state from :func:`narx_initial_state`, given the same ``Ts``, or
    :func:`narx_steady_state`).
    By default the MA part of a NARMAX model is left out, as in :meth:`graybox.Model.simulate`.

    Parameters
    ----------
    model : Model
        A polynomial NARX model.
    Ts : float, optional
        Sampling period (s); default the model's own (``model.Ts``, the period it was identified at), as
        for :func:`local_model` (another than the model's own refused but over its 1 s, where a transient input keeps
        the decay per step its records had). Needed for a model that does not know its period.
    noise : bool
        Add the noise e(k) as a last system input ``"noise"`` (output units; not ``"e"``, the name a loop's
        error signal usually has, which ``control.interconnect`` would join to it by name) and the model's linear MA
        part: y(k) = F(x(k)) + Σ_l c_l e(k−l) + e(k), with e(k−1) … e(k−n_e) appended to the
        state (for a NARX model, y(k) = F(x(k)) + e(k)). Fed the model's one-step residuals on a
        record, the system reproduces the record's output; fed white noise of the residuals'
        variance, it simulates the loop with the identified disturbance. e(k) reaches y(k)
        directly (the only feedthrough).
    name : str, optional
        The system's name (default from the model's name).

    Returns
    -------
    control.NonlinearIOSystem
        Needs python-control (``pip install graybox[control]``). Its output raises
        :class:`~graybox.DivergenceError`, naming the time, once it is no longer a finite number
        (a diverging loop or free run), out of ``control.input_output_response``.
    """
    model = check_polynomial(model, "narx_iosystem")
    noise = check_bool(noise, "noise")
    if name is not None:
        check_str(name, "name")
        if not name.strip():  # python-control takes "" as a name, and control.interconnect then fails on it
            raise ValueError("name must name the system (a non-empty text), or be None for the default from the "
                             f"model's name; got {name!r}")
    Ts = check_Ts(Ts, None, model, takes_data=False)
    c = _noise_coefficients(model) if noise else np.zeros(0)
    if noise and NOISE_INPUT in model.input_names:
        raise ValueError(f"noise=True adds a system input named {NOISE_INPUT!r}, and the model has an input of that "
                         "name: rename the model's input (Model.input_names)")
    ct = require_control()
    lay = _layout(model.structure, model.input_names)
    theta = np.array(model.theta)
    E = lay.E
    n_proc = E.shape[1]  # the process states; the noise lags follow
    fed = np.array(lay.fed, dtype=np.intp)
    m = fed.size  # the system's inputs from the model's; the noise input follows
    # each transient input computed as transient_inputs computed it for the records: (its row z(k−1), its source
    # input, the source's row u(k−1), ρ = exp(−Ts/τ), 1 − ρ) at the model's own period, whose steps its τ was read
    # in (a Ts given over a model's 1 s, records made without Ts=, relabels the steps, not the decay per step)
    Tz = Ts if model.Ts is None else model.Ts
    transient = [(j, lay.u_rows[j][0], i, lay.u_rows[i][0], np.exp(-Tz / tau), -np.expm1(-Tz / tau))
                 for j, i, tau in lay.transient]

    label = name if name is not None else system_name(model.name, "narx")
    said = label if label is not None else "narx_iosystem's system"  # a nameless model's: python-control numbers it

    def output(t, x, u, params):
        x = np.asarray(x, float)
        with np.errstate(over="ignore", invalid="ignore"):
            y = theta @ np.prod(x[None, :n_proc] ** E, axis=1)
            if noise:
                y += c @ x[n_proc:] + np.atleast_1d(np.asarray(u, float))[m]
        if not np.isfinite(y):
            # numpy's overflow warnings and python-control's "algebraic loop detected" (there is no
            # feedthrough) would hide what happened: the run diverged, as Model.simulate says it
            raise DivergenceError(
                f"{said}: the model's output is no longer a finite number at t = {float(t):g} s (its state "
                f"reached {np.max(np.abs(x)):.3g}): the run diverged, e.g. a loop whose controller gain is too "
                "high or of the wrong sign at this operating point, or a model unstable along this input")
        return np.array([y])

    def update(t, x, u, params):
        x = np.asarray(x, float)
        u = np.atleast_1d(np.asarray(u, float))
        new = np.empty_like(x)
        if lay.Ly:
            new[0] = output(t, x, u, params)[0]
            new[1: lay.Ly] = x[: lay.Ly - 1]
        v = np.zeros(model.n_inputs)  # every model input at k: those fed, and the transient ones from their sources
        v[fed] = u[:m]
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is the output's DivergenceError, next sample
            for j, zrow, i, urow, rho, gain in transient:  # z(k) = ρ z(k−1) + (1 − ρ)(u(k) − u(k−1))²
                v[j] = rho * x[zrow] + gain * (v[i] - x[urow]) ** 2
        for i, rows in enumerate(lay.u_rows):
            if rows.size:
                new[rows[0]] = v[i]
                new[rows[1:]] = x[rows[:-1]]
        if c.size:
            new[n_proc] = u[m]
            new[n_proc + 1:] = x[n_proc:-1]
        return new

    inputs = [model.input_names[j] for j in lay.fed] + ([NOISE_INPUT] if noise else [])
    return ct.nlsys(update, output, inputs=inputs, outputs=["y"], states=narx_state_names(model, noise=noise),
                    dt=Ts, name=label)
