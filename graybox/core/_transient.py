"""Transient inputs: regressors that are zero at every steady state.

Some plants carry effects that a change of the input sets off and that die out while the input
rests: air drawn into a pump's suction that vents over half a minute, a heater's casing that warms
after each step, a tank's level that swings and settles. A careful static test waits them out, so
the static points do not show them; the dynamic records do. A model held to the static points
within their uncertainty then pays for them on every record (its static curve cannot move to
absorb their mean), while a black box absorbs them into a static curve that misses the points.

A transient input gives the model a way to carry such an effect without touching its static
curve. For an input u and a time constant τ it is the low-pass filtered squared change

    z(k) = ρ z(k−1) + (1 − ρ) (u(k) − u(k−1))²,   ρ = exp(−Ts / τ),   z(0) = 0,

zero while u rests (hence zero at every static point), positive after any change (either
direction), decaying with τ. It is an input channel like any other (``u_tau30`` for τ = 30 s), so
every estimator, the free runs, the static analysis and ``select_graybox`` use it as they use a
second input; the static points get z̄ = 0. Which τ (if any) the data support is a choice like the
structure's: offer a few and let the selection choose on the validation record.
"""

from __future__ import annotations

from typing import Mapping, Sequence, TypeVar

import numpy as np

from ._records import Dataset, Record, StaticPoints, check_units, input_unit
from ._reprs import squared_unit
from ._renamed import renamed_keyword
from ._terms import transient_name, transient_source, transient_tau_text
from ._validation import check_real, check_sequence

__all__ = ["transient_inputs", "steady_levels", "recomputed_transients", "refuse_transient_levels"]

_Data = TypeVar("_Data", Record, Dataset, StaticPoints)


def _units(data: Record | StaticPoints, names: Sequence[str], new: list) -> tuple:
    """The units of ``data`` extended by the transient inputs ``new`` ((name, input, τ) each): inputs in units of their
    own give each new one its input's unit squared; one unit for every input stays so (a model saved with it holds
    its transient inputs in that unit, and is compared with them by name)."""
    if isinstance(data.units[0], str):
        return data.units
    each = [input_unit(data.units, j) for j in range(len(names))]
    each += [squared_unit(input_unit(data.units, list(names).index(n))).strip() for _, n, _ in new]
    return check_units((each, data.units[1]), data.name, len(each))


def _filtered_square_change(u: np.ndarray, log_rho: float) -> np.ndarray:
    from scipy.signal import lfilter  # here: import graybox.core stays light

    du2 = np.empty_like(u)
    du2[0] = 0.0  # the record is taken to begin at rest
    du2[1:] = np.diff(u) ** 2
    # 1 − ρ as −expm1(−Ts/τ): 1.0 − ρ cancels to nothing for τ ≫ Ts (exactly 0 beyond about 1e16 Ts)
    return lfilter([-np.expm1(log_rho)], [1.0, -np.exp(log_rho)], du2)


