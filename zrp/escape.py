"""Escaping: the one home that makes a user's string inert in every report format.

Labels, model, joint and file names, sources and messages come from the user's files; a
report shows them as text, never as structure. Every report writer passes them through:

* :func:`md_text` for Markdown (report.md, fleet.md, summaries, comparison tables): one line
  (newlines and every other control character collapse to a space, so a label can never start
  a heading or a list), Markdown and HTML punctuation backslash-escaped (``|`` cannot add a
  table cell, ``<script>`` stays text, ``**`` and backticks stay literal). A renderer that
  knows CommonMark (GitHub, report.html's :func:`md_unescape`) shows the string as given.
* :func:`html_text` for HTML text and attribute values (quotes escaped too).
* :func:`file_href` for links to files: relative links only, each path component
  percent-encoded (a file named ``javascript:alert(1)`` becomes the relative link
  ``javascript%3Aalert%281%29``); absolute paths, ``..`` and empty names are refused.
* :func:`csv_cell` for CSV cells: a text cell that a spreadsheet would run as a formula
  (first character ``= + - @``, tab or carriage return) is prefixed with ``'`` (OWASP's
  advice), numbers are kept as they are. :func:`csv_text` is the CSV writer every CSV output
  uses: it passes every cell (header too) through :func:`csv_cell`, so no caller can forget.
  The prefix is undone by :func:`csv_uncell` when zrp reads its own files back (a label
  ``=A1`` written as ``'=A1`` reads as ``=A1``); the pair is exact both ways (a label that
  already starts with ``'`` and then a formula character gets one more ``'``).
* :func:`md_row` and :func:`md_line` build Markdown from a template the program wrote and
  values that are always escaped with :func:`md_text` (numbers are formatted, not escaped;
  :class:`Md` marks a fragment the program itself wrote, such as a link to a figure).
* JSON needs nothing more: :func:`zrp.jsonio.dumps` writes every string as a JSON string
  (control characters and non-ASCII escaped), so a label cannot close it.
"""

from __future__ import annotations

import csv
import html
import io
import math
import re
from collections.abc import Iterable
from urllib.parse import quote

from zrp.errors import InputError

__all__ = ["Md", "csv_cell", "csv_text", "csv_uncell", "file_href", "html_text", "md_line",
           "md_row", "md_text", "md_unescape", "one_line"]

#: control characters (C0, DEL, C1) and the Unicode line and paragraph separators
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029]")
#: characters with a meaning in Markdown anywhere in a line (emphasis, code, links, tables,
#: strikethrough, raw HTML, entities); each is backslash-escaped by :func:`md_text`
_MD_SPECIAL = re.compile(r"([\\`*\[\]<>|~#&{}])")
#: an underscore that can open or close emphasis (one inside a word, snake_case, cannot)
_MD_UNDERSCORE = re.compile(r"(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])")
#: what starts a block when it begins a line: a list item, a numbered item, a setext line
_MD_LINE_START = re.compile(r"^([-+=]|\d+(?=[.)]))")
_MD_ESCAPED = re.compile(r"\\([!-/:-@\[-`{-~])")
#: first characters that make a spreadsheet run a cell as a formula
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
#: a text that :func:`csv_cell` prefixed: quotes, then a formula character
_QUOTED_FORMULA = re.compile(r"^'+[=+\-@\t\r]")


def one_line(text: object) -> str:
    """``text`` as one line: every run of whitespace and control characters becomes one
    space; leading and trailing space removed."""
    return " ".join(_CONTROL.sub(" ", str(text)).split())


def md_text(text: object) -> str:
    """``text`` as inert Markdown inline text: one line, each character with a meaning in
    Markdown or HTML backslash-escaped (``snake_case`` and ``q6.offset`` read as written)."""
    s = _MD_UNDERSCORE.sub(r"\\_", _MD_SPECIAL.sub(r"\\\1", one_line(text)))
    m = _MD_LINE_START.match(s)
    if m is None:
        return s
    if m.group(1).isdigit():  # "1." would start a numbered list: escape the full stop
        return s[:m.end()] + "\\" + s[m.end():]
    return "\\" + s


