"""One coercion per concept, called at every public entry.

- a **structure** from a Structure, a sequence of terms, a Model, or a result that carries one
  (``.structure`` of a Selection, SEMPResult, ParetoSet or GrayboxSelection; ``.model`` of an
  ELSResult, CLSResult, OEResult, Decision, DSFResult …);
- a **model** from a Model or a result that carries one in ``.model``;
- the **static information** from an explicit argument, else the Dataset's static points, and
  the **static points** an estimator scores: given points, or a curve or surface sampled at ``ubar``
  or over its domain (:func:`static_points`: one sampling for PE, SE and the selection);
- a **record** from a Record, or the part of a Dataset the entry means (``ident`` for an
  estimate, ``valid`` for a judgement): :func:`as_record` for one, ``records_of`` (core's
  ``as_records``, which core's own regressors use too) for a Record, a sequence or a Dataset.

Anything else is a ``TypeError`` that lists what is accepted. The results live in higher layers,
so they are recognised by what they carry (a ``.structure`` or a ``.model`` attribute), not by
their class.
"""

from __future__ import annotations

import numpy as np

from ..core._records import Dataset, Record, StaticPoints, check_same_units, frame_inputs, record_hint, static_hint
from ..core._records import as_records as records_of  # records: coerced in core, which its own regressors need
from ..core._terms import STRUCTURE_ACCEPTED, Structure, structure_of
from ..core._validation import as_1d_finite, float_array
from ..static._curves import StaticCurve
from ..static._surfaces import StaticSurface, box_grid
from ._model import Model

__all__ = ["STRUCTURE_ACCEPTED", "MODEL_ACCEPTED", "as_structure", "as_model", "static_info", "static_points",
           "as_record", "records_of", "CURVE_LEVELS", "SURFACE_LEVELS"]

#: Levels a StaticCurve is sampled at over its domain when no ū is given.
CURVE_LEVELS = 10
#: Levels per input a StaticSurface is sampled at over its domain box (a grid) when no ū is given.
SURFACE_LEVELS = 6

#: What a model argument may be, in words.
MODEL_ACCEPTED = ("a Model or a result that carries one in .model (ELSResult, CLSResult, OEResult, Decision, "
                  "DSFResult, Selection, SEMPResult, GrayboxSelection)")

def _carried_model(obj: object, kinds: tuple[type, ...]) -> object | None:
    """``obj.model`` when it is an attribute of one of ``kinds`` (a method is not a model)."""
    m = getattr(obj, "model", None)
    return m if isinstance(m, kinds) else None


def _set_hint(obj: object) -> str:
    if hasattr(obj, "member_model") and hasattr(obj, "thetas"):
        return (f"; a {type(obj).__name__} holds many models: choose one (graybox.decide_dsf(front, band=B).model, or "
                "front.member_model(i))")
    return ""


def _duck_model(obj: object, name: str, needs: tuple[str, ...], accepted: str) -> object:
    """``obj``, which has the method ``needs[0]``, when it has every other name in ``needs`` too, else a ``TypeError``."""
    missing = [n for n in needs[1:] if not hasattr(obj, n)]
    if missing:
        raise TypeError(f"{name} must be {accepted}; got a {type(obj).__name__} that has .{needs[0]}() but no "
                        f"{', '.join('.' + n for n in missing)}, which a model used here needs")
    return obj


def as_structure(obj: object, name: str = "structure", *, with_noise: bool = False) -> Structure:
    """The structure ``obj`` means.

    Parameters
    ----------
    obj : Structure, sequence of str or Term, Model, or a result
        A result is read through its ``.structure`` (Selection, SEMPResult, ParetoSet,
        GrayboxSelection) or its ``.model`` (ELSResult, CLSResult, OEResult, Decision, DSFResult).
    name : str
        The argument's name, for the error message.
    with_noise : bool
        Append the noise terms ``obj`` carries (a Selection's ``noise``, a Model's
        ``noise_structure``), for an estimator that fits an MA part (ELS). Otherwise a Model or a
        result gives its process terms only; an explicit Structure is returned as given.

    Returns
    -------
    Structure

    Raises
    ------
    TypeError
        ``obj`` is none of these; the message lists what is accepted.
    """
    if isinstance(obj, Structure):
        return obj
    carried = None if isinstance(obj, Model) else getattr(obj, "structure", None)
    if isinstance(carried, Structure):  # a result's own structure first: a Selection's carries its noise terms
        noise = getattr(obj, "noise", None)
        if with_noise and isinstance(noise, Structure) and len(noise):
            return Structure(tuple(carried) + tuple(noise))
        return carried
    model = obj if isinstance(obj, Model) else _carried_model(obj, (Model,))
    if model is not None:
        if with_noise and len(model.noise_structure):
            return Structure(tuple(model.structure) + tuple(model.noise_structure))
        return model.structure
    return structure_of(obj, name)  # a sequence of terms, else the one TypeError that lists what is accepted


