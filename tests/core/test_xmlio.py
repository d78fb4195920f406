"""zrp.xmlio, the one checked entry of every XML reader (issue 35, findings 11 and 12a): a
stated bound on the markup (refused by name before parsing, just over it; read just under
it), the reader's tree the standard library's, the writer's document everything the file had.
That no reader parses XML another way is checked on the source."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from zrp.errors import InputError, ModelFileError
from zrp.xmlio import MAX_XML_MARKUP, parse_xml, read_xml, xml_document

ROOT = Path(__file__).resolve().parents[2]

#: every way to parse XML the standard library (and MuJoCo's XML loaders) offers
_PARSERS = re.compile(r"\bET\.(?:parse|fromstring|XML|XMLParser|iterparse|XMLPullParser)\b|"
                      r"\bElementTree import .*\b(?:parse|fromstring|XML|XMLParser|iterparse)\b|"
                      r"\bminidom\b|\bpyexpat\b|\bxml\.parsers\b|\bxml\.sax\b(?!\.saxutils)|"
                      r"\blxml\b")


def test_no_reader_parses_xml_but_through_xmlio():
    """The class fix: every XML reader goes through zrp.xmlio (MuJoCo's own loaders are
    reached only after mjcf.assets.check_model_files, which parses with it)."""
    found = []
    for pkg in ("zrp", "mjcf", "sim"):
        for f in sorted((ROOT / pkg).rglob("*.py")):
            if f.name == "xmlio.py" and f.parent.name == "zrp":
                continue
            for i, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1):
                if _PARSERS.search(line.split("#")[0]):
                    found.append(f"{f.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not found, "\n".join(found)


def _comments(n_markup: int) -> str:
    """A URDF-like text of exactly ``n_markup`` markup items, nearly all comments on lines of
    their own (the shape that made the standard library's builder quadratic)."""
    head, tail = '<robot name="r"><link name="a"/>', "</robot>"
    fill = n_markup - (head + tail).count("<")
    return head + "<!--a-->\n" * fill + tail


def test_one_over_the_bound_is_refused_by_name_before_parsing(tmp_path):
    text = _comments(MAX_XML_MARKUP + 1)
    assert text.count("<") == MAX_XML_MARKUP + 1
    with pytest.raises(ModelFileError, match=r"m\.urdf: 1,000,001 markup items .*the "
                                             r"1,000,000 an XML model file may have"):
        parse_xml(text, label="m.urdf")
    f = tmp_path / "m.urdf"
    f.write_text(text)
    with pytest.raises(InputError, match="1,000,001 markup items"):
        read_xml(f, error=InputError)
    with pytest.raises(ModelFileError, match="1,000,001 markup items"):
        xml_document(f)
    with pytest.raises(ModelFileError, match="1,000,001 markup items"):  # even when lenient
        parse_xml(text, label="m.urdf", strict=False)


def test_at_the_bound_the_file_reads():
    root = parse_xml(_comments(MAX_XML_MARKUP), label="m.urdf")
    assert root is not None and [el.tag for el in root] == ["link"]
    assert (root[0].tail or "").strip() == ""


@pytest.mark.parametrize("text", [
    "<r>a<!--c-->b<x/>c<!--d-->d<?p q?>e<y>t<!--z--></y>f</r>",
    "<r><!--only--></r>",
    "<r>x<!--c--><a/></r>",
    "<r><a/>t1<!--c-->t2<b/><!--e--><?pi?></r>",
    '<?xml version="1.0"?>\n<!-- head -->\n<r k="v"><a><b/></a>tail<!--x--></r>\n<!-- end -->',
])
def test_the_readers_tree_is_the_standard_librarys(text):
    """Comments and processing instructions dropped, the text around them joined: what
    ET.fromstring gives (it is only slow)."""
    mine = parse_xml(text, label="t")
    assert ET.tostring(mine) == ET.tostring(ET.fromstring(text))


def test_not_well_formed_names_the_file_and_line():
    with pytest.raises(ModelFileError, match=r"^m\.xml, line 2: not valid XML"):
        parse_xml("<r>\n<a></r>", label="m.xml")
    assert parse_xml("<r>\n<a></r>", label="m.xml", strict=False) is None


def test_the_writers_document_keeps_everything_the_file_had():
    text = ('<?xml version="1.0" encoding="ISO-8859-1"?>\n<!-- licence -->\n'
            '<?xml-stylesheet href="s.xsl"?>\n<!DOCTYPE robot>\n'
            '<robot name="r"><!-- inside --><?pi data?><link name="a"/></robot>\n'
            '<!-- after --><?after x?>\n')
    doc = xml_document(text)
    out = doc.text("patched")
    for part in ("<!-- licence -->", '<?xml-stylesheet href="s.xsl"?>', "<!DOCTYPE robot>",
                 "<!-- inside -->", "<?pi data?>", "<!-- after -->", "<?after x?>"):
        assert part in out
    # the declaration first, naming the encoding the text is written in, then the note
    assert out.startswith('<?xml version="1.0" encoding="UTF-8"?>\n<!-- patched -->\n')
    assert ET.tostring(ET.fromstring(out)) == ET.tostring(ET.fromstring(text))
