"""Strict measurement loading and hostile inputs to the diagnosis: clear errors or warnings."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import zrp
from zrp.errors import InputError, OutputExistsError
from zrp.gap import (
    DataWarning,
    GapWarning,
    Injection,
    Measurements,
    diagnose,
    load_measurements,
    noise_floor,
    split_poses,
    synthesize,
)
from zrp.kinematics import uniform_joint_values

PUMA = zrp.load_model("puma")
HEADER = "pose,point,q1,q2,q3,q4,q5,q6,x,y,z\n"


def _write(tmp_path, text, name="d.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _row(pose, point="a", q=(0.1, 0.2, 0.3, 0.4, 0.5, 0.6), xyz=(1.0, 2.0, 3.0)):
    return ",".join([str(pose), point, *map(str, q), *map(str, xyz)]) + "\n"


def test_valid_file_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    meas = synthesize(PUMA, uniform_joint_values(PUMA, 5, rng), Injection(), rng=rng,
                      temp=rng.uniform(18, 22, 5))
    meas.to_csv(tmp_path / "m.csv", deg=True)
    back = load_measurements(tmp_path / "m.csv", PUMA, deg=True)
    np.testing.assert_allclose(back.q, meas.q, atol=1e-12)
    np.testing.assert_allclose(back.xyz, meas.xyz)
    np.testing.assert_allclose(back.temp, meas.temp)
    assert back.point_labels == ("s1", "s2", "s3")
    assert back.lines.tolist()[:2] == [2, 3]
    with pytest.raises(OutputExistsError, match="overwrite"):
        meas.to_csv(tmp_path / "m.csv")


@pytest.mark.parametrize("text, match", [
    ("", "empty"),
    ("   \n\n", "empty"),
    (HEADER, "no data rows"),
    ("pose,q1,q2,q4,q5,q6,x,y,z\n1,0,0,0,0,0,1,2,3\n", "missing column.*q3"),
    ("pose,q1,q2,q3,q4,q5,q6,q7,x,y,z\n", r"unknown column.*q7.*6 joints"),
    ("pose,q1,q2,q3,q4,q5,q6,x,y,z,colour\n", "unknown column.*colour"),
    ("pose,q1,q1,q2,q3,q4,q5,q6,x,y,z\n", "more than once"),
    (HEADER + _row(1) + "2,a,0.1,0.2,abc,0.4,0.5,0.6,1,2,3\n", "line 3: column q3 is 'abc'"),
    (HEADER + _row(1) + "2,a,0.1,0.2,nan,0.4,0.5,0.6,1,2,3\n", "line 3: column q3.*finite"),
    (HEADER + _row(1) + "2,a,0.1,0.2,0.3,0.4,0.5,0.6,1,,3\n", "line 3: column y is empty"),
    (HEADER + "2,a,0.1,0.2,0.3\n", "line 2: 5 fields"),
    (HEADER + _row(1) + _row(1), r"line 3: pose '1' point 'a' was already measured on line 2"),
    (HEADER + _row(1) + _row(1, "b", q=(0.1, 0.2, 0.3, 0.4, 0.5, 0.7)),
     "line 3: pose '1' has q6"),
    (HEADER + _row(1, q=(10, 20, 30, 40, 50, 60)), r"line 2: column q1 is 10.*--deg"),
    (HEADER + ",a,0,0,0,0,0,0,1,2,3\n", "line 2: column pose is empty"),
    ("pose,q1,q2,q3,q4,q5,q6,x,y,z,qw,qx\n", "orientation needs all"),
])
def test_bad_files_name_line_and_column(tmp_path, text, match):
    with pytest.raises(InputError, match=match):
        load_measurements(_write(tmp_path, text), PUMA)


def test_comment_lines_are_not_dropped_silently(tmp_path):
    text = "# tracker export\n" + HEADER + _row(1) + "#" + _row(2) + _row(3)
    with pytest.warns(DataWarning, match=r"1 comment line\(s\).*lines 4"):
        m = load_measurements(_write(tmp_path, text), PUMA)
    assert m.pose_ids == ("1", "3")


def test_missing_file_and_bad_frame(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_measurements(tmp_path / "nope.csv", PUMA)
    with pytest.raises(InputError, match=r"frame.*instrument"):
        load_measurements(_write(tmp_path, HEADER + _row(1)), PUMA, frame="tool")


def test_temperature_and_load_are_checked(tmp_path):
    head = HEADER.strip() + ",temp,load\n"
    with pytest.raises(InputError, match="line 2: column temp is 400"):
        load_measurements(_write(tmp_path, head + _row(1).strip() + ",400,1\n"), PUMA)
    with pytest.raises(InputError, match="line 2: column load is -1"):
        load_measurements(_write(tmp_path, head + _row(1).strip() + ",20,-1\n"), PUMA)
    with pytest.raises(InputError, match="line 3: pose '1' has temp"):
        load_measurements(_write(tmp_path, head + _row(1).strip() + ",20,1\n"
                                 + _row(1, "b").strip() + ",21,1\n"), PUMA)


def test_orientation_columns_warn_that_they_are_unused(tmp_path):
    head = HEADER.strip() + ",qw,qx,qy,qz\n"
    with pytest.warns(DataWarning, match="positions only"):
        m = load_measurements(_write(tmp_path, head + _row(1).strip() + ",1,0,0,0\n"), PUMA)
    assert m.quat.shape == (1, 4)


def _synthetic(n_poses=40, seed=0, **kw):
    rng = np.random.default_rng(seed)
    return synthesize(PUMA, uniform_joint_values(PUMA, n_poses, rng), Injection(), rng=rng, **kw)


def test_single_pose_is_an_error():
    meas = _synthetic(1)
    with pytest.raises(InputError, match="at least 8 distinct poses"):
        diagnose(PUMA, meas)


def test_units_that_do_not_fit():
    meas = _synthetic(40)
    in_metres = Measurements.from_arrays(meas.pose, meas.q, meas.xyz / 1000.0, point=meas.point)
    with pytest.raises(InputError,
                       match=r"units do not fit.*scaled by 1e-03 \(e.g. m instead of mm\)"):
        diagnose(PUMA, in_metres)
    tiny_q = Measurements.from_arrays(meas.pose, np.radians(np.radians(meas.q)), meas.xyz,
                                      point=meas.point)
    with pytest.raises(InputError, match=r"units do not fit|hardly moves"):
        diagnose(PUMA, tiny_q)


def test_wrong_model_is_an_error_not_an_answer():
    """Data of the PUMA diagnosed with the Stanford arm's model: no confident answer."""
    meas = _synthetic(60)
    stanford = zrp.load_model("stanford")
    with pytest.raises(InputError):
        diagnose(stanford, meas)


