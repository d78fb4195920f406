"""Issue 41 finding 5: ``--validate`` on the training log (the same path, a symbolic link, a
hard link, a copy) was reported as "on another log"; now refused naming both options, before
any work. The API refuses a validation log with the training log's samples."""

from __future__ import annotations

import os
import shutil

import numpy as np
import pytest

from zrp.cli import main
from zrp.errors import InputError

HEAD = "t [s],q1 [rad],q2 [rad],tau1 [Nm],tau2 [Nm]\n"


def _log(path, shift=0.0):
    t = np.arange(400) * 1e-3
    table = np.column_stack([t, np.sin(3 * t) + shift, np.cos(t), np.sin(5 * t),
                             np.cos(2 * t)]).tolist()
    rows = [",".join(map(repr, r)) for r in table]
    path.write_text(HEAD + "\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("how", ["same path", "symlink", "hard link", "copy"])
def test_validate_on_the_training_log_is_refused(tmp_path, capsys, how):
    data = _log(tmp_path / "run.csv")
    other = tmp_path / "other.csv"
    if how == "same path":
        other = data
    elif how == "symlink":
        other.symlink_to(data)
    elif how == "hard link":
        os.link(data, other)
    else:
        shutil.copyfile(data, other)
    code = main(["diagnose-dynamics", "--model", "puma", "--data", str(data), "--validate",
                 str(other), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and "--data, --validate:" in err and "of the training log" in err
    assert not (tmp_path / "out" / "diagnosis.json").exists()


def test_the_api_refuses_a_validation_log_with_the_training_samples(tmp_path):
    from mjcf.arm import resolve_arm
    from zrp.gap.dynamics import load_torque_log
    from zrp.gap.dynamics.run import run_dynamics

    log = load_torque_log(_log(tmp_path / "a.csv"))
    again = load_torque_log(shutil.copyfile(tmp_path / "a.csv", tmp_path / "b.csv"))
    with pytest.raises(InputError, match=r"validation_log \(--validate\): its samples are the "
                                         r"training log's"):
        run_dynamics(resolve_arm("puma"), log, validation_log=again)


def test_another_log_is_not_refused():
    from zrp.gap.dynamics.samelog import check_other_arrays

    t = np.arange(5.0)
    check_other_arrays(t, np.zeros((5, 2)), np.zeros((5, 2)), t, np.ones((5, 2)),
                       np.zeros((5, 2)))
