"""A log file read whole in its dialect (:mod:`mtident.io.dialect`): its lines, its rows checked, a workbook as CSV.

A row with more cells than the header is refused, and so is a header name the delimiter splits;
data lines cut short by a write, the header written again (logs joined into one file) and a last
line cut by a logger still writing are left out and said. An Excel .xlsx workbook's sheet is read
as the CSV text a logger would have written (:func:`workbook_as_csv`), so that the same dialect and
the same checks apply. The file reader (:func:`~mtident.io.logs.read_temperature_log`) takes its
lines from here, and the live follower (:class:`~mtident.io.follow.LogFollower`) the row checks.
"""

from __future__ import annotations

import codecs
import csv
import datetime
import io
import math
import re
import warnings
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from mtident.exceptions import InputError
from mtident.io.columns import check_header_names
from mtident.io.dialect import HEAD_BYTES, LINE_BREAK, CsvDialect, binary_kind, data_like, sniff_dialect

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "header_names",
    "read_csv",
    "refuse_split_name",
    "read_lines",
    "workbook_as_csv",
    "no_sheets",
]


def header_names(file: Path, sheet: str | int | None = None) -> list[str]:
    """The column names of a log, read from its head only (a live log may be large); [] while
    its header line is incomplete.

    Parameters
    ----------
    file : Path
        The log: CSV text, or an Excel .xlsx workbook (the sheet ``sheet`` names, else its first
        sheet with a table).
    sheet : str or int, optional
        A workbook's sheet, as for :func:`workbook_as_csv`; not looked at for CSV text.

    Returns
    -------
    list of str
        The names as the log's dialect reads them (a T&D logger's channel names where it gives them),
        empty names left out.

    Raises
    ------
    InputError
        A workbook that does not open, or has no sheet ``sheet``.
    """
    with file.open("rb") as handle:
        head = handle.read(HEAD_BYTES)
    if binary_kind(head) in ("xlsx", "xls"):
        head = workbook_as_csv(file, file, sheet)[1][:HEAD_BYTES]
    dialect = sniff_dialect(head)
    if dialect is None:
        return []
    return [name for name in dialect.header(_header_line(head, dialect)) if name]


def _header_line(head: bytes, dialect: CsvDialect) -> str:
    return LINE_BREAK.split(dialect.decode(head))[dialect.preamble_lines]


def read_lines(
    path: str | Path, notes: list[str] | None = None, sheet: str | int | None = None
) -> tuple[list[str], CsvDialect]:
    """A whole log file's lines from its header line on, read in its own dialect; InputError,
    naming ``path`` as given, if it is missing or no CSV.

    A row with more cells than the header is refused (:func:`_check_rows`); a last line cut short,
    without its line end (a log still being written), is left out, and said in ``notes``.

    Parameters
    ----------
    path : str or Path
        The file: CSV text in any dialect :func:`~mtident.io.dialect.sniff_dialect` tells, or an Excel .xlsx workbook.
    notes : list of str, optional
        What was left out is appended here (a cut last line), and which sheet of a workbook of
        several was read (:func:`workbook_as_csv`); not said where None.
    sheet : str or int, optional
        A workbook's sheet to read, by name or number (from 1); default: its first sheet with a table.
        Refused for CSV text.

    Returns
    -------
    lines : list of str
        The header line, the rows under it (``dialect.extra_rows``) and the data lines, without their
        line breaks (the last one empty where the file ends in one); empty for an empty file.
    dialect : CsvDialect
        How the file is written.

    Raises
    ------
    InputError
        The file is missing, binary or an .xls workbook, has no header line or two columns of one name,
        a row with more cells than the header, or text its encoding cannot read; a workbook has no sheet
        ``sheet``, or ``sheet`` is given for CSV text.
    """
    file = Path(path)
    if not file.is_file():
        msg = f"{path}: a folder, not a log file" if file.is_dir() else f"{path}: no such file"
        raise InputError(msg)
    with file.open("rb") as handle:
        head = handle.read(HEAD_BYTES)
    kind = binary_kind(head)
    data, sheet_read = None, ""
    if kind in ("xlsx", "xls"):
        sheet_read, data = workbook_as_csv(file, path, sheet, notes)
        head = data[:HEAD_BYTES]
    elif kind is not None:
        msg = f"{path}: not a text file; a log is read as CSV text (or as an Excel .xlsx workbook)"
        raise InputError(msg)
    elif sheet is not None:  # an option that would change nothing is not passed over without a word
        raise InputError(no_sheets(path, sheet))
    # the whole file fits in the head: its last line is complete even without a newline
    whole = len(head) < HEAD_BYTES
    try:
        dialect = sniff_dialect(head, whole=whole)
    except csv.Error as exc:
        msg = f"{path}: not a readable CSV file ({exc})"
        raise InputError(msg) from exc
    if dialect is None and head.strip():
        msg = f"{path}: no header line, only # comments and blank lines"
        raise InputError(msg)
    if dialect is None:  # an empty file: the reader says so
        return [], CsvDialect()
    if data is None and dialect.encoding.startswith("utf-16") and file.stat().st_size % 2:
        # a UTF-16 log still being written, cut inside its last character: its whole characters are
        # read, and the cut last line is left out below; bytes without a whole line in them are no such log
        whole_characters = file.read_bytes()[:-1]
        if dialect.complete_length(whole_characters):
            data = whole_characters
    check_header_names(dialect.header(_header_line(head, dialect)), dialect.number, path)
    text = _checked_text(file.read_bytes() if data is None else data, head, dialect, path, notes)
    return LINE_BREAK.split(text)[dialect.preamble_lines :], replace(dialect, sheet=sheet_read)


