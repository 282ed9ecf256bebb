// The page: a scene from a file (dropped or opened) or from ?scene=URL, traced
// progressively on the page's WebGPU device by the library (gpurt_web.wasm), drawn into a
// 2D canvas from the library's 8-bit image; an animated scene (AFF) plays or steps through
// its frames. With ?scene=URL it renders once (&frame=N: that frame) and puts the result
// in <img id="gpurt-result"> (or the error in <pre id="gpurt-error">) and the camera as
// an NFF `v` block in <pre id="gpurt-view">, for tests.
import init, { Session } from "./gpurt_web.js";

const $ = (id) => document.getElementById(id);
const status = (text) => { $("status").textContent = text; };

function showError(message) {
  let pre = $("gpurt-error");
  if (!pre) {
    pre = document.createElement("pre");
    pre.id = "gpurt-error";
    $("out").appendChild(pre);
  }
  // An Error's message alone: String(e) would prefix "Error: ".
  pre.textContent = message instanceof Error ? message.message : String(message);
  status("error");
}

function clearError() {
  const pre = $("gpurt-error");
  if (pre) pre.remove();
}

function base64(bytes) {
  let s = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(s);
}

let session = null;
let generation = 0; // bumps whenever the image starts again; a stale loop stops
let running = false;
// Calls on the session asked for by the page's controls. The session is busy while a
// sample is traced (a call then is refused: "recursive use of an object"), so the run loop
// makes them between samples (`later`).
let pending = [];
// An animated scene's frames and the one shown.
let frameCount = 0;
let shownFrame = 0;
let playing = false; // an animation moves on a frame once each frame has a sample

function draw() {
  const [w, h] = session.size();
  const canvas = $("canvas");
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  const rgba = session.rgba();
  if (rgba.length === w * h * 4) {
    canvas.getContext("2d").putImageData(new ImageData(new Uint8ClampedArray(rgba), w, h), 0, 0);
  }
}

// Traces sample after sample until the image is done or starts again.
async function run() {
  if (running) return;
  running = true;
  try {
    for (;;) {
      for (const call of pending.splice(0)) call();
      const mine = generation;
      const more = await session.step();
      draw();
      const [done, spp] = session.samples();
      status(`${done} / ${spp} samples, ${session.rays()} rays, on ${session.adapter()}`);
      if (playing && done >= 1) {
        // Unless paused before the loop comes round to it.
        pending.push(() => playing && showFrame((shownFrame + 1) % frameCount));
      } else if (mine === generation && !more && pending.length === 0) {
        break;
      }
      await new Promise((r) => requestAnimationFrame(r));
    }
  } catch (e) {
    showError(e);
  } finally {
    running = false;
  }
}

function restart() {
  generation += 1;
  run();
}

// `call` on the session, made by the run loop before its next sample, and the image
// started again.
function later(call) {
  pending.push(call);
  restart();
}

// `call` on the session, made by the run loop before its next sample (or at once, when
// the image is complete), the image going on as it was.
function soon(call) {
  pending.push(call);
  run();
}

// Shows frame `i` of an animated scene, and the slider and the number with it (from the
// run loop, or while nothing is traced).
function showFrame(i) {
  session.set_frame(i);
  shownFrame = i;
  generation += 1;
  $("frame").value = String(i);
  $("frame-number").textContent = `${i} / ${frameCount}`;
}

// The animation's controls, shown for a scene with frames (after a load, while nothing
// is traced).
function animationControls() {
  frameCount = session.frames();
  shownFrame = 0;
  playing = false;
  $("animation").hidden = frameCount === 0;
  $("play").textContent = "Play (space)";
  $("frame").max = String(Math.max(frameCount - 1, 0));
  $("frame").value = "0";
  $("frame-number").textContent = frameCount ? `0 / ${frameCount}` : "";
}

function togglePlay() {
  if (frameCount === 0) return;
  playing = !playing;
  $("play").textContent = playing ? "Pause (space)" : "Play (space)";
  restart();
}

// A number from the URL or a box: a whole number, or an error naming the parameter
// (parseInt would take "-2" as -2, which wraps to 4294967294 on the way to the library,
// and "abc" as nothing). The library checks the range.
function whole(id, text) {
  if (!/^[0-9]+$/.test(text.trim())) {
    throw new Error(`${id} must be a whole number, got ${JSON.stringify(text)}`);
  }
  return parseInt(text, 10);
}

