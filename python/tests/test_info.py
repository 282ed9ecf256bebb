"""Scene.info(), gpurt.info() and `gpurt info --json` are one dict."""

import json

import pytest

import gpurt
from conftest import SCENES, generated_scene, run_cli, shared_scenes


def cli_info(path):
    return json.loads(run_cli("info", path, "--json").stdout)


@pytest.mark.parametrize(
    "name", ["spheres.nff", "arealight.nff", "lens.nff", "patches.nff", "icosahedron.stl", "blocks.gltf", "cornell.nff", "textured.glb"]
)
def test_info_equals_the_cli_json_on_bundled_scenes(name):
    want = cli_info(SCENES / name)
    assert gpurt.info(SCENES / name) == want
    assert gpurt.Scene.open(str(SCENES / name)).info() == want


def test_emitters_are_lights():
    """The Cornell box's ceiling (`Ke` in its .mtl) is its one light; blocks.gltf's glowing
    panel (an emissive material) is a light beside the file's two."""
    (light,) = gpurt.info(SCENES / "cornell.nff")["lights"]
    assert (light["kind"], light["color"], light["triangles"]) == ("emitter", [17.0, 12.0, 4.0], 2)
    kinds = [l["kind"] for l in gpurt.info(SCENES / "blocks.gltf")["lights"]]
    assert kinds == ["point", "directional", "emitter"]


@pytest.mark.parametrize("name", ["spd/teapot-2.nff", "spd/mount-1.nff", "spd/balls-5.nff.gz", "p3d/mount_low.nff"])
def test_info_equals_the_cli_json_on_shared_scenes(name):
    path = shared_scenes() / name
    assert gpurt.info(path) == cli_info(path)


def test_info_of_a_string_equals_the_file_s_but_for_its_name(tmp_path):
    path = tmp_path / "gen.nff"
    path.write_text(generated_scene(11, lights=6))
    want = cli_info(path)
    got = gpurt.Scene.from_string(path.read_text(), name="generated").info()
    assert got["file"] == "generated"
    assert {**got, "file": want["file"]} == want
    # And the comparison notices a change: another seed is another dict.
    other = gpurt.Scene.from_string(generated_scene(12, lights=6), name=want["file"]).info()
    assert other != want


def test_mesh_strings_are_read_by_their_format(tmp_path):
    stl = (SCENES / "icosahedron.stl").read_bytes()
    obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
    (tmp_path / "t.obj").write_text(obj)
    assert gpurt.Scene.from_string(obj, format="obj", name=str(tmp_path / "t.obj")).info() == cli_info(tmp_path / "t.obj")
    scene = gpurt.Scene.from_string(stl, format="stl", name="ico")
    assert scene.info()["triangles"] == cli_info(SCENES / "icosahedron.stl")["triangles"] > 0
    assert "ico" in repr(scene)
    ply = (SCENES / "torus.ply").read_text()
    got = gpurt.Scene.from_string(ply, format="ply", name=str(SCENES / "torus.ply")).info()
    assert got == cli_info(SCENES / "torus.ply")
    assert got["triangles"] == 2 * 32 * 14


def test_warnings_are_kept():
    text = "v from 0 -5 0 at 0 0 0 up 0 0 1 angle 40\ns 0 0 0 1\np 3 0 0 0 1 0 0 2 0 0\n"
    scene = gpurt.Scene.from_string(text, name="w.nff")
    assert scene.warnings and scene.warnings == scene.info()["warnings"]
    assert scene.warnings[0].startswith("w.nff:3:")
