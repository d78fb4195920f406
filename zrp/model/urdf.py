"""Read the kinematic tree of a URDF file (standard library ``xml.etree``) into a ZRP model.

Only what kinematics needs is read: links (by name), joints (type, parent, child, ``origin``
xyz/rpy, ``axis``, ``limit``, ``mimic``). Meshes, ``package://`` URIs, inertias and collision
geometry are never opened or checked, so a URDF imports as shipped.

The chain runs from ``base_link`` (default: the tree's root) to ``end_link`` (any link, also one
behind fixed joints such as ``tool0``). At q = 0 every joint frame sits at its ``origin``; its
world axis R_joint @ axis is u_{k,0} and its origin the point on joint k, so b_{1,0} is the
first joint's origin in the base link's frame, b_{k,0} the difference of consecutive joint
origins and b_{n+1,0} the vector to the end link's origin, whose frame's z and y columns give
u_{a,0} and u_{t,0} (the ``zrp.hand_frame`` convention). URDF lengths are metres; the model is
converted to ``length_unit``. ``revolute`` and ``continuous`` joints become revolute joints
(continuous ones without limits), ``prismatic`` ones prismatic, ``fixed`` ones fold into the
body vectors. ``floating`` and ``planar`` joints and mimic joints on the chain are refused with
an error that names them (for a mobile manipulator, start at the arm's base link).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zrp.arrays import F64
from zrp.errors import ModelFileError
from zrp.model.manipulator import Manipulator
from zrp.textio import read_text
from zrp.units import metres_per_unit
from zrp.xmlio import parse_xml

__all__ = ["URDFImport", "URDFJoint", "URDFTree", "from_urdf", "import_urdf", "read_urdf"]

_MOVING = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}
_KNOWN = {*_MOVING, "fixed", "floating", "planar"}


@dataclass(frozen=True)
class URDFJoint:
    """One ``<joint>``: lengths in m, angles in rad; ``limits`` None when absent/continuous."""

    name: str
    type: str
    parent: str
    child: str
    origin: F64 = field(repr=False)  # 4x4 homogeneous transform parent -> joint frame
    axis: F64 = field(repr=False)
    limits: tuple[float, float] | None = None
    velocity_limit: float | None = None
    mimic: str | None = None


@dataclass(frozen=True)
class URDFTree:
    """The kinematic tree: link names, joints by child link, and the root link (the joints
    form a tree: :func:`read_urdf` refuses cycles and undeclared links)."""

    name: str
    source: str
    links: tuple[str, ...]
    joints: dict[str, URDFJoint]  # keyed by child link
    root: str
    _kids: dict[str, list[str]] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self._kids:  # children by parent link, in document order: built once
            for child, j in self.joints.items():
                self._kids.setdefault(j.parent, []).append(child)

    def children(self, link: str) -> list[str]:
        return list(self._kids.get(link, ()))

    def leaves(self, start: str) -> list[str]:
        """Links without children in the subtree under ``start`` (depth first)."""
        out, stack = [], [start]
        while stack:
            link = stack.pop()
            kids = self._kids.get(link, ())
            if not kids:
                out.append(link)
            stack.extend(reversed(kids))
        return out

    def path(self, base: str, end: str) -> list[URDFJoint]:
        """Joints from ``base`` down to ``end``, base first."""
        chain: list[URDFJoint] = []
        link = end
        while link != base:
            j = self.joints.get(link)
            if j is None or len(chain) > len(self.joints):
                raise ModelFileError(f"{self.source}: end_link {end!r} is not below base_link "
                                     f"{base!r} in the kinematic tree")
            chain.append(j)
            link = j.parent
        return chain[::-1]


@dataclass(frozen=True, eq=False)
class URDFImport:
    """A URDF import: the model, the links it runs between and notes on what was left out."""

    model: Manipulator
    base_link: str
    end_link: str
    joints: tuple[str, ...]
    notes: tuple[str, ...] = ()


def _floats(text: str | None, n: int, default: list[float], where: str) -> F64:
    if text is None:
        return np.array(default, dtype=float)
    try:
        v = np.array([float(x) for x in text.split()], dtype=float)
    except ValueError as exc:
        raise ModelFileError(f"{where}: expected {n} numbers, got {text!r}") from exc
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ModelFileError(f"{where}: expected {n} finite numbers, got {text!r}")
    return v


def rpy_matrix(rpy: F64) -> F64:
    """URDF fixed-axis roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll), shape (3, 3)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _number(lim: ET.Element, attr: str, default: str | None, where: str) -> float | None:
    """The finite number in attribute ``attr`` of a ``<limit>`` (``default`` when absent)."""
    text = lim.get(attr, default)
    if text is None:
        return None
    try:
        v = float(text)
    except ValueError:
        raise ModelFileError(f"{where} limit {attr}: {text!r} is not a number") from None
    if not np.isfinite(v):
        raise ModelFileError(f"{where} limit {attr}: {text!r} is not a finite number")
    return v


