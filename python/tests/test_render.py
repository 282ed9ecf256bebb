"""gpurt.render and Scene.render give the command line's EXR, value for value, and trace
as many rays; the comparison itself fails on a perturbed render."""

import numpy as np
import pytest

import gpurt
from conftest import SCENES, assert_same, cli_render, generated_scene, shared_scenes

BUNDLED = ["spheres.nff", "glass.nff", "cones.nff", "mirrors.nff", "icosahedron.stl", "torus.ply", "blocks.gltf", "cornell.nff", "textured.glb"]
SPD = ["balls-1.nff", "gears-1.nff", "mount-1.nff", "teapot-2.nff", "tree-1.nff", "rings-1.nff"]


def python_render(scene, **kw):
    """The Python render and its ray count (read from a Renderer's counter)."""
    r = gpurt.Renderer(scene, **{k: kw.pop(k) for k in ("width", "height", "backend") if k in kw})
    img = r.render(**kw)
    return img, r.rays


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_scenes_equal_the_cli_exr(name, tmp_path):
    want, rays = cli_render(SCENES / name, tmp_path, "--width", 40, "--height", 30, "--backend", "cpu")
    got = gpurt.render(SCENES / name, width=40, height=30, backend="cpu")
    assert isinstance(got, gpurt.Image) and isinstance(got, np.ndarray)
    assert got.dtype == np.float32 and got.shape == (30, 40, 3)
    assert_same(got, want)
    _, got_rays = python_render(SCENES / name, width=40, height=30, backend="cpu")
    assert got_rays == rays


@pytest.mark.parametrize("name", SPD)
def test_spd_scenes_equal_the_cli_exr(name, tmp_path):
    scene = shared_scenes() / "spd" / name
    want, rays = cli_render(scene, tmp_path, "--width", 48, "--height", 36, "--backend", "cpu", "--spp", 2)
    got, got_rays = python_render(str(scene), width=48, height=36, spp=2, backend="cpu")
    assert_same(got, want)
    assert got_rays == rays


def test_a_gzip_p3d_scene_equals_the_cli_exr(tmp_path):
    scene = shared_scenes() / "spd" / "balls-5.nff.gz"
    want, _ = cli_render(scene, tmp_path, "--width", 16, "--height", 12, "--backend", "cpu")
    assert_same(gpurt.render(scene, width=16, height=12, backend="cpu"), want)
    p3d = shared_scenes() / "p3d" / "balls_low.nff"
    want, _ = cli_render(p3d, tmp_path, "--width", 16, "--height", 12, "--backend", "cpu")
    assert_same(gpurt.render(p3d, width=16, height=12, backend="cpu"), want)


@pytest.mark.parametrize(
    "seed,lights,spp,depth,ambient",
    [(1, 1, 1, 5, None), (2, 9, 7, 16, 0.3), (3, 24, 3, 12, (0.05, 0.1, 0.2)), (4, 2, 16, 1, None)],
)
def test_generated_scenes_beyond_the_defaults_equal_the_cli_exr(seed, lights, spp, depth, ambient, tmp_path):
    path = tmp_path / f"gen{seed}.nff"
    path.write_text(generated_scene(seed, lights=lights))
    args = ["--backend", "cpu", "--spp", spp, "--depth", depth]
    if ambient is not None:
        args += ["--ambient", ",".join(map(str, np.atleast_1d(ambient)))]
    want, rays = cli_render(path, tmp_path, *args)
    got, got_rays = python_render(path, backend="cpu", spp=spp, depth=depth, ambient=ambient)
    assert_same(got, want)
    assert got_rays == rays
    # From a string, the same scene renders the same image.
    scene = gpurt.Scene.from_string(path.read_text())
    assert_same(scene.render(backend="cpu", spp=spp, depth=depth, ambient=ambient), want)


@pytest.mark.parametrize("aov", ["normal", "depth", "cost"])
def test_aovs_equal_the_cli_exr(aov, tmp_path):
    want, _ = cli_render(SCENES / "mirrors.nff", tmp_path, "--width", 32, "--height", 24, "--backend", "cpu", "--aov", aov)
    got = gpurt.render(SCENES / "mirrors.nff", width=32, height=24, backend="cpu", aov=aov)
    assert got.aov == aov
    assert_same(got, want)


