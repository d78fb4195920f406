"""Read a serial arm from an MJCF file into a ZRP model (a ``.urdf`` path is read by
:mod:`zrp.model.urdf`, without MuJoCo: kinematics need no meshes or inertias).

The zero reference position is MuJoCo's qpos = 0 (not the model's ``qpos0``/``ref``): at
qpos = 0 MuJoCo's kinematics gives, for each hinge/slide joint on the chain from the world to
the end body, its world axis (u_{k,0}) and anchor (the point on joint k); the body vectors are
the differences of consecutive anchors, b_{1,0} being the first anchor (from the world origin)
and b_{n+1,0} the vector from the last anchor to the end-effector point. The end effector is a
site (or a body frame): its position is p and its frame's z and y columns give u_{a,0} and
u_{t,0} (the ``zrp.hand_frame`` convention). Everything is expressed in the world frame.
"""

from __future__ import annotations

import os
from pathlib import Path

import mujoco
import numpy as np

from mjcf.assets import check_model_files
from mjcf.errors import MJCFImportError
from zrp.errors import InputError
from zrp.model.manipulator import Manipulator
from zrp.model.urdf import from_urdf
from zrp.textio import read_text, text_encoding
from zrp.units import metres_per_unit

__all__ = ["from_mjcf", "load_mujoco_model", "manipulator_from_mujoco"]

_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
_SLIDE = int(mujoco.mjtJoint.mjJNT_SLIDE)
_CHAIN_JOINTS = (_HINGE, _SLIDE)


def load_mujoco_model(source: str | os.PathLike[str] | mujoco.MjModel) -> mujoco.MjModel:
    """Compile an MJCF/URDF file path, an MJCF string or pass through an :class:`MjModel`."""
    if isinstance(source, mujoco.MjModel):
        return source
    if isinstance(source, str) and source.lstrip().startswith("<"):
        check_model_files(None, text=source)
        try:
            return mujoco.MjModel.from_xml_string(source)
        except ValueError as exc:
            raise MJCFImportError(f"source: MuJoCo could not load the XML text: {exc}") from exc
    if not isinstance(source, (str, os.PathLike)):
        raise InputError(f"source: expected a file path, an XML string or a mujoco.MjModel, got "
                         f"{type(source).__name__}")
    path = Path(source)
    if not path.exists():
        raise MJCFImportError(f"source: no such file {str(path)!r} (expected an MJCF .xml or a "
                              f".urdf file)")
    _check_utf8(path)
    check_model_files(path)
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        raise MJCFImportError(f"source {str(path)!r}: MuJoCo could not load it: {exc}") from exc


def _check_utf8(path: Path) -> None:
    """MJCF and URDF files are UTF-8 XML in a regular file of bounded size
    (:func:`zrp.textio.read_text`): name the first line that is not UTF-8."""
    label = f"source {str(path)!r}"
    text = read_text(path, label=label, error=MJCFImportError)
    with path.open("rb") as fh:
        head = fh.read(4)
    if text and text_encoding(head) != "utf-8-sig":
        raise MJCFImportError(f"{label}: the file is UTF-16; MuJoCo reads MJCF and URDF files "
                              "as UTF-8: save it as UTF-8")


def _name(m: mujoco.MjModel, obj: mujoco.mjtObj, i: int) -> str:
    try:
        return mujoco.mj_id2name(m, obj, i) or f"#{i}"
    except UnicodeDecodeError as exc:  # MuJoCo keeps names as bytes; ours are text
        kind = str(obj).rsplit("_", 1)[-1].lower()
        raise MJCFImportError(f"{kind} #{i}: its name is not UTF-8 text ({exc.reason} at byte "
                              f"{exc.start}); the file must be UTF-8") from None


def _branch_ends(m: mujoco.MjModel) -> list[int]:
    """Leaf bodies whose chains of joints are not all one chain (unequal branches included)."""
    chains: dict[tuple[int, ...], int] = {}
    parents = set(int(p) for p in m.body_parentid[1:])
    for leaf in (b for b in range(1, m.nbody) if b not in parents):
        path, b = [], leaf
        while b > 0:
            path += range(m.body_jntadr[b] + m.body_jntnum[b] - 1, m.body_jntadr[b] - 1, -1)
            b = int(m.body_parentid[b])
        if path:
            chains.setdefault(tuple(path[::-1]), leaf)
    longest = max(chains, key=len, default=())
    if all(c == longest[:len(c)] for c in chains):
        return []
    return list(chains.values())


