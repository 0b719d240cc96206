"""How a data-acquisition program wrote its CSV: delimiter, decimal mark, preamble, encoding, the rows under its header.

Loggers differ. European ones write ``;`` between cells and a decimal comma
(``17,90``); many write a preamble (device, channel setup), as ``#`` lines or
as plain lines, before the header; Windows programs write cp1252, where ``°`` is
the single byte 0xB0 that UTF-8 refuses, Japanese ones Shift-JIS, Excel's
"Unicode text" UTF-16; a trailing delimiter leaves an empty last column; many
write rows between the header and the data: a row of units (``min;°C;°C``,
``[s],[K]``), which states the time unit and the temperature scale
(:mod:`mtident.io.units`), a second row of names, a description of each channel,
section tags. Both readers of a log (the whole file,
:func:`~mtident.io.logs.read_temperature_log`, and the live follower,
:class:`~mtident.io.follow.LogFollower`) take the dialect from the file's head
here, so they read a log the same way; the time stamps are read in
:mod:`mtident.io.stamps`, and what each column is, is decided in
:mod:`mtident.io.columns`; the whole file is read in its dialect, its rows checked, in
:mod:`mtident.io.log_file`.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass, replace

from mtident.io.columns import event_named
from mtident.io.units import (
    carried_unit,
    is_from_humidity,
    is_humidity,
    is_number,
    is_time_or_temperature_unit,
    number_without_unit,
    time_unit_name,
    unit_in_name,
)

__all__ = [
    "CsvDialect",
    "sniff_dialect",
    "binary_kind",
    "HEAD_BYTES",
]

# enough for a preamble, the header and a few rows
HEAD_BYTES = 65536
_DELIMITERS = (",", ";", "\t")
# Excel's first line "sep=;" states the delimiter
_SEP_DIRECTIVE = re.compile(r"^sep=(.)\r?$")
# a header whose first column, the row counter, is named "#" (HOBOware: #,"Date Time, GMT+01:00",...): no comment
_HASH_HEADER = re.compile(r'^\s*"?#"?\s*[,;\t]')
# a time column's unit in words at the end of its name
_TIME_WORDS = frozenset(
    ("milliseconds", "seconds", "second", "secs", "sec", "minutes", "minute", "mins", "hours", "hour", "hrs", "days")
)
# Line ends as pandas reads them: CRLF (Windows), LF, and a lone CR (old Macs, some instruments'
# serial loggers), which inside a line made the csv module fail with a traceback.
LINE_BREAK = re.compile(r"\r\n|\r|\n")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+(?:[eE][+-]?\d+)?\s*$")
_DECIMAL_POINT = re.compile(r"^\s*[+-]?\d*\.\d+(?:[eE][+-]?\d+)?\s*$")
# 1,500: a thousands' grouping as much as a decimal comma
_THOUSANDS = re.compile(r"^\s*[+-]?\d{1,3}(?:,\d{3})+\s*$")


@dataclass(frozen=True, slots=True)
class CsvDialect:
    """How one log file is written.

    Attributes
    ----------
    delimiter : {",", ";", "\\t"}
    decimal : {".", ","}
    preamble_lines : int
        Lines before the header: ``#`` comments, blank lines, Excel's ``sep=;``, a
        logger's settings written before its table.
    encoding : {"utf-8-sig", "cp1252", "cp932", "utf-16-le", "utf-16-be"}
        UTF-8 (a byte-order mark is skipped), Windows' cp1252 where UTF-8 fails,
        Shift-JIS (cp932) where both fail, or UTF-16 (Excel's "Unicode text"),
        told by its byte-order mark.
    units : tuple of (str, str)
        Each column's unit as the log states it under the header: in a units row
        (``min;°C;°C``), in the readings' cells (``13.1 °C``), or as a humidity in a
        logger's description rows; empty if it states none.
    extra_rows : int
        Lines between the header and the first data row: a units row, a second
        row of names, a logger's description of each channel (serial number,
        type, property), an empty row or a section tag (``[#D]``).
    units_source : str
        Where ``units`` come from, for messages: "the units row", "its cells",
        "the rows under the header".
    units_in_cells : bool
        The readings carry their unit (``13.1 °C``, ``56.3 %RH``), taken off when read.
    names : tuple of str
        The columns' names where the header numbers the channels (``No.3``) and the row
        under it names them (``Spindle``), as a T&D logger writes the names a user gave;
        empty where the header's own names stand.
    sheet : str
        The sheet of an Excel workbook of several that the text comes from ("" for CSV text, or a
        workbook of one sheet): messages name it beside the file.
    """

    delimiter: str = ","
    decimal: str = "."
    preamble_lines: int = 0
    encoding: str = "utf-8-sig"
    # (column name, unit) from under the header; () if the log states none there
    units: tuple[tuple[str, str], ...] = ()
    extra_rows: int = 0
    units_source: str = "the units row"
    units_in_cells: bool = False
    # the columns' names where a second row of names under the header names the channels (T&D:
    # "No.3" in the header, "Spindle" under it); () where the header's names stand
    names: tuple[str, ...] = ()
    written_names: tuple[str, ...] = ()  # the header's own names, where ``names`` replace them
    # columns the rows under the header describe as computed from the humidity ("Property: Dew Point")
    from_humidity: tuple[str, ...] = ()
    sheet: str = ""

    def cells(self, line: str) -> list[str]:
        """The cells of one line (a header), stripped; quotes removed.

        Parameters
        ----------
        line : str
            One line of the log as text, without its line break.

        Returns
        -------
        list of str
            The cells split at the dialect's delimiter; empty for an empty line.
        """
        return [cell.strip() for cell in next(csv.reader([line], delimiter=self.delimiter), [])]

    def header(self, line: str) -> list[str]:
        """The columns' names: the header line's cells, or the channels' names under it (``names``).

        Parameters
        ----------
        line : str
            The log's header line as text (the line after the preamble), without its line break.

        Returns
        -------
        list of str
            One name per column, as the log's readers name them.
        """
        return list(self.names) or self.cells(line)

    def renaming(self) -> str | None:
        """A note on the channels named by the row under the header, if any."""
        if not self.names:
            return None
        pairs = [f"{old} is {new!r}" for old, new in zip(self.written_names, self.names, strict=False) if old != new]
        return f"channels named by the row under the header: {', '.join(pairs)}"

    def number(self, cell: str) -> float:
        """A cell as a float under this decimal mark (a unit after it taken off where the log
        writes one there); ValueError if it is none.

        Parameters
        ----------
        cell : str
            One cell of a data row as written ("17,90" under a decimal comma, "13.1 °C" where the readings
            carry their unit).

        Returns
        -------
        float
            The cell's value.
        """
        if self.units_in_cells:
            cell = number_without_unit(cell)
        return float(cell.replace(",", ".") if self.decimal == "," else cell)

    def decode(self, data: bytes) -> str:
        """Bytes of the log, read from a line's start, as text (a byte-order mark dropped).

        Parameters
        ----------
        data : bytes
            Bytes of the log in its ``encoding``, beginning at the start of a line.

        Returns
        -------
        str
            The text; bytes the encoding cannot read are replaced by U+FFFD.
        """
        return data.decode(self.encoding, errors="replace").removeprefix("\ufeff")

    def complete_length(self, data: bytes) -> int:
        """How many bytes of ``data`` (read from a line's start) are complete lines: up to the last
        LF, or where there is none, the last CR (a log whose lines end in a lone CR; a CRLF cut
        after its CR has its line's cells all the same, and the LF is then an empty line).

        Parameters
        ----------
        data : bytes
            Bytes of the log in its ``encoding``, beginning at the start of a line; the last line may be
            incomplete (a live log being written).

        Returns
        -------
        int
            The number of bytes up to and including the last line break; 0 where no line is complete.
        """
        for mark in ("\n", "\r"):
            newline = mark.encode(self.encoding.removesuffix("-sig"))
            end = len(data)
            while (at := data.rfind(newline, 0, end)) >= 0:
                if at % len(newline) == 0:  # UTF-16: a newline's two bytes, not the halves of two characters
                    return at + len(newline)
                end = at + len(newline) - 1
        return 0

    @property
    def head_lines(self) -> int:
        """Lines before the first data row: the preamble, the header and the rows under it."""
        return self.preamble_lines + 1 + self.extra_rows

    def unit_of(self, column: str) -> str:
        """The column's unit as the log states it under the header, else as its name ends
        ("Time [s]", "T1 (°F)": a unit this module knows only); "" without one.

        Parameters
        ----------
        column : str
            The column's name, as :meth:`header` gives it.

        Returns
        -------
        str
            The unit as written ("min", "°C", "[s]", "%RH"), "s" for LabVIEW's "X_Value", or "".
        """
        stated = dict(self.units).get(column, "")
        if stated.strip():
            return stated
        if column == "X_Value":  # LabVIEW's measurement files (.lvm) give their x axis in seconds
            return "s"
        return unit_in_name(column)

    def time_unit(self, column: str) -> str | None:
        """ "ms", "s", "min", "h" or "d" if the units row or the time column's name states its
        unit, else None. A time column's name may be its unit in words ("Seconds", "Elapsed
        hours", "Time in minutes": read as minutes before, a 6-h test lasted 6 min); a sensor's
        may not ("T min" is a lowest temperature).

        Parameters
        ----------
        column : str
            The time column's name, as :meth:`header` gives it.

        Returns
        -------
        str or None
            The key of the unit in ``logs.TIME_UNITS`` ("ms", "s", "min", "h" or "d"), or None where the
            log states none.
        """
        stated = time_unit_name(self.unit_of(column))
        words = column.split()
        if stated is None and words and words[-1].lower() in _TIME_WORDS:
            return time_unit_name(words[-1])
        return stated


def sniff_dialect(head: bytes, wait_for_row: bool = False, whole: bool = False) -> CsvDialect | None:
    """The dialect of a log from its first bytes; None while its header line is incomplete
    (with ``wait_for_row``, a live log's: until its first data row is complete). ``whole``: the
    head is the whole file, its last line complete without a newline.

    The delimiter is the one an Excel ``sep=`` line states, else the candidate
    that splits the header line into the most cells and the data rows into as
    many (a header has no decimal commas, so ``;`` against ``,`` is clear there,
    where csv.Sniffer, looking at data rows, would take the decimal comma for the
    delimiter). A decimal comma is assumed when the delimiter is not a comma and a
    data cell reads like ``17,90`` or ``1,5e-05``. The header is the first line
    that is no comment, or, where the lines after it do not continue its table,
    the line that heads the table below (:func:`_table_start`).

    Parameters
    ----------
    head : bytes
        The file's first bytes as the readers take them (``HEAD_BYTES``, 64 KiB, or less of a short
        file), in any of the encodings a log may have.
    wait_for_row : bool, optional
        A live log: return None until the first data row after the header is complete too.
    whole : bool, optional
        ``head`` is the whole file: its last line counts as complete without a newline.

    Returns
    -------
    CsvDialect or None
        How the log is written, or None while the header line (or, with ``wait_for_row``, the first
        data row) is incomplete, or where there are only comments and blank lines.
    """
    text, encoding = _decoded_head(head)
    if not whole:
        # A CRLF cut between its CR and its LF: the line is not complete yet (the follower reads up
        # to the last LF where there is one; a row taken as complete here was not there to tell the
        # time's columns). A log of lone CRs waits a row longer for it.
        text = text.removesuffix("\r")
    lines = LINE_BREAK.split(text)
    complete = lines if whole else lines[:-1]  # the last piece has no newline yet
    preamble, stated = 0, None
    while preamble < len(complete):
        line = complete[preamble]
        directive = _SEP_DIRECTIVE.match(line)
        if directive and directive.group(1) in _DELIMITERS:
            stated = directive.group(1)
        elif line.strip() and (not line.lstrip().startswith("#") or _HASH_HEADER.match(line)):
            break
        preamble += 1
    table_start = _table_start(complete, preamble, stated, wait_for_row)
    if table_start is None:  # a live log's settings written, its table not yet
        return None
    preamble = table_start
    if preamble + wait_for_row >= len(complete):
        return None
    header = complete[preamble]
    delimiter = stated or _delimiter(header, complete[preamble + 1 : preamble + 21])
    decimal = "."
    if delimiter != ",":
        rows = csv.reader(
            complete[preamble + 1 : preamble + 21], delimiter=delimiter
        )  # "17,90" quoted, as spreadsheets write it
        if any(_DECIMAL_COMMA.match(number_without_unit(cell)) for row in rows for cell in row):  # also "20,5 °C"
            decimal = ","
    elif _quoted_decimal_commas(complete[preamble + 1 : preamble + 21]):
        decimal = ","
    dialect = _stated_units(CsvDialect(delimiter, decimal, preamble, encoding), complete)
    if wait_for_row and preamble + 1 + dialect.extra_rows >= len(complete):
        # A live log's header comes before its rows; the delimiter (a tie in the header) and the
        # decimal mark are told by a data row: sniffed from the header alone, a decimal-comma log
        # read every reading as NaN.
        return None
    return dialect


def _quoted_decimal_commas(rows: list[str]) -> bool:
    """Whether comma-separated rows write their numbers with decimal commas, quoted (``"0,5","22,41"``,
    as a spreadsheet in a decimal-comma locale writes them): a cell holds a decimal comma that is no
    thousands' grouping (``1,500``), and no cell a decimal point. Such a log was refused, each reading
    "not a number"."""
    cells = [number_without_unit(cell) for row in csv.reader(rows, delimiter=",") for cell in row]
    commas = [cell for cell in cells if _DECIMAL_COMMA.match(cell)]
    return any(not _THOUSANDS.match(cell) for cell in commas) and not any(_DECIMAL_POINT.match(cell) for cell in cells)


def _stated_units(dialect: CsvDialect, lines: list[str]) -> CsvDialect:
    """The dialect with the rows between its header and its first data row, and the units they
    state: a units row's, a humidity named in a description row ("Property: Humidity"), or the
    units the first data row's readings carry (``13.1 °C``)."""
    k = dialect.preamble_lines
    extra = _extra_rows(lines, k, dialect.delimiter) or 0
    written = header = dialect.cells(lines[k])
    names = _channel_names(header, dialect.cells(lines[k + 1])) if extra else None
    header = names or header
    units: dict[str, str] = {}
    source = "the units row"
    from_humidity: list[str] = []
    for line in lines[k + 1 : k + 1 + extra]:
        cells = dialect.cells(line)
        from_humidity += [
            name
            for name, cell in zip(header, cells, strict=False)
            if is_from_humidity(cell) and name not in from_humidity
        ]
        if not units and _is_units_row(cells, dialect):
            units, source = {name: unit for name, unit in zip(header, cells, strict=False) if unit}, "the units row"
        elif not units:
            named = {name: "%RH" for name, cell in zip(header, cells, strict=False) if is_humidity(cell)}
            units, source = named, "the rows under the header"
    in_cells = False
    if k + 1 + extra < len(lines):
        carried = {
            name: unit
            for name, cell in zip(header, dialect.cells(lines[k + 1 + extra]), strict=False)
            if (unit := carried_unit(cell))
        }
        in_cells = bool(carried)
        if carried:  # the readings' own units say most
            units, source = {**units, **carried}, "its cells"
    return replace(
        dialect,
        units=tuple(units.items()),
        extra_rows=extra,
        units_source=source,
        units_in_cells=in_cells,
        names=tuple(names or ()),
        written_names=tuple(written) if names else (),
        from_humidity=tuple(from_humidity),
    )


# a channel's number as a header gives it: "No.3", "CH3", "Channel 3", "3"
_NUMBERED = re.compile(r"(?:no\.?|ch\.?|channel|kanal)?\s*\d+", re.IGNORECASE)


def _channel_names(header: list[str], below: list[str]) -> list[str] | None:
    """The header's names with each numbered channel ("No.3") named as the row under it names it
    ("Spindle"), where that row is a row of names (no number, no unit) that names one at least
    and leaves every name distinct; None otherwise."""
    if any(is_number(c) for c in below if c) or any(is_time_or_temperature_unit(c) for c in below if c):
        return None
    names = [
        b if _NUMBERED.fullmatch(h) and b and not _NUMBERED.fullmatch(b) else h
        for h, b in zip(header, [*below, *[""] * len(header)], strict=False)
    ]
    renamed = [i for i, (n, h) in enumerate(zip(names, header, strict=True)) if n != h]
    # a new name must name one column only (the header's own repeats, T&D's "Date/Time" twice, stay)
    if not renamed or any(names.count(names[i]) > 1 for i in renamed):
        return None
    return names


def _decoded_head(head: bytes) -> tuple[str, str]:
    """The head as text, and its encoding: UTF-16 by its byte-order mark (Excel's "Unicode
    text", Windows programs) or by a zero byte in every other place, else UTF-8, else cp1252
    (Windows in Europe and America), else Shift-JIS (cp932: Japanese loggers; it uses bytes that
    cp1252 leaves undefined), else cp1252 with the undefined bytes replaced."""
    utf16 = _utf16(head)
    if utf16 is not None:
        return head[: len(head) // 2 * 2].decode(utf16, errors="replace").removeprefix("\ufeff"), utf16
    for encoding in ("utf-8-sig", "cp1252", "cp932"):
        try:
            return head.decode(encoding), encoding
        except UnicodeDecodeError as exc:
            # a multi-byte character cut off at the end of the head is not a decoding failure
            if exc.start >= len(head) - 3 and _decodes(head[: exc.start], encoding):
                return head[: exc.start].decode(encoding), encoding
    return head.decode("cp1252", errors="replace"), "cp1252"


def _utf16(head: bytes) -> str | None:
    if head.startswith(b"\xff\xfe"):
        return "utf-16-le"
    if head.startswith(b"\xfe\xff"):
        return "utf-16-be"
    sample = head[:200]
    if len(sample) >= 8 and sample.count(0) * 2 >= len(sample) - 1:  # ASCII text in UTF-16 without a mark
        return "utf-16-le" if not any(sample[1::2]) else "utf-16-be" if not any(sample[0::2]) else None
    return None


def _table_start(lines: list[str], first: int, stated: str | None, wait_for_row: bool) -> int | None:
    """The header's line among the complete ``lines``: ``first`` (the first line that is no
    comment), unless the lines after it do not continue its table and a later line heads one: a
    logger's settings ("Model,GL240", "Interval: 60 s") before the header, without ``#``.

    A line heads a table when the lines after it (up to 20) have as many cells and a data row
    follows it, directly or after rows that describe its columns (:func:`_extra_rows`; a
    settings line "Model,GL240" above a blank line and a two-column table heads none). A later
    line must besides begin a block (after a blank line, or a line with another number of
    cells) and begin like no data row: a bad first data row is not taken for a header. Where
    no line does, ``first`` (a log whose first data row is bad, or whose rows do not match its
    header in number). A live log (``wait_for_row``) waits for more lines (None) while none
    is found.
    """
    if first >= len(lines):
        return first
    delimiter = _table_delimiter(lines, first, stated)
    if delimiter is not None and _data_row_below(lines, first, delimiter):
        return first
    for k in range(first + 1, len(lines)):
        if _blank_like(lines[k]) or data_like(lines[k]):
            continue
        delimiter = _table_delimiter(lines, k, stated)
        # a line inside a table (a bad first row below its header) heads none
        if delimiter is None:
            continue
        above = next(csv.reader([lines[k - 1]], delimiter=delimiter), [])
        # (a title padded with delimiters, "Plot Title: 20827226,,,,", is no row of a table)
        inside = sum(bool(c.strip()) for c in above) >= 2 and len(above) == len(
            next(csv.reader([lines[k]], delimiter=delimiter))
        )
        if not inside and _data_row_below(lines, k, delimiter):
            return k
    written = [line for line in lines[first:] if not _blank_like(line)]
    if wait_for_row and len(written) <= _TABLE_LOOKAHEAD + 1:
        return None
    return first


# rows after a header that must match it in number of cells
_TABLE_LOOKAHEAD = 20
# rows between a header and its first data row: a units row, a second row of names, a logger's
# description of its channels (Tinytag: S/N, Type, Description, Property), empty rows, section tags
_MAX_EXTRA_ROWS = 6
# a date or a time of day somewhere in a cell
_STAMP_LIKE = re.compile(r"\d{1,4}[./-]\d{1,2}[./-]\d{1,4}|\d{1,2}:\d{2}")


def _following(lines: list[str], k: int) -> list[str]:
    return [line for line in lines[k + 1 : k + 1 + _TABLE_LOOKAHEAD] if not _blank_like(line)]


def _blank_like(line: str) -> bool:
    """A line that belongs to no table: empty, empty cells alone (",,,"), or a section tag
    alone ("[#D],,,", "[Data]", as Rotronic writes its file's parts)."""
    core = line.strip().strip(",;\t").strip()
    if not core.strip('",;\t '):
        return True
    if core.startswith("***") and core.endswith("***"):  # LabVIEW's ***End_of_Header***
        return True
    return core.startswith("[") and "]" in core and not any(d in core for d in _DELIMITERS)


def _table_delimiter(lines: list[str], k: int, stated: str | None) -> str | None:
    """A delimiter that splits line ``k`` into two written cells or more and the lines after it into as many."""
    following = _following(lines, k)
    for delimiter in (stated,) if stated else _DELIMITERS:
        cells = next(csv.reader([lines[k]], delimiter=delimiter), [])
        if (
            sum(bool(c.strip()) for c in cells) >= 2
            and following
            and all(_continues(row, cells) for row in csv.reader(following, delimiter=delimiter))
        ):
            return delimiter
    return None


def _continues(row: list[str], header: list[str]) -> bool:
    """Whether a row has as many cells as the ``header``, or one more that is empty (a delimiter
    at the end of each data row but not of the header, as a climate controller writes it), or one
    fewer where the header ends in a column of the logger's own records, which rows leave out
    (LabVIEW's "Comment", the "Serial Number" EasyLog writes in the first row alone)."""
    count = len(header)
    return (
        len(row) == count
        or (len(row) == count + 1 and not row[-1].strip())
        or (len(row) == count - 1 and event_named(header[-1]))
    )


def _data_row_below(lines: list[str], k: int, delimiter: str) -> bool:
    """Whether a data row follows line ``k``, directly or after rows that describe its columns."""
    return _extra_rows(lines, k, delimiter) is not None


def _extra_rows(lines: list[str], k: int, delimiter: str) -> int | None:
    """How many lines come between the header at line ``k`` and its first data row (a units
    row, rows that describe the columns, empty rows, section tags); None if no data row follows
    within ``_MAX_EXTRA_ROWS`` of them. Rows that describe the columns come straight under the
    header: after an empty row, a row of names heads a table of its own (a logger's settings
    line "Interval,60,s" above a blank line and the real header is no header)."""
    blank_seen = False
    for j, line in enumerate(lines[k + 1 : k + 2 + _MAX_EXTRA_ROWS]):
        cells = [c.strip() for c in next(csv.reader([line], delimiter=delimiter), [])]
        if _data_row(cells):
            return j
        blank_seen = blank_seen or _blank_like(line)
        if not (_blank_like(line) or (_describes(cells) and not blank_seen)):
            return None
    return None


def _data_row(cells: list[str]) -> bool:
    """Cells that begin like a data row: with a number or a date, or with text before a time
    stamp (a wireless logger's receiver and transmitter names before the date)."""
    if cells and data_like(cells[0]):
        return True
    return len(cells) >= 3 and bool(cells[0]) and any(_STAMP_LIKE.search(c) for c in cells[1:4])


def _describes(cells: list[str]) -> bool:
    """A row under the header that describes the columns and holds no readings: no number in
    it (units, names, types), or its first or second cell empty where a data row has its time
    (Tinytag's "S/N,,227659"): a row whose time is text ("yesterday,20") is a bad data row."""
    return not any(is_number(c) for c in cells if c) or not all(cells[:2])


def data_like(line: str) -> bool:
    """A line that begins like a data row: with a number or a date (a digit, a sign or a point)."""
    text = line.strip().lstrip('"')
    return text[:1].isdigit() or (text[:1] in "+-." and text[1:2].isdigit())


def _is_units_row(cells: list[str], dialect: CsvDialect) -> bool:
    """No cell is a number and one at least is a unit this module knows: a units row, not a data
    row (a data row's time stamp with every sensor empty has no unit in it)."""

    def number(cell: str) -> bool:
        try:
            dialect.number(cell)
        except ValueError:
            return False
        return True

    known = [c for c in cells if is_time_or_temperature_unit(c)]
    return bool(known) and not any(number(c) for c in cells if c)


def _delimiter(header: str, rows: list[str]) -> str:
    """The candidate that splits the header most often and the data rows into as many cells
    (a tie in the header, "Zeit;Temp, Spindel;Temp, Motor", is settled by the rows)."""
    cells = {d: next(csv.reader([header], delimiter=d)) for d in _DELIMITERS}
    counts = {d: len(cells[d]) for d in _DELIMITERS}
    # on a full tie ';' and tab come first: decimal commas in the rows can match commas in the names
    ranked = sorted((d for d in (";", "\t", ",") if counts[d] > 1), key=lambda d: -counts[d])
    for d in ranked:
        if all(_continues(row, cells[d]) for row in csv.reader([r for r in rows if not _blank_like(r)], delimiter=d)):
            return d
    return ranked[0] if ranked else ","


def binary_kind(head: bytes) -> str | None:
    """What a file is if it is no text: "xlsx" for an Excel workbook (a zip archive), "xls" for
    an Excel 97-2003 one, "binary" for other data with zero bytes (not UTF-16 text); else None.

    Parameters
    ----------
    head : bytes
        The file's first bytes (8 at least to tell binary data from UTF-16 text).

    Returns
    -------
    {"xlsx", "xls", "binary"} or None
        The kind of binary file, or None for text (or a head too short to tell).
    """
    if head.startswith(b"PK\x03\x04"):
        return "xlsx"
    if head.startswith(b"\xd0\xcf\x11\xe0"):
        return "xls"
    # (a live UTF-16 log's first few bytes cannot tell yet: it is told from eight on)
    if len(head) >= 8 and b"\x00" in head and _utf16(head) is None:
        return "binary"
    return None


def _decodes(data: bytes, encoding: str = "utf-8-sig") -> bool:
    try:
        data.decode(encoding)
    except UnicodeDecodeError:
        return False
    return True
