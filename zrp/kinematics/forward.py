"""Forward kinematics and the Jacobian of the ZRP method, batched over leading axes.

* :func:`forward_kinematics` returns everything eqs (1)-(6) define (current joint axes and
  points, body vectors, p, u_a, u_t, the hand rotation and its Euler-Rodrigues parameters),
  vectorised with NumPy.
* :func:`end_effector_pose` and :func:`jacobian` are the fast paths (compiled kernels) used by
  the inverse kinematics, the error analysis and the benchmarks.

Conventions: R_k is the composition of the rotations of joints 1..k (R_0 = I), so
b_k = R_{k-1} b_{k,0}, u_k = R_{k-1} u_{k,0} and p = sum_k b_k (+ q_k u_k for prismatic k).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64, recycled_empty
from zrp.errors import InputError
from zrp.kinematics import _kernels as K
from zrp.kinematics._range_kernels import all_in_range, joint_limits
from zrp.kinematics.parallel import MIN_FK_POSES, MIN_JAC_POSES, run_split, thread_count
from zrp.model.manipulator import Manipulator, derived, hand_frame
from zrp.rotations.rodrigues import (
    er_from_axis_angle,
    er_identity,
    er_multiply,
    er_rotate,
    matrix_from_er,
)
from zrp.units import length_scale

__all__ = ["FKResult", "check_q", "end_effector_pose", "forward_kinematics", "jacobian"]



def check_q(model: Manipulator, q: ArrayLike, name: str = "q") -> F64:
    """Coerce joint values to a float array of shape (..., n), or raise naming the joint.

    Revolute values are in rad, prismatic ones in the model's length unit; only real numbers
    (no complex, date, masked or boolean arrays) within the range of :mod:`._range_kernels`.
    """
    if not isinstance(model, Manipulator):
        raise InputError(f"model: expected a zrp.Manipulator, got {type(model).__name__}")
    kind = getattr(getattr(q, "dtype", None), "kind", "f")
    if kind not in "iuf" or isinstance(q, np.ma.MaskedArray):
        what = "a masked array" if isinstance(q, np.ma.MaskedArray) else f"dtype {q.dtype}"
        raise InputError(f"{name}: expected real numbers (rad or length unit), got {what}")
    try:
        arr = np.asarray(q, dtype=float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{name}: expected numbers, got {type(q).__name__}") from exc
    if arr.ndim == 0 or arr.shape[-1] != model.n:
        raise InputError(
            f"{name}: expected shape (..., {model.n}) for the {model.n} joints of "
            f"{model.name!r}, got shape {arr.shape}"
        )
    lim = joint_limits(model)
    if arr.dtype == np.float64 and arr.flags.c_contiguous and all_in_range(arr, lim):
        return arr
    bad = ~(np.abs(arr) <= lim)
    if bad.any():
        idx = np.argwhere(bad)[0]
        where = f" at index {tuple(int(i) for i in idx[:-1])}" if arr.ndim > 1 else ""
        unit = model.length_unit if model.prismatic[idx[-1]] else "rad"
        raise InputError(f"{name}: joint {idx[-1] + 1} ({model.joint_names[idx[-1]]}) is "
                         f"{arr[tuple(idx)]}{where}; expected finite values within "
                         f"+-{lim[idx[-1]]:g} {unit}")
    return arr


@dataclass(frozen=True, eq=False)
class FKResult:
    """Everything forward kinematics gives for joint values of shape (..., n).

    Attributes:
        axes: current joint axes u_k, shape (..., n, 3).
        points: current point on each joint axis, p_k = b_1 + ... + b_k, shape (..., n, 3).
        bodies: current body vectors b_k, k = 1..n+1, shape (..., n + 1, 3).
        position: end-effector point p, shape (..., 3).
        axial: u_a, shape (..., 3).
        transverse: u_t, shape (..., 3).
        er: Euler-Rodrigues parameters of the hand rotation R_n, shape (..., 4).
    """

    axes: F64
    points: F64
    bodies: F64
    position: F64
    axial: F64
    transverse: F64
    er: F64

    @property
    def rotation(self) -> F64:
        """Hand rotation R_n relative to the zero reference position, shape (..., 3, 3)."""
        return matrix_from_er(self.er)

    @property
    def hand_frame(self) -> F64:
        """Columns (u_t x u_a, u_t, u_a) in the base frame, shape (..., 3, 3)."""
        return hand_frame(self.axial, self.transverse)


def forward_kinematics(model: Manipulator, q: ArrayLike) -> FKResult:
    """Eqs (1)-(6) vectorised: joint values shape (..., n) -> :class:`FKResult`."""
    q = check_q(model, q)
    batch = q.shape[:-1]
    n = model.n
    e = er_identity(batch)
    axes = np.empty((*batch, n, 3))
    points = np.empty((*batch, n, 3))
    bodies = np.empty((*batch, n + 1, 3))
    pos = np.zeros((*batch, 3))
    for k in range(n):
        bodies[..., k, :] = er_rotate(e, model.bodies[k])  # eq (2)
        axes[..., k, :] = er_rotate(e, model.axes[k])  # eq (1)
        pos = pos + bodies[..., k, :]
        points[..., k, :] = pos
        if model.prismatic[k]:
            pos = pos + q[..., k, None] * axes[..., k, :]
        else:
            e = er_multiply(e, er_from_axis_angle(model.axes[k], q[..., k]))  # eqs (4)-(6)
    bodies[..., n, :] = er_rotate(e, model.bodies[n])
    pos = pos + bodies[..., n, :]
    ee = model.end_effector
    return FKResult(axes, points, bodies, pos, er_rotate(e, ee.axial),
                    er_rotate(e, ee.transverse), e)


def _flat(model: Manipulator, q: ArrayLike) -> tuple[F64, tuple[int, ...]]:
    """q as a C-contiguous (N, n) float64 array and its batch shape. A C-contiguous float64
    array of the right shape passes as is: the batch kernels check its range themselves on
    their way through it (a separate pass cost 40 % of the FK kernel's time) and
    :func:`_range_error` then names the joint; anything else goes through :func:`check_q`."""
    if not (isinstance(model, Manipulator) and type(q) is np.ndarray and q.dtype is _F64
            and q.ndim >= 1 and q.shape[-1] == model.n  # type: ignore[union-attr]
            and q.flags.c_contiguous):  # type: ignore[union-attr]
        q = check_q(model, q)
    assert isinstance(q, np.ndarray)
    return np.ascontiguousarray(q.reshape(-1, model.n)), q.shape[:-1]


def _range_error(model: Manipulator, q: ArrayLike) -> None:
    """A batch kernel found a value out of range: :func:`check_q` raises naming it."""
    check_q(model, q)
    raise AssertionError("a batch kernel declined q, but check_q accepts it")  # pragma: no cover


def _kernel_arrays(model: Manipulator) -> tuple:
    return K.kernel_arrays(model.axes, model.bodies, model.prismatic)


def _pack(model: Manipulator) -> F64:
    return K.pack_model(model.axes, model.bodies, model.prismatic)


def _karrays(model: Manipulator) -> tuple:
    """The batch kernels' arrays of ``model`` (built once per model)."""
    return derived(model, "_kernel_arrays", _kernel_arrays)


def _packed(model: Manipulator) -> F64:
    """The single-pose kernels' packed model (built once per model, then read as
    ``model._kernel_packed`` by the one-pose paths)."""
    return derived(model, "_kernel_packed", _pack)


_F64 = np.dtype(np.float64)
_empty = np.empty  # one global read, not two, on the one-pose paths (~0.03 us of ~0.75)


def _entry(kernel: object, *ndims: int) -> object:
    """``kernel`` compiled for C-contiguous float64 arrays of ``ndims`` dimensions, as its
    bare entry point: a call skips the dispatcher's per-call type resolution (0.33 -> 0.24
    us of a one-pose FK call). The caller vouches for the types, which the entry point does
    not check (it would read another dtype or number of dimensions wrongly): q a 1-D float64
    ndarray, the rest arrays it made itself; the packed kernels decline a q that is not
    contiguous. The kernel itself where numba compiles nothing (NUMBA_DISABLE_JIT)."""
    compile_ = getattr(kernel, "compile", None)
    if compile_ is None:
        return kernel
    return compile_(tuple(numba.types.Array(numba.types.float64, d, "C") for d in ndims))


_FK_ONE = None  # fk_pose_packed's entry point (_entry), built by the first one-pose call
_JAC_ONE = None  # jac_packed's


def _model_packed(model: object) -> F64 | None:
    """The packed model (None when ``model`` is not a Manipulator: the general path names
    it)."""
    return _packed(model) if isinstance(model, Manipulator) else None


def _fk_one(model: object) -> tuple[F64 | None, object]:
    """The packed model and the one-pose FK entry point (built on the first call)."""
    global _FK_ONE
    if _FK_ONE is None:
        _FK_ONE = _entry(K.fk_pose_packed, 1, 1, 1, 1)
    return _model_packed(model), _FK_ONE


def _jac_one(model: object) -> tuple[F64 | None, object]:
    """The packed model and the one-pose Jacobian entry point (built on the first call)."""
    global _JAC_ONE
    if _JAC_ONE is None:
        _JAC_ONE = _entry(K.jac_packed, 1, 1, 2)
    return _model_packed(model), _JAC_ONE


def _length_scale(model: Manipulator, length_unit: str | None) -> float:
    """Factor from the model's length unit to ``length_unit`` (None: 1, the model's own)."""
    return 1.0 if length_unit is None else 1.0 / length_scale(length_unit, model.length_unit,
                                                                "length_unit")


def _q_in_model_unit(model: Manipulator, q: ArrayLike, s: float) -> ArrayLike:
    """Prismatic joint values given in ``length_unit`` (model unit times ``s``) back in the
    model's unit; q as it is when nothing changes."""
    if s == 1.0 or not np.any(model.prismatic):
        return q
    return np.where(model.prismatic, np.asarray(q, dtype=float) / s, q)


def end_effector_pose(model: Manipulator, q: ArrayLike, *,
                      out: F64 | None = None, length_unit: str | None = None,
                      threads: int | None = None) -> tuple[F64, F64]:
    """Fast forward kinematics of the end effector only.

    Args:
        q: joint values, shape (..., n) (rad; prismatic ones in ``length_unit``).
        length_unit: the unit of lengths in and out (``"m"``: metres, as Pinocchio and the
            Robotics Toolbox use; :data:`zrp.units.LENGTH_UNITS`); None: the model's own. The
            same kernel, its result scaled.
        out: optional buffer for the result, float64, C-contiguous, shape (..., 7) with the
            batch shape of ``q`` (position, then Euler-Rodrigues parameters). Reusing one
            buffer over many calls spares the allocation of a fresh result, which for large
            batches costs as much as a fifth of the kinematics (the OS zero-fills new pages).
        threads: threads the batch is split over (:mod:`zrp.kinematics.parallel`; the same
            result to the bit); None: every usable core from
            :data:`~zrp.kinematics.parallel.MIN_FK_POSES` poses on, one below (a single pose
            always runs on the calling thread).

    Returns:
        position p, shape (..., 3), and Euler-Rodrigues parameters of R_n, shape (..., 4)
        (views into ``out`` when it is given).

    Raises:
        InputError: q out of range or malformed, or ``out`` not a float64 C-contiguous
            array of shape (..., 7) matching q's batch shape.
    """
    if (out is None and length_unit is None and type(q) is np.ndarray and q.ndim == 1
            and q.dtype is _F64):  # type: ignore[union-attr]
        # one pose, ~0.7 us a call: the packed model kept on the model, the kernel's bare
        # entry point (_entry); the kernel declines a wrong length or value and the general
        # path below names it
        try:
            packed = model._kernel_packed  # type: ignore[attr-defined]  # kept by _packed
        except AttributeError:
            packed = None
        fk = _FK_ONE
        if packed is None or fk is None:
            packed, fk = _fk_one(model)
        p, er = _empty(3), _empty(4)
        if packed is not None and fk(q, packed, p, er):  # type: ignore[operator]
            return p, er
    if length_unit is not None:
        s = _length_scale(model, length_unit)
        p, er = end_effector_pose(model, _q_in_model_unit(model, q, s), out=out,
                                  threads=threads)
        p *= s
        return p, er
    qf, batch = _flat(model, q)
    res = _out_buffer(out, (*batch, 7)).reshape(-1, 7)
    t = thread_count(qf.shape[0], MIN_FK_POSES, threads)
    if not run_split(K.fk_pose_batch, qf, (*_karrays(model), joint_limits(model)), (res,), t):
        _range_error(model, q)
    res = res.reshape(*batch, 7)
    return res[..., :3], res[..., 3:]


def _out_buffer(out: object, shape: tuple[int, ...]) -> F64:
    """``out`` checked as the result buffer of :func:`end_effector_pose` (or a new one)."""
    if out is None:
        return recycled_empty(shape)  # a fresh 56 MB costs a third of the kernel (zero-fill)
    if not (isinstance(out, np.ndarray) and out.dtype == np.float64
            and out.flags.c_contiguous and out.flags.writeable and out.shape == shape):
        got = (f"{type(out).__name__} {getattr(out, 'dtype', '')} shape "
               f"{getattr(out, 'shape', '?')}")
        raise InputError(f"out: expected a writeable C-contiguous float64 array of shape "
                         f"{shape} (q's batch shape, then 7), got {got}")
    return out


def jacobian(model: Manipulator, q: ArrayLike, *, rows: str = "wv",
             length_unit: str | None = None, threads: int | None = None) -> F64:
    """Eq (7): J with J qdot = [omega_h; V_p], shape (..., 6, n).

    Revolute column k: [u_k; u_k x (p - p_k)]; prismatic column k: [0; u_k]. Rows 0-2 are in
    rad per joint unit, rows 3-5 in length unit per joint unit (base frame).

    Options for the conventions other libraries use (the same kernel, its result reordered
    and scaled): ``rows="vw"`` gives [V_p; omega_h], the row order of Pinocchio's
    ``getFrameJacobian(..., LOCAL_WORLD_ALIGNED)`` and the Robotics Toolbox's ``jacob0``;
    ``length_unit="m"`` gives V_p in m/rad (prismatic joint values in m). ``threads``: as in
    :func:`end_effector_pose` (from :data:`~zrp.kinematics.parallel.MIN_JAC_POSES` poses on).
    """
    if rows not in ("wv", "vw"):
        raise InputError(f"rows: expected 'wv' ([omega; v], eq 7) or 'vw' ([v; omega], "
                         f"Pinocchio/RTB), got {rows!r}")
    if rows == "vw" or length_unit is not None:
        s = _length_scale(model, length_unit)
        jac = jacobian(model, _q_in_model_unit(model, q, s), threads=threads)
        jac[..., 3:, :] *= np.where(model.prismatic, 1.0, s)  # m/m stays for a slide
        return np.concatenate([jac[..., 3:, :], jac[..., :3, :]], axis=-2) if rows == "vw" \
            else jac
    if type(q) is np.ndarray and q.ndim == 1 and q.dtype is _F64:  # type: ignore[union-attr]
        try:  # one pose: as in end_effector_pose
            packed = model._kernel_packed  # type: ignore[attr-defined]  # kept by _packed
        except AttributeError:
            packed = None
        jac_one = _JAC_ONE
        if packed is None or jac_one is None:
            packed, jac_one = _jac_one(model)
        if packed is not None:
            jac = _empty((6, model.n))
            if jac_one(q, packed, jac):  # type: ignore[operator]
                return jac
    qf, batch = _flat(model, q)
    jac = recycled_empty((qf.shape[0], 6, model.n))
    t = thread_count(qf.shape[0], MIN_JAC_POSES, threads)
    if not run_split(K.jac_batch, qf, (*_karrays(model), joint_limits(model)),
                     (np.empty((0, 7)), jac), t):
        _range_error(model, q)
    return jac.reshape(*batch, 6, model.n)
