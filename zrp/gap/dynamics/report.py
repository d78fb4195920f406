"""The dynamic gap report: report.md, report.html (self-contained, as the static diagnosis's,
:func:`zrp.gap.report.html.report_html`), the per-joint torque residuals before and after
against velocity and position (PNG beside it, SVG inside the page) and diagnosis.json.

Every name from the model or the log (the arm, its joints and bodies in the effects' labels,
the notes) reaches the Markdown only through :mod:`zrp.escape` (:func:`~zrp.escape.md_row`,
:func:`~zrp.escape.md_line`, :func:`~zrp.escape.md_text`): a joint named
``j1\n\n## Verdict`` stays one table cell, ``|`` adds no cell and ``<script>`` stays text, in
report.md and in report.html. The ``extra`` sections are Markdown the caller built the same
way."""

from __future__ import annotations

import io
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from zrp.escape import md_line, md_row, md_text, one_line
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis
from zrp.gap.report.html import report_html
from zrp.jsonio import to_jsonable
from zrp.output import OutputDir

__all__ = ["REPORT_FILES", "diagnosis_json", "report_markdown", "write_report"]

FIGURES = {"residuals_velocity.png": ("qd", "joint velocity (rad/s)"),
           "residuals_position.png": ("q", "joint position (rad)")}
#: the files :func:`write_report` writes
REPORT_FILES = ("report.md", "report.html", "diagnosis.json", *FIGURES)


def _fmt(v: float | None) -> str:
    return "-" if v is None else f"{v:.3g}"


def _verdict(d: DynamicDiagnosis) -> str:
    worst = int(np.argmax(d.rms_before / d.noise_nm))
    if not d.effects:
        return (f"The model's torques match the log down to the noise floor (worst joint "
                f"{worst + 1}: {d.rms_before[worst]:.3g} N m RMS against a noise of "
                f"{d.noise_nm[worst]:.3g} N m); no effect is needed.")
    names = ", ".join(md_text(e.label) for e in d.effects)
    return (f"The model misses most on joint {worst + 1} ({d.rms_before[worst]:.3g} N m RMS, "
            f"{d.rms_before[worst] / d.noise_nm[worst]:.1f}x its noise). Found: {names}. "
            f"Withheld torque RMS on joint {worst + 1} drops to {d.rms_after[worst]:.3g} N m "
            f"({d.rms_after[worst] / d.noise_nm[worst]:.2f}x the noise).")


def _effects(d: DynamicDiagnosis) -> list[str]:
    out = ["| effect | parameter | value | 95 % interval | unit | withheld chi2 drop |",
           "|---|---|---|---|---|---|"]
    for e in d.effects:
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


def report_markdown(d: DynamicDiagnosis, extra: dict[str, Any] | None = None) -> str:
    """The report's text (``extra``: more sections, heading -> lines)."""
    n = len(d.joints)
    lines = [md_line("# Dynamic gap: {}", d.arm), "", "## Verdict", "", _verdict(d), "",
             "## Torque residual per joint (N m RMS)", "",
             "| joint | name | noise floor | model | corrected (withheld) | ratio to noise |",
             "|---|---|---|---|---|---|"]
    lines += [md_row(k + 1, d.joints[k], f"{d.noise_nm[k]:.3g}", f"{d.rms_before[k]:.3g}",
                     f"{d.rms_after[k]:.3g}", f"{d.rms_after[k] / d.noise_nm[k]:.2f}")
              for k in range(n)]
    lines += ["", "## Effects found", ""]
    lines += _effects(d) if d.effects else ["None: the torques are explained to the noise."]
    lines += ["", "## Selection (withheld chi2: 1 is the noise floor)", "",
              " -> ".join(md_line("{} {}", s.key, f"{s.chi2:.3g}") for s in d.steps), "",
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
    fig.tight_layout()
    return fig, plt


def _inertial_fit(d: DynamicDiagnosis) -> dict[str, Any] | None:
    """The physical link inertia fit's figures (its values are under effects and
    inertial_phi)."""
    f = d.inertial_fit
    if f is None:
        return None
    return {**{k: v for k, v in asdict(f).items() if k not in ("theta", "phi")},
            "matched": f.matched, "summary": f.describe()}


def diagnosis_json(d: DynamicDiagnosis, extra: dict[str, Any] | None = None) -> dict:
    out = {"arm": d.arm, "joints": d.joints, "noise_nm": d.noise_nm,
           "rms_before_nm": d.rms_before, "rms_after_withheld_nm": d.rms_after,
           "steps": [asdict(s) for s in d.steps],
           "effects": [asdict(e) for e in d.effects], "cannot_tell": d.cannot_tell,
           "regimes": d.regimes, "inertial_fit": _inertial_fit(d),
           "inertial_phi": {str(b): v for b, v in d.inertial_phi.items()}, "notes": d.notes}
    return to_jsonable({**out, **(extra or {})})


def write_report(d: DynamicDiagnosis, folder: str | Path, *, overwrite: bool = False,
                 extra: dict[str, Any] | None = None) -> Path:
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
        md = report_markdown(d, sections)
        out.write_text("report.md", md)
        out.write_text("report.html", report_html(md, svgs, f"Dynamic gap: {one_line(d.arm)}"))
        out.write_json("diagnosis.json", diagnosis_json(d, {k: v for k, v in (extra or {}).items()
                                                            if k != "sections"}))
    return Path(folder)
