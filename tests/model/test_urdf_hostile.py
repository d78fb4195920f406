"""URDF import on hostile files (issue 26): cycles, encodings, limits that are not numbers,
streams and devices: a named error or the right model, never a hang or a traceback. The cost
of large files (linear in the joints) is measured in tests/benchmarks/bench_large_inputs.py."""

from __future__ import annotations

import os

import numpy as np
import pytest

from zrp.cli import main
from zrp.errors import ModelFileError
from zrp.model.urdf import import_urdf, read_urdf

JOINT = ('<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
         '<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
         '<limit lower="{lo}" upper="1" velocity="1"/></joint>')


def _urdf(extra: str = "", lo: str = "-1") -> str:
    return ('<robot name="arm"><link name="base"/><link name="l1"/><link name="l2"/>'
            + JOINT.format(n="j1", p="base", c="l1", lo=lo)
            + JOINT.format(n="j2", p="l1", c="l2", lo="-1") + extra + "</robot>")


def test_a_self_loop_is_a_named_cycle():
    text = _urdf('<link name="x"/>' + JOINT.format(n="jx", p="x", c="x", lo="-1"))
    with pytest.raises(ModelFileError, match=r"joints \['jx'\] form a cycle through the links "
                                             r"\['x'\]"):
        read_urdf(text)


def test_a_disconnected_cycle_with_end_is_a_named_error_not_a_hang():
    cyc = ('<link name="a"/><link name="b"/>' + JOINT.format(n="ja", p="b", c="a", lo="-1")
           + JOINT.format(n="jb", p="a", c="b", lo="-1"))
    with pytest.raises(ModelFileError, match="form a cycle"):
        import_urdf(_urdf(cyc), end_link="a")


def test_a_joint_to_an_undeclared_link_is_named():
    with pytest.raises(ModelFileError, match="joint 'jg': parent link 'ghost' is not a <link>"):
        read_urdf(_urdf(JOINT.format(n="jg", p="ghost", c="l2b", lo="-1")
                        + '<link name="l2b"/>'))


@pytest.mark.parametrize(("attr", "value"), [("lower", "abc"), ("upper", "1,5"),
                                             ("velocity", "fast"), ("lower", "nan")])
def test_a_limit_that_is_not_a_number_names_the_joint_and_attribute(attr, value):
    text = _urdf().replace('lower="-1" upper="1" velocity="1"',
                           {"lower": f'lower="{value}" upper="1" velocity="1"',
                            "upper": f'lower="-1" upper="{value}" velocity="1"',
                            "velocity": f'lower="-1" upper="1" velocity="{value}"'}[attr], 1)
    with pytest.raises(ModelFileError, match=rf"joint 'j1' limit {attr}: '{value}' is not a"):
        read_urdf(text)


def _same(a, b):
    assert np.allclose(a.model.axes, b.model.axes) and np.allclose(a.model.bodies, b.model.bodies)
    assert a.joints == b.joints == ("j1", "j2")


def test_a_bom_urdf_is_read_as_urdf_by_import(tmp_path):
    plain = tmp_path / "plain.urdf"
    plain.write_text(_urdf(), encoding="utf-8")
    bom = tmp_path / "bom.urdf"
    bom.write_bytes(b"\xef\xbb\xbf" + _urdf().encode())
    _same(import_urdf(bom), import_urdf(plain))
    out = tmp_path / "m.toml"
    assert main(["import", str(bom), "--out", str(out)]) == 0
    assert "revolute" in out.read_text()


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le", "utf-16-be"])
def test_a_utf16_urdf_is_decoded(tmp_path, codec):
    f = tmp_path / "a.urdf"
    f.write_bytes(('<?xml version="1.0" encoding="UTF-16"?>\n' + _urdf()).encode(codec))
    plain = tmp_path / "plain.urdf"
    plain.write_text(_urdf(), encoding="utf-8")
    _same(import_urdf(f), import_urdf(plain))
    assert main(["import", str(f), "--out", str(tmp_path / f"{codec}.toml")]) == 0


def test_a_bad_utf8_byte_is_a_named_error(tmp_path, capsys):
    f = tmp_path / "a.urdf"
    f.write_bytes(_urdf().replace('name="l1"', 'name="l\xe91"', 1).encode("latin-1"))
    with pytest.raises(ModelFileError, match="line 1: byte 0xe9 is not UTF-8"):
        import_urdf(f)


@pytest.mark.parametrize("node", ["/dev/zero", "fifo"])
def test_import_refuses_streams(tmp_path, capsys, node):
    if node == "fifo":
        node = str(tmp_path / "pipe")
        os.mkfifo(node)
    elif not os.path.exists(node):
        pytest.skip(node)
    assert main(["import", node, "--out", str(tmp_path / "m.toml")]) != 0
    assert "not a regular file" in capsys.readouterr().err
    with pytest.raises(ModelFileError, match="not a regular file"):
        import_urdf(node)


def test_default_end_and_branches_unchanged():
    tool = ('<link name="tool0"/><joint name="jt" type="fixed"><parent link="l2"/>'
            '<child link="tool0"/></joint>')
    assert import_urdf(_urdf(tool)).end_link == "tool0"
    two = tool + '<link name="flange"/><joint name="jf" type="fixed"><parent link="l2"/>' \
                 '<child link="flange"/></joint>'
    assert import_urdf(_urdf(two)).end_link == "l2"  # several fixed tips: the last moving link
    branch = '<link name="side"/>' + JOINT.format(n="js", p="l1", c="side", lo="-1")
    with pytest.raises(ModelFileError, match=r"branches.*\['l2', 'side'\]"):
        import_urdf(_urdf(branch))
    assert import_urdf(_urdf(branch), end_link="side").joints == ("j1", "js")
