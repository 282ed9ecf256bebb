//! The shader on the device: the bind group layouts of `types.wgsl` and of `resume`, the
//! shader modules (one per length of the ray stack), the compiling of an entry point for a
//! `Specialization`, and the pipeline cache kept on disk between runs. Apart from the
//! renderer, which decides what to compile and when, so that how a pipeline is made is
//! written once for the `main` and `resume` entry points alike.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use super::device::scoped;
use super::shaders;
use super::specialization::Specialization;
use super::upload::TEXEL_FORMAT;
use crate::error::Result;
use crate::gpu_types::GpuTile;

/// Where the pipeline cache lives: `GPURT_CACHE_DIR`, else `$XDG_CACHE_HOME/gpurt`, else
/// `~/.cache/gpurt`. `GPURT_CACHE_DIR=` (empty) turns the cache off.
fn cache_dir() -> Option<PathBuf> {
    if let Ok(d) = std::env::var("GPURT_CACHE_DIR") {
        return (!d.is_empty()).then(|| PathBuf::from(d));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("gpurt"))
}

/// The on-disk pipeline cache: wgpu's cache of compiled pipelines, read from its file
/// when a renderer is set up and written back after each pipeline it compiles.
pub(super) struct DiskCache {
    cache: wgpu::PipelineCache,
    file: PathBuf,
}

impl DiskCache {
    /// The cache's file for the adapter `adapter_info`, when the device has
    /// `PIPELINE_CACHE` and there is a cache directory (`cache_dir`).
    pub(super) fn file(
        device: &wgpu::Device,
        adapter_info: Option<&wgpu::AdapterInfo>,
    ) -> Option<PathBuf> {
        adapter_info
            .filter(|_| device.features().contains(wgpu::Features::PIPELINE_CACHE))
            .and_then(|info| Some(cache_dir()?.join(wgpu::util::pipeline_cache_key(info)?)))
    }

    /// The cache, holding what `file` holds if it can be read.
    pub(super) fn open(device: &wgpu::Device, file: PathBuf) -> DiskCache {
        let data = std::fs::read(&file).ok();
        // SAFETY: the data was written by `PipelineCache::get_data` for an adapter
        // with the same cache key; `fallback` makes wgpu ignore data it rejects.
        let cache = unsafe {
            device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                label: Some("gpurt"),
                data: data.as_deref(),
                fallback: true,
            })
        };
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
            let _ = crate::atomic::write_atomic(&self.file, &data);
        }
    }
}

/// The shader modules made so far, one per length of `trace`'s ray stack (the only part
/// of a specialisation written into the source, `shaders::source`), each on first use;
/// shared by the `main` and `resume` pipelines.
#[derive(Default)]
pub(super) struct Modules(Mutex<HashMap<u32, wgpu::ShaderModule>>);

impl Modules {
    fn get(&self, device: &wgpu::Device, trace_stack: u32) -> Result<wgpu::ShaderModule> {
        let mut modules = self.0.lock().expect("not poisoned");
        if let Some(m) = modules.get(&trace_stack) {
            return Ok(m.clone());
        }
        let module = scoped(device, "compiling the shader", || {
            let desc = wgpu::ShaderModuleDescriptor {
                label: Some("gpurt"),
                source: wgpu::ShaderSource::Wgsl(shaders::source(trace_stack).into()),
            };
            // SAFETY: without runtime checks an out-of-bounds index or an endless loop is
            // undefined behaviour. The renderer calls `SceneBuffers::check` first, which proves
            // every index the shader follows (children, leaf ranges, materials, normal
            // slots) in range, children after parents (so traversal ends), the tree depth
            // within the stack and the ray depth within the ray stack (whose length,
            // `SceneBuffers::trace_stack`, bounds the rays a trace holds). The checks cost
            // lavapipe about a quarter of its tracing time.
            unsafe {
                device.create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
            }
        })?;
        modules.insert(trace_stack, module.clone());
        Ok(module)
    }
}

/// Compiles the shader's entry point `entry` for a specialisation.
pub(super) fn compile(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    modules: &Modules,
    entry: &str,
    spec: Specialization,
    cache: Option<&wgpu::PipelineCache>,
) -> Result<wgpu::ComputePipeline> {
    let constants = spec.constants();
    let module = &modules.get(device, spec.trace_stack)?;
    scoped(device, "compiling the shader", || {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(layout),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: &constants,
                // Every traversal-stack entry is written before it is read, so the
                // workgroup memory needs no zeroing (wgpu would otherwise add stores
                // and a barrier to the start of every workgroup).
                zero_initialize_workgroup_memory: false,
            },
            cache,
        })
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
    pub(super) fn get(
        &self,
        device: &wgpu::Device,
        spec: Specialization,
    ) -> Result<wgpu::ComputePipeline> {
        let mut compiled = self.compiled.lock().expect("not poisoned");
        if let Some(p) = compiled.get(&spec) {
            return Ok(p.clone());
        }
        let p = compile(
            device,
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

/// The bindings of `types.wgsl`: globals (read-only storage) and tile (uniform), nodes,
/// primitives and triangle normals (rgba32uint texture arrays, split into layers as large
/// as the device allows), the other scene arrays (read-only storage), the tile's output
/// (read-write storage). Explicit, so that a binding the shader happens not to use is
/// still accepted.
pub(super) fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let texels = |binding: u32| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::ReadOnly,
            format: TEXEL_FORMAT,
            view_dimension: wgpu::TextureViewDimension::D2Array,
        },
        count: None,
    };
    let mut entries = vec![
        entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
        wgpu::BindGroupLayoutEntry {
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(size_of::<GpuTile>() as u64),
            },
            ..entry(1, wgpu::BufferBindingType::Uniform)
        },
        texels(2),
        texels(3),
        texels(4),
    ];
    entries.extend((5..8).map(|b| entry(b, wgpu::BufferBindingType::Storage { read_only: true })));
    entries.push(entry(
        8,
        wgpu::BufferBindingType::Storage { read_only: false },
    ));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("gpurt"),
        entries: &entries,
    })
}

/// Group 1 of `resume`: the pixels to resume (read-only), their states and the count of
/// unfinished ones (read-write storage).
pub(super) fn resume_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entry = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("gpurt resume"),
        entries: &[entry(0, true), entry(1, false), entry(2, false)],
    })
}

/// The pipeline layouts of the `main` entry point (group 0, `layout`) and of `resume`
/// (groups 0 and 1).
pub(super) fn pipeline_layouts(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    resume_layout: &wgpu::BindGroupLayout,
) -> (wgpu::PipelineLayout, wgpu::PipelineLayout) {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gpurt"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let resume_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gpurt resume"),
        bind_group_layouts: &[Some(layout), Some(resume_layout)],
        immediate_size: 0,
    });
    (pipeline_layout, resume_pipeline_layout)
}
