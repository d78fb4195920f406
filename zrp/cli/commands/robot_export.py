"""``zrp export``: write a model as URDF, MJCF, a DH/MDH table or model TOML."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from zrp.model.manipulator import Manipulator
from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.errors import InputError
from zrp.model.builtin import builtin_models
from zrp.output import check_writable, safe_name, write_text

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
    p.add_argument("--calibration", metavar="C.json",
                   help="export a calibrated robot (compensation.json of zrp calibrate; "
                   "checked against the physical domains) instead of --model, with a side "
                   "file of the terms the format cannot hold (OUT.calibration.json)")
    p.add_argument("--urdf", metavar="SRC.urdf",
                   help="with --calibration --to urdf: the URDF the robot was imported from; "
                   "the export patches it (same links, names, types, limits, inertias, "
                   "meshes; only the calibrated origins and axes change)")
    p.add_argument("--mjcf", metavar="SRC.xml",
                   help="with --calibration --to mjcf: the MJCF the robot was imported from; "
                   "the export patches it (only the chain's body poses, joint axes and the end "
                   "site change)")
    p.add_argument("--site", metavar="NAME", help="with --mjcf: the end site, as given to "
                   "zrp import")
    p.add_argument("--base", metavar="LINK",
                   help="with --urdf: the chain's base link, as given to zrp import")
    end = p.add_argument("--end-link", metavar="LINK",
                         help="with --urdf: the chain's end link (with --mjcf: its end body), "
                         "as given to zrp import")
    deprecated_alias(p, "--end", end)
    p.add_argument("--to", choices=tuple(FORMATS), required=True, help="output format")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="file to write (default renders/<model><suffix>)")
    p.add_argument("--force", action="store_true",
                   help="replace --out if it exists (refused otherwise, before the work)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run, api_names={"end_link": "--end-link", "base_link": "--base",
                                         "site": "--site", "body": "--end-link"})


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


def _calibrated(args: argparse.Namespace, out: Path) -> tuple[Manipulator, Path]:
    """Export the calibration of --calibration: the patched --urdf or the format, and the
    side file; (the calibrated model, the side file)."""
    from zrp.calibration import read_calibration  # on use: keeps --help quick
    from zrp.calibration.export import export_urdf, side_document  # on use: keeps --help quick
    from zrp.jsonio import dumps  # on use: keeps --help quick

    side = out.with_name(out.name.split(".")[0] + ".calibration.json")
    check_writable([out, side], args.force)
    cal = read_calibration(args.calibration)
    if args.mjcf is not None:
        if args.to != "mjcf":
            raise InputError("--mjcf: patches an MJCF file; use it with --to mjcf")
        # mjcf loads MuJoCo: only for this export
        from mjcf.patch import export_mjcf

        export_mjcf(cal, args.mjcf, out, side, site=args.site, body=args.end_link,
                    overwrite=args.force)
        return cal.model, side
    if args.urdf is not None:
        if args.to != "urdf":
            raise InputError("--urdf: patches a URDF; use it with --to urdf")
        export_urdf(cal, args.urdf, out, side, base_link=args.base,
                    end_link=args.end_link, overwrite=args.force)
        return cal.model, side
    write_text(out, _text(cal.model, args.to), overwrite=args.force)
    write_text(side, dumps(side_document(cal, out.name, "", None, None)),
               overwrite=args.force)
    return cal.model, side


def _refuse_calibrated_model(model: str) -> None:
    """A calibrated model TOML holds the geometry only: its cyclic-error, backlash and other
    joint-map terms live in its compensation file, which --calibration exports whole."""
    from zrp.calibration.storage import calibrated_marker  # on use: keeps --help quick
    from zrp.textio import read_text  # on use: keeps --help quick

    path = Path(model)
    if not path.is_file():
        return
    try:
        comp = calibrated_marker(read_text(path))
    except (OSError, UnicodeDecodeError):
        return  # load_model names what is wrong with the file
    if comp is not None:
        raise InputError(
            f"--model {model}: a calibrated model holds the geometry only; its joint-map "
            "terms (encoder scale, cyclic error, compliance, backlash), thermal expansion and "
            f"registration are in {comp} beside it and would be dropped; export with "
            f"--calibration {path.parent / comp}, which keeps them (the format, plus a side "
            "file of what it cannot hold)")


def _run(args: argparse.Namespace) -> int:
    from zrp.model.files import load_model  # on use: keeps --help quick

    if args.calibration is None and (args.urdf or args.mjcf or args.base or args.end_link
                                     or args.site):
        raise InputError("--urdf, --mjcf: patch the robot's file with a calibration; give "
                         "--calibration C.json")
    if args.calibration is None:
        _refuse_calibrated_model(args.model)
    src = args.calibration or args.model
    stem = safe_name(Path(src).stem, lower=True)
    out = Path(args.out or f"renders/{stem}{FORMATS[args.to]}")
    side = None
    if args.calibration is not None:
        model, side = _calibrated(args, out)
    else:
        check_writable([out], args.force)
        model = load_model(args.model)
        write_text(out, _text(model, args.to), overwrite=args.force)
    payload = {"written": str(out), "format": args.to, "model": model.name, "joints": model.n,
               "joint_names": list(model.joint_names), "length_unit": model.length_unit}
    if side is not None:
        payload["side_file"] = str(side)
    emit(args, payload, f"wrote {out}: {model.name} as {args.to} ({model.n} joints)"
         + ("" if side is None else f"\nwrote {side} (the terms {args.to} cannot hold)"))
    return 0
