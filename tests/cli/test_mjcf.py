"""``zrp mjcf``: write MJCF models and import arms from MJCF/URDF."""

from __future__ import annotations

import mujoco
import numpy as np

import zrp
from zrp.cli.app import main


def test_writes_perturbed_model_and_refuses_overwrite(tmp_path, capsys):
    out = tmp_path / "puma.xml"
    assert main(["mjcf", "--perturb", "JE2=0.1", "--inertia", "puma560", "--actuators",
                 "--out", str(out)]) == 0
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.njnt == 6 and m.nu == 12
    assert abs(m.jnt_axis[1][0]) > 0  # the perturbation tilted joint 2's axis
    assert main(["mjcf", "--out", str(out)]) == 2
    assert "exists" in capsys.readouterr().err


def test_import_round_trip_to_toml(tmp_path):
    xml = tmp_path / "puma.xml"
    toml = tmp_path / "puma.toml"
    assert main(["mjcf", "--out", str(xml)]) == 0
    assert main(["mjcf", "--from", str(xml), "--out", str(toml)]) == 0
    back = zrp.load_model(toml)
    nominal = zrp.load_model("puma")
    np.testing.assert_allclose(back.bodies, nominal.bodies, atol=1e-9)
    np.testing.assert_allclose(back.axes, nominal.axes, atol=1e-15)


def test_bad_perturbation_is_a_clear_error(tmp_path, capsys):
    assert main(["mjcf", "--perturb", "JE2:0.1", "--out", str(tmp_path / "x.xml")]) == 2
    assert "NAME=XI" in capsys.readouterr().err


def test_an_unknown_end_body_names_the_option(tmp_path, capsys):
    # the end body is --end-link (was --body, issue 33): the error names the option typed
    xml = tmp_path / "puma.xml"
    assert main(["mjcf", "--out", str(xml)]) == 0
    capsys.readouterr()
    assert main(["mjcf", "--from", str(xml), "--end-link", "nope",
                 "--out", str(tmp_path / "x.toml")]) == 2
    err = capsys.readouterr().err
    assert "--end-link: no body named 'nope'" in err and "body:" not in err
