//! The door to wgpu's device and queue: no module of `src/` but `gpu::device` (its
//! `device/` folder, or a `device.rs`) calls a method of `wgpu::Device` or `wgpu::Queue`.
//!
//! Read from the source text, as the module graph is (comments and literals blanked out).
//! A call is `.m(` (or `.m::<`) or a path `Device::m` / `Queue::m` / `DeviceExt::m`, where
//! `m` is one of their methods. A method that only they have (`OWN`) counts on any
//! receiver; one that other wgpu types have too (`SHARED`: `Adapter::limits`,
//! `Buffer::destroy`) counts when its receiver is named for a device or a queue
//! (`device.limits()`, `ctx.queue.destroy()`, `self.device().features()`): the renderer
//! names the door's values `gpu`, and the door's methods never take a name of wgpu's.

use wgpu::util::DeviceExt as _;

use super::source::{Token, strip, tokens};

/// Names the methods of `$ty` as a list of strings, each named as a path too, so that a
/// name wgpu does not have fails to compile.
macro_rules! methods {
    ($($ty:ty: [$($m:ident $(::<$g:ty>)?),* $(,)?]),* $(,)?) => {{
        $($(let _ = <$ty>::$m $(::<$g>)?;)*)*
        &[$($(stringify!($m)),*),*]
    }};
}

/// The methods of `wgpu::Device`, `wgpu::Queue` and `wgpu::util::DeviceExt` that no other
/// wgpu type has. Two take closures (`impl Fn` arguments, which cannot be named as
/// paths): `_closure_methods_exist` names them. (One is deprecated, not gone.)
#[allow(deprecated)]
fn own() -> Vec<&'static str> {
    let named: &[&str] = methods!(
        wgpu::Device: [
            poll, adapter_info, create_shader_module, create_shader_module_unchecked,
            create_shader_module_trusted, create_shader_module_passthrough,
            create_command_encoder, create_render_bundle_encoder, create_bind_group,
            create_bind_group_layout, create_pipeline_layout, create_render_pipeline,
            create_mesh_pipeline, create_compute_pipeline, create_buffer, create_texture,
            create_external_texture, create_sampler, create_query_set,
            on_uncaptured_error, push_error_scope, start_graphics_debugger_capture,
            stop_graphics_debugger_capture, get_internal_counters,
            generate_allocator_report, create_pipeline_cache, create_blas, create_tlas,
        ],
        wgpu::Queue: [
            write_buffer, write_buffer_with, write_texture,
            submit::<Vec<wgpu::CommandBuffer>>, get_timestamp_period, present, compact_blas,
        ],
        wgpu::Device: [create_buffer_init, create_texture_with_data],
    );
    let mut all = named.to_vec();
    all.extend(["set_device_lost_callback", "on_submitted_work_done"]);
    all
}

/// The two methods of `own` that take closures, named by calls that never run.
fn _closure_methods_exist(device: &wgpu::Device, queue: &wgpu::Queue) {
    device.set_device_lost_callback(|_, _| {});
    queue.on_submitted_work_done(|| {});
}

/// Methods of `wgpu::Device` or `wgpu::Queue` that other wgpu types have too.
fn shared() -> &'static [&'static str] {
    methods!(wgpu::Device: [limits, features, destroy])
}

/// Whether `name` (a receiver's last name) names a device or a queue.
fn names_device_or_queue(name: &str) -> bool {
    let name = name.to_lowercase();
    name.contains("device") || name.contains("queue")
}

/// The calls of a method of wgpu's device or queue in a file's text, as `LINE: CALL`.
pub(super) fn calls(src: &str) -> Vec<String> {
    let toks: Vec<Token> = tokens(&strip(src));
    let text = |k: usize| toks.get(k).map_or("", |t| t.text.as_str());
    let (own, shared) = (own(), shared());
    let mut found = Vec::new();
    for (i, t) in toks.iter().enumerate() {
        let m = t.text.as_str();
        let called = text(i + 1) == "(" || text(i + 1) == "::";
        if !called || i == 0 {
            continue;
        }
        let on = receiver(&toks, i - 1);
        let hit = match text(i - 1) {
            "::" => {
                let ty = text(i.wrapping_sub(2));
                ["Device", "Queue", "DeviceExt"].contains(&ty)
                    && (own.contains(&m) || shared.contains(&m))
            }
            "." => own.contains(&m) || (shared.contains(&m) && names_device_or_queue(&on)),
            _ => false,
        };
        if hit {
            found.push(format!("{}: {on}{}{m}", t.line, text(i - 1)));
        }
    }
    found
}

