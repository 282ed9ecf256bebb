//! Finding an adapter and opening a device. Kept apart from rendering so tests (and other
//! programs) can pass in a device of their own to `render_gpu`.

use crate::util::error::{Error, Result};

/// A device and queue with the adapter they came from. Cloning shares the device.
#[derive(Clone)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::Adapter,
    pub info: wgpu::AdapterInfo,
}

impl GpuContext {
    /// One line naming the adapter, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)`.
    pub fn describe(&self) -> String {
        describe(&self.info)
    }

    /// One line saying which of the adapter's optional features that bear on the
    /// renderer's speed it offers, e.g. `timestamps yes, subgroups yes, ray queries no`:
    /// timestamps time the wavefront's kernels; subgroups (a warp's lanes exchanging
    /// values) and ray queries (traversal in the hardware's ray-tracing units) are what a
    /// walk would need to go past the software walks of now. `gpurt bench` and `tune`
    /// print it beside the adapter, so a measurement says what the hardware had.
    pub fn capabilities(&self) -> String {
        let has = self.adapter.features();
        [
            ("timestamps", wgpu::Features::TIMESTAMP_QUERY),
            ("subgroups", wgpu::Features::SUBGROUP),
            ("ray queries", wgpu::Features::EXPERIMENTAL_RAY_QUERY),
        ]
        .map(|(name, f)| format!("{name} {}", if has.contains(f) { "yes" } else { "no" }))
        .join(", ")
    }
}

/// Mesa's Vulkan device-select layer connects to a Wayland display to choose a default
/// GPU, and on a headless machine prints "error: XDG_RUNTIME_DIR is invalid or not set"
/// twice for every instance although nothing failed. gpurt chooses its adapter itself
/// (`open`), so the layer is turned off, once a process, unless the user set
/// `NODEVICE_SELECT` either way. `instance` calls it, so that every front end (the command
/// line, the Python module, a program over the library) is quiet; a program that starts
/// threads of its own before its first render calls it first thing in `main`, as the
/// command line does.
pub fn quiet_device_select() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("NODEVICE_SELECT").is_none() {
            // SAFETY: the environment may be written only while no other thread reads or
            // writes it. The command line calls this first thing in `main`, the Python
            // module when it is imported, and otherwise it runs before the process's
            // first GPU instance, before wgpu or the Vulkan loader has read anything.
            unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
        }
    });
}

/// A wgpu instance for Vulkan, Metal and DX12, or for the backends `WGPU_BACKEND` names,
/// the device-select layer silenced first (`quiet_device_select`): what every GPU path
/// opens adapters on first. GL is left to `gl_instance`, asked only where these offer no
/// adapter: an instance with GL starts EGL, and on NVIDIA's driver (580.159 on an H200)
/// EGL's teardown, as a context was dropped, deadlocked with Vulkan pipelines compiling
/// and devices being destroyed on other threads of the process (each thread waiting on a
/// lock inside the driver's shared library; docs/gpu.md, "A suite that stopped"). It also
/// spares the process the EGL driver's loading.
pub fn instance() -> wgpu::Instance {
    instance_for(wgpu::Backends::PRIMARY)
}

/// What `find` finds on `instance`, or where it finds no adapter there, on `gl_instance`:
/// the one order every adapter search takes (`open`, `choose` when named, the viewer).
pub fn on_any_backend<T>(find: impl Fn(wgpu::Instance) -> Result<T>) -> Result<T> {
    match find(instance()) {
        Err(Error::NoAdapter(_)) if let Some(gl) = gl_instance() => find(gl),
        found => found,
    }
}

/// An instance for GL alone, for where `instance` found no adapter; `None` when
/// `WGPU_BACKEND` names the backends, since `instance` searched exactly those.
fn gl_instance() -> Option<wgpu::Instance> {
    wgpu::Backends::from_env()
        .is_none()
        .then(|| instance_for(wgpu::Backends::GL))
}

fn instance_for(backends: wgpu::Backends) -> wgpu::Instance {
    quiet_device_select();
    let descriptor = wgpu::InstanceDescriptor {
        backends,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    };
    wgpu::Instance::new(descriptor.with_env())
}

pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

