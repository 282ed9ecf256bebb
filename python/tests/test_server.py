"""Python on a server: nothing on stderr from a GPU render on a headless machine; one device
a process for `gpurt.render`, replaced when it fails and dropped by `gpurt.release()`; a
`Renderer` shared by a pool of threads, each frame equal to a lone render."""

import os
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import gpurt
from conftest import ROOT, SCENES

SCENE = SCENES / "glass.nff"


def python(code: str, env: dict) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_a_gpu_render_on_a_headless_machine_prints_nothing(gpu_available):
    """Mesa's device-select layer, left on, prints "error: XDG_RUNTIME_DIR is invalid or
    not set" twice for every device opened without a display; the module turns it off."""
    if not gpu_available:
        pytest.skip("no GPU adapter")
    env = {k: v for k, v in os.environ.items() if k not in ("XDG_RUNTIME_DIR", "NODEVICE_SELECT", "WAYLAND_DISPLAY")}
    code = f"""
        import gpurt
        for _ in range(3):
            gpurt.render({str(SCENE)!r}, width=16, height=12, backend="gpu")
        r = gpurt.Renderer({str(SCENE)!r}, width=16, height=12, backend="gpu")
        r.render()
        assert r.backend == "gpu", r.backend
        print("rendered")
    """
    run = python(code, env)
    assert run.returncode == 0, run.stderr
    assert run.stdout == "rendered\n"
    assert run.stderr == ""


def test_gpurt_render_keeps_one_device_and_replaces_a_lost_one(gpu_available):
    """Calls on the GPU share one device; one lost mid-render (GPURT_FAULT=lose-device)
    raises, and the next call opens a new device, whose image equals the first's; and
    `release()` drops it. The loss on software adapters only, as the command line's test
    of it (tests/gpurt/cli/errors.rs says why)."""
    if not gpu_available:
        pytest.skip("no GPU adapter")
    device = gpurt.Renderer(SCENE, width=4, height=4, backend="gpu").device
    if "Cpu)" not in device and os.environ.get("GPURT_TEST_LOSS_ON_HARDWARE") != "1":
        pytest.skip(f"{device}: a lost device is tested on software adapters only")
    # Several bands: a software adapter's take 2^18 samples, a GPU's are capped at 4 MiB.
    env = {k: v for k, v in os.environ.items() if k != "GPURT_FAULT"}
    env["GPURT_BAND_BYTES"] = "4194304"
    code = f"""
        import os
        import numpy as np
        import gpurt
        scene = {str(SCENE)!r}
        first = gpurt.render(scene, width=24, height=18, backend="gpu")
        for _ in range(4):
            again = gpurt.render(scene, width=24, height=18, backend="gpu")
            assert np.array_equal(again, first)
        assert gpurt._native._devices_opened() == 1, gpurt._native._devices_opened()
        # A lost device: the session opened with the fault loses its device mid-render.
        gpurt.release()
        os.environ["GPURT_FAULT"] = "lose-device"
        try:
            gpurt.render(scene, width=512, height=1024, backend="gpu")
            raise SystemExit("a lost device did not raise")
        except RuntimeError as e:
            assert "lost" in str(e) or "GPU" in str(e), e
        del os.environ["GPURT_FAULT"]
        replaced = gpurt.render(scene, width=24, height=18, backend="gpu")
        assert np.array_equal(replaced, first)
        assert gpurt._native._devices_opened() == 3, gpurt._native._devices_opened()
        print("ok")
    """
    run = python(code, env)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout == "ok\n"


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_a_renderer_shared_by_a_thread_pool_renders_each_frame_as_a_lone_one(backend, gpu_available):
    """Eight frames of four cameras asked of one Renderer from a pool of four threads: the
    calls wait their turn, and each frame equals the same camera's frame rendered alone."""
    if backend == "gpu" and not gpu_available:
        pytest.skip("no GPU adapter")
    cameras = [dict(eye=(x, 1.0, 6.0), look_at=(0, 0, 0)) for x in (-3.0, -1.0, 1.0, 3.0)]
    alone = [gpurt.Renderer(SCENE, width=40, height=30, backend=backend).render(camera=c, spp=2) for c in cameras]
    r = gpurt.Renderer(SCENE, width=40, height=30, backend=backend)
    with ThreadPoolExecutor(max_workers=4) as pool:
        frames = list(pool.map(lambda k: r.render(camera=cameras[k % 4], spp=2), range(8)))
    for k, frame in enumerate(frames):
        assert np.array_equal(frame, alone[k % 4]), f"frame {k} differs from its lone render"
    assert r.frames_rendered == 8
    # The comparison can fail: two different cameras' frames differ.
    assert not np.array_equal(alone[0], alone[1])
