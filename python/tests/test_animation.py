"""A scene that moves (BART's AFF) renders a frame at a time from Python: the frame the
command line's `--frames` writes for that time, value for value."""

import numpy as np
import pytest

import gpurt
from conftest import SCENES, assert_same, cli_render

ORBIT = SCENES / "orbit.aff"


def test_frames_render_at_their_times_as_the_command_line_renders_them(tmp_path):
    scene = gpurt.Scene.open(ORBIT)
    assert scene.time_range == (0.0, 2.0, 48)
    t = scene.frame_time(12)
    assert t == pytest.approx(24 / 47)
    got = gpurt.render(ORBIT, width=40, height=30, backend="cpu", time=t)
    want, _ = cli_render(ORBIT, tmp_path, "--width", 40, "--height", 30, "--backend", "cpu", "--time", repr(t))
    assert_same(got, want)
    # Another time is another picture, and Scene.render and Scene.at agree with it.
    later = scene.render(width=40, height=30, backend="cpu", time=scene.frame_time(30))
    assert not np.array_equal(later, got)
    still = scene.at(t)
    assert still.time_range is None
    assert_same(gpurt.Renderer(still, width=40, height=30, backend="cpu").render(), got)


def test_times_are_refused_where_nothing_moves_or_out_of_range():
    with pytest.raises(ValueError, match="nothing moves"):
        gpurt.render(SCENES / "spheres.nff", width=8, height=8, backend="cpu", time=0.5)
    with pytest.raises(ValueError, match="finite"):
        gpurt.Scene.open(ORBIT).render(width=8, height=8, backend="cpu", time=float("nan"))
    with pytest.raises(ValueError, match="outside the animation"):
        gpurt.Scene.open(ORBIT).frame_time(48)
