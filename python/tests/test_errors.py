"""Errors are Python exceptions: SceneError (a ValueError) with the command line's
`FILE:LINE:COL: message`, ValueError or TypeError for bad arguments, never a crash."""

import subprocess
import sys

import pytest

import gpurt
from conftest import SCENES, run_cli

BAD = {
    "bad.nff": "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\ns 0 0 zero 1\n",
    "view.nff": "v\nfrom 0 0 0\nat 0 0 0\nup 0 1 0\nangle 40\n",
    "bad.obj": "v 0 0 0\nv 1 0\n",
    "bad.stl": "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nope\n",
    "bad.ply": "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_bad_scene_raises_scene_error_with_the_cli_message(name, tmp_path):
    path = tmp_path / name
    path.write_text(BAD[name])
    cli = run_cli(path, "-o", tmp_path / "out.png", check=False)
    assert cli.returncode == 2
    # The first line; the command line draws the source line and a caret under it.
    message = cli.stderr.strip().splitlines()[0].removeprefix("gpurt: ")
    assert message.startswith(str(path) + ":")
    for call in [lambda: gpurt.render(path), lambda: gpurt.Scene.open(path), lambda: gpurt.info(path),
                 lambda: gpurt.Renderer(path)]:
        with pytest.raises(gpurt.SceneError) as e:
            call()
        assert str(e.value) == message
        assert isinstance(e.value, ValueError)
    kind = name.split(".")[1]
    with pytest.raises(gpurt.SceneError) as e:
        gpurt.Scene.from_string(BAD[name], format=kind, name=str(path))
    assert str(e.value) == message


def test_a_scene_error_holds_its_path_line_column_and_reason(tmp_path):
    path = tmp_path / "bad.nff"
    path.write_text(BAD["bad.nff"])
    with pytest.raises(gpurt.SceneError) as e:
        gpurt.Scene.open(path)
    assert (e.value.path, e.value.line, e.value.column, e.value.offset) == (str(path), 6, 7, None)
    assert str(e.value) == f"{path}:6:7: {e.value.reason}"
    # A binary STL's fault is at a byte, not a line.
    stl = tmp_path / "cut.stl"
    stl.write_bytes(b"x" * 80 + (2).to_bytes(4, "little") + bytes(60))
    with pytest.raises(gpurt.SceneError) as e:
        gpurt.Scene.open(stl)
    assert (e.value.path, e.value.line, e.value.column) == (str(stl), None, None)
    assert isinstance(e.value.offset, int) and f"at byte {e.value.offset}:" in str(e.value)


def test_a_missing_file_is_file_not_found():
    with pytest.raises(FileNotFoundError, match="no-such.nff"):
        gpurt.render("no-such.nff")
    with pytest.raises(gpurt.SceneError, match="directory"):
        gpurt.Scene.open(SCENES)


@pytest.mark.parametrize(
    "kwargs,error",
    [
        (dict(width=0), ValueError),
        (dict(width=-3), ValueError),
        (dict(height=10**12), ValueError),
        (dict(spp=0), ValueError),
        (dict(spp=4097), ValueError),
        (dict(depth=17), ValueError),
        (dict(width=2.5), TypeError),
        (dict(spp="4"), TypeError),
        (dict(ambient=-0.1), ValueError),
        (dict(ambient=(1, 2)), ValueError),
        (dict(ambient="0.1"), TypeError),
        (dict(ambient=float("nan")), ValueError),
        (dict(backend="both"), ValueError),
        (dict(backend="cuda"), ValueError),
        (dict(aov="wireframe"), ValueError),
        (dict(shading="toon"), ValueError),
        (dict(colour=1), TypeError),
    ],
)
def test_bad_arguments_raise_value_or_type_errors(kwargs, error):
    with pytest.raises(error):
        gpurt.render(SCENES / "spheres.nff", **kwargs)


def test_phong_shading_is_accepted_and_is_the_default():
    a = gpurt.render(SCENES / "spheres.nff", width=8, height=8, backend="cpu", shading="phong")
    b = gpurt.render(SCENES / "spheres.nff", width=8, height=8, backend="cpu")
    assert (a == b).all()


@pytest.mark.parametrize(
    "camera,error",
    [
        (dict(eye=(0, 0, 0), look_at=(0, 0, 0)), ValueError),
        (dict(up=(0, 0, 0)), ValueError),
        (dict(fov=0), ValueError),
        (dict(fov=180), ValueError),
        (dict(eye=(1, 2)), TypeError),
        (dict(eye=(1, 2, float("inf"))), ValueError),
        (dict(target=(0, 0, 0)), ValueError),
        ([1, 2, 3], TypeError),
    ],
)
def test_bad_cameras_raise(camera, error):
    r = gpurt.Renderer(SCENES / "spheres.nff", width=8, height=8, backend="cpu")
    with pytest.raises(error):
        r.render(camera=camera)
    # The renderer still works after a refused frame.
    assert r.render().shape == (8, 8, 3)


def test_scene_format_and_type_errors():
    with pytest.raises(ValueError, match="format"):
        gpurt.Scene.from_string("s 0 0 0 1", format="fbx")
    with pytest.raises(TypeError):
        gpurt.Scene.from_string(42)
    with pytest.raises(TypeError):
        gpurt.render(42)


def test_hostile_input_never_takes_the_interpreter_down(tmp_path):
    """A subprocess feeds the readers garbage; it must end with exceptions, exit 0."""
    code = r"""
import random, gpurt
random.seed(3)
for i in range(300):
    text = bytes(random.randrange(256) for _ in range(random.randrange(1, 200)))
    fmt = ["nff", "stl", "obj", "ply"][i % 4]
    if fmt == "ply":
        text = b"ply\nformat ascii 1.0\n" + text
    try:
        s = gpurt.Scene.from_string(text, format=fmt)
        s.render(width=4, height=4, backend="cpu")
    except (ValueError, TypeError):
        pass
print("survived")
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0 and "survived" in p.stdout, p.stderr
