"""Load data sets: the bundled pumping plant, the buck converter, and users' CSV files.

CSV conventions (all loaders): one header line naming the columns (line 1, or the line after the
``skiprows=N`` lines of a data logger's header block, or after Excel's ``sep=;`` line, whose delimiter
is used; a block not skipped is refused with the line that names the columns), one sample per line, numbers
in any form Python's ``float`` reads but its ``_`` digit groups. A Campbell Scientific TOA5 file (LoggerNet's and
CardConvert's ASCII format: line 1 starts ``TOA5``, then the column names, their units, the processing codes such
as ``Smp`` and ``Avg``, then the samples) is read without options, its units row as ``units_row=True`` reads
one; its binary TOB1/TOB2/TOB3 files are refused, naming how to convert them to TOA5. Files as spreadsheets
export them are read: the delimiter (``,`` ``;`` or tab) and the decimal mark (``.`` or ``,``) are detected from
the header and the first lines (``delimiter=`` and ``decimal=`` override). The text is UTF-8 (a byte-order mark
skipped), UTF-16 or UTF-32 when a byte-order mark says so (Excel's "Unicode text"), or what
``encoding=`` names (e.g. ``"cp1252"``, Excel's "CSV" on Windows); a binary file (an Excel workbook,
a compressed CSV) is refused as what it is. A file that allows two readings
is refused with what was seen, among them numbers that may hold a thousands separator (``1,234``
with no other decimal in sight); thousands separators themselves are never read. Columns are
picked by name, so a file may hold other columns too. Every problem found is a ``ValueError`` naming the file and the line
(the file's own, 1-based: line 1 is its first line, skipped or not) or the column: empty cells, NaN or inf, text where a number
belongs, rows with too few fields, a missing column (with the closest existing names), time stamps
that do not increase or are unevenly spaced, repeated static input levels.
"""

from __future__ import annotations

import codecs
import csv
import difflib
import functools
import io
import itertools
import math
import os
import re
import unicodedata
import warnings
from datetime import date, datetime, timedelta, time as dt_time
from importlib import resources
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from ..static._curves import StaticCurve
from ..core._files import bom_encoding
from ..core._reprs import exact_text
from ..core._records import Dataset, Record, StaticPoints, check_same_period, check_units, input_unit
from ..core._terms import check_input_names
from ..core._validation import (check_bool, check_choice, check_int, check_ordered, check_path, check_real,
                                check_str)
from ..reference import EQ1_COEFFICIENTS

__all__ = [
    "load_record_csv",
    "load_static_csv",
    "load_pumping",
    "load_buck",
    "find_buck_dir",
    "pumping_data_dir",
    "BUCK_ENV",
    "BUCK_STATIC_CURVE",
]

#: Environment variable that points at the folder holding buck_id.csv and buck_valid.csv.
BUCK_ENV = "GRAYBOX_BUCK_DIR"

#: The buck converter's theoretical static function, a :class:`~graybox.StaticCurve`: ȳ = (4 − ū)·8 V.
#: With supply Vd = 24 V, ȳ = 4 Vd/3 − (Vd/3) ū, gain −8 V per unit of input; its domain ū ∈ [1, 4] is
#: where 0 ≤ ȳ ≤ Vd, the only outputs a buck converter can produce.
BUCK_STATIC_CURVE = StaticCurve.polynomial([32.0, -8.0], domain=(1.0, 4.0),
                                           name="buck theoretical static function (4 - u)*8")


# ---------------------------------------------------------------------------
# Generic CSV reading with row/column diagnostics
# ---------------------------------------------------------------------------

def _read_columns(path: str | os.PathLike, wanted: dict[str, str], *, delimiter: str | None = None,
                  decimal: str | None = None, encoding: str | None = None,
                  skiprows: int | None = None, units_row: bool | None = None) -> dict[str, np.ndarray]:
    """Read the columns ``wanted`` (role -> column name) of a CSV file as finite float arrays.

    The encoding (:func:`_utf8`), the delimiter and the decimal mark are detected (:func:`_dialect`)
    unless given. The first ``skiprows`` lines are not read, and an Excel ``sep=X`` line where the
    header belongs gives the delimiter (the header is the line after it). With ``units_row`` the line
    after the header (blank lines passed over) holds each column's unit: it is read into ``"_units"``
    (role -> unit text, brackets dropped) and is no sample. A TOA5 file (:func:`_toa5_options`) sets both, and its line of
    processing codes after the units is no sample either; ``None`` is the format's default (0 and False
    for plain CSV). Raises ``ValueError`` naming the file and the line (the file's
    own: line 1 is its first) or column of the first problem.
    """
    p = Path(path)
    # a name typed composed (ü) and written decomposed (u and U+0308, as macOS tools write it), or the reverse, is the
    # same text by Unicode's canonical equivalence, and printed alike: names are matched in one form (NFC)
    wanted = {role: _nfc(n) for role, n in wanted.items()}
    names = list(wanted.values())
    blank = next((role for role, n in wanted.items() if not n.strip()), None)
    if blank is not None:  # it would match an unnamed column: pandas' index (to_csv's default), a trailing delimiter's
        raise ValueError(f"{p}: {blank} names no column, got {wanted[blank]!r} (an empty name); give the column's name "
                         "as the header line writes it")
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        roles = [r for r, n in wanted.items() if n in dup]
        raise ValueError(f"{p}: {', '.join(roles)} all name the column {sorted(dup)[0]!r}; each must be a different column")
    raw, start, own = _utf8(p, p.read_bytes(), encoding)
    if b"\r" in raw and b"\n" not in raw:
        # lines ended by CR alone (Excel's "CSV (Macintosh)", old Mac exports): the lines skipped, the units row
        # and the header block are found by line feeds, so the file is read with them; its lines keep their numbers
        if own:  # read as UTF-8: Excel's "CSV (Macintosh)" is Mac Roman, which cp1252 (the usual hint) reads as garbage
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError as exc:
                line = raw.count(b"\r", 0, exc.start) + 1
                raise ValueError(f"{p}: line {line} is not UTF-8 text (byte {raw[exc.start]:#04x}); its lines end in CR "
                                 "alone, as Excel's \"CSV (Macintosh)\" writes them, in Mac Roman: pass "
                                 "encoding='mac_roman' (or the encoding it was saved in), or save the file as UTF-8 "
                                 "CSV") from None
        raw, own = raw.replace(b"\r", b"\n"), False
    skiprows, units_row, codes_row = _toa5_options(p, raw, start, skiprows, units_row)
    first = skiprows + 1  # the file's line number of the header
    skipped_from = start
    start = _skip_lines(raw, start, skiprows)
    if start >= len(raw) and codes_row:
        raise ValueError(f"{p}: line 2: the TOA5 file ends after line 1, before its column names (line 2)")
    if start >= len(raw) and skiprows:
        raise ValueError(f"{p}: line {first}: the file is empty after the {skiprows} line(s) skipped (skiprows="
                         f"{skiprows}); expected a header line naming the columns, then one sample per line")
    end = _skip_lines(raw, start, 1)
    hint = re.fullmatch(r"sep=([^\w\r\n\"])\r?\n?", _decode(p, raw, start, end))
    if hint:  # Excel's "sep=;" line: the delimiter it names, the header on the next line
        if delimiter is not None and delimiter != hint.group(1):
            raise ValueError(f"{p}: line {first} is {hint.group(0).strip(chr(13) + chr(10))!r}, Excel's delimiter hint, "
                             f"but delimiter={delimiter!r} was given; omit delimiter= (the hint is used) or correct "
                             f"line {first}")
        delimiter, start, first = hint.group(1), end, first + 1
    # The dialect and the header come from the first lines alone: a long file is decoded whole
    # only when the careful reader (or a decimal comma) needs its text. A header block not skipped (or
    # skipped too far) is told from the lines as the file holds them: the units row blanked below may be
    # the very line that names the columns.
    end = _skip_lines(raw, start, _SNIFF_LINES)
    head = _decode(p, raw, start, end)
    saved = re.match(r'\s*\{\s*"format"\s*:\s*"graybox".*?"type"\s*:\s*"(\w+)"', head, re.DOTALL)
    if saved:  # what graybox.save wrote (a Record, a Dataset …): its first line "{" read as one column named "{"
        raise ValueError(f"{p}: the file is a graybox JSON file (a {saved.group(1)}, written by graybox.save), not CSV "
                         "text; read it with graybox.load(path)")
    block = head
    if end < len(raw) and not _names_columns(head.split("\n", 1)[0], names):
        # the header line does not name them: a logger's block (one line per channel) may run past the lines sniffed
        block = raw[start:_skip_lines(raw, start, _BLOCK_LINES)].decode("utf-8", errors="replace")
    _refuse_header_block(p, block, names, first)
    if skiprows:
        _refuse_skipped_header(p, _decode(p, raw, skipped_from, start), head, names, skiprows)
    _refuse_headerless(p, head, names, first)
    unit_line, code_line, cut = None, None, None
    rows_out = int(units_row) + int(codes_row)  # the lines after the header that hold no sample
    blanks = 0  # blank lines between the header and its units row
    if units_row:  # read, then blanked in place: the lines keep their numbers, and a blank line is no sample
        u0 = _skip_lines(raw, start, 1)
        while not codes_row and u0 < len(raw) and not raw[u0:_skip_lines(raw, u0, 1)].strip():
            # a blank line is no sample, nor a row of units: the units row is the first line after the header that
            # holds anything (the refusal without units_row=True names that line as units)
            u0, blanks = _skip_lines(raw, u0, 1), blanks + 1
        u1 = _skip_lines(raw, u0, 1)
        u2 = _skip_lines(raw, u1, int(codes_row))
        if u0 >= len(raw):
            raise ValueError(f"{p}: line {first + 1}: " + ("the TOA5 file ends after its column names (line 2), "
                             "before its units (line 3)" if codes_row else "units_row=True, but there is no line "
                             "after the header"))
        if codes_row and u1 >= len(raw):
            raise ValueError(f"{p}: line {first + 2}: the TOA5 file ends after its units (line 3), before its "
                             "processing codes (line 4)")
        unit_line = _decode(p, raw, u0, u1).rstrip("\r\n")
        code_line = _decode(p, raw, u1, u2).rstrip("\r\n") if codes_row else None
        cut = raw[start:u0] + raw[u2:]  # for numpy's reader, which a blank line sends to the careful one
        nl = b"\r\n" if raw[u0:u1].endswith(b"\r\n") else b"\n"
        raw = raw[:u0] + nl * rows_out + raw[u2:]
        own = False
    if units_row:  # the first lines again, the units row blanked
        end = _skip_lines(raw, start, _SNIFF_LINES)
        head = _decode(p, raw, start, end)
    delim, dec, guessed = _dialect(p, head, delimiter, decimal, first)
    sniffed = (first, first + min(_SNIFF_LINES, head.count("\n") + 1) - 1)  # the lines the mark was judged on
    header = next(csv.reader(io.StringIO(head, newline=""), delimiter=delim), None)
    if header is None:
        raise ValueError(f"{p}: line {first}: the file is empty; expected a header line naming the columns, then "
                         "one sample per line")
    header = [_nfc(h.strip()) for h in header]
    if not any(header):
        raise ValueError(f"{p}: line {first} is blank; expected a header line naming the columns, then one sample "
                         "per line")
    if header[0] == "#" and len(header) > 1 and _first_row_width(head, delim) == len(header) - 1:
        # np.savetxt(..., header="t u y") writes "# t u y": split at the spaces, the '#' is a column of its own and
        # every name sits one field right of its data ("line 2 has 3 field(s), but column 'y' is field 4")
        raise ValueError(f"{p}: line {first}: the header's first cell is a lone '#', the comment marker np.savetxt "
                         f"writes before a header (comments='# '), so every column name sits one field right of its "
                         f"data; write the file with np.savetxt(..., header=..., comments='') or delete the '# '. The "
                         f"header reads {header}.")
    index: dict[str, int] = {}
    for role, col in wanted.items():
        if col not in header:
            raise ValueError(_missing_column_message(p, role, col, header, delim))
        if header.count(col) > 1:
            raise ValueError(f"{p}: column {col!r} appears {header.count(col)} times in the header")
        index[role] = header.index(col)
    toa5 = " (a TOA5 file's units)" if codes_row else ""
    units = None if unit_line is None else _units_of_row(p, unit_line, delim, index, first + 1 + blanks, toa5)
    coded = [(wanted[r], u) for r, u in (units or {}).items() if codes_row and u in _TOA5_CODES]
    if coded:  # lines 3 and 4 swapped (or edited): the codes would be the record's units without a word
        raise ValueError(f"{p}: line {first + 1} gives column {coded[0][0]!r} the unit {coded[0][1]!r}, one of a TOA5 "
                         "file's processing codes (Smp, Avg, Max …), which belong on line 4: the file's header lines "
                         "were swapped or edited; a TOA5 file has its column names on line 2, their units on line 3 "
                         "and the processing codes on line 4: collect or convert the file again, or put them in order")
    if code_line is not None:
        _check_codes_row(p, code_line, delim, index, wanted, first + 2)
        if header.count("RECORD") == 1:  # a TOA5 file's record numbers, read to find a gap (load_record_csv)
            wanted, index = {**wanted, "_record": "RECORD"}, {**index, "_record": header.index("RECORD")}
    text = (lambda: head) if end >= len(raw) else functools.cache(lambda: _decode(p, raw, start, len(raw)))
    if guessed and raw.find(b".", start) >= 0 and _GROUPED_CELL.search(raw, start):
        # a cell that reads as a decimal or a grouped integer (1.050) where no mark was seen: the careful reader
        # names it if it is in a column read
        fast = None
    elif cut is not None:  # the units row taken out: the samples' file lines are one further on
        fast = _fast_columns(p, index, raw=cut, text=functools.cache(lambda: _decode(p, cut, 0, len(cut))),
                             delimiter=delim, decimal=dec, n_fields=len(header), reread=False, first=first)
        if fast is not None:
            fast["_lines"] = fast["_lines"] + rows_out
    elif start == 0 or (start <= 3 and raw.startswith(codecs.BOM_UTF8)):
        fast = _fast_columns(p, index, raw=raw, text=text, delimiter=delim, decimal=dec, n_fields=len(header),
                             reread=own)
    else:  # lines skipped: numpy reads the text from the header on, and the file's line numbers follow
        fast = _fast_columns(p, index, raw=raw[start:], text=text, delimiter=delim, decimal=dec,
                             n_fields=len(header), reread=False, first=first)
    if fast is not None:
        if "_time_cells" in fast:  # dates or clock times
            fast["time"], fast["_stamps"] = _stamps(p, wanted["time"], fast.pop("_time_cells"), fast["_lines"], dec)
        return fast if units is None else fast | {"_units": units}
    reader = csv.reader(io.StringIO(text(), newline=""), delimiter=delim)
    next(reader)  # the header, read above
    need = max(index.values()) + 1
    values: dict[str, list[float]] = {role: [] for role in wanted}
    lines: list[int] = []
    read = reader.line_num  # lines read so far: a quoted cell may hold line breaks, so a sample may span lines
    ended = None  # the line from which every column read is empty
    last = 0  # the text's lines before the last sample
    # a last line with no line end: where it is short, the file was cut off in it (a copy interrupted, a logger writing)
    open_end = -1 if text().endswith(("\n", "\r")) else text().count("\n") + 1
    cut = (": the file's last line, which has no line end: the file was cut off in the middle of it (a copy or "
           "download interrupted, a logger still writing)? Copy the file again, or delete the line")
    # where the sniffed lines showed no mark: the first cell read as a decimal or a grouped integer (1.050), refused at
    # the end unless a number with a point that groups no thousands (1.25, 0.500), before or after it, shows the mark
    ambiguous: tuple[int, str, str] | None = None
    for row in reader:
        line, read = read + first, reader.line_num  # the line the sample starts on, where its first cells are
        if not row or all(not c.strip() for c in row):
            continue  # blank line (e.g. a trailing newline): not a sample
        if codes_row and row[0].strip() == "TOA5":  # read as a sample it was "8 fields but the header names 4"
            raise ValueError(f"{p}: line {line} starts a TOA5 file's header again (\"TOA5\", then the column names, "
                             "units and processing codes): two files joined into one? Cut the file there into two "
                             "files, each read as a record (several records of one plant go to the estimators as a "
                             "list)")
        if [_nfc(c.strip()) for c in row[:len(header)]] == header:  # read as a sample it was "'u' is not a number"
            raise ValueError(f"{p}: line {line} repeats the header (line {first}): two files joined into one, or a "
                             "logger restarted? Cut the file there into two files, each read on its own (several "
                             "records of one plant go to the estimators as a list)")
        if read - (line - first) > 1:  # a quoted cell spans lines: it may hold samples a quote left open took in
            _refuse_swallowed(p, text(), row, line - first, line, read + first - 1, header, index, delim, dec)
        if all(not (row[i].strip() if i < len(row) else "") for i in index.values()):
            # every column read empty (or cut off) from here: shorter columns beside longer ones (a second run
            # exported beside a first, Vernier's and pandas' to_csv of columns of unequal length) end here
            ended = ended or line
            continue
        if ended is not None:
            cols = ", ".join(repr(wanted[r]) for r in index if not r.startswith("_"))
            raise ValueError(f"{p}: line {ended}: the columns read ({cols}) are empty there but hold samples again "
                             f"from line {line}: a gap in the record, not its end; fill it, or cut the file into two "
                             "records there (several records of one plant go to the estimators as a list)")
        if len(row) < need:
            raise ValueError(f"{p}: line {line} has {len(row)} field(s), but column "
                             f"{header[need - 1]!r} is field {need}{_other_delimiter_hint(row, delim)}"
                             + (cut if read == open_end else ""))
        if any(c.strip() for c in row[len(header):]):
            # a field past the header's last column shifts nothing we could trust: refuse
            raise ValueError(f"{p}: line {line} has {len(row)} fields but the header names {len(header)} "
                             f"columns{_decimal_comma_hint(row, delim)}")
        if not lines and units is None and all(not _numeric(row[i], dec) for i in index.values()):
            # text in every column read, right under the header: what a logger's row of units looks like
            cells = ", ".join(repr(row[i].strip()) for i in index.values())
            raise ValueError(f"{p}: line {line} holds text in every column read ({cells}), no sample: if it "
                             "gives the columns' units, pass units_row=True (they become the record's units)")
        for role, i in index.items():
            # a time column may hold dates or clock times: its cells are read when the column is whole (_stamps)
            if read == open_end and not row[i].strip():
                raise ValueError(f"{p}: line {line}, column {wanted[role]!r}: empty cell{cut}")
            if guessed and "." in row[i]:
                if _GROUPED.match(row[i].strip()):
                    ambiguous = ambiguous or (line, wanted[role], row[i].strip())
                elif _DECIMAL_POINT.match(row[i].strip()):
                    guessed = False
            values[role].append(row[i] if role == "time" else _number(p, line, wanted[role], row[i], dec))
        lines.append(line)
        last = line - first
    if guessed and ambiguous is not None:
        raise ValueError(_grouped_message(p, *ambiguous, sniffed))
    if lines and read - last > 1:
        _refuse_open_quote(p, text(), last, lines[-1], read + first - 1, header, delim)
    if not lines:
        after = ("the header" if units is None else "the header's units row" if not codes_row
                 else "the TOA5 file's four header lines")
        raise ValueError(f"{p}: line {first + 1 + blanks + rows_out}: no data rows after {after}; expected one sample "
                         "per line")
    out = {role: np.array(v) for role, v in values.items() if role != "time"}
    if "time" in values:
        out["time"], out["_stamps"] = _stamps(p, wanted["time"], values["time"], lines, dec)
    out["_lines"] = np.array(lines)
    return out if units is None else out | {"_units": units}


