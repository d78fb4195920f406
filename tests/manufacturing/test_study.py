"""One-at-a-time study: agreement with the NumPy deviation path, tables, joint-path inputs."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from zrp import load_model, puma_circle_ik
from zrp.errors import InputError, OutputExistsError, ZRPWarning
from zrp.manufacturing.deviation import trajectory_deviation
from zrp.manufacturing.perturb import Perturbation
from zrp.manufacturing.study import (
    PAPER_PARAMETERS,
    PAPER_XI,
    JointPath,
    fit_linearity,
    load_joint_csv,
    one_at_a_time,
)
from zrp.paper.scenario import circle_joint_path

SHARED = Path(__file__).resolve().parents[2].parent / "shared"


def _path(n: int, steps: int = 150, seed: int = 0) -> JointPath:
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 3.0, steps)
    q = rng.uniform(0.3, 2.5, n) * np.sin(2 * np.pi * t[:, None] / 3 + rng.uniform(0, 6, n))
    return JointPath(t, q, "test path")


def test_study_matches_reference_deviation():
    model = load_model("puma")
    path = _path(6)
    st = one_at_a_time(model, path)
    assert st.delta_p.shape == (10, 9, 150)
    for name in ("LE3", "JE2", "JE6"):
        for xi in (-0.07, 0.1):
            dev = trajectory_deviation(model, Perturbation.single(name, xi), path.q, path.t)
            i, j = st.index(name), list(PAPER_XI).index(xi)
            np.testing.assert_allclose(st.delta_p[i, j], dev.delta_p, rtol=1e-10, atol=1e-13)
            np.testing.assert_allclose(st.delta_r[i, j], dev.delta_r, rtol=1e-8, atol=1e-15)
            np.testing.assert_allclose(st.angle_rad[i, j], dev.angle_rad, rtol=1e-8,
                                       atol=1e-15)


def test_link_columns_are_trajectory_independent_and_exact():
    model = load_model("puma")
    for seed in (1, 2):
        st = one_at_a_time(model, _path(6, seed=seed), ("LE2", "LE3", "LE4", "LE7"))
        lengths = np.linalg.norm(model.bodies[[1, 2, 3, 6]], axis=1)
        expected = np.abs(st.xi_percent)[None, :] / 100 * lengths[:, None]
        np.testing.assert_allclose(st.max_delta_p, expected, rtol=1e-9, atol=1e-12)
        assert st.max_angle_rad.max() < 1e-15
        for lin in st.linearity().values():
            assert lin.r2 == pytest.approx(1.0, abs=1e-12)


def test_axis_columns_linear_for_small_xi():
    model = load_model("puma")
    st = one_at_a_time(model, _path(6, seed=3), [f"JE{k}" for k in range(1, 7)],
                       (-0.02, -0.01, 0.0, 0.01, 0.02))
    for lin in st.linearity("delta_p").values():
        assert lin.r2 > 0.99999
    for lin in st.linearity("delta_r").values():
        assert lin.r2 > 0.99999
        assert lin.slope_pos == pytest.approx(lin.slope_neg, rel=1e-3)


def test_tables_and_overwrite(tmp_path):
    model = load_model("puma")
    st = one_at_a_time(model, _path(6), PAPER_PARAMETERS, (0.0, 0.02, 0.1))
    header, rows = st.table("delta_p", ["LE2", "JE1"], [0.02, 0.1])
    assert header == ["xi_percent", "LE2", "JE1"]
    assert rows[0][1] == pytest.approx(0.0508, rel=1e-12)
    csv_path = st.write_table(tmp_path / "t.csv")
    md_path = st.write_table(tmp_path / "t.md", "delta_r", ["JE1"])
    assert csv_path.read_text().splitlines()[0].startswith("xi_percent,LE2")
    assert "sign(0) = 0 for link vectors" in md_path.read_text()
    with pytest.raises(OutputExistsError):
        st.write_table(tmp_path / "t.csv")
    with pytest.raises(InputError, match="not a level"):
        st.table(xi_rows=[0.05])


def test_default_circle_is_the_examples_setup():
    model = load_model("puma")
    path = circle_joint_path(model, steps=120)
    ik = puma_circle_ik(steps=120)
    np.testing.assert_allclose(path.q, ik.q, atol=1e-12)
    assert path.ik_position_error < 1e-9


def test_joint_csv_roundtrip_and_errors(tmp_path):
    model = load_model("puma")
    path = _path(6, steps=20)
    f = tmp_path / "j.csv"
    rows = ["t_s,q1,q2,q3,q4,q5,q6,extra"] + [
        ",".join(repr(float(x)) for x in (t, *q, 0.0)) for t, q in zip(path.t, path.q,
                                                                        strict=True)]
    f.write_text("\n".join(rows))
    back = load_joint_csv(f, model)
    np.testing.assert_array_equal(back.q, path.q)
    bad = tmp_path / "bad.csv"
    bad.write_text("t,q1\n0,1\n1,2\n")
    with pytest.raises(InputError, match="line 2"):
        load_joint_csv(bad, model)


def test_errors():
    model = load_model("puma")
    path = _path(6)
    with pytest.raises(InputError, match="LE8"):
        one_at_a_time(model, path, ["LE8"])
    with pytest.raises(InputError, match="eq 8"):
        one_at_a_time(model, path, ["LE2"], [1.0])
    with pytest.raises(InputError, match="duplicate"):
        one_at_a_time(model, path, ["LE2", "le2"])
    with pytest.raises(InputError, match="path"):
        one_at_a_time(model, path.q)
    with pytest.raises(InputError, match="q0"):
        circle_joint_path(load_model("scara"))
    with pytest.raises(InputError, match="t: expected shape"):
        JointPath(np.zeros(3), np.zeros((4, 6)))
    with pytest.raises(InputError, match="two distinct"):
        fit_linearity([0.1, -0.1], [1.0, 1.0])
    with pytest.warns(ZRPWarning, match="sign_zero_axes = 0"):
        st = one_at_a_time(model, path, ["JE3"], [0.1], sign_zero_axes=0)
    assert st.max_delta_p.max() == 0.0


@pytest.mark.skipif(not (SHARED / "data/irb120-lasertracker/irb120.toml").exists(),
                    reason="../shared data not available")
def test_irb120_model_from_shared_data():
    model = load_model(SHARED / "data/irb120-lasertracker/irb120.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        st = one_at_a_time(model, _path(model.n, seed=7),
                           [f"LE{k}" for k in range(1, model.n + 2)], (0.05, 0.1))
    lengths = np.linalg.norm(model.bodies, axis=1)
    np.testing.assert_allclose(st.max_delta_p[:, 1], 1e-3 * lengths, rtol=1e-9, atol=1e-12)
