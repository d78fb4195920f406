"""A shipped URDF's inertials made acceptable to MuJoCo, each change said in words.

Pinocchio (and most URDF tools) load any ``<inertial>``; MuJoCo refuses a moving body whose
mass or inertia is below ``mjMINVAL`` (1e-15), an inertia tensor that is not positive
definite and one whose principal moments A <= B <= C violate A + B >= C. Shipped files have
all of these: a point mass (the Staubli TX40's ``link_6``: 0.2 kg, inertia zero), a massless
link between two joints or at the end, a tensor typed with a wrong sign, and the same on
links off the arm (a mobile robot's antenna, a camera). :func:`repair_inertials` edits the
spec, after the joints off the arm's chain are made fixed, so that it compiles:

* **a moving link** (one that turns with a joint of the arm, itself or rigidly attached):

  - principal moments below ``I_MIN`` (a point mass, or eigenvalues <= 0: not positive
    definite) are raised to the floor ``max(2/5 m r0^2, I_MIN)`` with ``r0 = R_BALL`` =
    0.1 mm: the link becomes a uniform ball of 0.1 mm radius with the same mass and centre.
    A point mass is exact physics (its torques are the m (point) terms, which are kept); the
    ball adds ``2/5 m r0^2`` to the inertia about the centre (8e-10 kg m^2 for the TX40's
    0.2 kg), so a torque changes by at most that times the link's angular acceleration, a
    fraction 0.4 (r0/d)^2 of the point mass's own m d^2 at a distance d from an axis:
    1.6e-6 at d = 5 cm, below the 5 significant digits of a torque log. (A 1 mm ball, tried
    first, changed a light arm's torques by 5.6e-6 of their size.) Tested against
    Pinocchio's RNEA on the TX40 and on the point-mass arms of tests/mjcf/test_arm.py.
    MuJoCo's own ``boundinertia`` raises the moments of every body, silently; this names
    the link. The floor leaves a joint that turns only a point mass on its axis (the
    TX40's joint 6) with an inertia of that size: a forward simulation of it without
    armature is stiff (MuJoCo warns), as the file's model is singular there;
  - a triangle violation A + B < C is removed by the nearest change of the principal moments
    (the Euclidean projection onto A + B = C, landing 1e-9 C inside): A and B grow and C
    shrinks by (C - A - B)/3 each; the principal axes are kept. (MuJoCo's ``balanceinertia``
    replaces all three by their mean, a larger change, and silently);
  - a link that moves with a joint and has no mass in its rigid group (a massless frame
    between two joints, a massless end link) is given ``M_MIN`` = 1e-9 kg and ``I_MIN`` =
    1e-12 kg m^2 at its origin (MuJoCo's ``boundmass`` would add mass to every body): the
    torques change by about M_MIN g r, below 1e-8 N m on a 1 m arm;
  - a negative or non-finite mass, or a non-finite tensor, is refused
    (:class:`mjcf.errors.MJCFImportError` naming the link): nothing physical is near it;

* **a link that does not move** with the arm (welded to the base once the other joints are
  fixed: a wheel, an antenna, a head, the base itself) has an invalid inertial (any of the
  above) removed (mass 0): with the base fixed it does not enter the arm's torques.

Every change returns a note naming the link, its old and its new values. MJCF files are
MuJoCo's own format and are not touched (:func:`mjcf.arm.load_arm` calls this on URDFs).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from mjcf.errors import MJCFImportError
from zrp.arrays import F64

__all__ = ["I_MIN", "M_MIN", "R_BALL", "kinematic_copy", "nearest_valid_moments",
           "repair_inertials"]

#: The smallest principal moment kept, kg m^2 (1 kg at 1 um); MuJoCo refuses <= 1e-15.
I_MIN = 1e-12
#: The mass given to a massless moving link, kg.
M_MIN = 1e-9
#: The radius of the ball a point mass becomes, m.
R_BALL = 1e-4
#: How far inside the triangle inequality a repaired inertia lands, relative to C.
_INSIDE = 1e-9


def nearest_valid_moments(moments: F64, mass: float) -> F64:
    """The principal moments (3,) made valid: each at least ``max(2/5 m R_BALL^2, I_MIN)``,
    then A + B >= C restored by the projection of the module docstring (order kept)."""
    lam = np.array(moments, dtype=float)
    floor = max(0.4 * max(mass, 0.0) * R_BALL**2, I_MIN)
    lam = np.maximum(lam, floor)
    order = np.argsort(lam)
    a, b, c = lam[order]
    excess = c - a - b
    if excess >= 0.0:
        d = (excess + _INSIDE * c) / 3.0
        lam[order] = (a + d, b + d, c - d)
    return lam


def _tensor(body: mujoco._specs.MjsBody) -> F64:
    """The body's inertia tensor about its centre, in its inertial frame (``iquat``)."""
    full = np.array(body.fullinertia, dtype=float)
    if not math.isnan(full[0]):
        xx, yy, zz, xy, xz, yz = full
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    return np.diag(np.array(body.inertia, dtype=float))


def _set_tensor(body: mujoco._specs.MjsBody, tensor: F64) -> None:
    body.fullinertia = list(_six(0.5 * (tensor + tensor.T)))
    body.inertia = [0.0, 0.0, 0.0]


