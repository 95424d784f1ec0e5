"""The polynomial NARMAX model as an immutable value."""

from __future__ import annotations

from dataclasses import dataclass, field
from collections.abc import Mapping
from typing import Literal

import numpy as np

from ..core import _simulation
from ..static import _analysis as _static
from ..static import _surface_analysis as _static_surface
from ..core._equation_text import latex_equation
from ..core._records import Record, check_fitted_on, check_period, check_units, frame_inputs
from ..core._validation import Relocked, check_int, check_real, check_sequence, check_str, check_theta, frozen
from ..core._terms import Structure, check_input_names, require_inputs, structure_of

__all__ = ["Model", "model_input_names"]


def model_input_names(structure: Structure, input_names: object = None) -> tuple[str, ...]:
    """The input names of a model of ``structure``: ``input_names`` checked (every input the
    structure uses among them), or by default the structure's inputs sorted by name (``("u",)``
    for an output-only structure). Results that hand out models (fronts, selections) use it too."""
    names = (structure.input_names or ("u",)) if input_names is None else check_input_names(input_names)
    require_inputs(structure.input_names, names, "which is not among input_names")
    return names


@dataclass(frozen=True, eq=False)
class Model(Relocked):
    """Structure + parameters of a polynomial NARMAX model.

    Parameters
    ----------
    structure : Structure, sequence of str, or a result that carries one
        Process (NARX) terms, in parameter order (a Selection, a Model … gives its ``.structure``, and its
        ``input_names`` where ``input_names`` is not given).
    theta : array_like, shape (n_terms,)
        Process parameters, engineering units.
    noise_structure : Structure, optional
        MA terms e(k-l) estimated with the model (e.g. by ELS); never used in simulation.
    noise_theta : array_like, optional
        Their parameters.
    name : str, optional
        Label for tables and plots.
    input_names : sequence of str, optional
        The model's inputs, in the column order of an input array (default: the inputs the
        structure uses, in natural name order, or ``("u",)`` when it uses none). Must contain
        every input the structure uses.
    Ts : float, optional
        The sampling period (s) of the records the model was identified on; a Record sampled at
        another period is refused where the model meets it (``simulate``, ``predict``, and the
        scores built on them). None (default: a model written by hand, or read from a file of an
        earlier graybox): unknown, not checked. Estimators set it from their records.
    units : tuple, optional
        The units of the input(s) and the output in the records the model was identified on (e.g.
        ``("rpm", "mlc")``, or ``(("l/min", "°C"), "m")`` for inputs in units of their own), as
        :class:`~graybox.Record` has them. Its parameters hold in those units
        only: a Record in other units is refused where the model meets it, as one at another period
        is. Empty (the default, a model written by hand or read from an earlier file): unknown, not
        checked. Estimators set them from their records.
    """

    structure: Structure
    theta: np.ndarray
    noise_structure: Structure = field(default_factory=lambda: Structure(()))
    noise_theta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    name: str = ""
    input_names: tuple[str, ...] | None = None
    Ts: float | None = None
    units: tuple[str | tuple[str, ...], str] = ("", "")

    def __post_init__(self) -> None:
        check_str(self.name, "name")
        object.__setattr__(self, "units", check_units(self.units, f"model {self.name!r}"))
        if self.Ts is not None:
            object.__setattr__(self, "Ts", check_real(self.Ts, "Ts (seconds)", low=0, low_open=True))
        # a Structure, terms, or what carries one (a Selection, another Model), as wherever a structure is meant
        given = self.structure
        st = structure_of(given)
        if any(t.is_noise for t in st):
            raise ValueError("noise terms belong in noise_structure, not in the process structure")
        ns = self.noise_structure
        if not isinstance(ns, Structure):
            items = check_sequence(ns, "noise_structure", "a Structure or a sequence of noise terms",
                                   ordered="noise terms (the order of noise_theta)")
            try:
                ns = Structure(items)
            except (TypeError, ValueError) as exc:  # a number among the terms: said with the field's name
                raise type(exc)(f"noise_structure: {exc}") from None
        if not all(t.is_noise for t in ns):
            raise ValueError(f"noise_structure must hold noise terms e(k-l) only; got {ns}")
        object.__setattr__(self, "structure", st)
        object.__setattr__(self, "noise_structure", ns)
        object.__setattr__(self, "theta", frozen(check_theta(len(st), self.theta)))
        object.__setattr__(self, "noise_theta", frozen(check_theta(len(ns), self.noise_theta, "noise_theta")))
        names = self.input_names
        if names is None and not isinstance(given, Structure):
            # what carries the structure carries the inputs it was found on (a Selection's, a Model's): Model(sel, θ)
            # reads the data's frames as sel.model does, not by the structure's inputs alone
            carried = getattr(given, "input_names", None)
            names = carried if isinstance(carried, tuple) and getattr(given, "structure", None) is st else None
            inner = getattr(given, "model", None)  # a result that carries a model (ELSResult, Decision …): its inputs
            if names is None and isinstance(getattr(inner, "input_names", None), tuple) and \
                    getattr(inner, "structure", None) is st:
                names = inner.input_names
        object.__setattr__(self, "input_names", model_input_names(st, names))
        object.__setattr__(self, "units", check_units(self.units, f"model {self.name!r}", len(self.input_names)))

    # -- basic facts --------------------------------------------------------
    @property
    def n_params(self) -> int:
        """N_p: number of process parameters (the MA part is not counted, as in Table I)."""
        return len(self.structure)

    @property
    def max_lag(self) -> int:
        """Largest lag of the process terms (number of initial conditions of a free run)."""
        return self.structure.max_lag

    def with_theta(self, theta: np.ndarray, *, name: str | None = None) -> "Model":
        """The same structure with other parameters; the noise part is dropped, the inputs' names, ``Ts`` and units
        kept.

        Parameters
        ----------
        theta : ndarray, shape (n_terms,)
            Process parameters, in engineering units (those of the model's output and inputs).
        name : str, optional
            The new model's name (default: this model's name).

        Returns
        -------
        Model
        """
        return Model(self.structure, theta, name=self.name if name is None else name, input_names=self.input_names,
                     Ts=self.Ts, units=self.units)

    def check_period(self, record: Record) -> None:
        """``ValueError`` when ``record`` is sampled at another period than the model was identified at
        (nothing when the model's ``Ts`` is unknown).

        Parameters
        ----------
        record : Record
            Its ``Ts`` (s) is compared with the model's.
        """
        check_period(self.Ts, f"model {self.name!r} was identified on records sampled", record)

    def check_record(self, record: Record) -> None:
        """``ValueError`` when ``record`` (or static points) cannot be met by this model: sampled at another
        period than the model was identified at, or in other units where both name them.

        Parameters
        ----------
        record : Record or StaticPoints
            Its ``Ts`` (s) and units are compared with the model's.
        """
        check_fitted_on(self.Ts, self.units, f"model {self.name!r} was identified", record,
                        "its parameters hold in those units only; convert the data (or give them the model's units "
                        "if only the label differs)", self.input_names)

    # -- dynamics -----------------------------------------------------------
    def predict(self, record: Record, *, horizon: int = 1) -> np.ndarray:
        """Prediction ``horizon`` samples ahead over ``record``; see :func:`graybox.predict`.

        Parameters
        ----------
        record : Record
            N samples; one sampled at another period than ``Ts``, or in other ``units``, is refused (``ValueError``).
        horizon : int, optional
            Steps ahead, >= 1 (default 1: one-step-ahead prediction).

        Returns
        -------
        ndarray, shape (N,)
            Predicted output, output units.
        """
        self.check_record(record)
        return _simulation.predict(self.structure, self.theta, record, horizon=horizon)

    @property
    def n_inputs(self) -> int:
        """m, the number of inputs (columns of an input array)."""
        return len(self.input_names)

    def simulate(
        self,
        u: np.ndarray | Record,
        y0: np.ndarray | None = None,
        *,
        on_diverge: Literal["raise", "nan"] = "raise",
        bound: float | None = None,
    ) -> np.ndarray:
        """Free run; see :func:`graybox.simulate`.

        Parameters
        ----------
        u : Record, or ndarray or pandas.DataFrame, shape (N,) or (N, m)
            A Record (inputs taken by name; sampled at ``Ts`` and in the model's ``units``, else refused) or an
            array with the columns in ``input_names`` order, input units; a DataFrame is read by column name where
            its columns are the ``input_names`` (any order), by position where they name none of them, and refused
            where they name some (``ValueError`` naming the columns).
        y0 : ndarray, shape (>= max_lag,), optional
            The first ``max_lag`` outputs, output units (default with a Record: its measured ones; needed with an
            array).
        on_diverge : {"raise", "nan"}
            When the output leaves the bound, ``"raise"`` (default) a :class:`~graybox.DivergenceError` naming the
            sample, or ``"nan"`` NaN from that sample on.
        bound : float, optional
            The divergence bound on |y|, output units (default: 1e6 × the largest of max|y0|, the level the
            inputs' direct push on the output so far holds it at through the linear feedback, and the size at which
            the model's nonlinear output feedback matters, in the output's units whatever they are, also from
            rest).

        Returns
        -------
        ndarray, shape (N,)
            The simulated output, output units.
        """
        if isinstance(u, Record):
            self.check_record(u)
        if not isinstance(u, Record) and self.n_inputs > 1:
            return _simulation.simulate(self.structure, self.theta, u, y0, on_diverge=on_diverge, bound=bound,
                                        input_names=self.input_names)
        return _simulation.simulate(self.structure, self.theta, u, y0, on_diverge=on_diverge, bound=bound)

    # -- statics ------------------------------------------------------------
    # With several inputs the static function is a surface ȳ(ū_1, …, ū_m): ū is then of shape
    # (M, m) (columns in input_names order; a single point may be given as shape (m,)); a DataFrame
    # is read by column name as every input is (graybox.core._records.frame_inputs).
    def clusters(self) -> dict[str, float]:
        """Cluster coefficients by name, Σ = R θ.

        Returns
        -------
        dict of str to float
            ``{"Σ0": …, "Σy": …, "Σu": …}``; with several inputs one cluster per output power and
            input powers (``"Σyu1"``, ``"Σu1u2²"``, …).
        """
        cm = self.cluster_map()
        with np.errstate(over="ignore"):  # a sum beyond the float range is ±inf, and says so
            return dict(zip(cm.names, (cm.R @ self.theta).tolist()))

    def cluster_map(self) -> _static.ClusterMap | _static_surface.SurfaceClusterMap:
        """The clusters and the 0/1 map R of this structure (per input power with several inputs).

        Returns
        -------
        ClusterMap or SurfaceClusterMap
            As :func:`graybox.cluster_map` (one input) or :func:`graybox.surface_cluster_map` (several) give it.
        """
        if self.n_inputs > 1:
            return _static_surface.surface_cluster_map(self.structure, input_names=self.input_names)
        return _static.cluster_map(self.structure)

    def static_curve(self, ubar: np.ndarray, y0: float | None = None, *, strict: bool = True) -> np.ndarray:
        """Steady-state output at each ū of ``ubar``; see :func:`graybox.static_curve`.

        Parameters
        ----------
        ubar : array_like, shape (M,), or shape (M, m) with several inputs, or dict
            Input levels, input units. With several inputs, the static surface at the points ``ubar``
            (:func:`graybox.static_surface`): columns in ``input_names`` order, or a pandas DataFrame whose
            columns are the ``input_names`` (read by name, any order), or a dict by input name
            (``{"flow": [2.0, 7.0], "inlet": [20.0, 20.0]}``, one number each for one point; with one input
            ``{"u": [1.0, 2.0]}`` its levels); transient inputs
            (:func:`graybox.transient_inputs`) left out are 0, their level at every steady state, so a
            one-input plant's model with them takes levels of shape (M, 1), or (M,) for M ≠ m (m values
            could be one point as well, and are refused).
        y0 : float or array_like, shape (M,), optional
            Output units, one for all ū or one per ū: the equilibrium a free run started there settles on, as J_SF
            counts it (default: the one stable equilibrium).
        strict : bool, optional
            ``True`` (default) raises ``ValueError`` naming each ū where no equilibrium is reached (the first 20,
            and how many more); ``False`` gives NaN there.

        Returns
        -------
        ndarray, shape (M,)
            ȳ, output units.
        """
        if self.n_inputs > 1:
            return _static_surface.static_surface(self.structure, self.theta, ubar, y0=y0, strict=strict,
                                           input_names=self.input_names)
        return _static.static_curve(self.structure, self.theta, self._one_input(ubar), y0=y0, strict=strict)

    def _one_input(self, ubar: object) -> object:
        """A one-input model's levels given as a dict by its input's name (as local_model and the surfaces of
        several inputs take them): its values; anything else as given (the static paths check it)."""
        if isinstance(ubar, Mapping):
            return np.asarray(frame_inputs(ubar, self.input_names, "ubar", steady=True), dtype=float).ravel()
        return ubar

    def equilibria(self, ubar: float | np.ndarray) -> list[_static.Equilibrium]:
        """Every real equilibrium at one input level, with its stability; see :func:`graybox.equilibria`.

        Parameters
        ----------
        ubar : float, or array_like, shape (m,), or dict
            The input level ū, input units: a float, or a point of shape (m,) (or a dict by input name) with
            several inputs.

        Returns
        -------
        list of Equilibrium
            Each real equilibrium ȳ (output units) with its spectral radius and stability.
        """
        if self.n_inputs > 1:
            return _static_surface.surface_equilibria(self.structure, self.theta, ubar, input_names=self.input_names)
        one = self._one_input(ubar)
        return _static.equilibria(self.structure, self.theta, one[0] if isinstance(ubar, Mapping) and one.size == 1
                                  else one)

    def static_gain(self, ubar: np.ndarray, y0: float | None = None, *, strict: bool = True) -> np.ndarray:
        """dȳ/dū along the static curve at each ū of ``ubar``; with several inputs the gradient.

        Parameters
        ----------
        ubar : array_like, shape (M,), or shape (M, m) with several inputs, or dict
            Input levels, input units, as for :meth:`static_curve`.
        y0 : float or array_like, shape (M,), optional
            As for :meth:`static_curve` (output units).
        strict : bool, optional
            As for :meth:`static_curve` (``False``: NaN where no equilibrium is reached).

        Returns
        -------
        ndarray, shape (M,), or shape (M, m) with several inputs
            Gain in output units per input unit.
        """
        if self.n_inputs > 1:
            return _static_surface.static_surface_gain(self.structure, self.theta, ubar, y0=y0, strict=strict,
                                                       input_names=self.input_names)
        return _static.static_gain(self.structure, self.theta, self._one_input(ubar), y0=y0, strict=strict)

    @property
    def is_rational(self) -> bool:
        """True when the static function has the closed rational form of eq. (6)."""
        return _static.is_rational(self.structure)

    # -- printing -----------------------------------------------------------
    def equation(self, *, digits: int = 4) -> str:
        """Paper-style equation, e.g. ``y(k) = 0.6303 y(k-1) - 0.0264 y(k-4) + …``.

        Parameters
        ----------
        digits : int, optional
            Significant digits of each parameter, >= 1 (default 4).

        Returns
        -------
        str
        """
        digits = check_int(digits, "digits", low=1)
        parts = []
        for i, (th, t) in enumerate(zip(self.theta, self.structure)):
            mag = f"{abs(th):.{digits}g}"
            body = mag if t.is_constant else f"{mag} {t}"
            sign = "-" if th < 0 else "+"
            parts.append((f"-{body}" if sign == "-" else body) if i == 0 else f" {sign} {body}")
        for th, t in zip(self.noise_theta, self.noise_structure):
            parts.append(f" {'-' if th < 0 else '+'} {abs(th):.{digits}g} {t}")
        return "y(k) = " + ("".join(parts) if parts else "0") + (" + e(k)" if len(self.noise_structure) else "")

    def to_latex(self, digits: int = 4, terms_per_line: int | None = None) -> str:
        """The equation in LaTeX math (no ``$`` delimiters), the MA part written with ξ as in the paper.

        Parameters
        ----------
        digits : int, optional
            Significant digits of each parameter, >= 1 (default 4).
        terms_per_line : int, optional
            Breaks a long model into an ``aligned`` block of this many terms a line, >= 1 (put it inside
            ``\\begin{equation}`` … ``\\end{equation}``); default: one line.

        Returns
        -------
        str
        """
        digits = check_int(digits, "digits", low=1)
        if terms_per_line is not None:
            terms_per_line = check_int(terms_per_line, "terms_per_line", low=1)
        return latex_equation(self.structure, self.theta, self.noise_structure, self.noise_theta, digits, terms_per_line)

    def __str__(self) -> str:
        head = f"{self.name}: " if self.name else ""
        return head + self.equation()

    def __repr__(self) -> str:
        period = "" if self.Ts is None else f", Ts={self.Ts:g} s"
        units = f", units={self.units}" if any(self.units) else ""
        return f"Model(name={self.name!r}, n_params={self.n_params}, max_lag={self.max_lag}{period}{units})"
