#!/usr/bin/env python3
"""The browser page's test: serves web/dist on 127.0.0.1, renders scenes in headless
Chromium (WebGPU on SwiftShader, driven over the DevTools protocol) through
`index.html?scene=URL&...`, reads each image back from the page's <img id="gpurt-result">
(a canvas screenshot of WebGPU comes out blank), and holds it against the CPU renderer's
under the GPU-vs-CPU limits (`gpurt diff`), with ray counts; the camera's moves and the
`v` block it prints are checked against `gpurt --view`; the interactive page is driven
with the browser's own input events (file input, a drag and a wheel notch on the canvas,
the Camera and Download buttons, a dropped file, an animation's slider and space to play
and pause) and its canvas held against the CPU's image; a bad scene must show the command
line's `FILE:LINE:COL: message`, and bad numbers, a missing scene and a browser without
WebGPU their own messages. A self-test proves the
comparison fails on a perturbed image, on Phong's image for Blinn-Phong's, and on an
animation's first frame for its twentieth. Needs web/dist (web/build.sh), the command line
(target/debug/gpurt, or GPURT_CLI) and chromium; the SPD scenes in ../shared/scenes are
used when there (required under CI=true). Prints `N passed, M failed`; exits 1 on a failure.
"""

import base64
import fcntl
import functools
import gzip
import html
import http.server
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DIST = ROOT / "web" / "dist"
CLI = Path(os.environ.get("GPURT_CLI", ROOT / "target" / "debug" / "gpurt"))
SHARED = Path(os.environ.get("GPURT_SHARED_SCENES", ROOT.parent / "shared" / "scenes"))
OUT = ROOT / "target" / "web-test"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser") or "chromium"
FLAGS = ["--headless", "--no-sandbox", "--enable-unsafe-webgpu", "--use-vulkan=swiftshader",
         "--enable-features=Vulkan", "--disable-dev-shm-usage"]
# How long a page may take to show its result or error: SwiftShader compiles the shader and
# traces on the CPU, on a machine other builds may share.
PAGE_TIMEOUT = 600

OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
BAD = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nl 1 1 1\nf 1 0 0 1 0 0 0 0\ns 0 0 oops 1\n"



def generated(seed, lights):
    """An NFF scene from a seed: spheres and triangles of random materials (mirrors and
    glass among them, for deep rays) over a floor, under `lights` point lights."""
    rng = random.Random(seed)
    u = rng.uniform
    lines = ["v", "from 0 -9 3", "at 0 0 0.5", "up 0 0 1", "angle 40", "hither 0.01",
             "resolution 32 24", "b 0.1 0.15 0.3", f"am {u(0, 0.2):.3f} {u(0, 0.2):.3f} {u(0, 0.2):.3f}"]
    for _ in range(lights):
        lines.append(f"l {u(-6, 6):.3f} {u(-6, 6):.3f} {u(2, 8):.3f} {u(0.2, 1):.3f} 0.8 0.7")
    lines += ["f 0.8 0.8 0.8 0.7 0.3 10 0 1", "p 4 -8 -8 0 8 -8 0 8 8 0 -8 8 0"]
    for _ in range(10):
        ks, t, ior = rng.choice([(0.2, 0, 1), (0.8, 0, 1), (0.2, 0.7, 1.5)])
        lines.append(f"f {u(0.1, 1):.3f} {u(0.1, 1):.3f} {u(0.1, 1):.3f} {u(0.3, 0.9):.3f} {ks} {u(3, 60):.1f} {t} {ior}")
        x, y, z = u(-3, 3), u(-3, 3), u(0.2, 2)
        if rng.random() < 0.6:
            lines.append(f"s {x:.3f} {y:.3f} {z:.3f} {u(0.2, 0.9):.3f}")
        else:
            lines.append(f"p 3 {x:.3f} {y:.3f} {z:.3f} {x + 1:.3f} {y:.3f} {z + 0.5:.3f} {x:.3f} {y + 1:.3f} {z + 1:.3f}")
    return "\n".join(lines) + "\n"


