"""``zrp verify --data FRESH.csv``: what a calibration achieved on a fresh real measurement
(:mod:`zrp.calibration.verification`), written to a folder: verification.json, errors.csv
(per measured point), verification.md (the report page) and verification.png (the plot)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from zrp.errors import InputError

FILES = ("verification.json", "errors.csv", "verification.md", "verification.png")


def _plot(ver: Any, unit: str, path: Path) -> None:
    """Histogram of the achieved errors with the predicted RMS and the achieved RMS/p95."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from zrp.output.figures import tight_layout_once  # with matplotlib: on use only

    d = ver.to_dict()
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for mask, label in ((~ver.outside, "within the measured ranges"),
                        (ver.outside, "outside them")):
        if mask.any():
            ax.hist(ver.errors[mask], bins=40, alpha=0.7, label=label)
    ax.axvline(d["all"]["rms"], color="k", label=f"achieved RMS {d['all']['rms']:.3g}")
    ax.axvline(d["all"]["p95"], color="k", ls=":", label=f"95th pct {d['all']['p95']:.3g}")
    if ver.predicted_rms is not None:
        ax.axvline(ver.predicted_rms, color="r", ls="--",
                   label=f"predicted (withheld) RMS {ver.predicted_rms:.3g}")
    ax.set_xlabel(f"3-D position error ({unit})")
    ax.set_ylabel("measured points")
    ax.set_xlim(0, float(np.max(ver.errors)) * 1.05 or 1.0)
    ax.legend(fontsize=8)
    tight_layout_once(fig)
    fig.savefig(path, dpi=110, metadata={"Software": None})
    plt.close(fig)


def _page(ver: Any, unit: str, cal_path: str, data_path: str) -> str:
    d = ver.to_dict()
    rows = ["| set | points | RMS | 95th percentile | max |", "|---|---|---|---|---|"]
    for name, key in (("all", "all"), ("within the measured joint ranges",
                                        "within_measured_ranges"),
                      ("outside them", "outside_measured_ranges")):
        s = d[key]
        if s["n"]:
            rows.append(f"| {name} | {s['n']} | {s['rms']:.4g} | {s['p95']:.4g} | "
                        f"{s['max']:.4g} |")
    pred = ("not recorded in the calibration" if ver.predicted_rms is None
            else f"{ver.predicted_rms:.4g} {unit} RMS")
    return "\n".join([
        "# Verification on a fresh measurement", "",
        f"Calibration `{Path(cal_path).name}`, fresh data `{Path(data_path).name}`.", "",
        ver.words(unit), "",
        f"Predicted by the diagnosis (withheld poses): {pred}.", "",
        f"Achieved ({unit}):", "", *rows, "",
        "![errors](verification.png)", ""])


def _errors_csv(ver: Any, meas: Any, unit: str) -> str:
    from zrp.escape import csv_text  # on use: keeps --help quick

    rows = ([p, pt, repr(float(e)), int(o)] for p, pt, e, o in zip(
        meas.pose, meas.point, ver.errors, ver.outside, strict=True))
    return csv_text(["pose", "point", f"error[{unit}]", "outside_measured"], rows)


def run_data(args: argparse.Namespace) -> tuple[dict[str, Any], str]:
    """The --data mode: (summary, text); writes the folder --out when given."""
    from zrp.calibration import read_calibration  # on use: keeps --help quick
    from zrp.calibration.verification import verify_measurements  # on use: quick --help
    from zrp.gap.data.csvfile import load_measurements  # on use: keeps --help quick
    from zrp.jsonio import dumps  # NumPy: on use
    from zrp.output import check_writable, write_text  # on use: keeps --help quick

    if args.truth or args.targets or args.commands:
        raise InputError("--data: a fresh measurement is verified on its own; --truth, "
                         "--targets and --commands are for the simulated robot")
    out = None if args.out is None else Path(args.out)
    if out is not None:
        check_writable([out / f for f in FILES], args.force)
    cal = read_calibration(args.calibration)
    meas = load_measurements(args.data, cal.model, deg=args.deg, frame=args.frame)
    grav = None
    if args.mjcf is not None:
        from mjcf.gravity import gravity_torques  # MuJoCo: only when asked for

        def grav(q: Any) -> Any:
            return gravity_torques(args.mjcf, q, field="--mjcf",
                                   joint_names=[j.name for j in cal.model.joints])
    elif cal.compliance_model == "mjcf" and any(t.effect == "joint_compliance"
                                                for t in cal.terms):
        raise InputError("--mjcf: this calibration's joint compliance was identified with an "
                         "MJCF's gravity torques; pass the same MJCF or URDF with --mjcf")
    ver = verify_measurements(cal, meas, reregister=args.reregister,
                              min_repeats=args.min_repeats, gravity_torque=grav)
    unit = cal.model.length_unit
    s = ver.to_dict()
    text = ver.words(unit)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        written = [write_text(out / FILES[0], dumps(s), overwrite=args.force),
                   write_text(out / FILES[1], _errors_csv(ver, meas, unit),
                              overwrite=args.force),
                   write_text(out / FILES[2], _page(ver, unit, args.calibration, args.data),
                              overwrite=args.force)]
        if not args.no_plots:
            _plot(ver, unit, out / FILES[3])
            written.append(out / FILES[3])
        text += "".join(f"\nwrote {p}" for p in written)
    return s, text