def _limits(el: ET.Element, jtype: str, where: str) -> tuple[tuple[float, float] | None,
                                                             float | None]:
    lim = el.find("limit")
    if lim is None:
        return None, None
    vel = _number(lim, "velocity", None, where)
    v = vel if vel is not None and vel > 0 else None
    if jtype == "continuous":
        return None, v
    lo, hi = _number(lim, "lower", "0", where), _number(lim, "upper", "0", where)
    assert lo is not None and hi is not None
    if lo > hi:
        raise ModelFileError(f"{where} limit: lower {lo} > upper {hi}")
    return (lo, hi), v


def _joint(el: ET.Element, source: str) -> URDFJoint:
    name = el.get("name", "")
    where = f"{source}: joint {name!r}"
    jtype = el.get("type", "")
    if jtype not in _KNOWN:
        raise ModelFileError(f"{where}: type {jtype!r} is unknown; expected one of "
                             f"{sorted(_KNOWN)}")
    parent, child = el.find("parent"), el.find("child")
    if parent is None or child is None or not parent.get("link") or not child.get("link"):
        raise ModelFileError(f"{where}: needs <parent link=...> and <child link=...>")
    org = el.find("origin")
    xyz = _floats(org.get("xyz") if org is not None else None, 3, [0, 0, 0], f"{where} origin xyz")
    rpy = _floats(org.get("rpy") if org is not None else None, 3, [0, 0, 0], f"{where} origin rpy")
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rpy_matrix(rpy), xyz
    ax_el = el.find("axis")
    axis = _floats(ax_el.get("xyz") if ax_el is not None else None, 3, [1, 0, 0],
                   f"{where} axis")
    if jtype in _MOVING:
        norm = float(np.linalg.norm(axis))
        if norm < 1e-12:
            raise ModelFileError(f"{where} axis: is a zero vector; expected e.g. '0 0 1'")
        axis = axis / norm
    lims, vel = _limits(el, jtype, where) if jtype in _MOVING else (None, None)
    mimic = el.find("mimic")
    return URDFJoint(name, jtype, parent.get("link", ""), child.get("link", ""), t, axis, lims,
                     vel, mimic.get("joint") if mimic is not None else None)


def _parse(source: str | Path, label: str | None = None) -> tuple[ET.Element, str]:
    """The root element and a label: a path is read with :func:`zrp.textio.read_text` (a
    regular file, size checked, UTF-8 or UTF-16 decoded); text starting with ``<`` is XML,
    named ``label`` (the file it came from) in errors."""
    text_given = isinstance(source, str) and source.lstrip("\ufeff \t\r\n").startswith("<")
    if text_given:
        label, text = label or "<urdf string>", str(source)
    else:
        if not isinstance(source, (str, os.PathLike)):
            raise ModelFileError(f"source: expected a URDF file path or XML text, got "
                                 f"{type(source).__name__}")
        label = str(source)
        text = read_text(source, label=label, error=ModelFileError)
    root = parse_xml(text, label=label, error=ModelFileError)  # bounded, linear (zrp.xmlio)
    assert root is not None
    return root, label


def _check_links(label: str, links: tuple[str, ...], joints: dict[str, URDFJoint],
                 root: str | None) -> None:
    """Every joint between declared links and every link reachable from ``root``: otherwise
    the joints hold a cycle (a self-loop included), named. Linear in the joints."""
    declared = set(links)
    for j in joints.values():
        for role, link in (("parent", j.parent), ("child", j.child)):
            if link not in declared:
                raise ModelFileError(f"{label}: joint {j.name!r}: {role} link {link!r} is not "
                                     "a <link> of the robot")
    kids: dict[str, list[str]] = {}
    for child, j in joints.items():
        kids.setdefault(j.parent, []).append(child)
    seen, stack = ({root}, [root]) if root is not None else (set(), [])
    while stack:
        for c in kids.get(stack.pop(), ()):
            if c not in seen:
                seen.add(c)
                stack.append(c)
    lost = [lk for lk in links if lk not in seen]
    if not lost:
        return
    on_path: list[str] = []
    link = lost[0]
    while link not in on_path:  # every lost link has a parent: walking up must repeat
        on_path.append(link)
        link = joints[link].parent
    cycle = on_path[on_path.index(link):][::-1]
    names = [joints[c].name for c in cycle]
    raise ModelFileError(f"{label}: the joints {names} form a cycle through the links "
                         f"{cycle}; a URDF is a tree (each link has one parent and the root "
                         "none)")


