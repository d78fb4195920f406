"""Scale-out on a real Dask cluster: a LocalCluster of two worker processes over TCP on
localhost. Every result computed on it must equal the single-process one bit for bit."""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import zrp
from sim.studies.benchmark import BenchmarkConfig, run_benchmark
from zrp.cli import main
from zrp.cli.cluster import LOCAL_CONFIG, local_cluster
from zrp.gap import Injection, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.manufacturing import Tolerances, allocate_tolerances, chunk_rng, monte_carlo
from zrp.manufacturing.maxima import nonlinear_maxima, trajectory_arrays
from zrp.manufacturing.tolerance import draw_parameters
from zrp.tasks import TaskFailure, map_tasks

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def cluster():
    with local_cluster(2) as client:
        assert client.scheduler.address.startswith("tcp://127.0.0.1:")
        assert len(client.scheduler_info()["workers"]) == 2
        yield client


WORKER_PROBE = """
import os, sys
import zrp  # imports numba here, so a spawned worker imports it too before Dask's env=
from zrp.cli.cluster import executor

def probe(_):
    import dask, numba
    return (numba.config.NUMBA_NUM_THREADS, numba.get_num_threads(),
            dask.config.get("distributed.worker.profile.enabled"), os.getpid())

if __name__ == "__main__":
    before = dict(os.environ)
    with executor(2) as ex:
        rows = list(ex.map(probe, range(4)))
    print(repr((rows, dict(os.environ) == before)))
"""


def test_local_workers_run_numba_on_one_thread_when_main_imports_zrp(tmp_path):
    # the `zrp` script imports numba in __main__; a Nanny's env= came too late for that (each
    # worker ran a 2-thread numba kernel on a 2-core machine), pre-spawn-environ does not
    script = tmp_path / "probe.py"
    script.write_text(WORKER_PROBE)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_NUM_THREADS"}
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         env=env, timeout=300, check=True)
    rows, env_restored = ast.literal_eval(out.stdout.strip().splitlines()[-1])
    assert {r[:3] for r in rows} == {(1, 1, LOCAL_CONFIG["distributed.worker.profile.enabled"])}
    assert env_restored


def _path(n: int, steps: int = 60) -> np.ndarray:
    rng = np.random.default_rng(4)
    t = np.linspace(0, 1, steps)
    return rng.uniform(0.3, 2.0, n) * np.sin(2 * np.pi * t[:, None] + rng.uniform(0, 6, n))


def _same(a, b) -> None:
    for f in ("max_delta_p", "max_angle_rad", "first_order_delta_p", "first_order_angle_rad"):
        x, y = getattr(a, f), getattr(b, f)
        assert (x is None and y is None) or np.array_equal(x, y), f


def test_monte_carlo_on_two_workers_equals_one_process(cluster):
    model = zrp.load_model("puma")
    q = _path(6)
    tol = Tolerances.build(model, length=0.05, angle_rad=1e-4)
    ex = cluster.get_executor(pure=False)
    here = monte_carlo(model, q, tol, 3000, seed=7, chunk=400, first_order=True)
    with distributed.get_task_stream(client=cluster) as stream:
        there = monte_carlo(model, q, tol, 3000, seed=7, chunk=400, first_order=True,
                            executor=ex)
    _same(here, there)
    # the work was shared out: the 8 chunks ran on both workers
    assert len(stream.data) == 8 and len({t["worker"] for t in stream.data}) == 2
    # robots drawn here from an rng and shipped: also identical
    _same(monte_carlo(model, q, tol, 1000, rng=np.random.default_rng(1), chunk=300),
          monte_carlo(model, q, tol, 1000, rng=np.random.default_rng(1), chunk=300,
                      executor=ex))
    # chunk 2 of the seeded run is exactly the robots its own generator draws (independent
    # reference: the kernel on draws made here)
    dx = draw_parameters(tol, 400, "uniform", chunk_rng(7, 2))
    dp, ang = nonlinear_maxima(model, trajectory_arrays(model, q), dx, False)
    assert np.array_equal(there.max_delta_p[800:1200], dp)
    assert np.array_equal(there.max_angle_rad[800:1200], ang)


