"""The dynamic gap report: report.md, report.html (self-contained, as the static diagnosis's,
:func:`zrp.gap.report.html.report_html`), the per-joint torque residuals before and after
against velocity and position (PNG beside it, SVG inside the page) and diagnosis.json.

Every name from the model or the logs (the arm, its joints and bodies in the effects' labels
and words, a log's file name, the notes) reaches the Markdown only through :mod:`zrp.escape`
(:func:`~zrp.escape.md_row`, :func:`~zrp.escape.md_line`, :func:`~zrp.escape.md_text`): a
joint named ``j1\n\n## Verdict`` stays one table cell, ``|`` adds no cell and ``<script>``
stays text, in report.md and in report.html. The ``extra`` sections are Markdown the caller
built the same way."""

from __future__ import annotations

import io
from dataclasses import asdict
from pathlib import Path
from typing import Any

from zrp.escape import md_line, md_row, md_text, one_line
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis
from zrp.gap.dynamics.run import DynamicsRun
from zrp.gap.dynamics.validation import Validation
from zrp.gap.dynamics.verdict import effect_words, headline, overall_rms, validation_words
from zrp.gap.report.html import report_html
from zrp.jsonio import to_jsonable
from zrp.output import OutputDir, tight_layout_once, write_text

__all__ = ["REPORT_FILES", "diagnosis_json", "report_markdown", "run_json", "write_report",
           "write_run"]

FIGURES = {"residuals_velocity.png": ("qd", "joint velocity (rad/s)"),
           "residuals_position.png": ("q", "joint position (rad)")}
#: the files :func:`write_run` writes (corrected.xml when there is a corrected model)
REPORT_FILES = ("report.md", "report.html", "diagnosis.json", *FIGURES, "corrected.xml")


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.3g}"


def _verdict(d: DynamicDiagnosis, validation: Validation | None) -> list[str]:
    """The headline, then one line per finding in words."""
    out = [md_text(headline(d, validation))]
    if d.found:
        out += ["", *(md_line("- {}", effect_words(d, e)) for e in d.found)]
    return out


def _effects(d: DynamicDiagnosis) -> list[str]:
    out = ["| effect | parameter | value | 95 % interval | unit | withheld chi2 drop |",
           "|---|---|---|---|---|---|"]
    for e in d.found:
        for k, p in e.params.items():
            if k.startswith("beta"):
                continue
            flag = " (at its bound)" if p.at_bound else ""
            out.append(md_row(e.label, k, f"{p.value:.4g}{flag}", f"{p.low:.4g} .. {p.high:.4g}",
                              p.unit, f"{e.chi2_drop:.3g}"))
        if e.name == "inertial":
            out.append(md_row(e.label, f"{len(e.params)} base combinations",
                              "see diagnosis.json", "", "", f"{e.chi2_drop:.3g}"))
    return out


def _regimes(d: DynamicDiagnosis) -> list[str]:
    n = len(d.joints)
    out = ["| regime | " + " | ".join(f"joint {k + 1} before / after" for k in range(n)) + " |",
           "|---|" + "---|" * n]
    for name, before in d.regimes["before"].items():
        after = d.regimes["after"][name]
        out.append(md_row(name, *(f"{_fmt(b)} / {_fmt(a)}"
                                   for b, a in zip(before, after, strict=True))))
    return out


def _validation(v: Validation, joints: list[str]) -> list[str]:
    out = [md_text(validation_words(v)), "",
           "| joint | noise floor | model | corrected | ratio to noise |", "|---|---|---|---|---|"]
    out += [f"| {k + 1} | {v.noise_nm[k]:.3g} | {v.rms_before[k]:.3g} | {v.rms_after[k]:.3g} "
            f"| {v.rms_after[k] / v.noise_nm[k]:.2f} |" for k in range(len(joints))]
    out.append(f"| all | {v.overall_noise:.3g} | {v.overall_before:.3g} | "
               f"{v.overall_after:.3g} | {v.overall_after / v.overall_noise:.2f} |")
    return out