def _checked_text(data: bytes, head: bytes, dialect: CsvDialect, path: str | Path, notes: list[str] | None) -> str:
    """The file's text, its rows checked (:func:`_check_rows`) and a last line cut short left out (said
    in ``notes``); InputError for a row longer than the header, or bytes its encoding cannot read."""
    try:
        text, failed = _strictly_decoded(data, dialect.encoding), None
    except UnicodeDecodeError as exc:  # said after a row's error, which names the line to mend
        text, failed = dialect.decode(data), exc
    try:
        cut = _check_rows(text, dialect, path)
    except InputError as exc:
        if _looks_like_toml(head):
            msg = _TOML_GIVEN.format(path=path)
            raise InputError(msg) from exc
        raise
    if failed is not None:
        msg = f"{path}: not a readable CSV file ({str(failed).splitlines()[0]})"
        raise InputError(_TOML_GIVEN.format(path=path) if _looks_like_toml(head) else msg) from failed
    if cut is not None:
        if notes is not None:
            notes.append(cut)
        # up to the cut line's start: a quote it leaves open ("22,4) must not swallow the rows before it
        text = text[: max(text.rfind("\n"), text.rfind("\r")) + 1]
    return _without_stray_rows(text, dialect, notes)


def _without_stray_rows(text: str, dialect: CsvDialect, notes: list[str] | None) -> str:
    """The text without its data lines cut short (:func:`rows_cut_short`) or repeating the header
    (two logs joined: its time name read as a time made the whole column fail at its first row),
    said in ``notes``."""
    lines = LINE_BREAK.split(text)
    short = set(rows_cut_short(lines, dialect, dialect.head_lines))
    header_line = lines[dialect.preamble_lines]
    header = dialect.cells(header_line)
    # a cheap first look (the text before the first delimiter), cells read only where it matches
    lead = header_line.split(dialect.delimiter, 1)[0].strip()
    repeats = {
        n
        for n, line in enumerate(lines)
        if n >= dialect.head_lines
        and line.split(dialect.delimiter, 1)[0].strip() == lead
        and dialect.cells(line) == header
    }
    if not short and not repeats:
        return text
    if notes is not None:
        notes.extend(f"left out line {n + 1}, {cut_short_words(lines[n], dialect)}" for n in sorted(short))
        if repeats:
            where = ", ".join(str(n + 1) for n in sorted(repeats))
            notes.append(f"left out line(s) {where}: the header again (logs joined into one file?)")
    return "\n".join(line for n, line in enumerate(lines) if n not in short | repeats)


def header_again_words(path: str | Path, where: str, columns: str = "other columns (") -> str:
    """A header written again with other columns than the first's, refused by every reader, in words.

    Parameters
    ----------
    path : str or Path
        The log.
    where : str
        Its line or row ("line 202").
    columns : str, optional
        What its columns are, up to the question that follows ("more columns (time_min, A, B; ").

    Returns
    -------
    str
    """
    return (
        f"{path}: {where} is a header written again with {columns}a logger restarted or reconfigured?): the rows "
        "after it belong under its names, not the first header's; split the log there (watch refuses it too)"
    )


