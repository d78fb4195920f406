"""``diagnose`` with measured orientations (zrp.gap.search.posefit, issue 11 "full-pose data"): the
final model refitted from positions and orientations, judged on the diagnosis's own withheld
poses, shown in diagnosis.json, report.md and the verdict; the probe rotation and the noise
recorded in compensation.json.

References: the synthetic robot (nominal PUMA with a joint-2 offset and an exact axis-5
tilt, a known probe rotation RT and orientation noise 1e-4 rad) is measured through
zrp.forward_kinematics (tests/measured.py), not the fitting code; the
withheld orientation error of a correct model is the noise's own, sqrt(3) sigma_o."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import zrp
from tests.measured import PROBE_ROTATION as RT
from tests.measured import full_pose_measurements, puma_full_pose
from zrp.cli.app import main
from zrp.errors import InputError
from zrp.gap import Measurements, diagnose
from zrp.gap.report import verdict_text

PUMA = zrp.load_model("puma")
SIGMA_O = 1e-4   # rad, the orientation noise of puma_full_pose
# the data's 1.5 mrad axis-5 tilt is explained by the (aliased) q4 offset the position search
# picks; that model turns the probe frame by up to the tilt, so R_t is found to ~1.5 mrad
RT_TOL = 2e-3
TILT = 1e-3      # rad


def _diagnose(meas, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(PUMA, meas, seed=0, **kw)


@pytest.fixture(scope="module")
def both(full_pose_diagnosis):
    return full_pose_diagnosis, _diagnose(puma_full_pose(), use_orientation=False)


def test_diagnosis_refits_the_final_model_with_orientations(both):
    diag, plain = both
    fp = diag.full_pose
    assert plain.full_pose is None and plain.settings["orientation"] is False
    assert diag.settings["orientation"] is True
    # the search's fits use the orientations too (issue 22): here the same effects, and the
    # withheld position RMS within 2 % of the positions-only search's
    assert diag.final_fit.probe_rotation is not None and plain.final_fit.probe_rotation is None
    assert diag.effects == plain.effects
    assert diag.final.rms == pytest.approx(plain.final.rms, rel=0.02)
    # each block's noise: sigma_o estimated, the probe rotation found
    assert not fp.sigma_orientation_given
    assert fp.sigma_orientation == pytest.approx(SIGMA_O, rel=0.25)
    np.testing.assert_allclose(fp.probe_rotation, RT, atol=RT_TOL)
    # withheld orientation error of the right model: the noise's own, sqrt(3) sigma_o
    assert fp.withheld_orientation_after == pytest.approx(np.sqrt(3) * SIGMA_O, rel=0.25)
    assert fp.withheld_orientation_after <= 1.02 * fp.withheld_orientation_before
    assert fp.withheld_rms <= 1.05 * fp.withheld_rms_position_only
    # what it adds: the same std formula with and without orientations; q4 sharper
    ratio = {p.name: p.ratio for p in fp.parameters}
    assert set(ratio) == {s.name for s in diag.final_fit.specs[len(diag.registration):]}
    assert min(ratio.values()) < 0.8 and fp.std_ratio_median < 1.0
    q = {p.name: p for p in fp.parameters}
    assert q["q2.offset"].value == pytest.approx(1e-3, abs=5 * q["q2.offset"].std_full_pose)


def test_orientation_results_in_json_report_and_verdict(both):
    diag, plain = both
    doc = json.loads(json.dumps(diag.to_dict()))
    fp = doc["full_pose"]
    assert fp["sigma_orientation_source"] == "estimated"
    np.testing.assert_allclose(fp["probe_rotvec_rad"], Rotation.from_matrix(RT).as_rotvec(),
                               atol=RT_TOL)
    assert set(fp["withheld_orientation_rms_rad"]) == {"position_only", "full_pose"}
    assert {p["name"] for p in fp["parameters"]} == {p.name for p in diag.full_pose.parameters}
    assert plain.to_dict()["full_pose"] is None
    assert "Measured orientations (noise" in verdict_text(diag) and "mrad" in verdict_text(diag)
    assert "Measured orientations" not in verdict_text(plain)
    from zrp.gap.report.markdown import report_markdown  # the report layer, for its text
    md = report_markdown(diag)
    sec = md[md.index("## Full pose"):]
    sec = sec[:sec.index("\n## ", 1)]
    after = diag.full_pose.withheld_orientation_after
    assert f"({1e3 * after:.3g} mrad)" in sec and f"{after:.3g} rad" in sec
    assert "| q4.offset | rad |" in sec
    assert "## Full pose" not in report_markdown(plain)


def test_given_orientation_sigma_is_used():
    diag = _diagnose(puma_full_pose(), orientation_sigma=2e-4)
    assert diag.full_pose.sigma_orientation_given
    assert diag.full_pose.sigma_orientation == 2e-4
    assert diag.to_dict()["full_pose"]["sigma_orientation_source"] == "given"


@pytest.mark.parametrize("kw, match", [
    ({"orientation_sigma": -1e-4}, "orientation_sigma"),
    ({"orientation_sigma": float("nan")}, "orientation_sigma"),
    ({"orientation_sigma": 1e-4, "use_orientation": False}, "use_orientation=False"),
    ({"use_orientation": "yes"}, "use_orientation: expected True or False"),
])
def test_bad_orientation_options(kw, match):
    with pytest.raises(InputError, match=match):
        diagnose(PUMA, puma_full_pose(), **kw)


def test_orientation_sigma_needs_orientations():
    with pytest.raises(InputError, match=r"orientation_sigma: .*no qw, qx, qy, qz"):
        diagnose(PUMA, puma_full_pose(quat=False), orientation_sigma=1e-4)


def test_cli_diagnose_and_calibrate_record_the_full_pose(tmp_path, capsys):
    puma_full_pose().to_csv(tmp_path / "d.csv")
    puma_full_pose(quat=False).to_csv(tmp_path / "p.csv")
    base = ["--model", "puma", "--data", str(tmp_path / "d.csv")]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["diagnose", *base, "--out", str(tmp_path / "a"), "--no-plots",
                     "--no-progress", "--orientation-sigma", "1e-4"]) == 0
        assert main(["diagnose", *base, "--out", str(tmp_path / "b"), "--no-plots",
                     "--no-progress", "--no-orientation"]) == 0
        assert main(["calibrate", *base, "--out", str(tmp_path / "c")]) == 0
        assert main(["calibrate", *base, "--out", str(tmp_path / "e"),
                     "--no-orientation"]) == 0
        capsys.readouterr()
        rc = main(["diagnose", "--model", "puma", "--data", str(tmp_path / "p.csv"),
                   "--out", str(tmp_path / "f"), "--orientation-sigma", "1e-4"])
    assert rc == 2 and "--orientation-sigma: given" in capsys.readouterr().err
    a = json.loads((tmp_path / "a" / "diagnosis.json").read_text())
    assert a["full_pose"]["sigma_orientation_rad"] == 1e-4
    assert a["settings"]["orientation_sigma_rad"] == 1e-4
    assert "## Full pose" in (tmp_path / "a" / "report.md").read_text()
    assert "Full pose" in (tmp_path / "a" / "report.html").read_text()
    assert json.loads((tmp_path / "b" / "diagnosis.json").read_text())["full_pose"] is None
    comp = json.loads((tmp_path / "c" / "compensation.json").read_text())["full_pose"]
    np.testing.assert_allclose(comp["probe_rotvec_rad"], Rotation.from_matrix(RT).as_rotvec(),
                               atol=RT_TOL)
    np.testing.assert_allclose(comp["probe_rotation"], RT, atol=RT_TOL)
    assert comp["sigma_orientation_rad"] == pytest.approx(SIGMA_O, rel=0.25)
    assert comp["sigma_orientation_source"] == "estimated"
    assert json.loads((tmp_path / "e" / "compensation.json").read_text())["full_pose"] is None
    assert not (tmp_path / "f").exists()


def _tilted_wrist(n_poses: int, seed: int) -> Measurements:
    """The PUMA with axis 6 tilted 1 mrad towards its second tangent (turning it out of the
    plane of axes 5 and 6: no joint offset can mimic it), one reflector 3 mm off the wrist
    centre (positions see the tilt through 3 mm), orientation noise 5e-5 rad; measured
    through zrp.forward_kinematics."""
    return full_pose_measurements(PUMA, n_poses, seed, tilt=(6, 1, TILT),
                                  tools=[[3.0, 0.0, 127.0]], probe_rotation=RT,
                                  sigma_orientation=5e-5)


@pytest.fixture(scope="module")
def tilted_wrist():
    """The tilted wrist's data and its diagnosis (two tests read the same run)."""
    meas = _tilted_wrist(120, 3)
    return meas, _diagnose(meas)