def _refuse_open_quote(p: Path, text: str, last: int, line: int, end: int, header: Sequence[str], delim: str) -> None:
    """A ``ValueError`` when the last sample (file line ``line``, the text's line ``last`` on) holds a quote that no
    quote closes: the csv reader takes every later line into that cell (a note's stray '"'), and the samples
    there would be lost without a word."""
    tail = "".join(itertools.islice(io.StringIO(text, newline=""), last, None))
    try:
        for _ in csv.reader(io.StringIO(tail, newline=""), delimiter=delim, strict=True):
            pass
    except csv.Error as exc:
        if "unexpected end of data" not in str(exc):
            return  # another irregularity, which the lenient reader read as before
        row = next(csv.reader(io.StringIO(tail, newline=""), delimiter=delim), [])
        i = next((k for k, c in enumerate(row) if "\n" in c or "\r" in c), len(row) - 1)
        col = f", column {header[i]!r}" if i < len(header) else ""
        raise ValueError(f"{p}: line {line}{col}: a quote (\") opens a field that no quote closes, so lines {line} to "
                         f"{end}, the rest of the file, would be read as that one cell and their samples lost; close "
                         "the quote or delete it") from None


def _refuse_swallowed(p: Path, text: str, row: Sequence[str], start: int, line: int, end: int, header: Sequence[str],
                      index: dict[str, int], delim: str, decimal: str) -> None:
    """A ``ValueError`` when a quoted cell of the sample on file lines ``line`` to ``end`` (the text's line ``start``
    on) holds lines that read as samples: a quote left open (a note's stray '"') took them in, until a quote
    further on (or the file's end) closed it, and their samples would be lost without a word."""
    numeric = [j for role, j in index.items() if role != "time"]  # a time column may hold dates (a TOA5 TIMESTAMP)
    for i, cell in enumerate(row):
        for piece in cell.splitlines()[1:]:  # a whole line of the file: as many fields as the header, numbers read
            cells = _split(piece, delim)
            if (_width(piece, delim, len(header)) == len(header) > 1
                    and all(_numeric(cells[j], decimal) for j in numeric)):
                _refuse_open_quote(p, text, start, line, end, header, delim)
                col = f", column {header[i]!r}" if i < len(header) else ""
                raise ValueError(f"{p}: line {line}{col}: a quote (\") opens a field that closes only on line {end}, "
                                 f"so lines {line + 1} to {end}, which read as samples ({piece.strip()!r}), would be "
                                 "read as that one cell and their samples lost; close the quote where the cell ends "
                                 "or delete it")
    # the quote closed by the next line's opening quote (a date's closing quote missing): that line's first cell
    # ends the cell, its other cells are the sample's, and the sample where the quote opened is lost
    spanned = itertools.islice(io.StringIO(text, newline=""), start + 1, start + 1 + end - line)
    for k, physical in enumerate(spanned, start=line + 1):
        lead = physical.lstrip(" \t")
        if not lead.startswith('"') or lead[1:2] in ('"', delim, "\r", "\n", ""):
            # no field opens there: the line goes on a quoted cell (a note over lines, valid CSV: its last line
            # 'break",3.5,0.56' reads as a sample quotes removed), or its quote is doubled or closes the cell
            continue
        bare = physical.rstrip("\r\n").replace('"', "")
        cells = _split(bare, delim)
        if _width(bare, delim, len(header)) == len(header) > 1 and all(_numeric(cells[j], decimal) for j in numeric):
            raise ValueError(f"{p}: line {line}: a quote (\") opens a field that closes only on line {end}, so line "
                             f"{k}, which reads as a sample ({physical.strip()!r}), would be read into the sample of "
                             f"line {line} and one sample lost; close the quote where the cell ends or delete it")


def _numeric(cell: str, decimal: str) -> bool:
    """Whether a cell reads as a number (with the file's decimal mark)."""
    c = cell.strip()
    if "_" in c:  # Python's digit groups, which float() reads and _number does not
        return False
    try:
        float(c.replace(",", ".") if decimal == "," else c)
        return True
    except ValueError:
        return False


def _units_of_row(p: Path, line: str, delim: str, index: dict[str, int], number: int, toa5: str = "") -> dict[str, str]:
    """The units a logger's units row gives the columns read (role -> unit, ``[rpm]`` read as ``rpm``); ``toa5``
    non-empty: the units row of a TOA5 file, which no option drops."""
    cells = next(csv.reader([line], delimiter=delim), [])
    units = {role: _unbracket(cells[i]) if i < len(cells) else "" for role, i in index.items()}
    if all(_numeric(u, ".") or _numeric(u, ",") for u in units.values() if u) and any(units.values()):
        raise ValueError(f"{p}: line {number} holds numbers ({line.strip()!r}), a sample, not a row of units"
                         + (f"{toa5}: the file's header lines were cut or edited; a TOA5 file has its column "
                            "names on line 2, their units on line 3 and the processing codes on line 4, then its "
                            "samples: collect or convert the file again" if toa5 else ": drop units_row=True"))
    return units


def _check_codes_row(p: Path, line: str, delim: str, index: dict[str, int], wanted: Mapping[str, str],
                     number: int) -> None:
    """A ``ValueError`` when a TOA5 file's line of processing codes (``Smp``, ``Avg``, ``Max`` …, blank for
    TIMESTAMP and RECORD) holds a number in a column read: a sample there, the header lines cut or edited, which
    would be dropped without a word."""
    cells = next(csv.reader([line], delimiter=delim), [])
    for role, i in index.items():
        if i < len(cells) and _numeric(cells[i], "."):
            raise ValueError(f"{p}: line {number} holds numbers ({line.strip()!r}; column {wanted[role]!r}: "
                             f"{cells[i].strip()!r}) where a TOA5 file has its processing codes (Smp, Avg, Max …): "
                             "the file's header lines were cut or edited; a TOA5 file has its column names on line "
                             "2, their units on line 3 and the processing codes on line 4, then its samples: "
                             "collect or convert the file again")


#: The processing codes of a TOA5 file's line 4 (LoggerNet's manual, appendix B: the output instructions' suffixes)
_TOA5_CODES = frozenset({"Smp", "Avg", "Max", "Min", "Tot", "Std", "TMx", "TMn", "SMM", "MMT", "Hst", "H4D", "FFT",
                         "Cov", "RFH", "LCr", "WVc", "Med", "ETsz", "RSo"})

#: Line 1 of a TOA5 file: its first field TOA5, quoted (as Campbell Scientific's software writes it) or not, then a
#: comma, or the ';' or tab of a copy a spreadsheet saved again (Excel in a decimal-comma locale).
_TOA5 = re.compile(rb' *("?)TOA5\1 *(?:[,;\t]|\r?\n|$)')


def _toa5_options(p: Path, raw: bytes, start: int, skiprows: int | None,
                  units_row: bool | None) -> tuple[int, bool, bool]:
    """``(skiprows, units_row, codes_row)`` for the file whose UTF-8 text starts at ``raw[start]``.

    A TOA5 file (Campbell Scientific's ASCII format, as LoggerNet and CardConvert write it: line 1's first field
    ``TOA5``, quoted or not, then the column names, their units and the processing codes, then the samples) is read
    with ``skiprows=1``, its units row and its processing codes (``codes_row``) not read as samples; a ``skiprows``
    or ``units_row`` given that contradicts this is a ``ValueError``. Any other file: the options given, else 0 and
    False.
    """
    if not _TOA5.match(raw, start):
        return (0 if skiprows is None else skiprows), bool(units_row), False
    fmt = (f"{p}: the file is a TOA5 file (Campbell Scientific's ASCII format, line 1 starts \"TOA5\"), read as "
           "such without options: its column names are line 2, their units line 3 (the record's units) and the "
           "processing codes line 4, then the samples")
    if skiprows not in (None, 1):
        raise ValueError(f"{fmt}; skiprows={skiprows} says the column names are line {skiprows + 1}: omit skiprows= "
                         "(or pass skiprows=1)")
    if units_row is False:
        raise ValueError(f"{fmt}; units_row=False says line 3 is a sample, but it is the units row: omit units_row= "
                         "(or pass units_row=True)")
    return 1, True, True


def _unbracket(cell: str) -> str:
    """A unit cell without its one enclosing pair of brackets or parentheses: ``[kPa (abs)]`` is ``kPa (abs)``."""
    c = cell.strip()
    m = re.fullmatch(r"\[([^\[\]]*)\]|\(([^()]*)\)", c)
    return c if m is None else (m.group(1) if m.group(1) is not None else m.group(2)).strip()


#: The units of elapsed time a units row or the time column's name may give a time column of numbers: (multiply,
#: divide) that make them seconds (a division by 1000 rounds 1010 ms to the float nearest 1.01 s, where a product with
#: 1e-3 rounds twice). A name's units (:data:`_OTHER_UNITS`) are this table's.
_TIME_UNITS = {**dict.fromkeys(("", "s", "sec", "secs", "second", "seconds"), (1, 1)),
               **dict.fromkeys(("ms", "msec", "millis", "millisecond", "milliseconds"), (1, 1000)),
               **dict.fromkeys(("us", "µs", "μs", "usec", "micros", "microsecond", "microseconds"), (1, 10**6)),
               **dict.fromkeys(("ns", "nsec", "nanosecond", "nanoseconds"), (1, 10**9)),
               **dict.fromkeys(("min", "mins", "minute", "minutes"), (60, 1)),
               **dict.fromkeys(("h", "hr", "hrs", "hour", "hours"), (3600, 1)),
               **dict.fromkeys(("d", "day", "days"), (86400, 1))}


#: The spellings of :data:`_TIME_UNITS` whose letters' case names another unit (a capital M is mega, ``Ms`` and ``MS``
#: megaseconds; ``S`` is siemens, ``H`` henry): read as written only. The words (``sec``, ``min``, ``hours`` …) name
#: no other unit in any case, and are read in any (``Sec``, ``MIN``).
_CASED_TIME_UNITS = frozenset({"s", "ms", "msec", "us", "µs", "μs", "usec", "ns", "nsec", "h", "d"})
#: Of those, a prefix and the word sec: only the prefix's case names another unit ('mSec' is milliseconds, 'Msec' mega).
_PREFIXED_SEC = frozenset({"msec", "usec", "nsec"})


def _time_unit(p: Path, unit: str, col: str) -> tuple[int, int] | None:
    """(multiply, divide) that make the time column ``col``'s numbers in ``unit`` seconds (:data:`_TIME_UNITS`), None
    for a unit it does not list; a symbol written in another case (``Ms``, ``MS``, ``S``) is refused as ambiguous,
    naming the column (it read as ``ms``, milliseconds, where ``Ms`` is megaseconds)."""
    key = unit.strip()
    if key in _TIME_UNITS:
        return _TIME_UNITS[key]
    low = key.lower()
    if low in _PREFIXED_SEC and key[0] == low[0]:  # the prefix as written, 'sec' a word read in any case
        return _TIME_UNITS[low]
    if low in _CASED_TIME_UNITS:
        raise ValueError(f"{p}: the time column {col!r} is given the unit {unit!r}, which differs from {low!r} only by "
                         "case: ambiguous, as a unit's case is part of its name ('Ms' and 'MS' are megaseconds, 'S' "
                         f"siemens); write {low!r} if it is meant, or leave time= out and give Ts= in seconds")
    return _TIME_UNITS.get(low)


def _time_in_seconds(p: Path, unit: str, t: np.ndarray, stamps: Sequence[str] | None, col: str,
                     source: str = "the units row gives the time column") -> np.ndarray:
    """The numbers of the time column ``col`` whose units row (or name: ``source`` says which, for the messages)
    gives ``unit`` as seconds (``ms``, ``µs``/``us``, ``ns``, ``min``, ``h``, ``d`` converted; a symbol in another
    case, ``Ms`` or ``MS``, refused by :func:`_time_unit`); dates and clock times (``stamps`` not None) carry their
    own unit: a units row giving them one other than seconds (or ``TS``, a TOA5 file's TIMESTAMP) is refused, as is
    an unknown unit."""
    if unit.strip().lower() == "ts":
        return t
    scale = _time_unit(p, unit, col)
    if stamps is not None and scale == (1, 1):
        return t
    if stamps is None and scale is not None:
        mul, div = scale
        return t * mul if div == 1 else t / div
    known = "s, ms, µs (us), ns, min, h or d"
    said = (f"the time column holds dates or clock times ({stamps[0]!r}), which carry their own unit"
            if stamps is not None else f"graybox converts the units of elapsed time {known} to seconds")
    raise ValueError(f"{p}: {source} the unit {unit!r}, but {said}: convert the column "
                     "to seconds, or leave time= out and give Ts= in seconds")