def as_model(obj: object, name: str = "model", *, kinds: tuple[type, ...] = (Model,),
             duck: str | tuple[str, ...] | None = None, accepted: str = MODEL_ACCEPTED) -> object:
    """The model ``obj`` means: ``obj`` itself when it is one of ``kinds``, else its ``.model``.

    Parameters
    ----------
    obj : Model or a result with a ``.model`` attribute
        ELSResult, CLSResult, OEResult, Decision, DSFResult, Selection, SEMPResult, GrayboxSelection
        (a NeuralFit where ``kinds`` holds NeuralModel).
    name : str
        The argument's name, for the error message.
    kinds : tuple of type
        The model classes the entry works with (default: the polynomial Model).
    duck : str or tuple of str, optional
        A method name, then the other attributes the entry reads: any object with that method counts
        as a model too (e.g. ``"static_curve"`` lets a NeuralModel, which lives above this layer,
        through where only that method is used); one that has the method but lacks another of the
        names is a look-alike, refused with a ``TypeError`` naming what it lacks (not a bare
        ``AttributeError`` when the entry reads it).
    accepted : str
        What is accepted, in words, for the error message.

    Returns
    -------
    Model (or one of ``kinds``)

    Raises
    ------
    TypeError
        ``obj`` neither is nor carries such a model; the message lists what is accepted (and
        how to pick one model of a Pareto set).
    """
    needs = (duck,) if isinstance(duck, str) else tuple(duck or ())
    if isinstance(obj, kinds):
        return obj
    if needs and callable(getattr(obj, needs[0], None)):
        return _duck_model(obj, name, needs, accepted)
    m = getattr(obj, "model", None)
    if isinstance(m, kinds):
        return m
    if needs and callable(getattr(m, needs[0], None)):
        return _duck_model(m, f"{name}.model", needs, accepted)
    raise TypeError(f"{name} must be {accepted}; got {type(obj).__name__}{_set_hint(obj)}")


def static_info(static: object, data: object, *, needed_by: str | None = None, name: str = "static",
                curves: bool = False) -> StaticPoints | StaticCurve | StaticSurface | None:
    """The static information an entry uses: ``static`` when given, else the Dataset's static points.

    Parameters
    ----------
    static : StaticPoints, StaticCurve, StaticSurface or None
        The explicit argument (curves and surfaces only where ``curves`` is True).
    data : object
        The entry's data argument; a :class:`~graybox.Dataset` lends its ``static``.
    needed_by : str, optional
        The entry's name when it cannot work without static information: ``None`` found then
        raises ``ValueError`` saying so.
    name : str
        The argument's name, for the error message.
    curves : bool
        Accept a StaticCurve or StaticSurface as well as StaticPoints.

    Returns
    -------
    StaticPoints, StaticCurve, StaticSurface or None

    Raises
    ------
    TypeError
        ``static`` is of another type; the message lists what is accepted.
    ValueError
        No static information and ``needed_by`` is given.
    """
    kinds: tuple[type, ...] = (StaticPoints, StaticCurve, StaticSurface) if curves else (StaticPoints,)
    if static is not None and not isinstance(static, kinds):
        what = "StaticPoints, a StaticCurve, a StaticSurface or None" if curves else "StaticPoints or None"
        raise TypeError(f"{name} must be {what}; got {type(static).__name__}{static_hint(static)}")
    if isinstance(static, StaticPoints):  # given beside the records (a Dataset's own points are checked by it)
        for r in _records_in(data):
            check_same_units(r.units, f"{r.name!r} has", static, "the records and the static points of one "
                             "identification must be in the same units (convert one of them)", r.input_names)
    out = static if static is not None else (data.static if isinstance(data, Dataset) else None)
    if out is None and needed_by is not None:
        raise ValueError(f"{needed_by} needs static points: pass {name}= or a Dataset with static points")
    return out


def _records_in(data: object) -> list:
    """The records (Record, DaskRecord) an entry's ``data`` holds, for checking given static points against them:
    coerced nothing, refused nothing (the entry coerces its data itself)."""
    if isinstance(data, Dataset):
        return [r for r in (data.ident, data.valid) if r is not None]
    items = data if isinstance(data, (list, tuple)) else [data]
    return [r for r in items if not isinstance(r, StaticPoints) and isinstance(getattr(r, "units", None), tuple)
            and hasattr(r, "name")]