def test_an_effect_only_orientations_reveal_is_added(tilted_wrist):
    """The orientation search (zrp.gap.search.posesearch) on a position-only final model; and
    the diagnosis, whose geometric baseline now fits the orientations too (issue 22),
    explains them itself."""
    from zrp.gap.model.effects import effect_parameters
    from zrp.gap.search.posefit import refit_full_pose  # the search layer, for its own call

    meas, diag = tilted_wrist
    plain = _diagnose(meas, use_orientation=False)
    # positions alone: nothing significant (the tilt moves the reflector by ~3 um)
    assert plain.effects == ("none",) and diag.effects == ("none",)
    ctx = plain.context
    fp = refit_full_pose(ctx, plain.final_fit, plain.fitting_poses, plain.withheld_poses,
                         len(plain.registration),
                         candidates={"axis_misalignment":
                                     effect_parameters(ctx, "axis_misalignment")[0]})
    assert [(a.effect, a.joint) for a in fp.added] == [("axis_misalignment", 6)]
    step = fp.added[0]
    assert step.p_value < 1e-3 / step.n_tried
    u = {p.name: p for p in fp.parameters}
    assert u["u6.t2"].value == pytest.approx(TILT, abs=4 * u["u6.t2"].std_full_pose)
    assert abs(u["u6.t1"].value) < 4 * u["u6.t1"].std_full_pose
    assert u["u6.t2"].std_position_only > 50 * u["u6.t2"].std_full_pose
    # the withheld orientations confirm it: down to the noise's own sqrt(3) sigma_o
    assert fp.withheld_orientation_before > 8 * np.sqrt(3) * 5e-5
    assert fp.withheld_orientation_after == pytest.approx(np.sqrt(3) * 5e-5, rel=0.3)
    assert fp.sigma_orientation == pytest.approx(5e-5, rel=0.25)
    # the diagnosis with orientations: its final model (the geometric calibration fitted
    # from positions and orientations) already predicts the withheld orientations to the
    # noise, so the orientation search has nothing left to add
    assert diag.full_pose.withheld_orientation_final == pytest.approx(np.sqrt(3) * 5e-5,
                                                                      rel=0.3)
    assert diag.full_pose.added == ()
    assert "withheld orientation error" in verdict_text(diag)


