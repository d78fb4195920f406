"""Offscreen rendering (EGL/OSMesa), GL resource release, and video output."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

import mjcf
import sim
import sim.view.frames
import sim.view.gl
import zrp
from tests.arms import perturbed_puma
from zrp.errors import InputError, OutputExistsError


@pytest.fixture(scope="module")
def puma_arm() -> mjcf.BuiltArm:
    return mjcf.build(zrp.load_model("puma"), mjcf.MJCFOptions(offscreen_size=(640, 480)))


@pytest.fixture(scope="module")
def circle():
    from zrp.paper.scenario import puma_circle_ik

    ik = puma_circle_ik(steps=60)
    return ik.t, ik.q


def _pose(arm: mjcf.BuiltArm, q) -> mujoco.MjData:
    d = mujoco.MjData(arm.model)
    d.qpos[arm.qpos_adr] = arm.qpos(q)
    mujoco.mj_kinematics(arm.model, d)
    return d


# ---- backend choice (no GL needed) ----------------------------------------------------------
def test_unknown_backend_is_a_clear_error(monkeypatch):
    with pytest.raises(sim.GLBackendError, match=r"vulkan.*expected one of \('egl', 'osmesa'\)"):
        sim.resolve_backend("vulkan")
    monkeypatch.setenv("MUJOCO_GL", "bogus")
    with pytest.raises(sim.GLBackendError, match="MUJOCO_GL"):
        sim.resolve_backend()
    with pytest.raises(InputError, match="backend"):
        sim.VideoOptions(backend="directx")


def test_no_working_backend_names_the_packages(monkeypatch):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(sim.view.gl, "probe_backend", lambda name, timeout=60.0: (False, "no lib"))
    sim.view.gl.available_backend.cache_clear()
    try:
        with pytest.raises(sim.GLUnavailableError, match="libegl1 libgl1") as info:
            sim.resolve_backend()
        assert "libosmesa6" in str(info.value)
    finally:
        sim.view.gl.available_backend.cache_clear()


def test_size_beyond_offscreen_buffer_is_rejected(puma_arm):
    with pytest.raises(InputError, match="offscreen_size"):
        sim.OffscreenRenderer(puma_arm.model, 4000, 3000)
    with pytest.raises(InputError, match="width, height"):
        sim.OffscreenRenderer(puma_arm.model, 0, 10)


# ---- rendering ------------------------------------------------------------------------------
def test_pixels_change_when_the_pose_changes(backend, puma_arm):
    with sim.OffscreenRenderer(puma_arm.model, 320, 240, backend=backend) as r:
        r.look_at([0.3, 0.1, -0.3], 2.5)
        a = r.render_image(_pose(puma_arm, np.zeros(6)))
        b = r.render_image(_pose(puma_arm, [0.9, -0.6, 0.8, 0.3, 1.0, 0.2]))
        a2 = r.render_image(_pose(puma_arm, np.zeros(6)))
    assert a.shape == (240, 320, 3) and a.dtype == np.uint8
    assert a.std() > 5  # a real picture, not a blank buffer
    changed = np.any(a != b, axis=-1).mean()
    assert changed > 0.01, f"only {changed:.2%} of the pixels changed"
    np.testing.assert_array_equal(a, a2)  # deterministic: same pose, same image


def test_overlays_and_ghost_draw(backend, puma_arm):
    ghost = mjcf.build(perturbed_puma(), mjcf.MJCFOptions(alpha=0.3, floor=False,
                                                           prefix="ghost_"))
    q = np.array([0.4, -0.3, 0.5, 0.0, 0.7, 0.0])
    with sim.OffscreenRenderer(puma_arm.model, 320, 240, backend=backend) as r:
        r.look_at([0.3, 0.1, -0.3], 2.5)
        plain = r.render_image(_pose(puma_arm, q))
        r.update_scene(_pose(puma_arm, q), [(ghost.model, _pose(ghost, q + 0.3))])
        n_arm = r.scene.ngeom
        pts = np.stack([0.4 + 0.1 * np.cos(np.linspace(0, 6.3, 50)), np.full(50, 0.3),
                        -0.4 + 0.1 * np.sin(np.linspace(0, 6.3, 50))], axis=1)
        assert r.add_polyline(pts, (1, 0, 0, 1)) == 49
        assert r.add_arrow(pts[0], pts[0] + [0, 0, 0.2], (1, 1, 0, 1))
        assert r.scene.ngeom == n_arm + 50
        r.render()
        r.text("overlay")
        decorated = r.read()
    assert np.any(decorated != plain, axis=-1).mean() > 0.005


def test_gl_resources_are_released(backend, puma_arm):
    for _ in range(4):  # repeated create/free must not leak or crash
        with sim.OffscreenRenderer(puma_arm.model, 64, 48, backend=backend) as r:
            r.render_image(_pose(puma_arm, np.zeros(6)))
        assert r.closed
    with pytest.raises(InputError, match="after close"):
        r.render()
    r.close()  # idempotent


# ---- video ----------------------------------------------------------------------------------
def _tiny(fmt: str = "auto", **kw) -> sim.VideoOptions:
    return sim.VideoOptions(width=320, height=240, fps=10, seconds=0.5, format=fmt, **kw)


def test_video_written_with_stated_magnification(backend, circle, tmp_path):
    t, q = circle
    out = tmp_path / "cmp.mp4"
    res = sim.render_comparison_video(zrp.load_model("puma"), perturbed_puma(), t, q, out,
                                      label="test", options=_tiny(backend=backend),
                                      progress=False)
    assert res.path.exists() and res.path.stat().st_size > 1000
    assert res.frames == 5
    assert res.magnify == sim.nice_factor(res.magnify)  # a round 1/2/5 x 10^k factor
    assert res.max_delta_p[0] > 0.1  # mm: the perturbation is visible in the numbers
    import imageio.v3 as iio

    frames = iio.imread(res.path, index=None)
    assert frames.shape[0] == 5 and frames.shape[1:3] == (240, 320)
    assert np.any(frames[0] != frames[-1])  # the arm moved
    with pytest.raises(OutputExistsError, match="overwrite"):
        sim.render_comparison_video(zrp.load_model("puma"), perturbed_puma(), t, q, out,
                                    options=_tiny(backend=backend), progress=False)


def test_gif_fallback_format(backend, circle, tmp_path):
    t, q = circle
    res = sim.render_comparison_video(zrp.load_model("puma"), perturbed_puma(), t, q,
                                      tmp_path / "cmp.gif",
                                      options=_tiny("gif", backend=backend, magnify=50.0),
                                      progress=False)
    assert res.path.read_bytes()[:4] == b"GIF8"
    assert res.magnify == 50.0


def test_video_bad_inputs(circle, tmp_path):
    t, q = circle
    nominal = zrp.load_model("puma")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(sim.VideoWriteError, match="cannot write"):
        sim.render_comparison_video(nominal, perturbed_puma(), t, q, blocker / "v.mp4",
                                    options=_tiny(), progress=False)
    with pytest.raises(InputError, match=r"format.*expected one of"):
        sim.VideoOptions(format="avi")
    with pytest.raises(InputError, match="magnify"):
        sim.VideoOptions(magnify=-2)
    with pytest.raises(InputError, match="same joints"):
        sim.render_comparison_video(nominal, zrp.load_model("scara"), t, q,
                                    tmp_path / "x.mp4", options=_tiny(), progress=False)
    bad = np.array(q)
    bad[3, 1] = np.nan
    with pytest.raises(InputError, match="joint 2"):
        sim.render_comparison_video(nominal, perturbed_puma(), t, bad, tmp_path / "y.mp4",
                                    options=_tiny(), progress=False)


def test_nice_factor():
    assert sim.nice_factor(37.0) == 20.0
    assert sim.nice_factor(0.7) == 0.5
    assert sim.nice_factor(100.0) == 100.0
    assert sim.nice_factor(0.0) == 1.0


def test_comparison_frames_generator_releases_context(backend, circle):
    import contextlib

    t, q = circle
    gen = sim.comparison_frames(zrp.load_model("puma"), perturbed_puma(), t, q,
                                options=_tiny(backend=backend))
    with contextlib.closing(gen):
        first = next(gen)
        second = next(gen)
    assert first.shape == (240, 320, 3)
    assert np.any(first != second)
    frames = list(sim.comparison_frames(zrp.load_model("puma"), perturbed_puma(), t, q,
                                        options=_tiny(backend=backend)))
    assert len(frames) == 5


def test_lazy_import_and_configure_backend(monkeypatch):
    import subprocess
    import sys

    code = ("import sys, sim.view.gl; assert 'mujoco' not in sys.modules; "
            "print(sim.view.gl.configure_backend('osmesa'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**__import__("os").environ, "MUJOCO_GL": ""})
    assert out.stdout.strip() == "osmesa"


def test_failed_render_leaves_no_partial_file(backend, circle, tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        yield np.zeros((240, 320, 3), np.uint8)
        raise RuntimeError("renderer exploded")

    monkeypatch.setattr(sim.view.frames, "_segment_frames", broken)
    t, q = circle
    out = tmp_path / "v.mp4"
    with pytest.raises(RuntimeError, match="exploded"):
        sim.render_comparison_video(zrp.load_model("puma"), perturbed_puma(), t, q, out,
                                    options=_tiny(backend=backend), progress=False)
    assert list(tmp_path.iterdir()) == []


def test_exaggerated_model_scales_the_errors():
    nominal = zrp.load_model("puma")
    perturbed = perturbed_puma()
    big = sim.view.frames.exaggerated_model(nominal, perturbed, 10.0)
    np.testing.assert_allclose(big.bodies - nominal.bodies,
                               10.0 * (perturbed.bodies - nominal.bodies), atol=1e-9)
    q = np.array([0.3, -0.5, 0.4, 0.2, 0.9, -0.3])
    p0 = zrp.forward_kinematics(nominal, q).position
    p1 = zrp.forward_kinematics(perturbed, q).position
    p10 = zrp.forward_kinematics(big, q).position
    # first order: the tool point moves ~10 times as far (errors here are ~1e-3)
    assert np.linalg.norm(p10 - p0) == pytest.approx(10 * np.linalg.norm(p1 - p0), rel=0.05)
    same = sim.view.frames.exaggerated_model(nominal, perturbed, 1.0)
    np.testing.assert_allclose(same.axes, perturbed.axes, atol=1e-15)


def test_two_renderers_in_one_process(backend, puma_arm):
    q = [0.9, -0.6, 0.8, 0.3, 1.0, 0.2]
    with sim.OffscreenRenderer(puma_arm.model, 160, 120, backend=backend) as a, \
            sim.OffscreenRenderer(puma_arm.model, 160, 120, backend=backend) as b:
        for r in (a, b):
            r.look_at([0.3, 0.1, -0.3], 2.5)
        img_a = a.render_image(_pose(puma_arm, np.zeros(6)))
        img_b = b.render_image(_pose(puma_arm, q))
        img_a2 = a.render_image(_pose(puma_arm, np.zeros(6)))
    np.testing.assert_array_equal(img_a, img_a2)
    assert np.any(img_a != img_b)
