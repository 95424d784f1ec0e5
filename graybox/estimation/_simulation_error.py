"""The simulation-error (SE) bi-objective, eq. (13): min λ1 J_S(θ) + λ2 J_SF(θ).

Two solvers share one problem definition (:class:`SEProblem`):

- :func:`ga_front` — the paper's genetic algorithm, faithfully: real-coded, stochastic
  universal sampling, heuristic crossover (ratio 1.2, probability 0.9), Gaussian mutation
  (probability 0.1, standard deviation 5 % of the gene), population 200, elitism; one run per
  λ1 from λ1 = 1 down, each seeded with the previous run's best plus random individuals whose
  θ is least squares on 30 randomly chosen samples.
- :func:`gradient_front` — beyond the paper: ``scipy.optimize.least_squares`` on the stacked
  residuals [√(λ1/N) e_sim, √(λ2/N_SF) e_SF] with the Jacobian from the forward sensitivity
  recursion of the compiled kernel, streamed through a QR factorisation so that the solver sees
  n + 1 residuals instead of N (cost linear in N); continued along the λ sweep, with a multi-start
  ("trf" and "dogbox" from every feasible start) wherever the sweep has to restart.

Beyond the paper, both solvers take a stability margin (every local linear model along the records
and at the static points keeps its spectral radius ≤ 1 − margin: :mod:`._local_models`; a θ outside
it is a wall, and a start outside it is pulled in by shrinking its output feedback) and a ridge
towards least squares, through :class:`SEProblem`. Without a margin the gradient members on the
bundled plant buy identification error with near-unit roots that follow the record's drift.
:func:`graybox.estimation._output_error.output_error` is the problem at λ1 = 1 without static points.

:func:`se_pareto` runs either and returns a :class:`graybox.ParetoSet` whose J's come
from the shared evaluator. A λ whose fit fails (no feasible start; no individual with a finite
cost) stays in the set as a failed member with the reason, and the sweep goes on. Long sweeps show
a progress bar, write a checkpoint after each λ (failed members included) and resume from it; a
checkpoint written for another problem is refused, one written by another graybox version (whose
algorithm may differ) is started over with a warning naming both versions.

Inside the optimisers J_S is computed by the fused batch kernel (same definition as :func:`graybox.js`;
for a structure closed under shifts whose inputs all move over the records, on the centred signals with
the centred parameters, the same errors, so that whether a candidate diverges does not depend on the
output's zero: :meth:`SEProblem.js`) and J_SF by the package's one static definition
(:func:`graybox.static._analysis.reached_equilibria`; for such a structure, of the centred model at the centred
static points, the same errors: :meth:`SEProblem.static_errors`): at each static point the equilibrium a free run
at constant ū_i from the measured ȳ_i settles on; where it settles on none the cost is infinite — a
model does not settle on an unstable equilibrium, nor on a stable one whose basin does not hold ȳ_i, so
matching the static points there would be a false gain. The reported front is re-evaluated by the shared
evaluator, which uses the same definition.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import warnings
import zipfile
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Iterable, Literal, Mapping, Sequence, TypeVar

import numpy as np
from scipy.linalg.lapack import dgeqrf

from ._prediction_error import identified_by, pe_members, static_matrices
from ..core._simulation_kernels import (
    batch_sse,
    encode,
    free_run_sensitivity,
    free_run_sensitivity_blocks,
    input_products,
    record_inputs,
    simulate_one,
)
from ..core._least_squares import (binary_scaled, check_rows, column_scales, one_blas_thread, output_scale,
                                   refuse_beyond_float_range, refuse_parameter_scales, scaled_lstsq, scaled_points,
                                   scaled_theta, unscaled_rss, unscaled_theta)
from ..models._coerce import as_structure, records_of, static_points
from ._pareto import ParetoSet
from ..core._progress import progress_bar
from ..core._records import (
    Dataset,
    Record,
    StaticPoints,
    StaticRangeWarning,
    as_records,
    check_compatible,
    static_hint,
    warn_static_range,
)
from ..core._regressors import stacked_regressors
from ..core._gram import is_dask_data
from ..selection._centring import centred_data, is_closed, is_held, shift_map, signal_offsets
from ..static._analysis import reached_equilibria, static_theta_gradient
from ..static._surface_analysis import reached_surface, surface_theta_gradient
from ..static._curves import StaticCurve
from ..static._surfaces import StaticSurface
from ..core._files import folder_now, sweep_written_beside, write_atomically, written_path
from ..core._terms import Structure, default_input_names
from ..core._validation import (FrozenMap, check_choice, check_count, check_int, check_lambdas, check_real, check_seed, check_sequence,
                                short_value,
                                check_path, check_theta, frozen, locked, warn)
from ._local_models import (SLOW_FACTOR, LocalModels, SlowModeWarning, check_margin, record_points, slow_margin,
                            within_at)
from ..core._reprs import point_texts, short_repr
from ..core._version import graybox_version

__all__ = ["SEProblem", "GAOptions", "SEFront", "ga_front", "gradient_front", "se_pareto", "SE_LAMBDAS", "refit_if_slow"]

#: The paper's SE sweep (Section IV-C), the default ``lambdas``: 100 λ1 in logspace(−2, 0).
SE_LAMBDAS = locked(np.logspace(-2, 0, 100))


class SEProblem:
    """The data of one SE problem: structure, identification record(s), static points, margin.

    Parameters
    ----------
    structure : Structure
        Process terms.
    records : Record or sequence of Record
        Identification data. Each record is run freely from its own first max-lag samples (a
        free run never straddles two experiments) and J_S is the mean over all their samples.
    static : StaticPoints or None
        Measured steady states. None: a pure simulation-error (output-error) problem, whose only
        weight is λ1 = 1.
    margin : float in [0, 1) or None
        Stability margin: a θ is feasible only where every local linear model keeps its spectral
        radius ≤ 1 − margin, at up to :data:`~graybox.estimation._local_models.RECORD_POINTS`
        samples (u(k), y(k)) along the records and, where the weight on the static points is
        positive, at the equilibria reached at the static points (:mod:`._local_models`).
        None: no margin (stability at the static points is still required where J_SF counts).
    ridge : float >= 0
        Regularisation towards least squares: γ · mean_j (s_j (θ_j − θ_LS,j))² is added to the
        cost, with s_j the RMS of regressor j (so each term is a change of that term's contribution
        to ŷ, in output units, and the cost stays independent of units). For a structure closed under
        shifts θ_j and s_j are those of the centred signals (:meth:`_centre_basis`), so the ridge is also
        the same wherever the units' zeros are. 0: none.
    scored_only : bool
        A problem whose records only score θ's fitted elsewhere (a choosing record's J_S): no
        more regression rows than parameters are needed.
    """

    def __init__(self, structure: Structure, records: Record | Sequence[Record], static: StaticPoints | None,
                 *, margin: float | None = None, ridge: float = 0.0, scored_only: bool = False):
        self.records = as_records(records)
        if static is not None and not isinstance(static, StaticPoints):
            raise TypeError(f"static must be StaticPoints or None, got {type(static).__name__}{static_hint(static)}")
        structure = structure if isinstance(structure, Structure) else Structure(structure)
        if any(t.is_noise for t in structure):
            structure = structure.process
        if not len(structure):
            raise ValueError("the structure has no process terms to estimate")
        self.structure = structure
        self.record = self.records[0]
        r0 = self.record
        self.margin = check_margin(margin)
        if self.margin == "auto":
            raise ValueError("SEProblem takes a margin in [0, 1) or None; margin='auto' is resolved by the estimators "
                             "(se_pareto, se_dsf, output_error)")
        if static is not None and (static.n_inputs != r0.n_inputs or (r0.n_inputs > 1
                                                                       and static.input_names != r0.input_names)):
            check_compatible(r0, static)
        # several inputs: the static part lives on the surface ȳ(ū_1, …, ū_m), columns in the records' order
        self.surface_inputs = r0.input_names if (r0.n_inputs > 1 or len(structure.input_names) > 1) else None
        self.static = static
        self.L = structure.max_lag
        self.code = c = encode(structure)
        # input products are fixed across the whole sweep: computed once per record (those of the records as given
        # only when read, :attr:`U`, where the free runs are made on the centred records)
        self._U: list[np.ndarray] | None = None
        self.psi, self.target = stacked_regressors(structure, self.records)
        if not scored_only:
            check_rows(self.psi.shape[0], len(structure))  # as els, cls and pe: no error left to fit
        self.n_dyn = self.target.size
        self.scale = column_scales(self.psi)  # θ = z / scale keeps the optimisers well conditioned
        # the output's spread (output units): least_squares' gradient test is absolute, and the
        # gradient of these residuals is in output units, so its tolerance is scaled by this
        self.y_scale = output_scale(self.target)
        self._memo: dict = {}  # least squares and PE solutions, shared with with_margin's copies
        self._static_memo: tuple[bytes, np.ndarray, bool] | None = None  # (θ, ȳ, every point evaluated)
        self._centre_basis(scored_only)
        self.ridge = check_real(ridge, "ridge", low=0.0)
        self.ridge_ref = self.ls_z() if self.ridge > 0 else None
        self.local = LocalModels(structure, *record_points(structure, self.records)) if self.margin is not None \
            else None
        # the static points' ū as the local models read them: on a surface, columns in the kernel's input order
        self.margin_ubar = None if static is None else static.ubar
        if static is not None and self.surface_inputs is not None:
            mu = static.ubar[:, [static.input_names.index(n) for n in c.input_names]]
            self.margin_ubar = mu[:, 0] if mu.shape[1] == 1 else mu

    # -- the optimisers' coordinates ----------------------------------------------------
    def _centre_basis(self, scored_only: bool = False) -> None:
        """The coordinates z the optimisers move in (:meth:`to_z`, :meth:`from_z`).

        By default z = θ ⊙ s, s the RMS of each raw regressor. For a structure closed under shifts (every
        divisor of every term present, as ``centre=True`` returns) whose inputs all move over the records, z is
        instead the parameters of the same model on the signals minus their means over the records, times the RMS
        of each centred regressor: θ = A (z / s_c) + t (:func:`~graybox.selection._centring.shift_map`).
        An offset of y or of an input leaves the centred signals, hence the whole problem in z (starts,
        steps, trust regions, tolerances, the ridge, the GA's mutations), as it was, and a unit's scale
        is taken up by s_c: the fit is the same model whatever the units' zeros and scales. The raw
        coordinates are not: a trust-region step, a ridge or a mutation of the raw constant or u(k−1)
        means something else when u moves by 1e4, and the fits differed by up to 35 % in J_S. Records that
        identify θ only with the static points (a two-level input's u(k−1)², which they cannot tell from
        u(k−1) and 1) are centred too: the GA's random least-squares seeds are then the minimum-norm solutions
        in z, the same model at every offset. An input held over the records is not centred on its mean there (its
        centred terms would be round-off of zero, whose RMS would scale z by nothing the units set) but by
        :meth:`_held_offset`, from its static points, the only ones to tell its terms apart (the GA's fronts moved
        by 0.5 % of y's spread at y + 50, and by 2.4 % with the held input + 3, while a held input kept the
        problem raw or at its own level).
        """
        self.z_map = self.z_inv = self.z_shift = self.offsets = None
        self.static_run = None  # the static points (ū, ȳ) the equilibria are solved at, with the runs' θ (None: raw)
        self.z_psi, self.z_target = self.psi / self.scale, self.target
        # the records the optimisers' free runs are made on, their input products, and the divisor of z that gives
        # the parameters of those runs (None: θ, on the records as given)
        self.run_records, self.run_scale = self.records, None
        # a problem that only scores θ's fitted elsewhere (a choosing record) never moves in z: no centred basis
        if scored_only or is_dask_data(self.records) or not is_closed(self.structure):
            self.run_U = self.U
            return
        held = self._held_inputs()
        off = {k: (self._held_offset(k) if k in held else v) for k, v in signal_offsets(self.records).items()}
        A, t = shift_map(self.structure, off)
        Ainv = shift_map(self.structure, {k: -v for k, v in off.items()})[0]
        centred = centred_data(self.records, off, keep=held)
        psi_c, target_c = stacked_regressors(self.structure, centred)
        s_c = column_scales(psi_c)
        # the free runs too are made on the centred signals, with the centred parameters z / s_c: the same run less
        # the output's offset, so that whether a candidate diverges (the default bound, 10⁶ times the run's own size)
        # does not depend on where the output's zero is. On the raw signals a run that left a 2e7 bound around
        # y ≈ 20 stayed inside the 1e10 one of y + 1e4: the GA then ranked other individuals and its fronts at
        # another offset differed (J_SF up to 15 times)
        self.run_records, self.run_scale = centred, s_c
        self.run_U = self._products(centred)
        if self.static is not None:
            # the equilibria too are solved for the centred model at the centred points: on the raw ones the
            # polynomial carries the offsets' powers (a constant of 1e8 at y + 1e4), and the weighted cost of one z
            # came out 8e-9 (y + 1e4) to 9e-7 (y + 1e5) off relative where J_S is 1e-12 off, the gradient front's
            # costs 7e-7 at y + 1e5 (now 1e-11)
            ub = self.static.ubar
            names = self.records[0].input_names
            ub_c = ub - (off[names[0]] if ub.ndim == 1 else np.array([off[n] for n in names]))
            self.static_run = (ub_c, self.static.ybar - off["y"])
        self.offsets, self.z_shift = off, t
        self.z_map = A / s_c  # θ = z_map @ z + z_shift
        self.z_inv = s_c[:, None] * Ainv  # z = z_inv @ (θ − z_shift)
        psi_c /= s_c  # in place: one more N × n array, not two
        self.z_psi, self.z_target = psi_c, target_c  # ψ θ − y = z_psi z − z_target, without cancellation

    @property
    def U(self) -> list[np.ndarray]:
        """The input products of each record as given (:func:`~graybox.core._simulation_kernels.input_products`),
        made once when first read. A centred problem's optimisers run on :attr:`run_U` and never read these (only
        :meth:`residuals` does, for se_dsf and the covariances): holding both was a second N × n array through
        every sweep (+31 MB at N = 200000, n = 20)."""
        if self._U is None:
            self._U = self._products(self.records)
        return self._U

    def _products(self, records: Sequence[Record]) -> list[np.ndarray]:
        """Each record's input products for the structure's kernels (fixed across a sweep)."""
        c = self.code
        return [input_products(c.fptr, c.fsig, c.flag, c.fpow, record_inputs(r, c.input_names), self.L) for r in records]

    def _held_offset(self, name: str) -> float:
        """Where an input held over the records is centred: its held level less the RMS distance of its static
        points' levels from it, so that on the records it is that distance (a constant the static points, the only
        ones to tell its terms apart, scale with the input's unit) whatever the input's zero or unit. Without
        static points, or with every point at the held level to round-off (its terms then told apart by nothing):
        0, the input left at its level."""
        if self.static is None:
            return 0.0
        levels = self.static.ubar if self.static.ubar.ndim == 1 else \
            self.static.ubar[:, list(self.static.input_names).index(name)]
        held = float(record_inputs(self.records[0], [name]).reshape(-1)[0])
        if is_held(np.append(levels, held)):
            return 0.0
        return held - float(np.sqrt(np.mean((levels - held) ** 2)))

    def _held_inputs(self) -> frozenset:
        """The inputs of the structure that hold one value over every record (to round-off: the centring's one
        rule, :func:`~graybox.selection._centring.is_held`)."""
        names = self.code.input_names
        if not names:
            return frozenset()
        us = np.concatenate([record_inputs(r, names).reshape(len(r.y), -1) for r in self.records])
        return frozenset(n for i, n in enumerate(names) if is_held(us[:, i]))

    def to_z(self, thetas: np.ndarray) -> np.ndarray:
        """The optimisers' coordinates of θ (shape (n,) or (P, n)): see :meth:`_centre_basis`."""
        th = np.asarray(thetas, float)
        if self.z_map is None:
            return th * self.scale
        return (th - self.z_shift) @ self.z_inv.T

    def from_z(self, z: np.ndarray) -> np.ndarray:
        """θ (engineering units) of the optimisers' coordinates z, shape (n,) or (P, n)."""
        z = np.asarray(z, float)
        if self.z_map is None:
            return z / self.scale
        return z @ self.z_map.T + self.z_shift

    def run_theta(self, thetas: np.ndarray, z: np.ndarray | None = None) -> np.ndarray:
        """The parameters of the optimisers' free runs on :attr:`run_records`: θ, or for a centred problem the
        centred parameters z / s_c (from ``z`` when given: no round trip through raw θ)."""
        if self.run_scale is None:
            return np.asarray(thetas, float)
        return (self.to_z(thetas) if z is None else np.asarray(z, float)) / self.run_scale

    def jac_z(self, J: np.ndarray, w: float | np.floating) -> np.ndarray:
        """``J`` (rows of ∂r/∂θ) as ∂r/∂z, divided by ``w``."""
        if self.z_map is None:
            return J / (w * self.scale)
        return (J @ self.z_map) / w

    def z_lstsq(self, rows: np.ndarray | None = None, cols: np.ndarray | None = None,
                fixed: np.ndarray | None = None) -> np.ndarray:
        """Least squares of the regression in z on ``rows`` (all: None), solving for the ``cols`` of z (all: None)
        with the others held at ``fixed`` (z coordinates); returns those coordinates."""
        A = self.z_psi if rows is None else self.z_psi[rows]
        b = self.z_target if rows is None else self.z_target[rows]
        if cols is not None:
            b = b - A[:, ~cols] @ fixed[~cols]
            A = A[:, cols]
        return np.linalg.lstsq(A, b, rcond=None)[0]

    def with_margin(self, margin: float | None) -> SEProblem:
        """The same problem (structure, records, static points, ridge) with another margin; what does not
        depend on the margin (the least-squares and PE solutions) is computed once for both."""
        other = SEProblem(self.structure, self.records, self.static, margin=margin, ridge=self.ridge)
        other._memo = self._memo
        return other

    def fingerprint(self, *, shapes: bool = True) -> str:
        """A hash of everything that defines the problem (for checkpoints): each array with its dtype and shape, and
        the count of records, so that the same numbers cut otherwise (one record of 6 samples or two of 3, a record
        or static points) are another problem. ``shapes=False``: the hash of the versions that left them out, which
        a checkpoint they wrote holds (recognised, and started over, as one of another version)."""
        h = hashlib.sha256()
        h.update(str(self.structure).encode())
        static = [] if self.static is None else [self.static.ubar, self.static.ybar]
        if shapes:
            h.update(f"records={len(self.records)}".encode())
        for a in [x for r in self.records for x in (r.u, r.y)] + static:
            a = np.ascontiguousarray(a)
            if shapes:
                h.update(f"{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        # which column is which input is :meth:`input_names`', beside it in a checkpoint
        if self.margin is not None:  # a checkpoint without a margin stays valid
            h.update(f"margin={self.margin!r}".encode())
        if self.ridge > 0:
            h.update(f"ridge={self.ridge!r}".encode())
        return h.hexdigest()[:16]

    # -- the stability margin ----------------------------------------------------------
    def input_names(self) -> list[list[str]] | None:
        """Which column is which input, for checkpoints: the input names of each record and of the static points,
        or None where every one is the default u1 … um (or one input, named by the structure).

        The same arrays with the inputs named in another order are another problem (a file's columns mislabelled,
        then the names put right, resumed the mislabelled sweep's members). Kept beside :meth:`fingerprint`, not in
        it: a checkpoint written before they were recorded is then refused by this version naming them, and started
        over by another version as any checkpoint of another version is; the default names' checkpoints stay valid.
        """
        every = [r.input_names for r in self.records] + ([] if self.static is None else [self.static.input_names])
        if all(len(n) < 2 or tuple(n) == default_input_names(len(n)) for n in every):
            return None
        return [list(n) for n in every]

    def within_margin(self, thetas: np.ndarray, static_outputs: np.ndarray | None = None) -> np.ndarray:
        """Does each row keep every local model's spectral radius ≤ 1 − margin? Shape (P,).

        Checked at the record points and, when ``static_outputs`` (P, M) is given, at the
        equilibria (ū_i, ȳ_i) of each row (a non-finite ȳ_i is skipped: J_SF handles it).
        Always True without a margin.
        """
        th = np.atleast_2d(np.asarray(thetas, float))
        if self.margin is None:
            return np.ones(th.shape[0], bool)
        ok = self.local.within(th, self.margin)
        if static_outputs is not None and ok.any():
            ok[ok] = within_at(self.structure, th[ok], self.margin_ubar, np.atleast_2d(static_outputs)[ok], self.margin)
        return ok

    def slow_modes(self, thetas: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """Each row's largest local spectral radius along the records, whether it is slow, and ρ_LS.

        A row is slow where 1 − ρ < (1 − ρ_LS) / :data:`SLOW_FACTOR`, ρ_LS the least-squares model's
        (never where ρ_LS ≥ 1: no reference). Returns (radii (K,), slow (K,) bool, ρ_LS); a NaN row
        has radius NaN and is not slow.
        """
        th = np.atleast_2d(np.asarray(thetas, float))
        radii = np.array([self.radius(t) if np.all(np.isfinite(t)) else np.nan for t in th])
        rho_ls = self.radius(self.ls_theta())
        m = slow_margin(rho_ls)
        with np.errstate(invalid="ignore"):
            slow = np.zeros(len(th), bool) if m is None else (1.0 - radii) < m
        return radii, slow, rho_ls

    def warn_slow(self, thetas: np.ndarray, what: str, auto: bool = False, kept: str | None = None) -> np.ndarray:
        """:class:`SlowModeWarning` when some row of ``thetas`` is slow (:meth:`slow_modes`) and the
        problem has no margin; returns the rows' radii, shape (K,). ``auto``: the rows are what is
        left slow after ``margin="auto"`` tried to refit them inside the margin; ``kept``: why they
        were kept (default: no fit inside the margin was found)."""
        radii, slow, rho_ls = self.slow_modes(thetas)
        if self.margin is None and slow.any():
            k = int(slow.sum())
            who = what if len(radii) == 1 else f"{what}: {k} of {len(radii)}"
            warn(f"{who} {'has' if k == 1 else 'have'} local models along the identification "
                 f"record with spectral radius up to {np.nanmax(radii[slow]):.6g}, against the least-squares model's "
                 f"{rho_ls:.6g}: modes over {SLOW_FACTOR:g} times slower than its slowest, or unstable. Such "
                 "near-integrators follow the record's slow drift and err on new records; "
                 + (kept or "no fit inside that factor (margin='auto') was found for them: try another structure"
                    if auto else "margin='auto' refits them inside that factor")
                 + " (BENCHMARKS.md, 'A slow-mode check')", SlowModeWarning)
        return radii

    def radius(self, theta: np.ndarray) -> float:
        """The largest spectral radius of θ's local models at the record points (dimensionless)."""
        local = self.local if self.local is not None else LocalModels(self.structure,
                                                                      *record_points(self.structure, self.records))
        r = local.radius(theta)
        return float(r.max()) if r.size else 0.0

    def diverges(self, theta: np.ndarray) -> bool:
        """Whether θ's free run on some record leaves :func:`graybox.simulate`'s default bound
        (10⁶ × the run's own scale; for a centred problem, of the run on the centred signals, :meth:`js`):
        :meth:`js` is inf there."""
        return not np.isfinite(self.js(np.asarray(theta, float)[None, :])[0])

    # -- objectives -------------------------------------------------------------------
    def js(self, thetas: np.ndarray, threads: int = 1, *, bounded: bool = True, z: np.ndarray | None = None
           ) -> np.ndarray:
        """J_S of each row of ``thetas``, shape (P,): inf where a free run leaves :func:`graybox.simulate`'s
        default bound (as the optimisers' costs take it: a slowly diverging run, y(k) = 1.01 y(k−1) + … over
        3000 samples, has a huge finite sum of squares that would still beat an infinite cost). ``bounded=False``:
        inf only where a run overflows. ``z``: the rows' optimiser coordinates, when the caller has them.

        The runs are made on :attr:`run_records`: for a centred problem the centred signals, with the same errors
        (a finite J_S is :func:`graybox.js`'s to round-off), but judged against the bound of the centred run (10⁶
        × its own scale), which does not move with the output's zero. :func:`graybox.js` of the model on the
        record as given judges against the raw run's, whose scale holds the signals' levels: far from zero it is
        wider, and a θ inf here can have a finite :func:`graybox.js` there."""
        th = np.atleast_2d(self.run_theta(thetas, z))
        sse = sum(batch_sse(self.code, th, record_inputs(r, self.code.input_names), r.y, self.L, threads, U,
                            bounded=bounded) for r, U in zip(self.run_records, self.run_U))
        js = sse / self.n_dyn
        return np.where(np.isfinite(js), js, np.inf)

    def static_outputs(self, thetas: np.ndarray, *, scored: bool = False) -> np.ndarray:
        """The equilibrium each row reaches from each measured ȳ_i (NaN where none), shape (P, M).

        :func:`graybox.static._analysis.reached_equilibria` with y0 = ȳ_i: the definition of J_SF.
        ``scored``: only J_SF and the residuals it is made of are asked, which are infinite once one point
        is not reached: a row's runs stop there (``until_failure``), so where a row misses a point its
        other points may be NaN too; a row that reaches every point is exactly as without.
        :meth:`static_errors` plus the measured ȳ_i (for a centred problem the centred model's equilibria, shifted
        back by the output's offset).
        """
        return self.static_errors(thetas, scored=scored) + self.static.ybar

    def static_errors(self, thetas: np.ndarray, *, scored: bool = False, z: np.ndarray | None = None) -> np.ndarray:
        """ȳ_model − ȳ_i at each static point (the residuals of J_SF; NaN where nothing is reached), shape (P, M):
        :meth:`static_outputs` less the measured ȳ_i, ``scored`` as there. For a centred problem (:meth:`_centre_basis`)
        the equilibria are those of the centred model (:meth:`run_theta`) at the centred points, the same
        equilibria less the output's offset, so that the errors do not depend on where the units' zeros are (from
        ``z``, the rows' optimiser coordinates, when given: raw θ holds the offsets' powers, and the round trip
        through it left J_SF 1e-8 off relative at y + 1e4)."""
        if self.static is None:
            raise ValueError("this problem has no static points")
        thetas = np.atleast_2d(thetas)
        # a least-squares solver takes the Jacobian at the point whose residuals it has just
        # evaluated: the last single θ's equilibria are kept (read-only), not solved again. Keyed by z too: a centred
        # problem solves them from z, and two z of one θ gave two answers 4e-16 apart, so that the next λ's start read
        # the last fit's and a sweep resumed from its checkpoint ended elsewhere than the uninterrupted one
        key = thetas.tobytes() + (b"" if z is None else b"z" + np.asarray(z, float).tobytes()) \
            if thetas.shape[0] == 1 else None
        memo = self._static_memo
        if key is not None and memo is not None and memo[0] == key and (scored or memo[2]):
            return memo[1]
        if self.static_run is None:
            th, (ub, yb0) = thetas, (self.static.ubar, self.static.ybar)
        else:
            th, (ub, yb0) = np.atleast_2d(self.run_theta(thetas, z)), self.static_run
        if self.surface_inputs is not None:
            yb = reached_surface(self.structure, th, ub, yb0, inputs=self.surface_inputs, until_failure=scored).ybar
        else:
            yb = reached_equilibria(self.structure, th, ub, yb0, until_failure=scored).ybar
        # a scored row with a point missed may have points left unevaluated: not the full answer
        complete = not scored or bool(np.all(np.isfinite(yb)))
        err = yb - yb0
        if key is not None:
            err.flags.writeable = False
            self._static_memo = (key, err, complete)
        return err

    def static_theta_gradient(self, theta: np.ndarray, ybar: np.ndarray) -> np.ndarray:
        """∂ȳ_i/∂θ at the static points' equilibria ``ybar`` (implicit differentiation), shape (M, n)."""
        if self.surface_inputs is not None:
            return surface_theta_gradient(self.structure, theta, self.static.ubar, ybar, inputs=self.surface_inputs)
        return static_theta_gradient(self.structure, theta, self.static.ubar, ybar)

    def jsf(self, thetas: np.ndarray) -> np.ndarray:
        """J_SF of each row (the equilibrium reached from the measured ȳ; inf where none), shape (P,)."""
        e = self.static_errors(thetas, scored=True)
        with np.errstate(all="ignore"):
            v = np.mean(e ** 2, axis=1)
        return np.where(np.isfinite(v), v, np.inf)

    def cost(self, thetas: np.ndarray, lam1: float, threads: int = 1, *, z: np.ndarray | None = None) -> np.ndarray:
        """λ1 J_S + λ2 J_SF with λ2 = 1 − λ1, shape (P,); inf for a diverging member. ``z``: the rows'
        optimiser coordinates, when the caller has them."""
        js = self.js(thetas, threads, z=z)
        c = lam1 * js
        yb = None
        if lam1 < 1.0:
            e = self.static_errors(thetas, scored=True, z=z)
            yb = e + self.static.ybar
            with np.errstate(all="ignore"):
                jsf = np.mean(e ** 2, axis=1)
            c = c + (1.0 - lam1) * np.where(np.isfinite(jsf), jsf, np.inf)
        if self.ridge > 0:
            zz = self.to_z(np.atleast_2d(thetas)) if z is None else np.atleast_2d(z)
            c = c + self.ridge * np.mean((zz - self.ridge_ref) ** 2, axis=1)
        c = np.where(np.isfinite(c), c, np.inf)
        if self.margin is not None:
            fin = np.isfinite(c)
            if fin.any():
                th = np.atleast_2d(thetas)
                ok = self.within_margin(th[fin], None if yb is None else yb[fin])
                c[np.flatnonzero(fin)[~ok]] = np.inf
        return c

    def _run_errors(self, th: np.ndarray, records, Us, jacobian: bool) -> tuple[list, list]:
        """Free-run errors ŷ − y of θ ``th`` over ``records`` from sample L on (one array each), and with ``jacobian``
        their sensitivities to θ (``Us``: the records' input arrays the sensitivity recursion takes)."""
        L = self.L
        e, J = [], []
        for rec, U in zip(records, Us):
            if jacobian:
                y, S = free_run_sensitivity(self.code, th, record_inputs(rec, self.code.input_names), rec.y[:L], L, U)
                J.append(S[L:])
            else:
                y = simulate_one(self.code, th, record_inputs(rec, self.code.input_names), rec.y[:L], L, 1e300)
            e.append(y[L:] - rec.y[L:])
        return e, J

    def residuals(self, theta: np.ndarray, *, jacobian: bool = True):
        """Free-run and static residuals of one θ and their Jacobians with respect to θ.

        Unweighted: ``e_dyn = ŷ − y`` over every record's samples L … (shape (N_dyn,)), and
        ``e_static = ȳ_model − ȳ`` at the static points (shape (M,), the equilibrium reached from
        each measured ȳ_i; NaN where none). With ``jacobian`` also ``J_dyn`` (N_dyn, n) by the
        forward sensitivity recursion and ``J_static`` (M, n) by implicit differentiation.
        For covariances and the direct D_SF solver, which need the whole Jacobian; the sweeps
        stream it instead (:func:`_r_factor`).
        """
        th = np.asarray(theta, float)
        e, J = self._run_errors(th, self.records, self.U, jacobian)
        e_static = self.static_errors(th)[0]
        yb = e_static + self.static.ybar
        if not jacobian:
            return np.concatenate(e), e_static, None, None
        with np.errstate(all="ignore"):
            Js = self.static_theta_gradient(th, yb)
        return np.concatenate(e), e_static, np.vstack(J), Js

    def run_residuals(self, z: np.ndarray, *, jacobian: bool = True):
        """:meth:`residuals` of the optimisers' coordinates ``z``, made as the optimisers' runs are, with the
        Jacobians with respect to z: for a centred problem (:meth:`_centre_basis`) the free runs of the centred model
        (:meth:`run_theta`) on :attr:`run_records` and its equilibria at the centred points (:attr:`static_run`), the
        same residuals without the offsets' powers. Through raw θ at y + 1e6 (a constant of 9e7 for a spread of 4)
        the residuals carried 1e-8 of round-off that moved with z, and se_dsf's steps stopped on it ('no step
        improves') at other points than at y (J_S 1.1e-5 apart, another start named)."""
        z = np.asarray(z, float)
        if self.run_scale is None:
            ed, es, Jd, Js = self.residuals(self.from_z(z), jacobian=jacobian)
            return ed, es, (None if Jd is None else Jd / self.scale), (None if Js is None else Js / self.scale)
        th = z / self.run_scale
        e, J = self._run_errors(th, self.run_records, self.run_U, jacobian)
        ub, yb0 = self.static_run
        if self.surface_inputs is not None:
            yb = reached_surface(self.structure, th[None], ub, yb0, inputs=self.surface_inputs).ybar[0]
        else:
            yb = reached_equilibria(self.structure, th[None], ub, yb0).ybar[0]
        e_static = yb - yb0
        if not jacobian:
            return np.concatenate(e), e_static, None, None
        with np.errstate(all="ignore"):
            Js = (surface_theta_gradient(self.structure, th, ub, yb, inputs=self.surface_inputs)
                  if self.surface_inputs is not None else static_theta_gradient(self.structure, th, ub, yb))
        return np.concatenate(e), e_static, np.vstack(J) / self.run_scale, Js / self.run_scale

    def records_identify(self) -> bool:
        """Whether the records alone identify θ (:func:`~graybox.estimation._prediction_error.identified_by`);
        not where an input is held constant, where the static points must (λ1 < 1)."""
        return self._unidentified(False) is None

    def check_identified(self, lam1: float | None = None) -> None:
        """``ValueError`` (saying what is missing) unless the records, with the static points where they carry
        weight (λ1 < 1; ``None``: wherever they are given), identify θ: the one rule of every estimator
        (:func:`~graybox.estimation._prediction_error.identified_by`)."""
        why = self._unidentified(self.static is not None and (lam1 is None or lam1 < 1.0))
        if why is not None:
            raise ValueError(why)

    def _unidentified(self, weighted: bool) -> str | None:
        """Why θ is not identified by the records (and the static points when ``weighted``), or None (remembered)."""
        key = ("unidentified", weighted)
        if key not in self._memo:
            what = "θ at λ1 = 1 (no weight on the static points)" if self.static is not None and not weighted else "θ"
            # judged on the problem the optimisers solve: for a centred one (:meth:`_centre_basis`) its regression
            # and the static points on the centred signals, the same rank at every offset (on the raw ones a closed
            # quadratic in y(k-1), y(k-2) at y + 1e6 read as rank 6 of 7, and the sweep was refused)
            # in the centred θ (z_psi · s_c), the coordinates of run_points' static rows Q R: the records' rows in z
            # (unit-RMS columns) beside those rows were swamped by them at y in a unit 1e14 times smaller (rank 4 of 5)
            psi = self.psi if self.z_map is None else self.z_psi * self.run_scale
            try:
                identified_by(self.structure, psi, psi.shape[0], points=self.run_points() if weighted else None,
                              inputs=self.record.input_names, what=what)
                self._memo[key] = None
            except ValueError as exc:
                self._memo[key] = str(exc)
        return self._memo[key]

    def run_points(self) -> StaticPoints | None:
        """The static points as the optimisers' runs see them: on the centred signals for a centred problem
        (:attr:`static_run`), else as given."""
        if self.static_run is None:
            return self.static
        return replace(self.static, ubar=self.static_run[0], ybar=self.static_run[1])

    def ls_theta(self) -> np.ndarray:
        """Least-squares (one-step) estimate on all samples (computed once; a copy). Where the records alone
        do not identify θ (an input held constant) but the static points do: the least squares of the
        records' regression and the static rows Q R θ = ȳ of eq. (12), each as a mean square (PE's closed
        form at λ1 = 1/2); neither: ``ValueError`` saying what is missing."""
        if "ls" not in self._memo:
            # a θ below the normal floats in these units (u(k-1)² of u ≈ 1e100, y ≈ 1e-150) became 0 silently
            refuse_parameter_scales(self.structure.terms, self.y_scale, self.scale, prefix="least squares: ")
            if self.records_identify() and self.z_map is not None:
                with np.errstate(over="ignore"):  # a θ beyond the float range (u(k-1)² of u ≈ 1e-100, y ≈ 1e150)
                    th = self.from_z(self.ls_z())
                refuse_beyond_float_range(self.structure.terms, th, prefix="least squares: ")
                self._memo["ls"] = th
            elif self.records_identify():
                self._memo["ls"] = scaled_lstsq(self.psi, self.target)
            else:
                self.check_identified()
                Q, R = static_matrices(self.structure, self.static)
                N, M = self.psi.shape[0], len(self.static)
                self._memo["ls"] = scaled_lstsq(np.vstack([self.psi / np.sqrt(N), (Q @ R) / np.sqrt(M)]),
                                                np.r_[self.target / np.sqrt(N), self.static.ybar / np.sqrt(M)])
        return self._memo["ls"].copy()

    def ls_z(self) -> np.ndarray:
        """:meth:`ls_theta` in the optimisers' coordinates (a copy). Where they are centred and the records
        identify θ, solved there and never taken through raw θ, whose parameters carry the offsets' powers
        (the round trip left the ridge's target 3.5e-10 off at 1e4 spreads, the solve 5e-13)."""
        if self.z_map is None or not self.records_identify():
            return self.to_z(self.ls_theta())
        if "ls_z" not in self._memo:
            self._memo["ls_z"] = scaled_lstsq(self.z_psi, self.z_target)
        return self._memo["ls_z"].copy()

    def random_ls(self, rng: np.random.Generator, count: int, samples: int = 30) -> np.ndarray:
        """``count`` θ's, each least squares on ``samples`` randomly chosen rows (the paper's seeds)."""
        return self.from_z(self.random_z(rng, count, samples))

    def random_z(self, rng: np.random.Generator, count: int, samples: int = 30) -> np.ndarray:
        """:meth:`random_ls` in the optimisers' coordinates, as solved there (the same draws): a centred problem's
        GA seeds its population with these, never through raw θ, which holds the offsets' powers."""
        n = self.psi.shape[0]
        if samples > n:
            raise ValueError(f"GAOptions.random_samples = {samples} (the rows of each random individual's least "
                             f"squares) exceeds the records' {n} regression rows: give "
                             f"options=GAOptions(random_samples=...) of at most {n}")
        out = np.empty((count, self.psi.shape[1]))
        for i in range(count):
            rows = rng.choice(n, size=samples, replace=False)
            out[i] = self.z_lstsq(rows)
        return out


@dataclass(frozen=True)
class GAOptions:
    """Settings of the paper's genetic algorithm (defaults: the paper's, 50 generations).

    Attributes
    ----------
    population : int
        Individuals per generation (paper: 200).
    generations : int
        Generations per λ (the paper does not state it; 50 here). The run stops after this many
        generations, or earlier when the best cost has not improved by a relative 1e-9 for
        ``stall`` generations (``stall=None``: never early).
    crossover_prob, crossover_ratio : float
        Heuristic crossover: with probability 0.9 a pair (better p1, worse p2) gives the children
        p2 + 1.2 (p1 − p2) and p2 + r (p1 − p2) with r ~ U(0, 1); otherwise the parents pass on.
    mutation_prob, mutation_scale : float
        Each gene mutates with probability 0.1 by adding N(0, (0.05 |gene|)²).
    elite : int
        Best individuals copied unchanged into the next generation.
    random_samples : int
        Samples of the identification record in each random individual's least squares (30; at least 1:
        on none, every random individual would be the zero model).
    selective_pressure : float
        Linear ranking pressure in [1, 2] for the fitness that stochastic universal sampling uses.
    stall : int, optional
        Generations without a relative improvement of 1e-9 in the best cost after which a run stops early
        (>= 1; None, the default: never early).
    """

    population: int = 200
    generations: int = 50
    stall: int | None = None
    crossover_prob: float = 0.9
    crossover_ratio: float = 1.2
    mutation_prob: float = 0.1
    mutation_scale: float = 0.05
    elite: int = 1
    random_samples: int = 30
    selective_pressure: float = 2.0

    def __post_init__(self) -> None:
        def put(name: str, v: object) -> None:
            object.__setattr__(self, name, v)

        put("population", check_count(self.population, "GAOptions: population", low=4))
        put("generations", check_int(self.generations, "GAOptions: generations", low=1))
        if self.stall is not None:
            put("stall", check_int(self.stall, "GAOptions: stall", low=1))
        for name in ("crossover_prob", "mutation_prob"):
            put(name, check_real(getattr(self, name), f"GAOptions: {name}", low=0, high=1))
        put("crossover_ratio", check_real(self.crossover_ratio, "GAOptions: crossover_ratio", low=0))
        put("mutation_scale", check_real(self.mutation_scale, "GAOptions: mutation_scale", low=0))
        put("elite", check_int(self.elite, "GAOptions: elite", low=0, high=self.population - 1))
        put("random_samples", check_count(self.random_samples, "GAOptions: random_samples", low=1))
        put("selective_pressure", check_real(self.selective_pressure, "GAOptions: selective_pressure", low=1, high=2))


def _sus(fitness: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Stochastic universal sampling (Baker 1987): n equally spaced pointers, one spin."""
    cum = np.cumsum(fitness)
    step = cum[-1] / n
    pointers = rng.uniform(0, step) + step * np.arange(n)
    idx = np.searchsorted(cum, pointers, side="right")
    return np.minimum(idx, fitness.size - 1)


def _ranking_fitness(cost: np.ndarray, sp: float) -> np.ndarray:
    """Linear ranking: best gets sp, worst 2 − sp (infinite costs rank last)."""
    n = cost.size
    order = np.argsort(cost, kind="stable")
    rank = np.empty(n)
    rank[order] = np.arange(n)[::-1]  # best → n−1
    return 2 - sp + 2 * (sp - 1) * rank / max(n - 1, 1)


def _genes(problem: SEProblem, thetas: np.ndarray) -> np.ndarray:
    """The GA's genes of θ's: the optimisers' coordinates z of a centred problem (:meth:`SEProblem.to_z`), θ
    itself otherwise (a copy)."""
    return problem.to_z(thetas) if problem.z_map is not None else np.array(thetas, float)


def _theta_of(problem: SEProblem, genes: np.ndarray) -> np.ndarray:
    """θ of the GA's ``genes`` (:func:`_genes`)."""
    return problem.from_z(genes) if problem.z_map is not None else np.array(genes, float)


def _ga_cost(problem: SEProblem, pop: np.ndarray, lam1: float, threads: int = 1) -> np.ndarray:
    """The cost of the GA's individuals ``pop`` (genes, (P, n)) at λ1, from z where the genes are z."""
    if problem.z_map is not None:
        return problem.cost(problem.from_z(pop), lam1, threads, z=pop)
    return problem.cost(pop, lam1, threads)


def _ga_run(problem: SEProblem, lam1: float, init: np.ndarray, opts: GAOptions, rng: np.random.Generator,
            threads: int) -> tuple[np.ndarray, float, int]:
    """One GA run for one λ1 from the individuals ``init`` (genes, :func:`_genes`); returns (the best
    individual's genes, its cost, generations run).

    The genes are θ, or for a structure closed under shifts the centred coordinates z
    (:meth:`SEProblem.to_z`): the crossover is linear, but a mutation of 5 % of a raw gene is not the same
    change of the model at another offset of u or y, and the runs chose other models there. The caller keeps
    them in z from the seeds to the carried member: raw θ holds the offsets' powers, and its round trip lost ~1e-8
    at y + 1e4, which the runs amplified (fronts 0.5 % apart in cost, 72 % in J_SF)."""
    pop = np.asarray(init, float)

    def cost_of(pop):
        return _ga_cost(problem, pop, lam1, threads)
    cost = cost_of(pop)
    best_hist = [np.min(cost)]
    n = opts.population
    g = 0
    for g in range(1, opts.generations + 1):
        order = np.argsort(cost, kind="stable")
        elite = pop[order[: opts.elite]]
        fit = _ranking_fitness(cost, opts.selective_pressure)
        nsel = n - opts.elite
        nsel += nsel % 2
        parents = _sus(fit, nsel, rng)
        rng.shuffle(parents)
        a, b = parents[0::2], parents[1::2]
        better = np.where((cost[a] <= cost[b])[:, None], pop[a], pop[b])
        worse = np.where((cost[a] <= cost[b])[:, None], pop[b], pop[a])
        cross = rng.random(a.size) < opts.crossover_prob
        r = rng.random((a.size, 1))
        c1 = np.where(cross[:, None], worse + opts.crossover_ratio * (better - worse), pop[a])
        c2 = np.where(cross[:, None], worse + r * (better - worse), pop[b])
        kids = np.vstack([c1, c2])[: n - opts.elite]
        mut = rng.random(kids.shape) < opts.mutation_prob
        kids = kids + mut * rng.standard_normal(kids.shape) * opts.mutation_scale * np.abs(kids)
        pop = np.vstack([elite, kids])
        cost = cost_of(pop)
        best_hist.append(np.min(cost))
        if opts.stall and g >= opts.stall:  # best_hist[0] is the initial population's: g >= stall has stall steps
            old = best_hist[-opts.stall - 1]
            # from no finite cost (inf) to one is an improvement: inf − c ≤ 1e-9 · inf said it was none
            if np.isfinite(old) and old - best_hist[-1] <= 1e-9 * abs(old):
                break
    i = int(np.argmin(cost))
    return pop[i].copy(), float(cost[i]), g


# -- results and checkpoints ----------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SEFront:
    """The members of one SE sweep, as the optimiser left them (before re-evaluation).

    Attributes
    ----------
    lambdas : ndarray, shape (K,)
        λ1 of each member, in the order the runs were made (descending).
    thetas : ndarray, shape (K, n_terms)
        Parameters, engineering units; a NaN row for a failed member.
    costs : ndarray, shape (K,)
        The optimised weighted cost λ1 J_S + λ2 J_SF (output units²); inf for a failed member.
    failures : mapping int -> str
        Members whose fit failed, with the reason in words.
    nfev : ndarray of int, shape (K,)
        Objective evaluations (free runs) spent on each member.
    """

    lambdas: np.ndarray
    thetas: np.ndarray
    costs: np.ndarray
    failures: Mapping[int, str] = field(default_factory=dict)
    nfev: np.ndarray | None = None

    def __post_init__(self) -> None:
        K = np.shape(self.lambdas)[0]
        object.__setattr__(self, "lambdas", frozen(self.lambdas))
        object.__setattr__(self, "thetas", frozen(self.thetas))
        object.__setattr__(self, "costs", frozen(self.costs))
        object.__setattr__(self, "nfev", frozen(np.zeros(K) if self.nfev is None else self.nfev, int))
        object.__setattr__(self, "failures", FrozenMap({int(k): str(v) for k, v in dict(self.failures).items()}))

    __repr__ = short_repr  # one line: the fields summarised, arrays by their shape


_CHECKPOINT_ARRAYS = ("thetas", "costs", "done", "failures", "nfev")

#: The first bytes of a zip file, which an .npz archive is.
_ZIP_MAGIC = b"PK\x03\x04"



def checkpoint_version(path: str | os.PathLike) -> str | None:
    """The graybox version a checkpoint file records: ``""`` when it records none (written before
    versions were), None when it is no readable checkpoint (resuming it names the fault)."""
    try:
        with open(path, "rb") as f, np.load(f, allow_pickle=False) as z:
            stored = json.loads(str(z["meta"]))
    except (ValueError, TypeError, KeyError, OSError, EOFError, zipfile.BadZipFile):
        return None
    return str(stored.get("graybox", "")) if isinstance(stored, dict) else None


class CheckpointError(ValueError):
    """A checkpoint file that cannot be resumed: unreadable, corrupt, of another problem or an older graybox."""


#: What names a sweep's problem in its checkpoint (the rest, settings and version, may change between versions).
_CHECKPOINT_IDENTITY = ("problem", "method", "lambdas", "seed")


#: What reading a file that is no whole .npz archive raises (:func:`read_npz`).
NPZ_ERRORS = (ValueError, TypeError, KeyError, OSError, EOFError, zipfile.BadZipFile)


def read_npz(path: Path) -> dict[str, np.ndarray]:
    """Every array of the ``.npz`` archive ``path``, read without pickle; one of :data:`NPZ_ERRORS` saying why a
    file is none."""
    # opened here: np.load leaves the file it opened open when a torn zip fails to read
    with open(path, "rb") as f:
        if f.read(4) != _ZIP_MAGIC:
            # said here: numpy takes any file that is neither .npy nor .npz for a pickle and says to load it
            # "unsafely" with pickle, which a checkpoint never is (a grid store, a spec, a model given by mistake)
            raise ValueError("it is no .npz archive (its first bytes are not a zip file's)")
        f.seek(0)
        with np.load(f, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}


def _load_checkpoint(path: Path, meta: dict, n_terms: int | None = None, coords: bool = False,
                     unshaped: str | None = None) -> dict | None:
    """The state a checkpoint of a sweep of ``n_terms`` parameters (None: as many as it holds) holds, or None (with
    a warning) when another graybox version wrote it. ``coords``: the sweep needs its members in their optimiser's
    coordinates too (``out["coords"]``; a centred problem's GA). ``unshaped``: the problem's fingerprint as the
    versions that hashed no shapes made it, whose checkpoint of it is one of another version."""
    def unreadable(exc: Exception) -> ValueError:
        return CheckpointError(f"checkpoint {path} is not a readable SE checkpoint ({exc}); delete it or choose "
                               "another checkpoint path")

    try:
        arrays = read_npz(path)
    except NPZ_ERRORS as exc:
        raise unreadable(exc) from None
    if "meta" not in arrays and str(arrays.get("kind", "")) == "select_graybox":
        # another function's file, perhaps hours of work: not offered for deletion
        raise CheckpointError(f"checkpoint {path} is select_graybox's checkpoint, not an SE sweep's; choose another "
                              "checkpoint path")
    if "meta" not in arrays:  # another tool's archive under the name: said in words, not as a KeyError's "('meta')"
        raise unreadable(ValueError("it holds no SE sweep's metadata; its arrays: "
                                    + (", ".join(map(repr, arrays)) or "none")))
    try:
        stored = json.loads(str(arrays["meta"]))
        raw = {k: arrays[k] for k in _CHECKPOINT_ARRAYS if k in arrays}
    except NPZ_ERRORS as exc:  # JSONDecodeError is a ValueError
        raise unreadable(exc) from None
    if not isinstance(stored, dict):
        raise unreadable(TypeError(f"its metadata is a {type(stored).__name__}, not a mapping"))
    if meta.get("method") == "gradient":  # it draws nothing: its seed is no part of the problem
        stored, meta = ({k: v for k, v in d.items() if k != "seed"} for d in (stored, meta))
    other = sorted(k for k in _CHECKPOINT_IDENTITY if stored.get(k) != meta.get(k))
    if other == ["problem"] and unshaped is not None and stored.get("problem") == unshaped:
        # written before the fingerprint held the arrays' shapes: this problem's (or one over the same numbers cut
        # otherwise, which that hash could not tell apart), by an older algorithm of fingerprints
        said = f"{stored.get('graybox', '?')} (one whose fingerprint of a problem left out its arrays' shapes)"
        stored = {**stored, "problem": meta["problem"], "graybox": said}
        other = []
    if other:  # another problem's file, whichever version wrote it: never overwritten
        raise CheckpointError(f"checkpoint {path} was written for another problem (differs in: {', '.join(other)}); "
                              "delete it or choose another checkpoint path")
    if stored.get("graybox") != meta["graybox"]:
        # members of two algorithms must not share a front; the stale file of this very problem is
        # this path's to replace
        by = f"graybox {stored['graybox']}" if "graybox" in stored else "a graybox that did not record its version"
        warn(f"checkpoint {path} was written by {by}, this is graybox {meta['graybox']}, whose algorithm may "
             "differ: the sweep starts over and overwrites it", UserWarning)
        return None
    if stored != meta:
        diff = sorted(k for k in set(stored) | set(meta) if stored.get(k) != meta.get(k))
        raise CheckpointError(
            f"checkpoint {path} was written for another problem or settings (differs in: {', '.join(diff)}); "
            "delete it or choose another checkpoint path"
        )
    if set(raw) != set(_CHECKPOINT_ARRAYS):
        raise CheckpointError(f"checkpoint {path} was written by an older graybox (it does not record failed "
                              "members); delete it or choose another checkpoint path")
    if coords and "coords" not in arrays:
        raise CheckpointError(f"checkpoint {path} was written by an older graybox (it does not record the GA's "
                              "members as its runs hold them, in the centred coordinates, which their θ does not "
                              "give back exactly); delete it or choose another checkpoint path")
    try:
        failed = json.loads(str(raw["failures"]))
        # the sweep writes a mapping of member index to reason: a list, a number or a reason that is no text is
        # no record of failed members (a list was read by .items(), a bare AttributeError)
        if not isinstance(failed, dict) or not all(isinstance(v, str) for v in failed.values()):
            raise TypeError(f"its failed members are {short_value(failed)}, not a mapping of member to reason")
        if not all(re.fullmatch(r"-?[0-9]+", k) for k in failed):  # int() reads " 1" and "+1" as member 1
            raise ValueError(f"its failed members are {short_value(failed)}, whose keys are not member indices")
        out = {"thetas": raw["thetas"], "costs": raw["costs"], "done": raw["done"], "nfev": raw["nfev"],
               "failures": {int(k): v for k, v in failed.items()}}
    except (ValueError, TypeError) as exc:
        raise unreadable(exc) from None
    K = len(meta["lambdas"])

    def corrupt(what: str) -> CheckpointError:
        return CheckpointError(f"checkpoint {path} is corrupt ({what}); delete it or choose another path")

    # every array as the sweep writes it: a short or mistyped one would be broadcast into the members, a NaN
    # cost or a non-finite θ taken for a fitted member's
    th, costs, done, nfev = out["thetas"], out["costs"], out["done"], out["nfev"]
    n_terms = th.shape[-1] if n_terms is None and th.ndim else n_terms
    if done.shape != () or done.dtype.kind not in "iu":
        raise corrupt(f"its count of members done is {done!r}, not an integer")
    done = out["done"] = int(done)
    # the sweep writes float64: members rewritten in another precision (float32 by another tool) were rounded, and
    # resumed they would join the front as other members than the ones fitted
    narrow = [f"{k} {a.dtype}" for k, a in (("thetas", th), ("costs", costs), ("coords", arrays.get("coords")))
              if a is not None and a.dtype.kind == "f" and a.dtype != np.float64 and (k != "coords" or coords)]
    if narrow:
        raise corrupt(f"its {', '.join(narrow)} are not the float64 the sweep writes: its members were rewritten "
                      "in another precision, and resumed they would not be the members fitted")
    if th.dtype.kind != "f" or th.ndim != 2 or th.shape != (K, n_terms) or costs.dtype.kind != "f" \
            or costs.shape != (K,) or nfev.dtype.kind not in "iu" or nfev.shape != (K,):
        raise corrupt(f"arrays of shapes thetas {th.shape}, costs {costs.shape}, nfev {nfev.shape} for "
                      f"{K} members of {n_terms} terms, or of the wrong kind")
    if not 0 <= done <= K or any(not 0 <= k < done for k in out["failures"]):
        raise corrupt("inconsistent sizes")
    fitted = np.ones(done, bool)
    fitted[list(out["failures"])] = False
    if not (np.all(np.isfinite(th[:done][fitted])) and np.all(np.isfinite(costs[:done][fitted]))
            and np.all(costs[:done][fitted] >= 0) and np.all(nfev[:done] >= 0)):
        raise corrupt("a fitted member's θ or cost is not finite, or a cost or count is negative")
    # a failed member as the sweep writes it (θ NaN, cost inf): one with a fitted member's θ and cost, named failed,
    # resumed into a front that had lost it without a word
    if not (np.all(np.isnan(th[:done][~fitted])) and np.all(np.isposinf(costs[:done][~fitted]))):
        raise corrupt("a member named failed has a θ or a finite cost, as only a fitted member has")
    if coords:
        z = arrays["coords"]
        if z.dtype.kind != "f" or z.shape != th.shape or not np.all(np.isfinite(z[:done][fitted])):
            raise corrupt(f"its members' coordinates, of shape {z.shape}, are not those of its {K} members of "
                          f"{n_terms} terms, or not finite for a fitted member")
        out["coords"] = z
    return out


def save_npz(path: Path, **arrays: Any) -> None:
    """Write ``arrays`` to the ``.npz`` file ``path`` atomically (:func:`~graybox.core._files.write_atomically`): a
    kill during the write never leaves a torn file, two writers at once never move each other's half-written file, a
    symbolic link is written through."""
    write_atomically(path, lambda f: np.savez(f, **arrays))


def _save_checkpoint(path: Path, meta: dict, thetas: np.ndarray, costs: np.ndarray, done: int,
                     failures: dict, nfev: np.ndarray, coords: np.ndarray | None = None) -> None:
    """``coords``: the members in their optimiser's coordinates (:func:`_sweep`), kept only when given."""
    more = {} if coords is None else {"coords": coords}
    save_npz(path, meta=json.dumps(meta), thetas=thetas, costs=costs, done=done,
             failures=json.dumps({str(k): v for k, v in failures.items()}), nfev=nfev, **more)


def check_lsq_tol(tol: object) -> float:
    """``tol`` of the least_squares fits, checked: at least machine epsilon (below it "lm" refuses to run, and
    every start was then a failed fit with scipy's message; "trf" and "dogbox" ignore it with a warning)."""
    return check_real(tol, "tol (the fits' relative tolerance, at least machine epsilon)", low=float(np.finfo(float).eps))


class _Failed(Exception):
    """A member's fit failed; the message is the reason kept in the result."""


def _sweep(problem: SEProblem, lam: np.ndarray, method: str, settings: dict, seed: int | None,
           checkpoint: str | os.PathLike | None, progress: bool, step, fitted: SEFront | None = None,
           coords: np.ndarray | None = None) -> SEFront:
    """Run ``step(i, lam1, thetas, rng) -> (θ, cost, nfev)`` over the λ's (descending).

    ``thetas`` holds the members so far (NaN rows for failed ones). A step that raises
    :class:`_Failed` leaves a failed member with its reason and the sweep goes on. Each λ is
    checkpointed, failures included, so a resumed sweep gives the uninterrupted one's set.
    ``fitted``: the first members of this very sweep, fitted already (a probe), taken as a
    checkpoint's are. ``coords``: an array (K, n) the step fills with each member as its optimiser holds it
    (the GA's genes in z, which θ does not give back exactly), checkpointed with the members and filled from
    a checkpoint on resume, so that a resumed sweep carries on exactly what an uninterrupted one does.
    """
    problem.check_identified()  # refused before any fit when not even the weighted static points identify θ
    K = lam.size
    n = len(problem.structure)
    thetas = np.full((K, n), np.nan)
    costs = np.full(K, np.inf)
    nfev = np.zeros(K, int)
    failures: dict[int, str] = {}
    done = 0
    meta = {"problem": problem.fingerprint(), "method": method, "lambdas": lam.tolist(), "seed": seed,
            "settings": settings, "graybox": graybox_version()}
    if problem.input_names() is not None:  # only when said: the default names' checkpoints stay valid
        meta["inputs"] = problem.input_names()
    path = None if checkpoint is None else checkpoint_path(checkpoint)
    ck = (_load_checkpoint(path, meta, n, coords is not None, problem.fingerprint(shapes=False))
          if path is not None and path.exists() else None)
    if ck is not None:
        done = ck["done"]
        thetas[:done], costs[:done], nfev[:done] = ck["thetas"][:done], ck["costs"][:done], ck["nfev"][:done]
        failures.update(ck["failures"])
        if coords is not None:
            coords[:done] = ck["coords"][:done]
    if fitted is not None and fitted.lambdas.size > done:
        p = fitted.lambdas.size
        if p > K or not np.array_equal(fitted.lambdas, lam[:p]):
            raise ValueError("fitted members must be those of the sweep's first λ1 values")
        thetas[:p], costs[:p] = fitted.thetas, fitted.costs
        nfev[:p] = fitted.nfev  # an SEFront's nfev is never None (zeros by default)
        failures.update(fitted.failures)
        done = p
        if path is not None:
            _save_checkpoint(path, meta, thetas, costs, done, failures, nfev, coords)
    bar = progress_bar(K, f"SE front ({method})", progress, initial=done)
    # The sweeps make thousands of small BLAS calls (QR of a few thousand rows, 30-row least
    # squares): a multi-threaded BLAS only adds synchronisation, and on a loaded 2-core machine
    # it measured 30x slower than one thread. Our own parallelism is the population threads.
    limits = one_blas_thread()
    try:
        for i in range(done, K):
            # one generator per λ index: a resumed sweep draws exactly what an uninterrupted one does
            rng = np.random.default_rng([0 if seed is None else seed, i])
            try:
                _check_weight(problem, float(lam[i]))
                thetas[i], costs[i], nfev[i] = step(i, float(lam[i]), thetas, rng)
            except _Failed as why:
                failures[i] = str(why)
                thetas[i], costs[i] = np.nan, np.inf
            if path is not None:
                _save_checkpoint(path, meta, thetas, costs, i + 1, failures, nfev, coords)
            bar.update(1)
    finally:
        bar.close()
        limits.restore_original_limits()
    return SEFront(lam, thetas, costs, failures, nfev)


def _check_weight(problem: SEProblem, lam1: float) -> None:
    """:class:`_Failed` when θ is not identified at λ1: at λ1 = 1 the static points carry no weight, and where
    the records alone leave θ free (an input held constant) any fit there would pick one θ of many."""
    try:
        problem.check_identified(lam1)
    except ValueError as exc:
        raise _Failed(str(exc)) from None


def _nearest(thetas: np.ndarray, i: int, side: str, count: int) -> list[int]:
    """Indices of up to ``count`` successful members nearest member i, earlier ("before") or later ("after")."""
    order = range(i - 1, -1, -1) if side == "before" else range(i + 1, thetas.shape[0])
    return [j for j in order if np.all(np.isfinite(thetas[j]))][:count]


def ga_front(
    problem: SEProblem,
    lambdas: Sequence[float] | np.ndarray = SE_LAMBDAS,
    *,
    options: GAOptions = GAOptions(),
    seed: int = 0,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
    threads: int = 1,
    theta0: np.ndarray | Literal["ls"] | None = "ls",
    starts: Sequence[np.ndarray] = (),
) -> SEFront:
    """The paper's GA over a λ1 sweep (run from λ1 = 1 down, whatever order is given).

    Parameters
    ----------
    problem : SEProblem
    lambdas : sequence of float in (0, 1]
    options : GAOptions
    seed : int
        Seeds every random draw; with a checkpoint, a resumed sweep equals an uninterrupted one.
    checkpoint : path, optional
        Written after each λ; resumed, refused or started over as in :func:`gradient_front`.
    progress : bool
    threads : int
    theta0 : ndarray, "ls" or None
        An individual added to the first run's initial population. The paper seeds its first
        run with random individuals only (least squares on 30 samples); for structures with
        cubic terms those almost never give a free run that stays bounded, and the run then has
        nothing to select from. The default, ``"ls"``, adds the least-squares estimate on all
        samples — one individual, in the spirit of the paper's seeds. ``None`` is the paper's
        choice exactly.
    starts : sequence of ndarray
        Further individuals put into every run's initial population in place of random ones
        (beyond the paper; e.g. PE or gradient SE solutions). Default: none. One outside the
        stability margin is pulled in by shrinking its output feedback (where no scaling does, it
        stays in with an infinite cost and ranks last).

    Returns
    -------
    SEFront
        One member per λ, each the best individual of its run (its cost optimised). A run whose
        best individual has an infinite cost (every free run diverged, or an equilibrium at some
        static point was unstable or undefined) is a failed member; the next run is seeded with
        the nearest earlier member that did not fail.
    """
    lam = np.sort(check_lambdas(lambdas))[::-1]
    zs = problem.z_map is not None  # genes in z (:func:`_genes`): every individual is kept there, never raw θ
    if isinstance(theta0, str):
        if theta0 != "ls":
            raise ValueError(f"theta0 must be an array, 'ls' or None, got {theta0!r}")
        first = problem.ls_theta()
        first_genes = problem.ls_z() if zs else first
    else:
        first = None if theta0 is None else check_theta(len(problem.structure), theta0, "theta0")
        first_genes = None if first is None else _genes(problem, first)
    extra = np.array([check_theta(len(problem.structure), s_, f"starts[{k}]") for k, s_ in enumerate(starts)]
                     ).reshape(-1, len(problem.structure))
    if extra.shape[0] > options.population - 1:
        raise ValueError(f"starts: {extra.shape[0]} individuals do not fit a population of {options.population} "
                         "besides the carried one")
    extra_genes = _genes(problem, extra)
    # each member's genes, carried on to the next run as they are (checkpointed): its θ, through which a centred
    # problem's were carried, lost ~1e-8 at y + 1e4, and the runs that followed amplified it
    carried = np.full((lam.size, len(problem.structure)), np.nan) if zs else None

    def inside(g, lam1):
        """A given individual outside the margin with its feedback shrunk (as it is where no scaling helps)."""
        if problem.margin is None or np.isfinite(_ga_cost(problem, g[None], lam1)[0]):
            return g
        pulled = _pull_inside(problem, _theta_of(problem, g), lam1)
        return g if pulled is None else _genes(problem, pulled[0])

    def step(i, lam1, thetas, rng):
        near = _nearest(thetas, i, "before", 1)
        carry = (carried[near[0]] if zs else thetas[near[0]]) if near else first_genes
        given = [inside(g, lam1) for g in ([] if carry is None else [carry]) + list(extra_genes)]
        count = options.population - len(given)
        init = problem.random_z(rng, count, options.random_samples) if zs else \
            problem.random_ls(rng, count, options.random_samples)
        if given:
            init = np.vstack([np.array(given), init])
        best, c, g = _ga_run(problem, lam1, init, options, rng, threads)
        if not np.isfinite(c):
            raise _Failed(f"no individual of the GA run at λ1 = {lam1:g} had a finite cost after {g} generation(s); "
                          f"of its {len(init)} initial individuals "
                          f"{_population_faults(problem, _theta_of(problem, init), lam1)}")
        if zs:
            carried[i] = best
        return _theta_of(problem, best), c, options.population * (g + 1)

    settings = dict(asdict(options), theta0=None if first is None else [float(v) for v in first])
    if extra.shape[0]:  # only when given: checkpoints of the paper's GA stay valid
        settings["starts"] = extra.tolist()
    return _sweep(problem, lam, "ga", settings, seed, checkpoint, progress, step, coords=carried)


def _population_faults(problem: SEProblem, pop: np.ndarray, lam1: float) -> str:
    """Why the individuals ``pop`` (P, n) have no finite cost at λ1, counted by reason, in words. (Every reason
    was once said as 'every free run diverged', also of runs that stayed bounded outside the stability margin.)"""
    div = ~np.isfinite(problem.js(pop))
    parts = [f"{int(div.sum())} diverged (free run)"] if div.any() else []
    rest = ~div
    yb = None
    if lam1 < 1.0 and rest.any():
        yb = problem.static_outputs(pop[rest], scored=True)
        undefined = ~np.all(np.isfinite(yb), axis=1)
        if undefined.any():
            parts.append(f"{int(undefined.sum())} had an unstable or undefined equilibrium at some static point")
        rest[np.flatnonzero(rest)[undefined]] = False
        yb = yb[~undefined]
    if problem.margin is not None and rest.any():
        out = ~problem.within_margin(pop[rest], yb)
        if out.any():
            parts.append(f"{int(out.sum())} lay outside the stability margin (a local model's spectral radius above "
                         f"1 − margin = {1 - problem.margin:g})")
    return ", ".join(parts) if parts else "none had a finite cost"


#: Samples per block of the streamed QR of the Jacobian (the block stays in cache).
_BLOCK = 4096


def _residuals(problem: SEProblem, z: np.ndarray, lam1: float) -> np.ndarray:
    """Stacked residuals [√(λ1/N) e_sim, √(λ2/N_SF) e_SF] at z (θ = problem.from_z(z)); all inf once a run
    diverges."""
    th = problem.from_z(z)
    L = problem.L
    M = len(problem.static) if lam1 < 1.0 else 0
    n_ridge = th.size if problem.ridge > 0 else 0
    r = np.empty(problem.n_dyn + M + n_ridge)
    a = 0
    th_run = problem.run_theta(th, z)
    for rec in problem.run_records:  # the centred signals of a centred problem: the same errors (SEProblem.js)
        # simulate's default bound: a run that leaves it is NaN from there, so its residuals are inf (as its J_S)
        y = simulate_one(problem.code, th_run, record_inputs(rec, problem.code.input_names), rec.y[:L], L, None)
        b = a + y.size - L
        np.subtract(y[L:], rec.y[L:], out=r[a:b])  # written in place: long records make no copies
        a = b
    r[:a] *= np.sqrt(lam1 / problem.n_dyn)
    yb = None
    if M:
        # an unstable equilibrium gives NaN here, hence inf residuals: the solver treats the
        # region as infeasible and shrinks its step, so the front never trades J_SF for stability
        e = problem.static_errors(th, scored=True, z=z)[0]
        yb = e + problem.static.ybar
        r[a:a + M] = np.sqrt((1.0 - lam1) / M) * e
    if n_ridge:
        r[a + M:] = np.sqrt(problem.ridge / n_ridge) * (z - problem.ridge_ref)
    if not np.all(np.isfinite(r)):
        r[:] = np.inf
    elif problem.margin is not None and not problem.within_margin(th, None if yb is None else yb[None])[0]:
        r[:] = np.inf  # outside the margin: a wall, as instability is (every accepted point keeps the margin)
    return r


def _r_factor(problem: SEProblem, z: np.ndarray, lam1: float) -> np.ndarray:
    """Triangular factor of the augmented Jacobian [J r] of :func:`_residuals` at z.

    The upper-triangular T, shape (n + 1, n + 1), has Tᵀ T = [J r]ᵀ [J r]: its first n
    columns hold R of J = QR, its last column Qᵀr and ±‖r − QQᵀr‖. The dynamic rows are
    streamed through a QR of a few thousand rows at a time, so neither the N × n Jacobian
    nor its SVD is ever formed: the cost is linear in N and the memory independent of it,
    with the conditioning of QR (normal equations JᵀJ would square it).
    """
    th = problem.from_z(z)
    n = th.size
    L = problem.L
    w1 = np.sqrt(lam1 / problem.n_dyn)
    # the runs' parameters are θ = z / scale, or on the centred records z / s_c: ∂ŷ/∂z is S over that divisor
    colw = w1 / (problem.scale if problem.run_scale is None else problem.run_scale)
    th_run = problem.run_theta(th, z)
    T = np.zeros((0, n + 1))
    for rec, U in zip(problem.run_records, problem.run_U):
        for k0, k1, yh, S in free_run_sensitivity_blocks(problem.code, th_run, U, rec.y[:L], L, _BLOCK):
            m = T.shape[0]
            b = k1 - k0
            # column-major, as LAPACK takes it: factored in place, with no copy of the block
            work = np.empty((m + b, n + 1), order="F")
            work[:m] = T
            np.multiply(S, colw, out=work[m:, :n])
            np.subtract(yh[k0:k1], rec.y[k0:k1], out=work[m:, n])
            work[m:, n] *= w1
            if not np.all(np.isfinite(work)):
                return np.full((n + 1, n + 1), np.nan)
            T = _triangle(work, overwrite=True)
    if lam1 < 1.0:
        sp = problem.static
        w2 = np.sqrt((1.0 - lam1) / len(sp))
        e = problem.static_errors(th, scored=True, z=z)[0]
        rows = np.column_stack([problem.jac_z(w2 * problem.static_theta_gradient(th, e + sp.ybar), 1.0), w2 * e])
        if not np.all(np.isfinite(rows)):
            return np.full((n + 1, n + 1), np.nan)
        T = _triangle(np.vstack([T, rows]))
    if problem.ridge > 0:
        w3 = np.sqrt(problem.ridge / n)
        T = _triangle(np.vstack([T, np.column_stack([w3 * np.eye(n), w3 * (z - problem.ridge_ref)])]))
    if T.shape[0] < n + 1:
        T = np.vstack([T, np.zeros((n + 1 - T.shape[0], n + 1))])
    return T


def _triangle(A: np.ndarray, overwrite: bool = False) -> np.ndarray:
    """R of A = QR (Householder, LAPACK): its first min(A.shape) rows. ``overwrite``: A (column-major)
    is scratch and is factored in place."""
    qr, _, _, _ = dgeqrf(A, overwrite_a=overwrite)
    return np.triu(qr[: min(A.shape)])


def free_run_scaled(records: list[Record], points: StaticPoints | None,
                    structure: Structure) -> tuple[list[Record], StaticPoints | None, dict[str, int]]:
    """The records and static points a free-run fit runs on: y and each input times a power of two where J_S's
    squares (or a term's products) would leave the float range (:func:`~graybox.core._least_squares.binary_scaled`;
    the exponents, empty where the data's own units serve), the points alike. A term whose column is no float in the
    data's own units is refused by name, as els refuses it. At y near 1e-170 J_S underflowed to 0 and every fit
    stopped at its start; near 1e157 every start's free run read as diverging."""
    fit, exps = binary_scaled(records, structure)
    if not exps:
        return list(fit), points, exps
    stacked_regressors(structure, records)
    return list(fit), None if points is None else scaled_points(points, exps), exps


class _Start:
    """The residuals and the factor of :func:`_r_factor` at one start z0 of a fit at λ1, each computed once: the
    start's feasibility check and every solver fitted from it (:func:`_multistart`) evaluate z0 first, and the
    runs and equilibria there cost a fifteenth of a selection's fits. Other points are evaluated as they come."""

    def __init__(self, problem: SEProblem, z0: np.ndarray, lam1: float):
        self.problem = problem
        self.key = np.array(z0, dtype=float).tobytes()  # bit for bit: a start is only ever this very point
        self.lam1 = lam1
        self._at_start: dict = {}  # evaluator -> its read-only value at z0

    def _once(self, evaluate, z: np.ndarray) -> np.ndarray:
        if z.tobytes() != self.key:
            return evaluate(self.problem, z, self.lam1)
        if evaluate not in self._at_start:
            value = evaluate(self.problem, z, self.lam1)
            value.flags.writeable = False
            self._at_start[evaluate] = value
        return self._at_start[evaluate]

    def residuals(self, z: np.ndarray) -> np.ndarray:
        return self._once(_residuals, z)

    def r_factor(self, z: np.ndarray) -> np.ndarray:
        return self._once(_r_factor, z)


class _Compressed:
    """The SE least-squares problem as ``least_squares`` sees it: n + 1 residuals, not N.

    ``least_squares`` only uses the residual vector f and the Jacobian J through ‖f‖, Jᵀf and
    JᵀJ (and the column norms of J). With the factor T of [J r] (:func:`_r_factor`) and a
    Householder reflection H that maps its last column c = [Qᵀr; ±ρ] onto ‖r‖ e₁, the pair
    f̃ = ‖r‖ e₁, J̃ = H [R; 0] has exactly those three quantities, so ``trf``, ``dogbox`` and ``lm``
    take the same steps as on the full problem while decomposing an (n + 1) × n matrix. A trial
    point costs one free run (its Jacobian is needed only where a step is accepted).
    """

    def __init__(self, problem: SEProblem, lam1: float, watch=None, start: _Start | None = None):
        self.problem = problem
        self.lam1 = lam1
        self.n = len(problem.structure)
        self.nfun = 0
        self.last = (None, np.inf)  # the last point with a finite cost, and that cost
        self.watch = watch  # called with θ at every point where a Jacobian is taken (the iterates)
        self.start = start if start is not None and start.lam1 == lam1 else None

    def fun(self, z: np.ndarray) -> np.ndarray:
        self.nfun += 1  # counted as the solver asks, whether or not the start's residuals are remembered
        r = self.start.residuals(z) if self.start is not None else _residuals(self.problem, z, self.lam1)
        f = np.zeros(self.n + 1)
        with np.errstate(over="ignore", invalid="ignore"):
            f[0] = np.sqrt(r @ r) if np.isfinite(r[0]) else np.inf
        if not np.isfinite(f[0]):
            return np.full(self.n + 1, np.inf)
        self.last = (z.copy(), float(f[0] ** 2))
        return f

    def jac(self, z: np.ndarray, f: np.ndarray | None = None) -> np.ndarray:
        if self.watch is not None:
            self.watch(self.problem.from_z(z))
        T = self.start.r_factor(z) if self.start is not None else _r_factor(self.problem, z, self.lam1)
        if not np.all(np.isfinite(T)):
            # bounded run, overflowing sensitivities (a run on the edge of instability): stop here
            last, cost = self.last
            if last is None or not np.array_equal(last, z):
                last, cost = z.copy(), float(np.sum(_residuals(self.problem, z, self.lam1) ** 2))
            raise _Stop(last, cost)
        A = T[:, :-1].copy()
        v = T[:, -1].copy()
        nc = np.linalg.norm(v)
        # v = c − ‖c‖e₁, its first entry without cancellation (as LAPACK's dlarfg)
        tail = v[1:] @ v[1:]
        v[0] = -tail / (v[0] + nc) if v[0] > 0 else v[0] - nc
        vv = v @ v
        if vv > 0 and np.isfinite(vv):
            A -= np.outer(v, (2.0 / vv) * (v @ A))
        return A


#: The second pass of :func:`gradient_front` fits a member again from its neighbour's solution
#: only when that solution beats it by this relative margin: most neighbours differ by the
#: solver's tolerance, and refitting those spent a quarter of the evaluations for nothing.
_UP_MARGIN = 1e-4


class _Stop(Exception):
    """The Jacobian overflowed at an accepted point: the fit ends there."""


def _fit(problem: SEProblem, theta0: np.ndarray, lam1: float, solver: str, max_nfev: int,
         tol: float, watch=None, start: _Start | None = None) -> tuple[np.ndarray, float, int]:
    """One ``least_squares`` fit at λ1 from a feasible θ0: (θ, weighted cost, evaluations).

    ``watch(θ)``, if given, sees every iterate (each point where a Jacobian is taken); ``start``, the
    evaluations at θ0's coordinates already made or to be shared with other fits from there.
    """
    cp = _Compressed(problem, lam1, watch, start)
    # least_squares sees z = θ·scale and the residuals (both in output units) over s, the power of two nearest
    # the output's spread: its tolerances are not all relative (it stops at ‖dx‖ < xtol (xtol + ‖x‖), an absolute
    # step of xtol² where ‖x‖ < xtol, so an output of spread 1e-12 ended the fits early, and "lm" reads gtol as
    # a cosine, which tol × the spread is not). A power of two scales every step exactly: the fits of outputs
    # of spread near 1 are the same to the last bit.
    ys = problem.y_scale
    s = math.ldexp(1.0, math.frexp(ys)[1]) if ys > 0 else 1.0
    # trf/dogbox bound the gradient Jᵀf, which the scaling divides by s; lm bounds a cosine, unit-free
    gtol = tol if solver == "lm" else max(tol * ys / s, float(np.finfo(float).eps))
    try:
        from scipy.optimize import least_squares  # slow to import: loaded where used
        with np.errstate(over="ignore", invalid="ignore"):  # inf residuals mark rejected steps
            res = least_squares(lambda x: cp.fun(x * s) / s, problem.to_z(theta0) / s,
                                jac=lambda x, f=None: cp.jac(x * s), method=solver, x_scale="jac",
                                max_nfev=max_nfev, ftol=tol, xtol=tol, gtol=gtol)
    except _Stop as stop:
        z, cost = stop.args
        return problem.from_z(z), cost, cp.nfun
    return problem.from_z(res.x * s), float(2 * res.cost) * s * s, cp.nfun


def _why_infeasible(problem: SEProblem, theta: np.ndarray, lam1: float) -> str:
    """Why a start cannot be used at λ1, in words."""
    if not np.isfinite(problem.js(theta[None]))[0]:
        return "free run diverges"
    if problem.static is None or lam1 == 1.0:
        if problem.margin is not None and not problem.within_margin(theta)[0]:
            return f"a local model's spectral radius {problem.radius(theta):.6g} exceeds 1 − margin = {1 - problem.margin:g}"
        return "cost not finite"
    yb = problem.static_outputs(theta[None])[0]
    bad = np.flatnonzero(~np.isfinite(yb))
    if bad.size:
        points = point_texts(problem.static.ubar)  # each point told apart from the others
        return f"equilibrium unstable or undefined at ū = {', '.join(points[j] for j in bad[:3])}" + \
            (f" (and {bad.size - 3} more)" if bad.size > 3 else "")
    if problem.margin is not None and not problem.within_margin(theta, yb[None])[0]:
        return f"outside the stability margin (a local model's spectral radius exceeds 1 − margin = {1 - problem.margin:g})"
    return "cost not finite"


#: Factors tried, in order, on a start's output-feedback parameters to bring it inside the margin.
_PULL = (0.99, 0.97, 0.94, 0.9, 0.8, 0.65, 0.5, 0.3, 0.1, 0.0)


def _pull_inside(problem: SEProblem, theta: np.ndarray, lam1: float) -> tuple[np.ndarray, float] | None:
    """θ with its output-feedback parameters scaled by the largest factor of _PULL that makes it
    feasible at λ1 (inside the margin, a bounded free run, stable static equilibria), with that
    factor; None if none does. Shrinking the feedback shrinks every local model's roots."""
    fb = np.array([any(s == "y" for s, _, _ in t.factors) for t in problem.structure])
    rest = ~fb
    z0 = None if problem.z_map is None else problem.to_z(theta)
    # the refit needs the records to identify the other terms (else the static points do: shrink only)
    refit_identified = problem.records_identify()
    for c in _PULL:
        if z0 is not None:
            # closed under shifts: the feedback shrunk and the rest refitted in the centred coordinates, so that
            # the start (the plain shrink too) is the same model wherever the units put their zeros
            z = np.where(fb, c * z0, z0)
            tries = [problem.from_z(z)]
            if rest.any() and fb.any() and refit_identified:
                zr = z.copy()
                zr[rest] = problem.z_lstsq(cols=rest, fixed=z)
                tries.insert(0, problem.from_z(zr))
            for t in tries:
                if np.isfinite(_residuals(problem, problem.to_z(t), lam1)[0]):
                    return t, c
            continue
        th = np.where(fb, c * theta, theta)
        tries = [th]
        if rest.any() and fb.any():
            # the other parameters refitted (least squares, the feedback held): shrinking the feedback alone
            # moves every equilibrium, by an amount the output's offset sets (the constant absorbs it), so
            # the start's quality depended on where the units put their zero
            refit = th.copy()
            try:
                refit[rest] = scaled_lstsq(problem.psi[:, rest], problem.target - problem.psi[:, fb] @ th[fb])
                tries.insert(0, refit)
            except ValueError:  # the record alone does not identify them (the static points do): shrink only
                pass
        for t in tries:  # the refit first; the plain shrink where the refit is not feasible
            if np.isfinite(_residuals(problem, problem.to_z(t), lam1)[0]):
                return t, c
    return None


def _multistart(problem: SEProblem, lam1: float, cands: list[tuple[str, np.ndarray]], solvers: Sequence[str],
                max_nfev: int, tol: float) -> tuple[np.ndarray, float, int]:
    """Fit from every feasible start with every solver; keep the lowest cost (or raise _Failed)."""
    best = None
    nfev = 0
    why: dict[str, list[str]] = {}  # reason -> the starts it applies to
    tried: list[np.ndarray] = []
    for name, th0 in cands:
        if any(np.allclose(th0, t, rtol=1e-9, atol=0) for t in tried):  # e.g. the PE member of λ1 = 1 is LS
            continue
        tried.append(th0)
        nfev += 1
        start = _Start(problem, problem.to_z(th0), lam1)
        if not np.isfinite(start.residuals(problem.to_z(th0))[0]):
            pulled = None
            # outside the margin, along the records or, where the static points weigh, at their equilibria, a
            # diverging start too (an unstable least squares, which the margin makes stable): shrink its feedback
            weighed = problem.static is not None and lam1 < 1.0
            if problem.margin is not None and not problem.within_margin(
                    th0, problem.static_outputs(th0[None]) if weighed else None)[0]:
                pulled = _pull_inside(problem, th0, lam1)
            if pulled is None:
                why.setdefault(_why_infeasible(problem, th0, lam1), []).append(name)
                continue
            th0 = pulled[0]
            start = _Start(problem, problem.to_z(th0), lam1)
        for solver in solvers:
            try:
                th, c, k = _fit(problem, th0, lam1, solver, max_nfev, tol, start=start)
            except (ValueError, np.linalg.LinAlgError) as exc:  # a numerical breakdown ends this run only
                why.setdefault(str(exc), []).append(f"{name} ({solver})")
                continue
            nfev += k
            if np.isfinite(c) and (best is None or c < best[1]):
                best = (th, c)
    if best is None:
        raise _Failed(f"no start of the gradient SE fit at λ1 = {lam1:g} is feasible: "
                      + "; ".join(f"{', '.join(names)}: {reason}" for reason, names in why.items()))
    return best[0], best[1], nfev


def _pe_members(problem: SEProblem, lambdas: np.ndarray) -> np.ndarray | None:
    """The PE member (closed form) of each λ1, a start of the same λ; None if PE cannot solve it.
    Remembered by the problem (and its :meth:`SEProblem.with_margin` copies): a sweep inside the
    margin starts from the same PE members."""
    lambdas = np.asarray(lambdas, float)
    key = ("pe", lambdas.tobytes())
    if key not in problem._memo:
        # a centred problem (:meth:`SEProblem._centre_basis`) solves PE on the signals it runs on, the centred ones,
        # and maps the centred parameters to θ: the closed form on the raw signals carried y's zero into every start
        # (at y + 1e4 the starts of a 21-term closure moved by up to 4e-4 of a parameter, so that the GA's and the
        # gradient's fits depended on the output's zero); the PE member is the same model either way (J_1 and the
        # static-equation error are unchanged by the shift of a closed structure)
        records, static = (problem.records, problem.static) if problem.static_run is None else \
            (problem.run_records, problem.run_points())
        try:
            with one_blas_thread(), warnings.catch_warnings():
                warnings.simplefilter("ignore", StaticRangeWarning)  # se_pareto has said it already
                # a member whose weights do not identify θ (λ1 = 1, an input held constant) is a NaN row
                th = pe_members(problem.structure, records, static, lambdas=lambdas, solver="closed")[0]
        except ValueError:  # e.g. not identifiable with the static rows
            th = None
        if th is not None and problem.static_run is not None:
            th = problem.from_z(th * problem.run_scale)
        if th is not None:
            th.setflags(write=False)
        problem._memo[key] = th if th is not None and np.any(np.all(np.isfinite(th), axis=1)) else None
    return problem._memo[key]


#: The gradient method's solver choices; "auto" picks per phase (see :func:`gradient_front`).
_SOLVERS = ("auto", "trf", "dogbox", "lm")


def gradient_front(
    problem: SEProblem,
    lambdas: Sequence[float] | np.ndarray = SE_LAMBDAS,
    *,
    theta0: np.ndarray | None = None,
    seed: int = 0,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
    max_nfev: int = 50,
    tol: float = 1e-8,
    starts: Sequence[np.ndarray] = (),
    solver: Literal["auto", "trf", "dogbox", "lm"] = "auto",
    fitted: SEFront | None = None,
) -> SEFront:
    """Gradient SE front: ``scipy.optimize.least_squares`` per λ1, continued along the sweep.

    The runs go from the largest λ1 down. A member starts from the previous member's solution
    (continuation in λ). Where that start is not feasible — the first λ, or after the λ1 = 1
    member, whose static equilibria nothing constrains — the fit restarts from every feasible
    start: the nearest earlier members, the PE member of the same λ (closed form), ``theta0``
    and ``starts``, and keeps the lowest cost. A second pass goes back up: the smallest λ1
    restarts from every start (and its own solution), and each member is fitted again from its
    neighbour's solution (next smaller λ1) wherever that beats it, so a better basin found low
    in the sweep carries upwards. A failed member (no feasible start) is tried again from its
    nearest later members; if it still fails it stays failed, with the reason, and the other
    members are kept.

    Parameters
    ----------
    problem : SEProblem
    lambdas : sequence of float in (0, 1]
        Run from λ1 = 1 down.
    theta0 : ndarray, optional
        A start of the first run (default: least squares on all samples).
    seed : int
        Unused: the method draws no random numbers (a checkpoint of another seed resumes).
    checkpoint : path, optional
        Written after each λ; an existing one for the same problem and settings resumes the sweep
        (one written by another graybox version is started over, with a warning).
    progress : bool, optional
        Show a progress bar; default: only on a terminal.
    max_nfev, tol : int, float
        Per ``least_squares`` run: evaluations and tolerances (``ftol = xtol = tol``, relative, and ``gtol``
        on the gradient over the output's standard deviation, on a problem whose parameters and residuals
        are divided by the power of two nearest that deviation, so the stop does not depend on units).
    starts : sequence of ndarray
        Further starts tried wherever the fit restarts. :func:`se_pareto` passes PE solutions
        (convex, with the static points weighted in).
    solver : {"auto", "trf", "dogbox", "lm"}
        ``least_squares`` method. ``"auto"`` (default) restarts with both "trf" and "dogbox" and
        continues with "trf": on the plant's ℓ = 2 problem "dogbox" finds far lower minima of
        the simulation error where it starts afresh, while along the sweep, where unstable static
        equilibria are walls, it stalls in poorer minima than "trf" (BENCHMARKS.md, SE section).
    fitted : SEFront, optional
        The first pass's members for the largest λ1 values, fitted already by this function on
        the same problem and settings (e.g. :func:`se_pareto`'s probe of the first member): kept
        as a checkpoint's are, not fitted again (the method is deterministic: the same members).

    Returns
    -------
    SEFront
    """
    lam = np.sort(check_lambdas(lambdas))[::-1]
    n = len(problem.structure)
    start = problem.ls_theta() if theta0 is None else check_theta(n, theta0, "theta0")
    check_choice(solver, "solver", _SOLVERS)
    max_nfev = check_int(max_nfev, "max_nfev", low=1)
    tol = check_lsq_tol(tol)
    extra = [check_theta(n, s_, f"starts[{k}]") for k, s_ in enumerate(starts)]
    restart_solvers = ("trf", "dogbox") if solver == "auto" else (solver,)
    follow = "trf" if solver == "auto" else solver
    pe = _pe_members(problem, lam)

    def candidates(i, thetas, neighbours):
        c = [(f"member λ1 = {lam[j]:g}", thetas[j]) for j in neighbours]
        if pe is not None and np.all(np.isfinite(pe[i])):
            c.append(("PE member of this λ", pe[i]))
        c.append(("theta0" if theta0 is not None else "least squares", start))
        c += [(f"starts[{k}]", s_) for k, s_ in enumerate(extra)]
        return c

    def step(i, lam1, thetas, rng):
        before = _nearest(thetas, i, "before", 2)
        if before:
            th0 = thetas[before[0]]
            first = _Start(problem, problem.to_z(th0), lam1)  # its residuals are the fit's first evaluation
            if np.isfinite(first.residuals(problem.to_z(th0))[0]):
                th, c, k = _fit(problem, th0, lam1, follow, max_nfev, tol, start=first)
                return th, c, k + 1
        return _multistart(problem, lam1, candidates(i, thetas, before), restart_solvers, max_nfev, tol)

    settings = {"max_nfev": max_nfev, "tol": tol, "solver": solver,
                "theta0": None if theta0 is None else list(map(float, start)),
                "starts": [list(map(float, s_)) for s_ in extra]}
    front = _sweep(problem, lam, "gradient", settings, seed, checkpoint, progress, step, fitted)
    if lam.size == 1 or len(front.failures) == lam.size:
        return front
    # Second pass, from the smallest λ1 up (deterministic, so a resumed sweep gives the same set).
    # Continuation follows one basin down the sweep, and the basin that was best where the sweep
    # restarted (static points nearly ignored) need not be best where they weigh most: the
    # smallest λ1 restarts from every start too, and going up each member starts again from its
    # neighbour's solution (next smaller λ1) wherever that solution beats it. A failed member
    # tries its nearest later members here.
    thetas, costs, nfev = front.thetas.copy(), front.costs.copy(), front.nfev.copy()
    failures = dict(front.failures)
    K = lam.size
    with one_blas_thread():
        for i in range(K - 1, -1, -1):
            lam1 = float(lam[i])
            after = _nearest(thetas, i, "after", 2)
            if i == K - 1 or i in failures:
                try:
                    _check_weight(problem, lam1)
                except _Failed:
                    continue  # stays failed, with its reason
                cands = ([] if i in failures else [("this member", thetas[i])]) + \
                    [(f"member λ1 = {lam[j]:g}", thetas[j]) for j in after]
                if i == K - 1:
                    cands += candidates(i, thetas, [])
                try:
                    th, c, k = _multistart(problem, lam1, cands, restart_solvers, max_nfev, tol)
                except _Failed as why:
                    if i in failures and after:
                        failures[i] += f"; then from the later members: {str(why).split(': ', 1)[1]}"
                    continue
            elif after:
                th0 = thetas[after[0]]
                c0 = problem.cost(th0[None], lam1)[0]
                if not c0 < costs[i] * (1 - _UP_MARGIN):
                    continue
                th, c, k = _fit(problem, th0, lam1, follow, max_nfev, tol)
            else:
                continue
            nfev[i] += k
            if c < costs[i]:
                thetas[i], costs[i] = th, c
                failures.pop(i, None)
    return SEFront(lam, thetas, costs, failures, nfev)


def _pe_starts(problem: SEProblem) -> list[np.ndarray]:
    """PE solutions (closed form) leaning more and more on the static points: further starts."""
    th = _pe_members(problem, np.array([1e-1, 1e-2, 1e-3, 1e-4]))
    return [] if th is None else [t for t in th if np.all(np.isfinite(t))]


def _all_failed_advice(method: str, reasons: Iterable[str], margin: float | None) -> str:
    """What to try when every member of a sweep failed, for this method: more generations help a GA run find
    a finite cost, not a gradient fit that has no feasible start; where free runs diverged or equilibria were
    unstable (the texts of :func:`_why_infeasible` and :func:`_population_faults`) and no margin was set, one pulls
    the starts inside (:func:`_pull_inside`)."""
    tries = "another structure, theta0 or starts" + (
        ", or more generations or a larger population (options=GAOptions(generations=..., population=...))"
        if method == "ga" else "")
    unstable = ("free run diverges", "diverged (free run)", "equilibrium unstable", "an unstable or undefined equil")
    if margin is None and any(t in r for r in reasons for t in unstable):
        # the buck converter's degree-3 structure, every member failing so, fits with margin=0.05 by both methods
        tries += ("; where free runs diverge or equilibria are unstable, a stability margin (margin=0.05, say) "
                  "pulls the starts inside it by shrinking their output feedback")
    return f"Try {tries}"


#: Options of :func:`se_pareto` that apply to one method only.
_METHOD_ONLY = {"ga": ("options",), "gradient": ("max_nfev", "tol", "solver")}


_R = TypeVar("_R")


def refit_if_slow(problem: SEProblem, fit: Callable[[SEProblem], _R], what: str, auto: bool) -> _R:
    """``fit(problem)`` (a result with ``.model``), for ``margin="auto"`` fitted again inside :func:`slow_margin`
    when its model is slow (kept when that refit finds no start: ValueError, or when the refit misses a band,
    ``in_band``, that the first fit met: the band is what the caller asked for); a :class:`SlowModeWarning`
    names a model left slow. ``problem`` has no margin when ``auto``."""
    result = fit(problem)
    kept = None  # why a slow model is kept, for the warning
    if auto:
        _, slow, rho_ls = problem.slow_modes(result.model.theta[None])
        if slow[0]:  # a mode over SLOW_FACTOR times least squares' slowest: fit again inside that margin
            try:
                inside = fit(problem.with_margin(slow_margin(rho_ls)))
            except ValueError:  # no start inside it: keep the model, and say what it is
                inside = None
            if inside is not None and (getattr(inside, "in_band", True) or not getattr(result, "in_band", True)):
                result = inside
            elif inside is not None:
                kept = ("the fit inside that factor (margin='auto') misses the band this one meets, so this one is "
                        "kept: widen the band or try another structure")
    problem.warn_slow(result.model.theta[None], what, auto=auto, kept=kept)
    return result


#: File name endings of graybox's other files and common formats, which a checkpoint (an ``.npz``) is not.
_OTHER_FORMATS = {".json": "JSON file", ".csv": "CSV file", ".toml": "TOML file", ".sqlite": "SQLite store",
                  ".db": "database", ".npy": "single NumPy array", ".pkl": "pickle", ".pickle": "pickle"}


def checkpoint_path(checkpoint: object) -> Path:
    """``checkpoint`` as a Path, checked before any fit: ``TypeError`` for what is no path, ``ValueError`` for an
    empty name, a name ending as another format does (``.json``, ``.sqlite``, …), a folder given as the file, a folder that does not exist or one this process cannot write in (the
    first write would fail only after a member: the file is written beside itself and moved into place)."""
    checkpoint = check_path(checkpoint, "checkpoint")
    if not os.fspath(checkpoint):
        raise ValueError("checkpoint: an empty file name; give a file path such as 'front.npz'")
    check_path(checkpoint, "checkpoint", file=True)  # 'ckpt/' (no such folder yet) was written as a file 'ckpt'
    path = Path(checkpoint)
    if path.suffix.lower() in _OTHER_FORMATS:  # a name promising another format, which the file would not be
        raise ValueError(f"checkpoint: {path} names a {_OTHER_FORMATS[path.suffix.lower()]}, but a checkpoint is an "
                         f".npz file; give a name such as "
                         f"{path.with_suffix('.npz').name}")
    if path.is_dir():  # the folder meant to hold it: never to be called unreadable, nor deleted
        raise ValueError(f"checkpoint: {path} is a folder; give a file path, such as {path / 'checkpoint.npz'}")
    # the folder the writes go to: a symbolic link is written through (save_npz), beside the file it names
    real = written_path(path)
    if not real.parent.is_dir():
        raise ValueError(f"checkpoint: the folder {real.parent} does not exist; create it or choose another path")
    try:  # a file made and gone at once: what the write will do (modes, read-only mounts, ACLs all say)
        now = folder_now(real.parent)
    except OSError as exc:
        raise ValueError(f"checkpoint: the folder {real.parent} cannot be written in ({exc.strerror or exc}); make "
                         "it writable or choose another path") from None
    sweep_written_beside(real, now)  # the file save_npz writes and sweeps beside
    return path


def _sibling(path: str | os.PathLike, tag: str) -> Path:
    """``name.tag.ext`` beside ``name.ext``: the checkpoint of a second sweep of the same call."""
    p = Path(path)
    return p.with_name(f"{p.stem}.{tag}{p.suffix}")


def se_pareto(
    structure: Structure | object,
    data: Record | Dataset | Sequence[Record],
    static: StaticPoints | StaticCurve | StaticSurface | None = None,
    *,
    lambdas: Sequence[float] | np.ndarray | None = None,
    method: Literal["ga", "gradient"] = "ga",
    seed: int = 0,
    checkpoint: str | os.PathLike | None = None,
    progress: bool | None = None,
    threads: int = 1,
    theta0: np.ndarray | Literal["ls"] | None = "ls",
    options: GAOptions | None = None,
    max_nfev: int | None = None,
    tol: float | None = None,
    solver: Literal["auto", "trf", "dogbox", "lm"] | None = None,
    starts: Sequence[np.ndarray] | Literal["pe"] | None = None,
    margin: float | Literal["auto"] | None = "auto",
    ridge: float = 0.0,
    ubar: np.ndarray | None = None,
) -> ParetoSet:
    """SE Pareto set of eq. (13) by the paper's GA or the gradient method.

    Parameters
    ----------
    structure : Structure, sequence of str, Model, or a result that carries one
        Process terms (noise terms are dropped: the SE problem has no MA part); a Selection,
        ELSResult, Decision … gives its own.
    data : Record, Dataset or sequence of Record
        Identification data (a Dataset's ``ident``); with several records each is run freely
        on its own and J_S is the mean over all their samples.
    static : StaticPoints, StaticCurve or StaticSurface, optional
        Static points (default: the Dataset's); a curve or surface is sampled at ``ubar``, or
        over its domain (10 levels; a surface: a grid of 6 levels per input), as :func:`pe_pareto`
        samples it. Points outside the records' input range are welcome (a
        :class:`StaticRangeWarning` names them once).
    lambdas : sequence of float in (0, 1], optional
        λ1 values; default: the paper's logspace(-2, 0, 100). The runs go from λ1 = 1 down whatever
        the order given; the set's members are in the order given (as :func:`pe_pareto`'s). Each distinct λ1 is
        fitted once: a value given twice gives two copies of its member (both methods).
    method : {"ga", "gradient"}
        The paper's genetic algorithm, or ``scipy.optimize.least_squares`` with the analytic
        Jacobian of the free run.
    seed : int
        Makes the GA (and its random initial individuals) reproducible.
    checkpoint : path, optional
        Written after each λ; an existing one for the same problem resumes the sweep; one for
        another problem is refused, one written by another graybox version (``graybox.__version__``
        is recorded) is started over and overwritten, with a warning naming both versions. With
        ``margin="auto"``, a sweep fitted inside the margin keeps its own beside it
        (``name.margin.ext``); when the gradient sweep is fitted inside it from the start (its
        first member slow), only that file is written. The first member's probe is not
        checkpointed: a resumed call fits it again (the same result).
    progress : bool, optional
        Show a progress bar; default: only on a terminal.
    threads : int
        Threads for the GA's population runs and the evaluation of the members.
    theta0 : ndarray of shape (n_terms,), "ls" or None
        Start. GA: an individual added to the first run's population (``"ls"``, the default: the
        least-squares estimate; ``None``: the paper's random individuals only). Gradient: the
        first run's start (``"ls"`` or ``None``: least squares).
    options : GAOptions, optional
        GA settings (GA only).
    max_nfev, tol, solver : optional
        Gradient only: evaluations per ``least_squares`` run (default 50), its tolerances
        (1e-8) and its method (``"auto"``: "trf" and "dogbox" wherever the fit restarts, "trf" along
        the sweep; see ``gradient_front``).
    starts : sequence of ndarray, each of shape (n_terms,), "pe" or None
        Further starting points (engineering units). ``"pe"``: four PE solutions (closed form,
        λ1 = 0.1 … 1e-4 of eq. (11), leaning more and more on the static points). Gradient: tried
        wherever the fit restarts (None, the default: ``"pe"``). GA: individuals put into every
        run's initial population in place of random ones (None, the default: none, the paper's
        seeding; beyond the paper, ``"pe"`` lets the GA search from the PE basins: on the bundled
        plant's ℓ = 3 structure it lowers the D_SF model's validation J_S from 3.05 to 1.18,
        BENCHMARKS.md, "SE D_SF against ELS").
    margin : float in [0, 1), "auto" or None
        Stability margin (both methods): every member keeps the spectral radius of its local
        linear models ≤ 1 − margin, along the identification records and at the static points'
        equilibria (see ``SEProblem``); a θ outside it is infeasible, as an unstable
        equilibrium is. Without it a free-run fit may buy identification error with near-unit
        roots that follow the record's slow drift (BENCHMARKS.md, "Output error"). Dimensionless
        but tied to the sampling period: ρ = 1 − margin is a time constant of about Ts / margin.
        Starts (and the GA's individuals) outside the margin are infeasible. ``"auto"`` (default):
        the members whose local models are over 10 times slower than the least-squares model's
        slowest (1 − ρ < (1 − ρ_LS) / 10, ρ_LS its largest local spectral radius along the
        records; never where ρ_LS ≥ 1) are refitted with the margin (1 − ρ_LS) / 10, independent
        of units and of the sampling period (gradient: when the first member, largest λ1, is that
        slow, the whole sweep is fitted inside the margin at once). Without it the
        gradient front on the paper's structure (15) is all near-integrators (D_SF validation J_S
        1.8e3 mlc² against 1.1 with it; BENCHMARKS.md, "A slow-mode check"). None: no margin, the
        paper's problem; a :class:`~graybox.SlowModeWarning` then names members that slow.
    ridge : float >= 0
        Regularisation towards least squares (both methods): γ · mean_j (s_j (θ_j − θ_LS,j))² is
        added to every member's cost, s_j the RMS of regressor j (of the centred one for a structure
        closed under shifts: see ``SEProblem``). 0
        (default): none, the paper's problem; ``extra["cost"]`` then holds the regularised cost.
    ubar : ndarray, optional
        Where to sample a StaticCurve (shape (K,)) or StaticSurface (shape (K, m)) given as
        ``static``, in input units; refused with static points, which carry their own ū.

    Returns
    -------
    ParetoSet
        All members, one per λ in the order of ``lambdas``, with J_1, J_S and J_SF from the shared
        evaluator (output units²: 0 or inf where they leave the float range, an output near 1e-160 or 1e160,
        whose sweep runs on the signals times a power of two); the optimised cost is in ``extra["cost"]``, each
        member's largest local spectral radius along the identification records in ``extra["radius"]``
        (dimensionless) and the margin it was fitted with in ``extra["margin"]`` (NaN: none). A λ whose fit
        failed (no feasible start, or no individual with a finite cost) stays in the set as a failed member,
        with the reason in ``failures``. Use ``.nondominated()`` for the front proper.

    Raises
    ------
    ValueError
        An option of the other method is given, an unknown method, no static points, or every
        member failed (the reasons are listed); or θ is not identified by the records and the static
        points together (the one rule of ``identified_by``;
        the message names the free terms and what data would identify them). Records whose input is
        held constant are fitted when the static points identify θ: the start is then the least
        squares of both (``ls_theta``), and the λ1 = 1 member, where the points carry no
        weight, is a failed member saying so.
    """
    check_choice(method, "method", ("ga", "gradient"))
    seed = check_seed(seed)
    threads = check_int(threads, "threads", low=1)
    given = {"options": options, "max_nfev": max_nfev, "tol": tol, "solver": solver, "starts": starts}
    other = "gradient" if method == "ga" else "ga"
    wrong = [k for k in _METHOD_ONLY[other] if given[k] is not None]
    if wrong:
        raise ValueError(f"{', '.join(wrong)} appl{'y' if len(wrong) > 1 else 'ies'} to method={other!r} only, "
                         f"not to method={method!r}")
    if options is not None and not isinstance(options, GAOptions):
        raise TypeError(f"options must be a GAOptions (e.g. GAOptions(population=100)), got {options!r} "
                        f"({type(options).__name__})")
    if isinstance(starts, str):
        check_choice(starts, "starts", ("pe",))
    elif starts is not None:
        starts = check_sequence(starts, "starts", "a sequence of θ arrays or 'pe'")
    rec = records_of(data)
    sp = static_points(static, data, ubar=ubar, needed_by="the SE problem")
    margin = check_margin(margin)
    st = as_structure(structure)
    if isinstance(theta0, str) and theta0 != "ls":
        raise ValueError(f"theta0 must be an array, 'ls' or None, got {theta0!r}")
    # θ and the J's of the fit on scaled signals are mapped back to the data's units below
    fit_rec, fit_sp, exps = free_run_scaled(rec, sp, st)
    if exps:
        if theta0 is not None and not isinstance(theta0, str):
            theta0 = scaled_theta(check_theta(len(st), theta0, "theta0"), st, exps)
        if starts is not None and not isinstance(starts, str):
            starts = [scaled_theta(check_theta(len(st), s_, f"starts[{k}]"), st, exps) for k, s_ in enumerate(starts)]
    problem = SEProblem(st, fit_rec, fit_sp, margin=None if margin == "auto" else margin, ridge=ridge)
    problem.check_identified()  # the records with the static points (an input held constant needs them)
    warn_static_range(sp.ubar, rec)  # after: bad input is an error, not a warning and an error
    lam_user = check_lambdas(SE_LAMBDAS if lambdas is None else lambdas)
    # one run per distinct λ1, from 1 down; a λ1 given twice is that member's copy (the GA's second run of it was
    # another member, the gradient method's the same one)
    lam_in = np.unique(lam_user)[::-1]

    def sweep(problem: SEProblem, checkpoint, lams=lam_in, progress=progress, fitted=None) -> SEFront:
        if method == "ga":
            return ga_front(problem, lams, options=options or GAOptions(), seed=seed, checkpoint=checkpoint,
                            progress=progress, threads=threads, theta0=theta0,
                            starts=_pe_starts(problem) if starts == "pe" else () if starts is None else starts)
        return gradient_front(
            problem, lams, theta0=None if (isinstance(theta0, str) and theta0 == "ls") else theta0, seed=seed,
            checkpoint=checkpoint, progress=progress, max_nfev=50 if max_nfev is None else max_nfev,
            tol=1e-8 if tol is None else tol, solver="auto" if solver is None else solver,
            starts=_pe_starts(problem) if starts is None or starts == "pe" else starts, fitted=fitted)

    inside_ck = None if checkpoint is None else _sibling(checkpoint_path(checkpoint), "margin")
    m = None
    if margin == "auto":
        rho_ls = problem.radius(problem.ls_theta())
        m = slow_margin(rho_ls)
    base, refit, probe = problem, m is not None, None
    if m is not None and method == "gradient":
        # the first member (largest λ1) alone tells, cheaply, whether this structure's fits run slow: then the
        # whole sweep is fitted inside the margin at once rather than twice
        probe = sweep(problem, None, [float(np.max(check_lambdas(lam_in)))], progress=False)
        if problem.slow_modes(probe.thetas)[1][0]:
            problem = problem.with_margin(m)
    # a probe of the sweep's own first member is that member (the method is deterministic): not fitted again
    front = sweep(problem, checkpoint if problem.margin is None or margin != "auto" else inside_ck,
                  fitted=probe if problem is base else None)
    if problem is not base and len(front.failures) == front.lambdas.size:
        # no member fits inside the margin: the sweep without it (its slow members then named, not refitted)
        problem, refit = base, False
        front = sweep(problem, checkpoint, fitted=probe)
    thetas, costs, failures = front.thetas.copy(), front.costs.copy(), dict(front.failures)
    margins = np.full(front.lambdas.size, np.nan if problem.margin is None else problem.margin)
    if refit and problem.margin is None:
        slow = problem.slow_modes(thetas)[1]
        if slow.any():  # members with modes over SLOW_FACTOR times least squares' slowest: refit inside that
            inside = sweep(problem.with_margin(m), inside_ck)
            redo = slow & np.all(np.isfinite(inside.thetas), axis=1)
            thetas[redo], costs[redo], margins[redo] = inside.thetas[redo], inside.costs[redo], m
    K = front.lambdas.size
    if len(failures) == K:
        reasons = "; ".join(f"λ1 = {front.lambdas[i]:g}: {why}" for i, why in sorted(failures.items()))
        raise ValueError(f"every member of the SE sweep ({method}) failed, so there is no Pareto set: {reasons}. "
                         + _all_failed_advice(method, failures.values(), problem.margin))
    radii = problem.warn_slow(thetas, f"SE sweep ({method}) members", auto=margin == "auto")
    if exps:  # in the data's own units: a member's θ that is no float there is refused by name
        fitted = np.array([i not in failures for i in range(K)], dtype=bool)
        thetas[fitted] = unscaled_theta(thetas[fitted], list(problem.structure), exps)
        refuse_beyond_float_range(problem.structure.terms, *thetas[fitted],
                                  prefix="se_pareto: a member cannot be used on these data: ")
        costs = unscaled_rss(costs, exps)  # output units²: inf or 0 beyond the range, as y² there
    # the sweep runs from λ1 = 1 down (an internal matter); the set keeps the caller's order of lambdas, as
    # pe_pareto's does: the caller's member k is sweep position back[k]
    back = np.searchsorted(-front.lambdas, -lam_user)
    return ParetoSet.from_thetas(problem.structure, thetas[back], front.lambdas[back], rec, sp, method=f"SE ({method})",
                                 extra={"cost": costs[back], "radius": radii[back], "margin": margins[back]},
                                 threads=threads, failures={k: failures[int(p)] for k, p in enumerate(back)
                                                            if int(p) in failures})