def test_no_orientation_effect_is_added_to_a_complete_model(both):
    # the calibration data: the position search's model explains the orientations too
    diag, _ = both
    assert diag.full_pose.added == ()


def test_calibrated_robot_keeps_the_tilt_only_orientations_reveal(tilted_wrist, tmp_path):
    """The calibrated robot (zrp.calibration, its own forward chain, not the fitting code)
    with the full-pose fit's probe rotation predicts the withheld orientations to the noise;
    so does the diagnosis's own (fitted with the orientations); a position-only diagnosis's
    misses the tilt by ~1 mrad."""
    from zrp.calibration import CalibratedRobot  # the calibration layer, for the round trip
    from zrp.calibration.fullpose import full_pose_calibration
    from zrp.calibration.storage import write_calibration
    from zrp.gap.fit.fullpose import pose_rotations

    _, diag = tilted_wrist
    full = full_pose_calibration(diag)
    assert full.fit is diag.full_pose.fit           # the diagnosis's own refit, reused
    w = diag.withheld_poses
    meas = pose_rotations(diag.context)[w]
    q = diag.context.meas.q_pose[w]

    def rms(cal, rt):
        # the calibrated model's hand frame has the joint offsets folded in: the fitted
        # model's is R'_n R_fold (CalibratedRobot.fold_rotations)
        r = cal.predict_rotation(q) @ cal.fold_rotations()[-1] @ rt
        e = Rotation.from_matrix(r @ np.swapaxes(meas, 1, 2)).as_rotvec()
        return float(np.sqrt(np.mean(np.sum(e ** 2, axis=1))))

    assert rms(full.robot, full.fit.probe_rotation) == pytest.approx(
        diag.full_pose.withheld_orientation_after, rel=1e-6)
    # the diagnosis's own calibrated robot (its fits used the orientations) gets them right;
    # a positions-only diagnosis's misses the tilt by ~1 mrad
    own = CalibratedRobot.from_diagnosis(diag)
    assert rms(own, diag.final_fit.probe_rotation) <= 1.3 * np.sqrt(3) * 5e-5
    plain = _diagnose(_tilted_wrist(120, 3), use_orientation=False)
    assert rms(CalibratedRobot.from_diagnosis(plain), full.fit.probe_rotation) > 0.8e-3
    _, comp = write_calibration(full.robot, tmp_path / "c.toml", tmp_path / "c.json",
                                full_pose=full.fit)
    doc = json.loads(comp.read_text())["full_pose"]
    # the file's probe rotation is in the calibrated model's hand frame (offsets folded in):
    # with it, the calibrated model predicts the measured orientations as the fit did
    np.testing.assert_allclose(doc["probe_rotation"],
                               full.robot.fold_rotations()[-1] @ full.fit.probe_rotation)
    r = full.robot.predict_rotation(q) @ np.asarray(doc["probe_rotation"])
    e = Rotation.from_matrix(r @ np.swapaxes(meas, 1, 2)).as_rotvec()
    assert float(np.sqrt(np.mean(np.sum(e ** 2, axis=1)))) == pytest.approx(
        diag.full_pose.withheld_orientation_after, rel=1e-6)
    assert doc["sigma_orientation_rad"] == diag.full_pose.sigma_orientation
