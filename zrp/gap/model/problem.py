"""The corrected model of a set of parameters, its residuals and its analytic Jacobian.

For pose i (joint values q_i, rad) and tool point j, the corrected model predicts

    m_ij = R_b (p(q'_i) + R_n(q'_i) t_j) + t_b,    q'_i = q_i + sum_s theta_s B_s[i]

where p and R_n come from the zero-reference-position forward kinematics of the corrected
geometry (body vectors b_{k,0} + db_k, scaled by 1 + kappa dT_i; axes tilted), R_b =
exp([phi]) R_b0 and t_b the registration. The Jacobian columns (derivations in
zrp/gap/README.md) are exact at any theta and are checked against finite differences in the
tests:

* rot: -[R_b x]_x J_l(phi) (J_l: left Jacobian of SO(3));  trans: I;  tool t_j: R_b R_n;
* dq (joint k): R_b (u_k x (x - p_k)) B[i, k] (revolute), R_b u_k B[i, k] (prismatic);
* link db_k: R_b s_i R_{k-1};  thermal: R_b dT_i sum_k R_{k-1} b_{k,0} (kappa, comp 0; a
  common scale of all body vectors, comp 1, has the column with 1 in place of dT_i: the
  look-alike that :mod:`zrp.gap.search.greedy` tests kappa against);
* tilt of axis k along dv: omega = R_{k-1}(sin q_k du + (1 - cos q_k) u x du) with
  du = (I - u u^T) dv / |v|; column R_b (omega x (x - p_k)) (revolute) or R_b q_k R_{k-1} du.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.model.context import Context, ParamSpec
from zrp.rotations import left_jacobian, matrix_from_rotvec, skew

__all__ = ["Evaluation", "Problem", "compressed"]



def _cross(a: F64, b: F64) -> F64:
    """a x b over the last axis (3), broadcast; the arithmetic of np.cross without its
    axis shuffling (~3x faster on the small arrays of a fit)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _axis_rotations(u: F64, q: F64) -> F64:
    """Rotations about the unit axis u (3,) by angles q (S,): shape (S, 3, 3)."""
    k = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])  # skew(u)
    s = np.sin(q)[:, None, None]
    c = np.cos(q)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


@dataclass(frozen=True)
class _Chain:
    """The corrected chain per pose (S poses): joint values q (S, n); axes u, v (n, 3);
    body scale (S,); rotations before each body R_{k-1} (S, n + 1, 3, 3); joint points p_k
    (S, n, 3); current axes (S, n, 3); sum of the rotated bodies (S, 3); end point (S, 3)."""

    q: F64
    u: F64
    v: F64
    scale: F64
    rprev: F64
    pts: F64
    ucur: F64
    bsum: F64
    pos: F64