def _found(d: DynamicDiagnosis) -> list[str]:
    """The findings' table, then the small effects in one line."""
    out = _effects(d) if d.found else ["None: the torques are explained to the noise."]
    small = [e for e in d.effects if e.small]
    if small:
        out += ["", "Small effects (in the corrected model; each lowers the withheld error by "
                "less than the selection's threshold, so none is a finding): "
                + md_text(", ".join(e.label for e in small)) + "."]
    return out


def _step(s: Any) -> str:
    if s.replaces:
        return md_line("{} for {} {}", s.key, s.replaces, f"{s.chi2:.3g}")
    return md_line("{} {}", s.key, f"{s.chi2:.3g}")


def _baseline(d: DynamicDiagnosis, v: Validation | None) -> list[str]:
    """The standard identification on the same samples (and the second log)."""
    b = d.baseline
    if b is None:
        return ["- not fitted"]
    m = d.measured
    out = [md_line("{}, fitted on the same samples and scored on the same withheld time "
                   "segments: {} N m RMS (withheld chi2 {}); the corrected model {} N m "
                   "(chi2 {}).", b.description, f"{overall_rms(b.rms_withheld, m):.3g}",
                   f"{b.chi2:.3g}", f"{overall_rms(d.rms_after, m):.3g}",
                   f"{d.steps[-1].chi2 if d.steps else float('nan'):.3g}")]
    if v is not None and v.overall_baseline is not None:
        out.append(md_line("On {}: the standard identification {} N m, the corrected model {} "
                           "N m.", v.source, f"{v.overall_baseline:.3g}",
                           f"{v.overall_after:.3g}"))
    return out


def _residuals(d: DynamicDiagnosis) -> list[str]:
    """The table of the torque residual per joint, and the joints not measured."""
    n = len(d.joints)
    lines = ["## Torque residual per joint (N m RMS)", "",
             "| joint | name | noise floor | model | corrected (withheld) | ratio to noise |",
             "|---|---|---|---|---|---|"]
    lines += [md_row(k + 1, d.joints[k], f"{d.noise_nm[k]:.3g}", f"{d.rms_before[k]:.3g}",
                     f"{d.rms_after[k]:.3g}", f"{d.rms_after[k] / d.noise_nm[k]:.2f}")
              if d.measured[k] else md_row(k + 1, d.joints[k], "-", "-", "-", "not measured")
              for k in range(n)]
    m = d.measured
    lines.append(f"| all measured | | {overall_rms(d.noise_nm, m):.3g} | "
                 f"{overall_rms(d.rms_before, m):.3g} | {overall_rms(d.rms_after, m):.3g} | "
                 f"{overall_rms(d.rms_after, m) / overall_rms(d.noise_nm, m):.2f} |")
    lines += [md_line("- joint {} is not measured ({}): left out of the fit and of the overall "
                      "figures", k + 1, why) for k, why in sorted(d.unmeasured.items())]
    return lines


def _data_problems(d: DynamicDiagnosis) -> list[str]:
    """The findings that point at the data (:mod:`zrp.gap.dynamics.plausible`), if any."""
    if not d.data_problems:
        return []
    return ["", "## Data problems", "", *(md_line("- {}", s) for s in d.data_problems)]


