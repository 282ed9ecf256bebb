"""Shared helpers: the command line to compare against, the scenes, EXR reading.

The command line is the repository's own build (`target/debug/gpurt`, else
`target/release/gpurt`, or the path in GPURT_CLI). The SPD scenes come from
`../shared/scenes` beside the checkout (or GPURT_SHARED_SCENES); tests that need what is
missing skip, except under CI=true, where they fail.
"""

import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
CI = os.environ.get("CI") == "true"


def _missing(what: str):
    if CI:
        pytest.fail(f"{what} (required under CI=true)")
    pytest.skip(what)


def cli_path() -> Path:
    candidates = [os.environ.get("GPURT_CLI")] if os.environ.get("GPURT_CLI") else [
        str(ROOT / "target" / "debug" / "gpurt"),
        str(ROOT / "target" / "release" / "gpurt"),
    ]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    _missing(f"no gpurt command line built at {', '.join(c for c in candidates if c)}")


def shared_scenes() -> Path:
    d = Path(os.environ.get("GPURT_SHARED_SCENES", ROOT.parent / "shared" / "scenes"))
    if not d.is_dir():
        _missing(f"no shared scenes at {d}")
    return d


def run_cli(*args, check=True, env=None):
    """Runs the command line; returns the completed process (text output)."""
    full_env = dict(os.environ, **(env or {}))
    p = subprocess.run(
        [str(cli_path()), *map(str, args)],
        capture_output=True,
        text=True,
        env=full_env,
        timeout=600,
    )
    if check and p.returncode != 0:
        raise AssertionError(f"gpurt {' '.join(map(str, args))} exited {p.returncode}:\n{p.stderr}")
    return p


def read_exr(path: Path) -> np.ndarray:
    import OpenEXR

    with OpenEXR.File(str(path)) as f:
        return np.asarray(f.channels()["RGB"].pixels, dtype=np.float32)


def cli_render(scene, tmp_path: Path, *args, name="cli.exr"):
    """The command line's EXR of a render (as float32 (H, W, 3)) and its ray count."""
    out = tmp_path / name
    p = run_cli(scene, "-o", out, "--stats", *args)
    rays = [int(m) for m in re.findall(r"^(?:cpu|gpu)\s+[\d.]+ s, (\d+) rays", p.stderr, re.M)]
    assert len(rays) == 1, p.stderr
    return read_exr(out), rays[0]


def assert_same(got: np.ndarray, want: np.ndarray):
    """Bit-for-bit equality of two float images, with a useful message."""
    assert got.shape == want.shape, (got.shape, want.shape)
    assert got.dtype == np.float32
    same = (got == want) | (np.isnan(got) & np.isnan(want))
    if not same.all():
        y, x, c = np.argwhere(~same)[0]
        raise AssertionError(
            f"{(~same).sum()} of {same.size} values differ; first at row {y}, column {x}, "
            f"channel {c}: {got[y, x, c]!r} != {want[y, x, c]!r}"
        )


def generated_scene(seed: int, lights: int = 3, objects: int = 12) -> str:
    """An NFF scene from a seed: spheres, polygons and a cone of random materials (mirrors
    and glass among them, for deep rays), `lights` point lights, an odd resolution."""
    rng = np.random.default_rng(seed)
    lines = [
        "v",
        "from 0 -9 3",
        "at 0 0 0.5",
        "up 0 0 1",
        "angle 40",
        "hither 0.01",
        f"resolution {int(rng.integers(17, 61))} {int(rng.integers(13, 47))}",
        "b 0.1 0.15 0.3",
        f"am {rng.uniform(0, 0.2):.3f} {rng.uniform(0, 0.2):.3f} {rng.uniform(0, 0.2):.3f}",
    ]
    for _ in range(lights):
        x, y, z = rng.uniform(-6, 6, 3)
        lines.append(f"l {x:.3f} {y:.3f} {abs(z) + 2:.3f} {rng.uniform(0.2, 1):.3f} 0.8 0.7")

    def material():
        r, g, b = rng.uniform(0.1, 1, 3)
        kind = rng.integers(0, 3)
        ks, t, ior = [(0.2, 0, 1), (0.8, 0, 1), (0.2, 0.7, 1.5)][kind]
        return f"f {r:.3f} {g:.3f} {b:.3f} {rng.uniform(0.3, 0.9):.3f} {ks} {rng.uniform(3, 60):.1f} {t} {ior}"

    lines.append("f 0.8 0.8 0.8 0.7 0.3 10 0 1")
    lines.append("p 4 -8 -8 0 8 -8 0 8 8 0 -8 8 0")
    for _ in range(objects):
        lines.append(material())
        x, y = rng.uniform(-3, 3, 2)
        if rng.random() < 0.6:
            lines.append(f"s {x:.3f} {y:.3f} {rng.uniform(0.3, 2):.3f} {rng.uniform(0.2, 0.9):.3f}")
        else:
            z = rng.uniform(0.2, 2)
            lines.append(
                f"p 3 {x:.3f} {y:.3f} {z:.3f} {x + 1:.3f} {y:.3f} {z + 0.5:.3f} {x:.3f} {y + 1:.3f} {z + 1:.3f}"
            )
    lines.append(material())
    lines.append("c 2 2 0 0.6 2 2 1.5 0.1")
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="session")
def gpu_available():
    """Whether the GPU backend finds an adapter (lavapipe counts). Required under
    GPURT_REQUIRE_GPU=1, as for the Rust tests."""
    import warnings

    import gpurt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = gpurt.Renderer(SCENES / "spheres.nff", width=4, height=4, backend="gpu").backend
    if found != "gpu" and os.environ.get("GPURT_REQUIRE_GPU") == "1":
        pytest.fail("no GPU adapter (required under GPURT_REQUIRE_GPU=1)")
    return found == "gpu"
