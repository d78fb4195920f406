"""Fuzz test of the readers added since the first round (issue 26): URDF import (mutated
files and random link graphs with cycles, self-loops and undeclared links), ``zrp import``'s
format detection, the trajectory CSV, and Monte Carlo checkpoints (damaged bytes, and edited
fields under a recomputed hash). As in test_fuzz_readers.py, the only assertion: the reader
returns a result or raises an error of the project's hierarchy (:class:`zrp.ZRPError`).

CI runs a seeded slice of ``ZRP_FUZZ_EXAMPLES`` cases per test (default 60). The documented
long run, 10,000 cases for each reader:

    ZRP_FUZZ_EXAMPLES=10000 python3 -m pytest -q tests/contracts/test_fuzz_new_readers.py

Run on the final code (shared 2-core machine under load): 10,000 cases for each of the four
tests here, none escaped (URDF files 405 s, link graphs 216 s, trajectory CSVs 115 s,
checkpoints 211 s); with them test_fuzz_readers.py's MJCF and URDF-through-MuJoCo readers at
10,000 cases each, none escaped (163 s, 133 s). Earlier runs found two escapes, fixed and kept
below as a test: a trajectory header naming a column twice (IndexError, 1,000-case run) and a
forged checkpoint whose robot count is NaN (ValueError).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import zrp
from tests.contracts.test_fuzz_readers import NASTY, URDF_TEXT, mutated
from zrp.cli.commands.robot_import import _read as import_read
from zrp.errors import ZRPError
from zrp.gap.motion import Trajectory, load_trajectory, write_trajectory
from zrp.manufacturing import Tolerances, monte_carlo_summary
from zrp.manufacturing.checkpoint import _content_hash, load_merge, run_identity
from zrp.manufacturing.population import chunk_tasks
from zrp.manufacturing.reduction import histogram_edges
from zrp.model.urdf import import_urdf

EXAMPLES = int(os.environ.get("ZRP_FUZZ_EXAMPLES", "60"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])

PUMA = zrp.load_model("puma")

#: a URDF with every joint type the reader knows, a mimic joint and a fixed tool link.
URDF_FULL = """<?xml version="1.0"?>
<!-- a comment -->
<robot name="full">
  <link name="world"/><link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
  <link name="tool0"/><link name="side"/>
  <joint name="fix" type="fixed"><parent link="world"/><child link="base"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.25 0.05 0" rpy="0 0.4 0"/><axis xyz="0 1 0"/>
    <limit effort="1" velocity="2"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.1 0 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.2" velocity="1"/>
  </joint>
  <joint name="jt" type="fixed"><parent link="l3"/><child link="tool0"/>
    <origin xyz="0 0 0.05"/></joint>
  <joint name="js" type="revolute"><parent link="l1"/><child link="side"/>
    <axis xyz="1 0 0"/><mimic joint="j2"/><limit lower="-1" upper="1"/></joint>
