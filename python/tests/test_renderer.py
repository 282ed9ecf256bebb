"""gpurt.Renderer: a camera sweep renders what the command line renders from the same
view, and uploads the scene once."""

import time

import numpy as np
import pytest

import gpurt
from conftest import SCENES, assert_same, cli_render, shared_scenes


def view_block(eye, look_at, up, fov, size):
    v = lambda p: " ".join(repr(float(c)) for c in p)
    return f"v\nfrom {v(eye)}\nat {v(look_at)}\nup {v(up)}\nangle {fov!r}\nresolution {size[0]} {size[1]}\n"


def turntable(n, radius=6.0, height=2.5):
    for i in range(n):
        a = 2 * np.pi * i / n
        yield dict(eye=(radius * np.cos(a), radius * np.sin(a), height), look_at=(0, 0, 0.5), up=(0, 0, 1), fov=45.0)


def test_a_camera_frame_equals_the_cli_render_from_that_view(tmp_path):
    scene = SCENES / "mirrors.nff"
    r = gpurt.Renderer(scene, width=37, height=23, spp=2, backend="cpu")
    for i, cam in enumerate(turntable(3)):
        view = tmp_path / f"view{i}.nff"
        view.write_text(view_block(cam["eye"], cam["look_at"], cam["up"], cam["fov"], (37, 23)))
        want, rays = cli_render(scene, tmp_path, "--view", view, "--spp", 2, "--backend", "cpu")
        got = r.render(camera=cam)
        assert_same(got, want)
        assert r.rays == rays
    # The comparison sees the camera: another frame of the sweep is another image.
    with pytest.raises(AssertionError):
        assert_same(r.render(camera=next(turntable(5))), want)


def test_a_partial_camera_keeps_the_scene_s_other_settings(tmp_path):
    scene = SCENES / "spheres.nff"
    r = gpurt.Renderer(scene, width=24, height=24, backend="cpu")
    assert_same(r.render(camera={}), r.render())
    narrower = r.render(camera=dict(fov=20))
    with pytest.raises(AssertionError):
        assert_same(narrower, r.render())


def test_frames_equal_one_off_renders_of_the_same_settings():
    r = gpurt.Renderer(SCENES / "glass.nff", width=30, height=20, backend="cpu", spp=2, depth=7)
    assert_same(r.render(), gpurt.render(SCENES / "glass.nff", width=30, height=20, backend="cpu", spp=2, depth=7))
    assert_same(r.render(spp=5, depth=2, ambient=0.4),
                gpurt.render(SCENES / "glass.nff", width=30, height=20, backend="cpu", spp=5, depth=2, ambient=0.4))
    assert_same(r.render(aov="depth"),
                gpurt.render(SCENES / "glass.nff", width=30, height=20, backend="cpu", spp=2, depth=7, aov="depth"))
    assert r.frames_rendered == 3 and r.size == (30, 20) and r.backend == "cpu"


def test_a_gpu_sweep_uploads_the_scene_once(gpu_available):
    if not gpu_available:
        pytest.skip("no GPU adapter")
    scene = gpurt.Scene.open(SCENES / "mirrors.nff")
    r = gpurt.Renderer(scene, width=32, height=24, backend="gpu")
    assert r.backend == "gpu" and r.scene_uploads == 0
    frames = [r.render(camera=c) for c in turntable(12)]
    assert r.scene_uploads == 1 and r.frames_rendered == 12
    # Another size, sample count and depth still reuse the upload.
    r.render(spp=3, depth=2)
    assert r.scene_uploads == 1
    # Each frame is the image a fresh renderer gives for its camera.
    for i in (0, 7):
        fresh = gpurt.Renderer(scene, width=32, height=24, backend="gpu")
        assert_same(fresh.render(camera=list(turntable(12))[i]), frames[i])
    assert not all((frames[0] == f).all() for f in frames[1:])


def test_a_sweep_costs_frames_not_loads(tmp_path):
    """A renderer reads its scene once: its frames render with the file gone. And a small
    frame of a large scene costs far less than a load of it, where a renderer that read
    the scene again or rebuilt its tree for each frame would pay most of a load a frame.
    The median of 20 frames is held to half a load: on a machine other work shares, some
    frames wait tens of milliseconds for the CPU's threads, which a sum would count."""
    scene = tmp_path / "balls-5.nff.gz"
    scene.write_bytes((shared_scenes() / "spd" / "balls-5.nff.gz").read_bytes())
    start = time.perf_counter()
    r = gpurt.Renderer(scene, width=8, height=8, backend="cpu")
    load = time.perf_counter() - start
    scene.unlink()
    frames = []
    for cam in turntable(20, radius=4, height=2):
        start = time.perf_counter()
        r.render(camera=dict(cam, look_at=(0, 0, 0)))
        frames.append(time.perf_counter() - start)
    assert r.frames_rendered == 20
    median = sorted(frames)[len(frames) // 2]
    assert median < load / 2, f"a frame took {median:.3f} s (median of 20), a load {load:.3f} s"
