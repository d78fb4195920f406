"""Model validation and the TOML model file: every documented error on its bad input."""

import warnings

import numpy as np
import pytest

import zrp
from zrp import EndEffector, Joint, Manipulator, ModelError, ModelFileError

PUMA_TEXT = (zrp.builtin_models()["puma"]).read_text()


def test_builtin_puma_is_table_1(puma):
    np.testing.assert_array_equal(puma.axes, [[0, 0, 1], [0, 1, 0], [0, 1, 0], [0, 0, 1],
                                              [0, -1, 0], [0, 0, -1]])
    np.testing.assert_array_equal(puma.bodies, [[0, 0, 0], [0, 254, 0], [431.8, 0, 0],
                                                [0, 0, -431.8], [0, 0, 0], [0, 0, 0],
                                                [0, 0, -127]])
    assert puma.length_unit == "mm"
    assert puma.joint_names == ("q1", "q2", "q3", "q4", "q5", "q6")


def test_model_is_immutable(puma):
    with pytest.raises(ValueError, match="read-only"):
        puma.axes[0, 0] = 1.0
    with pytest.raises(AttributeError):
        puma.name = "x"  # type: ignore[misc]


def test_zero_axis_is_an_error_naming_the_joint():
    with pytest.raises(ModelError, match=r"joint 2 axis: is a zero vector"):
        Manipulator.from_arrays([[0, 0, 1], [0, 0, 0]], np.zeros((3, 3)), axial=[0, 0, 1],
                                transverse=[1, 0, 0])


def test_axis_slightly_off_unit_is_normalised_with_warning():
    with pytest.warns(zrp.ZRPWarning, match="joint 1 axis: norm"):
        j = Joint("revolute", [0, 0, 1.0001], [0, 0, 0], index=1)
    assert np.linalg.norm(j.axis) == pytest.approx(1.0, abs=1e-15)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Joint("revolute", [0, 0, 1 + 1e-14], [0, 0, 0])  # rounding-level: silent


def test_axis_far_from_unit_is_an_error():
    with pytest.raises(ModelError, match=r"joint 1 axis: has norm 2.*expected a unit vector"):
        Joint("revolute", [0, 0, 2], [0, 0, 0], index=1)


@pytest.mark.parametrize("bad", [[0, 0], [0, 0, 0, 1], [[1, 2, 3]], "abc", [0, np.nan, 1]])
def test_bad_vectors_are_named(bad):
    with pytest.raises(ModelError, match="joint 4 body"):
        Joint("revolute", [0, 0, 1], bad, index=4)


def test_bad_joint_type_lists_choices():
    with pytest.raises(ModelError, match=r"'rotary' is not a joint type.*revolute.*prismatic"):
        Joint("rotary", [0, 0, 1], [0, 0, 0])  # type: ignore[arg-type]


def test_axial_and_transverse_must_be_perpendicular():
    with pytest.raises(ModelError, match="perpendicular"):
        EndEffector([0, 0, 0], [0, 0, 1], [0, 0.6, 0.8])


def test_manipulator_needs_joints_and_shapes():
    with pytest.raises(ModelError, match="at least one joint"):
        Manipulator((), EndEffector([0, 0, 0], [0, 0, 1], [1, 0, 0]))
    with pytest.raises(ModelError, match=r"bodies: expected shape \(3, 3\)"):
        Manipulator.from_arrays(np.eye(2, 3), np.zeros((2, 3)), axial=[0, 0, 1],
                                transverse=[1, 0, 0])


def test_toml_round_trip_is_exact(rng):
    model = zrp.testing.random_arm(rng, 7, 0.4)
    back = zrp.loads_model(zrp.dumps_model(model))
    zrp.testing.assert_manipulator_close(back, model, atol=0.0)


def test_save_model_refuses_to_overwrite(tmp_path, puma):
    path = tmp_path / "m.toml"
    zrp.save_model(puma, path)
    with pytest.raises(zrp.OutputExistsError, match="overwrite=True"):
        zrp.save_model(puma, path)
    zrp.save_model(puma, path, overwrite=True)
    assert zrp.load_model(path).n == 6


def _line_of(text, needle):
    return next(i for i, s in enumerate(text.splitlines(), 1) if needle in s)


def test_file_errors_name_the_line():
    bad = PUMA_TEXT.replace("axis = [0, 1, 0]", "axis = [0, 0, 0]", 1)
    line = _line_of(bad, "axis = [0, 0, 0]")
    with pytest.raises(ModelFileError, match=rf"line {line}: joint 2 axis: is a zero vector"):
        zrp.loads_model(bad, "x.toml")
    bad = PUMA_TEXT.replace('type = "revolute"', 'type = "spherical"', 1)
    with pytest.raises(ModelFileError, match=r"line \d+: joint 1 type: 'spherical'"):
        zrp.loads_model(bad)
    bad = PUMA_TEXT.replace("transverse = [0, -1, 0]", "transverse = [0, 0, -1]")
    with pytest.raises(ModelFileError, match=r"line \d+: end_effector axial and transverse"):
        zrp.loads_model(bad)


def test_file_structure_errors():
    with pytest.raises(ModelFileError, match="not valid TOML"):
        zrp.loads_model("name = \n")
    with pytest.raises(ModelFileError, match=r"no \[\[joint\]\] tables"):
        zrp.loads_model('name = "x"\n[end_effector]\nbody=[0,0,0]\naxial=[0,0,1]\n'
                        'transverse=[1,0,0]\n')
    with pytest.raises(ModelFileError, match=r"missing \[end_effector\]"):
        zrp.loads_model('[[joint]]\ntype="revolute"\naxis=[0,0,1]\nbody=[0,0,0]\n')
    with pytest.raises(ModelFileError, match=r"joint 1: missing 'body'"):
        zrp.loads_model('[[joint]]\ntype="revolute"\naxis=[0,0,1]\n[end_effector]\n'
                        'body=[0,0,0]\naxial=[0,0,1]\ntransverse=[1,0,0]\n')
    with pytest.raises(ModelFileError, match=r"line 4: joint 1: unknown key 'axes'"):
        zrp.loads_model('[[joint]]\ntype="revolute"\nbody=[0,0,0]\naxes=[0,0,1]\n'
                        '[end_effector]\nbody=[0,0,0]\naxial=[0,0,1]\ntransverse=[1,0,0]\n')
    with pytest.raises(ModelFileError, match="unknown key 'units'"):
        zrp.loads_model('units = "mm"\n' + PUMA_TEXT)
    with pytest.raises(ModelFileError, match="built-in models are"):
        zrp.load_model("no_such_model.toml")


def test_shared_irb120_model_loads(shared_dir):
    model = zrp.load_model(shared_dir / "data" / "irb120-lasertracker" / "irb120.toml")
    assert model.n == 6
    np.testing.assert_allclose(zrp.forward_kinematics(model, np.zeros(6)).position,
                               [374.0, 0.0, 630.0])
