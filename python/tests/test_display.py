"""Images show themselves in Jupyter as the command line's PNG; to_srgb8 gives its bytes."""

import io

import numpy as np
import pytest
from PIL import Image as PILImage

import gpurt
from conftest import SCENES, run_cli


def cli_png(tmp_path, *args):
    out = tmp_path / "cli.png"
    run_cli(SCENES / "glass.nff", "-o", out, "--width", 40, "--height", 30, "--backend", "cpu", *args)
    return np.asarray(PILImage.open(out).convert("RGB"))


@pytest.mark.parametrize("aov", [None, "normal", "depth", "cost"])
def test_repr_png_is_the_cli_png(aov, tmp_path):
    want = cli_png(tmp_path, *(["--aov", aov] if aov else []))
    img = gpurt.render(SCENES / "glass.nff", width=40, height=30, backend="cpu", aov=aov)
    png = img._repr_png_()
    assert png.startswith(b"\x89PNG")
    got = np.asarray(PILImage.open(io.BytesIO(png)).convert("RGB"))
    assert got.shape == want.shape and (got == want).all()


def test_to_srgb8_is_the_cli_png(tmp_path):
    want = cli_png(tmp_path)
    img = gpurt.render(SCENES / "glass.nff", width=40, height=30, backend="cpu")
    for got in (gpurt.to_srgb8(img), img.to_srgb8(), gpurt.to_srgb8(np.asarray(img, dtype=np.float64))):
        assert got.dtype == np.uint8 and got.shape == (30, 40, 3)
        assert (got == want).all()
    # It sees every level: one level brighter is another image.
    assert not (gpurt.to_srgb8(img + 1 / 255) == want).all()


def test_to_srgb8_clamps_and_rounds():
    a = np.array([[[-1.0, 0.0, 0.7 / 255]], [[1.6 / 255, 1.0, 7.0]]], dtype=np.float32)
    assert gpurt.to_srgb8(a).tolist() == [[[0, 0, 1]], [[2, 255, 255]]]
    with pytest.raises(ValueError):
        gpurt.to_srgb8(np.zeros((4, 4)))
    with pytest.raises(ValueError):
        gpurt.to_srgb8(np.zeros((4, 4, 4)))


def test_derived_arrays_keep_their_aov_and_odd_shapes_show_nothing():
    img = gpurt.render(SCENES / "spheres.nff", width=8, height=8, backend="cpu", aov="depth")
    assert (img * 2).aov == "depth" and img[:4].aov == "depth"
    assert img[:, :, 0]._repr_png_() is None


def test_save_writes_the_cli_png_and_refuses_other_formats(tmp_path):
    want = cli_png(tmp_path)
    img = gpurt.render(SCENES / "glass.nff", width=40, height=30, backend="cpu")
    img.save(tmp_path / "saved.png")
    got = np.asarray(PILImage.open(tmp_path / "saved.png").convert("RGB"))
    assert (got == want).all()
    with pytest.raises(ValueError, match="PNG"):
        img.save(tmp_path / "saved.jpg")
    assert not (tmp_path / "saved.jpg").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cli.png", "saved.png"]


def test_help_shows_each_signature_once_and_dir_the_public_names():
    for f in (gpurt.render, gpurt.info, gpurt.to_srgb8, gpurt.Renderer.render, gpurt.Scene.render):
        doc = f.__doc__ or ""
        assert "\n--\n" not in doc and not doc.startswith(f.__name__ + "("), doc[:120]
        assert f.__text_signature__, f.__name__
    names = dir(gpurt)
    assert "render" in names and "Image" in names
    assert not {"np", "Literal", "Optional", "os"} & set(names), names
