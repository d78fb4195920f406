"""Rendering speed at 640x480: our frames with overlays vs mujoco.Renderer's defaults.

Measured in one run on the same model (the Table 1 PUMA built by ``mjcf.build``):

* baseline: ``mujoco.Renderer`` with its default settings (shadows, reflections, 4x
  multisampling), update_scene + render per frame;
* ours, bare: ``sim.OffscreenRenderer`` (fast settings), update_scene + render + read;
* ours, full frame: the video frame pipeline (perturbed arm + nominal ghost, desired and actual
  traces, deviation arrow, three text blocks, live delta_p plot, read-back);
* end to end: a 10 s, 30 fps mp4 of the PUMA circle (models, playback, rendering, libx264
  encoding).

Targets (issue 4): full frames >= 30 fps on the 2-core CPU; the 10 s video in <= 20 s.

Run: ``python3 tests/benchmarks/bench_render.py [--frames 150] [--backend egl|osmesa] [--quick]
[--out FILE.md] [--force]`` (writes the table to renders/benchmarks/bench_render.md and .json;
--quick: 30 frames and no video).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
import time
from pathlib import Path

from _report import Report, add_output_arguments, output_path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--backend", default=None, help="egl or osmesa (default: MUJOCO_GL, else "
                    "the first that works)")
    ap.add_argument("--skip-video", action="store_true")
    ap.add_argument("--quick", action="store_true", help="30 frames, no video")
    add_output_arguments(ap, "bench_render")
    args = ap.parse_args()
    out = output_path(args)
    if args.quick:
        args.frames, args.skip_video = min(args.frames, 30), True

    # mujoco.Renderer reads MUJOCO_GL when mujoco is first imported: choose before importing.
    import sim.view.gl

    backend = sim.view.gl.configure_backend(args.backend)
    import mujoco
    import numpy as np

    import mjcf
    import sim
    import zrp
    from zrp.manufacturing.perturb import Perturbation
    from zrp.paper.scenario import puma_circle_ik

    w, h, n = 640, 480, args.frames
    nominal = zrp.load_model("puma")
    perturbed = Perturbation.single("JE2", 0.1).apply(nominal)
    ik = puma_circle_ik(steps=360)
    arm = mjcf.build(nominal, mjcf.MJCFOptions(offscreen_size=(w, h)))
    data = mujoco.MjData(arm.model)
    qs = ik.q[np.linspace(0, len(ik.q) - 1, n).astype(int)]

    def pose(i: int) -> None:
        data.qpos[arm.qpos_adr] = qs[i]
        mujoco.mj_kinematics(arm.model, data)

    print(f"backend {backend}, {w}x{h}, {n} frames, {os.cpu_count()} CPUs")

    with mujoco.Renderer(arm.model, h, w) as r:
        pose(0)
        r.update_scene(data)
        r.render()  # warm-up
        t0 = time.perf_counter()
        for i in range(n):
            pose(i)
            r.update_scene(data)
            r.render()
        base = n / (time.perf_counter() - t0)
    print(f"mujoco.Renderer (defaults)          {base:7.1f} fps   1.00x")
    rows = [("mujoco.Renderer (defaults: shadows, reflections, 4x MSAA)", f"{base:.1f} fps",
             "1.00x", "")]

    with sim.OffscreenRenderer(arm.model, w, h, backend=backend) as r:
        r.update_scene(data)
        r.render()
        t0 = time.perf_counter()
        for i in range(n):
            pose(i)
            r.update_scene(data)
            r.render()
            r.read()
        bare = n / (time.perf_counter() - t0)
    print(f"ours, bare (fast settings, read)    {bare:7.1f} fps   {bare / base:.2f}x")
    rows.append(("ours, bare (fast settings, read back)", f"{bare:.1f} fps",
                 f"{bare / base:.2f}x", ""))

    opts = sim.VideoOptions(width=w, height=h, fps=30, seconds=n / 30, backend=backend)
    gen = sim.comparison_frames(nominal, perturbed, ik.t, ik.q, label="JE2 +0.1 %",
                                options=opts)
    with contextlib.closing(gen):
        next(gen)  # setup (models, playback, GL context) excluded from the frame rate
        t0 = time.perf_counter()
        count = sum(1 for _ in gen)
        full = count / (time.perf_counter() - t0)
    verdict = "meets" if full >= 30 else "MISSES"
    print(f"ours, full frame with overlays      {full:7.1f} fps   {full / base:.2f}x   "
          f"({verdict} the 30 fps target)")
    rows.append(("ours, full video frame with overlays", f"{full:.1f} fps",
                 f"{full / base:.2f}x", f">= 30 fps: {verdict}"))

    if not args.skip_video:
        with tempfile.TemporaryDirectory() as tmp:
            res = sim.render_comparison_video(
                nominal, perturbed, ik.t, ik.q, Path(tmp) / "bench.mp4", label="JE2 +0.1 %",
                options=sim.VideoOptions(width=w, height=h, fps=30, seconds=10.0,
                                         backend=backend), progress=False)
            size = res.path.stat().st_size / 1e6
        verdict = "meets" if res.wall_seconds <= 20 else "MISSES"
        print(f"10 s 30 fps video end to end        {res.wall_seconds:7.2f} s     "
              f"{res.frames} frames, {size:.2f} MB ({verdict} the 20 s target; "
              f"{res.wall_seconds / 20:.2f} of the budget)")
        rows.append(("10 s, 30 fps mp4 end to end (models, playback, rendering, libx264)",
                     f"{res.wall_seconds:.2f} s", f"{res.frames} frames, {size:.2f} MB",
                     f"<= 20 s: {verdict}"))
    report = Report("bench_render", "offscreen rendering and video")
    report.table(f"The Table 1 PUMA at {w}x{h}, {n} frames, backend {backend}",
                 ["what", "measured", "vs mujoco.Renderer", "target"], rows)
    report.write(out, args)


if __name__ == "__main__":
    main()