def transient_inputs(data: _Data, taus: Sequence[float], *, input_names: Sequence[str] | None = None,
                     inputs: Sequence[str] | None = None) -> _Data:
    """Add transient inputs (low-pass filtered squared input changes) to a record, a data set or static points.

    For each input named in ``input_names`` and each ``τ`` in ``taus`` a new input channel
    ``z(k) = ρ z(k−1) + (1 − ρ) (u(k) − u(k−1))²`` with ``ρ = exp(−Ts/τ)`` and ``z(0) = 0`` is
    appended, named ``{input}_tau{τ}`` (:func:`transient_name`). It is zero while the input
    rests, so the static points get ``z̄ = 0`` and a model's static curve at the measured ū is
    untouched by the terms in z; it lets a gray box carry effects that input changes set off
    and that a static test waits out (see the module's notes), which otherwise make it pay on
    the dynamic records for meeting the static points.

    Parameters
    ----------
    data : Record, Dataset or StaticPoints
        What to extend. A Record (e.g. a test record: a model that uses transient inputs needs
        them in every record it runs on) gets the new channels computed from its own input; a
        Dataset gets them in both records and ``z̄ = 0`` in its static points; StaticPoints get
        ``z̄ = 0`` columns.
    taus : sequence of float
        Time constants τ in seconds (> 0, finite, distinct), e.g. ``(10, 30, 100)`` when effects
        that settle over tens of seconds are suspected.
    input_names : sequence of str, optional
        The inputs to take changes of (default: every input of ``data`` but the transient inputs
        it already has, named as :func:`transient_name` names them).
    inputs : sequence of str, optional
        The old name of ``input_names`` (``DeprecationWarning``).

    Returns
    -------
    Record, Dataset or StaticPoints
        A new value of the same type with ``len(inputs) × len(taus)`` more inputs, each in the
        input's units squared, after the existing ones (input by input, τ in the given order).
        A Dataset keeps its description and extra entries, and lists the new channels as
        ``extra["transient_inputs"]``: name → (input, τ).

    Notes
    -----
    A record is taken to begin at rest (z(0) = 0): one that begins just after a change starts
    its transient inputs too low for a few τ. The candidates of a selection name the new inputs
    with one lag each, e.g. ``Candidates(6, {"u": 6, "u_tau30": 1}, degree=2, input_names=…)``.

    Examples
    --------
    >>> data = gb.transient_inputs(gb.load_pumping(), taus=(10, 30, 100))
    >>> data.input_names
    ('u', 'u_tau10', 'u_tau30', 'u_tau100')
    """
    if not isinstance(data, (Record, Dataset, StaticPoints)):
        several = isinstance(data, (list, tuple)) and data and all(isinstance(d, (Record, Dataset, StaticPoints))
                                                                   for d in data)
        hint = (": sample it into static points first (e.g. curve.points(ubar, 'u')) and pass those"
                if hasattr(data, "points") else
                # each record's transient inputs start from rest at its own first sample: one call per record
                ": it takes one; call it once for each, [graybox.transient_inputs(r, taus=...) for r in records], "
                "with the same taus" if several else "")
        raise TypeError(f"transient_inputs: data must be a Record, a Dataset or StaticPoints, got "
                        f"{type(data).__name__}{hint}")
    tau_list = [check_real(t, "taus (seconds)", low=0, low_open=True) for t in
                check_sequence(taus, "taus", "a sequence of time constants in seconds")]
    if not tau_list:
        raise ValueError("taus is empty: give at least one time constant (seconds)")
    if len(set(tau_list)) != len(tau_list):
        raise ValueError(f"taus has repeated values: {tau_list}")
    inputs = renamed_keyword("transient_inputs", "inputs", "input_names", inputs, input_names)
    names = data.input_names
    # by default every input but the transient inputs already there (no transient of a transient)
    chosen = ([n for n in names if transient_source(n, names) is None] if inputs is None
              else check_sequence(inputs, "input_names", "a sequence of input names"))
    for n in chosen:
        if not isinstance(n, str):
            raise TypeError(f"input_names must name inputs (str), got {n!r} ({type(n).__name__})")
        if n not in names:
            raise ValueError(f"input_names: no input named {n!r}; the data's inputs are {names}")
    if len(set(chosen)) != len(chosen) or not chosen:
        raise ValueError(f"input_names must name at least one input, each once, got {chosen}")
    new = [(transient_name(n, t), n, t) for n in chosen for t in tau_list]
    taken = set(names) & {nm for nm, _, _ in new}
    if taken:
        raise ValueError(f"the data already have input(s) {sorted(taken)}: transient inputs added twice?")
    out_names = tuple(names) + tuple(nm for nm, _, _ in new)

    if isinstance(data, StaticPoints):
        ubar = np.column_stack([data.ubar.reshape(len(data.ybar), -1), np.zeros((len(data.ybar), len(new)))])
        return StaticPoints(ubar, data.ybar, data.name, out_names, data.uncertainty, _units(data, names, new))
    if isinstance(data, Record):
        cols = [data.inputs] + [_filtered_square_change(data.input(n), -data.Ts / t)[:, None]
                                for _, n, t in new]
        return Record(np.hstack(cols), data.y, data.Ts, data.name, _units(data, names, new), out_names)
    extra = dict(data.extra)
    before = extra.get("transient_inputs")
    extra["transient_inputs"] = {**(dict(before) if isinstance(before, Mapping) else {}),
                                 **{nm: (n, t) for nm, n, t in new}}
    return Dataset(transient_inputs(data.ident, tau_list, input_names=chosen),
                   transient_inputs(data.valid, tau_list, input_names=chosen),
                   None if data.static is None else transient_inputs(data.static, tau_list, input_names=chosen),
                   data.description, extra)


