"""How a data-acquisition program wrote its CSV: delimiter, decimal mark, preamble, encoding, time stamps.

Loggers differ. European ones write ``;`` between cells and a decimal comma
(``17,90``); many write a preamble of ``#`` lines (device, channel setup) before
the header; Windows programs write cp1252, where ``°`` is the single byte 0xB0
that UTF-8 refuses; a trailing delimiter leaves an empty last column; time
stamps come as ISO 8601, as ``22.11.2026 08:00:00`` (day first, as everywhere
dots separate the date) or as the time of day alone. Both readers of a log (the
whole file, :func:`~mtident.io.logs.read_temperature_log`, and the live
follower, :class:`~mtident.io.follow.LogFollower`) take the dialect from the
file's head here, so they read a log the same way.
"""

from __future__ import annotations

import csv
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from mtident.exceptions import InputError

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["CsvDialect", "sniff_dialect", "header_names", "check_unique_names", "read_csv", "stamp_format", "HEAD_BYTES", "TIME_OF_DAY_FORMATS", "MINUTES_PER_DAY"]

# enough for a preamble, the header and a few rows
HEAD_BYTES = 65536
_DELIMITERS = (",", ";", "\t")
# Excel's first line "sep=;" states the delimiter
_SEP_DIRECTIVE = re.compile(r"^sep=(.)\r?$")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+(?:[eE][+-]?\d+)?\s*$")
# A time of day alone passes midnight in an overnight test: a step back of more than 12 h is the next day.
TIME_OF_DAY_FORMATS = ("%H:%M:%S.%f", "%H:%M:%S")
# Time stamps other than ISO 8601, tried in this order (pandas/strptime formats). A dotted date is
# day first wherever it is written; a slashed one (01/02/2026) is not tried: month or day first
# cannot be told apart.
_STAMP_FORMATS = ("%d.%m.%Y %H:%M:%S.%f", "%d.%m.%Y %H:%M:%S", "%d.%m.%Y %H:%M", *TIME_OF_DAY_FORMATS)
MINUTES_PER_DAY = 1440.0


@dataclass(frozen=True, slots=True)
class CsvDialect:
    """How one log file is written.

    Attributes
    ----------
    delimiter : {",", ";", "\\t"}
    decimal : {".", ","}
    preamble_lines : int
        Lines before the header: ``#`` comments, blank lines, Excel's ``sep=;``.
    encoding : {"utf-8-sig", "cp1252"}
        UTF-8 (a byte-order mark is skipped), or Windows' cp1252 where UTF-8 fails.
    """

    delimiter: str = ","
    decimal: str = "."
    preamble_lines: int = 0
    encoding: str = "utf-8-sig"

    def cells(self, line: str) -> list[str]:
        """The cells of one line (a header), stripped; quotes removed."""
        return [cell.strip() for cell in next(csv.reader([line], delimiter=self.delimiter), [])]

    def number(self, cell: str) -> float:
        """A cell as a float under this decimal mark; ValueError if it is none."""
        return float(cell.replace(",", ".") if self.decimal == "," else cell)


def sniff_dialect(head: bytes) -> CsvDialect | None:
    """The dialect of a log from its first bytes; None while its header line is incomplete.

    The delimiter is the one an Excel ``sep=`` line states, else the candidate
    that splits the header line into the most cells and the data rows into as
    many (a header has no decimal commas, so ``;`` against ``,`` is clear there,
    where csv.Sniffer, looking at data rows, would take the decimal comma for the
    delimiter). A decimal comma is assumed when the delimiter is not a comma and a
    data cell reads like ``17,90`` or ``1,5e-05``.
    """
    try:
        text, encoding = head.decode("utf-8-sig"), "utf-8-sig"
    except UnicodeDecodeError as exc:
        # a multi-byte character cut off at the end of the head is not a decoding failure
        if exc.start >= len(head) - 3 and _decodes(head[: exc.start]):
            text, encoding = head[: exc.start].decode("utf-8-sig"), "utf-8-sig"
        else:
            text, encoding = head.decode("cp1252", errors="replace"), "cp1252"
    lines = text.split("\n")
    complete = lines[:-1]  # the last piece has no newline yet
    preamble, stated = 0, None
    while preamble < len(complete):
        line = complete[preamble]
        directive = _SEP_DIRECTIVE.match(line)
        if directive and directive.group(1) in _DELIMITERS:
            stated = directive.group(1)
        elif line.strip() and not line.lstrip().startswith("#"):
            break
        preamble += 1
    if preamble >= len(complete):
        return None
    header = complete[preamble]
    delimiter = stated or _delimiter(header, complete[preamble + 1 : preamble + 21])
    decimal = "."
    if delimiter != ",":
        rows = csv.reader(complete[preamble + 1 : preamble + 21], delimiter=delimiter)  # "17,90" quoted, as spreadsheets write it
        if any(_DECIMAL_COMMA.match(cell) for row in rows for cell in row):
            decimal = ","
    return CsvDialect(delimiter, decimal, preamble, encoding)


