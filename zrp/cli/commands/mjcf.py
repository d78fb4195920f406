"""``zrp mjcf``: write the MuJoCo model (MJCF) of a ZRP model, or import an arm from MJCF/URDF."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.cli.options import LENGTH_UNIT, real
from zrp.errors import InputError
from zrp.model.builtin import builtin_models
from zrp.output import safe_name


def _perturbations(items: list[str] | None) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items or []:
        m = re.fullmatch(r"\s*([A-Za-z]+\d+)\s*=\s*([-+0-9.eE]+)\s*", item)
        if not m:
            raise InputError(f"--perturb: {item!r} is not NAME=XI, e.g. JE2=0.1 (xi in percent)")
        out[m.group(1).upper()] = float(m.group(2))
    return out


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "mjcf", help="write a model as MuJoCo MJCF, or import an arm from MJCF/URDF",
        description="Write the MJCF of a ZRP model (nominal or perturbed; qpos = 0 is the zero "
        "reference position; lengths converted to m), or with --from import the serial arm of "
        "an MJCF/URDF file at qpos = 0 into a model TOML file.")
    p.add_argument("--model", default="puma", metavar="FILE",
                   help=f"model TOML file or built-in name ({', '.join(sorted(builtin_models()))}"
                        "; default puma)")
    p.add_argument("--perturb", nargs="+", metavar="NAME=XI", default=None,
                   help="perturb before writing, e.g. JE2=0.1 LE3=-0.05 (xi in percent, eqs "
                        "8-12, paper sign(0) convention)")
    p.add_argument("--inertia", choices=("none", "rods", "puma560"), default="none",
                   help="mass properties: none (kinematic), rods, or puma560 (literature "
                        "values, 6R PUMA-type only). Another real arm's own inertias are in its "
                        "shipped URDF/MJCF: give that file to --mjcf of diagnose/calibrate")
    p.add_argument("--actuators", action="store_true",
                   help="add PD servos (position + rate actuators) per joint")
    p.add_argument("--kp", type=real(0.0, 1e12, open_lo=True),
                   default=2000.0, help="servo gain, N m/rad")
    p.add_argument("--kv", type=real(0.0, 1e12), default=100.0, help="rate gain, N m s/rad")
    p.add_argument("--from", dest="source", metavar="XML", default=None,
                   help="import: MJCF or URDF file to read (writes a model TOML)")
    p.add_argument("--site", default=None, help="import: end-effector site name")
    end = p.add_argument("--end-link", default=None, metavar="NAME",
                         help="import: the chain's end body (MJCF) or link (URDF), if no site")
    deprecated_alias(p, "--body", end)
    p.add_argument("--unit", type=LENGTH_UNIT, default=None,
                   help="import: length unit of the TOML (default mm; only with --from)")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="output (default renders/<model>.xml, or renders/<name>.toml with "
                        "--from); an existing file, the default one too, needs --force")
    p.add_argument("--force", action="store_true",
                   help="replace --out if it exists (refused otherwise, before writing)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run, api_names={"body": "--end-link", "end_link": "--end-link",
                                         "site": "--site"})


def _slug(text: str) -> str:
    return safe_name(text, lower=True)


def _run(args: argparse.Namespace) -> int:
    # mjcf loads MuJoCo (+0.1 s measured): only when this command runs, not for every `zrp`.
    import mjcf
    from zrp.manufacturing.perturb import Perturbation  # on use: keeps --help quick
    from zrp.model.files import load_model, save_model  # on use: keeps --help quick

    if args.unit is not None and not args.source:
        raise InputError("--unit: only with --from (the length unit of the imported TOML); "
                         "the MJCF written is in metres whatever the model's unit")
    if args.source:
        model = mjcf.from_mjcf(args.source, site=args.site, body=args.end_link,
                               length_unit=args.unit or "mm")
        out = Path(args.out or f"renders/{_slug(Path(args.source).stem)}.toml")
        save_model(model, out, overwrite=args.force)
        emit(args, {"written": str(out), "joints": model.n, "types": model.joint_types,
                    "length_unit": model.length_unit},
             f"imported {model!r} from {args.source} -> {out}")
        return 0
    model = load_model(args.model)
    pert = _perturbations(args.perturb)
    label = "nominal"
    if pert:
        p = Perturbation(pert)
        model = p.apply(model)
        label = ", ".join(f"{k}={v:+g}%" for k, v in pert.items()) + f" ({p.convention})"
    options = mjcf.MJCFOptions(inertia=args.inertia, actuators=args.actuators, kp=args.kp,
                               kv=args.kv)
    arm = mjcf.build(model, options)
    suffix = "" if not pert else "_" + "_".join(f"{k}{v:g}" for k, v in pert.items())
    out = Path(args.out or f"renders/{_slug(Path(args.model).stem)}{suffix}.xml")
    mjcf.save_mjcf(arm, out, overwrite=args.force)
    emit(args, {"written": str(out), "model": model.name, "perturbation": label,
                "bodies": int(arm.model.nbody), "joints": int(arm.model.njnt),
                "actuators": int(arm.model.nu), "inertia": args.inertia},
         f"wrote {out}: {model.name} ({label}), {arm.model.njnt} joints, "
         f"{arm.model.nu} actuators, inertia={args.inertia}")
    return 0
