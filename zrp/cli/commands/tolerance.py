"""``zrp tolerance``: Monte Carlo tolerance analysis, first-order worst case, allocation."""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import Executor
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from zrp.model.manipulator import Manipulator

from zrp.cli.app import emit
from zrp.cli.cluster import add_cluster_options, check_cluster_options, executor_from_args
from zrp.cli.commands.study import add_path_options, check_path_options, path_from_args
from zrp.cli.options import LENGTH, SEED, TOLERANCE, add_progress, draw_bar, real, whole
from zrp.errors import InputError

if TYPE_CHECKING:
    from zrp.manufacturing.study import JointPath
from zrp.manufacturing.choices import DISTRIBUTIONS
from zrp.output import check_writable

#: Above this many robots `zrp tolerance` reduces on the workers (gathering costs 32 bytes a
#: robot with the first-order maxima: 320 MB here); --allocate verifies with at most this many.
GATHER_LIMIT = 10_000_000
#: Largest --robots: 1e10 robots x 360 points is ~3e4 core-hours (the per-pose rate of one core:
#: tests/benchmarks/bench_speed.py).
MAX_ROBOTS = 10**10


def _parse_tol(items: list[str] | None) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items or []:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise InputError(f"--tol {item!r}: expected NAME=VALUE, e.g. b3.x=0.01 or 'u*.*=1e-4'")
        try:
            out[name.strip()] = float(value)
        except ValueError as exc:
            raise InputError(f"--tol {item!r}: {value!r} is not a number") from exc
    return out


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "tolerance", help="Monte Carlo tolerance analysis, worst case and allocation",
        description="Draw every link-vector component (b<k>.x/y/z, length unit) and joint-axis "
        "tilt (u<k>.t1/t2, rad) within its tolerance for N robots, replay the nominal IK joints "
        "on each and report the distribution of max delta_p and max error angle, the first-order"
        " prediction, worst-case bound and ranked contributions. --allocate finds the loosest "
        "tolerances (reciprocal cost model) meeting a percentile requirement.")
    add_path_options(p)
    g = p.add_argument_group("tolerances")
    g.add_argument("--length", type=TOLERANCE, default=0.02,
                   help="tolerance of every body-vector component, length unit (default 0.02)")
    g.add_argument("--angle", type=real(0.0, math.pi, unit="rad"), default=5e-5,
                   help="tolerance of every axis tilt, rad (default 5e-5, about 10 arcsec)")
    g.add_argument("--offsets", type=TOLERANCE, default=None, metavar="TOL",
                   help="also perturb joint zero offsets with this tolerance (rad / length unit)")
    g.add_argument("--tol", action="append", metavar="NAME=VALUE",
                   help="per-parameter tolerance, name or glob: b3.x=0.01, 'u*.*=1e-4', "
                        "'b1.*=0' (repeatable)")
    g.add_argument("--distribution", choices=DISTRIBUTIONS, default="uniform",
                   help="uniform: U(-tol, tol); normal: N(0, (tol/3)^2) (default uniform)")
    m = p.add_argument_group("Monte Carlo")
    m.add_argument("-n", "--robots", type=whole(1, MAX_ROBOTS),
                   default=20000, help="robots N (default 20000; above "
                   f"{GATHER_LIMIT:,} the run is reduced on the workers, see --reduce)")
    m.add_argument("--reduce", action="store_true",
                   help="reduce each chunk on its worker to histograms of the per-robot maxima "
                        "(memory independent of N; percentiles known to a 0.56 %% bin); "
                        f"implied above {GATHER_LIMIT:,} robots")
    m.add_argument("--seed", type=SEED, default=1, help="random seed (default 1)")
    m.add_argument("--percentile", type=real(0.0, 100.0),
                   default=99.0, help="reported percentile (99)")
    m.add_argument("--checkpoint", default=None, metavar="NPZ",
                   help="write the run's state to this .npz file every few seconds and when it "
                        "stops (implies --reduce); run the same command with --resume to "
                        "continue an interrupted run (same result bit for bit)")
    m.add_argument("--resume", action="store_true",
                   help="continue the run held by --checkpoint (its inputs must be the same)")
    m.add_argument("--hist", default=None, metavar="PNG",
                   help="write a histogram PNG (checked before the Monte Carlo runs)")
    m.add_argument("--top", type=whole(1, 100_000),
                   default=10, help="rows of the contribution table (10)")
    add_progress(m)
    a = p.add_argument_group("allocation")
    a.add_argument("--allocate", action="store_true",
                   help="find per-parameter tolerances meeting --max-dp/--max-angle at "
                        "--percentile, as loose as possible")
    a.add_argument("--max-dp", type=LENGTH, default=0.1,
                   help="requirement on max delta_p, length unit (default 0.1)")
    a.add_argument("--max-angle", type=real(0.0, math.pi, open_lo=True, unit="rad"),
                   default=None, help="requirement on the angle, rad")
    a.add_argument("--angle-scale", type=LENGTH, default=100.0,
                   help="length-equivalent of 1 rad in the cost, mm (default 100)")
    a.add_argument("--n-search", type=whole(10, 10_000_000),
                   default=4000, help="robots per bisection step")
    a.add_argument("--fixed", action="append", metavar="NAME=VALUE",
                   help="tolerances kept fixed during allocation (repeatable)")
    add_cluster_options(p)
    p.add_argument("--force", action="store_true",
                   help="replace the --hist file if it exists (without it, an existing file is "
                        "never replaced)")
    p.set_defaults(func=_tolerance, api_names={
        "q0": "--q0",
        "steps": "--steps",
        "n_robots": "--robots",
        "percentile": "--percentile",
    })


