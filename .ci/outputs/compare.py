"""compare.py A B: two output trees byte for byte, after replacing each tree's own path by OUT
and masking wall-clock times (JSON keys and CSV columns named *_s, *_ms, elapsed*, timings*;
text lines that print a time in s or ms) and a warning's file:line prefix. Exit 1 on any
difference, naming the files."""

from __future__ import annotations

import csv
import io
import json
import re
import sys
from pathlib import Path

TIME_KEY = re.compile(r"(_s|_ms|_s_median|elapsed.*|timings?.*|seconds)$")
TIME_TEXT = re.compile(rb"\d(\.\d+)?\s*(ms|s)\b")
WARNING = re.compile(rb"^\S+\.py:\d+: \w*Warning: ", re.M)
BINARY = {".png", ".mp4", ".gif", ".npz"}


def _mask(obj: object) -> object:
    if isinstance(obj, dict):
        return {k: ("T" if TIME_KEY.search(k) else _mask(v)) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_mask(v) for v in obj]
    return obj


def normalised(path: Path, root: Path) -> bytes:
    data = path.read_bytes()
    if path.suffix in BINARY:
        return data
    data = WARNING.sub(b"WARNING: ", data.replace(str(root).encode(), b"OUT"))
    if path.suffix == ".json":
        try:
            return json.dumps(_mask(json.loads(data))).encode()
        except ValueError:
            pass
    if path.suffix == ".csv":
        rows = list(csv.reader(io.StringIO(data.decode())))
        if rows:
            drop = {i for i, h in enumerate(rows[0]) if TIME_KEY.search(h)}
            return repr([[c for i, c in enumerate(r) if i not in drop] for r in rows]).encode()
    return b"\n".join(line for line in data.split(b"\n") if not TIME_TEXT.search(line))


def main(a: Path, b: Path) -> int:
    fa = {p.relative_to(a) for p in a.rglob("*") if p.is_file()}
    fb = {p.relative_to(b) for p in b.rglob("*") if p.is_file()}
    bad = [f"only in {'the first' if r in fa else 'the second'}: {r}" for r in sorted(fa ^ fb)]
    bad += [f"differs: {r}" for r in sorted(fa & fb)
            if normalised(a / r, a) != normalised(b / r, b)]
    print("\n".join(bad))
    print(f"{len(fa & fb)} files compared, {len(bad)} differences")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()))
