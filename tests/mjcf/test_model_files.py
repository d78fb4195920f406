"""Issue 35, finding 7: a file a model names that is a FIFO hung every MJCF/URDF reader (MuJoCo
opens assets itself). Every loader of the mjcf layer, and each command that reads a model,
refuses it by name in bounded time; each runs in a subprocess with a time limit, so a
regression fails instead of hanging the suite. Also: the toolkit's stale temporary files."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from zrp.output import write_text
from zrp.output.atomic import STALE_AFTER_S

BODY = ('<worldbody><body><joint type="hinge"/><geom type="mesh" mesh="m"/>'
        '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></worldbody>')
ROOT = Path(__file__).resolve().parents[2]


def _models(tmp: Path) -> dict[str, Path]:
    os.mkfifo(tmp / "fifo.stl")
    (tmp / "meshes").mkdir()
    os.mkfifo(tmp / "meshes" / "deep.stl")
    os.mkfifo(tmp / "inc.xml")
    files = {
        "mesh": f'<mujoco><asset><mesh name="m" file="fifo.stl"/></asset>{BODY}</mujoco>',
        "meshdir": ('<mujoco><compiler meshdir="meshes"/><asset><mesh name="m" '
                    f'file="deep.stl"/></asset>{BODY}</mujoco>'),
        "include": f'<mujoco><include file="inc.xml"/>{BODY}</mujoco>',
        "texture": ('<mujoco><asset><texture name="t" type="2d" file="fifo.stl"/>'
                    f'<mesh name="m" vertex="0 0 0 1 0 0 0 1 0 0 0 1"/></asset>{BODY}</mujoco>'),
    }
    out = {}
    for k, text in files.items():
        out[k] = tmp / f"{k}.xml"
        out[k].write_text(text)
    out["urdf"] = tmp / "arm.urdf"
    out["urdf"].write_text(
        '<robot name="r"><link name="a"><visual><geometry><mesh filename="fifo.stl"/>'
        '</geometry></visual><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" '
        'ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')
    return out


LOADERS = {
    "load_shipped": "import mjcf; mjcf.load_shipped(P)",
    "load_shipped_spec": "import mjcf; mjcf.load_shipped_spec(P)",
    "load_mujoco_model": "from mjcf.importer import load_mujoco_model; load_mujoco_model(P)",
    "xml_string": ("import os; from mjcf.importer import load_mujoco_model; "
                   "os.chdir(os.path.dirname(P)); load_mujoco_model(open(P).read())"),
    "load_arm": "from mjcf.arm import load_arm; load_arm(P)",
}


def _run(code: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True,
                          text=True, timeout=90, env={**os.environ, "PYTHONPATH": str(ROOT)})


@pytest.mark.parametrize("kind", ["mesh", "meshdir", "include", "texture"])
def test_every_loader_refuses_a_fifo_asset(tmp_path, kind):
    p = _models(tmp_path)[kind]
    code = "\n".join(
        f"try:\n    P = {str(p)!r}; {stmt}\nexcept Exception as e:\n"
        f"    print({name!r}, type(e).__name__, 'FIFO' in str(e))"
        for name, stmt in LOADERS.items())
    res = _run(code, tmp_path)
    lines = sorted(res.stdout.split("\n")[:-1])
    assert lines == sorted(f"{n} {'InputError' if n == 'load_arm' else 'MJCFImportError'} True"
                           for n in LOADERS), res.stdout + res.stderr


def test_a_urdf_fifo_mesh_is_refused(tmp_path):
    p = _models(tmp_path)["urdf"]
    res = _run(f"import mjcf\ntry:\n    mjcf.load_shipped({str(p)!r})\nexcept Exception as e:"
               "\n    print(type(e).__name__, 'FIFO' in str(e))", tmp_path)
    assert res.stdout.strip() == "MJCFImportError True", res.stderr


@pytest.mark.parametrize("argv", [
    ["diagnose-dynamics", "--model", "M", "--data", "log.csv", "--out", "o"],
    ["excite", "--model", "M", "--q0", "0", "--out", "ex.csv"],
    ["plan", "--model", "puma", "--mjcf", "M", "--poses", "10", "--effects",
     "joint_compliance", "--out", "p.csv"],
])
def test_commands_refuse_a_fifo_mesh_in_bounded_time(tmp_path, argv):
    p = _models(tmp_path)["mesh"]
    # a log that reads (a moving joint, a torque that is data): the model is what is refused
    (tmp_path / "log.csv").write_text("t [s],q1 [rad],tau1 [N m]\n" + "".join(
        f"{0.001 * i:.3f},{0.01 * i:.4f},{(i * 37 % 11) * 0.1:.1f}\n" for i in range(300)))
    argv = [str(p) if a == "M" else a for a in argv]
    t0 = time.monotonic()
    res = subprocess.run([sys.executable, "-m", "zrp", *argv], cwd=tmp_path,
                         capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert res.returncode == 2 and "FIFO" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr and time.monotonic() - t0 < 120


def test_stale_temporaries_are_removed_at_the_next_write(tmp_path):
    """Finding 12 (own temporaries): kill -9 mid-write left .zrp-*.tmp.* for ever."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".zrp-{dead.pid}-1.tmp.csv"
    stale.write_bytes(b"x" * 1000)
    live = tmp_path / f".zrp-{os.getpid()}-2.tmp.csv"  # a writer of this process, running
    live.write_text("x")
    old = tmp_path / f".zrp-{os.getpid()}-3.tmp"
    old.write_text("x")
    os.utime(old, (time.time() - STALE_AFTER_S - 10,) * 2)
    others = [tmp_path / ".zrp-notmine.tmp.csv", tmp_path / "data.csv"]
    for o in others:
        o.write_text("keep")
    write_text(tmp_path / "out.csv", "a\n")
    assert not stale.exists() and not old.exists() and live.exists()
    assert all(o.read_text() == "keep" for o in others)