def _units_from_row(p: Path, units: tuple, row: dict[str, str], inputs: Sequence[str],
                    time: str | None) -> tuple:
    """The (input, output) units a units row gives (the inputs' one unit, or one per input where they differ),
    checked against ``units`` given too (a time column's unit is read by :func:`_time_in_seconds`)."""
    # one per input, in the inputs' order (one str where all are one); a blank says nothing of its input, not that
    # it is in the others' unit
    found = check_units((tuple(row[r] for r in inputs), row["y"]), f"{p}")
    for k in range(len(inputs)):
        given, read = input_unit(units, k), input_unit(found, k)
        if given and read and given != read:
            what = inputs[k] if inputs[k] != "u" else "input"  # a role: "u", or "input 'name'" of several
            raise ValueError(f"{p}: units={units!r} says the {what} is in {given!r}, but the units row says {read!r}")
    if units[1] and found[1] and units[1] != found[1]:
        raise ValueError(f"{p}: units={units!r} says the output is in {units[1]!r}, but the units row says "
                         f"{found[1]!r}")
    # input by input: units= where it names one, the row elsewhere
    each = [input_unit(units, k) or input_unit(found, k) for k in range(len(inputs))]
    return check_units((each, units[1] or found[1]), f"{p}", len(inputs))


def _skip_lines(raw: bytes, start: int, n: int) -> int:
    """Where the line ``n`` lines after the one starting at ``start`` starts in ``raw`` (its end when
    there are fewer)."""
    for _ in range(n):
        start = raw.find(b"\n", start) + 1
        if start == 0:
            return len(raw)
    return start


def _nfc(text: str) -> str:
    """``text`` in Unicode's composed form (NFC): a column name as it is matched."""
    return unicodedata.normalize("NFC", text)


def _names_columns(line: str, names: Sequence[str]) -> bool:
    """Whether ``line``, split at one of the delimiters, holds every name of ``names`` as a cell."""
    return any(set(names) <= {_nfc(c.strip()) for c in _split(line, d)} for d in _DELIMITERS)


def _refuse_header_block(p: Path, head: str, names: Sequence[str], first: int = 1) -> None:
    """A ``ValueError`` when the header line (file line ``first``, the first of ``head``) does not name
    the columns but a later line of ``head`` names them all.

    Data loggers write a block of lines (instrument, date, channels) before the column names; read
    as the header, its first line would be reported as a wrong delimiter or a missing column.
    """
    lines = head.splitlines()
    if not lines or _names_columns(lines[0], names):
        return  # the header line may name them (the reader checks it cell by cell)
    for i, line in enumerate(lines[1:], start=first + 1):
        if _names_columns(line, names):
            raise ValueError(f"{p}: line {i} names the columns ({line!r}), but the header was read from line {first}: "
                             f"the file has {i - 1} line(s) before the column names (a data logger's header "
                             f"block?); pass skiprows={i - 1}")
    for i, line in enumerate(lines[1:], start=first + 1):
        # every header line behind '# ', the names' too: np.savetxt's header of several lines, a logger's comments
        bare = re.sub(r"^\s*#+\s*", "", line) if line.lstrip().startswith("#") else None
        if bare is not None and (_names_columns(bare, names) or set(names) <= set(_nfc(bare).split())):
            spaces = "" if _names_columns(bare, names) else " and delimiter=' ' (its columns are split at spaces)"
            raise ValueError(f"{p}: line {i} names the columns behind the comment marker '#' ({line!r}), as "
                             "np.savetxt writes a header (comments='# '), and the header was read from line "
                             f"{first}: delete the '#' before the names on line {i} (or write the file with "
                             f"np.savetxt(..., comments='')) and pass skiprows={i - 1}{spaces}")


def _refuse_headerless(p: Path, head: str, names: Sequence[str], first: int) -> None:
    """A ``ValueError`` when the header line (file line ``first``) holds numbers alone and none of the
    columns asked for: a file written without its line of column names (``to_csv(header=False)``, a
    logger's bare export), whose first sample would be read as names or the delimiter judged from it."""
    line = head.splitlines()[0] if head.strip() else ""
    cells = [c.strip().strip('"').strip() for c in re.split(r"[,;\t]", line)]
    if not any(cells) or set(names) & set(cells):
        return
    if all(_numeric(c, ".") or _INTEGER.match(c) for c in cells if c):
        raise ValueError(f"{p}: line {first} holds numbers ({line.strip()!r}), not the column names: the file has no "
                         "header line. Add a first line naming the columns (e.g. t;power;temperature), or write the "
                         "file with its header (pandas: to_csv(path, index=False), header=True by default); if these "
                         "numbers are the column names, ask for the columns by them")


def _refuse_skipped_header(p: Path, skipped: str, head: str, names: Sequence[str], skiprows: int) -> None:
    """A ``ValueError`` when one of the ``skiprows`` lines skipped named the columns and the header
    read below them does not."""
    header = head.splitlines()[:1]
    if header and _names_columns(header[0], names):
        return
    lines = skipped.splitlines()
    for i in range(len(lines), 0, -1):  # the last such line: the one just above the data
        if _names_columns(lines[i - 1], names):
            raise ValueError(f"{p}: skiprows={skiprows} skips line {i}, which names the columns: pass skiprows={i - 1}")


def _decode(p: Path, raw: bytes, start: int, end: int) -> str:
    """``raw[start:end]`` as UTF-8 text, or a ``ValueError`` naming the line of the first bad byte."""
    try:
        return raw[start:end].decode("utf-8")
    except UnicodeDecodeError as exc:
        at = start + exc.start
        line = raw.count(b"\n", 0, at) + 1
        raise ValueError(f"{p}: line {line} is not UTF-8 text (byte {raw[at]:#04x}); save the file as UTF-8 CSV, "
                         "or pass the encoding it was saved in, e.g. encoding='cp1252' (Excel's \"CSV\" on "
                         "Windows in Western Europe and the Americas)") from None


_AS_ARRAYS = "and pass its columns as arrays to graybox.Record(u, y, Ts=...) / graybox.StaticPoints(ubar, ybar)"
_SAVE_AS_CSV = ("save it from the spreadsheet as CSV (UTF-8), or read it with pandas.read_excel " + _AS_ARRAYS)
#: Signatures (first bytes) of binary files users hand a CSV reader, with what they are and what to do:
#: their bytes would otherwise be judged as text and sent to an encoding that reads garbage. Each is
#: specific enough that no CSV header starts with it (bzip2's block or end-of-stream mark follows "BZh9").
_PARQUET = "a Parquet file"
_BINARY_SIGNATURES = tuple((re.compile(magic, re.DOTALL), what, advice) for magic, what, advice in (
    (re.escape(b"PK\x03\x04"), "a zip archive (an Excel .xlsx or OpenDocument .ods workbook, or a zipped file)",
     _SAVE_AS_CSV + "; a zipped CSV: unzip it first"),
    (re.escape(bytes.fromhex("d0cf11e0a1b11ae1")), "a legacy Excel (.xls) workbook or another OLE2 document",
     _SAVE_AS_CSV),
    (re.escape(b"\x1f\x8b"), "gzip-compressed (what pandas writes for to_csv('x.csv.gz'))",
     "decompress it first (gunzip), or read it with pandas.read_csv " + _AS_ARRAYS),
    (rb"BZh[1-9](?:1AY&SY|\x17rE8P\x90)", "bzip2-compressed",
     "decompress it first (bunzip2), or read it with pandas.read_csv " + _AS_ARRAYS),
    (re.escape(b"\xfd7zXZ\x00"), "xz-compressed",
     "decompress it first (unxz), or read it with pandas.read_csv " + _AS_ARRAYS),
    (re.escape(b"\x28\xb5\x2f\xfd"), "zstd-compressed",
     "decompress it first (unzstd), or read it with pandas.read_csv " + _AS_ARRAYS),
    (re.escape(b"\x93NUMPY"), "a NumPy .npy file", "read it with numpy.load " + _AS_ARRAYS),
    (re.escape(b"PAR1"), _PARQUET, "read it with pandas.read_parquet " + _AS_ARRAYS),
    (re.escape(b"\x89HDF\r\n\x1a\n"), "an HDF5 file (or a MATLAB v7.3 .mat file)",
     "read it with h5py or pandas.read_hdf " + _AS_ARRAYS),
    (re.escape(b"MATLAB 5.0 MAT-file"), "a MATLAB .mat file", "read it with scipy.io.loadmat " + _AS_ARRAYS),
    (rb"TDS[mh].{4}[\x68\x69]\x12\x00\x00", "a National Instruments TDMS file (LabVIEW's binary measurement format)",
     "read it with the nptdms package (nptdms.TdmsFile.read(path), a channel's data by [group][channel][:]) "
     + _AS_ARRAYS + ", or export it from LabVIEW or DIAdem as CSV text"),
    (re.escape(b"SQLite format 3\x00"), "an SQLite database (a grid's store?)",
     "read a grid's store with graybox.load_results; for your own tables, read them with pandas.read_sql "
     + _AS_ARRAYS),
))

#: Line 1 of Campbell Scientific's binary TOB1/TOB2/TOB3 files (an ASCII header, then binary frames): its first
#: field, quoted as their software writes it (group 1 the quote), after a UTF-8 byte-order mark or none.
_TOB = re.compile(rb'(?:\xef\xbb\xbf)?[ \t]*("?)(TOB[123])\1[ \t]*,')


def _is_utf8(raw: bytes) -> bool:
    try:
        raw.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


#: The byte order each UTF-16/32 byte-order mark says (UTF-32's little-endian mark starts with UTF-16's: same order).
_BOM_ORDERS = ((codecs.BOM_UTF32_BE, "-be"), (codecs.BOM_UTF16_LE, "-le"), (codecs.BOM_UTF16_BE, "-be"))
_ORDER_NAMES = {"-le": "little-endian", "-be": "big-endian"}


def _utf8(p: Path, raw: bytes, encoding: str | None) -> tuple[bytes, int, bool]:
    """The file's bytes as UTF-8, where its text starts in them (after a UTF-8 byte-order mark), and
    whether they are the file's own bytes (numpy's reader may then read the file itself).

    Without ``encoding`` a byte-order mark decides (UTF-8, UTF-16 or UTF-32), else UTF-8, checked
    lazily by :func:`_decode`. Text in another encoding is decoded here and written again as UTF-8.
    A file that starts with the signature of a binary format (a workbook, a compressed file) is
    refused as that format, whatever ``encoding`` says: no text encoding reads it.
    """
    for magic, what, advice in _BINARY_SIGNATURES:
        if magic.match(raw) and (what != _PARQUET or raw.endswith(b"PAR1")):  # a text header may start "PAR1,"
            raise ValueError(f"{p}: the file is {what}, not CSV text; {advice}")
    tob = _TOB.match(raw)
    if tob and (tob.group(1) or b"\x00" in raw or not _is_utf8(raw)):  # a column named TOB1 unquoted: text is text
        kind = tob.group(2).decode()
        raise ValueError(f"{p}: the file is a Campbell Scientific {kind} file (line 1 starts \"{kind}\"), the binary "
                         "format a data logger writes to its card or LoggerNet collects, not CSV text; convert it to "
                         "TOA5, the logger's ASCII format, with CardConvert (LoggerNet's Card Convert, or Campbell "
                         "Scientific's free CardConvert: output file format TOA5) or collect the table as ASCII "
                         "table data (TOA5) in LoggerNet, and read that file: graybox reads TOA5 without options")
    if encoding is not None:
        if not isinstance(encoding, str):
            raise TypeError(f"encoding must name a text encoding (a str) such as 'cp1252', got {encoding!r}")
        try:
            enc = codecs.lookup(encoding).name
            "".encode(enc)  # a codec that is no text encoding (hex, rot13, base64) is a LookupError here
        except LookupError:
            raise ValueError(f"{p}: encoding {encoding!r} is not a text encoding Python knows (e.g. 'utf-8', "
                             "'utf-16', 'cp1252')") from None
        marked = bom_encoding(raw)
        # the mark's byte order too: UTF-16's little-endian mark read as 'utf-16-be' is mojibake, not an error
        order = next((o for bom, o in _BOM_ORDERS if raw.startswith(bom)), "")
        if marked is not None and (not enc.startswith(marked)  # the mark's bytes would be read as text
                                   or (enc.endswith(("-le", "-be")) and not enc.endswith(order))):
            said = f"{marked.upper()} ({_ORDER_NAMES[order]})" if order else marked.upper()
            raise ValueError(f"{p}: the file starts with a {said} byte-order mark, but encoding={encoding!r} was "
                             f"given; omit encoding= (the mark decides) or pass encoding={marked!r}")
        if enc.startswith(("utf-16", "utf-32")) and raw and b"\x00" not in raw[:4096]:
            # its bytes read in pairs (fours) as CJK text, and the header's one garbled column blamed the delimiter
            wide = enc[:6].upper()
            raise ValueError(f"{p}: encoding={encoding!r} was given, but the file holds no NUL bytes, which {wide} "
                             f"text of digits and Latin letters has in every character: it is not {wide} (UTF-8, "
                             "or cp1252?); omit encoding= or pass the encoding it was saved in")
    else:
        enc = bom_encoding(raw) or "utf-8"
    if enc == "utf-8":
        nul = raw.find(b"\x00")
        if nul >= 0:
            order = _utf16_order(raw[:4096])  # encoding='utf-8' given too: the bytes are UTF-16 all the same
            if order is not None:
                raise ValueError(f"{p}: the file holds NUL bytes, so it is not UTF-8 text: UTF-16 without a byte-order "
                                 f"mark? Pass encoding='utf-16-{order}' (or the encoding it was saved in)")
            if nul > 0 and raw[nul - 1:nul] == b"\n" and not raw[nul:].strip(b"\x00"):
                # zeros after whole lines only: a logger's preallocated file, its written lines the samples
                return raw[:nul], (3 if raw.startswith(codecs.BOM_UTF8) else 0), False
            # no UTF-16 (a NUL between every character) but NULs in UTF-8 text, which no CSV holds: one cut off as it
            # was written (inside a line), padded with zeros, or a stray NUL in a cell
            line = raw.count(b"\n", 0, nul) + 1
            raise ValueError(f"{p}: line {line} holds NUL bytes (0x00), which are no CSV text: a data logger's file "
                             "padded with zeros, or one cut off as it was written? Delete them (or cut the file "
                             f"before line {line})")
        return raw, (3 if raw.startswith(codecs.BOM_UTF8) else 0), True
    try:
        text = raw.decode(enc)
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].decode(enc, errors="replace").count("\n") + 1
        raise ValueError(f"{p}: line {line} is not {enc} text (bytes {raw[exc.start:exc.end].hex(' ')}); pass "
                         "the encoding it was saved in as encoding=") from None
    return text.removeprefix("\ufeff").encode("utf-8"), 0, False


def _utf16_order(head: bytes) -> str | None:
    """``"le"`` or ``"be"`` when ``head`` reads as UTF-16 text without its byte-order mark (a NUL byte beside
    nearly every character, as CSV's ASCII letters and digits have in UTF-16), else None."""
    even, odd = head[0::2], head[1::2]
    if len(odd) < 2:
        return None
    if odd.count(0) >= 0.8 * len(odd) and even.count(0) < 0.2 * len(even):
        return "le"
    if even.count(0) >= 0.8 * len(even) and odd.count(0) < 0.2 * len(odd):
        return "be"
    return None


