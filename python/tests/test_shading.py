"""`shading=` picks the library's highlight model as `--shading` does: the arrays equal the
command line's EXR under each model, the models differ where a highlight is seen, and
any other name is a ValueError naming the models."""

import pytest

import gpurt
from conftest import SCENES, assert_same, cli_render, generated_scene

MODELS = ["phong", "blinn-phong"]


@pytest.mark.parametrize("model", MODELS)
def test_each_model_equals_the_cli_exr(model, tmp_path):
    path = tmp_path / "gen.nff"
    path.write_text(generated_scene(11, lights=6))
    for scene, spp, depth in [(SCENES / "spheres.nff", 1, 5), (path, 3, 9)]:
        args = ["--width", 37, "--height", 23, "--backend", "cpu", "--spp", spp, "--depth", depth]
        want, rays = cli_render(scene, tmp_path, *args, "--shading", model)
        got = gpurt.render(scene, width=37, height=23, spp=spp, depth=depth, backend="cpu", shading=model)
        assert_same(got, want)
        r = gpurt.Renderer(scene, width=37, height=23, spp=spp, depth=depth, backend="cpu", shading=model)
        assert_same(r.render(), want)
        assert r.rays == rays
        assert_same(gpurt.Scene.open(scene).render(width=37, height=23, spp=spp, depth=depth,
                                                   backend="cpu", shading=model), want)


def test_the_models_differ_and_phong_is_the_default(tmp_path):
    """Self-test of the wiring: Blinn-Phong's image is not Phong's, so an argument that
    was dropped on the way would fail the comparisons above."""
    kw = dict(width=40, height=30, backend="cpu")
    phong = gpurt.render(SCENES / "spheres.nff", shading="phong", **kw)
    blinn = gpurt.render(SCENES / "spheres.nff", shading="blinn-phong", **kw)
    assert (gpurt.render(SCENES / "spheres.nff", **kw) == phong).all()
    assert not (phong == blinn).all()
    want, _ = cli_render(SCENES / "spheres.nff", tmp_path, "--width", 40, "--height", 30,
                         "--backend", "cpu", "--shading", "blinn-phong")
    with pytest.raises(AssertionError):
        assert_same(phong, want)


def test_a_frame_s_shading_overrides_the_renderer_s(tmp_path):
    r = gpurt.Renderer(SCENES / "spheres.nff", width=24, height=18, backend="cpu", shading="blinn-phong")
    blinn, _ = cli_render(SCENES / "spheres.nff", tmp_path, "--width", 24, "--height", 18,
                          "--backend", "cpu", "--shading", "blinn-phong")
    phong, _ = cli_render(SCENES / "spheres.nff", tmp_path, "--width", 24, "--height", 18, "--backend", "cpu")
    assert_same(r.render(), blinn)
    assert_same(r.render(shading="phong"), phong)
    assert_same(r.render(), blinn)


def test_blinn_phong_on_the_gpu_equals_the_cli_gpu_exr(tmp_path, gpu_available):
    if not gpu_available:
        pytest.skip("no GPU adapter")
    path = tmp_path / "gen.nff"
    path.write_text(generated_scene(12, lights=4))
    want, rays = cli_render(path, tmp_path, "--width", 29, "--height", 19, "--backend", "gpu",
                            "--spp", 2, "--shading", "blinn-phong")
    r = gpurt.Renderer(path, width=29, height=19, spp=2, backend="gpu")
    r.render()
    # A change of model is a change of the frame: the scene stays uploaded.
    assert_same(r.render(shading="blinn-phong"), want)
    assert r.rays == rays and r.scene_uploads == 1


@pytest.mark.parametrize("name", ["blinn", "Blinn-Phong", "blinn_phong", "", "toon", "phong "])
def test_another_name_is_a_value_error_naming_the_models(name):
    with pytest.raises(ValueError, match="'phong', 'blinn-phong'") as e:
        gpurt.render(SCENES / "spheres.nff", width=8, height=8, backend="cpu", shading=name)
    assert not isinstance(e.value, gpurt.SceneError)
    with pytest.raises(ValueError, match="'phong', 'blinn-phong'"):
        gpurt.Renderer(SCENES / "spheres.nff", width=8, height=8, backend="cpu", shading=name)
    r = gpurt.Renderer(SCENES / "spheres.nff", width=8, height=8, backend="cpu")
    with pytest.raises(ValueError, match="'phong', 'blinn-phong'"):
        r.render(shading=name)


def test_a_non_string_model_is_a_type_error():
    with pytest.raises(TypeError):
        gpurt.render(SCENES / "spheres.nff", width=8, height=8, backend="cpu", shading=1)
