"""The type stubs match the compiled module (mypy's stubtest), and a typical script
type-checks against them."""

import subprocess
import sys

import os

import pytest


def need_mypy() -> None:
    """mypy checks the stubs; outside CI a missing mypy skips, under CI=true it fails."""
    try:
        import mypy  # noqa: F401
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("mypy is missing (required under CI=true; .ci/run installs it)")
        pytest.skip("mypy is not installed")


def test_stubs_match_the_module():
    need_mypy()
    p = subprocess.run([sys.executable, "-m", "mypy.stubtest", "gpurt"], capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr


def test_a_script_type_checks_and_a_wrong_one_does_not(tmp_path):
    need_mypy()
    good = tmp_path / "good.py"
    good.write_text(
        "import gpurt\n"
        "img: gpurt.Image = gpurt.render('s.nff', width=8, spp=2, backend='cpu', aov='depth')\n"
        "r = gpurt.Renderer(gpurt.Scene.from_string('', format='obj'), width=8, height=8)\n"
        "frame = r.render(camera={'eye': (0, 0, 1), 'fov': 30.0})\n"
        "b: bytes | None = frame._repr_png_()\n"
        "n: int | None = r.scene_uploads\n"
    )
    bad = tmp_path / "bad.py"
    bad.write_text("import gpurt\ngpurt.render('s.nff', backend='cuda', widht=3)\n")
    check = lambda f: subprocess.run([sys.executable, "-m", "mypy", "--strict", str(f)], capture_output=True, text=True)
    p = check(good)
    assert p.returncode == 0, p.stdout
    p = check(bad)
    assert p.returncode == 1 and "backend" in p.stdout and "widht" in p.stdout, p.stdout
