"""Forward kinematics and the Jacobian against independent references."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import zrp
from zrp.rotations.rodrigues import matrix_from_er
from zrp.testing import random_arm


def scipy_fk(model, q):
    """Independent composition with scipy's Rotation (product of exponentials at q = 0)."""
    r = Rotation.identity()
    p = np.zeros(3)
    bodies, axes = np.array(model.bodies), np.array(model.axes)  # writable copies for scipy
    for k in range(model.n):
        p = p + r.apply(bodies[k])
        u = axes[k]
        if model.prismatic[k]:
            p = p + q[k] * r.apply(u)
        else:
            r = r * Rotation.from_rotvec(u * q[k])
    p = p + r.apply(bodies[-1])
    return p, r.as_matrix()


@pytest.mark.parametrize("n", [3, 4, 6, 7, 8])
def test_fk_matches_scipy_composition(rng, n):
    for _trial in range(5):
        model = random_arm(rng, n, p_prismatic=0.3)
        q = rng.uniform(-np.pi, np.pi, n)
        fk = zrp.forward_kinematics(model, q)
        p_ref, r_ref = scipy_fk(model, q)
        np.testing.assert_allclose(fk.position, p_ref, atol=1e-10)
        np.testing.assert_allclose(fk.rotation, r_ref, atol=1e-13)
        np.testing.assert_allclose(fk.axial, r_ref @ model.end_effector.axial, atol=1e-13)
        np.testing.assert_allclose(fk.transverse, r_ref @ model.end_effector.transverse,
                                   atol=1e-13)
        # fast compiled path agrees with the vectorised NumPy path
        p, e = zrp.end_effector_pose(model, q)
        np.testing.assert_allclose(p, fk.position, atol=1e-10)
        np.testing.assert_allclose(e, fk.er, atol=1e-14)


def test_zero_configuration_gives_sums_of_body_vectors_exactly(rng):
    for model in (zrp.load_model("puma"), random_arm(rng, 7, 0.3), zrp.load_model("stanford")):
        q = np.zeros(model.n)
        expected = np.zeros(3)
        for b in model.bodies:
            expected = expected + b
        fk = zrp.forward_kinematics(model, q)
        np.testing.assert_array_equal(fk.position, expected)
        np.testing.assert_array_equal(zrp.end_effector_pose(model, q)[0], expected)
        np.testing.assert_array_equal(fk.axes, model.axes)
        np.testing.assert_array_equal(fk.axial, model.end_effector.axial)


def test_puma_zero_is_wrist_singular(puma):
    fk = zrp.forward_kinematics(puma, np.zeros(6))
    np.testing.assert_allclose(fk.axes[3], -fk.axes[5])
    assert np.linalg.matrix_rank(zrp.jacobian(puma, np.zeros(6)), tol=1e-9) == 5
    assert np.linalg.matrix_rank(zrp.jacobian(puma, np.radians([0, 0, 0, 0, 90, 0])),
                                 tol=1e-9) == 6


def test_current_vectors_follow_eqs_1_and_2(rng):
    model = random_arm(rng, 6)
    q = rng.uniform(-3, 3, 6)
    fk = zrp.forward_kinematics(model, q)
    # body vectors keep their length and the points are their partial sums
    np.testing.assert_allclose(np.linalg.norm(fk.bodies, axis=1),
                               np.linalg.norm(model.bodies, axis=1), rtol=1e-13)
    np.testing.assert_allclose(fk.points, np.cumsum(fk.bodies[:-1], axis=0), atol=1e-10)
    # eq (1)/(13) remark: rotating u_{k,0} by joints 1..k or 1..k-1 gives the same u_k
    for k in range(6):
        r_k = np.eye(3)
        for j in range(k + 1):
            r_k = r_k @ Rotation.from_rotvec(np.array(model.axes[j]) * q[j]).as_matrix()
        np.testing.assert_allclose(r_k @ model.axes[k], fk.axes[k], atol=1e-13)


