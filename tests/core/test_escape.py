"""zrp.escape, the one home of escaping, and index.html's links: user strings stay text in
Markdown, HTML, CSV and JSON; links are relative file links only."""

from __future__ import annotations

import csv
import html.parser
import io
import json
import os
from urllib.parse import unquote, urljoin

import pytest

from zrp.cli import main
from zrp.errors import InputError
from zrp.escape import csv_cell, file_href, html_text, md_text, md_unescape, one_line
from zrp.jsonio import dumps
from zrp.paper.index import index_html

HOSTILE = [
    "s1\n\n## Verdict\n\nRobot certified accurate.",
    "a | b | c",
    "<script>alert(document.domain)</script>",
    "**bold** `code` [link](javascript:alert(1)) ![img](x.png)",
    "# heading",
    "- item",
    "=HYPERLINK(\"http://x\",\"y\")",
    "x\r\ny\u2028z\x1b[31mred\x00",
    "back\\slash \\| pipe",
]


class _Links(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.urls: list[str] = []
        self.tags: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.urls += [v for k, v in attrs if k in ("href", "src") and v is not None]


@pytest.mark.parametrize("text", HOSTILE)
def test_markdown_text_is_one_inert_line_that_reads_back_as_given(text):
    md = md_text(text)
    assert "\n" not in md and "\r" not in md
    # every structural character is escaped: no unescaped pipe, angle bracket, star, backtick
    for ch in "|<>*`[]#":
        assert all(md[i - 1] == "\\" for i, c in enumerate(md) if c == ch), (ch, md)
    assert md_unescape(md) == one_line(text)  # a CommonMark reader shows the text as given


@pytest.mark.parametrize("text", HOSTILE)
def test_html_text_adds_no_tag(text):
    p = _Links()
    p.feed(f"<p title=\"{html_text(text)}\">{html_text(text)}</p>")
    assert p.tags == ["p"]


@pytest.mark.parametrize("name", ["javascript:alert(document.domain)", "data:text/html,x",
                                  "C:/x", "C:\\x", "a\\..\\b", "a b#c?d%e.png", "sub/x:y.png"])
def test_file_href_is_a_relative_link_to_that_file(name):
    href = file_href(name)
    base = "https://example.org/renders/"
    p = _Links()
    p.feed(f'<a href="{href}">x</a>')
    (url,) = p.urls
    resolved = urljoin(base, url)
    assert resolved.startswith(base)
    assert unquote(resolved[len(base):]) == name


@pytest.mark.parametrize("bad", ["/etc/passwd", "//evil.example/x", "../up.txt", "a/../../b",
                                 "", "./x", "a//b"])
def test_file_href_refuses_absolute_and_parent_links(bad):
    with pytest.raises(InputError, match="link"):
        file_href(bad)


@pytest.mark.parametrize("value", ["=1+1", "+cmd", "-2+3", "@SUM(A1)", "\t=x", "=HYPERLINK()"])
def test_csv_cells_never_start_a_formula(value):
    buf = io.StringIO()
    csv.writer(buf).writerow([csv_cell(value)])
    (cell,) = next(csv.reader(io.StringIO(buf.getvalue())))
    assert cell[0] not in "=+-@\t\r", cell
    assert cell.endswith(value.strip())


def test_csv_numbers_are_kept():
    assert csv_cell(-1.5) == -1.5 and csv_cell("-1.5") == "-1.5" and csv_cell("1e-3") == "1e-3"
    assert csv_cell("-inf") == "'-inf" and csv_cell("a\nb") == "a b"


@pytest.mark.parametrize("text", HOSTILE)
def test_json_keeps_every_string_a_string(text):
    doc = json.loads(dumps({"label": text, text: 1}))
    assert doc == {"label": text, text: 1}


def test_index_links_a_hostile_file_name_as_a_relative_file(tmp_path, capsys):
    names = ["javascript:alert(document.domain)", "<img src=x onerror=alert(1)>.png",
             'q"uote.txt']
    for n in names:
        (tmp_path / n).write_text("x")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "data:text,x.csv").write_text("x")
    (tmp_path / "descriptions.json").write_text(json.dumps({names[2]: "<script>x</script>"}))
    page = index_html(tmp_path)
    p = _Links()
    p.feed(page)
    assert set(p.tags) <= {"html", "head", "meta", "title", "style", "body", "h1", "h2", "p",
                           "ul", "ol", "li", "a", "br", "img", "section", "strong", "code"}
    base = "https://example.org/r/"
    for url in p.urls:
        resolved = urljoin(base, url)
        assert resolved.startswith(base), url
        assert os.path.exists(tmp_path / unquote(resolved[len(base):]))
    assert len(p.urls) == 5  # four links and one inline image
    assert "<script>" not in page
    assert main(["index", "--out", str(tmp_path)]) == 0
    assert 'href="javascript:' not in (tmp_path / "index.html").read_text()