def read_urdf(source: str | Path, *, label: str | None = None) -> URDFTree:
    """Parse a URDF file path (or URDF XML text, named ``label`` in errors) into its
    kinematic tree.

    Raises:
        ModelFileError: unreadable file (not a regular file, too large, not UTF-8/UTF-16),
            invalid XML (with its line), a joint without parent or child, an unknown joint
            type, a limit that is not a number, several roots, a link with two parents, a
            joint naming an undeclared link, or joints forming a cycle.
    """
    root_el, label = _parse(source, label)
    if root_el.tag != "robot":
        raise ModelFileError(f"{label}: the root element is <{root_el.tag}>; expected <robot>")
    links = tuple(el.get("name", "") for el in root_el.findall("link"))
    if not links:
        raise ModelFileError(f"{label}: the <robot> has no <link> elements: nothing to import")
    joints: dict[str, URDFJoint] = {}
    for el in root_el.findall("joint"):
        j = _joint(el, label)
        if j.child in joints:
            raise ModelFileError(f"{label}: link {j.child!r} has two parent joints "
                                 f"({joints[j.child].name!r}, {j.name!r})")
        joints[j.child] = j
    roots = [lk for lk in links if lk not in joints]
    if not roots:
        _check_links(label, links, joints, None)
    if len(roots) != 1:
        shown = roots[:10] + (["..."] if len(roots) > 10 else [])
        raise ModelFileError(f"{label}: expected one root link, found {len(roots)}: {shown}")
    _check_links(label, links, joints, roots[0])
    return URDFTree(root_el.get("name", "") or Path(label).stem, label, links, joints,
                    roots[0])


def _default_end(tree: URDFTree, base: str) -> str:
    """When every leaf under ``base`` lies on one chain of moving joints: the leaf at its end
    if it is the only one, else the last moving link (e.g. a UR's ``ee_link`` and ``tool0``).

    Linear in the links: a leaf's chain of moving joints is known from its last moving joint
    (``last``), and the chains are all one chain when those joints lie on one path."""
    last: dict[str, str | None] = {base: None}  # link -> child link of its last moving joint
    up: dict[str, str | None] = {}  # moving joint (by child link) -> the one before it
    depth: dict[str | None, int] = {None: 0}
    chains: dict[str, str] = {}  # last moving joint -> first leaf (depth first)
    stack = [base]
    while stack:
        link = stack.pop()
        kids = tree.children(link)
        if not kids and last[link] is not None:
            chains.setdefault(last[link], link)  # type: ignore[arg-type]
        for c in reversed(kids):
            if tree.joints[c].type == "fixed":
                last[c] = last[link]
            else:
                last[c], up[c], depth[c] = c, last[link], depth[last[link]] + 1
            stack.append(c)
    if not chains:
        raise ModelFileError(f"{tree.source}: no moving joint below base_link {base!r}")
    longest = max(chains, key=lambda k: depth[k])
    on_longest, k = set(), longest
    while k is not None:
        on_longest.add(k)
        k = up[k]
    if any(c not in on_longest for c in chains):
        raise ModelFileError(
            f"{tree.source}: the kinematic tree below {base!r} branches; name the end effector "
            f"(end_link=NAME), e.g. one of the branch ends {sorted(chains.values())}")
    tips = [leaf for leaf in tree.leaves(base) if last[leaf] == longest]
    if len(tips) == 1:  # one tool link (behind fixed joints or not)
        return tips[0]
    return longest


def _check_chain(tree: URDFTree, chain: list[URDFJoint], base: str) -> None:
    for j in chain:
        if j.type in ("floating", "planar"):
            raise ModelFileError(
                f"{tree.source}: joint {j.name!r} between {base!r} and the end effector is "
                f"{j.type}; a ZRP arm has revolute and prismatic joints only: start at "
                f"base_link={j.child!r} (the arm of a mobile manipulator)")
        if j.mimic is not None:
            raise ModelFileError(
                f"{tree.source}: joint {j.name!r} mimics joint {j.mimic!r}; coupled joints are "
                f"not modelled: choose an end_link before it")


