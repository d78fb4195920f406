"""The log-Cholesky map (eq. L1-L5 of zrp.gap.dynamics.logchol): every parameter vector is a
physical body, a known body (a solid box) round-trips to its closed-form parameters, and the
Jacobian matches central finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from zrp.errors import InputError
from zrp.gap.dynamics.inertia import pseudo_inertia, pseudo_inertia_min
from zrp.gap.dynamics.logchol import phi_from_theta, phi_jacobian, theta_from_phi, upper


def _box(mass, sides, centre, rot):
    """phi (eq. R1) of a uniform solid box, in closed form: inertia about its centre
    m/12 (b^2 + c^2, ...) in its own axes, rotated, moved to the origin (parallel axes)."""
    a, b, c = sides
    ic = rot @ np.diag(mass / 12.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])) \
        @ rot.T
    io = ic + mass * (centre @ centre * np.eye(3) - np.outer(centre, centre))
    return np.array([mass, *(mass * centre), io[0, 0], io[1, 1], io[2, 2], io[0, 1], io[0, 2],
                     io[1, 2]])


def test_every_parameter_vector_is_a_physical_body():
    rng = np.random.default_rng(3)
    for theta in rng.normal(0.0, 2.0, (500, 10)):
        phi = phi_from_theta(theta)
        assert pseudo_inertia_min(phi) > 0.0
        u = upper(theta)  # eq. L2 against eq. R5's own pseudo-inertia of phi
        np.testing.assert_allclose(pseudo_inertia(phi), u @ u.T, atol=1e-12 * np.abs(u @ u.T).max())
        # positive mass, and the principal moments about the centre obey the triangle
        # inequality (the body is realisable)
        mass, c = phi[0], phi[1:4] / phi[0]
        io = np.array([[phi[4], phi[7], phi[8]], [phi[7], phi[5], phi[9]],
                       [phi[8], phi[9], phi[6]]])
        w = np.linalg.eigvalsh(io - mass * (c @ c * np.eye(3) - np.outer(c, c)))
        assert mass > 0 and w.min() > 0 and w[0] + w[1] >= w[2] * (1 - 1e-9)


def test_box_round_trips_and_has_its_closed_form_theta():
    sides, centre = np.array([0.3, 0.1, 0.05]), np.array([0.02, -0.1, 0.3])
    # axis-aligned: J = [[Sigma_c + m c c^T, m c], [m c^T, m]] with Sigma_c = m diag(s^2)/12,
    # so U = sqrt(m) [[diag(s / sqrt 12), c], [0, 1]]: theta in closed form (eq. L1)
    phi = _box(2.5, sides, centre, np.eye(3))
    expected = np.array([0.5 * np.log(2.5), *np.log(sides / np.sqrt(12.0)), 0.0, 0.0, 0.0,
                         *centre])
    np.testing.assert_allclose(theta_from_phi(phi), expected, atol=1e-12)
    np.testing.assert_allclose(phi_from_theta(expected), phi, rtol=1e-12, atol=1e-14)
    # rotated: the round trip returns the same body
    rot = Rotation.from_euler("xyz", [0.4, -1.1, 2.0]).as_matrix()
    phi = _box(0.7, sides, centre, rot)
    np.testing.assert_allclose(phi_from_theta(theta_from_phi(phi)), phi, rtol=1e-11,
                               atol=1e-14)


def test_jacobian_matches_finite_differences():
    rng = np.random.default_rng(4)
    for theta in rng.normal(0.0, 1.0, (5, 10)):
        h = 1e-6
        fd = np.stack([(phi_from_theta(theta + h * e) - phi_from_theta(theta - h * e)) / (2 * h)
                       for e in np.eye(10)], axis=1)
        jac = phi_jacobian(theta)
        np.testing.assert_allclose(jac, fd, atol=1e-7 * np.abs(jac).max())


def test_non_physical_body_is_named():
    phi = _box(1.0, np.array([0.1, 0.1, 0.1]), np.zeros(3), np.eye(3))
    phi[6] = 3.0 * phi[4]  # Izz > Ixx + Iyy: breaks the triangle inequality
    with pytest.raises(InputError, match="link 3"):
        theta_from_phi(phi, "link 3")