def static_points(static: object, data: object, *, ubar: object = None, needed_by: str | None = None,
                  name: str = "static", takes_ubar: bool = True) -> StaticPoints | None:
    """The static points an entry scores: given points, a curve or surface sampled, or the Dataset's.

    Parameters
    ----------
    static : StaticPoints, StaticCurve, StaticSurface or None
        The explicit argument; None takes a :class:`~graybox.Dataset`'s static points.
    data : object
        The entry's data argument (a Record, records or a Dataset): a curve's points are of the
        records' (first) input, named as the records name it.
    ubar : ndarray, optional
        Where to sample a curve (shape (K,), input units) or a surface (shape (K, m)). Default:
        :data:`CURVE_LEVELS` levels over a curve's domain, a grid of :data:`SURFACE_LEVELS` levels
        per input over a surface's domain box. Refused with static points, which carry their own ū.
    needed_by : str, optional
        The entry's name when it cannot work without static information.
    name : str
        The argument's name, for the error message.
    takes_ubar : bool
        Whether the entry has a ``ubar`` argument (the error for a curve without a domain says
        what to give).

    Returns
    -------
    StaticPoints or None
        None only when nothing is given and ``needed_by`` is None.

    Raises
    ------
    TypeError
        ``static`` is of another type.
    ValueError
        ``ubar`` with static points, of the wrong shape or not finite; a curve or surface without
        a domain and no ``ubar``; no static information and ``needed_by`` is given.
    """
    static = static_info(static, data, needed_by=needed_by, name=name, curves=True)
    if static is None or isinstance(static, StaticPoints):
        if ubar is not None:
            raise ValueError("ubar is for sampling a StaticCurve or StaticSurface; static points carry their own ū")
        return static
    kind = type(static).__name__
    surface = isinstance(static, StaticSurface)
    if ubar is None and static.domain is None:
        shape = f"(K, {static.n_inputs})" if surface else "(K,)"
        give = f"ubar of shape {shape}: where to sample it" if takes_ubar else "static points (e.g. its .points(ubar))"
        raise ValueError(f"a {kind} without a domain needs {give}")
    if not surface:
        ub = (np.linspace(static.domain[0], static.domain[1], CURVE_LEVELS) if ubar is None
              else as_1d_finite(ubar, "ubar"))
        if not ub.size:  # said of ubar: the sampled points' own refusal named the curve's source, not the argument
            raise ValueError(f"ubar is empty: give the input levels where to sample the {kind} (shape (K,), K >= 1)")
        # a curve is of one input, whatever the records (a Record, a Dataset, a sequence) call it
        first = data[0] if isinstance(data, (list, tuple)) and data else data
        names = getattr(first, "input_names", None) or ("u",)
        return static.points(ub, names[0])
    if ubar is None:
        # SURFACE_LEVELS is no option of the caller's: past the grid's cap, ubar is what they can give
        return static.points(box_grid(static.domain, SURFACE_LEVELS, f"static: the {kind} sampled over its domain",
                                      "give ubar, the input levels where to sample it"))
    m = static.n_inputs
    # a DataFrame (or one point as a Series) by its column names, as every input is read
    first = data[0] if isinstance(data, (list, tuple)) and data else data
    ubar = frame_inputs(ubar, static.input_names or getattr(first, "input_names", None), "ubar")
    ub = float_array(ubar, "ubar", f"an array of numbers of shape (K, {m})")
    if m == 1 and ub.ndim == 1:
        ub = ub[:, None]
    if ub.ndim != 2 or ub.shape[1] != m or ub.shape[0] == 0:
        raise ValueError(f"ubar must have shape (K, {m}) for a surface of {m} inputs, got shape {ub.shape}")
    if not np.all(np.isfinite(ub)):
        raise ValueError(f"ubar has NaN or inf at rows {np.flatnonzero(~np.isfinite(ub).all(axis=1)).tolist()}")
    return static.points(ub)


def as_record(data: object, part: str, name: str = "data", call: str = "") -> Record:
    """One record: ``data`` itself, or the part ``part`` (``"ident"`` or ``"valid"``) of a Dataset; ``call``, the
    call on one record ``r`` that a list of records is told to make once per record.

    Raises
    ------
    TypeError
        ``data`` is neither; the message lists what is accepted and which part a Dataset gives.
    """
    if isinstance(data, Record):
        return data
    if isinstance(data, Dataset):
        return getattr(data, part)
    raise TypeError(f"{name} must be a Record or a Dataset (whose {part} record is used); got {type(data).__name__}"
                    f"{record_hint(data, call)}")