def rows_cut_short(lines: list[str], dialect: CsvDialect, first: int = 0) -> list[int]:
    """The indices of the data lines (from ``first`` on) with fewer cells than the lines before and
    after them: a write cut short inside the log (``150,27.829,2`` between rows of five cells, its
    last reading ``2`` a cut ``25.0..``, was read as T2 = 2 °C and trusted). A logger that leaves out
    a last empty column does so on every row, and its rows stay.

    Parameters
    ----------
    lines : list of str
        The log's lines, without their line breaks.
    dialect : CsvDialect
    first : int, optional
        The index of the first data line.

    Returns
    -------
    list of int
    """
    # delimiters counted first (one pass of str.count), cells read only where a line is short
    data = [(n, line.count(dialect.delimiter)) for n, line in enumerate(lines) if n >= first and line.strip()]
    return [
        n
        for (b, before), (n, row), (a, after) in zip(data, data[1:], data[2:], strict=False)
        if row < min(before, after)
        and len(dialect.cells(lines[n])) < min(len(dialect.cells(lines[b])), len(dialect.cells(lines[a])))
    ]


def cut_short_words(line: str, dialect: CsvDialect) -> str:
    """A line cut short (:func:`rows_cut_short`) and why it is left out, in words."""
    quoted = repr(line if len(line) <= _QUOTED_LINE else line[:_QUOTED_LINE] + "...")
    return (
        f"{quoted}: it has {len(dialect.cells(line))} cells where the lines around it have more (a write cut "
        "short; its last reading may be cut too)"
    )


def _strictly_decoded(data: bytes, encoding: str) -> str:
    """Bytes as text in ``encoding``; UnicodeDecodeError where they are not, read as a stream is (a
    character cut at the end is named at its own position)."""
    decoder = codecs.getincrementaldecoder(encoding)()
    return (decoder.decode(data) + decoder.decode(b"", final=True)).removeprefix("\ufeff")


def read_csv(path: str | Path, notes: list[str] | None = None) -> tuple[pd.DataFrame, CsvDialect]:
    """A whole CSV file as a DataFrame, read in its own dialect (:func:`read_lines`, whose checks
    it makes); InputError, naming ``path`` as given, if it is missing or no CSV.

    An empty column without a name (a delimiter at the end of every line) is dropped.

    Parameters
    ----------
    path, notes
        As for :func:`read_lines`.

    Returns
    -------
    frame : pandas.DataFrame
        The data rows under the header (preamble and units or description rows skipped), cells parsed
        by pandas with the dialect's delimiter and decimal mark.
    dialect : CsvDialect
        How the file is written.

    Raises
    ------
    InputError
        As :func:`read_lines`, and where pandas cannot parse the file.
    """
    import pandas as pd

    lines, dialect = read_lines(path, notes)
    try:
        with warnings.catch_warnings():
            # cells past the header's are empty (_check_rows refused any other): nothing is lost
            warnings.filterwarnings("ignore", "Length of header or names does not match", pd.errors.ParserWarning)
            frame = pd.read_csv(
                io.StringIO("\n".join(lines)),
                sep=dialect.delimiter,
                decimal=dialect.decimal,
                # a units row under the header
                skiprows=list(range(1, 1 + dialect.extra_rows)),
                skipinitialspace=True,
                # a delimiter at the end of the data rows alone: the first column stays the time, not an index
                index_col=False,
            )
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        msg = f"{path}: not a readable CSV file ({str(exc).splitlines()[0]})"
        raise InputError(msg) from exc
    if dialect.names:  # by position: pandas has renamed a repeated name ("Date/Time.1"), left as it is
        new = dict(enumerate(dialect.names))
        frame.columns = [
            new[i] if i in new and new[i] != dialect.written_names[i] else c for i, c in enumerate(frame.columns)
        ]
    unnamed = [c for c in frame.columns if str(c).startswith("Unnamed: ") and frame[c].isna().all()]
    return frame.drop(columns=unnamed), dialect


