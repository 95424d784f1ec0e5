"""The neural section of `graybox reproduce`: the NARMAX MLP's Table I row."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from ..models._evaluate import evaluate
from ..estimation._neural import DEFAULT_EPOCHS, DEFAULT_SIM_EPOCHS, DEFAULT_WEIGHT_DECAY, PAPER_EPOCHS, neural_narx
from ..core._records import Dataset
from ..core._validation import check_bool, check_path, frozen_value
from ..datasets import load_pumping
from ..plots import plot_free_run
from ..reference import TABLE_I

__all__ = ["PAPER_NEURAL_ROW", "section_neural"]


def figure_name(stem: str, quick: bool) -> str:
    """The file name of a ``graybox reproduce`` figure: ``<stem>.png`` in the full run, ``<stem>_quick.png`` in the
    quick one (as the checkpoints), so a quick run in the full run's folder leaves the full run's figures alone."""
    return f"{stem}{'_quick' if quick else ''}.png"


def out_folder(out: object) -> Path:
    """A section's ``out`` made ready before its work: a folder name (``TypeError`` naming ``out`` otherwise), not
    empty (``Path("")`` is the current folder, which nobody named: ``ValueError``, as :func:`graybox.reproduce.run`
    says), created if missing (as ``run`` creates it: a missing folder failed at the first figure, after the
    section's fits, and an empty name wrote there)."""
    out = check_path(out, "out")  # '~/figs' the home folder's, as check_path reads it
    if not os.fspath(out):
        raise ValueError("out is empty: give the folder's name ('.' for the current folder)")
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"{folder} is a file, not a folder for the figures")
    folder.mkdir(parents=True, exist_ok=True)
    return folder


#: Table I, "Neural" column, as printed (MSE in mlc²); read-only, as TABLE_I (a dict copy let an edit change the
#: "paper" row section_neural prints).
PAPER_NEURAL_ROW = TABLE_I["Neural"]

#: The paper's training: Norgaard's nnnarmax2 alone (one-step prediction error, no weight decay).
PAPER_TRAINING = frozen_value({"epochs": PAPER_EPOCHS, "sim_epochs": 0, "weight_decay": 0.0}, "PAPER_TRAINING")


def section_neural(quick: bool = True, out: Path | None = None, data: Dataset | None = None) -> str:
    """``graybox reproduce`` section: the neural NARMAX model's Table I row.

    The paper's network (ny = nu = 6, ne = 2, 7 tanh hidden nodes, N_p = 99) trained on the
    identification record twice from seed 0: by the default of :func:`graybox.neural_narx`
    (prediction error, then simulation error with weight decay) and by the paper's training
    (``nnnarmax2``: 60 epochs of one-step prediction error), each with its Table I row (columns
    JS_ident, JS_valid, JSF, n_params; MSE in output units²). Each training takes well under a second;
    the full mode adds seeds 1–4 and reports the spread (min / median / max) of both rows over
    the five initialisations. With ``out`` the default network's validation free run is drawn
    to ``out/neural_free_run.png`` (``neural_free_run_quick.png`` in quick mode); ``out`` is
    created if missing, before the training.
    """
    quick = check_bool(quick, "quick")  # "no" is truthy: five seeds
    if out is not None:
        out_folder(out)  # before the training, not at the figure after it
    if data is None:
        data = load_pumping()
    elif not isinstance(data, Dataset):  # a Record failed on its missing .ident, a bare AttributeError
        raise TypeError(f"data must be a Dataset (ident and valid records, static points), got {type(data).__name__}")
    seeds = (0,) if quick else (0, 1, 2, 3, 4)
    fits = {sd: neural_narx(data.ident, seed=sd, name="Neural") for sd in seeds}
    paper = {sd: neural_narx(data.ident, seed=sd, name="Neural, paper's training", **PAPER_TRAINING).model
             for sd in seeds}
    fit = fits[0]
    net = fit.model
    cols = ["JS_ident", "JS_valid", "JSF", "n_params"]
    table = evaluate({"Neural": net, "Neural, paper's training": paper[0]}, data)
    fmt = {"float_format": lambda v: f"{v:.4f}"}
    yu = data.ident.units[1]
    lines = [
        "== Neural NARMAX model (Section IV-A: the network of Norgaard's nnnarmax2) ==",
        f"ny = nu = {net.ny}, ne = {net.ne}, {net.hidden} tanh hidden nodes, linear output; "
        f"N_p = {net.n_params}: {net.hidden}·{net.ny + net.nu} input + {net.hidden} bias + {net.hidden} output "
        f"weights + 1 output bias; the {net.hidden * net.ne} residual-input weights (training only) are not counted",
        f"default training: {DEFAULT_EPOCHS} epochs of one-step prediction error (nnnarmax2), then "
        f"{DEFAULT_SIM_EPOCHS} of free-run simulation error, weight decay D = {DEFAULT_WEIGHT_DECAY:g} "
        "(chosen by cross-validation on the identification record), residual inputs re-fitted; "
        f"seed 0: {fit.epochs} epochs, {fit.seconds:.2f} s incl. any first-call JIT compilation; "
        f"free-run RMSE on the training data {fit.rmse_sim:.4f} {yu}",
        f"paper's training: {PAPER_EPOCHS} epochs of nnnarmax2 (one-step prediction error) alone, D = 0: on "
        "these data its free run degrades as the one-step fit improves (see graybox.estimation._neural's docstring)",
        "paper (measured plant, not these data): " + ", ".join(f"{k} = {v}" for k, v in PAPER_NEURAL_ROW.items()),
        "seed 0:",
        table[cols].to_string(**fmt),
    ]
    if len(seeds) > 1:
        for label, nets in (("default", {sd: f.model for sd, f in fits.items()}), ("paper's training", paper)):
            spread = evaluate({f"seed {sd}": nets[sd] for sd in seeds}, data)[cols[:3]]
            summary = pd.DataFrame({"min": spread.min(), "median": spread.median(), "max": spread.max()}).T
            lines.append(f"{label}, spread over seeds {list(seeds)}:")
            lines.append(summary.to_string(**fmt))
    if out is not None:
        path = Path(out) / figure_name("neural_free_run", quick)
        plot_free_run(data.valid, {"Neural": net}, ylabel="Pressure").savefig(path, dpi=120)  # type: ignore[arg-type]
        lines.append(f"figure: [{path}]")
    return "\n".join(lines)
