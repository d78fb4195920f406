"""One checked entry for every XML file the toolkit reads (URDF, MJCF and their includes).

* **Bounded.** A text with more than :data:`MAX_XML_MARKUP` markup items (elements, comments,
  processing instructions, declarations: each starts with ``<``) is refused by name before it
  is parsed; with the readers' size limit (:mod:`zrp.textio`) this bounds the time and memory
  of every XML reader, MuJoCo's included (the model files are checked before it opens them).
* **Linear.** The standard library's tree builder, told to drop comments, joins the text
  around each dropped comment onto the text gathered so far: quadratic in the comments
  between two elements (2e6 comments on lines of their own took 50 s). Here the tree is built
  with its comments and processing instructions, which is linear, and a reader's tree has
  them removed in one pass (their surrounding text joined once).
* **Everything kept for a writer.** :func:`xml_document` keeps the comments and processing
  instructions inside the root, and the text before and after it (the XML declaration, a
  licence comment, a stylesheet instruction), so a patched file keeps all the user's file had.
* **Named errors.** A file that is not well-formed XML is refused naming the file and line.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from zrp.errors import ModelFileError, ZRPError
from zrp.textio import read_text

__all__ = ["MAX_XML_MARKUP", "XMLDocument", "parse_xml", "read_xml", "xml_document"]

#: The most markup items (each ``<``) an XML text may hold: a robot's URDF or MJCF has a few
#: thousand elements (the Menagerie's largest scenes under 20,000); a million bounds the
#: parse to about a second.
MAX_XML_MARKUP = 1_000_000

#: One item of the text before the root element: white space, the XML declaration or
#: another processing instruction, a comment, a document type declaration.
_PROLOG_ITEM = re.compile(r"\s+|<\?.*?\?>|<!--.*?-->|<!DOCTYPE(?:[^\[>]|\[.*?\])*>", re.S)
_LEADING_PIS = re.compile(r"(?:\s*<\?.*?\?>)*", re.S)
_ENCODING = re.compile(r"""(\bencoding\s*=\s*)(["'])[^"']*\2""")


@dataclass(frozen=True)
class XMLDocument:
    """A whole XML file: its root element (with its comments and processing instructions),
    the text before the root (``prolog``) and after it (``epilog``), as the file had them."""

    root: ET.Element
    prolog: str
    epilog: str

    def text(self, note: str = "") -> str:
        """The document as UTF-8 text, the XML comment ``note`` (if any) after the
        processing instructions the file opens with (MuJoCo's parser accepts them only
        first); a declared encoding is written as UTF-8 (the file's bytes are)."""
        head = _LEADING_PIS.match(self.prolog)
        end = head.end() if head else 0
        first = _ENCODING.sub(r"\1\2UTF-8\2", self.prolog[:end]).rstrip()
        comment = f"<!-- {note} -->\n" if note else ""
        body = ET.tostring(self.root, encoding="unicode")
        return ((first + "\n" if first else "") + comment + self.prolog[end:].lstrip("\r\n")
                + body + self.epilog.rstrip() + "\n")


def _check_size(text: str, label: str, error: type[ZRPError]) -> None:
    n = text.count("<")
    if n > MAX_XML_MARKUP:
        raise error(f"{label}: {n:,} markup items ('<'), more than the {MAX_XML_MARKUP:,} an "
                    "XML model file may have (a robot's has thousands); refused before parsing")


def _tree(text: str, label: str, error: type[ZRPError]) -> ET.Element:
    _check_size(text, label, error)
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True, insert_pis=True))
    try:
        parser.feed(text.lstrip("\ufeff"))
        return parser.close()
    except ET.ParseError as exc:
        raise error(f"{label}, line {exc.position[0]}: not valid XML: {exc}") from None


def _drop_comments(root: ET.Element) -> None:
    """Remove comments and processing instructions, in one pass; the text after each joins
    the text before it (as a parser that drops them gives)."""
    stack = [root]
    while stack:
        el = stack.pop()
        kept: list[ET.Element] = []
        pieces: list[str] = []      # the text gathered for el.text, then kept[-1].tail
        changed = False
        for child in el:
            if isinstance(child.tag, str):
                if changed and pieces:
                    _put(el, kept, pieces)
                pieces = [child.tail] if child.tail else []
                kept.append(child)
                stack.append(child)
                continue
            if not changed:
                changed = True
                pieces = ([kept[-1].tail] if kept[-1].tail else []) if kept else (
                    [el.text] if el.text else [])
            if child.tail:
                pieces.append(child.tail)
        if changed:
            _put(el, kept, pieces)
            el[:] = kept


def _put(el: ET.Element, kept: list[ET.Element], pieces: list[str]) -> None:
    text = "".join(pieces) or None
    if kept:
        kept[-1].tail = text
    else:
        el.text = text


def parse_xml(text: str, *, label: str, error: type[ZRPError] = ModelFileError,
              strict: bool = True) -> ET.Element | None:
    """The root element of the XML ``text``, without comments and processing instructions.

    ``strict=False``: None for text that is not well-formed (for a caller that leaves the
    message to another parser); the size limit is enforced either way.

    Raises:
        error: more than :data:`MAX_XML_MARKUP` markup items, or not well-formed XML (naming
            ``label`` and the line).
    """
    if not strict:
        _check_size(text, label, error)
        try:
            root = _tree(text, label, error)
        except error:
            return None
    else:
        root = _tree(text, label, error)
    if "<!--" in text or "<?" in text:
        _drop_comments(root)
    return root


def read_xml(path: str | os.PathLike[str], *, label: str | None = None,
             error: type[ZRPError] = ModelFileError) -> ET.Element:
    """:func:`parse_xml` of the file ``path`` (read with :func:`zrp.textio.read_text`: a
    regular file, size checked, UTF-8 or UTF-16)."""
    label = str(path) if label is None else label
    root = parse_xml(read_text(path, label=label, error=error), label=label, error=error)
    assert root is not None
    return root


def _epilog_start(text: str) -> int:
    """Where the comments, processing instructions and white space after the root begin."""
    i = len(text)
    while True:
        while i > 0 and text[i - 1].isspace():
            i -= 1
        if text.endswith("-->", 0, i):
            start = text.rfind("<!--", 0, i - 3)
        elif text.endswith("?>", 0, i):
            start = text.rfind("<?", 0, i - 2)
        else:
            return i
        if start < 0:
            return i
        i = start


def xml_document(source: str | os.PathLike[str], *, label: str | None = None,
                 error: type[ZRPError] = ModelFileError) -> XMLDocument:
    """The whole XML file ``source`` (a path, or XML text starting with ``<``) for a writer
    that rewrites part of it: comments, processing instructions and the text around the root
    kept (:class:`XMLDocument`).

    Raises:
        error: as :func:`parse_xml`.
    """
    if isinstance(source, str) and source.lstrip("\ufeff \t\r\n").startswith("<"):
        label, text = label or "<XML text>", source
    else:
        label = label or str(source)
        text = read_text(Path(source), label=label, error=error)
    text = text.lstrip("\ufeff")
    root = _tree(text, label, error)
    pos = 0
    while (m := _PROLOG_ITEM.match(text, pos)) is not None and m.end() > pos:
        pos = m.end()
    return XMLDocument(root, text[:pos], text[_epilog_start(text):])