# (served name, source, width, height, spp, depth[, extra URL parameters])
CASES = [
    ("spheres.nff", ROOT / "scenes" / "spheres.nff", 48, 36, 2, 5),
    ("glass.nff", ROOT / "scenes" / "glass.nff", 40, 30, 1, 8),
    ("icosahedron.stl", ROOT / "scenes" / "icosahedron.stl", 32, 32, 1, 5),
    ("torus.ply", ROOT / "scenes" / "torus.ply", 36, 28, 1, 5),
    ("blocks.gltf", ROOT / "scenes" / "blocks.gltf", 40, 30, 1, 6),
    ("textured.glb", ROOT / "scenes" / "textured.glb", 48, 32, 2, 5),
    ("tetra.obj", OBJ, 33, 25, 1, 5),
    ("mirrors.nff.gz", ("gzip", ROOT / "scenes" / "mirrors.nff"), 40, 30, 1, 5),
    ("teapot-2.nff", SHARED / "spd" / "teapot-2.nff", 40, 40, 1, 5),
    ("balls-1.nff.gz", ("gzip", SHARED / "spd" / "balls-1.nff"), 32, 32, 1, 5),
    ("balls_low.nff", SHARED / "p3d" / "balls_low.nff", 32, 32, 1, 5),
    # Beyond the defaults: many lights, several samples, deep rays, odd sizes, Blinn-Phong.
    ("gen-1.nff", generated(1, 9), 37, 23, 3, 12),
    ("gen-2.nff", generated(2, 16), 29, 31, 2, 16, {"shading": "blinn-phong"}),
    ("spheres-blinn.nff", ROOT / "scenes" / "spheres.nff", 40, 30, 1, 5, {"shading": "blinn-phong"}),
    # An animation's frame: its moving parts placed, its camera moved.
    ("orbit.aff", ROOT / "scenes" / "orbit.aff", 40, 30, 2, 5, {"frame": "20"}),
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


class Browser:
    """Headless Chromium driven over the DevTools protocol on a pipe (`--remote-debugging-pipe`:
    NUL-terminated JSON on its fds 3 and 4, no websocket needed). `--dump-dom` with a virtual
    time budget cannot wait for a render: virtual time runs ahead while the page only waits
    on the GPU, and the DOM is dumped before the first frame is read back."""

    def __init__(self, profile):
        commands, self._to_browser = os.pipe()
        self._from_browser, replies = os.pipe()
        # Out of the way of 3 and 4 in the child, which take them below.
        keep = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (commands, replies)]

        def fds():
            os.dup2(keep[0], 3)
            os.dup2(keep[1], 4)

        self.proc = subprocess.Popen(
            [CHROMIUM, *FLAGS, f"--user-data-dir={profile}", "--remote-debugging-pipe", "about:blank"],
            preexec_fn=fds, close_fds=False, stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for fd in (commands, replies, *keep):
            os.close(fd)
        self._next, self._buffer = 0, b""

    def send(self, method, session=None, **params):
        self._next += 1
        message = {"id": self._next, "method": method, "params": params}
        if session:
            message["sessionId"] = session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self._buffer:
                chunk = os.read(self._from_browser, 1 << 16)
                if not chunk:
                    raise AssertionError("chromium closed its DevTools pipe")
                self._buffer += chunk
            line, self._buffer = self._buffer.split(b"\0", 1)
            reply = json.loads(line)
            if reply.get("id") == self._next:
                if "error" in reply:
                    raise AssertionError(f"{method}: {reply['error']}")
                return reply["result"]

    def page(self, url, screenshot=None, before=None):
        """The page's DOM once it shows a result or an error; with `screenshot`, a PNG of
        the page (800 px wide) is written there then; `before` is a script run in the page
        before its own."""
        target = self.send("Target.createTarget", url="about:blank" if before else url)["targetId"]
        session = self.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        if before:
            self.send("Page.enable", session)
            self.send("Page.addScriptToEvaluateOnNewDocument", session, source=before)
            self.send("Page.navigate", session, url=url)
        if screenshot:
            self.send("Emulation.setDeviceMetricsOverride", session, width=800, height=600,
                      deviceScaleFactor=1, mobile=False)
        shown = ("document.getElementById('gpurt-result') || document.getElementById('gpurt-error')"
                 " ? document.documentElement.outerHTML : ''")
        try:
            deadline = time.monotonic() + PAGE_TIMEOUT
            while time.monotonic() < deadline:
                dom = self.send("Runtime.evaluate", session, expression=shown, returnByValue=True)
                dom = dom["result"].get("value", "")
                if dom:
                    if screenshot:
                        shot = self.send("Page.captureScreenshot", session, format="png")
                        Path(screenshot).write_bytes(base64.b64decode(shot["data"]))
                    return dom
                time.sleep(0.25)
            status = self.send("Runtime.evaluate", session, returnByValue=True,
                               expression="document.getElementById('status').textContent")
            raise AssertionError(f"no result or error in the page after {PAGE_TIMEOUT} s: "
                                 f"status {status['result'].get('value')!r}")
        finally:
            self.send("Target.closeTarget", targetId=target)

    def close(self):
        self.proc.kill()
        self.proc.wait()
        os.close(self._to_browser)
        os.close(self._from_browser)


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


def url_args(params):
    return "".join(f"&{k}={v}" for k, v in params.items())


def frame_time(scene, frame):
    """The time of frame `frame` of the AFF `scene` (its `a start end frames`), computed as
    the renderer does, and written so that it reads back as the same double: the page's
    frame is the command line's `--time` (which prints the ray count a sequence does not)."""
    start, end, frames = next(line.split()[1:4] for line in Path(scene).read_text().splitlines()
                              if line.startswith("a "))
    start, end, frames = float(start), float(end), int(frames)
    return repr(start + (end - start) * frame / (frames - 1)) if frames > 1 else repr(start)


def cpu_args(params, view=None, scene=None):
    """The command line's flags for the page's URL parameters (the camera moves aside)."""
    args = ["--shading", params["shading"]] if "shading" in params else []
    args += ["--time", frame_time(scene, int(params["frame"]))] if "frame" in params else []
    return args + (["--view", view] if view else [])


def cpu_render(scene, out, w, h, spp, depth, *extra):
    p = cli(scene, "-o", out, "--backend", "cpu", "--width", w, "--height", h, "--spp", spp,
            "--depth", depth, "--stats", *extra)
    return int(re.search(r"^cpu\s+[\d.]+ s, (\d+) rays", p.stderr, re.M).group(1))


def screenshot(out, scene, query):
    """`web/test.py --screenshot OUT.png SCENE QUERY`: the page rendering SCENE with the
    URL parameters QUERY, captured once it shows its result (the README's picture)."""
    with tempfile.TemporaryDirectory() as tmp:
        site = Path(tmp) / "site"
        shutil.copytree(DIST, site)
        shutil.copy(scene, site / Path(scene).name)
        server = serve(site)
        browser = Browser(Path(tmp) / "profile")
        try:
            url = f"http://127.0.0.1:{server.server_address[1]}/index.html?scene={Path(scene).name}&{query}"
            result(browser.page(url, screenshot=out))
        finally:
            browser.close()
            server.shutdown()


def main():
    if sys.argv[1:2] == ["--screenshot"]:
        return screenshot(*sys.argv[2:5])
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
        browser = Browser(Path(tmp) / "profile")
        dump = browser.page

        def check(name, fn):
            nonlocal passed, failed
            try:
                fn()
                passed += 1
                print(f"ok      {name}", flush=True)
            except Exception as e:  # noqa: BLE001 (any failure is reported and counted)
                failed += 1
                print(f"FAILED  {name}: {e}", flush=True)

        def serve_scene(name, source):
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
            return scene

        def case(name, source, w, h, spp, depth, params):
            scene = serve_scene(name, source)
            size = f"width={w}&height={h}&spp={spp}&depth={depth}"
            dom = dump(f"{base}?scene=scenes/{name}&{size}{url_args(params)}")
            png, rays, adapter = result(dom)
            web = OUT / f"{name}.web.png"
            web.write_bytes(png)
            view = None
            if any(k in params for k in ("orbit", "pan", "dolly")):
                block = re.search(r'<pre id="gpurt-view">(.*?)</pre>', dom, re.S)
                assert block, "no camera block in the page"
                view = OUT / f"{name}.view.nff"
                view.write_text(html.unescape(block.group(1)))
            ref = OUT / f"{name}.cpu.png"
            cpu_rays = cpu_render(scene, ref, w, h, spp, depth, *cpu_args(params, view, scene))
            d = cli("diff", web, ref, check=False)
            assert d.returncode == 0, f"on {adapter}, beyond the GPU-vs-CPU limits:\n{d.stdout}{d.stderr}"
            assert abs(rays - cpu_rays) <= cpu_rays // 200, f"{rays} rays in the page, {cpu_rays} on the CPU"
            return web, scene, adapter, rays

        first, rendered = {}, {}
        for name, source, w, h, spp, depth, *more in CASES:
            params = more[0] if more else {}
            if isinstance(source, tuple) and not source[1].exists() or isinstance(source, Path) and not source.exists():
                skipped += 1
                print(f"skip    {name}: no {source}")
                continue

            def run(name=name, source=source, w=w, h=h, spp=spp, depth=depth, params=params):
                web, scene, adapter, rays = case(name, source, w, h, spp, depth, params)
                first.setdefault("case", (web, scene, w, h, spp, depth, adapter, rays))
                rendered[name] = (web, scene, w, h, spp, depth)

            check(f"{name} {w}x{h} {spp} spp depth {depth}{url_args(params)}", run)

        def camera():
            """The orbit, pan and dolly of `gpurt view` move the page's camera; the `v` block
            it prints renders, on the CPU, the page's image; and the image did move."""
            moves = {"orbit": "37,-21", "pan": "6,4", "dolly": "2"}
            moved, _, _, _ = case("moved.nff", ROOT / "scenes" / "mirrors.nff", 40, 30, 1, 5, moves)
            still = OUT / "still.cpu.png"
            cpu_render(local / "moved.nff", still, 40, 30, 1, 5)
            d = cli("diff", moved, still, check=False)
            assert d.returncode == 1, f"the moved camera's image is the scene camera's:\n{d.stdout}"

        check("the camera's orbit, pan and dolly, and its v block", camera)

        def interactive():
            """The page as a user drives it, through the browser's own input events: a
            scene opened with the file input renders sample by sample into the canvas (held
            against the CPU's image); a drag on the canvas orbits the camera, and the
            Camera button prints the `v` block the CPU renders the same image from; a wheel
            notch dollies; Download saves the image shown; a file dropped on the page
            replaces the scene; an animated scene's slider shows the frame it is moved to,
            and space plays the frames and pauses them."""
            w, h, spp, depth = 40, 30, 2, 5
            opened = serve_scene("opened.nff", ROOT / "scenes" / "mirrors.nff")
            dropped = serve_scene("dropped.nff", ROOT / "scenes" / "spheres.nff")
            animated = serve_scene("animated.aff", ROOT / "scenes" / "orbit.aff")
            target = browser.send("Target.createTarget", url=base)["targetId"]
            s = browser.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]

            def js(expression):
                r = browser.send("Runtime.evaluate", s, expression=expression, returnByValue=True)
                return r["result"].get("value")

            def wait(predicate, what):
                deadline = time.monotonic() + PAGE_TIMEOUT
                while time.monotonic() < deadline:
                    err = js("document.getElementById('gpurt-error')?.textContent")
                    assert not err, f"the page showed an error {what}: {err}"
                    if js(predicate):
                        return
                    time.sleep(0.25)
                status = js("document.getElementById('status').textContent")
                raise AssertionError(f"timed out {what}: status {status!r}")

            # The run loop writes the status after each sample: overwritten before an input
            # (with a line of text, so that nothing on the page moves), "N / N samples"
            # then means the image of that input is complete.
            complete = f"/^{spp} \\/ {spp} samples/.test(document.getElementById('status').textContent)"
            forget = "document.getElementById('status').textContent = 'input sent'"

            def centre(selector):
                return js(f"(() => {{ const r = document.querySelector('{selector}')"
                          ".getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; })()")

            def mouse(kind, x, y, **more):
                browser.send("Input.dispatchMouseEvent", s, type=kind, x=x, y=y, **more)

            def click(selector):
                x, y = centre(selector)
                mouse("mousePressed", x, y, button="left", buttons=1, clickCount=1)
                mouse("mouseReleased", x, y, button="left", clickCount=1)

            def canvas(name):
                url = js("document.getElementById('canvas').toDataURL('image/png')")
                out = OUT / name
                out.write_bytes(base64.b64decode(url.split(",", 1)[1]))
                return out

            def matches_cpu(image, scene, name, *extra):
                ref = OUT / name
                cpu_render(scene, ref, w, h, spp, depth, *extra)
                d = cli("diff", image, ref, check=False)
                assert d.returncode == 0, f"{image.name} beyond the GPU-vs-CPU limits:\n{d.stdout}{d.stderr}"

            def camera_block(name):
                click("#camera")
                view = OUT / name
                view.write_text(js("document.getElementById('view').textContent"))
                return view

            try:
                wait("document.getElementById('status').textContent.startsWith('ready on')", "starting")
                js(f"[['width', {w}], ['height', {h}], ['spp', {spp}], ['depth', {depth}]]"
                   ".forEach(([id, v]) => { document.getElementById(id).value = v; })")
                doc = browser.send("DOM.getDocument", s)["root"]["nodeId"]
                node = browser.send("DOM.querySelector", s, nodeId=doc, selector="#file")["nodeId"]
                browser.send("DOM.setFileInputFiles", s, files=[str(opened)], nodeId=node)
                wait(complete, "rendering the opened file")
                first = canvas("opened.canvas.png")
                matches_cpu(first, opened, "opened.cpu.png")

                def moved(name, before, what):
                    """The image after `what` moved the camera: changed, and the CPU's
                    render from the `v` block the Camera button prints."""
                    wait(complete, f"rendering after {what}")
                    after = canvas(f"{name}.canvas.png")
                    d = cli("diff", after, before, check=False)
                    assert d.returncode == 1, f"{what} left the image as it was:\n{d.stdout}"
                    view = camera_block(f"{name}.view.nff")
                    matches_cpu(after, opened, f"{name}.cpu.png", "--view", view)
                    return after

                x, y = centre("#canvas")
                js(forget)
                mouse("mousePressed", x, y, button="left", buttons=1, clickCount=1)
                mouse("mouseMoved", x + 12, y + 5, button="left", buttons=1)
                mouse("mouseReleased", x + 12, y + 5, button="left", clickCount=1)
                orbited = moved("orbited", first, "a drag")

                js(forget)
                mouse("mouseWheel", x, y, deltaX=0, deltaY=-120)
                dollied = moved("dollied", orbited, "a wheel notch")

                downloads = Path(tmp) / "downloads"
                downloads.mkdir()
                browser.send("Browser.setDownloadBehavior", behavior="allow",
                             downloadPath=str(downloads))
                click("#download")
                saved = downloads / "gpurt.png"
                deadline = time.monotonic() + 30
                while not saved.is_file() and time.monotonic() < deadline:
                    time.sleep(0.1)
                assert saved.is_file(), "Download saved no gpurt.png"
                d = cli("diff", saved, dollied, "--max-bad", "0", check=False)
                assert d.returncode == 0, f"the downloaded PNG is not the image shown:\n{d.stdout}"

                js(forget)
                x, y = centre("#drop")
                data = {"items": [], "files": [str(dropped)], "dragOperationsMask": 1}
                for kind in ("dragEnter", "dragOver", "drop"):
                    browser.send("Input.dispatchDragEvent", s, type=kind, x=x, y=y, data=data)
                wait(complete, "rendering the dropped file")
                matches_cpu(canvas("dropped.canvas.png"), dropped, "dropped.cpu.png")
                assert js("document.getElementById('animation').hidden"), "frame controls for a still scene"

                js(forget)
                browser.send("DOM.setFileInputFiles", s, files=[str(animated)], nodeId=node)
                wait(complete, "rendering the animated file")
                assert not js("document.getElementById('animation').hidden"), "no frame controls"
                js(forget)
                js("(() => { const f = document.getElementById('frame'); f.value = '12';"
                   " f.dispatchEvent(new Event('input')); })()")
                wait(complete, "rendering frame 12")
                matches_cpu(canvas("frame12.canvas.png"), animated, "frame12.cpu.png",
                            "--time", frame_time(animated, 12))

                def key(text):
                    for kind in ("keyDown", "keyUp"):
                        browser.send("Input.dispatchKeyEvent", s, type=kind, key=text,
                                     code="Space", text=text, windowsVirtualKeyCode=32)

                number = "document.getElementById('frame-number').textContent"
                # Space on a focused button presses it: the page plays on space elsewhere.
                js("document.activeElement && document.activeElement.blur()")
                key(" ")
                wait(f"!{number}.startsWith('12 /') && !{number}.startsWith('13 /')", "playing")
                key(" ")
                try:
                    wait("document.getElementById('play').textContent.startsWith('Play')", "pausing")
                except AssertionError as e:
                    play = js("document.getElementById('play').textContent")
                    focus = js("document.activeElement.tagName")
                    raise AssertionError(f"{e}; play {play!r}, focus {focus!r}, frame {js(number)!r}") from e
                paused = js(number)
                wait(complete, "finishing the paused frame")
                assert js(number) == paused, f"paused at {paused}, then {js(number)}"
            finally:
                browser.send("Target.closeTarget", targetId=target)

        check("the interactive page: open, drag, wheel, camera block, download, drop", interactive)

        def self_test():
            """A CPU render with another light or depth differs beyond the limits, and the
            ray count of another depth beyond the count's tolerance."""
            web, scene, w, h, spp, depth, adapter, rays = first["case"]
            print(f"        (rendered on {adapter})")
            other = OUT / "perturbed.png"
            for extra, d in ((["--ambient", "0.35"], depth), ([], 1)):
                other_rays = cpu_render(scene, other, w, h, spp, d, *extra)
                diff = cli("diff", web, other, check=False)
                assert diff.returncode == 1, f"{extra} depth {d}: gpurt diff exited {diff.returncode}, not 1:\n{diff.stdout}"
            assert abs(rays - other_rays) > other_rays // 200, (rays, other_rays)
            # A page that ignored shading=blinn-phong would show Phong's image: it fails too.
            web, scene, w, h, spp, depth = rendered["spheres-blinn.nff"]
            cpu_render(scene, other, w, h, spp, depth, "--shading", "phong")
            diff = cli("diff", web, other, check=False)
            assert diff.returncode == 1, f"Phong passes for Blinn-Phong: gpurt diff exited {diff.returncode}:\n{diff.stdout}"
            # A page that ignored frame=20 would show the first frame: it fails too.
            web, scene, w, h, spp, depth = rendered["orbit.aff"]
            cpu_render(scene, other, w, h, spp, depth, "--time", frame_time(scene, 0))
            diff = cli("diff", web, other, check=False)
            assert diff.returncode == 1, f"frame 0 passes for frame 20: gpurt diff exited {diff.returncode}:\n{diff.stdout}"

        check("self-test: a perturbed render fails the comparison", self_test)

        def bad_scene():
            (site / "scenes" / "bad.nff").write_text(BAD)
            (local / "bad.nff").write_text(BAD)
            want = cli(local / "bad.nff", "-o", OUT / "bad.png", check=False)
            assert want.returncode == 2
            # The first line; the command line draws the source line and a caret under it.
            first = want.stderr.strip().splitlines()[0]
            message = first.removeprefix("gpurt: ").removeprefix(str(local) + "/")
            dom = dump(f"{base}?scene=scenes/bad.nff&width=8&height=8")
            err = re.search(r'<pre id="gpurt-error">(.*?)</pre>', dom, re.S)
            assert err, "no error element"
            assert html.unescape(err.group(1)) == message, (html.unescape(err.group(1)), message)
            assert 'id="gpurt-result"' not in dom

        check("a bad scene shows FILE:LINE:COL: message", bad_scene)

        def bad_shading():
            dom = dump(f"{base}?scene=scenes/spheres.nff&width=8&height=8&shading=toon")
            err = re.search(r'<pre id="gpurt-error">(.*?)</pre>', dom, re.S)
            assert err, "no error element"
            assert html.unescape(err.group(1)) == 'shading must be one of phong, blinn-phong, got "toon"'
            assert 'id="gpurt-result"' not in dom

        check("an unknown shading model is an error naming the models", bad_shading)

        def shows(query, message, before=None):
            """The page given `query` shows `message` and no image."""
            dom = dump(f"{base}?{query}", before=before)
            err = re.search(r'<pre id="gpurt-error">(.*?)</pre>', dom, re.S)
            assert err, f"{query}: no error element"
            got = html.unescape(err.group(1))
            assert got.startswith(message), f"{query}: {got!r}, not {message!r}"
            assert 'id="gpurt-result"' not in dom

        def bad_numbers():
            scene = "scene=scenes/spheres.nff"
            shows(f"{scene}&width=abc&height=8", 'width must be a whole number, got "abc"')
            shows(f"{scene}&width=8&height=8&spp=-2", 'spp must be a whole number, got "-2"')
            shows(f"{scene}&width=8&height=8&depth=99", "depth must be 1 to 16, got 99")

        check("bad numbers in the URL are errors naming the parameter", bad_numbers)

        def bad_frames():
            serve_scene("orbit.aff", ROOT / "scenes" / "orbit.aff")
            shows("scene=scenes/orbit.aff&width=8&height=8&frame=48",
                  "frame 48 is outside the animation, whose 48 frames are 0..47")
            shows("scene=scenes/spheres.nff&width=8&height=8&frame=1",
                  "nothing moves in this scene: it has no frames")

        check("a frame outside the animation, or of a still scene, is an error", bad_frames)
        check("a scene the server does not have shows its HTTP status",
              lambda: shows("scene=scenes/missing.nff", "scenes/missing.nff: HTTP 404"))
        def gltf_needs_its_buffer():
            """A .gltf whose buffer is a file of its own names the file it needs."""
            doc = json.loads((ROOT / "scenes" / "blocks.gltf").read_text())
            doc["buffers"][0]["uri"] = "blocks.bin"
            serve_scene("split.gltf", json.dumps(doc))
            shows("scene=scenes/split.gltf", "split.gltf: buffer 0: cannot read 'blocks.bin'")

        check("a .gltf with its buffer in another file says which file it needs", gltf_needs_its_buffer)
        # A browser without WebGPU has no navigator.gpu.
        no_gpu = "Object.defineProperty(Navigator.prototype, 'gpu', { get() { return undefined; } });"
        check("a browser without WebGPU shows that it has none",
              lambda: shows("scene=scenes/spheres.nff", "no WebGPU: ", before=no_gpu))
        browser.close()
        server.shutdown()
    print(f"{passed} passed, {failed} failed" + (f", {skipped} skipped" if skipped else ""))
    sys.exit(1 if failed or (ci and skipped) else 0)


if __name__ == "__main__":
    main()
