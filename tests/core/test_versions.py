"""Issue 35, finding 12e: ``schema_version: true`` read as version 1 (Python's True == 1).
Every format-version field a reader checks goes through zrp.jsonio.version_field: an integer
among the known versions; booleans, floats and strings are refused by name."""

from __future__ import annotations

import io
import json
import re

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.results import load_diagnosis
from zrp.jsonio import version_field


@pytest.mark.parametrize(("value", "shown"), [
    (True, "true"), (False, "false"), (1.0, "1.0"), ("1", '"1"'), (None, "null"), (4, "4"),
    ([1], "[1]"),
])
def test_a_version_is_an_integer_among_the_known(value, shown):
    with pytest.raises(InputError, match=rf"^f\.json: schema_version {re.escape(shown)}, "
                                         r"expected one of 1, 2, 3 \(an integer\)"):
        version_field({"schema_version": value}, "schema_version", (1, 2, 3), src="f.json")
    assert version_field({"schema_version": 2}, "schema_version", (1, 2, 3), src="f") == 2


def test_a_diagnosis_json_with_version_true_is_refused(tmp_path):
    doc = {"schema_version": True, "steps": [], "nominal": {"rms": 1.0},
           "final": {"rms": 1.0}, "unexplained": None}
    f = tmp_path / "diagnosis.json"
    f.write_text(json.dumps(doc))
    with pytest.raises(InputError,
                       match=r"diagnosis\.json: schema_version true, expected one of 1, 2 "):
        load_diagnosis(f)
    for version in (1, 2):  # a 0.4.0 diagnosis (schema 1) is still read
        doc["schema_version"] = version
        f.write_text(json.dumps(doc))
        assert load_diagnosis(f).final_rms == 1.0


def test_a_checkpoint_with_version_true_is_refused(tmp_path):
    from zrp import load_model
    from zrp.manufacturing import Tolerances, monte_carlo_summary
    from zrp.manufacturing.checkpoint import VERSION, _content_hash

    model = load_model("puma")
    q = 0.8 * np.sin(2 * np.pi * np.linspace(0, 1, 5)[:, None] + np.arange(6))
    tol = Tolerances.build(model, length=0.05, angle_rad=1e-4)
    ck = tmp_path / "run.npz"
    monte_carlo_summary(model, q, tol, 200, checkpoint=ck, seed=1, chunk=100)
    with np.load(ck) as z:
        arrays = {k: z[k] for k in z.files}
    head = json.loads(str(arrays.pop("header")))
    arrays.pop("sha256")
    for bad in (True, float(VERSION)):
        head["version"] = bad
        text = json.dumps(head, sort_keys=True)
        buf = io.BytesIO()
        np.savez_compressed(buf, header=np.array(text),
                            sha256=np.array(_content_hash(text, arrays)), **arrays)
        ck.write_bytes(buf.getvalue())
        with pytest.raises(InputError, match=rf"version {json.dumps(bad)}, expected {VERSION}"):
            monte_carlo_summary(model, q, tol, 200, checkpoint=ck, resume=True, seed=1,
                                chunk=100)