/// The last name of the receiver before the `.` at `toks[dot]`: `b` in `a.b.m()`, `f` in
/// `a.f(x).m()`; empty where there is none (a literal, a closing bracket of an index).
fn receiver(toks: &[Token], dot: usize) -> String {
    let mut k = dot;
    if k > 0 && toks[k - 1].text == ")" {
        // Back to the matching `(`, then the name called.
        let mut depth = 0;
        while k > 0 {
            k -= 1;
            match toks[k].text.as_str() {
                ")" => depth += 1,
                "(" => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                break;
            }
        }
    }
    match k.checked_sub(1).map(|j| &toks[j].text) {
        Some(w) if w.chars().all(|c| c.is_alphanumeric() || c == '_') => w.clone(),
        _ => String::new(),
    }
}

/// Whether a file of `src/` (its path relative to `src/`) is the door itself.
pub(super) fn is_door(rel: &str) -> bool {
    rel == "gpu/device.rs" || rel.starts_with("gpu/device/")
}

#[test]
fn only_the_device_module_calls_wgpus_device_and_queue() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let files = super::sources_under(&src);
    assert!(files.iter().any(|(p, _)| is_door(p)), "no src/gpu/device");
    // The whole of `src/`: the viewer and the commands as much as the renderer.
    assert!(
        files.iter().any(|(p, _)| p.starts_with("view/")),
        "no src/view"
    );
    let mut found = Vec::new();
    for (rel, text) in files.iter().filter(|(p, _)| !is_door(p)) {
        found.extend(calls(text).into_iter().map(|c| format!("src/{rel}:{c}")));
    }
    assert!(
        found.is_empty(),
        "calls of wgpu::Device or wgpu::Queue outside src/gpu/device:\n{}",
        found.join("\n")
    );
}

/// The checker finds each way of calling the device or the queue, and none of the calls
/// that only look like one.
#[test]
fn the_door_check_finds_calls_on_the_device_and_queue_and_no_others() {
    let src = r#"
fn f(ctx: &GpuContext, gpu: &Gpu, adapter: &wgpu::Adapter, q: &wgpu::Queue) {
    let b = ctx.device.create_buffer(&desc);
    q.submit([enc.finish()]);
    let l = ctx.device.limits();
    wgpu::Device::poll(&ctx.device, wgpu::PollType::Poll);
    let f = self.device().features();
    q.write_buffer::<>(&b, 0, &[]);
    let a = adapter.limits();
    let g = gpu.limits();
    buffer.destroy();
    gpu.run(enc);
    // device.create_buffer(&desc) in a comment
    let s = "queue.submit([])";
    let t = ctx.device_type;
}
"#;
    assert_eq!(
        calls(src),
        [
            "3: device.create_buffer",
            "4: q.submit",
            "5: device.limits",
            "6: Device::poll",
            "7: device.features",
            "8: q.write_buffer",
        ]
    );
}

/// A call added to a real module of the renderer fails the check; the module as it is
/// passes it.
#[test]
fn a_call_on_the_queue_added_to_the_dispatch_loop_is_found() {
    let trace = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/gpu/trace.rs");
    let text = std::fs::read_to_string(trace).expect("src/gpu/trace.rs");
    assert_eq!(calls(&text), Vec::<String>::new());
    let at = text
        .find("let mut enc = gpu.encoder();")
        .expect("an encoder");
    let broken = format!("{}queue.submit([]);\n{}", &text[..at], &text[at..]);
    let line = text[..at].matches('\n').count() + 1;
    assert_eq!(calls(&broken), [format!("{line}: queue.submit")]);
}