def _tolerance(args: argparse.Namespace) -> int:
    from zrp.manufacturing.plots import check_png_path  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick

    model = load_model(args.model)
    check_path_options(args, model)
    if not 0.0 < args.percentile < 100.0:
        raise InputError(f"--percentile: expected 0 < P < 100 (e.g. 99), got {args.percentile}")
    check_cluster_options(args)
    if args.allocate and (args.robots > GATHER_LIMIT or args.reduce):
        raise InputError(f"--robots, --reduce: --allocate verifies its tolerances with at most "
                         f"{GATHER_LIMIT:,} robots gathered here (got --robots {args.robots:,}"
                         + (" and --reduce" if args.reduce else "") + ")")
    _check_checkpoint(args)
    if args.hist:
        check_png_path(args.hist, "--hist")
        check_writable([args.hist], args.force)
    path = path_from_args(args, model)
    try:
        with executor_from_args(args) as ex:
            if args.allocate:
                return _allocate(args, model, path, ex)
            return _analyse(args, model, path, ex)
    except KeyboardInterrupt:
        if args.checkpoint:
            print(f"the run's state is in {args.checkpoint}: the same command with --resume "
                  "continues it", file=sys.stderr)
        raise


def _check_checkpoint(args: argparse.Namespace) -> None:
    """--checkpoint / --resume, before any work."""
    if args.resume and not args.checkpoint:
        raise InputError("--resume: continues the run held by --checkpoint NPZ; give it")
    if not args.checkpoint:
        return
    if args.allocate:
        raise InputError("--checkpoint: --allocate's verification runs are not checkpointed")
    if not str(args.checkpoint).endswith(".npz"):
        raise InputError(f"--checkpoint: {args.checkpoint!r} is not a .npz file name (the state"
                         " is a NumPy archive, e.g. run.npz)")
    if Path(args.checkpoint).exists() and not (args.resume or args.force):
        raise InputError(f"--checkpoint: {args.checkpoint} exists (the state of an earlier "
                         f"run): --resume continues it, --force starts over")


