"""Issue 35, finding 11: leftovers of earlier rounds. Each ends in a named error (exit code 2,
one line naming the option or file, no traceback) or in correct behaviour."""

from __future__ import annotations

from pathlib import Path

from zrp.cli import main


def _refused(capsys, argv: list[str], match: str) -> str:
    """Run ``zrp argv`` in-process: exit code 2 and ``match`` in the one-line error."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own refusal of an option value
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert match in err, err
    return err


def test_plan_with_fewer_candidates_than_poses_names_candidates(tmp_path: Path, capsys):
    out = tmp_path / "plan.csv"
    _refused(capsys, ["plan", "--model", "puma", "--poses", "10", "--effects", "joint_offset",
                      "--out", str(out), "--candidates", "1"], "--candidates: 1 candidate")
    assert not out.exists()