#: Delimiters tried when none is given, and how many lines the detection reads.
_DELIMITERS = (",", ";", "\t")
_SNIFF_LINES = 50
#: How many lines are searched for the column names when the header line does not hold them (a header block).
_BLOCK_LINES = 2000
# A number written with a decimal comma: digits, one comma, digits (an exponent allowed).
#: A date (2026-11-20, 20.11.2026, 11/20/2026) or a clock time (09:14) in a cell.
_CLOCK = re.compile(r"\d:\d\d|\d[-/.]\d{1,2}[-/.]\d")
_DECIMAL_COMMA = re.compile(r"^[+-]?\d*,\d+(?:[eE][+-]?\d+)?$")
# A decimal number that also reads as an integer with a thousands separator (1,234 or 1.234).
_GROUPED = re.compile(r"^[+-]?[1-9]\d{0,2}[.,]\d{3}$")
#: A whole cell (between delimiters ; or tab, line ends, quotes) that :data:`_GROUPED` reads with a point
_GROUPED_CELL = re.compile(rb'(?:^|[;\t"])[ \t]*[+-]?[1-9][0-9]{0,2}\.[0-9]{3}[ \t]*(?=[;\t"\r\n]|$)', re.MULTILINE)
# Digits in groups of three after a thousands separator (, . ' space, no-break or narrow no-break
# space), maybe with a decimal part: what a spreadsheet's number format writes.
_THOUSANDS = re.compile(r"^[+-]?\d{1,3}(?:([,.'\u2019 \u00a0\u202f])\d{3})(?:\1\d{3})*(?:[.,]\d*)?$")
_THOUSANDS_HINT = ("; it looks like a number with a thousands separator, which is not read: export the numbers "
                   "without thousands separators")
_DECIMAL_POINT = re.compile(r"^[+-]?\d*\.\d+(?:[eE][+-]?\d+)?$")
_INTEGER = re.compile(r"^[+-]?\d+(?:[eE][+-]?\d+)?$")
#: Dashes that word processors, web pages and some exports write for a minus sign, which float() does not read.
_DASHES = frozenset("\u2010\u2011\u2012\u2013\u2014\u2015\u2212\ufe63\uff0d")


def _name(d: str) -> str:
    return {"\t": "tab", ",": "','", ";": "';'"}.get(d, repr(d))


def _dialect(p: Path, text: str, delimiter: str | None, decimal: str | None,
             first: int = 1) -> tuple[str, str, bool]:
    """The delimiter and the decimal mark of a CSV text, from its header and first data lines.

    The delimiter is the one of ``, ; tab`` that splits the header into several columns and every
    sampled data line into as many; the decimal mark is ``,`` when numbers such as ``2,5`` appear
    (with ``;`` or tab as delimiter, or in quoted fields), else ``.``. A file that allows two
    readings, mixes delimiters, or uses a decimal comma with an unquoted comma delimiter is refused
    with what was seen and what to pass. ``first`` is the file's line number of the text's first line. The third
    value says whether the mark is ``.`` for want of any number with a mark in those lines (whole numbers only) beside
    a ``;`` or tab delimiter, a decimal-comma locale's: a grouped number further on (``1.050``) is then ambiguous.
    """
    for name, v, example in (("delimiter", delimiter, "';'"), ("decimal", decimal, "','")):
        if v is not None and not isinstance(v, str):
            raise TypeError(f"{p}: {name} must be a one-character str such as {example}, got {v!r}")
    if delimiter is not None and (len(delimiter) != 1 or delimiter in "\"\r\n" or delimiter.isalnum()):
        raise ValueError(f"{p}: delimiter must be one character such as ',', ';' or '\\t', got {delimiter!r}")
    if decimal is not None and decimal not in (".", ","):
        raise ValueError(f"{p}: decimal must be '.' or ',', got {decimal!r}")
    head = [(i + first, ln) for i, ln in enumerate(itertools.islice(io.StringIO(text, newline=""), _SNIFF_LINES))]
    head = [(i, ln.rstrip("\r\n")) for i, ln in head]
    if not head:
        raise ValueError(f"{p}: line {first}: the file is empty; expected a header line naming the columns, then "
                         "one sample per line")
    data = [(i, ln) for i, ln in head[1:] if ln.strip()]
    if delimiter is None:
        delimiter = _detect_delimiter(p, head[0][1], data, head[0][0])
    guessed = False
    if decimal is None:
        decimal, seen = _detect_decimal(p, head[0][1], data, delimiter)
        guessed = not seen and delimiter != ","
    if delimiter == decimal and '"' not in text:
        # only quotes keep a decimal comma from splitting a number in two
        raise ValueError(f"{p}: the delimiter is {_name(delimiter)} and so is the decimal mark, but no field is "
                         "quoted, so a number such as 2,5 would read as two columns; pass another delimiter= or "
                         "decimal=, or export the file with quoted fields")
    return delimiter, decimal, guessed


def _split(line: str, d: str) -> list[str]:
    return next(csv.reader([line], delimiter=d), [])


def _width(line: str, d: str, header_width: int) -> int:
    """The fields of a line split at ``d``, not counting empty ones past the header's width (some
    exports end every line with a delimiter)."""
    cells = _split(line, d)
    while len(cells) > header_width and not cells[-1].strip():
        cells.pop()
    return len(cells)


def _detect_delimiter(p: Path, header: str, data: list[tuple[int, str]], first: int = 1) -> str:
    widths = {d: len(_split(header, d)) for d in _DELIMITERS}
    fits = [d for d in _DELIMITERS if widths[d] > 1 and all(_width(ln, d, widths[d]) == widths[d] for _, ln in data)]
    if len(fits) == 1:
        return fits[0]
    if len(fits) > 1:
        seen = " and ".join(f"{_name(d)} gives {widths[d]} columns" for d in fits)
        raise ValueError(f"{p}: the delimiter is ambiguous: on the first {len(data) + 1} lines "
                         f"{seen}; pass delimiter= ({' or '.join(repr(d) for d in fits)})")
    split = [d for d in _DELIMITERS if widths[d] > 1]
    if not split:
        return ","  # one column: the missing-column message shows the header as read
    best = max(split, key=lambda d: widths[d])
    for line, ln in data:
        n = _width(ln, best, widths[best])
        if n == widths[best]:
            continue
        other = [d for d in _DELIMITERS if d != best and _width(ln, d, widths[best]) == widths[best]]
        if best == "," and n > widths[best] and _decimal_comma_cells(ln.split(",")):
            raise ValueError(f"{p}: line {line} has {n} comma-separated fields but the header (line {first}) has "
                             f"{widths[best]} ({ln!r}). If its numbers use a decimal comma, commas also separate "
                             "the columns, which cannot be read unambiguously: export the file again with ';' as "
                             "the delimiter (the decimal comma is then detected), with '.' as the decimal mark, "
                             f"or with quoted fields; otherwise correct line {line}")
        if other and n == 1:
            raise ValueError(f"{p}: mixed delimiters: the header (line {first}) is separated by {_name(best)} but line "
                             f"{line} by {_name(other[0])} ({ln!r}); use one delimiter throughout, or pass "
                             f"delimiter={best!r} and correct line {line}")
        break  # another fault (a short row, say): the reader reports it with its line
    return best


def _decimal_comma_cells(cells: Sequence[str]) -> bool:
    """Whether cells split at commas look like numbers cut at their decimal comma (``2``, ``5``)."""
    cells = [c.strip() for c in cells]
    return len(cells) > 1 and all(_INTEGER.match(c) for c in cells if c)


def _detect_decimal(p: Path, header: str, data: list[tuple[int, str]], delimiter: str) -> tuple[str, bool]:
    """The decimal mark of the lines ``data``, and whether any number there has one (else ``.`` by default)."""
    seen: dict[str, list[tuple[int, int, str]]] = {",": [], ".": []}  # (line, field, cell): each mark's evidence
    for line, ln in data:
        for i, cell in enumerate(_split(ln, delimiter)):
            c = cell.strip()
            if "," in c and "." in c and _THOUSANDS.match(c):  # both marks: one groups thousands, never guessed
                names = _split(header, delimiter)
                col = names[i].strip() if i < len(names) else str(i + 1)
                raise ValueError(f"{p}: line {line}, column {col!r}: {c!r} is not a number{_THOUSANDS_HINT}")
            if _DECIMAL_COMMA.match(c):
                seen[","].append((line, i, c))
            elif _DECIMAL_POINT.match(c):
                seen["."].append((line, i, c))
    if seen[","] and seen["."]:
        (pl, _, pc), (cl, _, cc) = seen["."][0], seen[","][0]
        raise ValueError(f"{p}: the decimal mark is ambiguous: line {pl} has {pc!r} and line {cl} has {cc!r}; "
                         "pass decimal='.' or decimal=','")
    mark = "," if seen[","] else "."
    # 1,234 may be 1234 as a thousands separator writes it; a comma delimiter leaves no room for a
    # thousands point (it would need a decimal comma)
    if seen[mark] and (delimiter != "," or mark == ",") and all(_GROUPED.match(c) for *_, c in seen[mark]):
        line, i, c = seen[mark][0]
        names = _split(header, delimiter)
        col = f", column {names[i].strip()!r}" if i < len(names) else ""
        raise ValueError(f"{p}: the decimal mark is ambiguous: every number with a separator on the first "
                         f"{len(data) + 1} lines reads as a decimal or as an integer with a thousands separator "
                         f"(line {line}{col}: {c!r}, {c.replace(',', '.')} or {c.replace(mark, '')}); pass "
                         f"decimal={mark!r} if {mark!r} is the decimal mark, else export the numbers without "
                         "thousands separators")
    return mark, bool(seen[mark])


def _number(p: Path, line: int, col: str, cell: str, decimal: str, *, time: bool = False) -> float:
    """One cell as a finite float, or a ``ValueError`` naming the file, line and column (``time``: a
    time-stamp cell, whose date or clock time gets a hint)."""
    c = cell.strip()
    if c == "":
        raise ValueError(f"{p}: line {line}, column {col!r}: empty cell")
    hint = ""
    if "_" in c:  # float() reads Python's digit groups ('1_000' as 1000, '1_0.5' as 10.5); numpy's reader does not
        hint = ("; it holds '_', which groups digits as a thousands separator does: it is not read, export the "
                "numbers without it")
        c = "?"
    elif decimal == ",":
        if "." in c:  # in decimal-comma locales a point groups thousands: never guess
            hint = "; the decimal mark of this file is ',' (pass decimal='.' if it is not)"
            c = "?"
        c = c.replace(",", ".")
    elif _DECIMAL_COMMA.match(c):
        hint = "; it has a decimal comma: pass decimal=','"
    try:
        v = float(c)
    except ValueError:
        if _THOUSANDS.match(cell.strip()):  # float() reads no spreadsheet's separator, and none is guessed
            hint += _THOUSANDS_HINT
        dash = next((ch for ch in cell if ch in _DASHES), None)
        if dash is not None:  # '−1.5' looks like a number: the character that is not ASCII '-' is named
            hint += (f"; it holds {dash!r} (U+{ord(dash):04X} {unicodedata.name(dash, 'DASH')}), not the ASCII "
                     "minus '-' that numbers are read with: replace it with '-'")
        if time and _CLOCK.search(cell):
            hint += ("; time stamps are read as seconds (numbers), ISO 8601 dates and times (2026-11-20 09:14:03.5) "
                     "or clock times (09:14:03.5), and a date in another order (20.11.2026, 11/20/2026) does not say "
                     "which number is the day: convert the column to one of those, or leave time= out and give the "
                     "sampling period Ts= (seconds)")
        raise ValueError(f"{p}: line {line}, column {col!r}: {cell.strip()!r} is not a number{hint}") from None
    if not math.isfinite(v):
        raise ValueError(f"{p}: line {line}, column {col!r}: {cell.strip()!r} is not a finite number")
    return v


def _grouped_message(p: Path, line: int, col: str, cell: str, lines: tuple[int, int]) -> str:
    """What is ambiguous of a number ``cell`` (``1.050``) where the file's ``lines`` (first, last) showed no decimal
    mark."""
    return (f"{p}: line {line}, column {col!r}: {cell!r} reads as {cell} or as {cell.replace('.', '')} with a "
            f"thousands separator, and the numbers on lines {lines[0]} to {lines[1]}, whole numbers, do not show which "
            "decimal mark the file uses (a ';' or tab delimiter is a decimal-comma locale's, where a point groups "
            "thousands); pass decimal='.' if '.' is the decimal mark, else export the numbers without thousands "
            "separators")


def _other_delimiter_hint(row: Sequence[str], delimiter: str) -> str:
    quoted = next((c for c in row if delimiter in c or "\n" in c), None)
    if quoted is not None:  # the csv reader took delimiters into one field: quoted (a quote left open, often)
        return (f" (one field, {quoted.strip()[:40]!r}, is quoted and holds {_name(delimiter)}: if a quote (\") "
                "opens it that no quote closes, close the quote or delete it)")
    joined = delimiter.join(row)
    other = [d for d in _DELIMITERS if d != delimiter and d in joined]
    return f" (it holds {_name(other[0])}: mixed delimiters? pass delimiter= to choose)" if other else ""


def _decimal_comma_hint(row: Sequence[str], delimiter: str) -> str:
    if delimiter == "," and _decimal_comma_cells(row):
        return (": a decimal comma with a comma delimiter cannot be read unambiguously; export the file "
                "again with ';' as the delimiter or '.' as the decimal mark")
    return ""


def _fast_columns(p: Path, index: dict[str, int], *, raw: bytes, text: Callable[[], str], delimiter: str,
                  decimal: str, n_fields: int, reread: bool = True, first: int = 1) -> dict[str, np.ndarray] | None:
    """The columns by numpy's reader (faster on long records), or None when the file needs the
    careful reader: quotes, blank lines, bare carriage returns, a line with another number of fields
    than the header, a field that is not a finite number or that only Python reads (``1_000``), a
    point in a decimal-comma file. Where numpy reads a field it gives the same float as Python's
    ``float``, so a record's content, and the cells' keys, do not depend on the reader. ``raw``
    holds UTF-8 from the header on (file line ``first``); ``reread`` says whether they are the file's own
    bytes, which numpy then reads."""
    if raw.count(b"\r") != raw.count(b"\r\n"):
        return None
    if b'"' in raw:  # quoted fields (a TOA5 file's, every text field quoted): read without their quotes, if whole
        # (after a byte-order mark, which is no field's: the header's first quote opens the line)
        raw = _unquoted(raw[len(codecs.BOM_UTF8):] if raw.startswith(codecs.BOM_UTF8) else raw, delimiter)
        if raw is None:
            return None
        unquoted = raw
        text, reread = functools.cache(lambda: _decode(p, unquoted, 0, len(unquoted))), False
    rows = raw.count(b"\n") + (0 if raw.endswith(b"\n") else 1) - 1  # physical lines after the header
    if rows < 1:
        return None
    # Every line must hold exactly n_fields - 1 delimiters: numpy's reader with usecols would take
    # a line with extra fields silently. The delimiters and line ends, in file order, must then
    # read m delimiters and an end, line after line.
    m, lines = n_fields - 1, rows + 1
    if raw.count(delimiter.encode()) != m * lines:
        return None
    if m:
        buf = np.frombuffer(raw, np.uint8)
        marks = buf[np.flatnonzero((buf == 10) | (buf == ord(delimiter)))]
        if not raw.endswith(b"\n"):
            marks = np.append(marks, np.uint8(10))
        if marks.size != lines * (m + 1) or (marks.reshape(lines, m + 1)[:, m] != 10).any():
            return None
        del buf, marks
    roles = list(index)
    # numpy reads the file again itself: faster than parsing the text held here
    source: object = p if reread else io.StringIO(text())
    if decimal == ",":
        whole = text()
        if "." in whole[whole.find("\n") + 1:]:
            return None  # a point in a decimal-comma file: the careful reader names it
        source = io.StringIO(whole.replace(",", "."))
    stamps = None
    if "time" in index:  # dates or clock times (the first sample's cell says) are read as text, then as stamps
        # the first sample's line alone decoded (a bad byte there is the careful reader's to name)
        second = raw[_skip_lines(raw, 0, 1):_skip_lines(raw, 0, 2)].decode("utf-8", errors="replace")
        cell = _split(second.rstrip("\r\n"), delimiter)[index["time"]].strip() if rows else ""
        if _ISO_STAMP.fullmatch(cell) or _CLOCK_STAMP.fullmatch(cell):
            roles.remove("time")
            try:
                stamps = np.loadtxt(p if reread else io.StringIO(text()), delimiter=delimiter, skiprows=1,
                                    usecols=[index["time"]],
                                    comments=None, dtype=str, ndmin=1, encoding="utf-8-sig")
            except ValueError:
                return None
            if isinstance(source, io.StringIO):
                source.seek(0)
    try:
        arr = np.loadtxt(source, delimiter=delimiter, skiprows=1, usecols=[index[r] for r in roles], comments=None,
                         dtype=np.float64, ndmin=2, encoding="utf-8-sig")
    except ValueError:
        return None
    if arr.shape[0] != rows or not np.isfinite(arr).all() or (stamps is not None and stamps.shape[0] != rows):
        return None
    out = {role: np.ascontiguousarray(arr[:, j]) for j, role in enumerate(roles)}
    if stamps is not None:
        out["_time_cells"] = stamps
    out["_lines"] = np.arange(first + 1, first + rows + 1)
    return out


