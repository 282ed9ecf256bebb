"""A turntable of an SPD scene rendered from Python into a contact sheet and an animated GIF.

    pip install ./python pillow
    python examples/sweep.py ../shared/scenes/spd/teapot-6.nff --frames 24 --size 256

The scene is read, packed and (on the GPU) uploaded once by `gpurt.Renderer`; each frame
only moves the camera around the scene's own `at` point, keeping its distance, height and
field of view.
"""

import argparse
import math
import time
from pathlib import Path

import numpy as np
from PIL import Image

import gpurt


def turntable(info, frames):
    """Cameras circling the scene's `at` about its `up` axis, starting at its own eye."""
    cam = info["camera"]
    eye, at, up = (np.array(cam[k], dtype=np.float64) for k in ("from", "at", "up"))
    up /= np.linalg.norm(up)
    offset = eye - at
    height = offset @ up * up
    radial = offset - height
    side = np.cross(up, radial)
    for i in range(frames):
        a = 2 * math.pi * i / frames
        e = at + height + radial * math.cos(a) + side * math.sin(a)
        yield dict(eye=e.tolist(), look_at=at.tolist(), up=up.tolist(), fov=cam["angle"])


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default=str(Path(__file__).resolve().parents[2] / "shared/scenes/spd/teapot-6.nff"))
    p.add_argument("--frames", type=int, default=24)
    p.add_argument("--size", type=int, default=192)
    p.add_argument("--spp", type=int, default=4)
    p.add_argument("--backend", default="auto")
    p.add_argument("--out", default="turntable")
    args = p.parse_args()

    scene = gpurt.Scene.open(args.scene)
    start = time.perf_counter()
    r = gpurt.Renderer(scene, width=args.size, height=args.size, spp=args.spp, backend=args.backend)
    loaded = time.perf_counter() - start
    frames = []
    start = time.perf_counter()
    for camera in turntable(scene.info(), args.frames):
        frames.append(gpurt.to_srgb8(r.render(camera=camera)))
    took = time.perf_counter() - start
    print(f"{r.device}: packed in {loaded:.2f} s, {args.frames} frames in {took:.2f} s "
          f"({took / args.frames * 1000:.0f} ms a frame), scene uploads: {r.scene_uploads}")

    columns = math.ceil(math.sqrt(args.frames))
    rows = math.ceil(args.frames / columns)
    sheet = np.zeros((rows * args.size, columns * args.size, 3), dtype=np.uint8)
    for i, f in enumerate(frames):
        y, x = divmod(i, columns)
        sheet[y * args.size:(y + 1) * args.size, x * args.size:(x + 1) * args.size] = f
    Image.fromarray(sheet).save(f"{args.out}.png")
    gif = [Image.fromarray(f) for f in frames]
    gif[0].save(f"{args.out}.gif", save_all=True, append_images=gif[1:], duration=80, loop=0)
    print(f"wrote {args.out}.png ({columns}x{rows} frames) and {args.out}.gif")


if __name__ == "__main__":
    main()