def _orientation_fd(model, q, k, h):
    qp, qm = q.copy(), q.copy()
    qp[k] += h
    qm[k] -= h
    rp = matrix_from_er(zrp.end_effector_pose(model, qp)[1])
    rm = matrix_from_er(zrp.end_effector_pose(model, qm)[1])
    return Rotation.from_matrix(rp @ rm.T).as_rotvec() / (2 * h)


@pytest.mark.parametrize("n", [3, 5, 6, 7, 8])
def test_jacobian_matches_finite_differences(rng, n):
    for _trial in range(4):
        model = random_arm(rng, n, p_prismatic=0.35)
        q = rng.uniform(-np.pi, np.pi, n)
        jac = zrp.jacobian(model, q)
        h = 1e-6
        for k in range(n):
            qp, qm = q.copy(), q.copy()
            qp[k] += h
            qm[k] -= h
            dp = (zrp.end_effector_pose(model, qp)[0] - zrp.end_effector_pose(model, qm)[0])
            np.testing.assert_allclose(jac[3:, k], dp / (2 * h), atol=2e-6 * model.reach)
            np.testing.assert_allclose(jac[:3, k], _orientation_fd(model, q, k, h), atol=1e-8)
        if model.prismatic.any():
            np.testing.assert_array_equal(jac[:3, model.prismatic], 0.0)


def test_batched_shapes_and_consistency(rng, puma):
    q = rng.uniform(-3, 3, (4, 5, 6))
    fk = zrp.forward_kinematics(puma, q)
    assert fk.position.shape == (4, 5, 3)
    assert fk.axes.shape == (4, 5, 6, 3)
    assert fk.bodies.shape == (4, 5, 7, 3)
    assert fk.hand_frame.shape == (4, 5, 3, 3)
    p, e = zrp.end_effector_pose(puma, q)
    assert p.shape == (4, 5, 3) and e.shape == (4, 5, 4)
    jac = zrp.jacobian(puma, q)
    assert jac.shape == (4, 5, 6, 6)
    np.testing.assert_allclose(jac[2, 3], zrp.jacobian(puma, q[2, 3]), atol=0)
    np.testing.assert_allclose(p, fk.position, atol=1e-10)


def test_hand_frame_is_right_handed_rotation(rng, puma):
    fk = zrp.forward_kinematics(puma, rng.uniform(-3, 3, (20, 6)))
    h = fk.hand_frame
    np.testing.assert_allclose(np.einsum("nij,nik->njk", h, h), np.broadcast_to(np.eye(3), h.shape),
                               atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(h), 1.0, atol=1e-14)
    np.testing.assert_allclose(h[:, :, 2], fk.axial)
    # the hand frame turns with R_n
    np.testing.assert_allclose(h, fk.rotation @ puma.end_effector.frame, atol=1e-14)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-20, 20, allow_nan=False), min_size=6, max_size=6),
       st.floats(-3, 3, allow_nan=False))
def test_property_joint1_rotates_whole_arm(q, delta):
    """Turning joint 1 by delta rotates p about joint 1's axis (through b_{1,0}) by delta."""
    model = zrp.load_model("puma")
    q = np.array(q)
    q2 = q.copy()
    q2[0] += delta
    p1 = zrp.forward_kinematics(model, q).position
    p2 = zrp.forward_kinematics(model, q2).position
    r = Rotation.from_rotvec(np.array(model.axes[0]) * delta)
    np.testing.assert_allclose(p2, model.bodies[0] + r.apply(p1 - model.bodies[0]), atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 8), st.integers(0, 2**32 - 1))
def test_property_first_order_step(n, seed):
    """FK(q + dq) - FK(q) = J dq + O(|dq|^2) on random arms."""
    rng = np.random.default_rng(seed)
    model = random_arm(rng, n, 0.3)
    q = rng.uniform(-3, 3, n)
    dq = rng.normal(size=n) * 1e-6
    dp = zrp.end_effector_pose(model, q + dq)[0] - zrp.end_effector_pose(model, q)[0]
    lin = zrp.jacobian(model, q)[3:] @ dq
    assert np.linalg.norm(dp - lin) <= 1e-9 * model.reach + 1e-6 * np.linalg.norm(lin)


