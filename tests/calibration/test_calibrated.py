"""The calibrated robot out of a diagnosis, and compensation of targets (issue 11).

References: the diagnosis's own withheld residual (round trip through the written files
must reproduce it exactly); the synthetic "real robot" of zrp.gap.data.synthetic (forward
kinematics of a perturbed model, not the calibration code) for what the commands achieve.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import zrp
from tests.calibration.pairs import write_bound
from tests.gap.test_fallback import stopped_early_panda
from zrp.calibration import (
    CalibratedRobot,
    compensate,
    compensate_program,
    read_calibration,
    write_calibration,
)
from zrp.calibration.filecheck import PairWarning
from zrp.errors import InputError, OutputExistsError
from zrp.gap import Injection, diagnose, synthesize
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
LIM = np.tile([-2.5, 2.5], (6, 1))
SIGMA = 0.02
GEOMETRIC = Injection(joint_offset={2: 1e-3, 3: -8e-4}, link={3: (0.3, 0.0, -0.2)})
NON_GEOMETRIC = Injection(joint_offset={2: 1e-3}, backlash={2: 5e-4},
                          compliance={2: 2e-5, 3: 3e-5}, cyclic_error={3: (1, 5e-4, 3e-4)},
                          encoder_scale={5: 4e-4})
#: the load ahead of its approach by b/2 (its inertia carried it onto the leading flank, eq. B1)
LEADING = Injection(joint_offset={2: 1e-3}, backlash={3: -8e-4})


def _diagnosed(inj, seed=1):
    rng = np.random.default_rng(seed)
    q = uniform_joint_values(PUMA, 300, rng, LIM)
    meas = synthesize(PUMA, q, inj, rng=rng, noise_sigma=SIGMA)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(PUMA, meas, rng=np.random.default_rng(0), max_steps=6)


@pytest.fixture(scope="module")
def geometric():
    return _diagnosed(GEOMETRIC)


@pytest.fixture(scope="module")
def non_geometric():
    return _diagnosed(NON_GEOMETRIC)


@pytest.fixture(scope="module")
def leading():
    return _diagnosed(LEADING)


@pytest.fixture(scope="module")
def combined():
    """The final model is the geometric calibration plus the search's non-geometric effects
    (zrp/gap/analysis/fallback.py): the registration, the complete geometric base set and the
    cyclic error."""
    diag = stopped_early_panda()[0]
    assert diag.assessment.choice.source == "geometric_plus_non_geometric"
    return diag


@pytest.mark.parametrize("which", ["geometric", "non_geometric", "leading", "combined"])
def test_round_trip_reproduces_withheld_error(which, request, withheld_residual, tmp_path):
    diag = request.getfixturevalue(which)
    cal = CalibratedRobot.from_diagnosis(diag)
    m, c = write_calibration(cal, tmp_path / "cal.toml", tmp_path / "comp.json")
    back = read_calibration(c)
    r = withheld_residual(back, diag)
    assert np.abs(r - diag.withheld_residual_after).max() < 1e-9
    assert np.sqrt(np.mean(np.sum(r.reshape(-1, 3) ** 2, 1))) == pytest.approx(
        diag.final.rms, rel=1e-9)
    with pytest.raises(OutputExistsError):
        write_calibration(cal, m, c)
    # both files record the toolkit version that wrote them
    head = m.read_text().splitlines()
    assert head[0].startswith("# zrp calibrated model: ")  # names its compensation file
    assert head[1] == f"# written by zrp-accuracy {zrp.__version__}"
    assert json.loads(c.read_text())["zrp_version"] == zrp.__version__


def test_a_leading_flank_is_written_read_and_checked(leading, tmp_path):
    assert "backlash" in leading.final_joints
    cal = CalibratedRobot.from_diagnosis(leading)
    assert cal.backlash_lead is not None and cal.backlash_lead[2] is True
    _, c = write_calibration(cal, tmp_path / "cal.toml", tmp_path / "comp.json")
    doc = json.loads(c.read_text())
    assert doc["backlash"]["lead"][2] is True
    assert read_calibration(c).backlash_lead == cal.backlash_lead
    doc["backlash"]["lead"] = ["yes"] * 6
    write_bound(c, doc)  # the pair re-bound: the field check meets the edit
    with pytest.raises(InputError, match=r"backlash\.lead"):
        read_calibration(c)
    doc["backlash"]["lead"] = [True] * 5
    write_bound(c, doc)
    with pytest.raises(InputError, match="backlash_lead: 5 flags for 6 joints"):
        read_calibration(c)
    # a version-1 file (0.3.0) has no leading flanks: read as lagging, and a lead in it refused
    doc["schema_version"] = 1  # as 0.3.0 wrote it: none of the keys versions 2, 3 added
    for key in ("model_sha256", "learned_residual", "taken_out_non_physical", "undetermined"):
        del doc[key]
    del doc["backlash"]["lead"], doc["backlash"]["switch_weights"]
    c.write_text(json.dumps(doc))
    with pytest.warns(PairWarning, match="before schema_version 3"):
        assert read_calibration(c).backlash_lead is None
    doc["backlash"]["lead"] = list(cal.backlash_lead)
    c.write_text(json.dumps(doc))
    with pytest.raises(InputError, match=r"backlash\.lead \(schema_version 2\), which "
                                         r"schema_version 1 never had"):
        read_calibration(c)
    doc["schema_version"] = 4
    c.write_text(json.dumps(doc))
    with pytest.raises(InputError, match="schema_version 4, expected one of 1, 2, 3"):
        read_calibration(c)


def test_offsets_are_folded_into_the_model(geometric):
    cal = CalibratedRobot.from_diagnosis(geometric)
    delta = cal.joint_offsets
    assert np.count_nonzero(delta) >= 1  # identified offsets (values trade with b3 here)
    assert not any(t.effect == "joint_offset" for t in cal.terms)
    # the folded model at q equals the corrected model at q + delta: compare end points
    # of both through the toolkit's forward kinematics
    q = uniform_joint_values(PUMA, 20, np.random.default_rng(3), LIM)
    fit = geometric.final_fit
    from zrp.gap.model.problem import Problem
    u, _, bodies = Problem(geometric.context, fit.specs, geometric.fitting_poses[:1],
                           fit.base_rotation).geometry(fit.theta)
    corrected = PUMA.with_arrays(axes=u, bodies=bodies)
    a = zrp.forward_kinematics(corrected, q + delta).position
    b = zrp.forward_kinematics(cal.model, q).position
    assert np.abs(a - b).max() < 1e-9


def _targets(n=200, seed=5):
    qt = uniform_joint_values(PUMA, n, np.random.default_rng(seed), LIM * 0.8)
    nominal = synthesize(PUMA, qt, Injection(), rng=np.random.default_rng(0), noise_sigma=0.0)
    return qt, nominal.xyz[nominal.point_index == 0]


def _true_point(inj, q):
    true = synthesize(PUMA, q, inj, rng=np.random.default_rng(0), noise_sigma=0.0)
    return true.xyz[true.point_index == 0]


@pytest.mark.parametrize("which,inj", [("geometric", GEOMETRIC),
                                       ("non_geometric", NON_GEOMETRIC)])
def test_compensation_puts_the_robot_on_the_targets(which, inj, request):
    cal = CalibratedRobot.from_diagnosis(request.getfixturevalue(which))
    qt, y = _targets()
    comp = compensate(cal, y, qt, point="s1", frame="instrument", limits=LIM * 1.2,
                      accept_flagged=True)  # random targets: some near a singularity
    assert comp.converged.all()
    assert comp.residual.max() < 1e-6        # predicted residual, mm
    before = np.linalg.norm(_true_point(inj, qt) - y, axis=1)
    after = np.linalg.norm(_true_point(inj, comp.q_command) - y, axis=1)
    # the true robot at the commands: to the noise of the identification
    assert np.sqrt(np.mean(after ** 2)) < np.sqrt(3) * SIGMA * 1.5
    assert np.sqrt(np.mean(after ** 2)) < 0.1 * np.sqrt(np.mean(before ** 2))


def test_compensated_program_matches_full_pose(non_geometric):
    cal = CalibratedRobot.from_diagnosis(non_geometric)
    qt, _ = _targets(100, seed=8)
    comp = compensate_program(cal, qt, accept_flagged=True)  # flagged rows are left out
    ok = comp.converged & ~comp.near_singular
    assert ok.sum() > 80
    assert comp.residual[ok].max() < 1e-6 and comp.orientation_residual[ok].max() < 1e-8
    # the nominal pose at the program is the target: check the true robot's end point
    fk = zrp.forward_kinematics(PUMA, qt)
    true = synthesize(PUMA, comp.q_command[ok], NON_GEOMETRIC, rng=np.random.default_rng(0),
                      noise_sigma=0.0, tool_offsets=[[0.0, 0.0, 0.0]], frame="base")
    # mm; in the identified base frame (a few targets whose approach direction flips
    # between the program and its compensation miss by up to the play)
    err = np.linalg.norm(true.xyz - fk.position[ok], axis=1)
    assert np.median(err) < 0.02


def test_never_commands_beyond_a_limit(geometric):
    cal = CalibratedRobot.from_diagnosis(geometric)
    qt, y = _targets(20)
    lim = LIM.copy()
    lim[0] = [qt[:, 0].min() + 1e-6, 2.5]  # the lowest joint-1 target needs more than this
    i = int(np.argmin(qt[:, 0]))
    seed = np.clip(qt, lim[:, 0], lim[:, 1])  # every seed within the limits
    with pytest.raises(InputError, match=rf"target t{i}: .*joint 1 .*beyond its limit"):
        compensate(cal, y, seed, point="s1", frame="instrument", limits=lim,
                   target_ids=tuple(f"t{k}" for k in range(20)))
    # a seed (program row) outside a limit is refused before any solve, naming row and joint
    with pytest.raises(InputError, match=rf"target t{i}: the seed \(program\) value of joint 1 "
                       r"is .* outside its limit"):
        compensate(cal, y, qt, point="s1", frame="instrument", limits=lim,
                   target_ids=tuple(f"t{k}" for k in range(20)))
