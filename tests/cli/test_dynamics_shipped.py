"""``zrp diagnose-dynamics`` on a shipped URDF whose end link is a point mass (the Staubli
TX40 of ../shared/data/tx40-currents, its README's conversion of the motor-side log)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from zrp.cli import main

_DIR = ("data", "tx40-currents")


def _tx40_log(folder, out, rows: int = 10000, step: int = 5):
    """The first ``rows`` samples (every ``step``-th) as joint angles and torques."""
    p = np.loadtxt(folder / "pos_read_data.csv", delimiter=",", skiprows=1, max_rows=rows)
    c = np.loadtxt(folder / "curr_data.csv", delimiter=",", skiprows=1, max_rows=rows)
    r = np.diag([32.0, 32.0, 45.0, -48.0, 45.0, 32.0])
    r[5, 4] = 32.0
    q = np.linalg.solve(r, p.T).T
    q[:, 1] -= np.pi / 2
    q[:, 2] += np.pi / 2
    tau = c @ r
    t = np.arange(len(q)) * 0.0002
    table = np.column_stack([t, q, tau])[::step]
    head = ",".join(["t [s]", *(f"q{k} [rad]" for k in range(1, 7)),
                     *(f"tau{k} [Nm]" for k in range(1, 7))])
    np.savetxt(out, table, delimiter=",", header=head, comments="", fmt="%.8g")
    return out


def test_tx40_urdf_is_diagnosed(shared_dir, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo's warnings of the re-simulation go to ./MUJOCO_LOG.TXT
    folder = shared_dir.joinpath(*_DIR)
    if not (folder / "tx40_mdh_modified.urdf").is_file():
        pytest.skip("../shared/data/tx40-currents not present")
    log = _tx40_log(folder, tmp_path / "tx40.csv")
    code = main(["diagnose-dynamics", "--model", str(folder / "tx40_mdh_modified.urdf"),
                 "--data", str(log), "--out", str(tmp_path / "rep"), "--seconds", "0.5",
                 "--no-inertial", "--json"])
    assert code == 0
    payload = json.loads(capsys.readouterr().out)
    assert any("link 'link_6'" in n and "point mass" in n for n in payload["notes"])
    assert payload["rms_after_withheld_nm"] is not None
