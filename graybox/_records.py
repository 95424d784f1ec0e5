"""Measured data as immutable values: dynamic records and static points.

A :class:`Record` is one experiment (input and output sampled at ``Ts``). A
:class:`StaticPoints` holds measured steady states (ū_i, ȳ_i). Both validate at
construction, so everything downstream may assume finite, 1-D, equally long
arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._validation import as_1d_finite, warn

__all__ = ["Record", "StaticPoints", "StaticRangeWarning", "warn_static_range"]


@dataclass(frozen=True)
class Record:
    """One dynamic experiment: input ``u`` and output ``y`` sampled every ``Ts`` seconds.

    Parameters
    ----------
    u : array_like, shape (N,)
        Input samples (engineering units, e.g. rpm).
    y : array_like, shape (N,)
        Output samples (engineering units, e.g. mlc).
    Ts : float, optional
        Sampling period in seconds (default 1.0).
    name : str, optional
        A label used in messages and tables.
    units : tuple of str, optional
        Units of ``(u, y)``, for display only.
    """

    u: np.ndarray
    y: np.ndarray
    Ts: float = 1.0
    name: str = "record"
    units: tuple[str, str] = ("", "")

    def __post_init__(self) -> None:
        u = as_1d_finite(self.u, f"{self.name}: u")
        y = as_1d_finite(self.y, f"{self.name}: y")
        if u.shape != y.shape:
            raise ValueError(f"{self.name}: u and y must have the same length, got {u.size} and {y.size}")
        if not (np.isfinite(self.Ts) and self.Ts > 0):
            raise ValueError(f"{self.name}: Ts must be a positive number of seconds, got {self.Ts}")
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "y", y)

    def __len__(self) -> int:
        return int(self.u.size)

    def __repr__(self) -> str:
        uu, yu = (f" {x}" if x else "" for x in self.units)
        return (f"Record({self.name!r}: {len(self)} samples, Ts = {self.Ts:g} s, "
                f"u in [{self.u.min():.4g}, {self.u.max():.4g}]{uu}, y in [{self.y.min():.4g}, {self.y.max():.4g}]{yu})")

    @property
    def t(self) -> np.ndarray:
        """Time stamps in seconds, shape (N,), starting at 0."""
        return np.arange(len(self)) * self.Ts

    def slice(self, start: int | None = None, stop: int | None = None, name: str | None = None) -> "Record":
        """Return the samples ``start:stop`` as a new record."""
        return Record(self.u[start:stop], self.y[start:stop], self.Ts, name or self.name, self.units)

    def require_length(self, max_lag: int) -> None:
        """Raise ``ValueError`` unless the record has more than ``max_lag`` samples."""
        if len(self) < max_lag + 1:
            raise ValueError(
                f"{self.name}: record has {len(self)} samples, fewer than max lag + 1 = {max_lag + 1}"
            )


@dataclass(frozen=True)
class StaticPoints:
    """Measured steady states: at constant input ``ubar[i]`` the output settled at ``ybar[i]``.

    Parameters
    ----------
    ubar : array_like, shape (M,)
        Constant input levels (engineering units), all distinct.
    ybar : array_like, shape (M,)
        Settled output at each level.
    name : str, optional
        A label used in messages.
    """

    ubar: np.ndarray
    ybar: np.ndarray
    name: str = "static points"

    def __post_init__(self) -> None:
        u = as_1d_finite(self.ubar, f"{self.name}: ubar")
        y = as_1d_finite(self.ybar, f"{self.name}: ybar")
        if u.shape != y.shape:
            raise ValueError(f"{self.name}: ubar and ybar must have the same length, got {u.size} and {y.size}")
        if u.size == 0:
            raise ValueError(f"{self.name}: no static points")
        uniq, counts = np.unique(u, return_counts=True)
        if (counts > 1).any():
            raise ValueError(f"{self.name}: duplicated ubar value(s) {uniq[counts > 1].tolist()}")
        object.__setattr__(self, "ubar", u)
        object.__setattr__(self, "ybar", y)

    def __len__(self) -> int:
        return int(self.ubar.size)

    def __repr__(self) -> str:
        return (f"StaticPoints({self.name!r}: {len(self)} points, ū in [{self.ubar.min():.4g}, {self.ubar.max():.4g}], "
                f"ȳ in [{self.ybar.min():.4g}, {self.ybar.max():.4g}])")


@dataclass(frozen=True)
class Dataset:
    """A named bundle: identification and validation records plus static points.

    Attributes
    ----------
    ident, valid : Record
        Identification and validation records.
    static : StaticPoints or None
        Measured steady states, if any.
    description : str
        Where the data come from, in plain words.
    extra : dict
        Anything else a loader wants to expose (e.g. a theoretical static curve).
    """

    ident: Record
    valid: Record
    static: StaticPoints | None = None
    description: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def Ts(self) -> float:
        """Sampling period in seconds."""
        return self.ident.Ts

    def __repr__(self) -> str:
        st = "no static points" if self.static is None else f"static={self.static!r}"
        return f"Dataset(ident={self.ident!r}, valid={self.valid!r}, {st})"


__all__.append("Dataset")


def as_records(data: object) -> list[Record]:
    """The records an estimator works on, as a non-empty list, or ``ValueError``.

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        A Dataset stands for its identification record.
    """
    if isinstance(data, Dataset):
        return [data.ident]
    if isinstance(data, Record):
        return [data]
    if isinstance(data, (str, bytes)) or not hasattr(data, "__iter__"):
        raise ValueError(f"data must be a Record, a Dataset or a sequence of Records, got {type(data).__name__}")
    recs = list(data)  # type: ignore[call-overload]
    if not recs:
        raise ValueError("no records given")
    for r in recs:
        if not isinstance(r, Record):
            raise ValueError(f"data must be a Record, a Dataset or a sequence of Records, got an element of type {type(r).__name__}")
    return recs


__all__.append("as_records")


class StaticRangeWarning(UserWarning):
    """Static points lie outside the input range of the dynamic records (said once per call).

    Not an error: static knowledge where the dynamic data do not reach is what gray-box
    identification is for. The warning names the points so that a units mix-up is visible.
    """


def warn_static_range(ubar: np.ndarray, records: list[Record], what: str = "static points") -> None:
    """Warn once, in words, which static ū lie outside the dynamic records' input range."""
    ub = np.unique(np.atleast_1d(np.asarray(ubar, float)))
    lo = min(float(r.u.min()) for r in records)
    hi = max(float(r.u.max()) for r in records)
    tol = 1e-9 * max(abs(lo), abs(hi), 1.0)
    out = ub[(ub < lo - tol) | (ub > hi + tol)]
    if out.size:
        warn(
            f"{what}: ū = {np.round(out, 6).tolist()} lie outside the input range [{lo:.6g}, {hi:.6g}] of the dynamic "
            "records; the model is extrapolated there by the static information (if the points and the records "
            "should overlap, check their units)", StaticRangeWarning)