def refuse_split_name(header_line: str, widest: int, delimiter: str, path: str | Path) -> None:
    """Refuse a header whose name holds the delimiter, unquoted, where no row has as many cells as
    the header: ``T (PT100, ch 3)`` split in two moved every later name one column left (the room's
    readings under ``ch 3)``, the room's own name left with none). Only a name whose brackets the
    split leaves open is taken as split; a header whose last names have no cells (an event column)
    stays readable.

    Parameters
    ----------
    header_line : str
        The header as written.
    widest : int
        The most cells of any data row (0: no rows yet).
    delimiter : str
        The log's delimiter.
    path : str or Path
        The log, as the message names it.

    Raises
    ------
    InputError
        Where a name is split so.
    """
    header = next(csv.reader([header_line], delimiter=delimiter), [])
    extra = len(header) - widest
    if widest == 0 or extra <= 0:
        return
    for i, name in enumerate(header[:widest]):
        if _open_brackets(name) <= 0:
            continue
        joined = delimiter.join(header[i : i + extra + 1]).strip()
        if _open_brackets(joined) != 0:
            continue
        msg = (
            f"{path}: the header has {len(header)} names and its data rows no more than {widest} cells: the name "
            f"{joined!r} holds the delimiter {delimiter!r}, which splits it, and every later name would stand over "
            f"the wrong column's readings; put that name in double quotes in the header "
            f'("{joined}") or write it without {delimiter!r}'
        )
        raise InputError(msg)


def _open_brackets(text: str) -> int:
    return sum(text.count(a) - text.count(b) for a, b in ("()", "[]", "{}"))


_TOML_GIVEN = "{path}: a TOML file (name = value lines), not a CSV file of readings; give the CSV log here"
# a line quoted in a message is cut to this many characters
_QUOTED_LINE = 80
_INTEGER = re.compile(r"^[+-]?\d+$")


def _check_rows(text: str, dialect: CsvDialect, path: str | Path) -> str | None:
    """Refuse a data row with more cells than the header where the cells past it hold something:
    pandas read such a file with each row's first cells under the header's names and dropped the
    rest (a comma-separated export with decimal commas: one sensor's integer parts read as its
    readings, the next sensor's decimal parts as the next one's). Returns a note on a last line
    cut short (no line end, fewer cells than the line before it: a log still being written, which
    :class:`~mtident.io.follow.LogFollower` waits for), which the reader leaves out; None if none.
    A last line without its line end is cut short too where its last cell is (:func:`_cut_short`):
    ``...;29,3`` for ``...;29,35``, or ``2`` for ``22,41``, was read as a reading, wrong and trusted."""
    lines = LINE_BREAK.split(text)
    header = dialect.cells(lines[dialect.preamble_lines])
    count = len(header)
    previous = count
    rows = csv.reader(lines[dialect.head_lines :], delimiter=dialect.delimiter)
    last: list[str] = []
    before: list[str] = []
    widest = 0
    for row in rows:
        if not row:
            continue
        widest = max(widest, len(row))
        if len(row) > count and any(cell.strip() for cell in row[count:]):
            number = dialect.head_lines + rows.line_num
            line = lines[number - 1]
            if row[0].strip() and row[0].strip() == header[0].strip():
                raise InputError(header_again_words(path, f"line {number}", f"more columns ({', '.join(row)}; "))
            quoted = repr(line if len(line) <= _QUOTED_LINE else line[:_QUOTED_LINE] + "...")
            msg = (
                f"{path}: line {number} has {len(row)} cells where the header has {count} ({', '.join(header)}): "
                f"{quoted}; a row's readings would land under the wrong names"
            )
            readings = [cell.strip() for cell in row[1:] if cell.strip()]
            if dialect.delimiter == "," and len(readings) >= 2 and all(_INTEGER.match(cell) for cell in readings):
                msg += (
                    f" (likely decimal commas in a comma-separated file: '{readings[0]},{readings[1]}' is one "
                    "reading split in two); export it with ';' or tabs between the cells, or with a decimal point"
                )
            raise InputError(msg)
        previous, last, before = len(last) or previous, row, last
    refuse_split_name(lines[dialect.preamble_lines], widest, dialect.delimiter, path)
    ended = text.endswith(("\n", "\r"))
    if ended or not lines[-1].strip() or len(lines) <= dialect.head_lines:
        return None
    line = lines[-1]
    quoted = repr(line if len(line) <= _QUOTED_LINE else line[:_QUOTED_LINE] + "...")
    # fewer cells than the header too: a row that leaves out the header's last column (a logger's
    # event column) or a trailing delimiter is whole
    if len(last) >= min(previous, count):
        k = len(last) - 1
        if not (before and k < len(before) and _cut_short(last[k], before[k], dialect.decimal)):
            return None
        return (
            f"left out the last line, {quoted}: it has no line end and its last cell {last[k].strip()!r} is shorter "
            f"than the one above it, {before[k].strip()!r} (a log still being written, cut in a reading; "
            "`thermal watch` follows it as it grows)"
        )
    return (
        f"left out the last line, {quoted}: it has no line end and {len(last)} of the {previous} cells of the line "
        "before it (a log still being written; `thermal watch` follows it as it grows)"
    )


