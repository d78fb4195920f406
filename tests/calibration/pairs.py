"""Tests that edit a compensation file by hand re-bind the pair (both SHA-256 recomputed, as
zrp.calibration.filecheck.bind_pair writes them), so that the reader's field checks, not the
hash check, meet the edit."""

from __future__ import annotations

import json
import re
from pathlib import Path

from zrp.calibration.filecheck import bind_pair


def write_bound(comp_path: Path, doc: dict, model_path: Path | None = None) -> None:
    """Write ``doc`` as ``comp_path`` and re-bind it to its model file (default: the one
    ``doc["model_file"]`` names beside it)."""
    model = model_path or Path(comp_path).parent / doc["model_file"]
    toml = re.sub(r"^# compensation_sha256 = [0-9a-f]{64}\n", "", model.read_text(),
                  flags=re.MULTILINE)
    body = {k: v for k, v in doc.items() if k != "model_sha256"}
    bound, text = bind_pair(body, toml)
    model.write_text(text)
    Path(comp_path).write_text(json.dumps(bound))
