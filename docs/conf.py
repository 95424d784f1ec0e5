"""Sphinx configuration of graybox's documentation site.

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html`` (tests/test_docs.py runs
the same build, warnings as errors). The API reference is generated at build time from the public
names each subpackage exports (its ``__all__``), grouped by concern in the layer order of
``graybox/_layers.py``; the notebooks are copied with ``QUICK = True`` and executed by myst-nb.
"""

from __future__ import annotations

import importlib
import inspect
import json
import os
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

import graybox  # noqa: E402
from graybox._layers import LAYERS  # noqa: E402

project = "graybox"
author = "the graybox developers"
copyright = "2026, the graybox developers"
release = graybox.__version__

extensions = ["sphinx.ext.autodoc", "sphinx.ext.autosummary", "sphinx.ext.napoleon", "sphinx.ext.mathjax",
              "myst_nb"]
exclude_patterns = ["_build", "**.ipynb_checkpoints"]
html_theme = "alabaster"
html_title = "graybox"
html_static_path: list[str] = []

autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "description"
autodoc_member_order = "bysource"
autosummary_generate = False
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# Dataclass fields are documented in their class's Parameters/Attributes sections; numpy-style
# "Attributes" sections would list them a second time as directives.
napoleon_use_ivar = True
# Attribute names repeat across classes (``n_terms`` of a Selection and of a StructureSpec); a field
# type naming one is ambiguous to Sphinx but harmless to a reader.
suppress_warnings = ["myst.header", "ref.python"]

myst_enable_extensions = ["dollarmath"]
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 600
nb_execution_show_tb = True
nb_merge_streams = True

# --- the API reference, written from the public names --------------------------------------------
#: Public subpackages in the reference, in layer order (top-level names are re-exports of these).
#: ``reproduce`` is the command ``graybox reproduce``; ``reference`` (the paper's tables and models, which the README
#: sends readers to) is data a user reads.
API_PACKAGES = [unit for unit, _, _ in LAYERS if not unit.startswith("_") and unit != "reproduce"]
OWNS = {unit: owns for unit, _, owns in LAYERS}


def _write_api() -> None:
    out = HERE / "api"
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir()
    index = ["API reference", "=============", "",
             *_at_the_top(), "", "The subpackages are listed bottom layer first: each uses only those before it.",
             "", ".. toctree::", "   :maxdepth: 1", ""]
    for unit in API_PACKAGES:
        mod = importlib.import_module(f"graybox.{unit}")
        names = sorted(mod.__all__, key=lambda n: (not n[0].isupper(), n.lower()))
        title = f"graybox.{unit}"
        lines = [title, "=" * len(title), "", f".. module:: graybox.{unit}", "", OWNS[unit][0].upper() + OWNS[unit][1:]
                 + ".", ""]
        for name in names:
            obj = getattr(mod, name)
            directive = _api_directive(obj)
            if directive == "py:data":
                # the name alone: under ".. module::" a dotted one was taken as relative to it (anchors
                # "graybox.datasets.graybox.datasets.BUCK_STATIC_CURVE")
                lines += [f".. py:data:: {name}", "", *_data_doc(unit, name, obj), ""]
                continue
            lines += [f".. {directive}:: graybox.{unit}.{name}", ""]
        (out / f"{unit}.rst").write_text("\n".join(lines), encoding="utf-8")
        index.append(f"   {unit}")
    (out / "index.rst").write_text("\n".join(index) + "\n", encoding="utf-8")


def _api_directive(obj: object) -> str:
    """How the reference shows a public name: a class, an exception, a function, or a constant (``py:data``, with
    its ``#:`` comment). A callable instance is a constant: ``BUCK_STATIC_CURVE``, a StaticCurve, was shown as a
    function carrying StaticCurve's docstring."""
    if isinstance(obj, type):
        return "autoexception" if issubclass(obj, BaseException) else "autoclass"
    return "autofunction" if inspect.isroutine(obj) else "py:data"


def _at_the_top() -> list[str]:
    """Which names below are also exported from :mod:`graybox` itself, read from the package (not written by hand)."""
    top = set(graybox.__all__)
    whole, some, none = [], [], []
    for unit in API_PACKAGES:
        names = importlib.import_module(f"graybox.{unit}").__all__
        there = [n for n in names if n in top]
        (whole if len(there) == len(names) else some if there else none).append((unit, there))
    mods = ", ".join(f":mod:`graybox.{u}`" for u, _ in whole)
    lines = [f"Every name of {mods} is also exported from :mod:`graybox` itself (``import graybox as gb``)."]
    for unit, there in some:
        lines.append(f"Of :mod:`graybox.{unit}`, only " + ", ".join(f"``{n}``" for n in sorted(there))
                     + " are; the others are used through the subpackage.")
    if none:
        lines.append("The names of " + ", ".join(f":mod:`graybox.{u}`" for u, _ in none)
                     + " are used through their subpackage.")
    return lines