def _chain_ends(tree: URDFTree, base_link: str | None, end_link: str | None
                ) -> tuple[str, str]:
    """(base, end) links of the chain to import: the root and the default end when not given;
    an unknown link is an error listing the links."""
    base = tree.root if base_link is None else base_link
    for arg, link in (("base_link", base), ("end_link", end_link)):
        if link is not None and link not in tree.links:
            raise ModelFileError(f"{tree.source}: {arg}: no link named {link!r}; the links are "
                                 f"{list(tree.links)}")
    end = _default_end(tree, base) if end_link is None else end_link
    return base, end


@dataclass
class _Joints:
    """The moving joints of a chain, in the base frame and the model's length unit."""

    axes: list[F64] = field(default_factory=list)
    points: list[F64] = field(default_factory=list)
    types: list[str] = field(default_factory=list)
    names: list[str] = field(default_factory=list)
    limits: list[tuple[float, float] | None] = field(default_factory=list)
    velocities: list[float | None] = field(default_factory=list)


def _moving_joints(chain: list[URDFJoint], scale: float) -> tuple[F64, _Joints]:
    """(transform base -> end of the chain, the moving joints); fixed joints only move the
    frame. Prismatic limits and velocities are scaled to the length unit."""
    t = np.eye(4)
    js = _Joints()
    for j in chain:
        t = t @ j.origin
        if j.type == "fixed":
            continue
        js.axes.append(t[:3, :3] @ j.axis)
        js.points.append(t[:3, 3] * scale)
        js.types.append(_MOVING[j.type])
        js.names.append(j.name)
        s = scale if j.type == "prismatic" else 1.0
        js.limits.append(None if j.limits is None else (j.limits[0] * s, j.limits[1] * s))
        js.velocities.append(None if j.velocity_limit is None else j.velocity_limit * s)
    return t, js


def import_urdf(source: str | Path, *, end_link: str | None = None,
                base_link: str | None = None, length_unit: str = "mm",
                name: str | None = None, label: str | None = None) -> URDFImport:
    """Import the serial chain base_link -> end_link of a URDF (see the module docstring).

    Args:
        source: URDF file path or XML text.
        end_link: the end-effector link (default, when the tree has one chain of moving joints:
            its only end link, or the last moving link if several fixed links hang there;
            otherwise an error lists the branch ends).
        base_link: the link whose frame is the base frame (default: the root link).
        length_unit: unit of the model (URDF is in metres).
        name: model name (default: the robot's name).
        label: the name of XML text ``source`` in errors (the file it was read from).

    Raises:
        ModelFileError: an unknown link, a branching tree without ``end_link``, a floating or
            planar joint or a mimic joint on the chain, no moving joint.
    """
    tree = read_urdf(source, label=label)
    base, end = _chain_ends(tree, base_link, end_link)
    chain = tree.path(base, end)
    _check_chain(tree, chain, base)
    scale = 1.0 / metres_per_unit(length_unit)
    t, js = _moving_joints(chain, scale)
    if not js.axes:
        raise ModelFileError(f"{tree.source}: no revolute, continuous or prismatic joint between "
                             f"{base!r} and {end!r}")
    pts = np.array(js.points)
    bodies = np.vstack([pts[:1], np.diff(pts, axis=0), (t[:3, 3] * scale - pts[-1])[None]])
    model = Manipulator.from_arrays(
        np.array(js.axes), bodies, axial=t[:3, 2], transverse=t[:3, 1], types=js.types,
        name=name or tree.name, length_unit=length_unit, joint_names=js.names, limits=js.limits,
        velocity_limits=js.velocities)
    on_chain = {j.name for j in chain}
    others = sorted(j.name for j in tree.joints.values() if j.name not in on_chain
                    and j.type != "fixed")
    notes = [f"{len(others)} moving joints off the chain {base!r} -> {end!r} ignored: {others}"
             ] if others else []
    return URDFImport(model, base, end, tuple(js.names), tuple(notes))


def from_urdf(source: str | Path, **kwargs: object) -> Manipulator:
    """The model of :func:`import_urdf` (same arguments)."""
    return import_urdf(source, **kwargs).model  # type: ignore[arg-type]
