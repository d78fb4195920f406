"""Fuzz test of a stored diagnosis's final-model record (issue 41, finding 7: 5,000 fuzzed
diagnosis.json gave 118 escapes in finalrecord.py and calibrated.py in 0.5.0).

A real diagnosis.json (tests/gap/test_record_binding.py's) is mutated: a value anywhere in
its record replaced by a huge, negative, tiny, non-finite (``1e999``, ``NaN``), string,
boolean, null, list or object value, joints out of range, keys dropped or added, lists cut or
grown, the versions changed; most cases recompute the record's ``content_sha256`` (as an
attacker who knows the scheme would), so that the domains, not the hash, meet the edit. Each
case is read (:func:`zrp.calibration.recipe.stored_record`) and calibrated from
(``calibrate --diagnosis``: :func:`zrp.calibration.calibrate`, the files written). The only
assertion: nothing but a :class:`zrp.ZRPError` escapes.

CI runs ``ZRP_FUZZ_EXAMPLES`` cases (default 300, seeded); the long run, by hand:

    ZRP_FUZZ_EXAMPLES=5000 python3 -m pytest -q tests/gap/test_fuzz_final_record.py -s
"""

from __future__ import annotations

import json
import os
import warnings
from collections import Counter

import numpy as np

from zrp.calibration import calibrate
from zrp.calibration.recipe import stored_record
from zrp.errors import ZRPError
from zrp.gap.recordcheck import content_sha256

from .test_record_binding import PUMA, stored  # noqa: F401  (the fixture)

EXAMPLES = int(os.environ.get("ZRP_FUZZ_EXAMPLES", "300"))
VALUES = [1e300, -1e300, 1e-320, -1, 0, 7, 99, -3, 2**70, 1.5, -0.0, "x", "", "1", None,
          True, False, [], {}, [1, 2, 3], [[0.0, 0.0, 1.0]] * 9, {"a": 1}, float("inf"),
          float("-inf"), float("nan"), 1e9, 3.2, "q2.offset", [None], [0], [1e999]]


def _paths(node, prefix=()):
    """Every (path, value) below ``node``."""
    yield prefix, node
    items = node.items() if isinstance(node, dict) else (
        enumerate(node) if isinstance(node, list) else ())
    for k, v in items:
        yield from _paths(v, (*prefix, k))


def _at(node, path):
    for k in path:
        node = node[k]
    return node


def _mutate(doc, rng):
    """One mutation of the record (or, rarely, of the document around it), in place."""
    rec = doc["final_model_record"]
    paths = [p for p, _ in _paths(rec) if p]
    path = paths[rng.integers(len(paths))]
    parent, key = _at(rec, path[:-1]), path[-1]
    kind = rng.integers(8)
    if kind <= 3:
        parent[key] = VALUES[rng.integers(len(VALUES))]
    elif kind == 4 and isinstance(parent, dict):
        del parent[key]
    elif kind == 4:
        parent.pop(key)
    elif kind == 5 and isinstance(parent, dict):
        parent["extra_" + str(rng.integers(9))] = VALUES[rng.integers(len(VALUES))]
    elif kind == 5:
        parent.append(parent[key])
    elif kind == 6:  # joints out of range
        for p in rec.get("parameters", []) if isinstance(rec.get("parameters"), list) else []:
            if isinstance(p, dict) and rng.random() < 0.5:
                p["joint"] = int(rng.choice([0, -3, 7, 99, 2**40]))
    else:
        where = rng.integers(3)
        if where == 0:
            rec["version"] = VALUES[rng.integers(len(VALUES))]
        elif where == 1:
            doc["schema_version"] = VALUES[rng.integers(len(VALUES))]
        else:
            rec.pop("content_sha256", None)


def _text(doc) -> str:
    return (json.dumps(doc).replace("-Infinity", "-1e999").replace("Infinity", "1e999"))


def test_no_exception_but_the_projects_escapes(stored, tmp_path):  # noqa: F811
    _root, meas, base = stored
    rng = np.random.default_rng(41)
    outcomes: Counter[str] = Counter()
    escapes = []
    for case in range(EXAMPLES):
        doc = json.loads(json.dumps(base))
        for _ in range(1 + rng.integers(3)):
            try:
                _mutate(doc, rng)
            except (KeyError, IndexError, TypeError, AttributeError):
                pass  # the mutation's own path vanished: the case stands as it is
        rec = doc.get("final_model_record")
        if isinstance(rec, dict) and rng.random() < 0.8:
            rec["content_sha256"] = content_sha256(rec)
        path = tmp_path / "diagnosis.json"
        path.write_text(_text(doc), encoding="utf-8")
        for step in ("read", "calibrate"):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    if step == "read":
                        stored_record(path)
                    else:
                        res = calibrate(PUMA, meas, diagnosis=path)
                        res.write(tmp_path / "calibrated.toml", tmp_path / "comp.json",
                                  overwrite=True)
                outcomes[f"{step}: ok"] += 1
            except ZRPError as exc:
                outcomes[f"{step}: {type(exc).__name__}"] += 1
                break
            except Exception as exc:
                escapes.append((case, step, f"{type(exc).__name__}: {exc}"[:200]))
                break
    print(f"\n{EXAMPLES} cases: {len(escapes)} escapes; {dict(sorted(outcomes.items()))}")
    assert not escapes, escapes[:10]
