"""Bounded, streaming reading of the text files users hand in (one home for every reader).

Every reader of a user's file (model TOML, URDF, MJCF, DH tables, measurement, trajectory,
target, joint and plan CSVs) goes through here, so that none of them can be made to hang or
to exhaust memory:

* **Regular files only.** A FIFO, a character device (``/dev/zero``, a terminal), a socket or
  a directory is refused before it is opened (opening a FIFO would block) unless the caller
  passes ``allow_stream=True``.
* **Size checked before reading.** A file larger than ``max_bytes`` is refused from its size;
  a stream (or a file that grows while read) is refused once it passes ``max_bytes``.
* **Line length enforced while streaming.** :func:`iter_lines` decodes the file in 64 KiB
  chunks and refuses a line longer than ``max_line`` characters as soon as that many have
  accumulated without a line end, so a 300 MB line is never held whole.
* **Encodings.** UTF-8 (with or without a byte-order mark) and UTF-16 (with its byte-order
  mark, or an XML declaration in UTF-16 without one); a byte that does not decode is an error
  naming its line.

Errors are of the class the caller gives (:class:`~zrp.errors.InputError` by default; model
readers pass :class:`~zrp.errors.ModelFileError`) and name the file and, where there is one,
the line. Only CR, LF or CR LF end a line (as ``open(..., newline="")``), so the CSV module sees
quoted fields with a form feed or U+2028 unchanged.
"""

from __future__ import annotations

import codecs
import os
import re
import stat
from collections.abc import Iterator
from pathlib import Path

from zrp.errors import InputError, ZRPError

__all__ = ["MAX_LINE_CHARS", "MAX_STREAM_BYTES", "MAX_TEXT_BYTES", "check_file", "iter_lines",
           "read_text", "text_encoding"]

#: Largest file read whole (model TOML, URDF, MJCF): 256 MiB (a URDF of 20,000 joints is
#: about 10 MB).
MAX_TEXT_BYTES = 256 * 2**20
#: Largest file read line by line (CSV): 16 GiB (the row limits of each reader bound memory).
MAX_STREAM_BYTES = 16 * 2**30
#: Longest line of a streamed file, characters: 1 Mi (a CSV row of 1,000 numbers is ~25 k).
MAX_LINE_CHARS = 2**20

_CHUNK = 65536
_EOL = re.compile(r"\r\n|\r|\n")


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _mb(n: int) -> str:
    return f"{n / 2**20:,.1f} MiB" if n >= 2**20 else f"{n:,} bytes"