def test_the_uv_aov_equals_the_cli_exr(tmp_path):
    """The Cornell box's walls carry texture coordinates (`vt`), each from 0 to 1."""
    want, _ = cli_render(SCENES / "cornell.nff", tmp_path, "--width", 32, "--height", 24, "--backend", "cpu", "--aov", "uv")
    got = gpurt.render(SCENES / "cornell.nff", width=32, height=24, backend="cpu", aov="uv")
    assert got.aov == "uv"
    assert_same(got, want)
    pixels = np.asarray(got)
    assert pixels[..., :2].max() > 0.9 and pixels[..., 2].max() == 0.0


def test_the_gpu_backend_equals_the_cli_gpu_exr(tmp_path, gpu_available):
    if not gpu_available:
        pytest.skip("no GPU adapter")
    path = tmp_path / "gen.nff"
    path.write_text(generated_scene(7, lights=5))
    for scene, spp in [(SCENES / "glass.nff", 2), (path, 4)]:
        want, rays = cli_render(scene, tmp_path, "--width", 33, "--height", 21, "--backend", "gpu", "--spp", spp)
        got, got_rays = python_render(scene, width=33, height=21, spp=spp, backend="gpu")
        assert_same(got, want)
        assert got_rays == rays


def test_the_comparison_fails_on_a_perturbed_render(tmp_path):
    """Self-test: each one-step change of the render must fail `assert_same`."""
    path = tmp_path / "gen.nff"
    path.write_text(generated_scene(5, lights=4))
    want, rays = cli_render(path, tmp_path, "--backend", "cpu", "--spp", 2)
    base = dict(backend="cpu", spp=2)
    assert_same(gpurt.render(path, **base), want)
    for change in [dict(spp=3), dict(depth=4), dict(ambient=0.11)]:
        got = gpurt.render(path, **{**base, **change})
        with pytest.raises(AssertionError):
            assert_same(got, want)
    # One value changed by one ulp, and an image shifted by a pixel.
    got = np.array(gpurt.render(path, **base))
    got[3, 4, 1] = np.nextafter(got[3, 4, 1], np.float32(np.inf))
    with pytest.raises(AssertionError):
        assert_same(got, want)
    with pytest.raises(AssertionError):
        assert_same(np.roll(want, 1, axis=1), want)
    _, more_rays = python_render(path, backend="cpu", spp=3)
    assert more_rays != rays


def test_the_image_is_moved_into_numpy_not_copied():
    img = gpurt.render(SCENES / "spheres.nff", width=8, height=6, backend="cpu")
    # A view of a buffer numpy does not own: the film's own allocation, handed over.
    assert not img.flags.owndata
    owner = img.base
    while isinstance(owner, np.ndarray):
        owner = owner.base
    assert owner is not None and not isinstance(owner, np.ndarray), type(owner)
    assert img.flags.c_contiguous and img.flags.writeable


def test_a_missing_gpu_falls_back_to_the_cpu_with_one_runtime_warning(gpu_available):
    """`backend="gpu"` without an adapter (wgpu told to look only for DX12, which Linux
    and macOS lack) renders on the CPU and says so in one RuntimeWarning, as the command
    line does; with an adapter it warns of nothing. In a process of its own, so that the
    environment is the one wgpu reads."""
    import json
    import os
    import subprocess
    import sys

    code = (
        "import json, warnings, gpurt\n"
        "with warnings.catch_warnings(record=True) as caught:\n"
        "    warnings.simplefilter('always')\n"
        f"    r = gpurt.Renderer({str(SCENES / 'spheres.nff')!r}, width=8, height=8, backend='gpu')\n"
        "    r.render()\n"
        "print(json.dumps([r.backend, [(w.category.__name__, str(w.message)) for w in caught]]))\n"
    )

    def run(**env):
        p = subprocess.run([sys.executable, "-c", code], env=dict(os.environ, **env), capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)

    backend, caught = run(WGPU_BACKEND="dx12")
    assert backend == "cpu"
    assert caught == [["RuntimeWarning", "gpurt: no GPU adapter; rendering on the CPU"]]
    if gpu_available:
        assert run() == ["gpu", []]
