"""The torque log's text, read defensively: the delimiter the header uses (comma, semicolon,
tab, or whitespace as UR's RTDE ``record.py`` writes), bounded lines, UTF-8 named by line,
blank and comment lines skipped, the numbers of the used columns parsed by NumPy's C reader.

Every problem is an :class:`~zrp.errors.InputError` naming the file and line (and the
column for a cell): a line longer than :data:`MAX_LINE` characters, bytes that are not
UTF-8, a header that is not CSV, a row with another number of fields than the header, a
cell that is not a finite number. Lines that are empty or whitespace only, and lines whose
first non-blank character is ``#`` or ``%``, are skipped (counted). Cost: one pass over the
lines in Python (about 1 s a million lines) feeding ``np.loadtxt``; only when that fails are
the rows read again, one by one, to name the first bad cell.
"""

from __future__ import annotations

import csv
import io
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zrp.errors import InputError
from zrp.gap.data.csvrows import number_cell

__all__ = ["MAX_LINE", "RawTable", "read_table"]

#: Longest line read, characters (a 12-joint row of 17-digit numbers is about 1,000).
MAX_LINE = 1 << 20


@dataclass(frozen=True)
class RawTable:
    """The header cells, the numbers of the used columns (rows x used), the file line of each
    row, the first data row's cells (for names logged as text), and the lines skipped."""

    header: list[str]
    values: np.ndarray
    lines: np.ndarray
    first_row: list[str]
    skipped: int


class _Lines:
    """The file's data lines, checked, with their line numbers (an iterator for loadtxt)."""

    def __init__(self, path: Path, src: str, n_fields: int, delimiter: str | None = ",") -> None:
        self.path, self.src, self.n_fields, self.delimiter = path, src, n_fields, delimiter
        self.lines: list[int] = []
        self.skipped = 0

    def texts(self) -> Iterator[tuple[int, str]]:
        """(line number, text) of every line, header included."""
        with open(self.path, "rb") as fh:
            k = 0
            while True:
                raw = fh.readline(MAX_LINE + 1)
                if not raw:
                    return
                k += 1
                if len(raw) > MAX_LINE:
                    raise InputError(f"{self.src} line {k}: longer than {MAX_LINE} characters; "
                                     "not a torque log line")
                try:
                    text = raw.decode("utf-8")
                except UnicodeDecodeError as exc:
                    raise InputError(f"{self.src} line {k}: not UTF-8 text (byte "
                                     f"{exc.start + 1} is {raw[exc.start]:#04x})") from None
                yield k, (text.removeprefix("\ufeff") if k == 1 else text).rstrip("\r\n")

    def data(self) -> Iterator[str]:
        it = self.texts()
        next(it, None)
        for k, text in it:
            s = text.strip()
            if not s or s.startswith(("#", "%")):
                self.skipped += 1
                continue
            fields = _count(text, self.delimiter)
            if fields and fields != self.n_fields:
                raise InputError(f"{self.src} line {k}: {fields} fields, but the header has "
                                 f"{self.n_fields}")
            self.lines.append(k)
            yield text


def _count(text: str, delimiter: str | None) -> int:
    """The fields of a line (0: quoted, left to the parser)."""
    if '"' in text:
        return 0
    return len(text.split()) if delimiter is None else text.count(delimiter) + 1


def _delimiter(header: str) -> str | None:
    """Comma, semicolon or tab, whichever the header has (in this order); else whitespace
    (None), as UR's RTDE ``record.py`` writes."""
    return next((d for d in ",;\t" if d in header), None)


def _header(src: str, reader: _Lines) -> tuple[list[str], str | None]:
    first = next(reader.texts(), None)
    if first is None or not first[1].strip():
        raise InputError(f"{src}: empty file (or an empty first line); expected a header line "
                         "t, q1..qn, tau1..taun")
    text = first[1].lstrip()
    if text.startswith("%") and not text.lower().startswith("%time"):
        text = text[1:]  # a KUKA Sunrise trace's header starts with "%" (rostopic: "%time")
    delimiter = _delimiter(text)
    if delimiter is None:
        return text.split(), None
    try:
        return next(csv.reader(io.StringIO(text), delimiter=delimiter)), delimiter
    except csv.Error as exc:
        raise InputError(f"{src} line 1: not a CSV header ({exc})") from None


def _cells(text: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return text.split()
    return next(csv.reader(io.StringIO(text), delimiter=delimiter))


def _locate(path: Path, src: str, header: list[str], cols: list[int], delimiter: str | None
            ) -> InputError:
    """The error of the first bad cell (the rows read again one by one)."""
    again = _Lines(path, src, len(header), delimiter)
    for text in again.data():
        line = again.lines[-1]
        try:
            rec = _cells(text, delimiter)
        except (csv.Error, StopIteration) as exc:
            return InputError(f"{src} line {line}: not a CSV row ({exc})")
        if len(rec) != len(header):
            return InputError(f"{src} line {line}: {len(rec)} fields, but the header has "
                              f"{len(header)}")
        for c in cols:
            number_cell(rec[c], src, line, header[c].strip())
    return InputError(f"{src}: not a numeric CSV after its header")


def first_cells(path: Path, src: str, n_fields: int, delimiter: str | None) -> list[str]:
    """The cells of the first data row (for joint names logged as text)."""
    lines = _Lines(path, src, n_fields, delimiter)
    text = next(lines.data(), None)
    if text is None:
        return []
    try:
        return _cells(text, delimiter)
    except (csv.Error, StopIteration):
        return []


def read_table(path: Path, src: str, cols: list[int] | None, max_rows: int | None
               ) -> tuple[list[str], RawTable | None]:
    """The header, and (when ``cols`` is given) the numbers of columns ``cols``."""
    header, delimiter = _header(src, _Lines(path, src, 0))
    if cols is None:
        return header, None
    reader = _Lines(path, src, len(header), delimiter)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "input contained no data": said below
            values = np.loadtxt(reader.data(), delimiter=delimiter, usecols=cols, ndmin=2,
                                dtype=float, quotechar='"',
                                max_rows=None if max_rows is None else max_rows + 1)
    except (ValueError, TypeError, OverflowError, IndexError):
        raise _locate(path, src, header, cols, delimiter) from None
    if values.shape[0] < 2:
        raise InputError(f"{src}: {values.shape[0]} data row(s) after the header; a torque "
                         "log needs a time series")
    if max_rows is not None and values.shape[0] > max_rows:
        raise InputError(f"{src}: more than max_rows = {max_rows} data rows; pass a larger "
                         "max_rows (or None) to read it")
    lines = np.asarray(reader.lines[: values.shape[0]], dtype=np.int64)
    if not np.all(np.isfinite(values)):
        raise _locate(path, src, header, cols, delimiter)
    return header, RawTable(header, values, lines,
                            first_cells(path, src, len(header), delimiter),
                            reader.skipped)
