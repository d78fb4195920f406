"""DH and modified-DH tables converted to ZRP models agree with direct DH chains."""

import numpy as np
import pytest

import zrp
from zrp.model.dh import DHRow, dh_forward, from_dh, from_mdh, mdh_forward

# PUMA 560, standard DH (Corke & Armstrong-Helouvry), mm.
PUMA_DH = [DHRow(0, np.pi / 2, 0), DHRow(431.8, 0, 0), DHRow(20.3, -np.pi / 2, 150.05),
           DHRow(0, np.pi / 2, 431.8), DHRow(0, -np.pi / 2, 0), DHRow(0, 0, 0)]
# PUMA 560, modified DH (Craig), mm.
PUMA_MDH = [DHRow(0, 0, 0), DHRow(0, -np.pi / 2, 0), DHRow(431.8, 0, 150.05),
            DHRow(20.3, -np.pi / 2, 431.8), DHRow(0, np.pi / 2, 0), DHRow(0, -np.pi / 2, 0)]


def _random_rows(rng, n):
    rows = []
    for _ in range(n):
        kind = "prismatic" if rng.random() < 0.3 else "revolute"
        rows.append(DHRow(a=rng.normal() * 200, alpha=rng.uniform(-np.pi, np.pi),
                          d=rng.normal() * 200, theta=rng.uniform(-np.pi, np.pi), type=kind,
                          offset=rng.uniform(-1, 1) * (1 if kind == "revolute" else 100)))
    return rows


def _tool(rng):
    t = np.eye(4)
    t[:3, :3] = zrp.rotations.matrix_from_er(zrp.rotations.er_from_rotvec(rng.normal(size=3)))
    t[:3, 3] = rng.normal(size=3) * 100
    return t


@pytest.mark.parametrize("convention", ["dh", "mdh"])
def test_conversion_matches_direct_chain(rng, convention):
    conv, direct = (from_dh, dh_forward) if convention == "dh" else (from_mdh, mdh_forward)
    cases = [(PUMA_DH if convention == "dh" else PUMA_MDH, None)]
    cases += [(_random_rows(rng, n), _tool(rng)) for n in (3, 5, 6, 7)]
    for rows, tool in cases:
        model = conv(rows, tool=tool)
        for _ in range(5):
            q = rng.uniform(-np.pi, np.pi, len(rows))
            t = direct(rows, q, tool)
            fk = zrp.forward_kinematics(model, q)
            np.testing.assert_allclose(fk.position, t[:3, 3], atol=1e-9)
            np.testing.assert_allclose(fk.hand_frame, t[:3, :3], atol=1e-12)


def test_puma_dh_link_lengths_survive_conversion():
    model = from_dh(PUMA_DH)
    # upper arm a2 = 431.8 between joints 2 and 3; wrist centre d4 = 431.8 from frame 3
    fk = zrp.forward_kinematics(model, np.zeros(6))
    np.testing.assert_allclose(np.linalg.norm(fk.points[2] - fk.points[1]), 431.8, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(fk.position - fk.points[3]), 431.8, atol=1e-12)
    # frame 3 sits d3 = 150.05 off the upper arm's plane and a3 = 20.3 beyond joint 3
    np.testing.assert_allclose(np.linalg.norm(fk.points[3] - fk.points[2]),
                               np.hypot(150.05, 20.3), atol=1e-12)


def test_bad_dh_rows():
    with pytest.raises(zrp.InputError, match="DH row type"):
        DHRow(0, 0, 0, 0, "ball")
    with pytest.raises(zrp.InputError, match="DH row alpha"):
        DHRow(0, np.nan)
    with pytest.raises(zrp.InputError, match="DH row 2"):
        from_dh([(0, 0, 0, 0), (1, 2, 3, 4, "revolute", 0, 99)])
    with pytest.raises(zrp.InputError, match="at least one row"):
        from_mdh([])
