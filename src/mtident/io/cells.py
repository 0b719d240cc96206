"""A log's data lines as cells, and cells as numbers: what both readers of a log share below its
rows' meaning (:mod:`mtident.io.parse`).

A cell is a number where ``float`` reads it under the log's decimal mark, a unit it carries taken
off (:meth:`~mtident.io.dialect.CsvDialect.number`), and it is written in ASCII digits without
``_`` (``float`` reads ``1_000`` and Arabic-Indic digits, which no logger writes for a reading).
A cell is empty as a spreadsheet leaves it, or where it holds one of the placeholders that
pandas, and so the readers before this one, took for a missing value (``NA``, ``#N/A``, ``None``...).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Iterable, Iterator, Sequence

import numpy as np

from mtident._typing import FloatArray
from mtident.io.dialect import CsvDialect
from mtident.io.units import number_without_unit

__all__ = [
    "split_rows",
    "iter_rows",
    "column",
    "numbers",
    "empty_cell",
    "empty_cells",
    "plain_numbers",
    "OPEN_CIRCUIT_HIGH_C",
    "OPEN_CIRCUIT_LOW_C",
]

# A PT100 channel with a broken wire reads far outside any machine-tool temperature.
OPEN_CIRCUIT_HIGH_C = 400.0
OPEN_CIRCUIT_LOW_C = -60.0

# the placeholders pandas reads as a missing value (its read_csv's na_values), as written
_NOT_AVAILABLE = frozenset(
    (
        "#N/A",
        "#N/A N/A",
        "#NA",
        "-1.#IND",
        "-1.#QNAN",
        "-NaN",
        "-nan",
        "1.#IND",
        "1.#QNAN",
        "<NA>",
        "N/A",
        "NA",
        "NULL",
        "NaN",
        "None",
        "n/a",
        "nan",
        "null",
    )
)
# a number as a spreadsheet or a logger writes it, with the decimal mark in its place
_PLAIN_NUMBER = r"\s*[+-]?(?:(?:\d+(?:{mark}\d*)?|{mark}\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?)\s*"
_PLAIN = {mark: re.compile(_PLAIN_NUMBER.format(mark=re.escape(mark)), re.IGNORECASE) for mark in (".", ",")}


def split_rows(lines: Iterable[str], dialect: CsvDialect, width: int) -> list[list[str]]:
    """The cells of data lines, each row at least ``width`` cells long (a short row's missing cells
    empty); blank lines are left out. Spaces after a delimiter are no part of a cell.

    Parameters
    ----------
    lines : iterable of str
        Data lines as text, without their line breaks.
    dialect : CsvDialect
        How the log is written (its delimiter).
    width : int
        The header's number of columns.

    Returns
    -------
    list of list of str
        One list of cells per line that is not blank.
    """
    return list(iter_rows(lines, dialect, width))


def iter_rows(lines: Iterable[str], dialect: CsvDialect, width: int) -> Iterator[list[str]]:
    """The rows of :func:`split_rows` (same parameters) one at a time, for a reader that may stop early.

    Yields
    ------
    list of str
        The cells of each line that is not blank, at least ``width`` of them.
    """
    rows = csv.reader((line for line in lines if line.strip()), delimiter=dialect.delimiter, skipinitialspace=True)
    for row in rows:
        yield row if len(row) >= width else row + [""] * (width - len(row))


def column(rows: Sequence[Sequence[str]], index: int) -> list[str]:
    """One column's cells.

    Parameters
    ----------
    rows : sequence of sequence of str
        Rows as :func:`split_rows` gives them.
    index : int
        The column's position.

    Returns
    -------
    list of str
    """
    return [row[index] for row in rows]


def empty_cell(cell: str) -> bool:
    """Whether a cell is empty, blank or a placeholder for a missing value (``NA``, ``#N/A``, ``None``...).

    Parameters
    ----------
    cell : str
        A cell as written.

    Returns
    -------
    bool
    """
    return not cell.strip() or cell.lstrip() in _NOT_AVAILABLE


def empty_cells(cells: Sequence[str]) -> np.ndarray:
    """Which cells are empty, blank or a placeholder for a missing value (``NA``, ``#N/A``, ``None``...).

    Parameters
    ----------
    cells : sequence of str
        A column's cells as written.

    Returns
    -------
    ndarray of bool, shape (len(cells),)
    """
    return np.fromiter(map(empty_cell, cells), bool, len(cells))


def numbers(cells: Sequence[str], dialect: CsvDialect) -> FloatArray:
    """Cells as numbers, read as :meth:`CsvDialect.number` reads one (a unit after the number taken
    off, a decimal comma); NaN for a cell that is none.

    Parameters
    ----------
    cells : sequence of str
        A column's cells as written.
    dialect : CsvDialect
        How the log writes its numbers.

    Returns
    -------
    ndarray, shape (len(cells),)
    """
    written: Sequence[str] = cells
    if dialect.units_in_cells:
        written = [number_without_unit(c) for c in written]
    if dialect.decimal == ",":
        written = [c.replace(",", ".") for c in written]
    joined = "".join(written)
    if joined.isascii() and "_" not in joined:
        try:  # every cell a number, as a clean log's columns are: at C speed
            return np.fromiter(map(float, written), float, len(written))
        except ValueError:
            pass
    return np.array([_number(c) for c in written], dtype=float).reshape(len(written))


def _number(cell: str) -> float:
    if not cell.isascii() or "_" in cell:
        return np.nan
    try:
        return float(cell)
    except ValueError:
        return np.nan


def plain_numbers(cells: Sequence[str], mark: str) -> bool:
    """Whether every cell is a plain number with ``mark`` as its decimal mark (``17,90`` for ","),
    as a table's reader takes a column of numbers: no unit after it, no other decimal mark.

    Parameters
    ----------
    cells : sequence of str
        A column's cells as written (no empty ones among them).
    mark : {".", ","}
        The decimal mark.

    Returns
    -------
    bool
    """
    return all(map(_PLAIN[mark].fullmatch, cells))