def steady_levels(ub: np.ndarray, names: Sequence[str], *, one_point: bool = False) -> np.ndarray:
    """Operating points ū of a model whose inputs ``names`` include transient inputs, with their z̄ = 0 filled in.

    A transient input is 0 at every steady state, so ū given for the other inputs alone is completed with zero
    columns, shape (M, m): with one other input, a scalar or levels of shape (M,) (as for a model of one input)
    or (M, 1); with k others, one point of shape (k,) or points (M, k). A 1-D ū of length m is one point of every
    input where ``one_point`` (the caller takes one) or k > 1; with one other input it could be m levels as well
    as one point, and is refused (ValueError) rather than read by its values. Anything else, and ū of a model
    without transient inputs, is returned as it is (the caller's shape checks say what is wrong).
    """
    names = tuple(names)
    base = [j for j, n in enumerate(names) if transient_source(n, names) is None]
    m, k = len(names), len(base)
    if k in (0, m):
        return ub
    if ub.ndim == 1 and ub.size == m:
        if one_point or k > 1:
            return ub  # one point of every input
        raise ValueError(
            f"ubar: {m} values for a model of inputs {names}, whose {m - 1} transient input(s) rest at 0: give "
            f"levels of {names[base[0]]!r} as a column, shape (M, 1), or points of every input, shape (1, {m}) "
            "for one")
    if k == 1 and ub.ndim <= 1:
        # levels of the one input: [1000, 1200] was the point (1000, z̄ = 1200), where the run never rests
        levels = ub.reshape(-1, 1)
    elif ub.ndim == 2 and ub.shape[1] == k:
        levels = ub
    elif ub.ndim == 1 and ub.size == k:
        levels = ub[None, :]
    else:
        return ub
    full = np.zeros((levels.shape[0], m))
    full[:, base] = levels
    return full


def refuse_transient_levels(ub: np.ndarray, names: Sequence[str], name: str = "ubar") -> None:
    """``ValueError`` naming the transient inputs among ``names`` to which the points ``ub`` (shape (m,) or (M, m),
    columns in the order of ``names``) give a level other than 0: a transient input is 0 at every steady state, so
    no equilibrium, local model or settled state is at any other (the one check of every steady-state entry)."""
    names = tuple(names)
    a = np.atleast_2d(np.asarray(ub, dtype=float))
    if a.ndim != 2 or a.shape[1] != len(names):
        return  # the caller's shape checks say what is wrong
    moving = [n for j, n in enumerate(names) if transient_source(n, names) is not None and np.any(a[:, j] != 0.0)]
    if moving:
        raise ValueError(f"{name} gives the transient input(s) {', '.join(moving)} a level other than 0, but a "
                         "transient input is 0 at every steady state (it is computed from its input's changes, and "
                         "decays while the input rests): leave it out or give 0")


def recomputed_transients(u: np.ndarray, names: Sequence[str], Ts: float,
                          taus: Mapping[str, tuple[str, float]] | None = None) -> np.ndarray:
    """The inputs ``u`` (shape (N,) or (N, m)) with every transient input among ``names`` computed afresh from its
    input at the period ``Ts`` (s): what :func:`transient_inputs` gives a record of these samples. ``taus``: name →
    (input, τ) (a Dataset's ``extra["transient_inputs"]``), else τ is read from the name (exactly: transient_name
    writes every digit τ needs). A record decimated keeps every q-th sample of its inputs, but z is no such sample:
    its (1 − ρ) and ρ are of Ts."""
    names = tuple(names)
    if u.ndim == 1:
        return u
    out = None
    for j, n in enumerate(names):
        source = transient_source(n, names)
        if source is None:
            continue
        given = None if taus is None else taus.get(n)
        tau = float(given[1]) if given is not None and given[0] == source else _tau_of(n, source)
        if tau is None:
            continue
        if out is None:
            out = np.array(u, dtype=float)
        out[:, j] = _filtered_square_change(out[:, names.index(source)], -Ts / tau)
    return u if out is None else out


def _tau_of(name: str, source: str) -> float | None:
    """τ (s) written in a transient input's name by :func:`transient_name` (``u_tau2p5`` → 2.5), or None."""
    try:
        tau = float(transient_tau_text(name, source))
    except ValueError:
        return None
    return tau if np.isfinite(tau) and tau > 0 else None
