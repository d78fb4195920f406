"""Issue 41 finding 7: ``zrp notebooks --timeout 2`` printed the interrupted kernel's ZMQError
traceback on the terminal (the kernel's own stderr, written as it shuts down); now the
kernel's stderr goes to a file and the run ends in the one named error."""

from __future__ import annotations

import pytest

from zrp.cli import main


def test_the_kernels_stderr_is_not_the_terminal(tmp_path, capsys, monkeypatch):
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("jupytext")
    from nbclient.exceptions import CellTimeoutError

    seen = {}

    def execute(self, **kwargs):
        seen.update(kwargs)
        raise CellTimeoutError("timed out")

    monkeypatch.setattr(nbclient.NotebookClient, "execute", execute)
    code = main(["notebooks", "kinematics", "--timeout", "2", "--out", str(tmp_path / "nb")])
    err = capsys.readouterr().err
    assert code == 2 and "ran over the time limit of 2 s" in err and "Traceback" not in err
    assert seen.get("stderr") is not None and hasattr(seen["stderr"], "fileno")


def test_a_short_timeout_is_one_named_error(tmp_path, capfd):
    pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    code = main(["notebooks", "kinematics", "--timeout", "2", "--out", str(tmp_path / "nb")])
    err = capfd.readouterr().err
    assert code == 2 and "over the time limit of 2 s" in err
    assert "Traceback" not in err and "ZMQError" not in err
