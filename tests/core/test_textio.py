"""The bounded text reader (zrp.textio): streams and devices refused before they are opened,
sizes checked before reading, over-long lines refused while streaming, decoding errors named
with their line."""

from __future__ import annotations

import os
import tracemalloc

import pytest

from zrp.errors import InputError, ModelFileError
from zrp.textio import iter_lines, read_text


def test_lines_keep_their_ends_and_only_cr_lf_split():
    # a form feed or U+2028 is not a line end (the CSV module sees quoted fields unchanged)
    text = "a,b\r\nc,d\re,\f\u2028f\ng"
    assert "".join(iter_lines_of(text)) == text
    assert iter_lines_of(text) == ["a,b\r\n", "c,d\r", "e,\f\u2028f\n", "g"]


def iter_lines_of(text: str, tmp=None) -> list[str]:
    import tempfile
    with tempfile.NamedTemporaryFile("w", delete=False, newline="", encoding="utf-8") as fh:
        fh.write(text)
    try:
        return list(iter_lines(fh.name))
    finally:
        os.unlink(fh.name)


def test_cr_lf_across_a_chunk_boundary_is_one_line_end(tmp_path):
    f = tmp_path / "a.csv"
    f.write_bytes(b"x" * 65535 + b"\r\n" + b"y\n")
    lines = list(iter_lines(f))
    assert [len(s) for s in lines] == [65537, 2]


@pytest.mark.parametrize("node", ["/dev/zero", "/dev/null"])
def test_devices_are_refused_before_reading(node):
    if not os.path.exists(node):
        pytest.skip(f"no {node}")
    with pytest.raises(InputError, match="character device, not a regular file"):
        list(iter_lines(node))
    with pytest.raises(ModelFileError, match="character device"):
        read_text(node, error=ModelFileError)


def test_a_fifo_is_refused_without_opening_it(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)  # opening it for reading would block until a writer comes
    with pytest.raises(InputError, match="FIFO"):
        read_text(fifo)
    with pytest.raises(InputError, match="FIFO"):
        list(iter_lines(fifo))


def test_a_directory_and_a_missing_file_are_named(tmp_path):
    with pytest.raises(InputError, match="directory"):
        read_text(tmp_path)
    with pytest.raises(InputError, match="no such file"):
        read_text(tmp_path / "nope.toml")


def test_an_allowed_stream_is_still_bounded():
    with pytest.raises(InputError, match=r"more than 1\.0 MiB read"):
        list(iter_lines("/dev/zero", allow_stream=True, max_bytes=2**20, max_line=2**30))
    with pytest.raises(InputError, match=r"more than 1\.0 MiB read"):
        read_text("/dev/zero", allow_stream=True, max_bytes=2**20)


def test_the_size_is_checked_before_reading(tmp_path):
    f = tmp_path / "big.toml"
    with open(f, "wb") as fh:  # sparse: 3 GiB on disk costs nothing
        fh.truncate(3 * 2**30)
    with pytest.raises(ModelFileError, match=r"3,072.0 MiB, more than the 256.0 MiB"):
        read_text(f, error=ModelFileError)


def test_one_long_line_is_refused_without_holding_it(tmp_path):
    f = tmp_path / "one_line.csv"
    with open(f, "w") as fh:
        fh.write("t,q1\n")
        fh.write("1" * (40 * 2**20))  # 40 MB without a line end
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match=r"one_line.csv, line 2: longer than 1,048,576"):
            list(iter_lines(f))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 8 * 2**20  # a few MiB, not the 40 MB line


def test_encodings_bom_and_utf16(tmp_path):
    f = tmp_path / "a.txt"
    f.write_bytes("\ufeffé,1\n".encode())
    assert read_text(f) == "é,1\n" and list(iter_lines(f)) == ["é,1\n"]
    f.write_text("é,1\nb,2\n", encoding="utf-16")
    assert read_text(f) == "é,1\nb,2\n" and list(iter_lines(f)) == ["é,1\n", "b,2\n"]
    f.write_bytes('<?xml version="1.0"?><robot/>'.encode("utf-16-le"))  # no byte-order mark
    assert read_text(f).startswith("<?xml")


def test_a_byte_that_does_not_decode_names_its_line(tmp_path):
    f = tmp_path / "bad.csv"
    f.write_bytes(b"a\nb\nc\xffd\n")
    with pytest.raises(InputError, match=r"bad.csv, line 3: byte 0xff is not UTF-8"):
        read_text(f)
    with pytest.raises(InputError, match=r"bad.csv, line 3: byte 0xff is not UTF-8"):
        list(iter_lines(f))