def test_allocation_verification_on_the_cluster(cluster):
    model = zrp.load_model("puma")
    q = _path(6, steps=40)
    kw = {"max_delta_p": 0.1, "n_search": 500, "n_verify": 2000, "refine": False}
    a = allocate_tolerances(model, q, rng=np.random.default_rng(3), **kw)
    b = allocate_tolerances(model, q, rng=np.random.default_rng(3), **kw,
                            executor=cluster.get_executor(pure=False))
    assert np.array_equal(a.tolerances.values, b.tolerances.values)
    _same(a.verification, b.verification)


def _fails_on_three(x: int) -> int:
    if x == 3:
        raise ValueError("three is not allowed")
    return x * x


def test_a_failed_task_is_reported_with_its_input_and_the_rest_completes(cluster):
    ex = cluster.get_executor(pure=False)
    got = dict(map_tasks(_fails_on_three, [1, 2, 3, 4], ex, capture=True,
                         describe=lambda x: f"x={x}"))
    assert {k: v for k, v in got.items() if not isinstance(v, TaskFailure)} == \
        {0: 1, 1: 4, 3: 16}
    fail = got[2]
    assert isinstance(fail, TaskFailure) and fail.task == "x=3"
    assert "ValueError: three is not allowed" in fail.error
    with pytest.raises(ValueError, match="three"):
        dict(map_tasks(_fails_on_three, [1, 3], cluster.get_executor(pure=False)))


def _strip(scores):
    return [{k: v for k, v in s.to_dict().items() if k not in ("sim_s", "diag_s")}
            for s in scores]


def test_blind_benchmark_on_two_workers_equals_one_process(cluster, puma, tmp_path):
    cfg = BenchmarkConfig(scenarios=3, seed=5, poses=40, none_fraction=0.0,
                          pair_fraction=0.0)
    a = run_benchmark(puma, cfg, tmp_path / "a", progress=False)
    b = run_benchmark(puma, cfg, tmp_path / "b", progress=False,
                      executor=cluster.get_executor(pure=False))
    assert _strip(a.scores) == _strip(b.scores) and not b.failures
    for f in sorted((tmp_path / "a/measurements").glob("*.csv")):
        assert f.read_bytes() == (tmp_path / "b/measurements" / f.name).read_bytes()


def _fleet(folder: Path) -> Path:
    model = zrp.load_model("puma")
    folder.mkdir()
    for i, inj in enumerate([Injection(joint_offset={2: 2e-3}), Injection(),
                             Injection(joint_offset={3: 1e-3})]):
        rng = np.random.default_rng(i)
        q = uniform_joint_values(model, 40, rng)
        synthesize(model, q, inj, rng=rng, noise_sigma=0.02).to_csv(folder / f"r{i}.csv")
    (folder / "r9.csv").write_text("pose,point,q1\n0,a,1\n", encoding="utf-8")
    return folder


