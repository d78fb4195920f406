"""The one output policy (zrp.output) and the one JSON converter (zrp.jsonio)."""

from __future__ import annotations

import json
import math
import multiprocessing as mp
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from zrp.errors import InputError, OutputBusyError, OutputExistsError
from zrp.jsonio import dict_from_dataclass, dumps, to_jsonable
from zrp.output import LOCK_NAME, OutputDir, atomic_path, check_writable, write_json, write_text

# ---- JSON --------------------------------------------------------------------------------------

def test_json_is_strict():
    obj = {"a": np.float64("nan"), "b": [np.inf, -np.inf, 1.5], "c": np.arange(3),
           "d": np.bool_(True), "e": (np.int32(4), Path("x/y")), 5: None}
    text = dumps(obj)
    assert "NaN" not in text and "Infinity" not in text
    back = json.loads(text)
    assert back == {"a": None, "b": [None, None, 1.5], "c": [0, 1, 2], "d": True,
                    "e": [4, "x/y"], "5": None}


def test_json_refuses_what_it_cannot_hold():
    with pytest.raises(TypeError, match="complex"):
        to_jsonable({"z": 1j})


@dataclass(frozen=True)
class _Inner:
    x: float
    tags: tuple[str, ...]


@dataclass(frozen=True)
class _Outer:
    name: str
    inner: _Inner
    items: tuple[_Inner, ...]
    score: float
    table: dict[str, tuple[int, int]]
    matrix: np.ndarray
    hidden: int = 0


def test_dict_from_dataclass_keeps_field_order_renames_and_converts():
    o = _Outer("a", _Inner(1.0, ("p", "q")), (_Inner(2.0, ()),), math.nan, {"k": (1, 2)},
               np.eye(2))
    d = dict_from_dataclass(o, exclude=("hidden",), rename={"score": "cv_rms"},
                            nan_to_none=("score",))
    assert list(d) == ["name", "inner", "items", "cv_rms", "table", "matrix"]
    assert d == {"name": "a", "inner": {"x": 1.0, "tags": ["p", "q"]},
                 "items": [{"x": 2.0, "tags": []}], "cv_rms": None, "table": {"k": [1, 2]},
                 "matrix": [[1.0, 0.0], [0.0, 1.0]]}
    assert math.isnan(dict_from_dataclass(o)["score"])  # NaN kept unless asked
    assert dict_from_dataclass(o)["hidden"] == 0
    with pytest.raises(TypeError, match="not a dataclass"):
        dict_from_dataclass({"a": 1})


# ---- single files ------------------------------------------------------------------------------

def test_existing_file_is_never_replaced_without_overwrite(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("mine")
    with pytest.raises(OutputExistsError, match=r"a\.csv: exists; pass overwrite=True"):
        write_text(p, "theirs")
    assert p.read_text() == "mine"
    write_text(p, "theirs", overwrite=True)
    assert p.read_text() == "theirs"


def test_error_names_every_existing_file_and_the_option(tmp_path):
    for n in ("a", "b"):
        (tmp_path / n).write_text("x")
    with pytest.raises(OutputExistsError) as exc:
        check_writable([tmp_path / "a", tmp_path / "b", tmp_path / "c"], overwrite=False)
    assert exc.value.paths == (str(tmp_path / "a"), str(tmp_path / "b"))
    assert "--force" in exc.value.message("--force")


def test_bad_targets_are_named(tmp_path):
    with pytest.raises(InputError, match="is a folder"):
        write_text(tmp_path, "x")
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(InputError, match="which is a file"):
        write_text(f / "sub.txt", "x")
    with pytest.raises(InputError, match="expected a file or folder path"):
        check_writable([None], overwrite=False)  # type: ignore[list-item]


def test_missing_folders_are_created(tmp_path):
    p = write_json(tmp_path / "new" / "deeper" / "r.json", {"x": math.nan})
    assert json.loads(p.read_text()) == {"x": None}


def test_failed_write_leaves_nothing(tmp_path):
    p = tmp_path / "out.txt"
    with pytest.raises(RuntimeError), atomic_path(p) as tmp:
        tmp.write_text("half")
        raise RuntimeError("writer crashed")
    assert not p.exists()
    assert os.listdir(tmp_path) == []


# ---- folders and concurrent runs ---------------------------------------------------------------

def test_names_are_checked_before_any_work(tmp_path):
    (tmp_path / "b.png").write_text("mine")
    ran = False
    with pytest.raises(OutputExistsError, match=r"b\.png"), \
            OutputDir(tmp_path, names=("a.csv", "b.png")):
        ran = True
    assert not ran
    assert not (tmp_path / LOCK_NAME).exists()


def test_output_dir_writes_and_releases(tmp_path):
    with OutputDir(tmp_path / "o", names=("a.txt",)) as out:
        out.write_text("a.txt", "1")
        out.write_json("b.json", {"k": np.float32(2)})
        assert (tmp_path / "o" / LOCK_NAME).exists()
    assert [p.name for p in out.written] == ["a.txt", "b.json"]
    assert sorted(os.listdir(tmp_path / "o")) == ["a.txt", "b.json"]
    with pytest.raises(InputError, match="inside"), OutputDir(tmp_path / "o", overwrite=True) \
            as out:
        out.write_text("../escape.txt", "x")


def _hold(folder: str, ready: mp.Event, release: mp.Event) -> None:
    with OutputDir(folder, overwrite=True) as out:
        out.write_text("first.txt", "run 1")
        ready.set()
        release.wait(30)
        out.write_text("second.txt", "run 1")


def test_two_concurrent_runs_never_mix_their_files(tmp_path):
    ctx = mp.get_context("spawn")
    ready, release = ctx.Event(), ctx.Event()
    proc = ctx.Process(target=_hold, args=(str(tmp_path), ready, release))
    proc.start()
    try:
        assert ready.wait(60)
        with pytest.raises(OutputBusyError, match=f"process {proc.pid}"), \
                OutputDir(tmp_path, overwrite=True) as out:
            out.write_text("first.txt", "run 2")
    finally:
        release.set()
        proc.join(60)
    assert proc.exitcode == 0
    assert (tmp_path / "first.txt").read_text() == "run 1"
    assert (tmp_path / "second.txt").read_text() == "run 1"
    with OutputDir(tmp_path, overwrite=True) as out:  # free again once the first run ended
        out.write_text("first.txt", "run 3")
    assert (tmp_path / "first.txt").read_text() == "run 3"


def test_a_lock_left_by_a_dead_process_is_taken_over(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    import socket

    (tmp_path / LOCK_NAME).write_text(f"{dead.stdout.strip()} {socket.gethostname()}\n")
    t0 = time.perf_counter()
    with OutputDir(tmp_path) as out:
        out.write_text("x.txt", "ok")
    assert time.perf_counter() - t0 < 10
    assert not (tmp_path / LOCK_NAME).exists()