def test_duplicate_poses_warn_and_feed_the_noise_floor():
    rng = np.random.default_rng(4)
    q = uniform_joint_values(PUMA, 30, rng)
    q = np.concatenate([q, q[:10]])  # ten poses measured twice
    meas = synthesize(PUMA, q, Injection(), rng=rng, noise_sigma=0.02,
                      tool_offsets=((0.0, 0.0, 50.0),))
    nf = noise_floor(meas)
    assert nf.method == "repeats"
    assert 0.01 < nf.sigma < 0.035
    with pytest.warns(DataWarning, match="repeat"):
        d = diagnose(PUMA, meas, seed=1)
    fit_ids, with_ids = set(d.split["fitting"]), set(d.split["withheld"])
    for i in range(10):  # a pose and its repeat stay on the same side
        assert (str(i) in fit_ids) == (str(i + 30) in fit_ids)
    assert not fit_ids & with_ids


def test_rank_deficient_data_are_reported():
    """Joint 3 never moves: its scale cannot be told from its offset; said so, not absorbed."""
    rng = np.random.default_rng(5)
    q = uniform_joint_values(PUMA, 120, rng)
    q[:, 2] = 0.7
    meas = synthesize(PUMA, q, Injection(joint_offset={2: 1e-3}), rng=rng)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        d = diagnose(PUMA, meas, seed=0)
    msgs = [str(x.message) for x in w if issubclass(x.category, GapWarning)]
    assert any("joint 3 does not move" in m for m in msgs)
    assert any("rank-deficient data" in m and "q3.scale" in m for m in msgs)
    limited = d.where["identifiability"]["encoder_scale"]["limited_by_data"]
    assert "q3.scale" in limited
    assert d.top_effect == "joint_offset"


def test_unidentifiable_registration_is_an_error():
    """Only joint 1 turns and one point is measured: the poses lie on a circle."""
    rng = np.random.default_rng(6)
    q = np.zeros((30, 6))
    q[:, 0] = np.linspace(-2, 2, 30)
    q[:, 1:] = 0.3
    meas = synthesize(PUMA, q, Injection(), rng=rng, tool_offsets=((0.0, 0.0, 50.0),))
    with pytest.raises(InputError, match="registration is not identifiable"):
        diagnose(PUMA, meas)


def test_split_is_seeded_and_disjoint():
    meas = _synthetic(50)
    a = split_poses(meas, np.random.default_rng(3))
    b = split_poses(meas, np.random.default_rng(3))
    c = split_poses(meas, np.random.default_rng(4))
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(a[1], c[1])
    assert not set(a[0]) & set(a[1])
    assert sorted(np.concatenate(a[2])) == sorted(a[0])
    with pytest.raises(InputError, match="withheld_fraction"):
        split_poses(meas, np.random.default_rng(0), withheld_fraction=1.5)


def test_unknown_effect_is_an_error():
    with pytest.raises(InputError, match=r"unknown.*valid: joint_offset"):
        diagnose(PUMA, _synthetic(20), effects=("gremlins",))


def test_loader_never_fails_with_anything_but_input_error(tmp_path):
    """Fuzz: any mangling of a valid file is either read or rejected with InputError."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    good = HEADER + "".join(_row(i, p, xyz=(1.0 + i, 2.0, 3.0)) for i in range(3)
                            for p in ("a", "b"))
    junk = st.sampled_from(["", "nan", "inf", "1e400", "x", ",", "\"", "-", "1,2", "\n", " ",
                            "#", "é", "0x10", "1_0", "--1"])

    @settings(max_examples=150, deadline=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(pos=st.integers(0, len(good) - 1), cut=st.integers(0, 5), ins=junk)
    def run(pos, cut, ins):
        text = good[:pos] + ins + good[pos + cut:]
        p = tmp_path / "fuzz.csv"
        p.write_text(text, encoding="utf-8")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DataWarning)
                m = load_measurements(p, PUMA)
        except InputError:
            return
        assert np.all(np.isfinite(m.q)) and np.all(np.isfinite(m.xyz))

    run()


def test_result_dataclasses_validate():
    from zrp.gap import Candidate, Metrics, NoiseFloor

    with pytest.raises(InputError, match="method"):
        NoiseFloor(0.01, "guess")
    with pytest.raises(InputError, match="sigma must be None"):
        NoiseFloor(None, "rigid_links")
    with pytest.raises(InputError, match="finite non-negative"):
        Metrics(float("nan"), 0.1, 0.2, 3)
    with pytest.raises(InputError, match="not in"):
        Candidate("gremlins", (), 0, 0.1, 0.0, 0.5, False)