/// Preference among adapters: real GPUs first, software last; Vulkan/Metal/DX12 before GL.
fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let device = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let backend = match info.backend {
        wgpu::Backend::Gl | wgpu::Backend::BrowserWebGpu => 1,
        _ => 0,
    };
    (device, backend)
}

/// Opens a device on the best adapter, or on the first whose name contains `filter`
/// (case-insensitive; from `--adapter` or `GPURT_ADAPTER`). `WGPU_BACKEND` limits the
/// backends searched, as in every wgpu program.
pub fn open(filter: Option<&str>) -> Result<GpuContext> {
    open_adapter(best_anywhere(filter)?)
}

/// The best adapter (see `best_adapter`) on any backend (`on_any_backend`).
fn best_anywhere(filter: Option<&str>) -> Result<wgpu::Adapter> {
    on_any_backend(|instance| best_adapter(&instance, filter, None))
}

/// `open` on a given instance, among the adapters that can present to `surface` when
/// one is given (the viewer's window).
pub fn open_on(
    instance: &wgpu::Instance,
    filter: Option<&str>,
    surface: Option<&wgpu::Surface>,
) -> Result<GpuContext> {
    open_adapter(best_adapter(instance, filter, surface)?)
}

/// Where `--backend auto` renders.
pub enum Choice {
    /// On this hardware adapter, or on the one asked for by name.
    Gpu(Box<GpuContext>),
    /// On the CPU, for this reason.
    Cpu(String),
}

/// The fastest backend here: the best adapter when it is hardware (discrete, integrated or
/// virtual GPU), or the one named by `filter` (or `GPURT_ADAPTER`), whatever it is;
/// otherwise the CPU, because a software rasteriser (llvmpipe/lavapipe, SwiftShader, WARP)
/// runs our shader several times slower than the CPU renderer on the same cores (3.2 to
/// 5.2 times on the SPD scenes at 512x512). The software adapter's device is never opened,
/// and on Linux without a GPU device node no driver is even loaded.
pub fn choose(filter: Option<&str>) -> Result<Choice> {
    let named = adapter_filter(filter).is_some();
    if !named && let Some(why) = no_gpu_device() {
        return Ok(Choice::Cpu(why));
    }
    // GL only when asked for, by name or by `WGPU_BACKEND`: the shader does not compile on
    // Mesa's GL (docs/gpu.md, "Host side"), and the CPU renders wherever it cannot.
    let found = if named {
        best_anywhere(filter)
    } else {
        best_adapter(&instance(), filter, None)
    };
    match found {
        Ok(adapter) if named || !is_software(&adapter.get_info()) => {
            open_adapter(adapter).map(|ctx| Choice::Gpu(Box::new(ctx)))
        }
        // The best adapter is software only when all of them are (`rank`).
        Ok(adapter) => Ok(Choice::Cpu(format!(
            "the GPU adapters here are software rasterisers (best: {}), slower than the CPU renderer",
            describe(&adapter.get_info())
        ))),
        Err(Error::NoAdapter(why)) if !named => Ok(Choice::Cpu(format!("no GPU adapter{why}"))),
        Err(e) => Err(e),
    }
}

/// Why no hardware adapter can exist here, if the device nodes say so. A GPU driver on
/// Linux works through a device node: a DRM render node (Mesa, NVIDIA's open modules,
/// virtio-gpu), NVIDIA's own nodes, or WSL2's `/dev/dxg`. Without any, only software
/// adapters remain, and looking for them would load their drivers for nothing (40 ms and
/// 50 MB of LLVM for lavapipe and Mesa's hardware drivers, a third of a small render).
/// `None` elsewhere than Linux, and where a node exists: then the adapters are asked.
fn no_gpu_device() -> Option<String> {
    if !cfg!(target_os = "linux") {
        return None;
    }
    let listed = |dir: &str, prefix: &str| {
        std::fs::read_dir(dir).is_ok_and(|entries| {
            entries
                .flatten()
                .any(|e| e.file_name().to_string_lossy().starts_with(prefix))
        })
    };
    let any = listed("/dev/dri", "renderD")
        || listed("/dev/dri", "card")
        || listed("/dev", "nvidia")
        || std::path::Path::new("/dev/dxg").exists();
    (!any).then(|| "there is no GPU device here (no /dev/dri, /dev/nvidia* or /dev/dxg)".into())
}