def report_markdown(d: DynamicDiagnosis, extra: dict[str, Any] | None = None,
                    validation: Validation | None = None) -> str:
    """The report's text (``extra``: more sections, heading -> lines; ``validation``: the
    corrected model on a second log)."""
    lines = [md_line("# Dynamic gap: {}", d.arm), "", "## Verdict", "", *_verdict(d, validation),
             "", *_residuals(d)]
    if validation is not None:
        lines += ["", "## Validation on another log (N m RMS)", "",
                  *_validation(validation, d.joints)]
    lines += _data_problems(d)
    lines += ["", "## Against the standard identification", "", *_baseline(d, validation)]
    lines += ["", "## Effects found", "", *_found(d)]
    lines += ["", "## Selection (withheld chi2: 1 is the noise floor)", "",
              " -> ".join(_step(s) for s in d.steps), "",
              "## Where: residual RMS per regime (N m; before / after)", ""]
    lines += _regimes(d)
    lines += ["", "## Cannot tell", ""]
    lines += [md_line("- {}", c) for c in d.cannot_tell] or [
        "- nothing: every joint effect is excited"]
    for heading, body in (extra or {}).items():
        lines += ["", md_line("## {}", heading), "", *body]
    lines += ["", "## Residuals", "", *(f"![residual against {v[1]}]({name})"
                                        for name, v in FIGURES.items())]
    lines += ["", "## Notes", "", *(md_line("- {}", s) for s in d.notes)]
    return "\n".join(lines) + "\n"


def _figure(d: DynamicDiagnosis, which: str, xlabel: str) -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = d.samples
    n = len(d.joints)
    cols = min(n, 4)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.6 * rows), squeeze=False)
    x = getattr(s, which)
    for k in range(n):
        ax = axes[k // cols][k % cols]
        ax.plot(x[:, k], s.before[:, k], ".", ms=1.5, color="tab:red", alpha=0.5,
                label="model", rasterized=True)
        ax.plot(x[:, k], s.after[:, k], ".", ms=1.5, color="tab:blue", alpha=0.5,
                label="corrected (withheld)", rasterized=True)
        ax.axhspan(-2 * d.noise_nm[k], 2 * d.noise_nm[k], color="0.85", zorder=0)
        ax.set_title(f"joint {k + 1}", fontsize=9)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel("measured - model (N m)", fontsize=8)
        ax.tick_params(labelsize=7)
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].axis("off")
    axes[0][0].legend(fontsize=7, markerscale=5, loc="best")
    fig.suptitle("torque residuals (grey: +-2 sigma noise)", fontsize=10)
    tight_layout_once(fig)
    return fig, plt


def _inertial_fit(d: DynamicDiagnosis) -> dict[str, Any] | None:
    """The physical link inertia fit's figures (its values are under effects and
    inertial_phi)."""
    f = d.inertial_fit
    if f is None:
        return None
    return {**{k: v for k, v in asdict(f).items() if k not in ("theta", "phi")},
            "matched": f.matched, "summary": f.describe()}


def _validation_json(v: Validation | None) -> dict[str, Any] | None:
    if v is None:
        return None
    return {"source": v.source, "samples": v.samples, "noise_nm": v.noise_nm,
            "rms_before_nm": v.rms_before, "rms_after_nm": v.rms_after,
            "overall_before_nm": v.overall_before, "overall_after_nm": v.overall_after,
            "overall_noise_nm": v.overall_noise, "rms_baseline_nm": v.rms_baseline,
            "overall_baseline_nm": v.overall_baseline}


def _bodies_json(d: DynamicDiagnosis) -> list[dict[str, Any]]:
    return [{"body": c.name, "effects": list(c.effects), "mass_change_kg": c.mass_change,
             "centre_shift_m": c.centre_shift_m, "phi_model": c.phi0, "phi": c.phi,
             "torque_rms_nm": c.torque_rms} for c in d.bodies.values()]


