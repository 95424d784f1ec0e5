"""The commented example spec that ``graybox grid init`` prints (the bundled pumping plant)."""

__all__ = ["EXAMPLE_SPEC"]

#: The TOML text ``graybox grid init`` prints: a commented grid for the bundled pumping plant, to edit and run with
#: ``graybox grid run`` (from Python: ``Grid.from_toml_text(EXAMPLE_SPEC)``).
EXAMPLE_SPEC = '''\
# A graybox grid: data sets x structures x variants x seeds.
#   graybox grid run spec.toml --store results.sqlite [--workers N | --scheduler ADDRESS]
#   graybox grid status results.sqlite          (from another terminal, while it runs)
#   graybox grid report results.sqlite --out report/ --html
# Every cell (data, structure, variant, seed) is scored by the shared evaluator on the
# identification AND the validation record. Running again skips the cells already in the store;
# add data sets, structures, variants or seeds here and only the new cells run.

name = "pumping-variants"
seeds = [0, 1]            # used by the stochastic estimators (se-ga, neural); the others run once

# ---------------------------------------------------------------------------------- data sets
[[data]]
name = "pumping"
bundled = "pumping"       # or "buck" (the real buck converter, measured) or "pumping_miso" (two pump speeds)
# D_SF's band B = [0, band] on J_SF (output units^2) comes from the static points' uncertainty:
# the bundled plant's transmitter error +/-0.175 mlc gives 0.175^2 mlc^2. To choose another: band = 0.05

# Your own plant: CSV files, columns chosen by name; paths relative to this file.
# [[data]]
# name = "my-plant"
# ident = {path = "ident.csv", u = "speed", y = "pressure", time = "t"}    # or Ts = 0.05 (seconds)
# valid = {path = "valid.csv", u = "speed", y = "pressure", time = "t"}
# static = {path = "static.csv", u = "speed", y = "pressure", uncertainty = 0.175}  # steady states, +/- error
# (uncertainty = "delta": each point's error from the file's column delta; the band is then their mean square)
# (without uncertainty give band = B, J_SF's bound in output units^2, and b to every band constraint)
# Several inputs: u = ["speed1", "speed2"] in all three files; input_names = ["n1", "n2"] (in each file's
# table too) names them for the terms (n1(k-1)) when the columns' names are not identifiers, e.g. "speed [rpm]".
# Static files that repeat an operating point: repeats = "mean" averages the repeats into one point.
# Files as a logger or a spreadsheet wrote them: skiprows = 3 (a header block above the column names),
# delimiter = ";", decimal = ",", encoding = "cp1252", time_rtol = 0.01 (stamps printed with few digits),
# units_row = true (a row of units under the names). A Campbell Scientific logger's TOA5 .dat needs none of
# them (give Ts; its units are read from the file).

# --------------------------------------------------------------------------------- structures
# Made by FROLS: a candidate space (graybox.Candidates) and a rule (n_terms, tol or criterion).
[[structures]]
name = "frols-17"
candidates = {ny = 6, nu = 6, degree = 2, max_y_power = 1}   # max_y_power = 1: rational statics, eq. (22) applies
n_terms = 17
include = ["1"]           # the constant first: eq. (22) needs it

[[structures]]
name = "frols-bic"
candidates = {ny = 3, nu = 3, degree = 2, max_y_power = 1}
criterion = "bic"
include = ["1"]

# Given: the terms themselves.
[[structures]]
name = "first-order"
terms = ["y(k-1)", "u(k-1)", "u(k-1)^2", "u(k-1)y(k-1)", "1"]

# ----------------------------------------------------------------------------------- variants
# estimator: ls, els, cls, pe, se-ga, se-gradient, se-dsf (the D_SF model solved directly), neural
# constraints (cls, pe): {type = "equality"} (eq. (22); curve = "fit" | "dataset" | [c0, c1, ...];
#   Sigma*_y estimated unless sigma_y = 0.95 or options = {reference = "els"}),
#   {type = "points"}, {type = "band"} (half-width: the static points' uncertainty; or b = 0.2 in
#   output units), {type = "gain", lower = 0.0},
#   {type = "clusters", bounds = {Sy = {upper = 0.999}}}; a list imposes them together.
# lambdas (pe, se-*): a list of lambda1 in (0, 1], or {logspace = [a, b, n]} (se-dsf: its coarse sweep).
# decision (pe, se-ga, se-gradient): {rule = "dsf"} (band from the data set), {rule = "dsf", band = 0.05,
#   fallback = "min_jsf"}, {rule = "min_correlation"}, {rule = "min_jsf"}.
# options: the estimator's keyword options (se-dsf: band, default the data set's; max_iter; tol).

[[variants]]
name = "LS"
estimator = "ls"

[[variants]]
name = "ELS"
estimator = "els"
options = {noise = 2}

[[variants]]
name = "CLS eq.(22)"
estimator = "cls"
constraints = [{type = "equality", curve = "fit"}]
options = {reference = "els"}     # Sigma*_y from ELS, as in the paper

[[variants]]
name = "PE"
estimator = "pe"
lambdas = {logspace = [-6, 0, 30]}
options = {solver = "closed"}     # eq. (11), no constraints

[[variants]]
name = "PE band"
estimator = "pe"
lambdas = {logspace = [-3, 0, 10]}
constraints = [{type = "band"}]

[[variants]]
name = "PE band+gain"
estimator = "pe"
lambdas = {logspace = [-3, 0, 10]}
constraints = [{type = "band"}, {type = "gain", lower = 0.0}]

[[variants]]
name = "SE gradient"
estimator = "se-gradient"
lambdas = {logspace = [-2, 0, 10]}
options = {max_nfev = 30}

[[variants]]
name = "SE D_SF direct"
estimator = "se-dsf"               # min J_S subject to J_SF <= the data set's band, no sweep to decide on
lambdas = {logspace = [-2, 0, 8]}  # the coarse sweep that finds its starts

[[variants]]
name = "SE GA (short)"
estimator = "se-ga"
lambdas = {logspace = [-2, 0, 5]}
decision = {rule = "dsf", fallback = "min_jsf"}
options = {population = 40, generations = 10}
'''