def md_unescape(text: str) -> str:
    """Undo the backslash escapes of Markdown inline text (as a CommonMark renderer does)."""
    return _MD_ESCAPED.sub(r"\1", text)


def html_text(text: object) -> str:
    """``text`` as HTML text or a quoted attribute value (one line, ``& < > " '`` escaped)."""
    return html.escape(one_line(text), quote=True)


def file_href(rel: str) -> str:
    """The ``href`` of a file at the relative path ``rel`` (``/``-separated): each component
    percent-encoded, so no part can be read as a scheme, a query or a fragment.

    Raises:
        InputError: ``rel`` is empty, absolute (``/x``, ``C:\\x``, ``//host``), contains a
            backslash or a ``.``/``..`` component.
    """
    if not isinstance(rel, str) or not rel:
        raise InputError(f"link {rel!r}: expected a relative file path")
    parts = rel.split("/")
    if rel.startswith("/") or any(p in ("", ".", "..") for p in parts):
        raise InputError(f"link {rel!r}: only relative links to files inside the folder are "
                         "written (no absolute path, no . or .. component)")
    return html.escape("/".join(quote(p, safe="") for p in parts), quote=True)


def csv_cell(value: object) -> object:
    """``value`` for a CSV cell: numbers unchanged; text one line, and prefixed with ``'``
    when a spreadsheet would run it as a formula (text that reads as a number stays as it
    is: ``-1.5`` is a number, ``-1+cmd`` is not)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return value
    text = str(value).replace("\r\n", " ").replace("\n", " ").replace("\r", " ")
    if _QUOTED_FORMULA.match(text):  # one more quote, so that csv_uncell gives it back
        return "'" + text
    if len(text) > 1 and text.startswith(_FORMULA_START):  # a lone "-" is no formula
        try:
            if math.isfinite(float(text)):
                return text
        except ValueError:
            pass
        return "'" + text
    return text


def csv_uncell(text: str) -> str:
    """A text cell as :func:`csv_cell` was given it: the one ``'`` it put before a formula
    character is removed (any other text is returned unchanged)."""
    return text[1:] if _QUOTED_FORMULA.match(text) else text


def csv_text(header: Iterable[object], rows: Iterable[Iterable[object]]) -> str:
    """CSV text (``\n`` line ends) of ``header`` and ``rows``, every cell through
    :func:`csv_cell`: the one CSV writer of the toolkit's outputs."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([csv_cell(c) for c in header])
    w.writerows([csv_cell(c) for c in r] for r in rows)
    return buf.getvalue()


class Md(str):
    """Markdown the program itself wrote (a literal of a template, a link to its own figure):
    :func:`md_row` and :func:`md_line` pass it through unescaped. Never wrap a user's
    string in it."""

    __slots__ = ()


def _md_value(v: object) -> str:
    if isinstance(v, Md):
        return str(v)
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return f"{v:.4g}" if isinstance(v, float) else str(int(v))  # digits . - e + only
    return md_text(v)


#: a cell of digits, signs, points, exponents, spaces and slashes (a formatted number, "0.5 /
#: 0.7", "1 .. 2"): nothing in it has a meaning inside a table cell, which never starts a line
_MD_NUMERIC_CELL = re.compile(r"[0-9eE.+\- /]*")


def md_row(*cells: object) -> str:
    """One Markdown table row: every cell escaped with :func:`md_text` (an :class:`Md` cell
    as it is, a formatted number too), so a name cannot add a cell, a line or a tag."""
    return "| " + " | ".join(c if isinstance(c, str) and _MD_NUMERIC_CELL.fullmatch(c)
                             else _md_value(c) for c in cells) + " |"


def md_line(template: str, *values: object) -> str:
    """``template`` (the program's own Markdown, ``{}`` placeholders) with each value
    escaped with :func:`md_text` (an :class:`Md` value as it is)."""
    return template.format(*(_md_value(v) for v in values))
