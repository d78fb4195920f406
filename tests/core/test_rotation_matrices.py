"""zrp.rotations.matrices: the batched skew matrices and left Jacobian of SO(3) against SciPy's
rotations (an independent reference) and against their one-vector form."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from zrp.rotations import left_jacobian, skew


def _rotvecs() -> np.ndarray:
    rng = np.random.default_rng(3)
    return np.concatenate([rng.normal(size=(20, 3)) * s for s in (1e-9, 1e-7, 1e-3, 0.5, 2.5)])


def test_skew_is_the_cross_product():
    v, w = _rotvecs(), np.random.default_rng(4).normal(size=(100, 3))
    assert np.allclose(np.einsum("sij,sj->si", skew(v), w), np.cross(v, w), rtol=0, atol=1e-15)


@pytest.mark.parametrize("i", [0, 25, 45, 65, 85])
def test_left_jacobian_is_the_derivative_of_exp(i):
    """d exp(phi) = [J_l dphi]_x exp(phi): central differences of SciPy's exp."""
    phi = _rotvecs()[i]
    r0 = Rotation.from_rotvec(phi)
    h = 1e-6
    num = np.stack([(Rotation.from_rotvec(phi + h * e) * r0.inv()).as_rotvec()
                    - (Rotation.from_rotvec(phi - h * e) * r0.inv()).as_rotvec()
                    for e in np.eye(3)], -1) / (2 * h)
    assert np.allclose(left_jacobian(phi), num, atol=1e-8)


def test_batched_left_jacobian_equals_one_at_a_time():
    phi = _rotvecs()
    batch = left_jacobian(phi)
    assert batch.shape == (len(phi), 3, 3)
    one = np.stack([left_jacobian(v) for v in phi])
    assert np.allclose(batch, one, rtol=1e-15, atol=1e-15)
    assert left_jacobian(phi.reshape(4, 25, 3)).shape == (4, 25, 3, 3)