def check_file(path: Path, label: str, max_bytes: int, allow_stream: bool,
                error: type[ZRPError]) -> bool:
    """Stat ``path``: True when it is a regular file (its size checked), False for an allowed
    stream; anything else is an ``error`` naming ``label`` (also for binary files, e.g. a
    checkpoint)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise error(f"{label}: no such file") from None
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror or exc})") from None
    if stat.S_ISREG(st.st_mode):
        if st.st_size > max_bytes:
            raise error(f"{label}: the file is {_mb(st.st_size)}, more than the "
                        f"{_mb(max_bytes)} this reader accepts; is it the right file?")
        return True
    if allow_stream and not stat.S_ISDIR(st.st_mode):
        return False
    raise error(f"{label}: is {_kind(st.st_mode)}, not a regular file; give a file (streams "
                "and devices are not read)")


def text_encoding(head: bytes) -> str:
    """The codec of a text file from its first bytes: ``utf-16`` after a UTF-16 byte-order
    mark or for XML written in UTF-16 without one (``<?`` as two-byte characters), else
    ``utf-8-sig`` (UTF-8 with or without its byte-order mark)."""
    if head[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return "utf-16"
    if head[:4] == b"<\x00?\x00":
        return "utf-16-le"
    if head[:4] == b"\x00<\x00?":
        return "utf-16-be"
    return "utf-8-sig"


def _decode_error(label: str, exc: UnicodeDecodeError, line: int, codec: str,
                  error: type[ZRPError]) -> ZRPError:
    byte = exc.object[exc.start] if exc.start < len(exc.object) else 0
    kind = "UTF-16" if codec.startswith("utf-16") else "UTF-8"
    return error(f"{label}, line {line}: byte 0x{byte:02x} is not {kind} text; save the file "
                 "as UTF-8 (or UTF-16 with a byte-order mark)")


def iter_lines(path: str | os.PathLike[str], *, label: str | None = None,
               max_bytes: int = MAX_STREAM_BYTES, max_line: int = MAX_LINE_CHARS,
               allow_stream: bool = False, error: type[ZRPError] = InputError
               ) -> Iterator[str]:
    """The lines of a text file, each with its line end, read in chunks (memory bounded by
    ``max_line``, whatever the file). Give the result to :func:`csv.reader` directly.

    Raises (as ``error``, naming ``label`` and the line):
        not a regular file (unless ``allow_stream``), larger than ``max_bytes``, a line longer
        than ``max_line`` characters, a byte that does not decode, a read error.
    """
    p = Path(path)
    label = str(p) if label is None else label
    check_file(p, label, max_bytes, allow_stream, error)
    try:
        fh = open(p, "rb")
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror or exc})") from None
    try:
        yield from _lines(fh, label, max_bytes, max_line, error)
    finally:
        fh.close()


def _lines(fh: object, label: str, max_bytes: int, max_line: int,
           error: type[ZRPError]) -> Iterator[str]:
    read = fh.read  # type: ignore[attr-defined]
    try:
        first = read(_CHUNK)
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror or exc})") from None
    codec = text_encoding(first)
    dec = codecs.getincrementaldecoder(codec)()
    pending, line, total, raw = "", 1, 0, first
    while True:
        total += len(raw)
        if total > max_bytes:
            raise error(f"{label}: more than {_mb(max_bytes)} read; this reader accepts at most "
                        "that much (is it the right file?)")
        try:
            text = dec.decode(raw, final=not raw)
        except UnicodeDecodeError as exc:
            at = line + pending.count("\n") + exc.object[:exc.start].count(b"\n")
            raise _decode_error(label, exc, at, codec, error) from None
        buf = pending + text
        start = 0
        for m in _EOL.finditer(buf):
            if m.group() == "\r" and m.end() == len(buf) and raw:
                break  # a CR at the chunk's end may be the first half of CR LF
            yield buf[start:m.end()]
            start = m.end()
            line += 1
        pending = buf[start:]
        if len(pending) > max_line:
            raise error(f"{label}, line {line}: longer than {max_line:,} characters without a "
                        "line end; is it the right file?")
        if not raw:
            break
        try:
            raw = read(_CHUNK)
        except OSError as exc:
            raise error(f"{label}, line {line}: cannot read ({exc.strerror or exc})") from None
    if pending:
        yield pending


def read_text(path: str | os.PathLike[str], *, label: str | None = None,
              max_bytes: int = MAX_TEXT_BYTES, allow_stream: bool = False,
              error: type[ZRPError] = InputError) -> str:
    """The whole text of a file (model TOML, URDF, MJCF) after its size was checked; the line
    length is not limited (XML may be written on one line). Encodings and errors as
    :func:`iter_lines`."""
    p = Path(path)
    label = str(p) if label is None else label
    check_file(p, label, max_bytes, allow_stream, error)
    try:
        with open(p, "rb") as fh:
            raw = fh.read(max_bytes + 1)
    except OSError as exc:
        raise error(f"{label}: cannot read ({exc.strerror or exc})") from None
    if len(raw) > max_bytes:
        raise error(f"{label}: more than {_mb(max_bytes)} read; this reader accepts at most "
                    "that much (is it the right file?)")
    codec = text_encoding(raw[:4])
    try:
        return raw.decode(codec)
    except UnicodeDecodeError as exc:
        eol = "\n".encode(codec)[-2:] if codec.startswith("utf-16") else b"\n"
        line = raw[:exc.start].count(eol) + 1
        raise _decode_error(label, exc, line, codec, error) from None
