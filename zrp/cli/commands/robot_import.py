"""``zrp import``: bring your own robot (URDF, MJCF, DH/MDH table) into a model TOML file."""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import TYPE_CHECKING

from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.cli.options import LENGTH_UNIT
from zrp.errors import InputError, ModelFileError

if TYPE_CHECKING:
    from zrp.model.manipulator import Manipulator
from zrp.output import check_writable, safe_name
from zrp.textio import read_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "import", help="import a serial arm from URDF, MJCF or a DH/MDH table into a model file",
        description="Read the serial chain of a robot description as shipped: a URDF (meshes, "
        "package:// URIs and inertias are never opened; read with the standard library), an "
        "MJCF (compiled by MuJoCo), or a DH/MDH table TOML (see zrp/model/README.md). Joint "
        "names and limits are kept. Writes a model TOML file.")
    p.add_argument("source", metavar="FILE", help=".urdf, MJCF .xml, or a DH table .toml")
    end = p.add_argument("--end-link", default=None, metavar="NAME",
                   help="end-effector link (URDF) or body (MJCF); default: the end of the only "
                        "chain (a branching tree is an error listing the branch ends)")
    deprecated_alias(p, "--end", end)
    p.add_argument("--site", default=None, help="MJCF: end-effector site")
    p.add_argument("--base", default=None, metavar="LINK",
                   help="URDF: base link (default the root; e.g. the arm's base on a mobile "
                        "robot)")
    p.add_argument("--unit", type=LENGTH_UNIT, default="mm",
                   help="length unit of the model (default mm)")
    p.add_argument("--name", default=None, help="model name (default: the robot's)")
    p.add_argument("--out", default=None, metavar="TOML",
                   help="model file to write (default renders/<source name>.toml)")
    p.add_argument("--force", action="store_true",
                   help="replace --out if it exists (refused otherwise, before reading)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run, api_names={"end_link": "--end-link", "base_link": "--base",
                                         "site": "--site", "body": "--end-link"})


def _slug(text: str) -> str:
    return safe_name(text, lower=True)


def _kind(text: str) -> str:
    """"urdf", "mjcf" or "toml", from the file's content (not its name): XML whose first
    element (after a byte-order mark, declarations and comments) is ``<robot`` is a URDF."""
    head = text[:65536].lstrip("\ufeff \t\r\n")
    if not head.startswith("<"):
        return "toml"
    body = re.sub(r"<\?.*?\?>|<!--.*?-->|<!DOCTYPE[^>]*>", "", head, flags=re.S).lstrip()
    return "urdf" if body.startswith("<robot") else "mjcf"


def _read(args: argparse.Namespace) -> tuple[Manipulator, dict[str, object]]:
    from zrp.model.dh_table import loads_dh  # on use: keeps --help quick
    from zrp.model.files import loads_model  # on use: keeps --help quick
    from zrp.model.urdf import import_urdf  # on use: keeps --help quick

    src = Path(args.source)
    text = read_text(src, label=str(src), error=ModelFileError)  # a regular file, size checked
    kind = _kind(text)
    if kind == "urdf":
        if args.site:
            raise InputError("--site: a URDF has no sites; name the end link with --end-link")
        imp = import_urdf(src, end_link=args.end_link, base_link=args.base, length_unit=args.unit,
                          name=args.name)
        return imp.model, {"format": "urdf", "base_link": imp.base_link,
                           "end_link": imp.end_link, "notes": list(imp.notes)}
    if kind == "toml":
        if re.search(r"^\s*\[\[\s*row\s*\]\]", text, re.M):
            table = loads_dh(text, str(src))
            return table.model(), {"format": f"dh ({table.convention})"}
        return loads_model(text, str(src)), {"format": "model toml"}
    if args.base:
        raise InputError("--base: only for a URDF; an MJCF chain starts at the world body")
    # mjcf loads MuJoCo: only for an MJCF source
    import mjcf

    model = mjcf.from_mjcf(src, site=args.site, body=args.end_link, length_unit=args.unit,
                           name=args.name)
    return model, {"format": "mjcf"}


def _run(args: argparse.Namespace) -> int:
    from zrp.model.files import save_model  # on use: keeps --help quick

    out = Path(args.out or f"renders/{_slug(Path(args.source).stem)}.toml")
    check_writable([out], args.force)
    model, info = _read(args)
    save_model(model, out, overwrite=args.force)
    joints = [{"name": nm, "type": j.type,
               "limits": None if j.limits is None else list(j.limits),
               "velocity_limit": j.velocity_limit}
              for nm, j in zip(model.joint_names, model.joints, strict=True)]
    payload = {"written": str(out), "model": model.name, "joints": joints,
               "length_unit": model.length_unit, **info}
    lines = [f"imported {model.name!r} ({info['format']}): {model.n} joints -> {out}"]
    if "end_link" in info:
        lines.append(f"  chain {info['base_link']} -> {info['end_link']}")
    for jd in joints:
        lim = "no limits" if jd["limits"] is None else f"limits {jd['limits']}"
        lines.append(f"  {jd['name']:<20s} {jd['type']:<9s} {lim}")
    lines += [f"  note: {n}" for n in info.get("notes", [])]  # type: ignore[union-attr]
    emit(args, payload, "\n".join(lines))
    return 0
