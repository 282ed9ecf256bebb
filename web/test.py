#!/usr/bin/env python3
"""The browser page's test: serves web/dist on 127.0.0.1, renders scenes in headless
Chromium (WebGPU on SwiftShader) through `index.html?scene=URL&...`, and holds each image
against the CPU renderer's under the GPU-vs-CPU limits (`gpurt diff`), with ray counts;
a bad scene must show the command line's `FILE:LINE:COL: message`. A self-test proves the
comparison fails on a perturbed image. Needs web/dist (web/build.sh), the command line
(target/debug/gpurt, or GPURT_CLI) and chromium; the SPD scenes in ../shared/scenes are
used when there (required under CI=true). Prints `N passed, M failed`; exits 1 on a failure.
"""

import base64
import functools
import gzip
import html
import http.server
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DIST = ROOT / "web" / "dist"
CLI = Path(os.environ.get("GPURT_CLI", ROOT / "target" / "debug" / "gpurt"))
SHARED = Path(os.environ.get("GPURT_SHARED_SCENES", ROOT.parent / "shared" / "scenes"))
OUT = ROOT / "target" / "web-test"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser") or "chromium"
FLAGS = ["--headless", "--no-sandbox", "--enable-unsafe-webgpu", "--use-vulkan=swiftshader",
         "--enable-features=Vulkan", "--disable-dev-shm-usage", "--virtual-time-budget=30000"]

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
BAD = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nl 1 1 1\nf 1 0 0 1 0 0 0 0\ns 0 0 oops 1\n"

# (served name, source, width, height, spp, depth)
CASES = [
    ("spheres.nff", ROOT / "scenes" / "spheres.nff", 48, 36, 2, 5),
    ("glass.nff", ROOT / "scenes" / "glass.nff", 40, 30, 1, 8),
    ("icosahedron.stl", ROOT / "scenes" / "icosahedron.stl", 32, 32, 1, 5),
    ("tetra.obj", OBJ, 33, 25, 1, 5),
    ("mirrors.nff.gz", ("gzip", ROOT / "scenes" / "mirrors.nff"), 40, 30, 1, 5),
    ("teapot-2.nff", SHARED / "spd" / "teapot-2.nff", 40, 40, 1, 5),
    ("balls-1.nff.gz", ("gzip", SHARED / "spd" / "balls-1.nff"), 32, 32, 1, 5),
    ("balls_low.nff", SHARED / "p3d" / "balls_low.nff", 32, 32, 1, 5),
]


def serve(directory):
    handler = functools.partial(QuietHandler, directory=str(directory))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map,
                      ".wasm": "application/wasm", ".js": "text/javascript"}

    def log_message(self, *args):
        pass


def dump(url, profile):
    """The page's DOM once it shows a result or an error; retried when it shows neither
    (the adapter may arrive after the dump)."""
    for _ in range(3):
        p = subprocess.run([CHROMIUM, *FLAGS, f"--user-data-dir={profile}", "--dump-dom", url],
                           capture_output=True, text=True, timeout=300)
        if 'id="gpurt-result"' in p.stdout or 'id="gpurt-error"' in p.stdout:
            return p.stdout
    raise AssertionError(f"no result or error in the page after 3 tries:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")


def result(dom):
    tag = re.search(r'<img[^>]*id="gpurt-result"[^>]*>', dom)
    if not tag:
        err = re.search(r'<pre id="gpurt-error">(.*?)</pre>', dom, re.S)
        raise AssertionError(f"the page showed an error: {err and html.unescape(err.group(1))}")
    attr = lambda name: html.unescape(re.search(fr'{name}="([^"]*)"', tag.group(0)).group(1))
    png = base64.b64decode(attr("src").split(",", 1)[1])
    return png, int(attr("data-rays")), attr("data-adapter")


def cli(*args, check=True):
    p = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True, timeout=600)
    if check and p.returncode != 0:
        raise AssertionError(f"gpurt {' '.join(map(str, args))}: exit {p.returncode}\n{p.stderr}")
    return p


def cpu_render(scene, out, w, h, spp, depth, *extra):
    p = cli(scene, "-o", out, "--backend", "cpu", "--width", w, "--height", h, "--spp", spp,
            "--depth", depth, "--stats", *extra)
    return int(re.search(r"^cpu\s+[\d.]+ s, (\d+) rays", p.stderr, re.M).group(1))


