"""Measured data as immutable values: dynamic records and static points.

A :class:`Record` is one experiment (input and output sampled at ``Ts``). A
:class:`StaticPoints` holds measured steady states (ū_i, ȳ_i). Both validate at
construction, so everything downstream may assume finite, 1-D, equally long
arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Record", "StaticPoints", "as_1d_finite", "frozen"]


def frozen(a: object, dtype: type = float) -> np.ndarray:
    """A read-only copy of ``a``: how every immutable value in graybox stores its arrays."""
    x = np.array(a, dtype=dtype, copy=True)
    x.setflags(write=False)
    return x


def as_1d_finite(x: object, name: str) -> np.ndarray:
    """Return ``x`` as a read-only 1-D float64 array, or raise ``ValueError``.

    Parameters
    ----------
    x : array_like
        The values.
    name : str
        What ``x`` is, used in error messages (e.g. ``"u"``).
    """
    a = np.array(x, dtype=float, copy=True)
    if a.ndim == 2 and 1 in a.shape:
        raise ValueError(f"{name} must be 1-D, got shape {a.shape}; pass a flat array (e.g. x.ravel())")
    if a.ndim != 1:
        raise ValueError(f"{name} must be 1-D, got {a.ndim}-D with shape {a.shape}")
    bad = ~np.isfinite(a)
    if bad.any():
        idx = np.flatnonzero(bad)
        raise ValueError(
            f"{name} has {idx.size} non-finite value(s) (NaN or inf), first at index {idx[0]}"
        )
    a.setflags(write=False)
    return a


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


__all__.append("Dataset")


def as_records(data: object, accept_dataset: bool = True) -> list[Record]:
    """The records an estimator works on, as a non-empty list, or ``ValueError``.

    Parameters
    ----------
    data : Record, Dataset or sequence of Record
        A Dataset stands for its identification record.
    accept_dataset : bool
        When False a Dataset is refused (for functions where using ``ident`` silently could
        surprise: the message says to pass ``data.ident``).
    """
    if isinstance(data, Dataset):
        if not accept_dataset:
            raise ValueError("pass the identification record (e.g. data.ident), not the whole Dataset")
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