def _cut_short(cell: str, above: str, decimal: str) -> bool:
    """Whether the last cell of a last line without its line end looks cut short against the cell
    above it (the same column, the row before): empty where that one is not, without the decimal mark
    that one has or fewer characters after it (``29,3`` under ``29,35``, ``2`` under ``22,41``), or,
    where that one has no decimal mark, fewer characters (``2`` under ``22``). A whole row whose last
    reading merely writes fewer decimals (%g-style numbers, 22.4 after 22.41) is left out too, and said:
    a reading lost, where the other way a wrong one was trusted."""
    cell, above = cell.strip(), above.strip()
    if not above:
        return False
    if not cell:
        return True
    if decimal in above:
        return decimal not in cell or len(cell) - cell.rindex(decimal) < len(above) - above.rindex(decimal)
    return len(cell) < len(above)


def workbook_as_csv(
    file: Path, path: str | Path, sheet: str | int | None = None, notes: list[str] | None = None
) -> tuple[str, bytes]:
    """A sheet of an Excel workbook as the CSV text a logger would have written, so that it is read
    like one: preamble, header, units row, time stamps and all. The sheet is the one ``sheet``
    names, else the first that holds a table (rows that begin like data rows; a logger's "Details"
    sheet before its data is passed over). Where the workbook has other sheets with something in
    them and none was named, ``notes`` is told which sheet was read, the others and how to pick one:
    readings on a later sheet were read from the first without a word.

    Parameters
    ----------
    file : Path
        The workbook (.xlsx).
    path : str or Path
        Its name as the user gave it, for the messages.
    sheet : str or int, optional
        The sheet to read: its name (case aside), or its number from 1 as Excel's tabs are counted
        (a string of digits that is no sheet's name is a number too).
    notes : list of str, optional
        Which sheet was read, where the workbook has several and ``sheet`` is None, is appended here.

    Returns
    -------
    name : str
        The sheet read, where the workbook has more than one (to name it beside the file); else "".
    text : bytes
        UTF-8 CSV text; dates and times of day as ISO 8601 text, empty cells empty.

    Raises
    ------
    InputError
        An old .xls workbook, one that does not open, or no sheet ``sheet`` (the message names the
        sheets there are).
    """
    import pandas as pd

    with file.open("rb") as handle:
        old_format = binary_kind(handle.read(8)) == "xls"
    if old_format:
        msg = f"{path}: an Excel 97-2003 workbook (.xls); save it as .xlsx or as CSV"
        raise InputError(msg)
    try:
        sheets = pd.read_excel(file, sheet_name=None, header=None, dtype=object)
    except Exception as exc:  # openpyxl raises many kinds for a damaged or foreign zip
        msg = (
            f"{path}: not a readable Excel workbook ({type(exc).__name__}: "
            f"{str(exc).splitlines()[0] if str(exc) else ''})"
        )
        raise InputError(msg) from exc

    def cell(value: object) -> str:
        if value is None or (isinstance(value, float) and math.isnan(value)) or value is pd.NaT:
            return ""
        if isinstance(value, (datetime.datetime, datetime.time)):
            return value.isoformat(sep=" ") if isinstance(value, datetime.datetime) else value.isoformat()
        return repr(value) if isinstance(value, float) else str(value)

    def text(sheet: pd.DataFrame) -> str:
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        for row in sheet.itertuples(index=False):
            writer.writerow([cell(v) for v in row])
        return out.getvalue()

    texts = {str(name): text(frame) for name, frame in sheets.items()}
    tables = [name for name, t in texts.items() if sum(data_like(line) for line in t.splitlines()[:200]) >= 2]
    if sheet is not None:
        name = _named_sheet(list(texts), sheet, path)
        if tables and name not in tables:
            # a sheet of a logger's details read as a log is refused for what it is, not for being short
            msg = (
                f"{path}: sheet {name!r} holds no table of readings (no rows that begin like data rows); the sheets "
                f"that do: {_sheet_list(tables)}"
            )
            raise InputError(msg)
        if notes is not None and name.strip().casefold() != str(sheet).strip().casefold() and len(texts) > 1:
            # a number counts Excel's tabs from 1, where pandas counts from 0: the sheet read is said
            notes.append(f"{path}: read sheet {name!r}, number {str(sheet).strip()} of {len(texts)} (counted from 1)")
        return (name if len(texts) > 1 else ""), texts[name].encode()
    read = (tables or list(texts) or [""])[0]
    if notes is not None and any(t.strip(", \n") for name, t in texts.items() if name != read):
        notes.append(_sheet_note(path, read, texts, tables))
    return (read if len(texts) > 1 else ""), texts.get(read, "").encode()


