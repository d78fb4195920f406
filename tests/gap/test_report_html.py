"""report.html in a real headless browser (Debian's ``chromium``, installed by .ci/run): the page
loads without console messages, is self-contained, and its first screen shows the verdict.
Skips only where no Chromium is installed."""

from __future__ import annotations

import html
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.gap import Injection, diagnose, synthesize, write_outputs
from zrp.gap.report import verdict_text
from zrp.gap.report.headline import headline_text
from zrp.kinematics import uniform_joint_values

BROWSER = next((b for b in ("chromium", "chromium-browser", "google-chrome")
                if shutil.which(b)), None)
needs_browser = pytest.mark.skipif(BROWSER is None, reason="no Chromium installed")
#: the verdict box's background (report/html.py: #fff4d6)
VERDICT_RGB = np.array([255, 244, 214])


def _browse(page: Path, tmp: Path) -> tuple[list[str], np.ndarray, str]:
    """Console lines, the screenshot (H, W, 3) of the first 1280 x 900 screen, and the DOM."""
    from PIL import Image

    shot = tmp / "shot.png"
    common = [BROWSER, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              f"--user-data-dir={tmp / 'profile'}", "--window-size=1280,900"]
    run = subprocess.run([*common, "--enable-logging=stderr", "--v=0",
                          f"--screenshot={shot}", page.as_uri()],
                         capture_output=True, text=True, timeout=120)
    console = [ln for ln in run.stderr.splitlines() if ":CONSOLE" in ln]
    dom = subprocess.run([*common, "--dump-dom", page.as_uri()], capture_output=True,
                         text=True, timeout=120).stdout
    return console, np.asarray(Image.open(shot).convert("RGB")), dom


def _verdict_shown(img: np.ndarray) -> bool:
    """The screenshot holds a verdict box of some size with text in it."""
    box = np.all(np.abs(img.astype(int) - VERDICT_RGB) <= 3, axis=-1)
    if box.sum() < 20_000:
        return False
    ys, xs = np.nonzero(box)
    inside = img[ys.min():ys.max() + 1, xs.min():xs.max() + 1]
    dark = np.all(inside < 110, axis=-1)
    return int(dark.sum()) > 500


def _check_page(out: Path, verdict: str, tmp: Path) -> None:
    page = out / "report.html"
    text = page.read_text(encoding="utf-8")
    # self-contained: every image and link is embedded or in-page
    refs = re.findall(r'(?:src|href)="([^"]*)"', text)
    assert "Content-Security-Policy" in text  # and the CSP forbids any network access
    assert refs and all(r.startswith(("data:", "#")) for r in refs), [
        r[:40] for r in refs if not r.startswith(("data:", "#"))]
    console, img, dom = _browse(page, tmp)
    assert console == [], console
    assert _verdict_shown(img), "the first screen does not show the verdict box"
    m = re.search(r'<div id="verdict">(.*?)</div>', dom, re.S)
    assert m is not None
    assert html.unescape(re.sub(r"<[^>]+>", "", m.group(1))).strip() == verdict
    assert dom.find('id="verdict"') < dom.find("<h2>Data</h2>")  # the verdict comes first


@needs_browser
def test_the_checks_can_fail(tmp_path):
    """Controls: a console error is caught, and a page without the verdict box is refused."""
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><head><link rel="icon" href="data:,"></head><body>'
                   '<p>no verdict</p><script>console.error("boom")</script></body></html>',
                   encoding="utf-8")
    console, img, _ = _browse(bad, tmp_path)
    assert any("boom" in c for c in console)
    assert not _verdict_shown(img)


#: appended to a copy of the page: a wheel turn over the first figure, then a drag; the
#: figure's state (data-scale, data-tx, data-ty) is read back from the dumped DOM.
_GESTURES = """<script>(function(){var box=document.querySelector('.pz');
var r=box.getBoundingClientRect(),cx=r.left+r.width/2,cy=r.top+r.height/2;
box.dispatchEvent(new WheelEvent('wheel',{deltaY:-500,clientX:cx,clientY:cy,bubbles:true,
cancelable:true}));document.body.dataset.afterWheel=box.dataset.scale+','+box.dataset.tx;
var o={clientX:cx,clientY:cy,bubbles:true,pointerId:1};
box.dispatchEvent(new PointerEvent('pointerdown',o));
box.dispatchEvent(new PointerEvent('pointermove',Object.assign({},o,{clientX:cx+40,
clientY:cy+25})));box.dispatchEvent(new PointerEvent('pointerup',o));
document.body.dataset.afterDrag=box.dataset.tx+','+box.dataset.ty;
box.dispatchEvent(new MouseEvent('dblclick',{bubbles:true}));
document.body.dataset.afterReset=box.dataset.scale;})();</script>"""


def _check_zoom(out: Path, tmp: Path) -> None:
    """Every figure is a pan/zoom box; a wheel turn zooms it about the pointer, a drag pans
    it, a double click restores it."""
    text = (out / "report.html").read_text(encoding="utf-8")
    assert text.count('class="pz"') == text.count("<figure") == 5
    probe = tmp / "probe.html"
    probe.write_text(text.replace("</body>", _GESTURES + "</body>"), encoding="utf-8")
    console, _, dom = _browse(probe, tmp)
    assert console == [], console
    body = re.search(r"<body([^>]*)>", dom).group(1)
    scale, tx = map(float, re.search(r'data-after-wheel="([^"]+)"', body).group(1).split(","))
    assert scale == pytest.approx(np.exp(500 * 0.0015), rel=1e-3) and tx < 0
    dx, dy = map(float, re.search(r'data-after-drag="([^"]+)"', body).group(1).split(","))
    assert dx == pytest.approx(tx + 40, abs=0.2) and dy < 0
    assert float(re.search(r'data-after-reset="([^"]+)"', body).group(1)) == 1.0


@needs_browser
def test_report_html_synthetic(tmp_path):
    model = zrp.load_model("puma")
    rng = np.random.default_rng(3)
    q = uniform_joint_values(model, 120, rng)
    meas = synthesize(model, q, Injection(joint_offset={2: 1e-3}), rng=rng, noise_sigma=0.02)
    d = diagnose(model, meas, seed=0)
    write_outputs(d, tmp_path / "out")
    _check_page(tmp_path / "out", headline_text(d), tmp_path)
    _check_zoom(tmp_path / "out", tmp_path)


@needs_browser
def test_report_html_real_irb120(irb120_real, tmp_path):
    d = irb120_real.diagnosis
    assert any(issubclass(w.category, zrp.gap.GapWarning) for w in irb120_real.warnings)
    write_outputs(d, tmp_path / "out")
    _check_page(tmp_path / "out", headline_text(d), tmp_path)
    md = (tmp_path / "out" / "report.md").read_text(encoding="utf-8")
    assert "complete geometric calibration" in md
    a = d.assessment
    assert a is not None
    # no cause is stated that conflicts with the IRB 120's specified repeatability
    assert "conflict with the specified repeatability" in verdict_text(d)
    # the final model is at or below the complete geometric calibration on withheld poses
    assert d.final.rms <= a.baseline.model_withheld.rms
