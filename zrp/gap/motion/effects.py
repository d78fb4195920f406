"""Effects that live in motion, as joint corrections of the static engine's ``dq`` kind.

Each effect maps the commanded joint trajectory u(t) (:class:`~zrp.gap.motion.data.Trajectory`)
to the actual one, q'(t) = u(t) + d(t; theta), and gives the exact derivative D = dd/dtheta:

======================= ============================== ===== =====================================
effect                  parameter (per joint k)        unit  d(t; theta)
======================= ============================== ===== =====================================
``sync_delay``          ``sync.delay`` (one, shared)   s     u(t - delta) - u(t): the tracker's
                                                             clock runs delta ahead (eq. M3)
``servo_lag``           ``q{k}.lag``                   s     first-order servo, tau y' + y = u
                                                             (eq. M1, ``kernels.first_order_lag``)
``reversal_friction``   ``q{k}.friction``              rad   play of half-width r: Coulomb friction
                                                             F against a servo of stiffness kp,
                                                             r = F / kp (eq. M2, stick-slip at
                                                             velocity reversals)
``dynamic_compliance``  ``q{k}.dyn_compliance``        rad/  -c tau_k(t): deflection under the full
                        [``q{k}.dyn_omega``            (N m) inverse-dynamics torque (gravity and
                        ``q{k}.dyn_zeta``]             rad/s inertia; MJCF inertias; passed in as
                                                       1     an array); with omega and zeta,
                                                             c omega^2 x, x'' + 2 zeta omega x'
                                                             + omega^2 x = -tau_k (eq. M8: the
                                                             spring 1/c against the joint's own
                                                             inertia; unit static gain; the
                                                             quasi-static limit omega -> infinity)
``residual_vibration``  ``q{k}.vib_gain``              1     g y(t): a lightly damped mode driven
                        ``q{k}.vib_omega``             rad/s by the joint's commanded acceleration,
                        ``q{k}.vib_zeta``              1     y'' + 2 zeta omega y' + omega^2 y =
                                                             -u_k'' (eq. M5, ``kernels.
                                                             mode_response``): the lag under
                                                             acceleration and the ringing after
                                                             each stop (g = 1 for a single link)
======================= ============================== ===== =====================================

With the arm's own stiffness s_k(t) and damping b_k(t) per unit inertia (``terms``, from the
MJCF by ``mjcf.mode_terms``) the mode is y'' + (2 zeta omega + b_k) y' + (omega^2 + s_k) y =
f (eq. M6); with a sync delay or a servo lag on the joint in the model, it is driven through
them, f = -L_tau[u_k''(t - delta)] (eq. M7), and its derivatives in delta and tau join those
parameters' columns (:attr:`Column.via`, merged by :func:`linearise`).

Compliance and vibration are both a spring against the joint's inertia; what tells them apart
is what the spring carries: the compliance's the joint's whole torque, gravity and the other
joints' coupling included (eq. M8), the vibration's mode only the joint's own acceleration
(eq. M5: the transmission behind a servo that feeds the gravity forward). A joint carries one
of the two (``search._one_mode_per_joint``).

The nonlinear ones (delay, lag, play, the mode's omega and zeta) are linearised at the current
estimate theta0: q' = u + [d(theta0) - D(theta0) theta0] + D(theta0) theta; the bracket (the
*shift*) goes into the joint values of :class:`MotionContext` and D into a ``dq`` basis, so the
static :class:`~zrp.gap.model.problem.Problem` and its analytic Jacobian apply unchanged; the search
re-linearises until theta stops moving (Gauss-Newton on the exact model; the mode's omega and
zeta start from the profile search of :mod:`zrp.gap.motion.profile`, within a trust region,
:func:`limit_step`).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.model.context import KINDS, Context, ParamSpec
from zrp.gap.motion.choices import MOTION_EFFECTS
from zrp.gap.motion.columns import Deviation, JointColumn, combine
from zrp.gap.motion.data import Trajectory
from zrp.gap.motion.kernels import first_order_lag, mode_response, play

__all__ = ["MOTION_EFFECTS", "POSITIVE", "Column", "JointColumn", "MotionContext", "MotionParam",
           "effect_columns", "joint_mode", "limit_step", "linearise", "mode_band", "plausible",
           "tested"]

#: effects whose parameters are physically positive (a negative estimate is not that effect)
POSITIVE = ("servo_lag", "reversal_friction", "dynamic_compliance", "residual_vibration")
#: where the mode's linearisation starts when no value is given (rad/s, 1)
VIB_START = (2.0 * np.pi * 10.0, 0.1)
#: the nonlinear parameters of a mode (residual vibration, eq. M5; compliance's response, M8)
MODE_NONLINEAR = (".vib_omega", ".vib_zeta", ".dyn_omega", ".dyn_zeta")
#: the largest damping ratio of a compliant joint's servo response taken as physical
MAX_SERVO_ZETA = 3.0
#: a joint must move at least this far (rad or length unit) to carry a per-joint effect.
MIN_TRAVEL = 1e-4


class MotionParam(ParamSpec):
    """A :class:`~zrp.gap.model.context.ParamSpec` of a motion effect (kind ``dq``)."""

    def __post_init__(self) -> None:
        if self.effect not in MOTION_EFFECTS or self.kind not in KINDS or self.kind != "dq":
            raise InputError(f"MotionParam {self.name}: effect {self.effect!r} must be one of "
                             f"{MOTION_EFFECTS} with kind 'dq'")
        if self.basis is None:
            raise InputError(f"MotionParam {self.name}: a basis is required")
        if not self.group:
            object.__setattr__(self, "group", self.name)


@dataclass(frozen=True, eq=False)
class MotionContext(Context):
    """A :class:`~zrp.gap.model.context.Context` whose joint values carry the linearisation shift of
    the nonlinear motion effects: q = commanded + shift, shape (S, n).

    q is computed when asked, not cached: a search holds several fits, and a cached q of every
    sample beside the shift was 48 bytes a sample per fit; a
    :class:`~zrp.gap.model.problem.Problem` takes the rows of its poses only (:meth:`q_of`)."""

    shift: F64 | None = None

    @property
    def q(self) -> F64:  # type: ignore[override]
        q = self.meas.q_pose
        return q if self.shift is None else q + self.shift

    def q_of(self, poses: NDArray[np.int64]) -> F64:
        q = self.meas.q_pose[poses]
        return q if self.shift is None else q + self.shift[poses]


@dataclass(frozen=True, eq=False)
class Column:
    """One motion parameter evaluated at a value.

    Attributes:
        name, unit, effect: as in :class:`~zrp.gap.model.context.ParamSpec`.
        joint: 1-based joint, 0 for a parameter acting on all joints.
        value: the value at which d and D are evaluated.
        d: the joint deviation d(theta), shape (S, n) (a :class:`JointColumn` when it acts on
            one joint).
        D: its derivative, shape (S, n) (idem).
        via: for a coupling column (eq. M7), the parameter through which ``name`` acts
            here (the mode's gain); "" for the parameter's own column.
    """

    name: str
    unit: str
    effect: str
    joint: int
    value: float
    d: Deviation
    D: Deviation
    via: str = ""


def _one_joint(s: int, n: int, k: int, col: F64) -> JointColumn:
    return JointColumn(n, k, np.array(col, dtype=float).reshape(s))


def _moving(traj: Trajectory, joints: Collection[int] | None = None) -> list[int]:
    """0-based moving joints, of ``joints`` (1-based; None: all) only."""
    return [k for k in range(traj.n_joints) if (joints is None or k + 1 in joints)
            and np.ptp(traj.q[:, k]) > MIN_TRAVEL]


def _sync(traj: Trajectory, values: Mapping[str, float]) -> list[Column]:
    delta = float(values.get("sync.delay", 0.0))
    ts = traj.t - delta
    d = traj.spline(ts) - traj.q
    D = -traj.spline(ts, 1)
    return [Column("sync.delay", "s", "sync_delay", 0, delta, d, D)]


def _per_joint(traj: Trajectory, values: Mapping[str, float], suffix: str, unit: str,
               effect: str, response: Callable[[F64, float], tuple[F64, F64]],
               joints: Collection[int] | None = None) -> list[Column]:
    """One column ``q{k}.{suffix}`` per moving joint k of an effect that passes the joint's
    commanded path u (S,) through ``response(u, value) -> (y, dy/dvalue)``, shapes (S,):
    d = y - u and D = dy/dvalue on joint k, zero on the others."""
    s, n = traj.q.shape
    out = []
    for k in _moving(traj, joints):
        name = f"q{k + 1}.{suffix}"
        v = float(values.get(name, 0.0))
        y, dy = response(traj.q[:, k], v)
        out.append(Column(name, unit, effect, k + 1, v,
                          _one_joint(s, n, k, y - traj.q[:, k]), _one_joint(s, n, k, dy)))
    return out


def _lag(traj: Trajectory, values: Mapping[str, float], joints: Collection[int] | None = None
         ) -> list[Column]:
    return _per_joint(traj, values, "lag", "s", "servo_lag",
                      lambda u, tau: first_order_lag(traj.t, u, tau), joints)


def _friction(traj: Trajectory, values: Mapping[str, float],
              joints: Collection[int] | None = None) -> list[Column]:
    return _per_joint(traj, values, "friction", "rad", "reversal_friction", play, joints)


def _compliance(traj: Trajectory, values: Mapping[str, float], torque: F64 | None,
                joints: Collection[int] | None = None) -> list[Column]:
    """Per joint carrying a torque: c (d = c y, D = y) with y = -tau_k quasi-statically, or,
    when ``q{k}.dyn_omega`` is in ``values``, y = omega^2 x with x'' + 2 zeta omega x' +
    omega^2 x = -tau_k (eq. M8: the joint's spring 1/c against its own inertia, unit static
    gain) and the columns of omega and zeta (d = 0, D = c dy/dparameter), as
    :func:`_vibration` does for the mode."""
    if torque is None:
        return []
    s, n = traj.q.shape
    out = []
    for k in range(n):
        if (joints is not None and k + 1 not in joints) or not np.any(torque[:, k] != 0.0):
            continue
        p = f"q{k + 1}.dyn_"
        c = float(values.get(p + "compliance", 0.0))
        if p + "omega" not in values:  # the joint yields to the torque it carries
            D = _one_joint(s, n, k, -torque[:, k])
            out.append(Column(p + "compliance", "rad/(N m)", "dynamic_compliance", k + 1, c,
                              JointColumn(n, k, c * D.col), D))
            continue
        lo, hi = mode_band(traj.rate_hz)
        w = float(np.clip(values[p + "omega"], 0.5 * lo, 2.0 * hi))
        z = float(np.clip(values.get(p + "zeta", 1.0), 1e-3, 4.0))
        x, dw, dz = mode_response(traj.t, -torque[:, k], w, z)
        y = w * w * x
        zero = JointColumn(n, k, np.zeros(s))
        out += [Column(p + "compliance", "rad/(N m)", "dynamic_compliance", k + 1, c,
                       _one_joint(s, n, k, c * y), _one_joint(s, n, k, y)),
                Column(p + "omega", "rad/s", "dynamic_compliance", k + 1, w, zero,
                       _one_joint(s, n, k, c * (2.0 * w * x + w * w * dw))),
                Column(p + "zeta", "1", "dynamic_compliance", k + 1, z, zero,
                       _one_joint(s, n, k, c * w * w * dz))]
    return out


def _drive(traj: Trajectory, k: int, delay: float | None, lag: float | None
           ) -> tuple[F64, F64, F64]:
    """The mode's forcing f = -L_tau[u_k''(t - delta)] (eq. M5 through the sync delay and the
    joint's servo lag, which act before the transmission: eq. M7) and df/ddelta, df/dtau
    (None: that effect is not in the model; its derivative is then zero)."""
    zero = np.zeros(traj.n_samples)
    if delay is None:
        a, a3 = traj.qdd[:, k], zero
    else:
        ts = traj.t - delay
        a, a3 = traj.spline(ts, 2)[:, k], traj.spline(ts, 3)[:, k]
    da = zero
    if lag is not None:
        a, da = first_order_lag(traj.t, a, lag)
        a3 = first_order_lag(traj.t, a3, lag)[0] if delay is not None else zero
    return -a, a3, -da


def joint_mode(traj: Trajectory, k: int, omega: float, zeta: float, terms: F64 | None,
               derivatives: bool = True, forcing: F64 | None = None) -> tuple[F64, F64, F64]:
    """The mode of 0-based joint ``k`` driven by ``forcing`` (default: its negated commanded
    acceleration, eq. M5), with the arm's own stiffness and damping along the path when
    ``terms`` (S, n, 2) are given (eq. M6): y, dy/domega, dy/dzeta, shape (S,) each
    (``kernels.mode_response``)."""
    f = -traj.qdd[:, k] if forcing is None else forcing
    if terms is None:
        return mode_response(traj.t, f, omega, zeta, derivatives)
    return mode_response(traj.t, f, omega, zeta, derivatives, terms[:, k, 0], terms[:, k, 1])


def _vibration(traj: Trajectory, values: Mapping[str, float], terms: F64 | None = None,
               couple: Mapping[str, float] | None = None,
               joints: Collection[int] | None = None) -> list[Column]:
    """Per moving joint: gain (d = g y, D = y), omega and zeta (d = 0, D = g dy/dparameter),
    so that :func:`linearise` gives the Gauss-Newton step of the exact model (eq. M5, M6).
    With ``couple`` (``sync.delay``, ``q{k}.lag`` of the effects in the model) the mode is
    driven through them (eq. M7) and columns named after them carry g dy/ddelta, g dy/dtau
    (``via`` the joint's gain: :func:`linearise` adds them to those parameters' columns)."""
    s, n = traj.q.shape
    lo, hi = mode_band(traj.rate_hz)
    couple = dict(couple or {})
    out = []
    for k in _moving(traj, joints):
        p = f"q{k + 1}.vib_"
        g = float(values.get(p + "gain", 0.0))
        # a Gauss-Newton step may leave the physical range: linearise at the nearest point of
        # a wide box (the search rejects a final estimate outside the plausible one)
        w = float(np.clip(values.get(p + "omega", VIB_START[0]), 0.5 * lo, 2.0 * hi))
        z = float(np.clip(values.get(p + "zeta", VIB_START[1]), 1e-4, 2.0))
        delay, lag = couple.get("sync.delay"), couple.get(f"q{k + 1}.lag")
        f, f_delay, f_lag = _drive(traj, k, delay, lag)
        y, dw, dz = joint_mode(traj, k, w, z, terms, forcing=f)
        zero = JointColumn(n, k, np.zeros(s))
        out += [Column(p + "gain", "1", "residual_vibration", k + 1, g,
                       _one_joint(s, n, k, g * y), _one_joint(s, n, k, y)),
                Column(p + "omega", "rad/s", "residual_vibration", k + 1, w, zero,
                       _one_joint(s, n, k, g * dw)),
                Column(p + "zeta", "1", "residual_vibration", k + 1, z, zero,
                       _one_joint(s, n, k, g * dz))]
        for name, df, eff, j in (("sync.delay", f_delay, "sync_delay", 0),
                                 (f"q{k + 1}.lag", f_lag, "servo_lag", k + 1)):
            if name in couple:
                dy = joint_mode(traj, k, w, z, terms, derivatives=False, forcing=df)[0]
                out.append(Column(name, "s", eff, j, couple[name], zero,
                                  _one_joint(s, n, k, g * dy), via=p + "gain"))
    return out


def mode_band(rate_hz: float) -> tuple[float, float]:
    """The angular frequencies (rad/s) a mode may have to be seen on a stream sampled at
    ``rate_hz``: from 0.5 Hz (a few cycles in a dwell-to-dwell stretch of seconds) to 40 % of
    the Nyquist frequency (at least 5 samples per period)."""
    return 2.0 * np.pi * 0.5, 0.4 * np.pi * rate_hz


def plausible(name: str, value: float, rate_hz: float) -> bool:
    """Whether a mode parameter's estimate is physical: 0 < zeta < 1 (a compliance response's
    0 < zeta <= :data:`MAX_SERVO_ZETA`) and omega in :func:`mode_band` (other parameters:
    True; their sign is checked with :data:`POSITIVE`)."""
    if name.endswith(".vib_zeta"):
        return 0.0 < value < 1.0
    if name.endswith(".dyn_zeta"):  # a servo may be overdamped
        return 0.0 < value <= MAX_SERVO_ZETA
    if name.endswith((".vib_omega", ".dyn_omega")):
        lo, hi = mode_band(rate_hz)
        return lo <= value <= hi
    return True


def limit_step(name: str, old: float | None, new: float) -> float:
    """A trust region for the Gauss-Newton steps of a mode's (or a compliance response's, eq.
    M8) omega (a factor 1.5 per step) and zeta (a factor 3): far from the optimum, the
    linearisation of a ringing response overshoots. Other parameters: ``new`` unchanged."""
    if old is None or old <= 0.0 or not name.endswith(MODE_NONLINEAR):
        return new
    f = 1.5 if name.endswith(("vib_omega", "dyn_omega")) else 3.0
    return float(np.clip(new, old / f, old * f))


def tested(spec: ParamSpec) -> bool:
    """Whether a parameter enters the Wald test of its joint group: all but the omega and zeta
    of a mode or of a compliance response (whose "absent" value is not zero: the gain alone
    says whether the mode is there)."""
    return not spec.name.endswith(MODE_NONLINEAR)


def effect_columns(traj: Trajectory, effect: str, values: Mapping[str, float],
                   torque: F64 | None = None, terms: F64 | None = None,
                   couple: Mapping[str, float] | None = None,
                   joints: Collection[int] | None = None) -> list[Column]:
    """All parameters of one motion effect evaluated at ``values`` (missing names: 0), of the
    1-based ``joints`` only for a per-joint effect (None: all; the others are not evaluated:
    a fit keeping one joint's mode does not hold every joint's columns of the whole stream).

    Args:
        torque: inverse-dynamics torque per sample and joint, N m, shape (S, n), or None
            (then ``dynamic_compliance`` has no parameters).
        terms: the arm's own stiffness (1/s^2) and damping (1/s) per unit inertia, shape
            (S, n, 2) (``mjcf.mode_terms``, eq. M6), or None (the mode alone, eq. M5).
        couple: for ``residual_vibration``, the sync delay and servo lags in the model that
            act before the transmission (eq. M7); None: none.
    """
    if effect == "sync_delay":
        return _sync(traj, values)
    if effect == "servo_lag":
        return _lag(traj, values, joints)
    if effect == "reversal_friction":
        return _friction(traj, values, joints)
    if effect == "dynamic_compliance":
        return _compliance(traj, values, torque, joints)
    if effect == "residual_vibration":
        return _vibration(traj, values, terms, couple, joints)
    raise InputError(f"effect: {effect!r} is not a motion effect; valid: "
                     f"{', '.join(MOTION_EFFECTS)}")


def linearise(cols: list[Column]) -> tuple[F64 | None, list[MotionParam]]:
    """The shift sum_c [d_c - D_c theta_c] (S, n) (None when zero) and the ``dq`` specs with
    basis D_c, so that q' = commanded + shift + sum_c D_c theta_c. Columns of the same name
    (a parameter's own and its coupling columns, eq. M7) are one parameter: d and D add."""
    merged: dict[str, Column] = {}
    for c in cols:
        o = merged.get(c.name)
        if o is None:
            merged[c.name] = c
        else:
            own = c if not c.via else o
            merged[c.name] = Column(c.name, own.unit, own.effect, own.joint, own.value,
                                    combine(o.d, c.d), combine(o.D, c.D))
    shift = None
    specs = []
    for c in merged.values():
        part = combine(c.d, c.D, -c.value)
        if isinstance(part, JointColumn):
            if np.any(part.col != 0.0):
                if shift is None:
                    shift = np.zeros(part.shape)
                shift[:, part.k] += part.col
        elif np.any(part != 0.0):
            shift = part if shift is None else shift + part
        basis = c.D  # the column's own array, frozen: no copy of (S, n) per parameter
        basis.setflags(write=False)
        specs.append(MotionParam(c.name, c.unit, c.effect, "dq", c.joint, 0, basis,
                                 f"q{c.joint}" if c.joint else "all"))
    return shift, specs