/// Whether an adapter rasterises in software on the CPU: Mesa's llvmpipe (lavapipe on
/// Vulkan), Google's SwiftShader, Microsoft's WARP. Drivers report most of them as
/// `DeviceType::Cpu`; the names catch those that do not.
pub fn is_software(info: &wgpu::AdapterInfo) -> bool {
    let name = info.name.to_lowercase();
    info.device_type == wgpu::DeviceType::Cpu
        || [
            "llvmpipe",
            "lavapipe",
            "softpipe",
            "swiftshader",
            "microsoft basic render",
        ]
        .iter()
        .any(|s| name.contains(s))
}

/// `--adapter`'s filter, else `GPURT_ADAPTER`'s, if not empty.
fn adapter_filter(filter: Option<&str>) -> Option<String> {
    filter
        .map(str::to_owned)
        .or_else(|| std::env::var("GPURT_ADAPTER").ok())
        .filter(|f| !f.is_empty())
}

/// The best adapter of `instance` (see `rank`) that runs compute shaders, can present to
/// `surface` when one is given, and whose name contains `filter` when one is given.
fn best_adapter(
    instance: &wgpu::Instance,
    filter: Option<&str>,
    surface: Option<&wgpu::Surface>,
) -> Result<wgpu::Adapter> {
    let filter = adapter_filter(filter);
    // The instance already honours WGPU_BACKEND; list what it enabled.
    let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    // Compute shaders need storage buffers; GL adapters without them cannot run ours.
    adapters.retain(|a| {
        a.get_downlevel_capabilities()
            .flags
            .contains(wgpu::DownlevelFlags::COMPUTE_SHADERS)
    });
    if let Some(surface) = surface {
        adapters.retain(|a| a.is_surface_supported(surface));
    }
    if let Some(f) = &filter {
        let f = f.to_lowercase();
        adapters.retain(|a| a.get_info().name.to_lowercase().contains(&f));
    }
    adapters.sort_by_key(|a| rank(&a.get_info()));
    let Some(adapter) = adapters.into_iter().next() else {
        let mut why = match filter {
            Some(f) => format!(" whose name contains '{f}'"),
            None => String::new(),
        };
        if surface.is_some() {
            why.push_str(" that can present to the window");
        }
        return Err(Error::NoAdapter(why));
    };
    Ok(adapter)
}

/// Opens a device on `adapter`.
fn open_adapter(adapter: wgpu::Adapter) -> Result<GpuContext> {
    pollster::block_on(open_adapter_async(adapter))
}

/// Opens a device on the adapter the instance offers when asked (the browser's WebGPU
/// adapter: a page cannot list adapters, only request one), without blocking.
pub async fn request(instance: &wgpu::Instance) -> Result<GpuContext> {
    let options = wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    };
    let adapter = instance
        .request_adapter(&options)
        .await
        .map_err(|e| Error::NoAdapter(format!(" ({e})")))?;
    open_adapter_async(adapter).await
}

/// `open_adapter` as a future, for the browser, which may not block.
async fn open_adapter_async(adapter: wgpu::Adapter) -> Result<GpuContext> {
    let info = adapter.get_info();
    // Ask for everything the adapter offers: big scenes need its largest buffer limits.
    let mut required_features = wgpu::Features::empty();
    if adapter.features().contains(wgpu::Features::PIPELINE_CACHE) {
        required_features |= wgpu::Features::PIPELINE_CACHE;
    }
    // For timing the wavefront's kernels (`GpuScene::time_kernels`); unused otherwise.
    if adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
        required_features |= wgpu::Features::TIMESTAMP_QUERY;
    }
    let (device, queue) = adapter
        .request_device(&wgpu::DeviceDescriptor {
            label: Some("gpurt"),
            required_features,
            required_limits: adapter.limits(),
            memory_hints: crate::util::fault::memory_hints(),
            ..Default::default()
        })
        .await
        .map_err(|e| Error::Gpu(format!("cannot open a device on {}: {e}", describe(&info))))?;
    Ok(GpuContext {
        device,
        queue,
        adapter,
        info,
    })
}