def no_sheets(path: str | Path, sheet: str | int) -> str:
    """The message for a sheet named for a log that is CSV text, which has none.

    Parameters
    ----------
    path : str or Path
        The log, as the user gave it.
    sheet : str or int
        The sheet named.

    Returns
    -------
    str
    """
    return f"{path}: `sheet='{sheet}'` names a sheet of an Excel workbook, but this log is CSV text; leave it out"


_SHEETS_LISTED = 12
"""The most sheets a message lists by name (a workbook of a sheet per day has dozens)."""


def _sheet_list(names: list[str], said: Callable[[str], str] = repr) -> str:
    """Sheets for a message, at most :data:`_SHEETS_LISTED` of them, then how many more."""
    listed = [said(name) for name in names[:_SHEETS_LISTED]]
    more = len(names) - len(listed)
    return ", ".join(listed) + (f" and {more} more" if more else "")


def _named_sheet(names: list[str], sheet: str | int, path: str | Path) -> str:
    """The name of the sheet ``sheet`` names (:func:`workbook_as_csv`); InputError naming the sheets
    there are where none is."""
    number: int | None
    wanted = str(sheet).strip()
    if isinstance(sheet, str):
        # Excel keeps sheet names unique regardless of case
        same = [n for n in names if n == wanted] or [n for n in names if n.strip().casefold() == wanted.casefold()]
        if same:
            return same[0]
        number = int(wanted) if wanted.isdecimal() else None
    else:
        number = int(sheet)
    if number is not None and 1 <= number <= len(names):
        return names[number - 1]
    numbered = _sheet_list(names, lambda n: f"{names.index(n) + 1} {n!r}")
    which = f"no sheet {wanted!r}" if number is None else f"no sheet number {number} (counted from 1)"
    msg = (
        f"{path}: {which}; the workbook's sheets: {numbered} (`sheet='NAME'` takes a sheet's name or its number, "
        "from 1)"
    )
    raise InputError(msg)


def _sheet_note(path: str | Path, read: str, texts: dict[str, str], tables: list[str]) -> str:
    """What a reader says of a workbook of several sheets when none was named: the sheet read, the
    others, and how to read another."""
    why = "the first that holds a table" if tables else "none holds a table: the first"

    def other(name: str) -> str:
        what = "a table too" if name in tables else "no table" if texts[name].strip(", \n") else "empty"
        return f"{name!r} ({what})"

    others = _sheet_list([name for name in texts if name != read], other)
    return (
        f"{path}: read sheet {read!r} of {len(texts)} ({why}); not read: {others}; `sheet='NAME'` reads another "
        "(its name, or its number from 1)"
    )


def _looks_like_toml(head: bytes) -> bool:
    """Whether most of the lines that are not comments are ``name = value`` (a parameter file given
    where a log belongs)."""
    lines = [line.strip() for line in head.decode("utf-8", "replace").splitlines()]
    lines = [line for line in lines if line and not line.startswith("#")]
    assigned = [line for line in lines if re.match(r"^[A-Za-z_][\w.-]*\s*=", line)]
    return len(lines) > 0 and len(assigned) >= 0.8 * len(lines)
