//! The shader on the device: the bind group layouts of `types.wgsl` and of `resume`, the
//! shader modules (one per length of the ray stack), the compiling of an entry point for a
//! `Specialization`, and the pipeline cache kept on disk between runs. Apart from the
//! renderer, which decides what to compile and when, so that how a pipeline is made is
//! written once for the `main` and `resume` entry points alike.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use super::cache::cache_dir;
use super::device::{Device, Slot};
use super::shaders::{self, Fetch};
use super::specialization::Specialization;
use crate::gpu_types::GpuTile;
use crate::util::error::Result;

/// The most of a pipeline cache file that is read, far past any written: after the whole
/// suite on an H200 the cache directory held under 1 MB.
const MAX_CACHE_BYTES: u64 = 1 << 30;

/// The on-disk pipeline cache: wgpu's cache of compiled pipelines, read from its file
/// when a renderer is set up and written back after each pipeline it compiles.
pub(super) struct DiskCache {
    cache: wgpu::PipelineCache,
    file: PathBuf,
}

impl DiskCache {
    /// The cache's file for the adapter `adapter_info`, when the device has
    /// `PIPELINE_CACHE` and there is a cache directory (`cache_dir`).
    pub(super) fn file(gpu: &Device, adapter_info: Option<&wgpu::AdapterInfo>) -> Option<PathBuf> {
        adapter_info
            .filter(|_| gpu.has_pipeline_cache())
            .and_then(|info| Some(cache_dir()?.join(wgpu::util::pipeline_cache_key(info)?)))
    }

    /// The cache, holding what `file` holds if it can be read and is no longer than
    /// `MAX_CACHE_BYTES` (a longer one, which `save` never writes, is left unread: an
    /// empty cache only costs compile time).
    pub(super) fn open(gpu: &Device, file: PathBuf) -> DiskCache {
        let data = crate::util::bounded::read(&file, MAX_CACHE_BYTES)
            .ok()
            .flatten();
        // SAFETY: the file is named by the adapter's cache key (`file`), and only `save`
        // writes it, with what `PipelineCache::get_data` gave.
        let cache = unsafe { gpu.pipeline_cache("gpurt", data.as_deref()) };
        DiskCache { cache, file }
    }

    pub(super) fn cache(&self) -> &wgpu::PipelineCache {
        &self.cache
    }

    /// Writes the cache back to its file.
    pub(super) fn save(&self) {
        if let Some(data) = self.cache.get_data() {
            // Best effort: a cache that cannot be written only costs time next run.
            let _ = std::fs::create_dir_all(self.file.parent().unwrap_or(&self.file));
            let _ = crate::util::atomic::write_atomic(&self.file, &data);
        }
    }
}

/// The shader modules made so far, one per length of `trace`'s ray stack (the only part
/// of a specialisation written into the source, `shaders::source`), each on first use,
/// all reading the scene as the renderer's `Fetch` says; shared by the `main` and
/// `resume` pipelines.
pub(super) struct Modules {
    fetch: Fetch,
    made: Mutex<HashMap<u32, wgpu::ShaderModule>>,
}

impl Modules {
    pub(super) fn new(fetch: Fetch) -> Self {
        Modules {
            fetch,
            made: Mutex::default(),
        }
    }

    fn get(&self, gpu: &Device, trace_stack: u32) -> Result<wgpu::ShaderModule> {
        let mut modules = self.made.lock().expect("not poisoned");
        if let Some(m) = modules.get(&trace_stack) {
            return Ok(m.clone());
        }
        let module = gpu.scoped("compiling the shader", || {
            // SAFETY: without runtime checks an out-of-bounds index or an endless loop is
            // undefined behaviour. The renderer calls `SceneBuffers::check` first, which proves
            // every index the shader follows (children, leaf ranges, materials, normal
            // slots) in range, children after parents (so traversal ends), the tree depth
            // within the stack and the ray depth within the ray stack (whose length,
            // `SceneBuffers::trace_stack`, bounds the rays a trace holds). The checks cost
            // lavapipe about a quarter of its tracing time.
            unsafe { gpu.unchecked_shader("gpurt", shaders::source(trace_stack, self.fetch)) }
        })?;
        modules.insert(trace_stack, module.clone());
        Ok(module)
    }
}