def _unquoted(raw: bytes, delimiter: str) -> bytes | None:
    """``raw`` without its quotes when each quotes a whole field (opens after a delimiter or a line's start and
    closes before a delimiter or a line's end: ``"2026-01-01 00:00:00",1,"Smp"``) and holds neither the delimiter nor
    a line break, else None (a quote inside a field, ``12"5``, or escaped, ``"a""b"``, one left open, a note over two
    lines: the careful reader's)."""
    buf = np.frombuffer(raw, np.uint8)
    q = np.flatnonzero(buf == ord('"'))
    if q.size % 2:
        return None
    opening, closing = q[0::2], q[1::2]
    ends = np.array([ord(delimiter), ord("\n"), ord("\r")], dtype=np.uint8)
    # the byte before each opening quote (a line feed at 0) and after each closing quote (one at the end): read where
    # they are, as copies of the file (np.append) would double a long file's memory
    before = np.where(opening > 0, buf[np.maximum(opening - 1, 0)], np.uint8(ord("\n")))
    after = np.where(closing + 1 < buf.size, buf[np.minimum(closing + 1, buf.size - 1)], np.uint8(ord("\n")))
    if not (np.isin(before, ends[:2]).all() and np.isin(after, ends).all()):
        return None
    # nor a delimiter or a line break between a quote and the next (a note's stray quotes around a line break
    # leave two lines of the header's width, which the careful reader reads as one sample and refuses): counted by
    # the marks' places, not by a running count over every byte (8 bytes each: 0.9 GB for a file of 33 MB)
    for mark in ends:
        at = np.flatnonzero(buf == mark)
        if (np.searchsorted(at, opening) != np.searchsorted(at, closing)).any():
            return None
    return raw.replace(b'"', b"")


def _bare(name: str) -> str:
    """A column name without a trailing unit in brackets or parentheses, lower case: ``'P (kW)'`` is ``'p'``."""
    return re.sub(r"\s*(\[[^\[\]]*\]|\([^()]*\))\s*$", "", name.strip()).lower()


def _first_row_width(head: str, delimiter: str) -> int | None:
    """The number of fields of the first non-blank line after the header in ``head`` (None: there is none)."""
    rows = csv.reader(io.StringIO(head, newline=""), delimiter=delimiter)
    next(rows, None)
    return next((len(r) for r in rows if r and any(c.strip() for c in r)), None)


def _lookalike(asked: str, found: str) -> str:
    """Where ``found`` differs from ``asked`` only in characters that are not ASCII (``'µ'`` MICRO SIGN for ``'μ'`` GREEK
    SMALL LETTER MU, ``'º'`` for ``'°'``), which print alike: the first such pair named by code point, else ''."""
    if len(asked) != len(found):
        return ""
    pairs = [(a, f) for a, f in zip(asked, found) if a != f]
    if not pairs or any(a.isascii() and f.isascii() for a, f in pairs):
        return ""
    a, f = pairs[0]
    return (f" (the file's {f!r} is U+{ord(f):04X} {unicodedata.name(f, '?')}, the name asked for has {a!r}, "
            f"U+{ord(a):04X} {unicodedata.name(a, '?')}: they print alike)")


def _missing_column_message(path: Path, role: str, col: str, header: Sequence[str], delimiter: str = ",") -> str:
    close = difflib.get_close_matches(col, header, n=3, cutoff=0.5)
    # the same name but for case or a unit in brackets ('u' for 'u [%]', 'p' for 'P (kW)'): difflib's ratio
    # misses a short name beside its unit
    close += [h for h in header if _bare(h) == _bare(col) and h not in close]
    # a character that prints alike but is another ('µ' MICRO SIGN for 'μ' MU), which a one-character name's ratio
    # misses: alike in the compatibility form (NFKC)
    close += [h for h in header if unicodedata.normalize("NFKC", h) == unicodedata.normalize("NFKC", col)
              and h not in close]
    hint = f" Did you mean {' or '.join(repr(c) for c in close)}?{_lookalike(col, close[0])}" if close else ""
    if header and header[0].startswith("#") and (header[0].lstrip("#").strip() == col
                                                 or (len(header) == 1 and col in header[0].lstrip("#").split())):
        # np.savetxt(..., header="t,u,y") writes "# t,u,y": its comments="# " marks the header line as a comment
        return (f"{path}: no column {col!r} (asked for as {role}): the header line starts with '#', so its first "
                f"column reads {header[0]!r}, as np.savetxt writes a header (comments='# '); write the file with "
                "np.savetxt(..., header=..., comments='') or delete the '#'"
                + (f"; the header was read as one column, split at {_name(delimiter)}: pass delimiter=' ' for "
                   "np.savetxt's spaces" if len(header) == 1 else "") + f". The columns are {list(header)}.")
    if len(header) == 1:
        hint += f" The header was read as one column, split at {_name(delimiter)}: pass delimiter= if the file uses another."
    return f"{path}: no column {col!r} (asked for as {role}).{hint} The columns are {list(header)}."


def load_record_csv(
    path: str | os.PathLike,
    u: str | Sequence[str],
    y: str,
    *,
    time: str | None = None,
    Ts: float | None = None,
    name: str | None = None,
    units: tuple[str | tuple[str, ...], str] = ("", ""),
    time_rtol: float = 1e-3,
    input_names: Sequence[str] | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    encoding: str | None = None,
    skiprows: int | None = None,
    units_row: bool | None = None,
) -> Record:
    """A dynamic record (input, output, sampling period) from a CSV file.

    Parameters
    ----------
    path : str or path-like
        The CSV file (header line with column names, one sample per line). The column names are
        line 1, or the line after ``skiprows`` lines; a file with lines before them that are not
        skipped (a data logger's header block) is refused, naming the line that holds them and
        the ``skiprows=`` to pass. A first line ``sep=;`` (Excel's delimiter hint) gives the
        delimiter, and the column names are the line after it. A Campbell Scientific TOA5 file (what
        LoggerNet and CardConvert write: line 1's first field ``TOA5``, then a line of column names,
        a line of units, a line of processing codes such as ``Smp``/``Avg``/``Max``, then the
        samples) is read without options: the names from line 2, the record's units from line 3 (as
        ``units_row=True`` reads a units row), line 4 no sample, and messages name the file's own
        lines; its ``RECORD`` numbers must step by one, or by k throughout in a file thinned to every k-th
        record (whose ``Ts`` is then k logger periods; records missing from the file or repeated in it are refused
        naming the lines); give ``time="TIMESTAMP"`` (or ``Ts``, or both: checked
        against each other) to have its stamps checked too: a pause of the logger, whose record numbers run on,
        shows only there. A binary TOB1/TOB2/TOB3 file is refused: convert it to TOA5 with
        CardConvert.
    u : str or sequence of str
        Name of the input column, or of several input columns (``["n1", "n2"]``).
    y : str
        Name of the output column.
    time : str, optional
        Name of a time-stamp column: seconds as numbers (a column whose name states another unit of elapsed
        time, e.g. ``t [ms]``, ``time (min)``, ``t_ms``, is converted to seconds as a units row's is, and a name
        and a units row giving two units are refused; ticks of one, ``Zeit [10ms]``, are refused, and so are numbers
        that are a spreadsheet's serial dates, MATLAB's datenums or Unix time counted in ms, µs or ns), ISO 8601
        dates and times (``2026-11-20 09:14:03.5``, ``2026-11-20T09:14:03Z``, a TOA5 file's ``TIMESTAMP``; with a
        UTC offset the elapsed time is read, so a clock change is no jump, while local times without one that jump
        by an hour are refused as one), or clock times with seconds (``09:14:03.5``, midnight passed read as the
        next day; ISO's 24:00:00 is the next midnight, hours past it, 26:13:05, an elapsed time as a spreadsheet's
        [h]:mm:ss duration writes it, and a leap second, 23:59:60, is refused). Dates in
        another order (``20.11.2026``, ``11/20/2026``) are refused: leave ``time`` out and give ``Ts``, or
        convert the column. Stamps must increase strictly and evenly: every
        step within ``time_rtol`` × (median step) of the median step (and of what float64 resolves of
        stamps far from zero, e.g. Unix time). The sampling period is the mean step, rounded to 12
        significant digits, or to those the stamps' float64 values resolve (about 5 for Unix time).
        Records restart at t = 0 whatever the first stamp is.
    Ts : float, optional
        Sampling period in seconds. Required when there is no time column; when both are given
        they must agree within ``time_rtol``, and the record's period is ``Ts``.
    name : str, optional
        Record name (default: the file name without extension).
    units : tuple
        Units of (u, y), as a :class:`~graybox.Record`'s (the inputs' one str, or one per input): shown,
        and checked against the other data's and a model's (default none said).
    time_rtol : float
        Relative tolerance on the time steps (default 1e-3: stamps printed with few digits pass,
        a logger's jitter or a missing sample does not).
    input_names : sequence of str, optional
        Names the terms use for the inputs. Default: ``"u"`` for a single column given as a
        string, the column names themselves for a list of columns (they must then be
        identifiers other than y, e, k).
    delimiter : str, optional
        The column delimiter, e.g. ``","``, ``";"`` or ``"\\t"``. Default: detected (``,``, ``;`` or
        tab: the one that splits the header and the first lines into the same number of columns).
    decimal : {".", ","}, optional
        The decimal mark. Default: detected (``,`` where numbers such as ``2,5`` appear with a
        ``;`` or tab delimiter, or quoted). With ``","`` a point in a number is an error, never a
        thousands separator. Thousands separators (``1,234.5``, ``1.234,5``, ``1 234,5`` with a
        space or a no-break space) are never read: such a number is an error naming its line, and a
        file whose every decimal could also be an integer with a thousands separator (``1,234``
        and no other decimal in the first 50 lines) is refused unless ``decimal=`` is given, and so is such a
        number (``1.050``) further on in a ``;`` or tab file whose first 50 lines hold whole numbers only.
    encoding : str, optional
        The text encoding, any name Python knows (e.g. ``"cp1252"``, what Excel writes as "CSV"
        on Windows in Western Europe and the Americas; ``"utf-16-le"``). Default: UTF-8, or UTF-16
        or UTF-32 when the file starts with their byte-order mark (Excel's "Unicode text"); a file
        that is not UTF-8 is an error naming the line and suggesting ``encoding=``; an encoding
        that contradicts the file's byte-order mark is an error.
    skiprows : int, optional
        Lines before the column names that are not read (default 0; 1 for a TOA5 file, where
        another value is refused), e.g. a data logger's header
        block of instrument, date and channels. Messages still name the file's own lines (line 1
        is its first line, skipped or not).
    units_row : bool, optional
        The line after the column names (blank lines passed over) gives each column's unit
        (``s;rpm;Pa``, brackets allowed),
        as data loggers write: it becomes the record's ``units`` (inputs in units of their own keep
        one each, ``(("rpm", "%"), "Pa")``; a ``units=`` that contradicts it is refused; a time
        column of numbers in ``ms``, ``µs`` (``us``), ``ns``, ``min``, ``h`` or ``d`` is converted to seconds, one
        of dates or clock times must say ``s`` or nothing; a symbol is read in its own case only, ``Ms`` or ``MS``
        refused as ambiguous, words such as ``Sec`` or ``MIN`` in any, and ``mSec`` as its prefix is written).
        Without it such a line is refused, naming this option.
        Default False, True for a TOA5 file (where ``False`` is refused).

    Returns
    -------
    Record
        ``u`` of shape (N,) for one input, (N, m) for several; ``y`` of shape (N,).

    Raises
    ------
    ValueError
        Naming the file and the line or column: a missing column (with close names), column names
        below the header line (a header block not skipped, or skipped too far), a ``sep=`` line that
        disagrees with ``delimiter=``, a negative ``skiprows``, a ``skiprows`` or ``units_row`` that
        contradicts a TOA5 file, a TOA5 file whose header lines were cut (numbers on its units or
        processing-codes line) or swapped (processing codes on its units line) or a gap in its ``RECORD`` numbers, a binary TOB1/TOB2/TOB3 file, an empty cell, NaN/inf or text in a used column, non-increasing or uneven stamps, Ts disagreeing
        with the stamps, or neither ``time`` nor ``Ts`` given; an empty file, a header without
        rows, mixed delimiters, a decimal comma with an unquoted comma delimiter, a delimiter or
        decimal mark that the first lines leave ambiguous (pass ``delimiter=`` / ``decimal=``), a
        thousands separator, text that is not in the encoding (UTF-8 by default), an unknown
        ``encoding`` (or one that contradicts the file's byte-order mark), or a binary file (an
        Excel workbook, a compressed CSV, NumPy, Parquet or LabVIEW TDMS), named as what it is.
    TypeError
        ``path``, ``u``, ``y``, ``time``, ``name``, ``Ts``, ``delimiter``, ``decimal``, ``encoding``, ``skiprows`` or ``units`` of the wrong
        type (a column is named by a str; units are a pair of str).
    """
    p = Path(check_path(path, "path", file=True))
    if name is not None:
        check_str(name, "name")
    if time is None and Ts is None:
        raise ValueError(f"{p}: give the time-stamp column (time=...) or the sampling period (Ts=... seconds)")
    if Ts is not None:
        # one number as Record reads it (a 0-d array too); an int beyond the float range was a bare OverflowError
        try:
            Ts = check_real(Ts, f"{p}: Ts (seconds)")
        except TypeError:
            raise TypeError(f"{p}: Ts must be a positive number of seconds, got {Ts!r}") from None
        if not Ts > 0:
            raise ValueError(f"{p}: Ts must be a positive number of seconds, got {Ts!r}")
    if time is not None and not isinstance(time, str):
        raise TypeError(f"time must name the time-stamp column (a str), got {time!r}")
    units = check_units(units, f"{p}")
    check_real(time_rtol, "time_rtol", low=0, high=1, low_open=True, high_open=True)
    skiprows = None if skiprows is None else check_int(skiprows, "skiprows", low=0)
    ucols, names = _input_columns(p, u, y, input_names)
    wanted = _wanted(ucols, y, time=time)
    units_row = None if units_row is None else check_bool(units_row, "units_row")
    cols = _read_columns(p, wanted, delimiter=delimiter, decimal=decimal, encoding=encoding, skiprows=skiprows,
                         units_row=units_row)
    lines = cols["_lines"]
    if "_units" in cols:  # units_row=True, or a TOA5 file
        units = _units_from_row(p, units, cols["_units"], [r for r in wanted if r not in ("y", "time")], time)
    if "_record" in cols:
        _check_record_numbers(p, cols["_record"], lines)
    if time is not None:
        t = _time_column_seconds(p, time, cols["time"], cols.get("_units"), cols.get("_stamps"))
        Ts = _check_time(p, time, t, lines, Ts, time_rtol, cols.get("_stamps"))
    return Record(_inputs(cols, ucols), cols["y"], Ts=float(Ts), name=name or p.stem, units=units, input_names=names)


