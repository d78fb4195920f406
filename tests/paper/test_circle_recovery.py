"""The paper's circle recovered from Tables 2-3 (zrp.paper.placement / inverse), the LE3
readings, and `zrp paper --circle recovered`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.errors import InputError
from zrp.paper.circles import je_cells
from zrp.paper.inverse import fit_cells, local_pinning, recover_circle
from zrp.paper.placement import (
    CELL_LABELS,
    DEFAULT_PLACEMENT,
    PUBLISHED_JE_CELLS,
    RECOVERED,
    TYPO_MASK,
    CirclePlacement,
    placement_path,
)
from zrp.paper.published import half_ulp, le3_readings

ROOT = Path(__file__).resolve().parents[2]


def test_default_placement_is_the_default_circle():
    ex = zrp.run_paper_example(steps=120)
    fit = fit_cells(DEFAULT_PLACEMENT, steps=120)
    np.testing.assert_allclose(fit.ours, je_cells(ex.study), rtol=1e-9)


@pytest.fixture(scope="module")
def recovered():
    return fit_cells(RECOVERED)


def test_recovered_circle_reproduces_the_published_cells(recovered):
    r = recovered.ratio
    assert np.all(np.abs(r[~TYPO_MASK] - 1) <= 0.005)           # every cell within 0.5 %
    digits = sum(abs(o - p) <= half_ulp(p) * 1.0001 for o, p in
                 zip(recovered.ours, PUBLISHED_JE_CELLS, strict=True))
    assert digits >= 41
    # the two likely typos: the circle gives 1/10 and 10x the printed values
    typos = dict(zip([CELL_LABELS[i] for i in np.flatnonzero(TYPO_MASK)], r[TYPO_MASK],
                     strict=True))
    assert typos[(2, "JE1", 0.1)] == pytest.approx(0.1, rel=0.01)
    assert typos[(2, "JE2", 0.1)] == pytest.approx(10.0, rel=0.01)


def test_recovered_table3_follows_the_closed_form_of_the_joint_angles():
    """Independent of the fit: eq (15) of JE_k from max |sin(q_k / 2)| along the path
    (sin(theta/4) = |sin(q_k/2)| sin(alpha/2)) equals the perturbed-FK cells."""
    path = placement_path(RECOVERED)
    fit = fit_cells(RECOVERED)
    for k in range(6):
        s = np.max(np.abs(np.sin(path.q[:, k] / 2)))
        for j, xi in enumerate((0.02, 0.05, 0.07, 0.1)):
            alpha = np.arctan(np.sqrt(2) * xi / 100 / (1 + xi / 100))
            theta = 4 * np.arcsin(s * np.sin(alpha / 2))
            expect = 2 * np.sqrt(2) * np.sin(theta / 2)
            assert fit.ours[24 + 4 * k + j] == pytest.approx(expect, rel=1e-6)


def test_the_held_hand_cannot_reach_the_wrist_cells():
    """With the hand held, joints 4 and 6 stay near their start, so Table 3's JE4 = JE6 =
    4.00E-3 (a half turn) needs q4 and q6 to start near 180 deg: the recovered start with
    the hand held instead misses the cells."""
    held = CirclePlacement(RECOVERED.q0_deg, RECOVERED.azimuth_deg, RECOVERED.elevation_deg,
                           RECOVERED.psi_deg, "held")
    assert fit_cells(held).rms_log > 10 * fit_cells(RECOVERED).rms_log


def test_search_and_pinning_run_and_never_beat_the_preset(recovered):
    res = recover_circle(orientations=("held",), popsize=2, maxiter=2, polish_starts=1,
                         steps=40)
    assert res.best.rms_log >= recovered.rms_log
    assert res.starts[0] is res.best and res.evaluations > 0
    pin = local_pinning(RECOVERED, steps=120)
    assert all(v >= 0 for v in pin.values())
    assert pin["q3_0 (deg)"] < pin["q4_0 (deg)"]       # the elbow is pinned, the wrist is not
    with pytest.raises(InputError, match="orientations"):
        recover_circle(orientations=("spinning",))


def test_placement_validation():
    with pytest.raises(InputError, match="q0_deg"):
        CirclePlacement((0, 0, 0), 0, 0, 0)
    with pytest.raises(InputError, match="orientation"):
        CirclePlacement((0,) * 6, 0, 0, 0, "tumbling")
    v = RECOVERED.vector()
    assert CirclePlacement.from_vector(v, "turning") == RECOVERED


def test_only_seventeen_and_a_half_inches_give_le3():
    rows = le3_readings()
    full = [r for r in rows if r["cells_matching"] == 4]
    assert len(full) == 1 and full[0]["b3_mm"] == pytest.approx(444.5)
    assert next(r for r in rows if r["b3_mm"] == pytest.approx(431.8))["cells_matching"] == 0


def _zrp(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env_path = str(ROOT)
    import os

    env = {**os.environ, "PYTHONPATH": env_path}
    return subprocess.run([sys.executable, "-m", "zrp", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


@pytest.mark.slow
def test_cli_recovered_circle(tmp_path):
    p = _zrp("paper", "--circle", "recovered", "--no-video", "--no-plots", "--json",
             "--out", str(tmp_path / "rec"), cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    import json

    out = json.loads(p.stdout)
    assert out["circle"] == "recovered"
    assert out["cell_status_counts"] == {"match": 53, "reproduced": 5, "discrepancy": 4,
                                         "typo": 2}
    text = (tmp_path / "rec" / "comparison.md").read_text()
    assert "## Both circles" in text and "17.5 in" in text
    bad = _zrp("paper", "--circle", "recovered", "--q0", "0", "0", "0", "0", "90", "0",
               "--out", str(tmp_path / "x"), cwd=tmp_path)
    assert bad.returncode == 2 and "--circle" in bad.stderr and "--q0" in bad.stderr


@pytest.mark.slow
def test_cli_recover_runs_a_tiny_search(tmp_path):
    import json

    p = _zrp("recover", "--popsize", "1", "--maxiter", "1", "--starts", "1", "--laws", "turning",
             "--json", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert len(out["cells"]) == 48 and out["placement"]["orientation"] == "turning"
    assert out["rms_log"] > 0.01            # a tiny search does not find the circle
    bad = _zrp("recover", "--popsize", "0", cwd=tmp_path)
    assert bad.returncode == 2 and "--popsize" in bad.stderr