def _named_end(m: mujoco.MjModel, site: str | None, body: str | None) -> tuple[int, int]:
    """(body id, site id or -1) of the end effector named by ``site`` or ``body``."""
    if site is not None:
        sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, site)
        if sid < 0:
            names = [_name(m, mujoco.mjtObj.mjOBJ_SITE, i) for i in range(m.nsite)]
            raise MJCFImportError(f"site: no site named {site!r}; the model has {names}")
        return int(m.site_bodyid[sid]), int(sid)
    bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)
    if bid < 0:
        names = [_name(m, mujoco.mjtObj.mjOBJ_BODY, i) for i in range(1, m.nbody)]
        raise MJCFImportError(f"body: no body named {body!r}; the model has {names}")
    return int(bid), -1


def _deepest_tips(m: mujoco.MjModel) -> list[int]:
    """The bodies with the most joints on their path from the world and no child with as
    many."""
    njoint_path = np.zeros(m.nbody, dtype=int)
    for b in range(1, m.nbody):
        njoint_path[b] = njoint_path[m.body_parentid[b]] + int(m.body_jntnum[b])
    deepest = int(njoint_path.max())
    if deepest == 0:
        raise MJCFImportError("the model has no hinge or slide joint: nothing to import")
    return [b for b in range(1, m.nbody) if njoint_path[b] == deepest
            and not any(m.body_parentid[c] == b and njoint_path[c] == deepest
                        for c in range(1, m.nbody))]


