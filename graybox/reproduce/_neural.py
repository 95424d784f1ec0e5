"""The neural section of `graybox reproduce`: the NARMAX MLP baseline's Table I row."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from .._evaluate import evaluate
from .._neural import PAPER_EPOCHS, neural_narx
from .._records import Dataset
from ..datasets import load_pumping
from ..plots import plot_free_run

__all__ = ["PAPER_NEURAL_ROW", "section_neural"]

#: Table I, "Neural" column, as printed (MSE in mlc²).
PAPER_NEURAL_ROW = {"J_S ident": 1.09, "J_S valid": 0.536, "J_SF": 0.0496, "N_p": 99}


def section_neural(quick: bool = True, out: Path | None = None, data: Dataset | None = None) -> str:
    """``graybox reproduce`` section: the neural NARMAX baseline's Table I row.

    Trains ny = nu = 6, ne = 2, 7 tanh hidden nodes (N_p = 99) on the identification record
    for the paper's 60 epochs from seed 0 and prints its row (J_S ident, J_S valid, J_SF, N_p;
    MSE in output units²). Training takes under a second, so ``quick`` does not shorten it
    (fewer epochs would change the model, not just the time); the full mode adds seeds 1–4
    and reports the spread of the row over the five initialisations. With ``out`` the
    seed-0 validation free run is drawn to ``out/neural_free_run.png``.
    """
    if data is None:
        data = load_pumping()
    seeds = (0,) if quick else (0, 1, 2, 3, 4)
    nets, infos = {}, {}
    for sd in seeds:
        fit = neural_narx(data.ident, epochs=PAPER_EPOCHS, seed=sd, name="Neural")
        nets[sd], infos[sd] = fit.model, fit
    net, info = nets[0], infos[0]
    cols = ["J_S ident", "J_S valid", "J_SF", "N_p"]
    table = evaluate({"Neural": net}, data)
    paper = ", ".join(f"{k} = {v}" for k, v in PAPER_NEURAL_ROW.items())
    fmt = {"float_format": lambda v: f"{v:.4f}"}
    lines = [
        "== Neural NARMAX baseline (Norgaard's nnnarmax2, Section IV-A) ==",
        f"ny = nu = {net.ny}, ne = {net.ne}, {net.hidden} tanh hidden nodes, linear output; "
        f"Levenberg–Marquardt, {PAPER_EPOCHS} epochs from seed 0 ({info.accepted} steps accepted, "
        f"{info.seconds:.2f} s wall time incl. any first-call JIT compilation); training RMSE of the NARMAX predictor {info.rmse_train:.4f} {data.ident.units[1]}",
        f"N_p = {net.n_params}: {net.hidden}·{net.ny + net.nu} input + {net.hidden} bias + {net.hidden} output "
        f"weights + 1 output bias; the {net.hidden * net.ne} residual-input weights (training only) are not counted",
        f"paper (measured plant, not these data): {paper}",
        table[cols].to_string(**fmt),
    ]
    if len(seeds) > 1:
        spread = evaluate({f"seed {sd}": nets[sd] for sd in seeds}, data)[cols[:3]]
        summary = pd.DataFrame({"min": spread.min(), "median": spread.median(), "max": spread.max()}).T
        lines.append(f"spread over seeds {list(seeds)}:")
        lines.append(summary.to_string(**fmt))
    if out is not None:
        path = Path(out) / "neural_free_run.png"
        plot_free_run(data.valid, {"Neural": net}).savefig(path, dpi=120)  # type: ignore[arg-type]
        lines.append(f"figure: [{path}]")
    return "\n".join(lines)