def test_fleet_diagnosis_on_the_cluster(cluster, tmp_path, capsys):
    data = str(_fleet(tmp_path / "fleet") / "*.csv")
    base = ["diagnose", "--model", "puma", "--data", data, "--no-plots", "--json",
            "--no-progress", "--tolerance", "0.5"]
    # a robot whose file is broken is reported with its input; the others are diagnosed
    assert main([*base, "--out", str(tmp_path / "here")]) == 1
    here = json.loads(capsys.readouterr().out)
    assert main([*base, "--out", str(tmp_path / "there"), "--scheduler",
                 cluster.scheduler.address]) == 1
    there = json.loads(capsys.readouterr().out)
    assert here["rows"] == there["rows"]
    assert [f["task"].split()[0] for f in there["failures"]] == ["r9"]
    assert "missing column" in there["failures"][0]["error"]
    # the injected joint offsets are found and dominate; r1 (no effect) is within tolerance
    rows = {r["robot"]: r for r in there["rows"]}
    assert rows["r0"]["top_effect"] == "joint_offset" and rows["r0"]["top_joints"] == [2]
    assert rows["r2"]["top_effect"] == "joint_offset" and rows["r2"]["top_joints"] == [3]
    assert there["dominant_effect"] == "joint_offset"
    assert there["out_of_tolerance"] == ["r0", "r2"] and not rows["r1"]["out_of_tolerance"]
    assert (tmp_path / "there/robots/r0/report.md").exists()
    # an interrupted run resumes: robots already done are read back, not recomputed
    (tmp_path / "there/robots/r2/report.md").unlink()
    assert main([*base, "--out", str(tmp_path / "there"), "--resume", "--scheduler",
                 cluster.scheduler.address]) == 1
    again = json.loads(capsys.readouterr().out)
    assert again["resumed"] == 2 and again["rows"] == there["rows"]
    # without --resume or --force the finished robots' files are never replaced
    assert main([*base, "--out", str(tmp_path / "there")]) == 2
    assert "--force" in capsys.readouterr().err
    # the fleet's options are refused for a single file rather than ignored
    one = str(tmp_path / "fleet/r0.csv")
    assert main(["diagnose", "--model", "puma", "--data", one, "--out", str(tmp_path / "one"),
                 "--workers", "2"]) == 2
    assert "--workers: only for a fleet" in capsys.readouterr().err


def test_tolerance_cli_on_the_cluster_equals_in_process(cluster, capsys):
    base = ["tolerance", "-n", "3000", "--steps", "40", "--no-progress", "--json"]
    assert main(base) == 0
    here = json.loads(capsys.readouterr().out)
    assert main([*base, "--scheduler", cluster.scheduler.address]) == 0
    there = json.loads(capsys.readouterr().out)
    for k in ("max_delta_p_mm", "max_angle_rad", "p99_max_delta_p", "first_order"):
        assert here[k] == there[k]
    # reduced on the workers: histograms merged in chunk order, so even the mean is bit-equal
    assert main([*base, "--reduce"]) == 0
    here = json.loads(capsys.readouterr().out)
    assert main([*base, "--reduce", "--scheduler", cluster.scheduler.address]) == 0
    there = json.loads(capsys.readouterr().out)
    assert here["reduced_on_workers"] and there["reduced_on_workers"]
    for k in ("max_delta_p_mm", "max_angle_rad", "p99_max_delta_p", "p99_max_delta_p_ci95",
              "first_order", "mc_max_over_worst_case_p"):
        assert here[k] == there[k], k
    with pytest.raises(SystemExit) as exit_:  # a checked option type: argparse refuses it
        main([*base, "--workers", "0"])
    assert exit_.value.code == 2
    assert "--workers" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_a_stopped_local_cluster_run_keeps_its_checkpoint_and_prints_no_traceback(tmp_path,
                                                                                   how):
    # Ctrl-C in a terminal sends SIGINT to the whole process group (the command and its
    # workers); a batch scheduler's time limit sends SIGTERM
    import signal
    import time

    ck = tmp_path / "mc.npz"
    cmd = [sys.executable, "-m", "zrp", "tolerance", "-n", "20000000", "--workers", "2",
           "--checkpoint", str(ck), "--no-progress"]
    # SIGINT at its default, as a terminal's shell starts a command: an ignored SIGINT is
    # inherited, and the whole suite's process may have it ignored by then
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, cwd=Path(__file__).resolve().parents[2],
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if ck.exists():
                head = json.loads(str(np.load(ck)["header"]))
                if head["ready"] >= 2:
                    break
            time.sleep(0.2)
        if how == "ctrl-c":
            os.killpg(proc.pid, signal.SIGINT)
        else:
            proc.send_signal(signal.SIGTERM)
        # a worker busy compiling its kernels (a cold numba cache on a fresh machine) takes
        # its time to stop; what is checked is how it stops, not how fast
        _, err = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode != 0 and "Traceback" not in err, err[-2000:]
    assert "interrupted" in err and "--resume continues it" in err
    head = json.loads(str(np.load(ck)["header"]))
    assert head["ready"] >= 2 and head["identity"]["robots"] == "20000000"
