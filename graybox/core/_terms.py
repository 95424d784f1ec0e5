"""Polynomial NARMAX terms, structures and candidate sets.

A :class:`Term` is a product of lagged signals with powers, e.g. ``u(k-2)y(k-6)``
or ``u(k-6)^2``; the empty product is the constant term ``1``. Signals are named:
``"y"`` is the output, ``"e"`` the noise/residual, and every other valid identifier
(``"u"`` for a single input, ``"u1"``, ``"u2"``, … or a CSV column's name such as
``"n1"``) is an input. A :class:`Structure` is an ordered tuple of distinct terms.
:func:`Candidates` enumerates every monomial up to a degree, with lags per input.

Printing follows the paper (``"u(k-2)y(k-6)"``, ``"u1(k-1)u2(k-2)"``): inputs first
in natural name order (u2 before u10), then y, then e; :func:`parse_term` reads any
factor order back, and ``parse_term(str(t)) == t`` for every term.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Iterable, Iterator, Mapping, Sequence

from ._renamed import RenamedAttribute
from ._validation import check_bool, check_int, check_ordered, check_real, check_sequence

__all__ = ["Term", "Structure", "Candidates", "parse_term", "parse_structure", "SIGNALS", "check_input_names",
           "default_input_names", "require_inputs", "transient_name", "transient_source", "carried_input_names"]

#: The signals of a single-input model, in printing order (the paper writes u before y). Any
#: other identifier except ``y``, ``e`` and ``k`` is accepted as the name of a further input.
SIGNALS: tuple[str, ...] = ("u", "y", "e")
_RESERVED = ("y", "e", "k")
_NAME_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
_NUM_RE = re.compile(r"(\d+)")


@lru_cache(maxsize=1024)
def _rank(signal: str) -> tuple:
    """Printing/sorting rank of a signal: inputs (natural name order), then y, then e."""
    if signal == "y":
        return (1,)
    if signal == "e":
        return (2,)
    # the name itself breaks ties: a01 and a1 read as one number, and ranked alike they were ordered by the order
    # given (one monomial, two terms) or by a set's iteration (a structure's inputs, by the hash seed)
    return (0, tuple((0, int(p), "") if p.isdigit() else (1, 0, p) for p in _NUM_RE.split(signal) if p), signal)


def _check_signal(sig: object) -> str:
    if not isinstance(sig, str) or not _valid_signal(sig):
        raise ValueError(f"unknown signal {sig!r}: a signal is y (output), e (noise) or an input named by an "
                         "identifier other than y, e, k (e.g. u, u1, n1)")
    return sig


@lru_cache(maxsize=1024)
def _valid_signal(sig: str) -> bool:
    return bool(_NAME_RE.match(sig)) and sig != "k"


def transient_name(input_name: str, tau: float) -> str:
    """The name of the transient input of ``input_name`` with time constant ``tau`` seconds: ``u_tau30``, ``u_tau2p5``.

    Parameters
    ----------
    input_name : str
        The input's name, e.g. ``"u"``.
    tau : float
        The time constant in seconds (> 0).

    Returns
    -------
    str
        ``{input_name}_tau{τ}``, τ written with ``p`` for the decimal point: to 6 significant digits where they
        give τ back exactly (``u_tau30``, ``u_tau2p5``), else with every digit it takes (``u_tau0p3333333333333333``
        for τ = 1/3), so that τ read back from the name (a model's transient input in a control system) is τ itself.
    """
    if not isinstance(input_name, str):
        raise TypeError(f"input_name must be a str, got {input_name!r} ({type(input_name).__name__})")
    tau = check_real(tau, "tau (seconds)", low=0, low_open=True)
    text = f"{tau:g}"
    if float(text) != tau:  # 6 digits would lose τ: 1/3 read back as 0.333333 (ρ = e^(−Ts/τ) 1e-6 off)
        text = repr(tau)
    tag = text.replace(".", "p").replace("-", "m").replace("+", "")
    return f"{input_name}_tau{tag}"


def require_inputs(used: Iterable[str], names: tuple[str, ...], among: str, prefix: str = "") -> None:
    """``ValueError`` unless every input a structure ``used`` is in ``names``; a missing transient input of
    an input that is there says how to add it. ``among`` joins the two in the message (e.g. "which is
    not among the inputs")."""
    used = tuple(used)
    missing = [n for n in used if n not in names]
    if not missing:
        return
    raise ValueError(f"{prefix}the structure uses input {missing[0]!r}, {among} {names}{missing_input_hint(used, names)}")


def missing_input_hint(used: Sequence[str], names: Sequence[str], data: str = "record") -> str:
    """How to give the data the inputs a structure ``used`` lacks among ``names``: a transient input of an input
    that is there, added with transient_inputs; inputs left with their default names, named; else terms and
    data named alike (:func:`rename_hint`). Every message of a missing input says it (:func:`require_inputs`, the
    regressors'). ``data``: what transient_inputs is told to extend (``"record"``, ``"static"``)."""
    used, names = tuple(used), tuple(names)
    missing = [n for n in used if n not in names]
    if not missing:
        return ""
    source = transient_source(missing[0], names)
    if source is not None:
        tau = transient_tau_text(missing[0], source)
        return (f" (if it is a transient input, add it with graybox.transient_inputs({data}, taus=[{tau}], "
                f"input_names=[{source!r}]))")
    if names == default_input_names(len(names)):
        # the data's inputs carry the default names: they were never named (one CSV column is "u")
        # one input: its name is sure; several: the columns' order is the data's, which only the user knows
        said = (f"{list(missing)}" if len(names) == 1 else
                f"[...], one per column in the columns' order (the structure uses {', '.join(map(repr, used))})")
        return (f" (the data's inputs have the default names: name them, e.g. Record(..., input_names={said}), "
                "load_record_csv(..., input_names=[...]) or input_names = [...] in a grid spec's file entry)")
    return rename_hint(used, names)


def rename_hint(used: Sequence[str], have: Sequence[str]) -> str:
    """How to make terms and data name their inputs alike (e.g. candidates made with the default ``u`` for a
    record whose input is named after its column)."""
    if len(used) != len(have):
        defaults = {"u", *(f"u{i}" for i in range(1, len(have) + 1))}
        if set(used) <= defaults and not set(have) & defaults:
            # candidates made without naming their inputs (the default "u") for data whose inputs are named
            return (f": candidates made without input names are for one input 'u'; make them for the data's "
                    f"{len(have)} input(s), e.g. Candidates(..., input_names={list(have)!r}) (an int nu is every "
                    "input's largest lag)")
        return ""
    return (f": name the inputs alike, in the terms (Candidates(..., input_names={list(have)!r}), "
            f"{used[0]}(k-1) written {have[0]}(k-1)) or in the data (Record(..., input_names={list(used)!r}), "
            "the loaders' input_names=)")


def transient_tau_text(name: str, source: str) -> str:
    """τ as :func:`transient_name` wrote it in the name of ``source``'s transient input, read back ("2.5" of
    ``u_tau2p5``; not checked to be a number)."""
    return name[len(source) + len("_tau"):].replace("p", ".").replace("m", "-")


def transient_source(name: str, names: Iterable[str]) -> str | None:
    """The input among ``names`` whose transient input ``name`` looks like (``"u"`` for ``"u_tau30"``), or None."""
    m = re.fullmatch(r"(.+)_tau([0-9][0-9pem]*)", name)
    return m.group(1) if m is not None and m.group(1) in set(names) else None


def default_input_names(m: int) -> tuple[str, ...]:
    """The input names used when none are given: ``("u",)`` for one input, ``u1 … um`` otherwise."""
    return ("u",) if m == 1 else tuple(f"u{i}" for i in range(1, m + 1))


def check_input_names(names: object, m: int | None = None, what: str = "input_names") -> tuple[str, ...]:
    """Validated input names: identifiers, not y/e/k, none given twice (and ``m`` of them when given)."""
    if isinstance(names, (str, Mapping)) or not hasattr(names, "__iter__"):  # a mapping's keys: its values dropped
        raise TypeError(f"{what} must be a sequence of names (strings), got {names!r}")
    check_ordered(names, what, "names (one per input column, in order)")
    out = tuple(names)  # type: ignore[arg-type]
    if not out:
        raise ValueError(f"{what}: at least one input name is needed")
    for n in out:
        if not isinstance(n, str):
            raise TypeError(f"{what}: an input name must be a string, got {n!r}")
        if not _NAME_RE.match(n) or n in _RESERVED:
            why = (f"is {n!r}, the name of the output, the noise or the time index" if n in _RESERVED else
                   "is not an ASCII letter followed by ASCII letters, digits or _")
            raise ValueError(f"{what}: input name {n!r} is not a valid identifier other than y, e, k (it {why}; "
                             "terms print the inputs by name, e.g. n1(k-1))")
    dup = sorted({n for n in out if out.count(n) > 1})
    if dup:
        raise ValueError(f"{what}: input {dup[0]!r} is named twice in {out}")
    if m is not None and len(out) != m:
        raise ValueError(f"{what}: {len(out)} names {out} for {m} input column(s)")
    return tuple(str(n) for n in out)  # plain str: a numpy array's np.str_ printed as np.str_('speed') everywhere

#: y(k) reads as lag 0, which Term refuses by name (lags start at 1), as it does y(k-0)
_FACTOR_RE = re.compile(r"\s*([a-zA-Z]\w*)\s*\(\s*k\s*(?:-\s*(\d+)\s*)?\)\s*(?:\^\s*(\d+))?\s*\*?")


#: Largest lag of a factor (the compiled kernels encode terms as int64).
_INT64_MAX = 2**63 - 1

#: Largest power of a factor: x^1024 overflows a float for every |x| >= 2 and underflows for every
#: |x| <= 1/2, so no larger power means anything; the kernels raise to a power by repeated
#: multiplication, and a power near 2^63 never finished.
MAX_POWER = 1023


@dataclass(frozen=True, order=False)
class Term:
    """A monomial in lagged signals.

    Parameters
    ----------
    factors : tuple of (signal, lag, power)
        ``signal`` is ``"y"``, ``"e"`` or an input name, ``lag >= 1`` samples (``lag >= 0`` for ``e``,
        not used here), ``power >= 1``. Stored in canonical order with repeated
        (signal, lag) pairs merged. The empty tuple is the constant term.
    """

    factors: tuple[tuple[str, int, int], ...] = ()

    def __post_init__(self) -> None:
        merged: dict[tuple[str, int], int] = {}
        for f in check_sequence(self.factors, "factors", "a sequence of (signal, lag, power) factors"):
            if isinstance(f, str) or not isinstance(f, Sequence) or len(f) != 3:
                raise ValueError(f"factors: a factor must be (signal, lag, power), got {f!r}")
            sig, lag, power = f
            _check_signal(sig)
            lag = check_int(lag, f"factors: lag of {sig}", low=1)
            power = check_int(power, f"factors: power of {sig}(k-{lag})", low=1)
            merged[(sig, lag)] = merged.get((sig, lag), 0) + power
            if lag > _INT64_MAX:  # the compiled kernels hold lags as int64
                raise ValueError(f"factors: {sig}(k-{lag}): a lag beyond the 64-bit integer range")
            if merged[(sig, lag)] > MAX_POWER:
                raise ValueError(f"factors: {sig}(k-{lag})^{merged[(sig, lag)]}: a power above {MAX_POWER} (a float "
                                 "raised to it overflows or underflows unless its size is within a factor 2 of 1)")
        canon = tuple(
            (s, l, p) for (s, l), p in sorted(merged.items(), key=lambda kv: (_rank(kv[0][0]), kv[0][1]))
        )
        object.__setattr__(self, "factors", canon)

    # -- properties -------------------------------------------------------
    @property
    def is_constant(self) -> bool:
        """True for the constant term ``1``."""
        return not self.factors

    @property
    def degree(self) -> int:
        """Total degree (sum of powers)."""
        return sum(p for _, _, p in self.factors)

    def power_of(self, signal: str) -> int:
        """Total power of one signal in the term (e.g. 2 for ``y`` in ``u(k-1)y(k-2)^2``).

        Parameters
        ----------
        signal : str
            A signal's name: ``"y"``, ``"e"`` or an input's.

        Returns
        -------
        int
            0 when the term does not hold it.
        """
        return sum(p for s, _, p in self.factors if s == signal)

    @property
    def input_names(self) -> tuple[str, ...]:
        """The input signals of the term, in printing order (empty for y-only terms)."""
        out: list[str] = []
        for s, _, _ in self.factors:
            if s not in ("y", "e") and s not in out:
                out.append(s)
        return tuple(out)

    inputs = RenamedAttribute("input_names")

    @property
    def input_power(self) -> int:
        """Total power of all inputs together (e.g. 3 for ``u1(k-1)u2(k-2)^2y(k-1)``)."""
        return sum(p for s, _, p in self.factors if s not in ("y", "e"))

    @property
    def max_lag(self) -> int:
        """Largest lag in the term (0 for the constant)."""
        return max((l for _, l, _ in self.factors), default=0)

    @property
    def is_noise(self) -> bool:
        """True when the term involves the noise signal ``e``."""
        return any(s == "e" for s, _, _ in self.factors)

    def __str__(self) -> str:
        if not self.factors:
            return "1"
        return "".join(f"{s}(k-{l})" + (f"^{p}" if p > 1 else "") for s, l, p in self.factors)

    def __repr__(self) -> str:
        return f"Term({str(self)!r})"

    def sort_key(self) -> tuple:
        """Key ordering terms by degree, then signals and lags (used for candidates).

        Returns
        -------
        tuple
            ``(degree, [(signal's rank, lag, −power), …])``, compared as Python compares tuples.
        """
        return (self.degree, [(_rank(s), l, -p) for s, l, p in self.factors])


def _syntax_hint(s: str, pos: int) -> str:
    """What a term that does not parse got wrong, and how terms are written."""
    rest = s[pos:]
    if rest.startswith("*") and "**" in s:
        why = "powers are written ^2, not **2"
    elif re.search(r"\(\s*k\s*\+", s):
        why = "a term holds past samples, lags only: u(k-1), never u(k+1)"
    elif re.search(r"\^\s*(?:[-+.]|\d+\s*\.)", s):
        why = "a power is a whole number >= 1, e.g. ^2"
    elif re.match(r"[+-]\s*\S", rest) and pos > 0:
        why = "give one term per string (a list of terms), not a sum"
    elif re.match(r"(?:[+-]|[+-]?\d*\.?\d+\s*\*?)\s*[a-zA-Z]", s):
        why = "terms are written without coefficients or signs (the estimators fit them)"
    else:
        why = "each factor is name(k-lag), with an optional ^power"
    return (f"; {why}. A term is a product of factors name(k-lag)^power, e.g. 'u(k-2)y(k-6)', 'u(k-1)^2', "
            "'u1(k-1)u2(k-2)', or '1' for the constant")


def parse_term(text: str) -> Term:
    """Parse a paper-style term such as ``"u(k-2)y(k-6)"``, ``"u1(k-1)u2(k-2)"``, ``"u(k-6)^2"`` or ``"1"``.

    Factors may be separated by nothing, spaces or ``*``. Raises ``ValueError`` with the
    offending text when it cannot be read, ``TypeError`` when it is not text.

    Parameters
    ----------
    text : str
        One term: lagged factors ``name(k-j)`` with optional powers ``^p``, or ``"1"`` for the constant.

    Returns
    -------
    Term
    """
    if not isinstance(text, str):
        raise TypeError(f"a term must be a string, got {type(text).__name__}")
    s = text.strip()
    if s == "1":
        return Term(())
    if not s:
        raise ValueError("cannot parse an empty term")
    factors = []
    pos = 0
    while pos < len(s):
        m = _FACTOR_RE.match(s, pos)
        if m is None or m.end() == pos:
            raise ValueError(f"cannot parse term {text!r} at position {pos}: {s[pos:]!r}{_syntax_hint(s, pos)}")
        sig, lag, power = m.group(1), int(m.group(2) or 0), int(m.group(3) or 1)
        try:
            _check_signal(sig)
        except ValueError as exc:
            raise ValueError(f"cannot parse term {text!r}: {exc}") from None
        factors.append((sig, lag, power))
        pos = m.end()
        if pos == len(s) and s.endswith("*"):  # 'y(k-1)*' (a truncated 'y(k-1)*u(k-2)') read as y(k-1)
            raise ValueError(f"cannot parse term {text!r}: it ends in '*', a product missing its last factor"
                             f"{_syntax_hint(s, len(s))}")
    try:
        return Term(tuple(factors))
    except ValueError as exc:
        raise ValueError(f"cannot parse term {text!r}: {exc}") from None


#: Structures with more terms print as a summary (a candidate set would fill the screen).
_REPR_TERMS = 12


@dataclass(frozen=True)
class Structure:
    """An ordered tuple of distinct terms: the model's regressors in parameter order.

    Parameters
    ----------
    terms : sequence of Term or str
        Terms, or paper-style strings parsed with :func:`parse_term`.
    """

    terms: tuple[Term, ...]

    def __init__(self, terms: Iterable[Term | str]):
        if isinstance(terms, str):  # iterated, it would be read character by character
            raise TypeError(f"a structure is a sequence of terms, got the string {terms!r}: pass a list of terms, "
                            "or parse a '+'-joined string with parse_structure")
        if isinstance(terms, (bytes, Mapping)) or not isinstance(terms, Iterable):
            # a dict of term -> θ read as its keys (its values dropped), a number a bare "not iterable"
            raise TypeError(f"a structure is a sequence of terms (str or Term), got {type(terms).__name__}"
                            + (": pass the terms, list(d), and their values apart" if isinstance(terms, Mapping) else ""))
        check_ordered(terms, "a structure", "terms (the order of θ)")
        ts = tuple(t if isinstance(t, Term) else parse_term(t) for t in terms)
        seen: set[Term] = set()
        for t in ts:
            if t in seen:
                raise ValueError(f"duplicated term {t} in structure")
            seen.add(t)
        object.__setattr__(self, "terms", ts)

    def __len__(self) -> int:
        return len(self.terms)

    def __hash__(self) -> int:
        # cached: structures key the compiled-code cache and are hashed on every kernel call
        h = self.__dict__.get("_hash")
        if h is None:
            h = hash(self.terms)
            object.__setattr__(self, "_hash", h)
        return h

    def __getstate__(self) -> dict:
        # without the cached hash: a str's hash differs from one process to the next (PYTHONHASHSEED), so a
        # structure sent to a worker (executor="processes") carried a hash no equal structure there has, and
        # missed every set, dict and compiled-code cache keyed by an equal one
        state = dict(self.__dict__)
        state.pop("_hash", None)
        return state

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Structure) and (self is other or self.terms == other.terms)

    def __iter__(self) -> Iterator[Term]:
        return iter(self.terms)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return Structure(self.terms[i])
        return self.terms[i]

    def __add__(self, other: "Structure") -> "Structure":
        return Structure(self.terms + structure_of(other, "the terms added").terms)

    def index(self, term: Term | str) -> int:
        """Position of a term in the structure.

        Parameters
        ----------
        term : Term or str
            A term not in the structure is refused (``ValueError``).

        Returns
        -------
        int
            Its index in ``terms`` (and in a θ of this structure).
        """
        t = term if isinstance(term, Term) else parse_term(term)
        if t not in self.terms:
            raise ValueError(f"{t} is not in the structure {self}")
        return self.terms.index(t)

    def positions(self, terms: Iterable[Term | str], what: str = "term") -> list[int]:
        """Positions of ``terms`` in the structure, in the order given.

        Parameters
        ----------
        terms : sequence of Term or str
            Terms of the structure, each once.
        what : str, optional
            The role of the terms, named in an error message (e.g. ``"included term"``; default ``"term"``).

        Returns
        -------
        list of int
            Each term's index in ``terms`` (and in a θ of this structure).

        Raises
        ------
        ValueError
            A term that is not in the structure or is given twice (named).
        TypeError
            ``terms`` not a sequence, or an item neither a Term nor a string.
        """
        out: list[int] = []
        if isinstance(terms, (str, Term)) or not hasattr(terms, "__iter__"):
            raise TypeError(f"{what}s must be a sequence of terms (Terms or strings), got {terms!r}")
        check_ordered(terms, f"{what}s", "terms (an included term leads θ in the order given)")
        for t in terms:
            if not isinstance(t, (Term, str)):
                raise TypeError(f"{what}: a term must be a Term or a string, got {t!r}")
            try:
                term = t if isinstance(t, Term) else parse_term(t)
            except ValueError as exc:
                raise ValueError(f"{what}: {exc}") from None
            if term not in self.terms:
                raise ValueError(f"{what} {term} is not among the process candidates")
            i = self.terms.index(term)
            if i in out:
                raise ValueError(f"{what} {term} is given twice")
            out.append(i)
        return out

    def __contains__(self, term: object) -> bool:
        t = parse_term(term) if isinstance(term, str) else term
        return t in self.terms

    @cached_property
    def max_lag(self) -> int:
        """Largest lag over all terms (0 for a static structure)."""
        return max((t.max_lag for t in self.terms), default=0)

    @cached_property
    def input_names(self) -> tuple[str, ...]:
        """Every input signal the terms use, in natural name order (``()`` when none does)."""
        names = {n for t in self.terms for n in t.input_names}
        return tuple(sorted(names, key=_rank))

    inputs = RenamedAttribute("input_names")

    def input_lag(self, name: str) -> int:
        """Largest lag of one input over the terms.

        Parameters
        ----------
        name : str
            An input's name.

        Returns
        -------
        int
            Samples; 0 when no term uses it.
        """
        return max((l for t in self.terms for s, l, _ in t.factors if s == name), default=0)

    @property
    def process(self) -> "Structure":
        """The terms without the noise signal (the NARX part)."""
        return Structure(t for t in self.terms if not t.is_noise)

    @property
    def noise(self) -> "Structure":
        """The terms that involve the noise signal (the MA part)."""
        return Structure(t for t in self.terms if t.is_noise)

    @property
    def degree(self) -> int:
        """Largest term degree."""
        return max((t.degree for t in self.terms), default=0)

    def __str__(self) -> str:
        return " + ".join(str(t) for t in self.terms) if self.terms else "(empty)"

    def __repr__(self) -> str:
        names = [repr(str(t)) for t in self.terms]
        if len(names) <= _REPR_TERMS:
            return f"Structure([{', '.join(names)}])"
        # a candidate set holds hundreds of terms: its size, lags, degree and inputs, and its ends
        signals = sorted({s for t in self.terms for s, _, _ in t.factors}, key=lambda s: ({"y": 0, "e": 2}.get(s, 1), s))
        lags = ", ".join(f"{s} {min(l for t in self.terms for x, l, _ in t.factors if x == s)}.."
                         f"{max(l for t in self.terms for x, l, _ in t.factors if x == s)}" for s in signals)
        return (f"Structure({len(names)} terms, degree {self.degree}, lags {lags}: "
                f"[{', '.join(names[:3])}, …, {', '.join(names[-2:])}])")


#: What a structure argument may be, in words: every TypeError about one lists it (the estimators' coercion,
#: graybox.models._coerce.as_structure, and structure_of below say the same).
STRUCTURE_ACCEPTED = ("a Structure, a sequence of terms or a model: a sequence of terms (str or Term), a Model, or a "
                      "result that carries one (Selection, SEMPResult, ParetoSet, GrayboxSelection, ELSResult, "
                      "CLSResult, OEResult, Decision, DSFResult)")


def structure_of(obj: object, name: str = "structure") -> Structure:
    """``obj`` as a Structure: a Structure, a sequence of terms (Terms or strings), or anything that
    carries one in ``.structure`` (a Model, a Selection, a ParetoSet …) or whose ``.model`` does (an ELSResult, a
    Decision …); ``TypeError`` naming ``name`` and listing these otherwise (a lone string: naming parse_structure)."""
    if isinstance(obj, Structure):
        return obj
    carried = getattr(obj, "structure", None)
    if isinstance(carried, Structure):
        return carried
    # a result with a .model (ELSResult, CLSResult, OEResult, Decision …): the README promises them wherever a
    # structure is meant, and the estimators took them while simulate, static_curve and the rest refused them
    carried = getattr(getattr(obj, "model", None), "structure", None)
    if isinstance(carried, Structure):
        return carried
    if isinstance(obj, str):  # iterated, it would be read character by character
        raise TypeError(f"{name} must be {STRUCTURE_ACCEPTED}; got the string {obj!r:.80}: pass a list of terms, or "
                        "parse a '+'-joined string with parse_structure")
    if isinstance(obj, (bytes, Mapping)) or not isinstance(obj, Iterable):
        raise TypeError(f"{name} must be {STRUCTURE_ACCEPTED}; got {type(obj).__name__}")
    if iter(obj) is obj:  # read once, and an entry may read its structure twice (pe_pareto then found no terms)
        raise TypeError(f"{name} must be {STRUCTURE_ACCEPTED}; got a {type(obj).__name__}, which can be read only "
                        "once: pass a list of its terms (list(...))")
    try:
        return Structure(obj)
    except TypeError as exc:  # an item that is no term (a number, None): said with the argument's name
        raise TypeError(f"{name}: {exc}") from None


def carried_input_names(obj: object) -> tuple[str, ...] | None:
    """The input names, in its input arrays' column order, of what carries a structure (a Model, or a result whose
    ``.model`` is one): given where :func:`structure_of` takes its structure, a model's arrays of ū and u are read in
    its own order, as its methods read them. None for a Structure or terms (their callers' default order)."""
    for holder in (obj, getattr(obj, "model", None)):
        names = getattr(holder, "input_names", None)
        if isinstance(names, tuple) and isinstance(getattr(holder, "structure", None), Structure):
            return names
    return None


def parse_structure(text: str | Sequence[str]) -> Structure:
    """Parse ``"y(k-1) + u(k-2)y(k-6) + 1"`` (or a list of term strings) into a Structure.

    Parameters
    ----------
    text : str or sequence of str
        Terms joined by ``+``, or one string per term.

    Returns
    -------
    Structure
        The terms in the order given.
    """
    if isinstance(text, str):
        parts = text.split("+")
    else:  # a number, None or a mapping was "'int' object is not iterable" or parsed a dict's keys
        parts = check_sequence(text, "text", "a '+'-joined string of terms or a sequence of term strings")
    return Structure(parse_term(p) for p in parts)


def Candidates(
    ny: int,
    nu: int | Mapping[str, int],
    *,
    ne: int = 0,
    degree: int = 2,
    delay: int | Mapping[str, int] = 1,
    constant: bool = True,
    max_y_power: int | None = None,
    input_names: Sequence[str] | None = None,
) -> Structure:
    """Every monomial of degree <= ``degree`` in y(k-1..ny), each input's lags (and e(k-1..ne)).

    Parameters
    ----------
    ny : int
        Largest output lag (samples).
    nu : int or mapping name -> int
        Largest input lag (samples). An int applies to every input; a mapping gives each input
        its own (``{"u1": 4, "u2": 6}``) and, unless ``input_names`` is given, names the inputs.
        Input ``i``'s lags run from its delay to its ``nu``; ``nu = 0`` leaves that input out.
    ne : int, optional
        Largest noise lag. Noise terms are the linear ``e(k-1) … e(k-ne)`` only (the MA part
        of the paper's models); they are appended after the process candidates.
    degree : int, optional
        Largest total degree (the paper's ℓ).
    delay : int or mapping name -> int, optional
        Smallest input lag (pure delay, MATLAB's ``nk``, samples), >= 1; an int for every
        input or one per input (``{"u1": 1, "u2": 3}``; inputs not named get 1).
    constant : bool, optional
        Include the constant term.
    max_y_power : int, optional
        Drop terms whose total output power exceeds this. ``max_y_power=1`` keeps only
        structures with the rational static function of eq. (6) (what CLS with eq. (22) needs).
    input_names : sequence of str, optional
        Input names (default: the keys of ``nu`` when it is a mapping, else ``("u",)``, the
        single input). Names are identifiers other than y, e, k; a name given twice is an error.
        (The keyword of :class:`Record`, :class:`Model` and the loaders.)

    Returns
    -------
    Structure
        Process candidates ordered by degree, then noise terms. For ny = nu = 6, ne = 0 there
        are 91 at degree 2 and 455 at degree 3 (constant included).

    Examples
    --------
    >>> Candidates(1, {"u1": 1, "u2": 2}, delay={"u2": 2}, degree=1)
    Structure(['1', 'u1(k-1)', 'u2(k-2)', 'y(k-1)'])
    """
    if input_names is None:
        names = tuple(nu) if isinstance(nu, Mapping) else ("u",)
    else:
        names = input_names
    names = check_input_names(names, what="input_names")
    nus = _per_input(nu, names, "nu", None)
    delays = _per_input(delay, names, "delay", 1)
    ny, ne, degree = (check_int(v, name, low=0) for name, v in (("ny", ny), ("ne", ne), ("degree", degree)))
    constant = check_bool(constant, "constant")
    for n in names:
        for what, v, lo in (("nu", nus[n], 0), ("delay", delays[n], 1)):
            label = what if names == ("u",) else f"{what} of input {n!r}"
            (nus if what == "nu" else delays)[n] = check_int(v, label, low=lo)
        if nus[n] and delays[n] > nus[n]:
            label = "" if names == ("u",) else f" of input {n!r}"
            raise ValueError(f"delay{label} ({delays[n]}) must not exceed nu{label} ({nus[n]})")
    if max_y_power is not None:
        max_y_power = check_int(max_y_power, "max_y_power", low=0)
    n_u = sum(nus[n] - delays[n] + 1 for n in names if nus[n])
    count = _candidate_count(ny, n_u, degree, max_y_power) - (not constant) + ne
    if count > MAX_CANDIDATES:  # ny=10**9 ended in a MemoryError, ny=50 at degree 3 took minutes to build
        nu_said = dict(nus) if len(names) > 1 else nus[names[0]]
        raise ValueError(f"Candidates: ny={ny}, nu={nu_said}, ne={ne}, degree={degree} make "
                         f"{'more than ' if count > 10 * MAX_CANDIDATES else ''}{min(count, 10 * MAX_CANDIDATES):,} "
                         f"candidate terms, more than {MAX_CANDIDATES:,} (each a column of the regressor matrix); "
                         "take smaller lags or a lower degree")
    top_y = degree if max_y_power is None else min(max_y_power, degree)
    y_vars = [("y", i) for i in range(1, ny + 1)] if top_y else []  # none is used at max_y_power=0 (ny may be huge)
    u_vars = [(n, j) for n in names if nus[n] for j in range(delays[n], nus[n] + 1)] if degree else []
    terms: list[Term] = [Term(())] if constant else []
    # without inputs a term holds y alone, of degree top_y at most (Candidates(ny, 0, degree=10**9, max_y_power=1):
    # ny + 1 terms)
    for d in range(1, (degree if u_vars else top_y if y_vars else 0) + 1):
        # the output's part and the inputs' apart: only the powers of y kept are ever built (max_y_power=1 of
        # ny=1000 at degree 3 built all 10^8 products of y before dropping them)
        for k in range(min(d, top_y) + 1):
            for y_combo in itertools.combinations_with_replacement(y_vars, k):
                for u_combo in itertools.combinations_with_replacement(u_vars, d - k):
                    terms.append(Term(tuple((s, l, 1) for s, l in y_combo + u_combo)))
    terms.sort(key=Term.sort_key)
    terms += [Term((("e", l, 1),)) for l in range(1, ne + 1)]
    return Structure(terms)


#: Most process candidates a Candidates call builds: each is a column of an N-row regressor matrix (a million at
#: N = 1000 is 8 GB), and building them alone takes minutes.
MAX_CANDIDATES = 10**6


def _comb_capped(n: int, k: int) -> int:
    """``math.comb(n, k)``, or a number above 10 × MAX_CANDIDATES once it is that large (comb(2·10⁹, 10⁹) has
    hundreds of millions of digits)."""
    k = min(k, n - k)
    if k < 0:
        return 0
    r = 1
    for i in range(1, k + 1):  # comb(n - k + i, i): growing in i, at least doubling while i <= k <= n / 2
        r = r * (n - k + i) // i
        if r > 10 * MAX_CANDIDATES:
            return r
    return r


def _candidate_count(ny: int, n_u: int, degree: int, max_y_power: int | None) -> int:
    """How many process terms (constant included) of degree <= ``degree`` in ``ny`` output and ``n_u`` input
    variables, with at most ``max_y_power`` in the output, without building them; past 10 × MAX_CANDIDATES the
    count stops growing (the answer is then only "too many")."""
    if max_y_power is None or max_y_power >= degree:
        return _comb_capped(ny + n_u + degree, degree)
    total = 0
    for k in range(min(max_y_power, degree) + 1):  # k: the terms' power of y
        y_part = 1 if k == 0 else _comb_capped(ny + k - 1, k)
        total += y_part * _comb_capped(n_u + degree - k, degree - k)
        if total > 10 * MAX_CANDIDATES or (ny == 0 and k == 0):  # without y, every power of it above 0 is none
            break
    return total


def _per_input(value, names: tuple[str, ...], what: str, default: int | None) -> dict[str, int]:
    """``value`` (an int, or a mapping name -> int) spread over ``names``."""
    if not isinstance(value, Mapping):
        return {n: value for n in names}
    unknown = [k for k in value if k not in names]
    if unknown:
        raise ValueError(f"{what} names input {unknown[0]!r}, which is not among the inputs {names}")
    missing = [n for n in names if n not in value]
    if missing and default is None:
        raise ValueError(f"{what} gives no value for input {missing[0]!r} (inputs {names})")
    return {n: value.get(n, default) for n in names}