def _time_column_seconds(p: Path, col: str, t: np.ndarray, row: dict[str, str] | None,
                         stamps: Sequence[str] | None) -> np.ndarray:
    """The time column ``col``'s numbers ``t`` in seconds: elapsed time in ms, min … as its name (``t [ms]``,
    ``t_ms``) or the units row ``row`` says, through one table (:data:`_TIME_UNITS`); a name and a units row that
    give two units are refused naming both. A tick in the name (``t [10ms]``) is refused by :func:`_check_time`."""
    named = _TIME_UNIT.search(col)
    said = "" if row is None else row.get("time", "")
    if named is None or named.group(1) is None:
        return t if row is None else _time_in_seconds(p, said, t, stamps, col)
    unit = named.group(1)
    if said.strip() and _time_unit(p, said, col) != _time_unit(p, unit, col):
        raise ValueError(f"{p}: column {col!r} names its unit {unit!r}, but the units row gives it {said!r}: correct "
                         "the one that is wrong")
    return _time_in_seconds(p, unit, t, stamps, col, source=f"column {col!r} names")


def _wanted(ucols: Sequence[str], y: str, **more: str | None) -> dict[str, str]:
    """The columns a loader reads, by role: the inputs (``u``, or ``input 'name'`` each), ``y``, and
    the roles of ``more`` that name a column."""
    return ({f"input {c!r}" if len(ucols) > 1 else "u": c for c in ucols} | {"y": y}
            | {role: col for role, col in more.items() if col is not None})


def _inputs(cols: dict[str, np.ndarray], ucols: Sequence[str]) -> np.ndarray:
    """The input columns read by :func:`_read_columns`: shape (N,) for one, (N, m) for several."""
    return cols["u"] if len(ucols) == 1 else np.column_stack([cols[f"input {c!r}"] for c in ucols])


def _input_columns(p: Path, u: object, y: object, input_names: object) -> tuple[list[str], tuple[str, ...] | None]:
    """The input column names and the input names of a loader's ``u`` argument (its ``y`` checked too)."""
    if not isinstance(y, str):
        raise TypeError(f"{p}: y must name the output column (a str), got {y!r}")
    check_ordered(u, f"{p}: u", "input column names (the inputs' order)")  # a set's changes from run to run
    if isinstance(u, Mapping):  # its keys would be read, its values (units, say) dropped without a word
        raise TypeError(f"{p}: u must name an input column (a str) or be a list of input column names, got a "
                        f"{type(u).__name__} ({u!r}); units go in units=(input unit, output unit)")
    if isinstance(u, str):
        ucols = [u]
    elif hasattr(u, "__iter__") and hasattr(u, "__len__") and all(isinstance(c, str) for c in u):  # type: ignore[attr-defined]
        ucols = [str(c) for c in u]  # type: ignore[attr-defined]  # a list, a tuple, a pandas Index of names
    else:
        raise TypeError(f"{p}: u must name an input column (a str) or be a list of input column names, got {u!r}")
    if not ucols:
        raise ValueError(f"{p}: u must name an input column or a non-empty list of input columns, got {u!r}")
    dup = sorted({c for c in ucols if ucols.count(c) > 1})
    if dup:
        raise ValueError(f"{p}: input column {dup[0]!r} is named twice in u = {ucols}")
    if input_names is not None:
        return ucols, check_input_names(input_names, len(ucols), f"{p}: input_names")
    if isinstance(u, str):
        return ucols, None
    try:
        return ucols, check_input_names(ucols, len(ucols), f"{p}: input columns")
    except ValueError as exc:
        raise ValueError(f"{exc}; name the inputs with input_names=[...]") from None


#: A time column's name that states a unit other than seconds: "t [ms]", "time (min)", "t_ms", "Zeit/h".
_TICK_NUMBER = r"(?:\d+(?:[.,]\d+)?|[.,]\d+)"
#: a tick's power of ten as it is written: 1e-3, 10^-3, 10**-3, 1·10^-3, 1 x 10^-3, 10⁻³
_TICK_POWER = (r"(?:e[-+−]?\d+|(?:\s*[·*×x]\s*10)?\s*(?:\^|\*\*)\s*[-+−]?\d+"
               r"|(?:\s*[·*×x]\s*10)?\s*[⁻⁺]?[⁰¹²³⁴⁵⁶⁷⁸⁹]+)")
_TICK_FRACTION = r"(?:\s*/\s*" + _TICK_NUMBER + _TICK_POWER + "?)"
#: the units other than seconds a name may give, bare ("t [h]") or with a tick's number ("t [2h]")
#: (:data:`_TIME_UNITS`' own, not a list of its own: the table's nsec and nanoseconds, missing here, read as seconds)
_OTHER_UNITS = "|".join(re.escape(k) for k in sorted((k for k, v in _TIME_UNITS.items() if v != (1, 1)), key=len,
                                                     reverse=True))
_TICK_UNIT = rf"(?:s|secs?|seconds?|{_OTHER_UNITS})"
_TIME_UNIT = re.compile(rf"(?:[\[(]\s*|[_/ -])({_OTHER_UNITS})\s*[\])]?\s*$"
                        # a tick of a PLC or logger: "Zeit [10ms]", "t (0.1 s)", "t [1/10 s]", "t [1e-3 s]", "t [10^-3 s]",
                        # "t [10⁻³ s]", "t [s/10]", "time [100 µs]", "t [2h]" (but "[1 s]" is seconds)
                        r"|[\[(]\s*((?!1(?:[.,]0*)?\s*(?:s|secs?|seconds?)\s*[\])])"
                        rf"(?:{_TICK_NUMBER}{_TICK_POWER}?{_TICK_FRACTION}?\s*[·*×x]?\s*{_TICK_UNIT}{_TICK_FRACTION}?"
                        rf"|{_TICK_UNIT}{_TICK_FRACTION}))"
                        r"\s*[\])]\s*$", re.IGNORECASE)


#: An ISO 8601 date and time as loggers, pandas and spreadsheets write them: 2026-11-20 09:14:03.5,
#: 2026-11-20T09:14:03Z, 2026-11-20 09:14:03.125+01:00 (seconds and their fraction optional; a UTC offset or Z optional)
_ISO_STAMP = re.compile(r"(\d{4}-\d{2}-\d{2})[T ](\d{2}):(\d{2})(?::(\d{2})(?:[.,](\d+))?)?"
                        r"\s*(Z|[+-]\d{2}(?::?\d{2})?)?")
#: A clock time without a date, as loggers that write the date in a column of its own: 09:14:03, 09:14:03.5 (its
#: seconds required: 01:30 may be a stopwatch's minutes and seconds, read as hours and minutes it is 60 times too long);
#: an elapsed time's hours up to nine digits ([h]:mm:ss counts on: 1000:00:00 ends a 1000-hour run; more
#: would leave the whole seconds' int64)
_CLOCK_STAMP = re.compile(r"(\d{1,9}):(\d{2}):(\d{2})(?:[.,](\d+))?")
#: A date in another order (20.11.2026, 11/20/2026): which is the day is not told by the cell
_OTHER_DATE = re.compile(r"\d{1,4}[./-]\d{1,2}[./-]\d{1,4}")


def _stamps(p: Path, col: str, cells: Sequence[str], lines: Sequence[int],
            decimal: str) -> tuple[np.ndarray, tuple[str, ...] | None]:
    """A time column's cells as seconds, shape (N,), and the cells as written for messages (None for numbers).

    Numbers are seconds. ISO 8601 dates and times (every cell one: ``2026-11-20 09:14:03.5``, a TOA5 file's
    ``TIMESTAMP``) are the seconds after the first stamp, the elapsed time where the stamps carry a UTC offset (a
    clock change then no jump); clock times (``09:14:03.5``; seconds required, as ``01:30`` may be a stopwatch's
    minutes and seconds) the seconds after the first, a step back of more than 12 hours read as midnight passed, or,
    where an hour passes 24 (``26:13:05``, a spreadsheet's [h]:mm:ss duration), elapsed times that count on.
    The fraction of a second is read to every digit written (a datetime keeps six).
    Other forms of dates (``20.11.2026``, ``11/20/2026``: which number is the day the cell does not say) are refused,
    naming how to pass them."""
    first = cells[0].strip() if len(cells) else ""
    iso = _ISO_STAMP.fullmatch(first)
    if not iso and not _CLOCK_STAMP.fullmatch(first):
        out = np.empty(len(cells))
        for k, (line, cell) in enumerate(zip(lines, cells)):
            out[k] = _number(p, line, col, cell, decimal, time=True)
        return out, None
    shown = tuple(c.strip() for c in cells)
    if iso and iso[6] is None:
        t = _naive_iso_seconds(shown)
        if t is not None:
            return t, shown
    form = _ISO_STAMP if iso else _CLOCK_STAMP
    whole = np.empty(len(cells), dtype=np.int64)  # exact whole seconds
    frac = np.empty(len(cells))  # and their fraction
    aware = None
    elapsed = False  # clock times past 24 h: a duration, whose hours count on past midnight
    for k, (line, c) in enumerate(zip(lines, shown)):
        m = form.fullmatch(c)
        try:
            if m is None:
                raise ValueError
            if iso:
                day, h, mi, sec, f, tz = m.groups()
                days = date.fromisoformat(day).toordinal()
                if aware is None:
                    aware = tz is not None
                elif aware != (tz is not None):
                    raise ValueError(f"{p}: line {line}, column {col!r}: {c!r} " + (
                        "has a UTC offset but the stamps before it have none" if aware is False else
                        f"has no UTC offset but line {lines[0]}'s {shown[0]!r} has one") + ": write every stamp with "
                        "its offset (or in UTC), or none")
                shift = 0 if tz in (None, "Z") else (1 if tz[0] == "+" else -1) * (
                    3600 * int(tz[1:3]) + 60 * int(tz[3:].lstrip(":") or 0))
            else:
                h, mi, sec, f = m.groups()
                days, shift = 0, 0
            if int(sec or 0) == 60 and int(mi) == 59:  # UTC's leap second: no count of elapsed seconds past it here
                raise ValueError(f"{p}: line {line}, column {col!r}: {c!r} is a leap second (23:59:60 UTC), which "
                                 "the seconds elapsed are not read across (the stamps either side are 2 s apart, "
                                 "read as 1 s); cut the file into two records there, or write the stamps in GPS or "
                                 "TAI time, which have none")
            hour, minute, second = int(h), int(mi), int(sec or 0)
            end_of_day = (hour, minute, second) == (24, 0, 0) and not (f or "0").strip("0")
            # ISO 8601's 24:00:00 is the day's end, the next day's 00:00:00; a clock time's hour past it is an elapsed
            # time past a day (a spreadsheet's [h]:mm:ss duration: 24:00:01, 100:00:00), whose hours count on
            past_day = not iso and hour >= 24 and not end_of_day
            dt_time(0 if end_of_day or past_day else hour, minute, second)  # refuses 25:00 of a date, 09:61
            elapsed = elapsed or past_day
            whole[k] = 86400 * days + 3600 * hour + 60 * minute + second - shift
            frac[k] = float("0." + f) if f else 0.0
        except ValueError as exc:
            if str(exc).startswith(str(p)):
                raise
            kind = ("an ISO 8601 date and time (2026-11-20 09:14:03.5)" if iso
                    else "a clock time (09:14:03.5)")
            if k == 0:  # the first stamp, of the form its column is read in, but a field out of range
                raise ValueError(f"{p}: line {line}, column {col!r}: {c!r} is not {kind}: its "
                                 f"{'date, hour, ' if iso else ''}minute or second is out of range") from None
            raise ValueError(f"{p}: line {line}, column {col!r}: {c!r} is not {kind}, as the column's first stamp "
                             f"{shown[0]!r} (line {lines[0]}) is") from None
    t = (whole - whole[0]).astype(float) + (frac - frac[0])
    if not iso and not elapsed:  # a clock time past midnight starts the next day
        t += 86400.0 * np.concatenate([[0], np.cumsum(np.diff(t) < -43200)])
    return t, shown


#: Sampling periods (seconds) a spreadsheet's serial dates step by as a fraction of a day: 1 ms to 1 h, 1-2-5
_ROUND_PERIODS = np.array([m * 10.0**e for e in range(-3, 4) for m in (1, 2, 5) if m * 10.0**e <= 3600] + [60, 3600])


#: Usual acquisition rates (Hz): 1-2-5 from 1 Hz to 1 MHz, video and mains (24, 25, 30, 48, 60 …), powers of 2 and
#: audio. Stamps that read as seconds at one of them as well as serial dates of a round period (24 Hz is 1 h of a
#: day exactly; 25 Hz 3456 s, 40 Hz 2160 s: within what a short record's few decimals leave unknown) are seconds.
_ACQUISITION_RATES = np.array(sorted({m * 10.0**e for e in range(7) for m in (1, 2, 5) if m * 10.0**e <= 1e6}
                                     | {24.0, 25.0, 30.0, 40.0, 48.0, 60.0, 120.0, 240.0, 400.0, 4000.0, 11025.0,
                                        22050.0, 44100.0, 88200.0, 16000.0, 32000.0, 48000.0, 96000.0, 192000.0}
                                     | {2.0**k for k in range(6, 17)}))

#: MATLAB's datenum (days since year 0) of 1954-01-01 and 2202-01-01: seconds there are 8 days into a run
_DATENUM_SPAN = (713685, 804265)