class Problem:
    """Residuals and Jacobian of the corrected model on a subset of poses.

    Args:
        ctx: the data context.
        specs: the parameters (p of them), in column order.
        poses: indices of the poses used (into ``ctx.meas.pose_ids``), shape (S,).
        base_rotation: R_b0, the initial instrument-from-base rotation, shape (3, 3).
    """

    def __init__(self, ctx: Context, specs: Sequence[ParamSpec], poses: ArrayLike,
                 base_rotation: ArrayLike | None = None) -> None:
        self.ctx = ctx
        self.specs = tuple(specs)
        self.poses = np.asarray(poses, dtype=np.int64)
        if self.poses.ndim != 1 or self.poses.size == 0:
            raise InputError("poses: expected a non-empty 1-D array of pose indices")
        meas = ctx.meas
        P = len(meas.pose_ids)
        local = np.full(P, -1, dtype=np.int64)
        local[self.poses] = np.arange(self.poses.size)
        rows = np.flatnonzero(local[meas.pose_index] >= 0)
        self.rows = rows
        self.row_pose = local[meas.pose_index[rows]]
        self.row_point = meas.point_index[rows]
        self.measured = meas.xyz[rows]
        self.base_rotation = np.eye(3) if base_rotation is None else np.asarray(
            base_rotation, dtype=float)
        self.instrument = meas.frame == "instrument"
        kinds = np.array([s.kind for s in self.specs])
        self.idx = {k: np.flatnonzero(kinds == k) for k in
                    ("rot", "trans", "tool", "dq", "link", "tilt", "thermal")}
        if self.instrument and (self.idx["rot"].size != 3 or self.idx["trans"].size != 3):
            raise InputError("instrument-frame data need the 6 base_frame parameters")
        self.B = (np.stack([self.specs[i].basis[self.poses] for i in self.idx["dq"]], -1)
                  if self.idx["dq"].size else np.zeros((self.poses.size, ctx.n, 0)))
        self.dT = (None if ctx.dtemp is None else ctx.dtemp[self.poses])
        self.scale_basis = self._scale_basis()
        self.q = ctx.q_of(self.poses)
        #: the last chain computed, by its theta: a full-pose fit asks for the chain of the
        #: same theta twice (positions, then orientations), so the second is a look-up
        self._last: tuple[bytes, _Chain] | None = None

    def _scale_basis(self) -> F64:
        """Body scale per pose and unit parameter of each ``thermal`` spec, shape (S, k):
        dT_i for kappa (comp 0), 1 for a common scale of the links (comp 1)."""
        comps = [self.specs[i].comp for i in self.idx["thermal"]]
        if 0 in comps and self.dT is None:
            raise InputError("thermal_expansion needs a temp column")
        cols = [self.dT if c == 0 and self.dT is not None else np.ones(self.poses.size)
                for c in comps]
        return np.stack(cols, -1) if cols else np.zeros((self.poses.size, 0))

    @property
    def size(self) -> int:
        """p, the number of parameters."""
        return len(self.specs)

    @property
    def n_residuals(self) -> int:
        return 3 * self.rows.size

    # ---- geometry of the corrected model -----------------------------------------------
    def geometry(self, theta: F64) -> tuple[F64, F64, F64]:
        """Corrected axes (n, 3) (unit), un-normalised axes v (n, 3), bodies (n + 1, 3)."""
        model = self.ctx.model
        bodies = np.array(model.bodies, dtype=float)
        for i in self.idx["link"]:
            s = self.specs[i]
            bodies[s.joint - 1, s.comp] += theta[i]
        v = np.array(model.axes, dtype=float)
        tang = self.ctx.tangents
        for i in self.idx["tilt"]:
            s = self.specs[i]
            v[s.joint - 1] += theta[i] * tang[s.joint - 1, s.comp]
        u = v / np.linalg.norm(v, axis=1, keepdims=True)
        return u, v, bodies

    def tool_offsets(self, theta: F64) -> F64:
        """Tool offsets t_j, shape (M, 3)."""
        t = np.zeros((len(self.ctx.meas.point_labels), 3))
        for i in self.idx["tool"]:
            c = self.specs[i].comp
            t[c // 3, c % 3] = theta[i]
        return t

    def base(self, theta: F64) -> tuple[F64, F64]:
        """R_b (3, 3) and t_b (3,)."""
        if not self.instrument:
            return np.eye(3), np.zeros(3)
        return (matrix_from_rotvec(theta[self.idx["rot"]]) @ self.base_rotation,
                np.asarray(theta[self.idx["trans"]], dtype=float))

    def joint_values(self, theta: F64) -> F64:
        """Corrected joint values q' per pose, shape (S, n)."""
        return self.q + self.B @ theta[self.idx["dq"]]

    # ---- evaluation -----------------------------------------------------------------------
    def _chain(self, theta: F64) -> _Chain:
        """The corrected kinematic chain at ``theta`` on the problem's poses (read-only
        arrays: the last one is kept and handed out again for the same theta)."""
        key = np.asarray(theta, dtype=float).tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        ch = self._new_chain(theta)
        for f in fields(ch):
            getattr(ch, f.name).setflags(write=False)
        self._last = (key, ch)
        return ch

    def _new_chain(self, theta: F64) -> _Chain:
        model = self.ctx.model
        n = model.n
        S = self.poses.size
        q = self.joint_values(theta)
        u, v, bodies = self.geometry(theta)
        scale = 1.0 + self.scale_basis @ theta[self.idx["thermal"]]
        rprev = np.empty((S, n + 1, 3, 3))
        pts = np.empty((S, n, 3))
        ucur = np.empty((S, n, 3))
        bsum = np.zeros((S, 3))
        pos = np.zeros((S, 3))
        r = np.broadcast_to(np.eye(3), (S, 3, 3))
        for k in range(n + 1):
            rprev[:, k] = r
            bk = r @ bodies[k]
            bsum += bk
            pos = pos + scale[:, None] * bk
            if k == n:
                break
            pts[:, k] = pos
            uc = r @ u[k]
            ucur[:, k] = uc
            if model.prismatic[k]:
                pos = pos + q[:, k, None] * uc
            else:
                r = r @ _axis_rotations(u[k], q[:, k])
        return _Chain(q, u, v, scale, rprev, pts, ucur, bsum, pos)

    def evaluate(self, theta: ArrayLike, jac: bool = True) -> tuple[F64, F64 | None]:
        """Predicted positions (R, 3) and, with ``jac``, the Jacobian (R, 3, p)."""
        theta = np.asarray(theta, dtype=float)
        if theta.shape != (self.size,):
            raise InputError(f"theta: expected shape ({self.size},), got {theta.shape}")
        ch = self._chain(theta)
        rn = ch.rprev[:, self.ctx.model.n]
        t = self.tool_offsets(theta)
        rp, rpt = self.row_pose, self.row_point
        x = ch.pos[rp] + np.einsum("rij,rj->ri", rn[rp], t[rpt])
        rb, tb = self.base(theta)
        pred = x @ rb.T + tb
        if not jac:
            return pred, None
        # columns in the base frame first, rotated by R_b below
        J = np.zeros((rp.size, 3, self.size))
        self._tool_columns(J, rn)
        self._dq_columns(J, ch, x)
        self._link_columns(J, ch)
        self._tilt_columns(J, ch, x)
        for j, i in enumerate(self.idx["thermal"]):
            J[:, :, i] = self.scale_basis[rp, j, None] * ch.bsum[rp]
        J = np.matmul(rb, J)  # R_b J per row; 2.8x faster than the einsum it replaces
        if self.instrument:
            y = x @ rb.T
            jl = left_jacobian(theta[self.idx["rot"]])
            J[:, :, self.idx["rot"]] = -skew(y) @ jl
            J[:, :, self.idx["trans"]] = np.eye(3)
        return pred, J

    def _tool_columns(self, J: F64, rn: F64) -> None:
        rp, rpt = self.row_pose, self.row_point
        rows: dict[int, tuple[NDArray[np.bool_], F64]] = {}  # per tool point: rows, R_n
        for i in self.idx["tool"]:
            m, cc = divmod(self.specs[i].comp, 3)
            if m not in rows:
                sel = rpt == m
                rows[m] = (sel, rn[rp[sel]])
            sel, rsel = rows[m]
            J[sel, :, i] = rsel[:, :, cc]

    def _dq_columns(self, J: F64, ch: _Chain, x: F64) -> None:
        if not self.idx["dq"].size:
            return
        rp = self.row_pose
        rel = x[:, None, :] - ch.pts[rp]  # (R, n, 3)
        dxdq = np.where(self.ctx.model.prismatic[None, :, None], ch.ucur[rp],
                        _cross(ch.ucur[rp], rel))
        J[:, :, self.idx["dq"]] = np.matmul(dxdq.transpose(0, 2, 1), self.B[rp])  # 4x einsum

    def _link_columns(self, J: F64, ch: _Chain) -> None:
        rp = self.row_pose
        for i in self.idx["link"]:
            s = self.specs[i]
            J[:, :, i] = ch.scale[rp, None] * ch.rprev[rp, s.joint - 1, :, s.comp]

    def _tilt_columns(self, J: F64, ch: _Chain, x: F64) -> None:
        rp, q, tang = self.row_pose, ch.q, self.ctx.tangents
        for i in self.idx["tilt"]:
            s = self.specs[i]
            k = s.joint - 1
            uk = ch.u[k]
            du = (tang[k, s.comp] - uk * (uk @ tang[k, s.comp])) / np.linalg.norm(ch.v[k])
            if self.ctx.model.prismatic[k]:
                J[:, :, i] = (q[:, k, None] * (ch.rprev[:, k] @ du))[rp]
            else:
                loc = (np.sin(q[:, k])[:, None] * du
                       + (1.0 - np.cos(q[:, k]))[:, None] * _cross(uk, du))
                om = np.einsum("sij,sj->si", ch.rprev[:, k], loc)
                J[:, :, i] = _cross(om[rp], x - ch.pts[rp, k])

    def residual(self, theta: ArrayLike) -> F64:
        """Predicted minus measured, shape (3R,) (x, y, z per row)."""
        pred, _ = self.evaluate(theta, jac=False)
        return (pred - self.measured).ravel()

    def residual_and_jacobian(self, theta: ArrayLike) -> tuple[F64, F64]:
        """Residual (3R,) and Jacobian (3R, p)."""
        pred, J = self.evaluate(theta, jac=True)
        assert J is not None
        return (pred - self.measured).ravel(), J.reshape(-1, self.size)


def compressed(r: F64, jac: F64) -> tuple[F64, F64]:
    """The least-squares problem (r (m,), J (m, p)) reduced to p + 1 rows with the same
    Levenberg-Marquardt steps: R of the QR factorisation [J r] = Q R, g = R[:, p] = Q^T r
    (so ||g|| = ||r||, g[p] = the part of r outside span(J)) and J' = R[:, :p] (J'^T J' =
    J^T J, J'^T g = J^T r, the same column norms). MINPACK's own unblocked QR of the tall J
    then becomes one blocked LAPACK QR per evaluation (~2x faster; see the speed section of
    zrp/kinematics/README.md).

    Args:
        r: residual, shape (m,).
        jac: Jacobian, shape (m, p), m > p.

    Returns:
        g (p + 1,) and J' (p + 1, p), J'[p] = 0.
    """
    p = jac.shape[1]
    aug = np.empty((jac.shape[0], p + 1))
    aug[:, :p] = jac
    aug[:, p] = r
    R = np.linalg.qr(aug, mode="r")
    return R[:, p].copy(), np.ascontiguousarray(R[:, :p])


@dataclass(frozen=True)
class Evaluation:
    """The residual r (3R,) and Jacobian J (3R, p) of a parameter set at theta (p,) on poses
    (S,), already computed (by :func:`zrp.gap.fit.leastsq.identifiable_start`): a fit
    (:func:`zrp.gap.fit.leastsq.fit`) starting there reuses it instead of evaluating again."""

    poses: NDArray[np.int64]
    theta: F64
    residual: F64
    jac: F64

    def __post_init__(self) -> None:
        if self.jac.shape != (self.residual.size, self.theta.size):
            raise InputError(f"Evaluation: Jacobian of shape {self.jac.shape}, expected "
                             f"({self.residual.size}, {self.theta.size})")