def _end_body(m: mujoco.MjModel, site: str | None, body: str | None) -> tuple[int, int]:
    """(body id, site id or -1) of the end effector."""
    if site is not None and body is not None:
        raise InputError("site, body: give at most one of them (the end-effector frame)")
    if site is not None or body is not None:
        return _named_end(m, site, body)
    # Default: the deepest body carrying joints; it must be unique (a single chain).
    tips = _deepest_tips(m)
    ends = _branch_ends(m)
    if len(tips) > 1 or len(ends) > 1:
        names = sorted({_name(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in [*tips, *ends]})
        raise MJCFImportError(f"the kinematic tree branches (end bodies {names}); name the end "
                              f"effector with site= or body=")
    bid = tips[0]
    sites = [s for s in range(m.nsite) if m.site_bodyid[s] == bid]
    return bid, (sites[0] if len(sites) == 1 else -1)


def _refuse_coupled(m: mujoco.MjModel, joints: list[int]) -> None:
    """Joint equality constraints (couplings) on the chain are not modelled: refuse by name."""
    on_chain = set(joints)
    for e in range(m.neq):
        if int(m.eq_type[e]) != int(mujoco.mjtEq.mjEQ_JOINT):
            continue
        pair = [int(m.eq_obj1id[e]), int(m.eq_obj2id[e])]
        hit = [j for j in pair if j in on_chain]
        if hit:
            names = [_name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in pair if j >= 0]
            raise MJCFImportError(
                f"joint {_name(m, mujoco.mjtObj.mjOBJ_JOINT, max(hit, key=joints.index))!r} is "
                f"coupled by a joint "
                f"equality ({' ~ '.join(repr(n) for n in names)}); coupled joints are not "
                f"modelled: choose an end body or site before it")


def _chain_joints(m: mujoco.MjModel, bid: int) -> list[int]:
    """The joints from the world to body ``bid``, in order; only hinges and slides, none
    coupled, at least one."""
    chain = []
    b = bid
    while b > 0:
        chain.append(b)
        b = int(m.body_parentid[b])
    chain.reverse()
    joints: list[int] = []
    for b in chain:
        for j in range(m.body_jntadr[b], m.body_jntadr[b] + m.body_jntnum[b]):
            if int(m.jnt_type[j]) not in _CHAIN_JOINTS:
                kind = mujoco.mjtJoint(m.jnt_type[j]).name.removeprefix("mjJNT_").lower()
                raise MJCFImportError(
                    f"joint {_name(m, mujoco.mjtObj.mjOBJ_JOINT, j)!r} in body "
                    f"{_name(m, mujoco.mjtObj.mjOBJ_BODY, b)!r} is a {kind} joint; only hinge and "
                    f"slide joints form a ZRP serial arm")
            joints.append(j)
    _refuse_coupled(m, joints)
    if not joints:
        raise MJCFImportError(f"no hinge or slide joint between the world and body "
                              f"{_name(m, mujoco.mjtObj.mjOBJ_BODY, bid)!r}")
    return joints


def _end_frame(d: mujoco.MjData, bid: int, sid: int) -> tuple[np.ndarray, np.ndarray]:
    """(position, 3x3 frame) in the world of the end site ``sid``, or of body ``bid``."""
    if sid >= 0:
        return d.site_xpos[sid].copy(), d.site_xmat[sid].reshape(3, 3).copy()
    return d.xpos[bid].copy(), d.xmat[bid].reshape(3, 3).copy()


def _model_name(m: mujoco.MjModel) -> str:
    """The MJCF model's name, or "imported arm"."""
    return bytes(m.names).split(b"\0", 1)[0].decode(errors="replace") or "imported arm"


def _limits(m: mujoco.MjModel, joints: list[int], scale: float
            ) -> list[tuple[float, ...] | None]:
    """Each joint's range (None when unlimited), slides in the model's length unit."""
    return [None if not m.jnt_limited[j] else
            tuple(m.jnt_range[j] / (scale if int(m.jnt_type[j]) == _SLIDE else 1.0))
            for j in joints]


def manipulator_from_mujoco(
    source: str | os.PathLike[str] | mujoco.MjModel,
    *,
    site: str | None = None,
    body: str | None = None,
    length_unit: str = "mm",
    name: str | None = None,
) -> Manipulator:
    """Import the serial chain from the world to the end effector as a :class:`zrp.Manipulator`.

    Args:
        source: MJCF/URDF path, MJCF text, or a compiled :class:`mujoco.MjModel`.
        site: name of the end-effector site (its frame gives u_a = z, u_t = y).
        body: or the name of the end body (its frame is used); default: the unique deepest body
            with joints, and its site if it has exactly one.
        length_unit: unit of the returned model ("mm", "m", ...); MuJoCo works in metres.
        name: model name; default the MJCF model name.

    Raises:
        MJCFImportError: ball/free joints on the chain, a branching tree without site/body, an
            unknown site/body name, or a file MuJoCo cannot load.
    """
    if isinstance(source, (str, os.PathLike)) and str(source).lower().endswith(".urdf"):
        # kinematics of a URDF come from its tree (zrp.model.urdf): no meshes or inertias
        if site is not None:
            raise InputError("site: a URDF has no sites; name the end-effector link with body=")
        return from_urdf(source, end_link=body, length_unit=length_unit, name=name)
    m = load_mujoco_model(source)
    scale = metres_per_unit(length_unit)
    bid, sid = _end_body(m, site, body)
    joints = _chain_joints(m, bid)
    d = mujoco.MjData(m)
    d.qpos[:] = 0.0
    mujoco.mj_kinematics(m, d)
    axes = np.array([d.xaxis[j] for j in joints])
    anchors = np.array([d.xanchor[j] for j in joints])
    p, frame = _end_frame(d, bid, sid)
    bodies = np.vstack([anchors[:1], np.diff(anchors, axis=0), (p - anchors[-1])[None]]) / scale
    types = ["prismatic" if int(m.jnt_type[j]) == _SLIDE else "revolute"
             for j in joints]
    names = [_name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in joints]
    model_name = name or _model_name(m)
    limits = _limits(m, joints, scale)
    return Manipulator.from_arrays(axes, bodies, axial=frame[:, 2], transverse=frame[:, 1],
                                   types=types, name=model_name, length_unit=length_unit,
                                   joint_names=[n if not n.startswith("#") else "" for n in names],
                                   limits=limits)


def from_mjcf(path: str | os.PathLike[str], **kwargs: object) -> Manipulator:
    """Alias of :func:`manipulator_from_mujoco` for a file (MJCF or URDF)."""
    return manipulator_from_mujoco(path, **kwargs)  # type: ignore[arg-type]
