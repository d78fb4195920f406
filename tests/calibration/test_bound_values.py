"""compensation.json vouches for its own values (issue 41, findings 2, 3 and 9).

* The writer runs the reader's field checks: a reflection, a translation of 1e9, harmonics
  [0], a joint offset of 1e6 rad were written by 0.5.0's ``calibrate`` and refused only when
  ``compensate`` read them; now nothing is written.
* Schema versions by what the file holds: a 0.5.0 file relabelled as schema_version 2 (whose
  pair the reader cannot check) with its learned term's training ranges widened was read with
  a warning and compensated unflagged beyond the ranges the term was trained on; refused.
* Learned coefficients of 1e300: refused on read (naming learned_residual.coef), and a
  calibrated robot built with them in the API gives no NaN command (0.5.0: "predicted RMS
  error nan -> nan mm", exit 0).
"""

from __future__ import annotations

import dataclasses
import json
import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import (
    CalibratedRobot,
    Term,
    compensate,
    compensate_program,
    read_calibration,
    write_calibration,
)
from zrp.calibration.filecheck import FieldDomainError
from zrp.calibration.guards import NonFiniteResultError
from zrp.calibration.learned import LearnedTerm
from zrp.calibration.schema import SchemaMismatchError

from .pairs import write_bound

PUMA = zrp.load_model("puma")
LABELS = ("s1", "s2")


def _term(coef: float = 0.01) -> LearnedTerm:
    """A small learned term on joint 1, trained on q1 in [-1, 1]."""
    train = np.array([[0.0, 1.0], [1.0, 0.0]])
    return LearnedTerm(("q1",), (2,), np.zeros(2), np.ones(2), np.ones(2), 1.0, train,
                       np.full((2, 6), coef), np.zeros(6), LABELS, ((-1.0, 1.0),), 0.05, 0.03,
                       3.0, 2, np.eye(3), None)


def _robot(**kw) -> CalibratedRobot:
    base = dict(model=PUMA, nominal=PUMA, base_rotation=np.eye(3),
                base_translation=np.array([1.0, 2.0, 3.0]), tool_labels=LABELS,
                tool_points=np.array([[0.0, 0, 50], [10.0, 0, 40]]),
                joint_offsets=np.zeros(6),
                terms=(Term("q3.sin1", "cyclic_error", 3, "rad", 1e-4),))
    return CalibratedRobot(**{**base, **kw})


@pytest.mark.parametrize("change, field", [
    ({"base_rotation": np.diag([1.0, 1.0, -1.0])}, "base_rotation: a reflection"),
    ({"base_translation": np.array([1e9, 0.0, 0.0])}, "base_translation"),
    ({"harmonics": (0,)}, "harmonics"),
    ({"joint_offsets": np.array([0.0, 1e6, 0, 0, 0, 0])}, "joint_offsets_folded"),
    ({"terms": (Term("q2.offset", "joint_offset", 2, "rad", 7.0),)}, r"joint_map\[0\]"),
    ({"terms": (Term("q3.sin7", "cyclic_error", 3, "rad", 1e-4),)}, "not a harmonic"),
    ({"learned": _term(1e300)}, "learned_residual.coef"),
])
def test_the_writer_refuses_what_the_reader_refuses(tmp_path, change, field):
    cal = _robot(**change)
    with pytest.raises(FieldDomainError, match=field):
        write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    assert not any(tmp_path.iterdir())  # nothing written


@pytest.fixture()
def written(tmp_path):
    _, c = write_calibration(_robot(learned=_term()), tmp_path / "calibrated.toml",
                             tmp_path / "compensation.json")
    return c


def test_a_relabelled_file_is_refused_by_what_it_holds(written):
    doc = json.loads(written.read_text())
    doc["schema_version"] = 2  # relabelled: its pair is then not checked
    doc["learned_residual"]["training_ranges"]["q1"] = [-3.0, 3.0]  # widened
    written.write_text(json.dumps(doc))
    with pytest.raises(SchemaMismatchError, match=r"schema_version 2, but it holds "
                       r"learned_residual \(schema_version 3\), model_sha256"):
        read_calibration(written)


def test_a_target_beyond_the_training_range_is_flagged(written):
    cal = read_calibration(written)
    q = np.zeros((2, 6))
    q[1, 0] = 2.0  # beyond q1's training range [-1, 1]
    q[:, 1:3] = (0.3, -0.4)
    target = cal.predict(q, point="s1")
    comp = compensate(cal, target, q, point="s1", frame="instrument", accept_flagged=True)
    assert comp.outside_measured.tolist() == [False, True]


def test_huge_learned_coefficients_are_refused_on_read(written):
    doc = json.loads(written.read_text())
    doc["learned_residual"]["coef"] = np.full((2, 6), 1e300).tolist()
    write_bound(written, doc)  # as an attacker who knows the scheme would
    with pytest.raises(FieldDomainError, match=r"learned_residual\.coef, mean: a correction "
                                               r"of up to 2e\+300 mm"):
        read_calibration(written)


@pytest.mark.parametrize("offset", [0.0, 0.1])
def test_no_command_is_nan(written, offset):
    cal = dataclasses.replace(read_calibration(written), learned=_term(1e300))
    q = np.array([[0.1, 0.3, -0.4, 0.2, 0.5, 0.1], [0.2, 0.3, -0.4, 0.2, 0.5, 0.1]])
    with warnings.catch_warnings(), pytest.raises(NonFiniteResultError,
                                                  match=r"target 1: .*learned_residual"):
        warnings.simplefilter("ignore")
        if offset:  # targets near the (absurd) prediction
            compensate(cal, cal.predict(q, point="s1") + offset, q, point="s1",
                       frame="instrument", accept_flagged=True)
        else:  # the program's own poses (0.5.0: "predicted RMS error nan -> nan mm")
            compensate_program(cal, q, accept_flagged=True)