</robot>
"""

LINKS = ["a", "b", "c", "d", "e"]
TYPES = ["revolute", "continuous", "prismatic", "fixed", "floating", "planar", "ball", ""]


@st.composite
def urdf_graph(draw: st.DrawFn) -> tuple[str, str | None, str | None]:
    """A random link graph: joints between random (also undeclared, or the same) links, so
    that cycles, self-loops, forests and branches all occur; random values in every field."""
    value = st.one_of(st.sampled_from(NASTY), st.sampled_from(["0", "1", "-1", "0.5"]))
    links = draw(st.lists(st.sampled_from(LINKS), min_size=1, max_size=5, unique=True))
    out = ['<robot name="g">', *(f'<link name="{lk}"/>' for lk in links)]
    for k in range(draw(st.integers(0, 7))):
        parent = draw(st.sampled_from([*LINKS, "ghost"]))
        child = draw(st.sampled_from([*LINKS, "ghost"]))
        attrs = {a: draw(value) for a in ("lower", "upper", "velocity")
                 if draw(st.booleans())}
        limit = "<limit " + " ".join(f'{a}="{_xml(v)}"' for a, v in attrs.items()) + "/>"
        out.append(f'<joint name="j{k}" type="{draw(st.sampled_from(TYPES))}">'
                   f'<parent link="{parent}"/><child link="{child}"/>'
                   f'<origin xyz="{_xml(draw(st.sampled_from(["0 0 0.1", "1 2", "nan 0 0"])))}"/>'
                   f'<axis xyz="{_xml(draw(st.sampled_from(["0 0 1", "0 0 0", "1 0 0"])))}"/>'
                   f"{limit if draw(st.booleans()) else ''}</joint>")
    out.append("</robot>")
    ends = st.one_of(st.none(), st.sampled_from([*LINKS, "ghost"]))
    return "\n".join(out), draw(ends), draw(ends)


def _xml(v: str) -> str:
    return (v.replace("&", "&amp;").replace('"', "&quot;").replace("<", "&lt;")
            .replace("\x00", "").replace("\ud7ff", ""))


def _only_project_errors(fn, *args, **kwargs) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            fn(*args, **kwargs)
        except ZRPError:
            pass


@pytest.fixture(scope="module")
def tmp_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz2")


def _write(tmp_dir: Path, name: str, data: bytes) -> Path:
    path = tmp_dir / name
    path.write_bytes(data)
    return path


@FUZZ
@given(data=st.one_of(mutated(URDF_FULL), mutated(URDF_TEXT)),
       end=st.one_of(st.none(), st.sampled_from(["l2", "l3", "tool0", "side", "nope"])),
       base=st.one_of(st.none(), st.sampled_from(["base", "l1", "world"])))
def test_urdf_import(tmp_dir, data, end, base):
    path = _write(tmp_dir, "arm.urdf", data)
    _only_project_errors(import_urdf, path, end_link=end, base_link=base)
    args = argparse.Namespace(source=str(path), end_link=end, base=base, site=None, unit="mm",
                              name=None)
    _only_project_errors(import_read, args)  # zrp import: format detection, then the reader


@FUZZ
@given(graph=urdf_graph())
def test_urdf_link_graphs(graph):
    text, end, base = graph
    _only_project_errors(import_urdf, text, end_link=end, base_link=base)


def _trajectory_text() -> str:
    t = np.arange(60) / 100.0
    q = np.radians([10, -20, 30, 5, 60, 0]) + 0.3 * np.sin(2.0 * t)[:, None]
    xyz = zrp.forward_kinematics(PUMA, q).position
    two = np.concatenate([xyz[:, None], xyz[:, None] + 1.0], axis=1)
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        p = write_trajectory(Trajectory(t, q, two, ("a", "b"), "base"), Path(tmp) / "t.csv")
        return p.read_text()


TRAJ_TEXT = _trajectory_text()
TRAJ_TQ = "\n".join(line + (",tq" if i == 0 else f",{i * 0.005}")
                    for i, line in enumerate(TRAJ_TEXT.splitlines())) + "\n"


@FUZZ
@given(data=st.one_of(mutated(TRAJ_TEXT), mutated(TRAJ_TQ)), deg=st.booleans(),
       unit=st.sampled_from(["s", "ms", "us"]))
def test_trajectory_csv_reader(tmp_dir, data, deg, unit):
    _only_project_errors(load_trajectory, _write(tmp_dir, "t.csv", data), PUMA, deg=deg,
                         time_unit=unit)


def _checkpoint() -> tuple[bytes, dict, tuple, list[int]]:
    import tempfile
    t = np.linspace(0.0, 1.0, 10)
    q = 0.8 * np.sin(2 * np.pi * t[:, None] + np.arange(6))
    tol = Tolerances.build(PUMA, length=0.05, angle_rad=1e-4)
    with tempfile.TemporaryDirectory() as tmp:
        ck = Path(tmp) / "c.npz"
        monte_carlo_summary(PUMA, q, tol, 600, seed=3, chunk=200, checkpoint=ck)
        data = ck.read_bytes()
    edges = histogram_edges(PUMA, q, tol)
    tasks = chunk_tasks(PUMA, q, tol, 600, seed=3, chunk=200, edges=edges)
    return data, run_identity(tasks), edges, [task.size for task in tasks]


CHECKPOINT, IDENTITY, EDGES, SIZES = _checkpoint()

#: JSON values an edited header may hold.
JSON_VALUES = st.one_of(st.integers(-3, 10), st.sampled_from([None, True, "3", 1.5, [], {},
                                                              [1], [0, 0], [7], 10**30]))


@st.composite
def damaged_checkpoint(draw: st.DrawFn) -> bytes:
    """The checkpoint with random bytes replaced, inserted or cut, or a header field or an
    array edited and the SHA-256 recomputed (what a careful forger does)."""
    data = CHECKPOINT
    if draw(st.booleans()):
        for _ in range(draw(st.integers(1, 4))):
            i = draw(st.integers(0, len(data)))
            j = min(len(data), i + draw(st.integers(0, 64)))
            data = data[:i] + draw(st.binary(max_size=16)) + data[j:]
        return data
    with np.load(io.BytesIO(data)) as z:
        arrays = {k: z[k] for k in z.files}
    head = json.loads(str(arrays.pop("header")))
    arrays.pop("sha256")
    for _ in range(draw(st.integers(1, 3))):
        field = draw(st.sampled_from(["ready", "waiting", "per_chunk", "version", "identity",
                                      "counts", "stats", "elapsed"]))
        if field in arrays:
            a = arrays[field].astype(float if field != "counts" else np.int64)
            if a.size:
                idx = draw(st.integers(0, a.size - 1))
                a.flat[idx] = draw(st.sampled_from([-1, 0, 7, -7, 2**40] if field == "counts"
                                                   else [-1, 0, 1e300, np.nan, 7, -7]))
            arrays[field] = a if draw(st.booleans()) else a[:draw(st.integers(0, len(a)))]
        else:
            head[field] = draw(JSON_VALUES)
    text = json.dumps(head, sort_keys=True)
    buf = io.BytesIO()
    np.savez_compressed(buf, header=np.array(text), sha256=np.array(_content_hash(text, arrays)),
                        **arrays)
    return buf.getvalue()


@FUZZ
@given(data=damaged_checkpoint())
def test_checkpoint_reader(tmp_dir, data):
    path = _write(tmp_dir, "c.npz", data)
    _only_project_errors(load_merge, path, IDENTITY, EDGES, resume=True, overwrite=False,
                         sizes=SIZES)


def test_the_unmutated_inputs_load(tmp_dir):
    """The bases are valid: the fuzzing starts from inputs each reader accepts."""
    imp = import_urdf(_write(tmp_dir, "ok.urdf", URDF_FULL.encode()), end_link="tool0")
    assert imp.joints == ("j1", "j2", "j3")
    traj = load_trajectory(_write(tmp_dir, "ok.csv", TRAJ_TEXT.encode()), PUMA)
    assert traj.n_samples == 60 and traj.point_labels == ("a", "b")
    assert load_trajectory(_write(tmp_dir, "ok2.csv", TRAJ_TQ.encode()), PUMA).n_samples == 60
    state = load_merge(_write(tmp_dir, "ok.npz", CHECKPOINT), IDENTITY, EDGES, resume=True,
                       overwrite=False, sizes=SIZES)
    assert state is not None and state.ready == 3 and state.merged[0].total == 600


def test_the_escapes_the_fuzzer_found(tmp_dir):
    """Its findings, kept: a trajectory header naming a column twice (IndexError) and a
    forged checkpoint whose robot count is NaN (ValueError from int()) are named errors."""
    dup = TRAJ_TEXT.replace("t,point,", "t,point,point,", 1)
    with pytest.raises(zrp.InputError, match="column 'point' appears twice"):
        load_trajectory(_write(tmp_dir, "dup.csv", dup.encode()), PUMA)
    with np.load(io.BytesIO(CHECKPOINT)) as z:
        arrays = {k: z[k] for k in z.files}
    text = str(arrays.pop("header"))
    arrays.pop("sha256")
    arrays["stats"] = arrays["stats"].copy()
    arrays["stats"][0, 0] = np.nan
    buf = io.BytesIO()
    np.savez_compressed(buf, header=np.array(text), sha256=np.array(_content_hash(text, arrays)),
                        **arrays)
    with pytest.raises(zrp.InputError, match="does not match the robots its histograms count"):
        load_merge(_write(tmp_dir, "nan.npz", buf.getvalue()), IDENTITY, EDGES, resume=True,
                   overwrite=False, sizes=SIZES)
