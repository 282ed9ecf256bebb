"""The GIL is released while rendering, and Ctrl-C stops a render with KeyboardInterrupt."""

import signal
import subprocess
import sys
import threading
import time

import pytest

import gpurt
from conftest import ROOT, SCENES

# How much of its free rate the other thread must keep while a call runs: free (while the
# main thread sleeps), it counts millions a second; beside a render on every core, a third
# of that or more; behind a call that keeps the GIL, a few tenths of a percent (the
# self-test below). Measured in the same run, as machines differ tenfold.
SHARE = 0.1


def count_during(render):
    """How far another Python thread counts while `render()` runs, and how long it ran."""
    counter = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counter[0] += 1

    t = threading.Thread(target=count)
    t.start()
    time.sleep(0.05)
    before, start = counter[0], time.perf_counter()
    render()
    after, took = counter[0], time.perf_counter() - start
    stop.set()
    t.join()
    return after - before, took


def free_rate():
    """Counts a second of the other thread while this one sleeps."""
    counted, took = count_during(lambda: time.sleep(0.3))
    return counted / took


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_another_thread_runs_during_a_render(backend, gpu_available):
    if backend == "gpu" and not gpu_available:
        pytest.skip("no GPU adapter")
    r = gpurt.Renderer(SCENES / "glass.nff", width=160, height=120, backend=backend)
    r.render(spp=1)  # compiles and uploads
    # Samples enough for a render long enough to tell, on a machine of any speed.
    spp = 24 if backend == "cpu" else 6
    while True:
        counted, took = count_during(lambda: r.render(spp=spp))
        if took > 0.3 or spp >= 4096:
            break
        spp *= 4
    assert took > 0.2, f"the render took only {took:.3f} s at {spp} spp; too short to tell"
    free = free_rate()
    what = f"{counted} counts in {took:.2f} s, {free:.0f} a second free"
    assert counted > SHARE * free * took, what


def test_a_call_holding_the_gil_fails_the_same_measure():
    """Self-test: a C call that keeps the GIL throughout (the builtin `sum` over a range
    runs in C without a bytecode boundary) leaves the other thread nearly still. Long
    enough (seconds) that the other thread's counting at the call's edges, while the GIL
    changes hands on a loaded machine, does not decide it."""
    counted, took = count_during(lambda: sum(range(200_000_000)))
    assert took > 0.2
    free = free_rate()
    what = f"{counted} counts in {took:.2f} s, {free:.0f} a second free"
    assert counted < SHARE * free * took, what


# Python's own Ctrl-C handler is installed first: a process started in the background of a
# non-interactive shell (a CI step run with `&`) inherits SIGINT ignored, and Python then
# leaves it ignored.
CTRL_C = r"""
import signal, sys, time, gpurt
signal.signal(signal.SIGINT, signal.default_int_handler)
r = gpurt.Renderer(sys.argv[1], width=640, height=480, backend=sys.argv[2])
r.render(spp=1)
print("rendering", flush=True)
start = time.perf_counter()
try:
    r.render(spp=4096)
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted after {time.perf_counter() - start:.2f} s", flush=True)
    img = r.render(spp=1)
    print("renders again", img.shape, flush=True)
"""


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_ctrl_c_stops_a_long_render_with_keyboard_interrupt(backend, gpu_available):
    if backend == "gpu" and not gpu_available:
        pytest.skip("no GPU adapter")
    p = subprocess.Popen(
        [sys.executable, "-c", CTRL_C, str(SCENES / "glass.nff"), backend],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
    )
    assert p.stdout.readline().strip() == "rendering"
    time.sleep(1.0)
    sent = time.perf_counter()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    stopped = time.perf_counter() - sent
    assert p.returncode == 0, err
    assert "interrupted after" in out, out + err
    assert "renders again (480, 640, 3)" in out
    # 4096 samples of 640x480 would take minutes; the interrupt ends it in seconds.
    assert stopped < 30, f"took {stopped:.1f} s to stop"
