"""``zrp export``: write a model as URDF, MJCF, a DH/MDH table or model TOML."""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import TYPE_CHECKING

from zrp.cli.app import emit
from zrp.model.builtin import builtin_models

if TYPE_CHECKING:
    from zrp.model.manipulator import Manipulator
from zrp.output import check_writable, write_text

FORMATS = {"urdf": ".urdf", "mjcf": ".xml", "dh": ".dh.toml", "mdh": ".mdh.toml",
           "toml": ".toml"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "export", help="write a model as URDF, MJCF, DH/MDH table or TOML",
        description="Export any model file (nominal, perturbed or calibrated): URDF (joint "
        "origins, axes, limits; loads in Pinocchio and MuJoCo with the same FK), MJCF, a DH or "
        "modified-DH table with base and tool transforms (canonical form, see "
        "zrp/model/README.md), or the model TOML.")
    p.add_argument("--model", default="puma", metavar="FILE",
                   help=f"model TOML file or built-in name ({', '.join(sorted(builtin_models()))}"
                        "; default puma)")
    p.add_argument("--to", choices=tuple(FORMATS), required=True, help="output format")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="file to write (default renders/<model><suffix>)")
    p.add_argument("--force", action="store_true",
                   help="replace --out if it exists (refused otherwise, before the work)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run)


def _text(model: Manipulator, fmt: str) -> str:
    from zrp.model.dh_table import dumps_dh, to_dh  # on use: keeps --help quick
    from zrp.model.files import dumps_model  # on use: keeps --help quick
    from zrp.model.urdf_writer import urdf_xml  # on use: keeps --help quick

    if fmt == "urdf":
        return urdf_xml(model)
    if fmt in ("dh", "mdh"):
        return dumps_dh(to_dh(model, "standard" if fmt == "dh" else "modified"))
    if fmt == "toml":
        return dumps_model(model)
    # mjcf loads MuJoCo: only for this format
    import mjcf

    return mjcf.mjcf_xml(mjcf.build(model))


def _run(args: argparse.Namespace) -> int:
    from zrp.model.files import load_model  # on use: keeps --help quick

    stem = re.sub(r"[^A-Za-z0-9]+", "_", Path(args.model).stem).strip("_").lower() or "model"
    out = Path(args.out or f"renders/{stem}{FORMATS[args.to]}")
    check_writable([out], args.force)
    model = load_model(args.model)
    write_text(out, _text(model, args.to), overwrite=args.force)
    payload = {"written": str(out), "format": args.to, "model": model.name, "joints": model.n,
               "joint_names": list(model.joint_names), "length_unit": model.length_unit}
    emit(args, payload, f"wrote {out}: {model.name} as {args.to} ({model.n} joints)")
    return 0
