"""The schema of a compensation.json decided by what the file holds, not only by what it says
(issue 41).

Each ``schema_version`` has its own keys: version 1 (0.3.0 and earlier) no ``backlash.lead``;
version 2 (0.4.0) ``backlash.lead``; version 3 (0.5.0) adds ``model_sha256`` (the pair's
hashes, :mod:`zrp.calibration.filecheck`), ``undetermined``, ``taken_out_non_physical``,
``learned_residual`` and ``backlash.switch_weights`` (``undetermined``, notes only, is read in a
version-2 file too: 0.5.0's first commits wrote it so). A file holding a key its version never
had (an edited 0.5.0 file relabelled as version 2, whose pair the reader cannot check) is
refused by name (:func:`check_schema`), as is a key no version has.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from zrp.errors import InputError

__all__ = ["BACKLASH_KEYS", "KEYS", "SchemaMismatchError", "check_schema"]

_COMMON = ("schema_version", "zrp_version", "kind", "model_file", "length_unit",
           "nominal_model", "frame", "base_rotation", "base_rotvec", "base_translation",
           "tool_points", "joint_offsets_folded", "joint_map", "thermal", "backlash",
           "gravity_dir", "harmonics", "compliance_model", "withheld_rms",
           "gravity_side_weights", "full_pose", "conditions", "domains_widened", "apply")
#: the top-level keys of each schema_version
KEYS: dict[int, frozenset[str]] = {
    # "undetermined" came while version 2 was current (0.5.0's first commits; notes only)
    1: frozenset(_COMMON), 2: frozenset((*_COMMON, "undetermined")),
    3: frozenset((*_COMMON, "model_sha256", "undetermined", "taken_out_non_physical",
                            "learned_residual"))}
#: the keys of ``backlash`` in each schema_version
BACKLASH_KEYS: dict[int, frozenset[str]] = {
    1: frozenset(("switch", "payload_kg")), 2: frozenset(("switch", "payload_kg", "lead")),
    3: frozenset(("switch", "payload_kg", "lead", "switch_weights"))}


class SchemaMismatchError(InputError):
    """A compensation file holds keys its ``schema_version`` never had."""


def _since(key: str, table: dict[int, frozenset[str]]) -> str:
    first = [v for v, keys in sorted(table.items()) if key in keys]
    return f"schema_version {first[0]}" if first else "no schema_version"


def check_schema(doc: Mapping[str, Any], version: int, src: str) -> None:
    """Refuse ``doc`` when it holds a key its ``version`` (already checked to be a known
    one) never had.

    Raises:
        SchemaMismatchError: naming the keys and the version each came with.
    """
    extra = sorted(set(doc) - KEYS[version])
    bl = doc.get("backlash")
    if isinstance(bl, Mapping):
        extra += [f"backlash.{k}" for k in sorted(set(bl) - BACKLASH_KEYS[version])]
    if not extra:
        return
    words = ", ".join(
        f"{k} ({_since(k.split('.', 1)[-1], BACKLASH_KEYS if k.startswith('backlash.') else KEYS)})"
        for k in extra[:8])
    raise SchemaMismatchError(
        f"{src}: schema_version {version}, but it holds {words}, which schema_version "
        f"{version} never had: the file was relabelled or edited (a schema is decided by what "
        "the file holds); refused. Use the file as zrp calibrate wrote it, or calibrate again")