def _refuse_serial_dates(p: Path, col: str, t: np.ndarray) -> None:
    """A ``ValueError`` when numeric stamps are a spreadsheet's serial dates (days since 1899-12-30, what Excel
    writes for a date cell formatted as a number: 46000.5 is 2025-12-09 12:00; since 1904-01-01 in a workbook of
    the 1904 date system, which the message names too; or MATLAB's datenum, days since year 0: 739960.5): every stamp
    a day of the years 1954-2201 (1958-2205) and the mean step a round period as a fraction of a day (1 s is
    1.157e-5), to within what the digits the stamps are written with leave unknown (at least 0.1 %; at most 10 % where
    they increase strictly), where read as seconds the record's period would be 86,400 times too short without a
    word. Seconds that look so are sampled at 86.4 kHz / (1, 2, 5 …), a rate no acquisition uses (100 kHz is 0.864 s
    of a day: 14 % off; 44.1 kHz 1.96 s: 2 %).
    The mean step, not the median: a General cell shows 11 digits, 1e-6 of a day, so 0.1 s steps print as 1e-6 or
    2e-6 (and are uneven), while their mean keeps the period (to 1e-6 day over the record: 4.5 % of 0.1 s at 20
    samples).
    Stamps that read as seconds at a usual acquisition rate (:data:`_ACQUISITION_RATES`) as closely as they read as
    serial dates of a round period are seconds, not refused: 25 or 40 Hz lie within what a short record's few
    decimals leave unknown of 1 h or 2000 s. 24 Hz is 1 h of a day exactly (36000.041667 …, 10 h into a run): the
    numbers cannot tell those seconds from hourly serial dates (46000.041667 …), and they stay refused, the message
    saying how to read them as seconds."""
    ref = (t[-1] - t[0]) / (t.size - 1)
    matlab = _DATENUM_SPAN[0] <= t.min() and t.max() < _DATENUM_SPAN[1]
    if not ((t.min() >= 20000 and t.max() < 110000) or matlab) or not 0 < ref < 1:
        return
    seconds = ref * 86400
    near = _ROUND_PERIODS[np.argmin(np.abs(np.log(_ROUND_PERIODS / seconds)))]
    # the stamps' last decimal (days): each printed to half of it, so the mean step to it over the N − 1 steps (a 5 %
    # window took 44.1 kHz seconds, 2 % off 2 s, for dates); the floats tell decimals down to their round-off
    noise = 64 * float(np.spacing(np.abs(t).max()))
    places = int(np.floor(np.log10(1e-2 / noise)))
    last = 10.0**-places
    for d in range(places + 1):
        x = t * 10.0**d
        if np.all(np.abs(x - np.round(x)) < noise * 10.0**d):
            last = 10.0**-d
            break
    window = max(1e-3, last * 86400 / ((t.size - 1) * near))
    if np.all(np.diff(t) > 0):
        # stamps that increase may be seconds: a short record's few decimals leave its mean step unknown by 14 % and
        # more (100 kHz is 0.864 s of a day: 5 samples of 100000.00001 s steps were refused), and they are not said
        # to be dates past 10 % off a round period; serial dates of steps below their 11 digits repeat
        window = min(window, 0.1)
    off = abs(seconds / near - 1)
    rate = _ACQUISITION_RATES[np.argmin(np.abs(np.log(_ACQUISITION_RATES * ref)))]  # read as seconds: 1/ref Hz
    # a tie within the floats' round-off (24 Hz is 1 h of a day exactly) stays refused: hourly serial dates read as
    # 24 Hz seconds would be a period 86,400 times off without a word; the message says how to load such seconds
    if off > window or abs(rate * ref - 1) < off - 1e-9:
        return
    if matlab:
        day = datetime(1, 1, 1) + timedelta(days=float(t[0]) - 367)  # datenum(1, 1, 1) is 367
        raise ValueError(f"{p}: column {col!r} holds {t[0]:.10g} and steps by {ref:.4g}: MATLAB's datenum (days since "
                         f"year 0: {t[0]:.10g} is {day:%Y-%m-%d %H:%M:%S}; a step of {near:g} s), not seconds, which "
                         "would make the sampling period 86,400 times too short; convert the column to seconds "
                         "(MATLAB: (t - t(1)) * 86400) or write it as dates and times (datestr(t, 'yyyy-mm-dd "
                         "HH:MM:SS.FFF')), or leave time= out and give Ts=")
    # the file does not say which of Excel's two date systems wrote the numbers: both readings are named
    day = datetime(1899, 12, 30) + timedelta(days=float(t[0]))
    mac = datetime(1904, 1, 1) + timedelta(days=float(t[0]))
    raise ValueError(f"{p}: column {col!r} holds {t[0]:.10g} and steps by {ref:.4g}: a spreadsheet's serial dates "
                     f"(days since 1899-12-30, or since 1904-01-01 in a workbook of the 1904 date system (Mac Excel): "
                     f"{t[0]:.10g} is {day:%Y-%m-%d %H:%M:%S} in the 1900 system, {mac:%Y-%m-%d %H:%M:%S} in the "
                     f"1904 system; a step of {near:g} s), not "
                     "seconds, which would make the sampling period 86,400 times too short; format the column as "
                     "dates and times (2026-11-20 09:14:03.5) before saving the file, convert it to seconds "
                     "(pandas: (x - x[0]) * 86400), or leave time= out and give Ts="
                     + (f" (seconds at {rate:g} Hz, whose steps are {near:g} s of a day exactly: leave time= out and "
                        f"give Ts=1/{rate:g})" if abs(rate * ref - 1) <= 1e-6 else ""))