def main():
    ci = os.environ.get("CI") == "true"
    if not (DIST / "index.html").is_file():
        sys.exit(f"no page at {DIST}: run web/build.sh first")
    if not CLI.is_file():
        sys.exit(f"no command line at {CLI}: cargo build first")
    if not SHARED.is_dir() and ci:
        sys.exit(f"no shared scenes at {SHARED} (required under CI=true)")
    OUT.mkdir(parents=True, exist_ok=True)
    passed, failed, skipped = 0, 0, 0
    with tempfile.TemporaryDirectory() as tmp:
        site = Path(tmp) / "site"
        shutil.copytree(DIST, site)
        (site / "scenes").mkdir()
        local = Path(tmp) / "scenes"
        local.mkdir()
        server = serve(site)
        base = f"http://127.0.0.1:{server.server_address[1]}/index.html"
        profile = Path(tmp) / "profile"

        def check(name, fn):
            nonlocal passed, failed
            try:
                fn()
                passed += 1
                print(f"ok      {name}", flush=True)
            except Exception as e:  # noqa: BLE001 (any failure is reported and counted)
                failed += 1
                print(f"FAILED  {name}: {e}", flush=True)

        def case(name, source, w, h, spp, depth):
            served = site / "scenes" / name
            if isinstance(source, tuple):
                served.write_bytes(gzip.compress(source[1].read_bytes()))
            elif isinstance(source, Path):
                shutil.copy(source, served)
            else:
                served.write_text(source)
            # The CLI reads the same bytes under the same name.
            scene = local / name
            shutil.copy(served, scene)
            dom = dump(f"{base}?scene=scenes/{name}&width={w}&height={h}&spp={spp}&depth={depth}", profile)
            png, rays, adapter = result(dom)
            web = OUT / f"{name}.web.png"
            web.write_bytes(png)
            ref = OUT / f"{name}.cpu.png"
            cpu_rays = cpu_render(scene, ref, w, h, spp, depth)
            d = cli("diff", web, ref, check=False)
            assert d.returncode == 0, f"on {adapter}, beyond the GPU-vs-CPU limits:\n{d.stdout}{d.stderr}"
            assert abs(rays - cpu_rays) <= cpu_rays // 200, f"{rays} rays in the page, {cpu_rays} on the CPU"
            return web, scene, adapter

        first = {}
        for name, source, w, h, spp, depth in CASES:
            if isinstance(source, tuple) and not source[1].exists() or isinstance(source, Path) and not source.exists():
                skipped += 1
                print(f"skip    {name}: no {source}")
                continue

            def run(name=name, source=source, w=w, h=h, spp=spp, depth=depth):
                web, scene, adapter = case(name, source, w, h, spp, depth)
                first.setdefault("case", (web, scene, w, h, spp, depth, adapter))

            check(f"{name} {w}x{h} {spp} spp depth {depth}", run)

        def self_test():
            """A CPU render of another view or light differs beyond the limits."""
            web, scene, w, h, spp, depth, adapter = first["case"]
            print(f"        (rendered on {adapter})")
            for extra in (["--ambient", "0.35"], ["--depth", "1"]):
                other = OUT / "perturbed.png"
                cpu_render(scene, other, w, h, spp, depth, *extra)
                d = cli("diff", web, other, check=False)
                assert d.returncode == 1, f"{extra}: gpurt diff exited {d.returncode}, not 1:\n{d.stdout}"

        check("self-test: a perturbed render fails the comparison", self_test)

        def bad_scene():
            (site / "scenes" / "bad.nff").write_text(BAD)
            (local / "bad.nff").write_text(BAD)
            want = cli(local / "bad.nff", "-o", OUT / "bad.png", check=False)
            assert want.returncode == 2
            message = want.stderr.strip().removeprefix("gpurt: ").removeprefix(str(local) + "/")
            dom = dump(f"{base}?scene=scenes/bad.nff&width=8&height=8", profile)
            err = re.search(r'<pre id="gpurt-error">(.*?)</pre>', dom, re.S)
            assert err, "no error element"
            assert html.unescape(err.group(1)) == message, (html.unescape(err.group(1)), message)
            assert 'id="gpurt-result"' not in dom

        check("a bad scene shows FILE:LINE:COL: message", bad_scene)
        server.shutdown()
    print(f"{passed} passed, {failed} failed" + (f", {skipped} skipped" if skipped else ""))
    sys.exit(1 if failed or (ci and skipped) else 0)


if __name__ == "__main__":
    main()