/// Compiles the shader's entry point `entry` for a specialisation.
pub(super) fn compile(
    gpu: &Device,
    layout: &wgpu::PipelineLayout,
    modules: &Modules,
    entry: &str,
    spec: Specialization,
    cache: Option<&wgpu::PipelineCache>,
) -> Result<wgpu::ComputePipeline> {
    let constants = spec.constants();
    let module = &modules.get(gpu, spec.trace_stack)?;
    gpu.scoped("compiling the shader", || {
        gpu.compute_pipeline(entry, layout, module, &constants, cache)
    })
}

/// The `resume` entry point: its group 1 layout, its pipeline layout (groups 0 and 1),
/// and its pipelines compiled so far, one per `Specialization`, each on first use (most
/// renders never need one), shared by every scene a `GpuRenderer` uploads.
pub(super) struct ResumePipelines {
    pub(super) layout: wgpu::BindGroupLayout,
    pub(super) pipeline_layout: wgpu::PipelineLayout,
    pub(super) modules: Arc<Modules>,
    pub(super) compiled: Mutex<HashMap<Specialization, wgpu::ComputePipeline>>,
}

impl ResumePipelines {
    pub(super) fn get(&self, gpu: &Device, spec: Specialization) -> Result<wgpu::ComputePipeline> {
        // One `resume` whichever entry point traced the frame.
        let spec = Specialization {
            pooled: false,
            ..spec
        };
        let mut compiled = self.compiled.lock().expect("not poisoned");
        if let Some(p) = compiled.get(&spec) {
            return Ok(p.clone());
        }
        let p = compile(
            gpu,
            &self.pipeline_layout,
            &self.modules,
            "resume",
            spec,
            None,
        )?;
        compiled.insert(spec, p.clone());
        Ok(p)
    }
}

/// The bindings of `types.wgsl`: globals (read-only storage) and tile (uniform, one
/// record per dispatch), nodes, primitives and triangle normals (as `fetch` says: texture
/// arrays, split into layers as large as the device allows, or read-only storage), the
/// other scene arrays (read-only storage), the tile's output and its counts (read-write
/// storage).
fn main_slots(fetch: Fetch) -> [Slot; 10] {
    use Slot::*;
    let tile = UniformRecord {
        size: size_of::<GpuTile>() as u64,
    };
    let texels = match fetch {
        Fetch::Textures => Texels,
        Fetch::Buffers => ReadOnly,
    };
    [
        ReadOnly, tile, texels, texels, texels, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadWrite,
    ]
}

/// Group 0 of every entry point: `main_slots`.
pub(super) fn bind_group_layout(gpu: &Device, fetch: Fetch) -> wgpu::BindGroupLayout {
    gpu.bind_group_layout("gpurt", &main_slots(fetch))
}

/// Storage buffers group 0 binds (a stage's limit counts them with its other groups').
pub(super) fn storage_buffers(fetch: Fetch) -> u32 {
    let storage = |s: &&Slot| matches!(s, Slot::ReadOnly | Slot::ReadWrite);
    main_slots(fetch).iter().filter(storage).count() as u32
}

/// Group 1 of `resume`: the pixels to resume (read-only), their states and the count of
/// unfinished ones (read-write storage).
pub(super) fn resume_group_layout(gpu: &Device) -> wgpu::BindGroupLayout {
    use Slot::*;
    gpu.bind_group_layout("gpurt resume", &[ReadOnly, ReadWrite, ReadWrite])
}

/// The pipeline layouts of the `main` entry point (group 0, `layout`) and of `resume`
/// (groups 0 and 1).
pub(super) fn pipeline_layouts(
    gpu: &Device,
    layout: &wgpu::BindGroupLayout,
    resume_layout: &wgpu::BindGroupLayout,
) -> (wgpu::PipelineLayout, wgpu::PipelineLayout) {
    (
        gpu.pipeline_layout("gpurt", &[Some(layout)]),
        gpu.pipeline_layout("gpurt resume", &[Some(layout), Some(resume_layout)]),
    )
}