def test_bad_joint_values_are_named(puma):
    with pytest.raises(zrp.InputError, match=r"shape \(\.\.\., 6\)"):
        zrp.forward_kinematics(puma, np.zeros(5))
    with pytest.raises(zrp.InputError, match=r"joint 3 \(q3\) is nan"):
        zrp.end_effector_pose(puma, [0, 0, np.nan, 0, 0, 0])
    with pytest.raises(zrp.InputError, match="joint 2"):
        zrp.jacobian(puma, [[0, 0, 0, 0, 0, 0], [0, np.inf, 0, 0, 0, 0]])
    with pytest.raises(zrp.InputError, match="expected numbers"):
        zrp.forward_kinematics(puma, "abc")


def test_vectorised_sincos_matches_libm():
    from zrp.kinematics import _kernels as K

    x = np.concatenate([np.linspace(-100, 100, 200_001), [0.0, -0.0, 1e-300, np.pi / 4,
                                                          np.pi / 2, np.pi, -np.pi, 1e5]])
    s, c = np.empty_like(x), np.empty_like(x)
    K.sincos_batch(x, s, c)
    np.testing.assert_allclose(s, np.sin(x), rtol=0, atol=2.3e-16)
    np.testing.assert_allclose(c, np.cos(x), rtol=0, atol=2.3e-16)


def test_blocked_batch_kernels_match_single_pose_kernels(rng):
    from zrp.kinematics import _kernels as K

    model = random_arm(rng, 7, 0.3)
    q = rng.uniform(-4, 4, (1000, 7))  # spans several blocks
    arrays = K.kernel_arrays(model.axes, model.bodies, model.prismatic)
    out = np.empty((1000, 7))
    pose = np.empty((1000, 7))
    jac = np.empty((1000, 6, 7))
    lim = np.full(7, 1e6)
    assert K.fk_pose_batch(q, *arrays, lim, out)
    assert K.jac_batch(q, *arrays, lim, pose, jac)
    one, j1 = np.empty(7), np.empty((6, 7))
    for i in (0, 255, 256, 999):
        K.fk_jac_one(q[i], *arrays, one, j1)
        np.testing.assert_allclose(out[i], one, atol=1e-12)
        np.testing.assert_allclose(pose[i], one, atol=1e-12)
        np.testing.assert_allclose(jac[i], j1, atol=1e-12)