def _delimiter(header: str, rows: list[str]) -> str:
    """The candidate that splits the header most often and the data rows into as many cells
    (a tie in the header, "Zeit;Temp, Spindel;Temp, Motor", is settled by the rows)."""
    counts = {d: len(next(csv.reader([header], delimiter=d))) for d in _DELIMITERS}
    # on a full tie ';' and tab come first: decimal commas in the rows can match commas in the names
    ranked = sorted((d for d in (";", "\t", ",") if counts[d] > 1), key=lambda d: -counts[d])
    for d in ranked:
        if all(len(row) == counts[d] for row in csv.reader([r for r in rows if r.strip()], delimiter=d)):
            return d
    return ranked[0] if ranked else ","


def header_names(file: Path) -> list[str]:
    """The column names of a log, read from its head only (a live log may be large); [] while
    its header line is incomplete."""
    with file.open("rb") as handle:
        head = handle.read(HEAD_BYTES)
    dialect = sniff_dialect(head)
    if dialect is None:
        return []
    return [name for name in dialect.cells(_header_line(head, dialect)) if name]


def _header_line(head: bytes, dialect: CsvDialect) -> str:
    return head.decode(dialect.encoding, errors="replace").split("\n")[dialect.preamble_lines]


def check_unique_names(header: list[str], source: str | Path) -> None:
    """InputError if two columns share a name: which one a sensor name meant could not be told
    (pandas would call the second 'T1.1', a reader by name would read the first twice)."""
    seen: dict[str, int] = {}
    for position, name in enumerate(header, start=1):
        if name and name in seen:
            msg = f"{source}: the column name {name!r} appears twice (columns {seen[name]} and {position}); give each column its own name"
            raise InputError(msg)
        seen[name] = position


def read_csv(path: str | Path) -> tuple[pd.DataFrame, CsvDialect]:
    """A whole CSV file as a DataFrame, read in its own dialect; InputError, naming ``path`` as
    given, if it is missing or no CSV.

    An empty column without a name (a delimiter at the end of every line) is dropped.
    """
    import pandas as pd

    file = Path(path)
    if not file.is_file():
        msg = f"{path}: no such file"
        raise InputError(msg)
    with file.open("rb") as handle:
        head = handle.read(HEAD_BYTES)
    # the whole file fits in the head: its last line is complete even without a newline
    whole = len(head) < HEAD_BYTES
    dialect = sniff_dialect(head + b"\n" if whole else head)
    if dialect is None and whole and head.strip():
        msg = f"{path}: no header line, only # comments and blank lines"
        raise InputError(msg)
    dialect = dialect or CsvDialect()
    if head.strip():
        check_unique_names(dialect.cells(_header_line(head, dialect)), path)
    try:
        frame = pd.read_csv(
            file,
            sep=dialect.delimiter,
            decimal=dialect.decimal,
            skiprows=dialect.preamble_lines,
            encoding=dialect.encoding,
            skipinitialspace=True,
        )
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        msg = f"{path}: not a readable CSV file ({str(exc).splitlines()[0]})"
        raise InputError(msg) from exc
    unnamed = [c for c in frame.columns if str(c).startswith("Unnamed: ") and frame[c].isna().all()]
    return frame.drop(columns=unnamed), dialect


def _decodes(data: bytes) -> bool:
    try:
        data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return False
    return True


def stamp_format(cell: str) -> str | None:
    """The pandas format of a time-stamp cell: "ISO8601", one of the dotted day-first or
    time-of-day formats, or None if it is no time stamp."""
    import pandas as pd

    text = cell.strip()
    for fmt in ("ISO8601", *_STAMP_FORMATS):
        try:
            pd.to_datetime(text, format=fmt, utc=True)
        except (ValueError, TypeError):
            continue
        return fmt
    return None
