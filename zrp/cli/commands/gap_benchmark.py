"""``zrp gap-benchmark``: the blind benchmark of the gap diagnosis on the MuJoCo real robot."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.cli.cluster import add_cluster_options, check_cluster_options, executor_from_args
from zrp.cli.options import FRACTION, SEED, add_progress, draw_bar, real, whole
from zrp.errors import InputError
from zrp.model.builtin import builtin_models
from zrp.output import OutputDir, claim_generated

DEFAULT_OUT = "renders/gap_benchmark"


def register(sub: argparse._SubParsersAction) -> None:
    from zrp.gap.model.choices import EFFECTS as EFFECT_NAMES  # light: no SciPy, numba

    p = sub.add_parser(
        "gap-benchmark", help="blind benchmark of the gap diagnosis on simulated robots",
        description="Draw K scenarios, each hiding one effect (or none, or two) with a random "
        "magnitude in the MuJoCo 'real' robot; measure it, run the diagnosis on the "
        "measurement CSV alone, then score it against the truth: effect named first, joints "
        "located, withheld RMS after correction vs the noise, shrink. Prints and writes a "
        "confusion matrix and a summary table (sim/README.md).")
    p.add_argument("--scenarios", type=whole(1, 100_000), default=50, metavar="K",
                   help="number of scenarios (default 50)")
    p.add_argument("--seed", type=SEED, default=0, metavar="S", help="master seed (default 0)")
    p.add_argument("--model", default="puma", metavar="M.toml",
                   help=f"model TOML file or built-in name ({', '.join(sorted(builtin_models()))}"
                        "; default puma)")
    p.add_argument("--poses", type=whole(8, 100_000),
                   default=200, help="poses per scenario (default 200)")
    p.add_argument("--none", type=FRACTION, default=0.1, metavar="FRACTION",
                   help="share of scenarios with no hidden effect (default 0.1)")
    p.add_argument("--pairs", type=FRACTION, default=0.15, metavar="FRACTION",
                   help="share of scenarios with two hidden effects (default 0.15)")
    p.add_argument("--effects", nargs="+", choices=EFFECT_NAMES, default=list(EFFECT_NAMES),
                   metavar="EFFECT", help="effects to draw from (default all)")
    p.add_argument("--noise", type=real(0.0, 1e3),
                   nargs=2, default=None, metavar=("LO", "HI"),
                   help="range of the tracker noise sigma per coordinate, model length unit "
                        "(default 0.01-0.03 mm in the model's unit)")
    traj = p.add_argument("--trajectory", choices=("random", "circle"), default="random",
                          help="random reachable poses (default) or the PUMA circle")
    deprecated_alias(p, "--poses-from", traj)
    p.add_argument("--approach", choices=("gravity", "random", "order"), default="gravity",
                   help="final approach against gravity for the gravity-loaded joints and "
                        "from a random side for the others (default), from a random side for "
                        "all, or straight moves in measurement order")
    p.add_argument("--reflectors", type=whole(1, 3), default=3, metavar="M",
                   help="reflectors on the tool, 1-3 (default 3; with 1 the diagnosis has no "
                        "noise floor from rigid links)")
    arm = p.add_argument("--mjcf", default=None, metavar="FILE",
                         help="the arm's shipped URDF or MJCF (its joints named as the "
                              "model's): the simulated robot takes its inertias, damping, "
                              "friction and tool, and the diagnosis gets it as its MJCF. "
                              "Without it an arm with no inertias of its own borrows the PUMA "
                              "560's (6R) or rods', announced")
    deprecated_alias(p, "--arm", arm)
    p.add_argument("--no-mjcf", action="store_true",
                   help="do not give the diagnosis the nominal MJCF (lumped-mass compliance)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help=f"output directory (default {DEFAULT_OUT}, generated output that is "
                        "replaced; elsewhere existing files need --force). One run at a time "
                        "per folder: a second run into it is refused")
    p.add_argument("--workdir", default=None, metavar="DIR",
                   help="where the measurement CSVs, truth files and diagnoses go (default "
                        "OUT/work)")
    p.add_argument("--compensate", type=whole(0, 100_000), default=0, metavar="N",
                   help="the compensated column: compensate N fresh random targets (plus N/2 "
                        "circle points) with each scenario's diagnosis, command and measure "
                        "them (default 0: no column)")
    add_cluster_options(p)
    p.add_argument("--resume", action="store_true",
                   help="keep the scores an interrupted run of the same configuration wrote "
                        "into WORKDIR/scores and run only the other scenarios")
    p.add_argument("--force", action="store_true",
                   help="replace existing output files in --out (checked before the run)")
    p.add_argument("--no-plots", action="store_true", help="skip confusion.png")
    add_progress(p)
    p.add_argument("--json", action="store_true", help="print results.json to stdout")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo and the diagnosis (+0.2 s measured): only when this command runs.
    from sim.studies.benchmark import (
        BenchmarkConfig,
        output_names,
        render_text,
        run_benchmark,
        write_outputs,
    )
    from zrp.model.files import load_model  # on use: keeps --help quick

    out = Path(args.out or DEFAULT_OUT)
    overwrite = args.force or (args.out is None and claim_generated(out))
    work = Path(args.workdir) if args.workdir else out / "work"
    if work.resolve() == out.resolve():
        raise InputError("--workdir: must differ from --out (it is locked for the run)")
    check_cluster_options(args)
    cfg = BenchmarkConfig(scenarios=args.scenarios, seed=args.seed, poses=args.poses,
                          none_fraction=args.none, pair_fraction=args.pairs,
                          effects=tuple(args.effects),
                          noise=None if args.noise is None else tuple(args.noise),
                          poses_from=args.trajectory, approach=args.approach,
                          use_mjcf=not args.no_mjcf, compensate=args.compensate,
                          reflectors=args.reflectors, arm_file=args.mjcf)
    model = load_model(args.model)
    # the folder is locked and its files checked before the (long) run
    with OutputDir(out, overwrite=overwrite, names=output_names(True), prune=True) as folder:
        # the work folder must be visible to the workers (same path on a remote cluster)
        with executor_from_args(args) as ex:
            result = run_benchmark(model, cfg, work, progress=draw_bar(args), executor=ex,
                                   resume=args.resume)
        files = write_outputs(result, folder, plots=not args.no_plots)
    text = render_text(result) + "\n" + "\n".join(f"wrote {f}" for f in files)
    emit(args, result.to_dict(), text)
    return 0