def _data_doc(unit: str, name: str, obj: object) -> list[str]:
    """The ``#:`` comment of a public constant, read from the private module that defines it."""
    from sphinx.pycode import ModuleAnalyzer

    # a subpackage's private modules, or the module itself when it has none (graybox.reference)
    for full in [f"graybox.{unit}.{m}" for m in dict((u, m) for u, m, _ in LAYERS)[unit]] or [f"graybox.{unit}"]:
        if getattr(importlib.import_module(full), name, None) is obj:
            doc = ModuleAnalyzer.for_module(full).find_attr_docs().get(("", name))
            if doc:
                return ["   " + line for line in doc]
    return ["   " + f"``{name}``"]


def _literal_bars(app, what, name, obj, options, lines) -> None:  # noqa: ANN001
    """Docstrings write absolute values and norms as |x|, which reStructuredText reads as a substitution. Inside an
    inline literal (between double backticks, which may span lines) a bar is no markup and a backslash shows as
    itself: those bars are left alone."""
    inside = False  # within an inline literal begun on an earlier line of its paragraph
    for i, line in enumerate(lines):
        bare = line.strip()
        if not bare:
            inside = False  # a literal ends with its paragraph at the latest
            continue
        if bare.startswith("+") or (bare.startswith("|") and bare.endswith("|")):  # a table's or a line block's
            continue
        parts = line.split("``")
        for k in range(len(parts)):
            inside = inside != (k > 0)  # each ``, after the first part, opens or closes a literal
            if not inside:
                parts[k] = parts[k].replace("|", "\\|")
        lines[i] = "``".join(parts)


#: Where each public name is documented: its subpackage.
HOME = {name: unit for unit in reversed(API_PACKAGES) for name in importlib.import_module(f"graybox.{unit}").__all__}

#: Cross-references to graybox's own names (``graybox.X``, or a public name alone: ``Model.name``) must resolve (a
#: broken one is a warning, so an error of the -W build); the others (numpy, pandas, "optional", "shape (N,)" of
#: numpy-style type lines) and private names are not checked.
nitpicky = True
nitpick_ignore_regex = [(r".*", r"(?!graybox\.|(?:" + "|".join(sorted(HOME)) + r")(?:\.|$)).*"),
                        (r".*", r"graybox\.(\w+\.)*_\w*(\..*)?")]


def _public_home(app, env, node, contnode):  # noqa: ANN001, ANN202
    """Docstrings name a public name where users meet it, ``graybox.frols``, ``graybox.LocalModel.ybar`` or, in another
    subpackage's docstring, ``Model``; the reference documents it under its subpackage (``graybox.selection.frols``).
    Without this such a reference rendered as unlinked text: 122 of them."""
    if node.get("refdomain") != "py":
        return None
    name = node.get("reftarget", "").lstrip("~.")
    head, _, rest = (name[len("graybox."):] if name.startswith("graybox.") else name).partition(".")
    if head not in HOME:
        return None
    target = f"graybox.{HOME[head]}.{head}" + (f".{rest}" if rest else "")
    return env.get_domain("py").resolve_xref(env, node["refdoc"], app.builder, node["reftype"], target, node, contnode)


def setup(app):  # noqa: ANN001, ANN201
    app.connect("autodoc-process-docstring", _literal_bars)
    app.connect("missing-reference", _public_home)


# --- the notebooks, executed in quick mode -------------------------------------------------------
#: Set by the test suite (tests/conftest.py): a folder for the verdicts of the notebooks' checks, which run in the
#: kernels of this build rather than in a second execution of every notebook.
CHECKS = os.environ.get("GRAYBOX_NOTEBOOK_CHECKS", "")


def _hidden_cell(source: str) -> dict:
    """A code cell the site does not show (myst-nb's ``remove-cell`` tag)."""
    return {"cell_type": "code", "metadata": {"tags": ["remove-cell"]}, "source": source, "outputs": [],
            "execution_count": None}


def _copy_notebooks() -> None:
    out = HERE / "notebooks"
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir()
    for src in sorted((ROOT / "notebooks").glob("*.ipynb")):
        nb = json.loads(src.read_text(encoding="utf-8"))
        first = next(c for c in nb["cells"] if c["cell_type"] == "code")
        first["source"] = ["QUICK = True  # the documentation runs every notebook in its quick mode"]
        nb["nbformat_minor"] = max(nb.get("nbformat_minor", 0), 5)
        if CHECKS:  # the test suite's build: its checks run in the notebook's own kernel (tests/_notebook_checks.py)
            nb["cells"] = [_hidden_cell(f"import sys\nsys.path.insert(0, {str(ROOT / 'tests')!r})\n"
                                        "import _notebook_checks\n_notebook_checks.start()"),
                           *nb["cells"],
                           _hidden_cell(f"_notebook_checks.finish({src.name!r}, globals(), {CHECKS!r})")]
        for i, cell in enumerate(nb["cells"]):  # cell ids, which nbformat 4.5 requires
            cell.setdefault("id", f"cell-{i}")
        (out / src.name).write_text(json.dumps(nb, indent=1), encoding="utf-8")


_write_api()
_copy_notebooks()
# Figures inline, whatever the machine's default backend; the notebooks' checkpoints land in a scratch folder.
os.environ.setdefault("MPLBACKEND", "Agg")
nb_execution_in_temp = True