def _allocate(args: argparse.Namespace, model: Manipulator, path: JointPath,
              ex: Executor | None) -> int:
    """--allocate: the loosest tolerances meeting the requirement, verified (the verification
    Monte Carlo runs on the executor)."""
    import numpy as np  # on use: keeps --help quick

    from zrp.manufacturing.allocation import allocate_tolerances  # on use: keeps --help quick
    from zrp.manufacturing.plots import histogram_png  # on use: keeps --help quick

    rng = np.random.default_rng(args.seed)
    u = model.length_unit
    al = allocate_tolerances(model, path.q, rng=rng, max_delta_p=args.max_dp,
                             max_angle_rad=args.max_angle, percentile=args.percentile,
                             distribution=args.distribution, angle_scale_mm=args.angle_scale,
                             fixed=_parse_tol(args.fixed), n_search=args.n_search,
                             n_verify=args.robots, progress=draw_bar(args),
                             executor=ex)
    s = al.summary()
    s["trajectory"] = path.label
    s["distribution"] = args.distribution
    pct = args.percentile
    lines = [
        f"{model.name}: {path.label} ({path.t.size} samples), {args.distribution} "
        f"({'half-width' if args.distribution == 'uniform' else '3 sigma'})",
        f"requirement: max delta_p <= {args.max_dp:g} {u}"
        + (f", max angle <= {args.max_angle:g} rad" if args.max_angle else "")
        + f" at the {pct:g}th percentile",
        f"looseness = harmonic mean of length-equivalent tolerances (angles x "
        f"{args.angle_scale:g} mm): {al.looseness_mm:.4g} mm "
        f"(equal-tolerance baseline {al.baseline_looseness_mm:.4g} mm, x"
        f"{s['looser_than_baseline_factor']:.3g})",
        f"verified by Monte Carlo ({al.verification.n_robots} fresh robots): P{pct:g} "
        f"delta_p = {s[f'verified_p{pct:g}_delta_p']:.4g} {u} (95 % CI "
        f"{al.ci_delta_p[0]:.4g}..{al.ci_delta_p[1]:.4g}) -> "
        f"{'OK' if al.verified else 'NOT MET'}",
        f"first-order worst case (all parameters at the corner of their box): "
        f"{al.worst_case_p:.4g} {u}, {al.worst_case_angle_rad:.3g} rad",
        "",
        "allocated tolerances:",
    ]
    for nm, val, unit in zip(al.tolerances.names, al.tolerances.values,
                             al.tolerances.units, strict=True):
        lines.append(f"  {nm:10s} {val:.4g} {unit}")
    lines += ["", al.contribution.markdown(u, top=args.top)]
    if args.hist:
        s["histogram"] = str(histogram_png(al.verification, args.hist,
                                           overwrite=args.force))
        lines.append(f"wrote {s['histogram']}")
    emit(args, s, "\n".join(lines))
    return 0