#: Unix time (seconds since 1970-01-01 UTC) of 1980-01-01 and 2100-01-01: counted in ms, µs or ns, the instants
#: between lie past 10,000 years read as seconds, where no elapsed or wall-clock time in seconds lies (Unix, GPS,
#: LabVIEW's 1904 and NTP's 1900 epochs give at most 6e9 s), and the ranges of the three units do not overlap
_UNIX_SPAN = (315532800.0, 4102444800.0)
_SUBSECONDS = (("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9))


def _refuse_unix_subseconds(p: Path, col: str, t: np.ndarray) -> None:
    """A ``ValueError`` when numeric stamps are Unix time counted in milliseconds (JavaScript's ``Date.now()``, many
    IoT and logger exports), microseconds or nanoseconds: every stamp an instant of 1980-2100 in that unit, where read
    as seconds the record's period would be 1000, 10^6 or 10^9 times too long without a word."""
    for unit, per_second in _SUBSECONDS:
        if _UNIX_SPAN[0] * per_second <= t.min() and t.max() < _UNIX_SPAN[1] * per_second:
            step = (t[-1] - t[0]) / (t.size - 1) / per_second
            when = datetime(1970, 1, 1) + timedelta(seconds=float(t[0]) / per_second)
            raise ValueError(f"{p}: column {col!r} holds {t[0]:.0f} and steps by {step * per_second:.6g}: Unix time "
                             f"in {unit} ({when:%Y-%m-%d %H:%M:%S} UTC; a step of {step:.6g} s), not seconds, which "
                             f"would make the sampling period {per_second:,.0f} times too long; convert the column to "
                             f"seconds (pandas: x / {per_second:.0f}), or leave time= out and give Ts=")


def _naive_iso_seconds(cells: Sequence[str]) -> np.ndarray | None:
    """:func:`_stamps` of ISO dates and times without a UTC offset, all written alike (one length), by numpy's
    parser (20 times faster than a cell at a time: 0.04 s for 200,000), to the nanosecond; None where it cannot
    take them all (an offset, a decimal comma, a cell of another form, NaT): the cell-by-cell reading then says
    which line is wrong."""
    a = np.asarray(cells, dtype=str)
    lengths = np.char.str_len(a)
    if not (lengths == lengths[0]).all():
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy warns of (and drops) an offset it reads
        try:
            # in microseconds first: nanoseconds hold only the years 1678-2261, and numpy wraps others silently
            # (2300-01-01 read as 1715-06-13)
            us = a.astype("datetime64[us]")
            if np.isnat(us).any() or not (_NS_RANGE[0] <= us.min() and us.max() <= _NS_RANGE[1]):
                return None
            d = a.astype("datetime64[ns]")
        except (ValueError, Warning):
            return None
    return (d - d[0]).astype(np.int64) / 1e9


#: The instants numpy's datetime64[ns] holds (with a day's margin)
_NS_RANGE = (np.datetime64("1677-09-23", "us"), np.datetime64("2262-04-10", "us"))


def _local_hour(shown: Sequence[str] | None, i: int) -> bool:
    """Whether stamp ``i`` as written is an ISO date and time without a UTC offset: local time, which a clock change
    moves by an hour."""
    m = None if shown is None else _ISO_STAMP.fullmatch(shown[i])
    return m is not None and m[6] is None


def _check_time(p: Path, col: str, t: np.ndarray, lines: np.ndarray, Ts: float | None, rtol: float,
                shown: Sequence[str] | None = None) -> float:
    """The sampling period the stamps ``t`` (seconds, shape (N,)) give, checked (``shown``: the stamps as written,
    dates or clock times, for the messages)."""

    def at(i: int) -> str:
        return f"{t[i]:g} s" if shown is None else repr(shown[i])

    unit = _TIME_UNIT.search(col)
    if unit and unit.group(2):  # a tick (a unit alone was converted): read as seconds, a period off by 10 or 1000
        raise ValueError(f"{p}: column {col!r} names its unit {unit.group(2)!r}, but time stamps are read as seconds "
                         "(a unit alone, t [ms], is converted, not a tick of one): convert the column to seconds, or "
                         "leave time= out and give the sampling period Ts= in seconds")
    if t.size < 2:
        raise ValueError(f"{p}: column {col!r} has a single time stamp; the sampling period needs two")
    if shown is None:  # before the steps are judged: printed with 11 digits, serial dates step unevenly, or by 0
        _refuse_serial_dates(p, col, t)
        _refuse_unix_subseconds(p, col, t)
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        i = int(bad[0])
        # a file listing the samples newest first (some loggers and exports do) decreases throughout
        order = (": the stamps decrease throughout, so the file lists the samples newest first; sort its rows by "
                 "time, oldest first (e.g. pandas: df.sort_values(time column))") if (dt < 0).all() else ""
        if not order and _local_hour(shown, i) and abs(dt[i] + 3600 - np.median(dt)) <= 1.0:
            order = (": an hour back, a clock change (daylight saving time) in local times? Write the stamps in UTC "
                     "or with their UTC offset (2026-10-25 02:59:59+02:00), or cut the file into two records there")
        raise ValueError(f"{p}: column {col!r}: time does not increase from line {lines[i]} ({at(i)}) "
                         f"to line {lines[i + 1]} ({at(i + 1)}){order}")
    # The median step is the reference, so the message points at the odd step (a gap, a jitter),
    # not at the first regular one.
    ref = float(np.median(dt))
    # float64 holds a stamp to half its spacing, so a step read from two stamps is off by up to one
    # spacing whatever was printed (Unix time, 1.7e9 s, to 2.4e-7 s): unevenness below that is unseen
    res = 2 * float(np.spacing(np.abs(t).max()))
    off = np.abs(dt - ref) > rtol * ref + res
    if off.any():
        i = int(np.flatnonzero(off)[0])
        n = round(dt[i] / ref)
        between = f"from line {lines[i]} to line {lines[i + 1]}" + ("" if shown is None else
                                                                     f" ({at(i)} to {at(i + 1)})")
        if _local_hour(shown, i) and abs(abs(dt[i] - ref) - 3600) <= max(rtol * ref, 1.0):
            raise ValueError(f"{p}: column {col!r}: uneven time stamps: step {dt[i]:g} s {between} is the usual "
                             f"(median) step {ref:g} s {'plus' if dt[i] > ref else 'less'} an hour: a clock change "
                             "(daylight saving time) in local times? Write the stamps in UTC or with their UTC "
                             "offset (2026-03-29 01:59:59+01:00), or cut the file into two records there")
        if n >= 2 and abs(dt[i] - n * ref) <= max(rtol, 0.1) * ref:  # a whole number of periods: samples lost
            raise ValueError(f"{p}: column {col!r}: uneven time stamps: step {dt[i]:g} s {between} "
                             f"is {n} times the usual (median) step {ref:g} s, a gap of {n - 1} "
                             "missing sample(s) (no time_rtol reads it); cut the file into two records at the gap "
                             "(several records of one plant go to the estimators as a list), or fill the gap first")
        raise ValueError(f"{p}: column {col!r}: uneven time stamps: step {dt[i]:g} s {between}, "
                         f"but the usual (median) step is {ref:g} s (off by "
                         f"{abs(dt[i] - ref) / ref:.1e} relative, tolerance {rtol:g}); resample the data to a "
                         "constant period first, or, if the stamps are only rounded (printed with few digits), "
                         "pass a larger time_rtol=")
    step = (t[-1] - t[0]) / (t.size - 1)
    if Ts is not None:  # the user's word, checked against the stamps
        if abs(Ts - step) > rtol * step:
            # hourly serial dates read as seconds at 24 Hz (the numbers cannot tell them apart: _refuse_serial_dates)
            days = (" (86,400 times: the stamps are a spreadsheet's serial dates, days, not seconds? Leave time= out "
                    "and give Ts=)" if shown is None and abs(Ts / (step * 86400) - 1) <= max(rtol, 1e-3) else "")
            raise ValueError(f"{p}: Ts = {Ts:g} s disagrees with column {col!r}, whose mean step is {step:g} s{days}")
        return float(Ts)
    # Stamps are printed decimals, so the true step is a short decimal: drop the float noise of the
    # division (e.g. 199.95 / 3999 = 0.049999999999999996 -> 0.05), and the digits the stamps' float64
    # rounding leaves unknown (a mean step from stamps near 1.7e9 s holds about 5 digits).
    with np.errstate(divide="ignore"):  # stamps near 1e-300 s: no digit unknown
        digits = int(np.clip(np.floor(-np.log10(res / (t.size - 1) / step)), 1, 12))
    return float(f"{step:.{digits}g}")


def _check_record_numbers(p: Path, rec: np.ndarray, lines: np.ndarray) -> None:
    """A ``ValueError`` when a TOA5 file's ``RECORD`` numbers do not step by one from sample to sample: records
    missing from the file (overwritten in the logger's memory before they were collected, lines deleted) or repeated
    in it (a collection appended twice, the table reset), so the lines either side are no one record at one sampling
    period. (A pause of the logger does not show here: its record numbers run on, and only TIMESTAMP jumps.) A file
    thinned to every k-th sample (CardConvert's or a script's decimation) steps by k throughout: its usual (median)
    step, a whole number held by most lines, is the step expected (it was refused as records missing at its first
    line)."""
    step = np.diff(rec)
    usual = float(np.median(step)) if step.size else 1.0
    # taken where it is the step of most lines, two at least (one step, 7 to 2345686, is no thinning: a gap)
    held = int(np.count_nonzero(step == usual))
    usual = usual if usual >= 1 and usual.is_integer() and held >= max(2, step.size / 2) else 1.0
    bad = np.flatnonzero(step != usual)
    if not bad.size:
        return
    i = int(bad[0])
    a, b = rec[i], rec[i + 1]
    # the numbers as they are, all their digits (%g said a gap from 1234568 to 1234570 as 'from 1.23457e+06 to
    # 1.23457e+06'): a logger's record numbers pass a million after twelve days at 1 Hz
    def text(v: float) -> str:
        return f"{v:.0f}" if float(v).is_integer() else exact_text(v)

    where = f"from {text(a)} (line {lines[i]}) to {text(b)} (line {lines[i + 1]})"
    if b > a and usual != 1 and not float((b - a) / usual).is_integer():
        # no whole number of the thinned steps: no count of records missing says it (it read '-0.5 of those')
        raise ValueError(f"{p}: column 'RECORD', the TOA5 file's record numbers, steps {where}, by {text(b - a)}, "
                         f"where the file's other lines step by {usual:.0f} (one record in {usual:.0f} kept): the "
                         "samples either side are no one record at one sampling period; cut the file into two "
                         "records there (several records of one plant go to the estimators as a list)")
    if b > a:
        thinned = "" if usual == 1 else (f" (it holds one record in {usual:.0f}: {text((b - a) / usual - 1)} of "
                                         "those)")
        raise ValueError(f"{p}: column 'RECORD', the TOA5 file's record numbers, jumps {where}: {text(b - a - 1)} "
                         f"record(s) missing from the file{thinned} (overwritten in the logger's memory before they "
                         "were collected, or lines deleted), so the samples either side are no "
                         "one record at one sampling period; cut the file into two records at the gap (several "
                         "records of one plant go to the estimators as a list)")
    raise ValueError(f"{p}: column 'RECORD', the TOA5 file's record numbers, goes back {where}: samples held twice "
                     "(a collection appended again?) or the logger's table reset; delete the repeated lines, or cut "
                     "the file into two records there (several records of one plant go to the estimators as a list)")


#: Lines at one input level from which a static file is taken for a dynamic record given to load_static_csv.
_HELD_SAMPLES = 20


def load_static_csv(
    path: str | os.PathLike,
    u: str | Sequence[str],
    y: str,
    *,
    name: str | None = None,
    input_names: Sequence[str] | None = None,
    repeats: str = "error",
    delimiter: str | None = None,
    decimal: str | None = None,
    uncertainty: float | Sequence[float] | str | None = None,
    encoding: str | None = None,
    skiprows: int | None = None,
    units: tuple[str | tuple[str, ...], str] = ("", ""),
    units_row: bool | None = None,
) -> StaticPoints:
    """Measured static points (ū_i, ȳ_i) from a CSV file.

    Parameters
    ----------
    path : str or path-like
        The CSV file (header line with column names, one point per line; lines before the header
        as in :func:`load_record_csv`), or a Campbell Scientific TOA5 file, read without options
        (as in :func:`load_record_csv`).
    u : str or sequence of str
        Name of the column holding the constant input level ū, or of one column per input.
    y : str
        Name of the column holding the settled output ȳ.
    name : str, optional
        Name of the points (default: the file name without extension).
    input_names : sequence of str, optional
        Names of the inputs (as in :func:`load_record_csv`).
    repeats : {"error", "mean"}
        Lines with the same ū: an error naming them (default: a steady state is one number per
        input level), or their mean, one point per level (:meth:`StaticPoints.from_repeats`).
    delimiter : str, optional
        The column delimiter (as in :func:`load_record_csv`; detected by default).
    decimal : {".", ","}, optional
        The decimal mark (as in :func:`load_record_csv`; detected by default).
    uncertainty : float, sequence of float or str, optional
        δ, how far each ȳ may lie from the true steady state (output units; one number, one per
        line of the file, or the name of the column holding each line's δ, read as the other
        columns are; with ``repeats="mean"`` averaged per level as ȳ is), carried on the points:
        D_SF's band and :class:`~graybox.StaticBand`'s half-widths then follow from it. Default:
        none (bands must be given).
    encoding : str, optional
        The text encoding (as in :func:`load_record_csv`; UTF-8, or UTF-16/32 by their byte-order
        mark, by default).
    skiprows : int, optional
        Lines before the column names that are not read (as in :func:`load_record_csv`; default 0,
        1 for a TOA5 file).
    units : tuple
        Units of (ū, ȳ), as a :class:`~graybox.Record`'s (the inputs' one str, or one per input): shown
        (plots label their axes with them) and checked against the records' and a model's; default none said.
    units_row : bool, optional
        The line after the column names gives each column's unit (as in :func:`load_record_csv`;
        default False, True for a TOA5 file); an
        ``uncertainty`` column's unit, if given, must be the output's (``ValueError`` otherwise, and when the
        output has none).

    Returns
    -------
    StaticPoints
        ``ubar`` of shape (M,) or (M, m), ``ybar`` of shape (M,), in file order (sorted by ū
        with ``repeats="mean"``).

    Raises
    ------
    ValueError
        Naming the file and line or column: a missing column, an empty, NaN or non-numeric cell,
        a δ ≤ 0 in the ``uncertainty`` column, or two lines with the same ū (unless
        ``repeats="mean"``); the file's faults listed in :func:`load_record_csv`.
    TypeError
        ``path``, ``u``, ``y``, ``name``, ``uncertainty``, ``delimiter``, ``decimal``, ``encoding``, ``skiprows`` or ``units`` of the wrong
        type (a column is named by a str; units are a pair of str).
    """
    p = Path(check_path(path, "path", file=True))
    if name is not None:
        check_str(name, "name")
    check_choice(repeats, "repeats", ("error", "mean"))
    skiprows = None if skiprows is None else check_int(skiprows, "skiprows", low=0)
    units = check_units(units, f"{p}")
    ucols, names = _input_columns(p, u, y, input_names)
    label = name or p.stem
    wanted = _wanted(ucols, y, uncertainty=uncertainty if isinstance(uncertainty, str) else None)
    units_row = None if units_row is None else check_bool(units_row, "units_row")
    cols = _read_columns(p, wanted, delimiter=delimiter, decimal=decimal, encoding=encoding, skiprows=skiprows,
                         units_row=units_row)
    if "_units" in cols:  # units_row=True, or a TOA5 file
        units = _units_from_row(p, units, cols["_units"], [r for r in wanted if r not in ("y", "uncertainty")], None)
        said = cols["_units"].get("uncertainty", "")
        if said and units[1] and said != units[1]:  # δ is read in the output's units: another would scale it
            raise ValueError(f"{p}: the units row gives the uncertainty column {wanted['uncertainty']!r} the unit "
                             f"{said!r}, but δ is read in the output's unit {units[1]!r}: convert the column to "
                             f"{units[1]!r}")
        if said and not units[1]:  # the output said unitless while δ, read in the output's unit, has one: was dropped
            raise ValueError(f"{p}: the units row gives the uncertainty column {wanted['uncertainty']!r} the unit "
                             f"{said!r} but the output column {wanted['y']!r} none, and δ is read in the output's "
                             f"unit: give the output's unit in the units row (or units=(..., {said!r})), or leave "
                             "the uncertainty's blank")
    ub = _inputs(cols, ucols)
    where = f"column {ucols[0]!r}" if len(ucols) == 1 else f"columns {ucols}"
    if isinstance(uncertainty, str):
        uncertainty = cols["uncertainty"]
        bad = np.flatnonzero(uncertainty <= 0)
        if bad.size:  # named here, with its line: StaticPoints would name only the value
            i = int(bad[0])
            raise ValueError(f"{p}: line {cols['_lines'][i]}, column {wanted['uncertainty']!r}: δ = "
                             f"{uncertainty[i]:g}, but an uncertainty must be > 0 (output units)")
    if repeats == "mean":
        return _in_file(p, lambda: StaticPoints.from_repeats(ub, cols["y"], name=label, input_names=names,
                                                             uncertainty=uncertainty, units=units))
    seen: dict[object, int] = {}
    for v, line in zip(ub.tolist() if ub.ndim == 1 else map(tuple, ub.tolist()), cols["_lines"].tolist()):
        if v in seen:
            level = f"{v:g}" if ub.ndim == 1 else str(v)
            times = int(np.sum(ub == v) if ub.ndim == 1 else np.sum(np.all(ub == np.array(v), axis=1)))
            if times >= _HELD_SAMPLES:  # a level held over many lines: samples of a run, whose mean is no steady state
                raise ValueError(f"{p}: {where}: {times} lines have the input level {level} (lines {seen[v]}, {line}, "
                                 "…): the file looks like a dynamic record (an input held while the output moves), "
                                 "not static points; read it with graybox.load_record_csv, and take each static "
                                 "point from a hold's settled end (averaging the whole hold mixes in its transient); "
                                 "if they are repeated readings of a steady state, repeats=\"mean\" averages them")
            raise ValueError(f"{p}: {where}: lines {seen[v]} and {line} have the same input level {level}; average "
                             "repeated measurements into one point per level (repeats=\"mean\" does it)")
        seen[v] = line
    return _in_file(p, lambda: StaticPoints(ub, cols["y"], name=label, input_names=names, uncertainty=uncertainty,
                                            units=units))


def _in_file(p: Path, make: Callable[[], StaticPoints]) -> StaticPoints:
    """``make()``, whose ``ValueError`` or ``TypeError`` (an ``uncertainty`` of one δ per line, but not as many as the
    file's lines, say) names the file: StaticPoints names only the points (``name=``, else the file's stem)."""
    try:
        return make()
    except (TypeError, ValueError) as exc:
        raise (TypeError if isinstance(exc, TypeError) else ValueError)(f"{p}: {exc}") from None


# ---------------------------------------------------------------------------
# Bundled pumping plant
# ---------------------------------------------------------------------------

def pumping_data_dir() -> Path:
    """The folder holding the bundled ``dynamic.csv`` and ``static.csv``.

    An installed package carries them as package data ``graybox/data/pumping`` (mapped from the
    repository's ``data/pumping`` by pyproject.toml); a source checkout (or an editable install)
    reads ``<repo>/data/pumping`` directly.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    FileNotFoundError
        Neither place holds the data (both named).
    """
    return bundled_data_dir("pumping", "the bundled pumping data", "graybox.datasets.pumping")


def bundled_data_dir(folder: str, what: str, module: str | None, probe: str = "dynamic.csv") -> Path:
    """The folder of a bundled data set: package data ``graybox/data/FOLDER`` of an installed
    package, else ``<repo>/data/FOLDER`` of a source checkout (the one holding the file ``probe``);
    ``FileNotFoundError`` naming both places tried, ``what`` is missing, and ``python -m MODULE``
    to regenerate it (when a module can)."""
    tried = []
    try:
        cand = Path(str(resources.files("graybox.data") / folder))
        tried.append(cand)
        if (cand / probe).is_file():
            return cand
    except ModuleNotFoundError:
        pass
    cand = Path(__file__).resolve().parents[2] / "data" / folder
    tried.append(cand)
    if (cand / probe).is_file():
        return cand
    again = f", or regenerate them with `python -m {module}`" if module else ""
    raise FileNotFoundError(f"{what} are missing; looked in {[str(t) for t in tried]}. Reinstall graybox{again}")


PUMPING_DESCRIPTION = (
    "Simulated stand-in for the hydraulic pumping plant of Barbosa, Aguirre, Martinez & Braga "
    "(IEEE TCST 2011), whose measured data are not public. The data come from a lumped physical "
    "model (graybox.datasets.pumping: drive and induction motors, two centrifugal pumps in parallel, "
    "water column inertia, Francis turbine load) calibrated to the paper's published facts: static "
    "curve eq. (1) over 750-1650 rpm, Ts = 0.05 s, 3200 identification + 800 validation samples of "
    "speed-reference steps at several operating points and sizes, a time constant that varies with "
    "the operating point (about 1.26 s at 750 rpm, 0.78 s at 1650 rpm), transmitter error +/-0.175 mlc "
    "(95 % band), plus coloured process noise and slow disturbances set off by speed changes "
    "(surge in the open return circuit, air in the pumps) sized so that black-box models miss the "
    "static curve, as in the paper's Table I. The static points are means of noisy stretches at "
    "750, 850, ..., 1650 rpm, each recorded after waiting 180 s for those disturbances to die out. "
    "It is not the paper's plant: numbers computed on it will not equal the paper's. "
    "Input: speed reference (rpm); output: pressure (mlc)."
)


def load_pumping() -> Dataset:
    """The bundled benchmark: simulated pumping-plant data (a stand-in for the paper's rig).

    Returns
    -------
    Dataset
        ``ident``: first 3200 samples, ``valid``: last 800 (Records, Ts = 0.05 s, units
        ("rpm", "mlc")); ``static``: 10 measured points at 750, 850, …, 1650 rpm, carrying
        the transmitter's error ±0.175 mlc as their ``uncertainty`` (so ``static.band`` is
        0.175² mlc², D_SF's band by its rule);
        ``description``: where the data come from (a simulated stand-in, said plainly);
        ``extra``: ``"static_curve"`` — eq. (1) as a :class:`~graybox.StaticCurve` on
        [750, 1650] rpm (the curve the plant is calibrated to), ``"plant"`` — the
        :class:`graybox.datasets.PumpingPlant` that generated the data, ``"seed"``, and
        ``"files"`` — the two CSV paths.
    """
    # imported here, not at module level, so that `python -m graybox.datasets.pumping` does not
    # import the module twice (once through this package, once as __main__)
    from .pumping import DEFAULT_SEED, DYNAMIC_COLUMNS, N_IDENT, STATIC_COLUMNS, PumpingPlant

    d = pumping_data_dir()
    t_col, u_col, y_col = DYNAMIC_COLUMNS
    rec = load_record_csv(d / "dynamic.csv", u=u_col, y=y_col, time=t_col, name="pumping",
                          units=("rpm", "mlc"))
    if len(rec) <= N_IDENT:
        raise ValueError(f"{d / 'dynamic.csv'}: {len(rec)} samples, need more than {N_IDENT} to split ident/valid")
    su, sy = STATIC_COLUMNS
    static = load_static_csv(d / "static.csv", u=su, y=sy, name="pumping static points",
                             uncertainty=PUMPING_STATIC_UNCERTAINTY, units=rec.units)
    eq1 = StaticCurve.polynomial(EQ1_COEFFICIENTS, domain=(750.0, 1650.0), name="eq. (1)")
    return Dataset(
        ident=rec.slice(0, N_IDENT, name="pumping ident"),
        valid=rec.slice(N_IDENT, None, name="pumping valid"),
        static=static,
        description=PUMPING_DESCRIPTION,
        extra={"static_curve": eq1, "plant": PumpingPlant(), "seed": DEFAULT_SEED,
               "files": (str(d / "dynamic.csv"), str(d / "static.csv"))},
    )


# ---------------------------------------------------------------------------
# Buck converter (real measurements, bundled with their MIT licence notice)
# ---------------------------------------------------------------------------

_BUCK_FILES = ("buck_id.csv", "buck_valid.csv")
#: The bundled static points' uncertainty δ (output units), carried on the loaded StaticPoints so
#: that D_SF's band and StaticBand's half-widths follow from the data: the pumping rig's pressure
#: transmitter error ±0.175 mlc (both rigs), the buck converter's half resolution 0.1 V.
PUMPING_STATIC_UNCERTAINTY = 0.175
BUCK_STATIC_UNCERTAINTY = 0.1


def find_buck_dir(path: str | os.PathLike | None = None) -> Path:
    """The folder with ``buck_id.csv`` and ``buck_valid.csv``.

    Search order: ``path`` if given; else the folder named by the environment variable
    ``GRAYBOX_BUCK_DIR`` if it is set; else the bundled copy (package data ``graybox/data/buck``,
    or ``<repo>/data/buck`` in a source checkout), which carries the data's MIT licence notice.
    Only one place is tried: a ``path`` or a variable naming a folder without the files is an
    error, never a silent fall-back to another copy.

    Parameters
    ----------
    path : str or path-like, optional
        The folder to use.

    Returns
    -------
    pathlib.Path
        The folder found.

    Raises
    ------
    FileNotFoundError
        Naming the folder tried and the files it lacks.
    """
    def check(d: Path, how: str) -> Path:
        missing = [f for f in _BUCK_FILES if not (d / f).is_file()]
        if missing:
            raise FileNotFoundError(f"{d}: expected {' and '.join(_BUCK_FILES)} in this folder ({how}); "
                                    f"missing {', '.join(missing)}")
        return d

    if path is not None:
        return check(Path(check_path(path, "path")), "given as path=")
    env = os.environ.get(BUCK_ENV)
    if env:
        return check(Path(env), f"named by {BUCK_ENV}")
    return bundled_data_dir("buck", "the bundled buck converter data", None, probe=_BUCK_FILES[0])


def load_buck(path: str | os.PathLike | None = None) -> Dataset:
    """The real DC-DC buck converter data (Aguirre et al. 2000), bundled with graybox.

    The files are those of wilsonrljr/sysidentpy-data (MIT licence, Copyright (c) 2024 Wilson
    Rocha); the licence notice ships beside them in ``graybox/data/buck``.

    Parameters
    ----------
    path : str or path-like, optional
        Folder holding ``buck_id.csv`` and ``buck_valid.csv``; default: see :func:`find_buck_dir`
        (the ``GRAYBOX_BUCK_DIR`` variable, else the bundled copy).

    Returns
    -------
    Dataset
        ``ident`` (buck_id.csv, 1001 samples) and ``valid`` (buck_valid.csv, 999 samples), Ts from
        the files' ``sampling_time`` column (1e-5 s), u = ``input`` (duty-cycle command, about
        2.2–2.5), y = ``y`` (output voltage, V). No static points were measured: ``static`` holds
        9 points *sampled from the theoretical static function* ȳ = (4 − ū)·8 at ū = 1.5, 1.75,
        …, 3.5 (mostly outside the dynamic data's input range, which is what makes them useful
        to gray-box estimation), carrying an ``uncertainty`` of 0.1 V (half the output's 0.2 V
        resolution), and ``extra["static_curve"]`` is that function as a
        :class:`~graybox.StaticCurve` (domain ū ∈ [1, 4]).
    """
    d = find_buck_dir(path)
    kw = dict(u="input", y="y", time="sampling_time", units=("", "V"))
    ident = load_record_csv(d / _BUCK_FILES[0], name="buck ident", **kw)
    valid = load_record_csv(d / _BUCK_FILES[1], name="buck valid", **kw)
    try:
        check_same_period(ident, valid)
    except ValueError as exc:
        raise ValueError(f"{d}: {exc}") from None
    ubar = np.linspace(1.5, 3.5, 9)
    static = StaticPoints(ubar, BUCK_STATIC_CURVE(ubar), name="buck theoretical static points",
                          uncertainty=BUCK_STATIC_UNCERTAINTY, units=ident.units)
    return Dataset(
        ident=ident,
        valid=valid,
        static=static,
        description=(
            "DC-DC buck converter measured in the laboratory (Aguirre, Donoso-Garcia & Santos-Filho, "
            "IEEE TCS-I 2000), files from wilsonrljr/sysidentpy-data (MIT licence). Input: duty-cycle "
            "command (about 2.2-2.5); output: voltage (V, 0.2 V resolution); Ts = 1e-5 s. No static "
            "points were measured: the static points are sampled from the converter's theoretical "
            "static function y = (4 - u)*8 (supply 24 V), which is also in extra['static_curve']."
        ),
        extra={"static_curve": BUCK_STATIC_CURVE, "folder": str(d)},
    )