def test_streamed_stores_of_a_large_batch_give_the_same_bits(rng):
    """fk_pose_batch writes a batch of >= _STREAM_MIN poses with non-temporal stores: the same
    bits as the ordinary stores of small batches, every row written, the range check intact."""
    from zrp.kinematics import _kernels as K

    model = random_arm(rng, 6, 0.3)
    n = K._STREAM_MIN + 777  # streamed, with a partial last block
    q = rng.uniform(-4, 4, (n, 6))
    arrays = K.kernel_arrays(model.axes, model.bodies, model.prismatic)
    lim = np.full(6, 1e6)
    out = np.full((n, 7), np.nan)
    assert K.fk_pose_batch(q, *arrays, lim, out)
    parts = np.full((n, 7), np.nan)
    for a in range(0, n, 1000):  # small batches: ordinary stores
        part = np.empty((min(1000, n - a), 7))
        assert K.fk_pose_batch(q[a:a + 1000], *arrays, lim, part)
        parts[a:a + part.shape[0]] = part
    assert np.array_equal(out, parts)  # no NaN left: every row written
    one = np.empty(7)
    for i in (0, n // 2, n - 1):
        K.fk_pose_one(q[i], *arrays, one)
        np.testing.assert_allclose(out[i], one, atol=1e-12)
    q[n - 3, 4] = 2e6
    assert not K.fk_pose_batch(q, *arrays, lim, out)


def test_end_effector_pose_into_a_given_buffer(rng):
    """``out=``: the same bits as a fresh result, written into the caller's buffer (views),
    for a batch and for one pose; a wrong buffer is refused naming ``out``."""
    puma = zrp.load_model("puma")
    q = rng.uniform(-2, 2, (3, 5, 6))
    p, e = zrp.end_effector_pose(puma, q)
    buf = np.full((3, 5, 7), np.nan)
    p2, e2 = zrp.end_effector_pose(puma, q, out=buf)
    assert np.shares_memory(p2, buf) and np.shares_memory(e2, buf)
    np.testing.assert_array_equal(p2, p)
    np.testing.assert_array_equal(e2, e)
    one = np.empty(7)
    p1, e1 = zrp.end_effector_pose(puma, q[1, 2], out=one)
    np.testing.assert_array_equal(one, np.concatenate([p[1, 2], e[1, 2]]))
    assert np.shares_memory(p1, one) and np.shares_memory(e1, one)
    for bad in (np.empty((3, 5, 6)), np.empty((3, 5, 7), np.float32),
                np.empty((3, 7, 5)).transpose(0, 2, 1), [[0.0] * 7]):
        with pytest.raises(zrp.InputError, match=r"^out: expected .*shape \(3, 5, 7\)"):
            zrp.end_effector_pose(puma, q, out=bad)
    with pytest.raises(zrp.InputError):  # the range is still checked
        zrp.end_effector_pose(puma, np.full((2, 6), np.inf), out=np.empty((2, 7)))


def test_one_pose_path_reads_any_joint_vector_right_and_names_bad_input(rng):
    """The one-pose path (a 1-D float64 array: the kernels' bare entry points, no dispatcher
    type check) against the batch kernel: strided, reversed and read-only vectors give the
    same bits as a contiguous copy; each call returns fresh arrays; a wrong length, a NaN, a
    2-D array, another dtype and a model that is not one are named as before."""
    puma = zrp.load_model("puma")
    q = rng.uniform(-3, 3, 6)
    p_ref, e_ref = zrp.end_effector_pose(puma, q[None])  # the batch kernel
    j_ref = zrp.jacobian(puma, q[None])[0]
    wide = np.zeros((6, 3))
    wide[:, 1] = q
    backwards = q[::-1].copy()[::-1]
    frozen = q.copy()
    frozen.flags.writeable = False
    for v in (q, wide[:, 1], backwards, frozen):
        p, e = zrp.end_effector_pose(puma, v)
        assert p.shape == (3,) and e.shape == (4,)
        np.testing.assert_array_equal(p, p_ref[0])
        np.testing.assert_array_equal(e, e_ref[0])
        np.testing.assert_allclose(zrp.jacobian(puma, v), j_ref, rtol=0, atol=1e-12)
    p1, e1 = zrp.end_effector_pose(puma, q)
    p2, _ = zrp.end_effector_pose(puma, q)
    assert not np.shares_memory(p1, p2) and not np.shares_memory(p1, e1)
    assert zrp.end_effector_pose(puma, q[None])[0].shape == (1, 3)  # (1, 6) stays a batch
    with pytest.raises(zrp.InputError, match=r"shape \(\.\.\., 6\)"):
        zrp.end_effector_pose(puma, np.zeros(5))
    with pytest.raises(zrp.InputError, match=r"shape \(\.\.\., 6\)"):
        zrp.end_effector_pose(puma, np.zeros(7)[1:].reshape(2, 3))
    with pytest.raises(zrp.InputError, match=r"joint 5 \(q5\) is nan"):
        zrp.end_effector_pose(puma, np.array([0, 0, 0, 0, np.nan, 0.0]))
    with pytest.raises(zrp.InputError, match=r"joint 2 \(q2\) is inf"):
        zrp.jacobian(puma, np.array([0, np.inf, 0, 0, 0, 0.0]))
    np.testing.assert_array_equal(zrp.end_effector_pose(puma, q.astype(np.float32))[0],
                                  zrp.end_effector_pose(puma, q.astype(np.float32)
                                                        .astype(float))[0])
    for not_a_model in ("puma", None, puma.bodies):
        with pytest.raises(zrp.InputError, match=r"^model: expected a zrp\.Manipulator"):
            zrp.end_effector_pose(not_a_model, q)
        with pytest.raises(zrp.InputError, match=r"^model: expected a zrp\.Manipulator"):
            zrp.jacobian(not_a_model, q)