def _analyse(args: argparse.Namespace, model: Manipulator, path: JointPath,
             ex: Executor | None) -> int:
    """Monte Carlo of the given tolerances, with the first-order budget beside it. Chunk i
    draws its robots from (--seed, i), so the result is the same in this process and on any
    number of workers. With --reduce (implied above GATHER_LIMIT robots) each chunk comes back
    as histograms: percentiles are known to their bin, extremes exactly."""
    from zrp.manufacturing.budget import tolerance_report  # on use: keeps --help quick
    from zrp.manufacturing.plots import histogram_png  # on use: keeps --help quick
    from zrp.manufacturing.population import (  # on use: keeps --help quick
        MonteCarloResult,
        monte_carlo,
    )
    from zrp.manufacturing.reduction import (  # on use: keeps --help quick
        MonteCarloSummary,
        monte_carlo_summary,
    )
    from zrp.manufacturing.tolerance import Tolerances  # on use: keeps --help quick

    u = model.length_unit
    offsets = args.offsets is not None
    tol = Tolerances.build(model, length=args.length, angle_rad=args.angle,
                           offset=args.offsets or 0.0, per_parameter=_parse_tol(args.tol),
                           joint_offsets=offsets)
    reduced = args.reduce or args.checkpoint is not None or args.robots > GATHER_LIMIT
    common = dict(seed=args.seed, distribution=args.distribution,
                  progress=draw_bar(args), first_order=True, executor=ex)
    mc: MonteCarloResult | MonteCarloSummary = (
        monte_carlo_summary(model, path.q, tol, args.robots, checkpoint=args.checkpoint,
                            resume=args.resume, overwrite=args.force, **common)
        if reduced else monte_carlo(model, path.q, tol, args.robots, **common))
    rep = tolerance_report(model, path.q, tol, mc)
    pct = args.percentile
    dp, ang = mc.percentile(pct)
    lo, hi = mc.percentile_ci(pct)
    payload: dict[str, Any] = mc.summary()
    payload.update({
        "model": model.name, "trajectory": path.label, "seed": args.seed,
        "tolerances": tol.as_dict(),
        f"p{pct:g}_max_delta_p": dp, f"p{pct:g}_max_delta_p_ci95": [lo, hi],
        f"p{pct:g}_max_angle_rad": ang,
        "worst_case_delta_p": rep["worst_case_delta_p"],
        "worst_case_angle_rad": rep["worst_case_angle_rad"],
        "mc_max_over_worst_case_p": rep["mc_over_worst_case_p"],
        "contribution": rep["contribution"].rows(),
    })
    fo_p = payload["first_order"][f"max_delta_p_{u}"][f"p{pct:g}"]
    lines = [
        f"{model.name}: {path.label} ({path.t.size} samples)",
        f"{mc.n_robots:,} robots, {args.distribution} "
        f"({'half-width' if args.distribution == 'uniform' else '3 sigma'}), seed {args.seed}: "
        f"length {args.length:g} {u}, angle {args.angle:g} rad"
        + (f", offsets {args.offsets:g}" if offsets else "")
        + (f", overrides {args.tol}" if args.tol else ""),
        f"kernel: {mc.elapsed_s:.3f} s summed over chunks, {mc.poses_per_s / 1e6:.2f} M "
        "poses/s per kernel",
    ]
    if reduced:
        lines.append(f"each chunk reduced to histograms where it ran: a percentile is known to "
                     f"its bin ({100 * mc.delta_p.relative_width:.2g} % wide; brackets in the "
                     "JSON), count, extremes and mean exactly")
        if args.checkpoint:
            lines.append(f"checkpoint {args.checkpoint}: {mc.resumed_robots:,} robots resumed "
                         f"from it, {mc.n_robots - mc.resumed_robots:,} run now")
    lines += [
        "",
        f"max_t delta_p ({u}) percentiles: " + _row(payload[f"max_delta_p_{u}"]),
        "max_t angle (rad) percentiles:  " + _row(payload["max_angle_rad"]),
        f"P{pct:g} delta_p = {dp:.4g} {u} (95 % CI {lo:.4g}..{hi:.4g}); first-order model "
        f"with the same draws: {fo_p:.4g} {u}",
        f"first-order worst case over the +-tol box: {rep['worst_case_delta_p']:.4g} {u}, "
        f"{rep['worst_case_angle_rad']:.3g} rad; Monte Carlo max reached "
        f"{rep['mc_over_worst_case_p']:.2f} of it"
        + (" (normal draws can leave the 3-sigma box)" if args.distribution == "normal"
           else ""),
        "",
        rep["contribution"].markdown(u, top=args.top),
    ]
    if args.hist:
        payload["histogram"] = str(histogram_png(mc, args.hist, overwrite=args.force))
        lines.append(f"wrote {payload['histogram']}")
    emit(args, payload, "\n".join(lines))
    return 0


def _row(block: dict[str, Any]) -> str:
    """"P50 0.05449, P90 ..." from a summary block (percentile keys; brackets and the
    reduced run's max/mean are left to the JSON)."""
    return ", ".join(f"{k.upper()} {v:.4g}" for k, v in block.items()
                     if k.startswith("p") and not k.endswith("_bracket"))