def _fmt(values: F64) -> str:
    return "(" + ", ".join(f"{v:.4g}" for v in values) + ")"


def _moves(body: mujoco._specs.MjsBody) -> bool:
    """Whether the body turns with some joint (its own or an ancestor's)."""
    b = body
    while b is not None and b.name != "world":
        if len(b.joints) > 0:
            return True
        parent = b.parent
        b = None if parent is None or parent.name == b.name else parent
    return False


def _invalid(mass: float, moments: F64) -> str | None:
    """Why MuJoCo would refuse this inertial (in words), or None."""
    lo, mid, hi = np.sort(moments)
    if mass > 0.0 and lo < I_MIN:
        if np.all(np.abs(moments) < I_MIN):
            return "a point mass (inertia zero)"
        return "its inertia is not positive definite"
    if lo < 0.0:
        return "its inertia is not positive definite"
    if lo + mid < hi:
        return "its inertia violates the triangle inequality A + B >= C"
    return None


def _repair_moving(body: mujoco._specs.MjsBody) -> str | None:
    mass = float(body.mass)
    tensor = _tensor(body)
    if not (math.isfinite(mass) and mass >= 0.0 and np.isfinite(tensor).all()):
        raise MJCFImportError(f"link {body.name!r}: its inertial (mass {mass:g} kg, inertia "
                              f"{_fmt(_six(tensor))} kg m^2 as xx, yy, zz, xy, xz, yz) is not "
                              "physical and the link moves with the arm: correct the URDF")
    w, v = np.linalg.eigh(tensor)
    why = _invalid(mass, w)
    if why is None:
        return None
    new = nearest_valid_moments(w, mass)
    _set_tensor(body, v @ np.diag(new) @ v.T)
    return (f"link {body.name!r}: {why}; principal moments {_fmt(w)} kg m^2 made "
            f"{_fmt(new)} (the nearest valid inertia, mass {mass:g} kg and centre kept)")


def _drop_static(body: mujoco._specs.MjsBody) -> str | None:
    mass = float(body.mass)
    tensor = _tensor(body)
    if not (math.isfinite(mass) and np.isfinite(tensor).all()):
        why: str | None = "not finite"
    elif mass < 0.0:
        why = "a negative mass"
    else:
        why = _invalid(mass, np.linalg.eigh(tensor)[0])
    if why is None:
        return None
    body.mass = 0.0
    body.fullinertia = [math.nan, 0.0, 0.0, 0.0, 0.0, 0.0]
    body.inertia = [0.0, 0.0, 0.0]
    return (f"link {body.name!r} does not move with the arm and its inertial is invalid "
            f"({why}: mass {mass:g} kg, inertia {_fmt(_six(tensor))} kg m^2 as xx, yy, zz, "
            "xy, xz, yz): left out (no effect on the arm's torques with the base fixed)")


def _six(t: F64) -> F64:
    return np.array([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]])


def _group(body: mujoco._specs.MjsBody) -> list[mujoco._specs.MjsBody]:
    """The body and the bodies welded to it below (no joint between)."""
    out = [body]
    stack = list(body.bodies)
    while stack:
        b = stack.pop()
        if len(b.joints) == 0:
            out.append(b)
            stack.extend(b.bodies)
    return out


def _give_mass(body: mujoco._specs.MjsBody) -> str | None:
    if any(float(b.mass) > 0.0 for b in _group(body)):
        return None
    body.explicitinertial = True
    body.mass = M_MIN
    body.ipos = [0.0, 0.0, 0.0]
    body.iquat = [1.0, 0.0, 0.0, 0.0]
    _set_tensor(body, np.eye(3) * I_MIN)
    joints = ", ".join(repr(j.name) for j in body.joints)
    return (f"link {body.name!r} moves with joint {joints} but has no mass (nor has anything "
            f"rigidly attached to it): given {M_MIN:g} kg and {I_MIN:g} kg m^2 at its origin "
            "(MuJoCo needs mass on a moving body; the torques change by < 1e-8 N m)")


def repair_inertials(spec: mujoco.MjSpec) -> tuple[str, ...]:
    """Edit ``spec``'s inertials as the module docstring says; the notes of what changed.

    Raises:
        MJCFImportError: a moving link with a negative or non-finite mass or inertia.
    """
    notes: list[str] = []
    for body in spec.bodies[1:]:
        if not body.explicitinertial:
            continue
        note = _repair_moving(body) if _moves(body) else _drop_static(body)
        if note is not None:
            notes.append(note)
    for body in spec.bodies[1:]:
        if len(body.joints) > 0:
            note = _give_mass(body)
            if note is not None:
                notes.append(note)
    return tuple(notes)


def kinematic_copy(spec: mujoco.MjSpec) -> mujoco.MjModel:
    """``spec`` compiled with every body given unit mass and inertia: its kinematics (bodies,
    joints, their order) whatever its inertials are.

    Raises:
        ValueError: MuJoCo cannot compile it for another reason.
    """
    copy = spec.copy()
    for body in copy.bodies[1:]:
        body.explicitinertial = True
        body.mass = 1.0
        body.fullinertia = [math.nan, 0.0, 0.0, 0.0, 0.0, 0.0]
        body.inertia = [1.0, 1.0, 1.0]
    return copy.compile()
