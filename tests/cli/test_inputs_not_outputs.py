"""Issue 35, finding 12d: ``excite --out`` equal to ``--model`` with ``--force`` replaced the
model. A command's input files are never its outputs, even with --force (zrp.output.inputs):
walked over every command's file options (each is an input or a declared output) and over
the commands that read a file and write one; the same file under another name (a hard link,
a relative spelling) is caught; an output folder's pruning leaves an input alone."""

from __future__ import annotations

import argparse
import os
import re

import pytest

from zrp.cli.app import _WRITTEN, build_parser, main
from zrp.errors import OutputIsInputError
from zrp.output import OutputDir, reading, write_text

#: the options that name files a command reads (any other file option must be declared
#: written: app._WRITTEN or the command's set_defaults(writes=...))
INPUTS = {"calibration", "commands", "data", "diagnosis", "joints", "mjcf", "model",
          "model_file", "poses", "source", "targets", "transmission", "truth", "urdf",
          "validate"}
_FILEISH = ("FILE", "DIR", "CSV", "TOML", "NPZ", "PNG", "XML", "JSON", "MP4")


def _commands():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices.items()


def test_every_file_option_of_every_command_is_an_input_or_a_declared_output():
    unknown = []
    for name, p in _commands():
        written = _WRITTEN | set(p.get_default("writes") or ())
        for a in p._actions:
            meta = str(a.metavar or "")
            if a.nargs == 0 or not (re.search(r"\.[A-Za-z]", meta)
                                    or any(k in meta.upper() for k in _FILEISH)):
                continue
            if a.dest not in written and a.dest not in INPUTS:
                unknown.append(f"{name} {a.option_strings or a.dest}")
    assert not unknown, f"classify these options (input or written): {unknown}"
    for name, p in _commands():  # measure writes its truth file; verify reads one
        assert ("truth" in (p.get_default("writes") or ())) == (name == "measure"), name


@pytest.fixture
def inputs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["export", "--model", "puma", "--to", "urdf", "--out", "arm.urdf"]) == 0
    assert main(["mjcf", "--model", "puma", "--inertia", "rods", "--out", "arm.xml"]) == 0
    assert main(["export", "--model", "puma", "--to", "toml", "--out", "arm.toml"]) == 0
    return tmp_path


@pytest.mark.parametrize(("argv", "target"), [
    (["import", "arm.urdf", "--out", "arm.urdf"], "arm.urdf"),
    (["import", "arm.xml", "--out", "./arm.xml"], "arm.xml"),
    (["mjcf", "--from", "arm.xml", "--out", "arm.xml"], "arm.xml"),
    (["export", "--model", "arm.toml", "--to", "toml", "--out", "arm.toml"], "arm.toml"),
    (["export", "--model", "arm.toml", "--to", "urdf", "--out", "link.urdf"], "arm.toml"),
    (["mjcf", "--model", "arm.toml", "--out", "link.urdf"], "arm.toml"),
    (["excite", "--model", "arm.xml", "--q0", "0", "0", "0", "0", "0", "0", "--iterations", "1",
      "--candidates", "1", "--out", "link.urdf"], "arm.xml"),
])
def test_no_command_writes_onto_its_input_even_with_force(inputs, argv, target, capsys):
    if "link.urdf" in argv:  # the input under another name: a hard link to it
        os.link(inputs / target, inputs / "link.urdf")
    before = (inputs / target).read_bytes()
    assert main([*argv, "--force"]) == 2
    err = capsys.readouterr().err
    assert "this command's input" in err or "is the model file" in err, err
    assert "Traceback" not in err and (inputs / target).read_bytes() == before


def test_a_folder_output_that_would_replace_an_input_is_refused_before_any_work(tmp_path):
    model = tmp_path / "run" / "corrected.xml"
    model.parent.mkdir()
    model.write_text("<mujoco/>")
    with reading([("--model corrected.xml", str(model))]):
        with pytest.raises(OutputIsInputError, match=r"--model corrected\.xml"):
            write_text(model, "x", overwrite=True)
        with pytest.raises(OutputIsInputError):  # its declared names include the input
            with OutputDir(tmp_path / "run", overwrite=True, names=("report.md",
                                                                   "corrected.xml"), prune=True):
                pytest.fail("refused before any work")
        with OutputDir(tmp_path / "run", overwrite=True, names=("report.md",)) as out:
            out.write_text("report.md", "r")
        with pytest.raises(OutputIsInputError):  # a name written without being declared
            with OutputDir(tmp_path / "run", overwrite=True) as out:
                out.write_text("corrected.xml", "x")
    assert model.read_text() == "<mujoco/>" and (tmp_path / "run" / "report.md").exists()
    write_text(model, "x", overwrite=True)  # outside the command, a file like any other
    assert model.read_text() == "x"