function applyOptions(shading = $("shading").value) {
  const n = (id) => whole(id, $(id).value);
  session.set_options(n("width"), n("height"), n("spp"), n("depth"), shading);
}

function loadBytes(name, bytes) {
  clearError();
  session.load(name, bytes);
  applyOptions();
  animationControls();
}

async function interactive() {
  const open = async (file) => {
    try {
      const bytes = new Uint8Array(await file.arrayBuffer());
      later(() => loadBytes(file.name, bytes));
    } catch (e) {
      showError(e);
    }
  };
  $("file").addEventListener("change", (e) => e.target.files[0] && open(e.target.files[0]));
  const drop = $("drop");
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    if (e.dataTransfer.files[0]) open(e.dataTransfer.files[0]);
  });
  for (const id of ["width", "height", "spp", "depth", "shading"]) {
    $(id).addEventListener("change", () => {
      later(applyOptions);
    });
  }
  const canvas = $("canvas");
  let last = null;
  canvas.addEventListener("pointerdown", (e) => { last = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointerup", () => { last = null; });
  canvas.addEventListener("pointermove", (e) => {
    if (!last) return;
    const [dx, dy, pan] = [e.clientX - last[0], e.clientY - last[1], e.shiftKey];
    later(() => session.drag(dx, dy, pan));
    last = [e.clientX, e.clientY];
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const notches = -Math.sign(e.deltaY);
    later(() => session.dolly(notches));
  }, { passive: false });
  const showView = () => soon(() => { $("view").hidden = false; $("view").textContent = session.view_block(); });
  $("camera").addEventListener("click", showView);
  document.addEventListener("keydown", (e) => {
    if (e.key === "c" || e.key === "C") showView();
    if (e.key === " " && e.target.tagName !== "INPUT" && e.target.tagName !== "BUTTON") {
      e.preventDefault();
      togglePlay();
    }
  });
  $("play").addEventListener("click", togglePlay);
  $("frame").addEventListener("input", () => {
    const i = $("frame").value;
    later(() => showFrame(whole("frame", i)));
  });
  $("reset").addEventListener("click", () => later(() => session.reset()));
  $("download").addEventListener("click", () => soon(() => {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([session.png()], { type: "image/png" }));
    a.download = "gpurt.png";
    a.click();
  }));
  status(`ready on ${session.adapter()}: open a scene`);
}

// ?scene=URL&width=W&height=H&spp=N&depth=D&shading=S: one render, its result in the page.
// orbit=DX,DY, pan=DX,DY and dolly=N move the camera first, as those drags and wheel
// notches would (in that order).
async function scripted(params) {
  const url = params.get("scene");
  for (const id of ["width", "height", "spp", "depth"]) {
    if (params.has(id)) $(id).value = whole(id, params.get(id));
  }
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  const name = decodeURIComponent(new URL(url, location.href).pathname.split("/").pop());
  loadBytes(name, new Uint8Array(await response.arrayBuffer()));
  // A <select> ignores a value it has no option for: the library checks the name.
  if (params.has("shading")) applyOptions(params.get("shading"));
  if (params.has("frame")) session.set_frame(whole("frame", params.get("frame")));
  const pair = (key) => params.get(key).split(",").map(Number);
  if (params.has("orbit")) session.drag(...pair("orbit"), false);
  if (params.has("pan")) session.drag(...pair("pan"), true);
  if (params.has("dolly")) session.dolly(Number(params.get("dolly")));
  while (await session.step()) { /* every sample */ }
  // A device error can arrive after the last readback: give it a turn of the event loop.
  await new Promise((r) => setTimeout(r, 0));
  session.check();
  draw();
  const view = document.createElement("pre");
  view.id = "gpurt-view";
  view.textContent = session.view_block();
  $("out").appendChild(view);
  const img = document.createElement("img");
  img.dataset.rays = String(session.rays());
  img.dataset.adapter = session.adapter();
  img.src = "data:image/png;base64," + base64(session.png());
  img.id = "gpurt-result";
  $("out").appendChild(img);
  status(`done: ${session.samples()[0]} samples on ${session.adapter()}`);
}

async function main() {
  await init();
  try {
    session = await Session.start();
  } catch (e) {
    showError(`no WebGPU: ${e}`);
    return;
  }
  const params = new URLSearchParams(location.search);
  if (params.has("scene")) {
    try {
      await scripted(params);
    } catch (e) {
      showError(e);
    }
  } else {
    await interactive();
  }
}

main();
