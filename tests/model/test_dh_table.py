"""DH/MDH: named fields, base/tool/flip/limits (Robotics Toolbox's DH robots, exact), and
export model -> DH/MDH table -> model (same FK) with canonical tables coming back identical.

Robotics Toolbox (roboticstoolbox-python) is optional and heavy (it pulls in many packages):
its test skips when it is absent."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import zrp
from zrp.errors import InputError, ModelFileError
from zrp.model.dh import DHRow, dh_forward, mdh_forward
from zrp.model.dh_table import DHTable, dumps_dh, loads_dh, to_dh


def _fk_gap(m1, m2, rng, n=20):
    q = rng.uniform(-3, 3, (n, m1.n))
    f1, f2 = zrp.forward_kinematics(m1, q), zrp.forward_kinematics(m2, q)
    return max(np.abs(f1.position - f2.position).max(), np.abs(f1.hand_frame - f2.hand_frame).max())


def test_robotics_toolbox_dh_robots_exact():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rtb = pytest.importorskip("roboticstoolbox", reason="optional: pip install "
                                  "roboticstoolbox-python")
    rng = np.random.default_rng(0)
    names = ["AL5D", "Baxter", "Cobra600", "IRB140", "Jaco", "KR5", "LWR4", "Mico", "Orion5",
             "P8", "Panda", "Puma560", "Sawyer", "Stanford", "UR10", "UR3", "UR5"]
    worst, flipped, based, tooled = 0.0, 0, 0, 0
    for nm in names:
        r = getattr(rtb.models.DH, nm)()
        rows = [dict(a=lk.a, alpha=lk.alpha, d=lk.d, theta=lk.theta, offset=lk.offset,
                     type="prismatic" if lk.isprismatic else "revolute", flip=bool(lk.isflip),
                     limits=None if lk.qlim is None else tuple(lk.qlim)) for lk in r.links]
        make = zrp.from_mdh if r.mdh else zrp.from_dh
        m = make(rows, base=r.base.A, tool=r.tool.A, length_unit="m")
        flipped += any(lk.isflip for lk in r.links)
        based += not np.allclose(r.base.A, np.eye(4))
        tooled += not np.allclose(r.tool.A, np.eye(4))
        for _ in range(5):
            q = rng.uniform(-1, 1, r.n)
            t = r.fkine(q).A
            fk = zrp.forward_kinematics(m, q)
            worst = max(worst, np.abs(fk.position - t[:3, 3]).max() * 1e3,
                        np.abs(fk.hand_frame - t[:3, :3]).max())
        # the exported table (canonical form) gives the same robot
        for conv in ("standard", "modified"):
            assert _fk_gap(m, to_dh(m, conv).model(), rng) < 1e-12  # m
    assert flipped >= 2 and based >= 2 and tooled >= 2  # Jaco/Mico flip; Baxter base; ...
    assert worst < 1e-9  # mm


@pytest.mark.parametrize("conv", ["standard", "modified"])
def test_canonical_table_round_trip_identical(conv):
    rng = np.random.default_rng(1)
    make = zrp.from_dh if conv == "standard" else zrp.from_mdh
    for _ in range(50):
        rows = [DHRow(a=rng.uniform(1, 300), alpha=rng.uniform(0.1, 3.0),
                      d=rng.uniform(-200, 200), offset=rng.uniform(-3, 3),
                      limits=(-2.0, 2.5)) for _ in range(6)]
        table = to_dh(make(rows), conv)
        for a, b in zip(rows, table.rows, strict=True):
            for key in ("a", "alpha", "d", "theta", "offset"):
                assert getattr(b, key) == pytest.approx(getattr(a, key), abs=1e-9)
            assert b.limits == a.limits and b.type == a.type
        assert np.allclose(table.base, np.eye(4), atol=1e-9)
        assert np.allclose(table.tool, np.eye(4), atol=1e-9)  # mm and rad
        back = loads_dh(dumps_dh(table))  # TOML round trip
        assert _fk_gap(table.model(), back.model(), rng) < 1e-9


@pytest.mark.parametrize("conv", ["standard", "modified"])
def test_any_model_exports_with_same_fk(conv):
    rng = np.random.default_rng(2)
    for name in ("puma", "stanford", "scara"):
        m = zrp.load_model(name)
        assert _fk_gap(m, to_dh(m, conv).model(), rng) < 1e-9
    for _ in range(20):  # random arms with tilted axes, prismatic joints
        m = zrp.testing.random_arm(rng, 6, p_prismatic=0.3)
        t = to_dh(m, conv)
        assert _fk_gap(m, t.model(), rng) < 1e-9
        # and the table's direct DH product agrees with ZRP FK (independent evaluation)
        q = rng.uniform(-2, 2, m.n)
        fwd = dh_forward if conv == "standard" else mdh_forward
        direct = fwd(list(t.rows), q, tool=t.tool, base=t.base)
        fk = zrp.forward_kinematics(m, q)
        assert np.abs(direct[:3, 3] - fk.position).max() < 1e-9
        assert np.abs(direct[:3, :3] - fk.hand_frame).max() < 1e-12


def test_named_fields_flip_and_errors():
    rows = [{"a": 0, "alpha": np.pi / 2, "d": 100}, {"a": 200, "alpha": 0, "flip": True}]
    m = zrp.from_dh(rows)
    assert np.allclose(m.axes[1], [0, 1, 0])  # flipped: -z_1, z_1 = Rx(pi/2) z = -y
    q = np.array([0.3, 0.4])
    direct = dh_forward(rows, q)
    assert np.abs(zrp.forward_kinematics(m, q).position - direct[:3, 3]).max() < 1e-12
    with pytest.raises(InputError, match="DH row 1: unknown field 'alhpa'"):
        zrp.from_dh([{"a": 0, "alhpa": 1.0}])
    with pytest.raises(InputError, match="base: expected a 4x4"):
        zrp.from_dh(rows, base=np.eye(3))
    with pytest.raises(InputError, match="convention: 'craig'"):
        DHTable(tuple(DHRow(a=0, alpha=0) for _ in range(1)), np.eye(4), np.eye(4), "craig")
    with pytest.raises(ModelFileError, match="unknown key 'rows'"):
        loads_dh("rows = 1")