def diagnosis_json(d: DynamicDiagnosis, extra: dict[str, Any] | None = None,
                   validation: Validation | None = None) -> dict:
    out = {"verdict": headline(d, validation), "arm": d.arm, "joints": d.joints,
           "noise_nm": d.noise_nm, "overall_nm": {
               "noise": overall_rms(d.noise_nm, d.measured),
               "before": overall_rms(d.rms_before, d.measured),
               "after_withheld": overall_rms(d.rms_after, d.measured)},
           "unmeasured": {str(k + 1): why for k, why in sorted(d.unmeasured.items())},
           "rms_before_nm": d.rms_before, "rms_after_withheld_nm": d.rms_after,
           "validation": _validation_json(validation), "bodies": _bodies_json(d),
           "steps": [asdict(s) for s in d.steps],
           "effects": [asdict(e) for e in d.effects], "cannot_tell": d.cannot_tell,
           "baseline": None if d.baseline is None else {
               "method": d.baseline.description, "effects": list(d.baseline.keys),
               "withheld_chi2": d.baseline.chi2,
               "rms_withheld_nm": d.baseline.rms_withheld,
               "overall_withheld_nm": overall_rms(d.baseline.rms_withheld, d.measured)},
           "window_s": d.window_s,
           "regimes": d.regimes, "inertial_fit": _inertial_fit(d),
           "inertial_phi": {str(b): v for b, v in d.inertial_phi.items()}, "notes": d.notes,
           "data_problems": d.data_problems}
    return to_jsonable({**out, **(extra or {})})


def write_report(d: DynamicDiagnosis, folder: str | Path, *, overwrite: bool = False,
                 extra: dict[str, Any] | None = None, validation: Validation | None = None
                 ) -> Path:
    """Write report.md, report.html, the residual PNGs and diagnosis.json into ``folder``."""
    svgs: dict[str, bytes] = {}
    sections = (extra or {}).get("sections")
    with OutputDir(folder, overwrite=overwrite) as out:
        for name, (which, label) in FIGURES.items():
            fig, plt = _figure(d, which, label)
            out.savefig(name, fig, dpi=110)
            buf = io.BytesIO()
            fig.savefig(buf, format="svg")
            svgs[name] = buf.getvalue()
            plt.close(fig)
        md = report_markdown(d, sections, validation)
        out.write_text("report.md", md)
        out.write_text("report.html", report_html(md, svgs, f"Dynamic gap: {one_line(d.arm)}"))
        out.write_json("diagnosis.json", diagnosis_json(
            d, {k: v for k, v in (extra or {}).items() if k != "sections"}, validation))
    return Path(folder)


def _tracking_lines(track: Any, joints: int) -> list[str]:
    if track is None:
        return ["- the log has no commanded positions qc1..qcn: no re-simulation"]
    lines = [md_line("Re-simulation of the logged command with {}; RMS of simulated minus "
                     "logged joint positions (rad):", track.servo), "",
             "| joint | model | corrected model |", "|---|---|---|"]
    return lines + [md_row(k + 1, f"{track.before_rad[k]:.3g}", f"{track.after_rad[k]:.3g}")
                    for k in range(joints)]


def _extra(run: DynamicsRun) -> dict[str, Any]:
    n = len(run.diagnosis.joints)
    sections: dict[str, list[str]] = {}
    data: dict[str, Any] = {}
    if run.corrected_model is not None:
        sections["Corrected model"] = [md_text(s) for s in run.model_notes]
        sections["Tracking"] = _tracking_lines(run.tracking, n)
        if run.tracking is not None:
            data["tracking"] = {"before_rad": run.tracking.before_rad,
                                "after_rad": run.tracking.after_rad,
                                "servo": run.tracking.servo}
    return {"sections": sections, **data}


def write_run(run: DynamicsRun, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Write report.html/.md, the residual plots, diagnosis.json and (when there is one)
    corrected.xml into ``folder``; existing files only with ``overwrite``."""
    out = write_report(run.diagnosis, folder, overwrite=overwrite, extra=_extra(run),
                       validation=run.validation)
    if run.corrected_model is not None:
        write_text(Path(out) / "corrected.xml", run.corrected_model, overwrite=overwrite)
    return Path(out)


def run_json(run: DynamicsRun) -> dict:
    """diagnosis.json of the run (as written)."""
    extra = {k: v for k, v in _extra(run).items() if k != "sections"}
    return diagnosis_json(run.diagnosis, extra, validation=run.validation)
