"""Fuzz test of the calibration pair's reader (issue 35): compensation.json with any field
replaced by any JSON value (also inside the joint map, the conditions, the backlash, thermal
and tool point sections), mutated as text, nested deep, and calibrated.toml mutated; most
cases re-bind the pair (both SHA-256 recomputed, as an attacker who knows the scheme would), so
that the field domains, not the hash check, meet the input. The only assertion, as in
test_fuzz_readers.py: :func:`zrp.calibration.read_calibration` returns a robot or raises an
error of the project's hierarchy (:class:`zrp.ZRPError`).

CI runs a seeded slice of ``ZRP_FUZZ_EXAMPLES`` cases (default 60). The documented long run:

    ZRP_FUZZ_EXAMPLES=5000 python3 -m pytest -q tests/contracts/test_fuzz_calibration_files.py

The first 5,000-case run found one escape (a list as ``length_unit``: TypeError; fixed, kept
in tests/calibration/test_file_domains.py); the run on the final code of issue 35: 5,000
cases, none escaped (48 s on the shared 2-core machine; 2,408 malformed, 1,411 tampered
pairs, 684 broken model files, 34 fields out of domain, 463 read).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import zrp
from tests.contracts.test_fuzz_readers import NASTY, mutated
from zrp.calibration.filecheck import MAX_JSON_DEPTH, document_sha256
from zrp.errors import ZRPError

EXAMPLES = int(os.environ.get("ZRP_FUZZ_EXAMPLES", "60"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])
PUMA = zrp.load_model("puma")
SECTIONS = [None, "joint_map", "conditions", "backlash", "thermal", "tool_points"]
JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.floats() | st.integers() | st.sampled_from(NASTY)
    | st.sampled_from([1e300, -1e300, 1e-320, 2**63, -1, 0, 1e9, "m", "furlong", "NaN"]),
    lambda inner: st.lists(inner, max_size=7) | st.dictionaries(st.text(max_size=8), inner,
                                                                max_size=4), max_leaves=12)


@pytest.fixture(scope="module")
def pair(tmp_path_factory) -> tuple[Path, str, str]:
    """A valid pair (backlash, cyclic error, conditions, gravity side weights): the folder,
    the compensation text and the model text."""
    from zrp.calibration import CalibratedRobot, Term, write_calibration
    from zrp.calibration.conditions import Conditions

    folder = tmp_path_factory.mktemp("calfuzz")
    cal = CalibratedRobot(
        PUMA, PUMA, np.eye(3), np.array([1.0, 2.0, 3.0]), ("s1", "s2"),
        np.array([[0.0, 0, 50], [10.0, 0, 40]]), np.zeros(6),
        (Term("q2.backlash", "backlash", 2, "rad", 1e-4),
         Term("q3.sin1", "cyclic_error", 3, "rad", 1e-4)),
        backlash_switch=(None, 3.0, None, None, None, None), payload_kg=1.0,
        gravity_side_weights=np.full((6, 4), 0.5),
        conditions=Conditions((0.0, 2.0), ("s1", "s2"), (20.0, 25.0), "mm",
                              ((-2.0, 2.0), *(None for _ in range(5)))))
    m, c = write_calibration(cal, folder / "calibrated.toml", folder / "ok.json")
    return folder, c.read_text(), m.read_text()


def _rebind(doc: dict, toml: str) -> tuple[str, str]:
    """Both files naming each other's SHA-256 again (doc a JSON object)."""
    toml = re.sub(r"# compensation_sha256 = [0-9a-f]{64}",
                  "# compensation_sha256 = " + document_sha256(doc), toml)
    return json.dumps({**doc, "model_sha256": hashlib.sha256(toml.encode()).hexdigest()}), toml


def _read(folder: Path, comp: bytes, toml: bytes) -> None:
    from zrp.calibration import read_calibration

    (folder / "calibrated.toml").write_bytes(toml)
    (folder / "c.json").write_bytes(comp)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            read_calibration(folder / "c.json")
        except ZRPError:
            pass


def _field_edit(data: st.DataObject, doc: dict) -> None:
    """One key of the document (or of one of its sections) replaced by any JSON value."""
    section = data.draw(st.sampled_from(SECTIONS))
    target = doc if section is None else doc[section]
    if isinstance(target, list) and target:
        target = target[data.draw(st.integers(0, len(target) - 1))]
    if not isinstance(target, dict) or not target:  # an earlier edit replaced the section
        target = doc
    key = data.draw(st.sampled_from(sorted(target)))
    target[key] = data.draw(JSON_VALUES)


@FUZZ
@given(data=st.data())
def test_compensation_pair_reader(pair, data):
    folder, comp, toml = pair
    mode = data.draw(st.sampled_from(["field", "field", "field", "text", "toml", "deep"]))
    doc = json.loads(comp)
    if mode == "field":
        for _ in range(data.draw(st.integers(1, 3))):
            _field_edit(data, doc)
        text, t = _rebind(doc, toml) if data.draw(st.integers(0, 4)) else (json.dumps(doc),
                                                                           toml)
        _read(folder, text.encode(), t.encode())
    elif mode == "text":
        _read(folder, data.draw(mutated(comp)), toml.encode())
    elif mode == "toml":
        t = data.draw(mutated(toml)).decode("utf-8", errors="replace")
        text, t = _rebind(doc, t)
        _read(folder, text.encode(), t.encode("utf-8", errors="surrogatepass"))
    else:
        depth = data.draw(st.integers(MAX_JSON_DEPTH - 2, 200_000))
        key = data.draw(st.sampled_from(["tool_points", "joint_map", "harmonics", "conditions"]))
        nested = "[" * depth + "1" + "]" * depth
        _read(folder, comp.replace(f'"{key}":', f'"{key}": {nested}, "x{key}":', 1).encode(),
              toml.encode())


def test_the_unmutated_pair_loads_and_each_file_alone_is_refused(pair):
    from zrp.calibration import read_calibration
    from zrp.calibration.filecheck import TamperedPairError

    folder, comp, toml = pair
    (folder / "calibrated.toml").write_text(toml)
    (folder / "c.json").write_text(comp)
    assert read_calibration(folder / "c.json").n == 6
    text, _ = _rebind(json.loads(comp), toml)
    (folder / "c.json").write_text(text)
    assert read_calibration(folder / "c.json").n == 6  # the test's re-binding is the writer's
    (folder / "c.json").write_text(comp.replace('"withheld_rms": null',
                                                '"withheld_rms": 0.001'))
    with pytest.raises(TamperedPairError, match=r"c\.json: its content"):
        read_calibration(folder / "c.json")
    (folder / "c.json").write_text(comp)
    (folder / "calibrated.toml").write_text(toml.replace("[[joint]]", "[[joint]]\n", 1))
    with pytest.raises(TamperedPairError, match=r"calibrated\.toml: its SHA-256"):
        read_calibration(folder / "c.json")
    (folder / "calibrated.toml").write_text(toml)
