"""Damaged and edited Monte Carlo checkpoints (issue 26): a file that is empty, truncated,
bit-flipped, edited (its SHA-256 no longer matches) or edited with a recomputed hash (a field
that contradicts its histograms) gives a named InputError, never a traceback or a result
counting the wrong robots."""

from __future__ import annotations

import io
import json
import os

import numpy as np
import pytest

from zrp import load_model
from zrp.cli import main
from zrp.errors import InputError
from zrp.manufacturing import Tolerances, monte_carlo_summary
from zrp.manufacturing.checkpoint import _content_hash

MODEL = load_model("puma")
T = np.linspace(0.0, 1.0, 20)
Q = 0.8 * np.sin(2 * np.pi * T[:, None] + np.arange(6))
TOL = Tolerances.build(MODEL, length=0.05, angle_rad=1e-4)
ARGS = dict(seed=5, chunk=250)


@pytest.fixture(scope="module")
def saved(tmp_path_factory) -> bytes:
    ck = tmp_path_factory.mktemp("ck") / "run.npz"
    monte_carlo_summary(MODEL, Q, TOL, 1000, checkpoint=ck, **ARGS)
    return ck.read_bytes()


def _resume(path):
    return monte_carlo_summary(MODEL, Q, TOL, 1000, checkpoint=path, resume=True, **ARGS)


def _rewrite(data: bytes, edit, rehash: bool) -> bytes:
    with np.load(io.BytesIO(data)) as z:
        arrays = {k: z[k] for k in z.files}
    head = json.loads(str(arrays.pop("header")))
    digest = str(arrays.pop("sha256"))
    edit(head, arrays)
    text = json.dumps(head, sort_keys=True)
    buf = io.BytesIO()
    np.savez_compressed(buf, header=np.array(text),
                        sha256=np.array(_content_hash(text, arrays) if rehash else digest),
                        **arrays)
    return buf.getvalue()


def test_the_intact_file_resumes_to_the_full_count(tmp_path, saved):
    (tmp_path / "ok.npz").write_bytes(saved)
    res = _resume(tmp_path / "ok.npz")
    assert res.n_robots == res.delta_p.total == 1000 and res.resumed_robots == 1000


@pytest.mark.parametrize("damage", ["empty", "truncated", "half", "junk"])
def test_empty_or_truncated_files_are_named(tmp_path, saved, damage):
    data = {"empty": b"", "truncated": saved[:len(saved) - 7], "half": saved[:len(saved) // 2],
            "junk": b"PK\x03\x04" + bytes(200)}[damage]
    f = tmp_path / "ck.npz"
    f.write_bytes(data)
    with pytest.raises(InputError, match=rf"checkpoint {f}: not a Monte Carlo checkpoint"):
        _resume(f)


def test_every_flipped_byte_is_caught_or_harmless(tmp_path, saved):
    """Each of 60 bytes spread over the file flipped in turn: a named error (the zip's
    checksums or the content's SHA-256), or, for a byte of zip metadata that no content
    depends on (a time stamp), the intact file's result."""
    f = tmp_path / "ck.npz"
    f.write_bytes(saved)
    intact = _resume(f)
    caught = 0
    for pos in np.linspace(0, len(saved) - 1, 60).astype(int):
        flipped = bytearray(saved)
        flipped[pos] ^= 0x10
        f.write_bytes(bytes(flipped))
        try:
            res = _resume(f)
        except InputError as exc:
            assert str(exc).startswith(f"checkpoint {f}: ")
            caught += 1
            continue
        assert np.array_equal(res.delta_p.counts, intact.delta_p.counts)
        assert res.delta_p.total == 1000 and res.resumed_robots == 1000
    assert caught >= 50


def test_an_edited_header_breaks_the_hash(tmp_path, saved):
    f = tmp_path / "ck.npz"
    f.write_bytes(_rewrite(saved, lambda h, a: h.update(ready=0), rehash=False))
    with pytest.raises(InputError, match="does not match the SHA-256 it was written with"):
        _resume(f)


@pytest.mark.parametrize(("edit", "field"), [
    (lambda h, a: h.update(ready=0), "field ready = 0"),
    (lambda h, a: h.update(ready=99), "field ready is 99"),
    (lambda h, a: h.update(ready="4"), "field ready is '4'"),
    (lambda h, a: h.update(per_chunk=3), "field per_chunk is 3"),
    (lambda h, a: h.update(waiting=[2]), "field waiting is"),
    (lambda h, a: a.update(elapsed=np.array([-1.0])), "counts/elapsed"),
    (lambda h, a: a.update(counts=a["counts"][:1]), "field counts has shape"),
    (lambda h, a: a.update(stats=a["stats"][:, :3]), "field stats has shape"),
])
def test_edited_fields_with_a_recomputed_hash_are_named(tmp_path, saved, edit, field):
    f = tmp_path / "ck.npz"
    f.write_bytes(_rewrite(saved, edit, rehash=True))
    with pytest.raises(InputError, match=field):
        _resume(f)


def test_cli_ready_0_is_refused_not_counted_twice(tmp_path, capsys):
    ck = tmp_path / "run.npz"
    base = ["tolerance", "-n", "2000", "--steps", "20", "--no-progress", "--json",
            "--checkpoint", str(ck)]
    assert main(base) == 0
    capsys.readouterr()
    ck.write_bytes(_rewrite(ck.read_bytes(), lambda h, a: h.update(ready=0), rehash=True))
    assert main([*base, "--resume"]) != 0
    err = capsys.readouterr().err
    assert "field ready = 0" in err and "Traceback" not in err
    os.mkfifo(tmp_path / "pipe.npz")
    assert main([*base[:-1], str(tmp_path / "pipe.npz"), "--resume"]) != 0
    assert "not a regular file" in capsys.readouterr().err
