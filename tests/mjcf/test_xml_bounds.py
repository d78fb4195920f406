"""Issue 35, finding 11 (2e6 short XML comments took 240 s to import) and 12a/12b, walked over
every reader of a model file: each loader of the mjcf layer, the URDF reader, the exports that
patch a file and each command that reads a model refuse a file one markup item over
zrp.xmlio.MAX_XML_MARKUP by name (in bounded time: counted before anything is parsed, MuJoCo's
parse included); an ``<include>`` over it too. The exports of both formats keep the
comments and processing instructions of the user's file; errors name the file."""

from __future__ import annotations

import warnings

import pytest

import mjcf
import zrp
from mjcf.arm import load_arm
from mjcf.importer import load_mujoco_model
from mjcf.patch import patch_mjcf
from zrp.calibration import CalibratedRobot, write_calibration
from zrp.cli.app import main
from zrp.errors import ZRPError
from zrp.model.urdf import import_urdf
from zrp.model.urdf_patch import patch_urdf
from zrp.xmlio import MAX_XML_MARKUP

BODY = ('<worldbody><body name="b"><joint name="j" type="hinge"/>'
        '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></worldbody>')
URDF = ('<link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" '
        'ixz="0" iyz="0"/></inertial></link><link name="b"><inertial><mass value="1"/>'
        '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
OVER = "1,000,001 markup items"


def _over(head: str, tail: str) -> str:
    fill = MAX_XML_MARKUP + 1 - (head + tail).count("<")
    return head + "<!--a-->\n" * fill + tail


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("over")
    out = {"xml": d / "m.xml", "urdf": d / "m.urdf", "include": d / "inc.xml"}
    out["xml"].write_text(_over("<mujoco>", BODY + "</mujoco>"))
    out["urdf"].write_text(_over('<robot name="r">', URDF + "</robot>"))
    (d / "part.xml").write_text(_over("<mujoco>", "</mujoco>"))
    out["include"].write_text(f'<mujoco><include file="part.xml"/>{BODY}</mujoco>')
    (d / "log.csv").write_text("t [s],q1 [rad],tau1 [N m]\n" + "".join(
        f"{0.001 * i:.3f},{0.01 * i:.4f},{(i * 37 % 11) * 0.1:.1f}\n" for i in range(300)))
    return out


LOADERS = {
    "load_shipped": mjcf.load_shipped,
    "load_shipped_spec": mjcf.load_shipped_spec,
    "load_mujoco_model": load_mujoco_model,
    "from_mjcf": mjcf.from_mjcf,
    "load_arm": load_arm,
    "import_urdf": import_urdf,
    "patch_urdf": lambda p: patch_urdf(p, zrp.load_model("puma")),
    "patch_mjcf": lambda p: patch_mjcf(p, zrp.load_model("puma")),
}
CASES = [(name, kind) for name in LOADERS for kind in ("xml", "urdf", "include")
         if (kind == "urdf") == (name in ("import_urdf", "patch_urdf"))
         or (kind == "urdf" and name in ("load_shipped", "load_shipped_spec", "load_arm"))]


@pytest.mark.parametrize(("name", "kind"), CASES)
def test_every_loader_refuses_a_file_over_the_bound(files, name, kind):
    with pytest.raises(ZRPError, match=OVER):
        LOADERS[name](files[kind])


@pytest.mark.parametrize(("argv", "kind"), [
    (["import", "M", "--out", "o.toml"], "urdf"),
    (["import", "M", "--out", "o.toml"], "xml"),
    (["mjcf", "--from", "M", "--out", "o.toml"], "xml"),
    (["mjcf", "--from", "M", "--out", "o.toml"], "urdf"),
    (["excite", "--model", "M", "--q0", "0", "--out", "ex.csv"], "xml"),
    (["excite", "--model", "M", "--q0", "0", "--out", "ex.csv"], "urdf"),
    (["diagnose-dynamics", "--model", "M", "--data", "log.csv", "--out", "dd"], "include"),
    (["plan", "--model", "puma", "--mjcf", "M", "--poses", "10", "--effects",
      "joint_compliance", "--out", "p.csv"], "xml"),
])
def test_every_command_refuses_a_model_over_the_bound(files, argv, kind, capsys, monkeypatch):
    monkeypatch.chdir(files["xml"].parent)
    assert main([str(files[kind]) if a == "M" else a for a in argv]) == 2
    err = capsys.readouterr().err
    assert OVER in err and "Traceback" not in err, err


def _with_comment_and_pi(text: str, root: str, inside: str = "<?tool setting?>") -> str:
    """Processing instructions first (MuJoCo's parser accepts them nowhere else), then a
    comment; a comment (and for a URDF a processing instruction) inside; one after."""
    head = '<?xml version="1.0"?>\n<?stylesheet href="x"?>\n<!-- licence: keep me -->\n'
    i = text.index(">", text.index(f"<{root}")) + 1
    return (head + text[:i] + "<!-- inside: keep me -->" + inside + text[i:]
            + "\n<!-- after: keep me -->\n")


def _calibrated(model, tmp):
    cal = CalibratedRobot.from_corrections(model, [1e-3] * model.n, model.axes,
                                           model.bodies)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return write_calibration(cal, tmp / "c.toml", tmp / "c.json")[1]


KEPT = ("<!-- licence: keep me -->", '<?stylesheet href="x"?>', "<!-- inside: keep me -->",
        "<?tool setting?>", "<!-- after: keep me -->")


def test_mjcf_export_keeps_comments_and_processing_instructions(tmp_path):
    src = tmp_path / "puma.xml"
    src.write_text(_with_comment_and_pi(mjcf.mjcf_xml(zrp.load_model("puma")), "mujoco", ""))
    comp = _calibrated(mjcf.from_mjcf(src), tmp_path)
    out = tmp_path / "out" / "cal.xml"
    assert main(["export", "--calibration", str(comp), "--mjcf", str(src), "--to", "mjcf",
                 "--out", str(out)]) == 0
    text = out.read_text()
    assert all(k in text for k in KEPT if k != "<?tool setting?>"), text[:400]
    assert text.index("licence") < text.index("<mujoco") < text.index("after: keep")
    assert mjcf.from_mjcf(out).n == 6  # MuJoCo reads the export


def test_urdf_export_keeps_comments_and_processing_instructions(tmp_path):
    src = tmp_path / "puma.urdf"
    assert main(["export", "--model", "puma", "--to", "urdf", "--out", str(src)]) == 0
    src.write_text(_with_comment_and_pi(src.read_text().split("?>", 1)[1], "robot"))
    comp = _calibrated(import_urdf(src).model, tmp_path)
    out = tmp_path / "cal.urdf"
    assert main(["export", "--calibration", str(comp), "--urdf", str(src), "--to", "urdf",
                 "--out", str(out)]) == 0
    text = out.read_text()
    assert all(k in text for k in KEPT), text[:400]
    assert text.startswith('<?xml version="1.0"?>\n<?stylesheet href="x"?>\n<!-- patched by')
    assert text.index("licence") < text.index("<robot") < text.index("after: keep")


def test_urdf_export_errors_name_the_file(tmp_path, capsys):
    """Finding 12b: they named ``<urdf string>``."""
    src = tmp_path / "arm.urdf"
    assert main(["export", "--model", "puma", "--to", "urdf", "--out", str(src)]) == 0
    comp = _calibrated(import_urdf(src).model, tmp_path)
    src.write_text(src.read_text().replace('type="continuous"', 'type="wobbly"', 1))
    assert main(["export", "--calibration", str(comp), "--urdf", str(src), "--to", "urdf",
                 "--out", str(tmp_path / "o.urdf")]) == 2
    err = capsys.readouterr().err
    assert f"{src}: joint 'q1': type 'wobbly' is unknown" in err and "<urdf string>" not in err
