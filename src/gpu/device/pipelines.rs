//! The shader on the device: bind group layouts, shader modules, compute pipelines and the
//! cache of compiled pipelines.

use super::{Device, TEXEL_FORMAT};

/// A binding of a compute shader's bind group, as the renderer's shaders use them.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Slot {
    /// A storage buffer the shader only reads.
    ReadOnly,
    /// A storage buffer the shader writes.
    ReadWrite,
    /// One of many `size`-byte uniform records in one buffer, chosen per dispatch by a
    /// dynamic offset (the tiles of a band).
    UniformRecord { size: u64 },
    /// A texture array of `TEXEL_FORMAT` texels the shader reads (a scene's arrays).
    Texels,
}

impl Device<'_> {
    /// A compute bind group layout of `slots`, binding `i` being `slots[i]`. Explicit, so
    /// that a binding a shader happens not to use is still accepted.
    pub(crate) fn bind_group_layout(&self, label: &str, slots: &[Slot]) -> wgpu::BindGroupLayout {
        let entry = |(binding, slot): (usize, &Slot)| {
            let buffer = |ty, has_dynamic_offset, min_binding_size| wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset,
                min_binding_size,
            };
            let storage = |read_only| wgpu::BufferBindingType::Storage { read_only };
            wgpu::BindGroupLayoutEntry {
                binding: binding as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: match *slot {
                    Slot::ReadOnly => buffer(storage(true), false, None),
                    Slot::ReadWrite => buffer(storage(false), false, None),
                    Slot::UniformRecord { size } => buffer(
                        wgpu::BufferBindingType::Uniform,
                        true,
                        wgpu::BufferSize::new(size),
                    ),
                    Slot::Texels => wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::ReadOnly,
                        format: TEXEL_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                    },
                },
                count: None,
            }
        };
        let entries: Vec<_> = slots.iter().enumerate().map(entry).collect();
        self.device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            })
    }

    /// The layout of a pipeline whose group `i` is `groups[i]` (none: a group it does not
    /// use).
    pub(crate) fn pipeline_layout(
        &self,
        label: &str,
        groups: &[Option<&wgpu::BindGroupLayout>],
    ) -> wgpu::PipelineLayout {
        self.device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: groups,
                immediate_size: 0,
            })
    }

    /// A bind group of `layout` binding `resources[i]` at binding `i`.
    pub(crate) fn bind_group(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        resources: Vec<wgpu::BindingResource>,
    ) -> wgpu::BindGroup {
        let entries: Vec<_> = resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout,
            entries: &entries,
        })
    }

    /// A shader module of WGSL `source` compiled without wgpu's runtime checks (bounds
    /// checks on every index, a bound on every loop).
    ///
    /// # Safety
    /// Without the checks an out-of-bounds index or an endless loop is undefined
    /// behaviour: the caller must have proved that no input the module will run on leads
    /// to either.
    pub(crate) unsafe fn unchecked_shader(
        &self,
        label: &str,
        source: String,
    ) -> wgpu::ShaderModule {
        let desc = wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        };
        // SAFETY: the caller's (see above).
        unsafe {
            self.device
                .create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
        }
    }

    /// The compute pipeline of `module`'s entry point `entry`, its `override` constants
    /// set to `constants`, through the pipeline cache `cache` when there is one.
    pub(crate) fn compute_pipeline(
        &self,
        entry: &str,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        constants: &[(&str, f64)],
        cache: Option<&wgpu::PipelineCache>,
    ) -> wgpu::ComputePipeline {
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(layout),
                module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    // The shaders write every workgroup-memory entry (the traversal
                    // stack) before they read it, so it needs no zeroing (wgpu would
                    // otherwise add stores and a barrier to the start of every workgroup).
                    zero_initialize_workgroup_memory: false,
                },
                cache,
            })
    }

    /// Whether the device keeps a cache of compiled pipelines (`pipeline_cache`).
    pub(crate) fn has_pipeline_cache(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::PIPELINE_CACHE)
    }

    /// A cache of compiled pipelines, filled from `data` where the driver accepts it
    /// (and empty where it rejects it).
    ///
    /// # Safety
    /// `data` must have been written by `PipelineCache::get_data` for an adapter with the
    /// same cache key (`wgpu::util::pipeline_cache_key`).
    pub(crate) unsafe fn pipeline_cache(
        &self,
        label: &str,
        data: Option<&[u8]>,
    ) -> wgpu::PipelineCache {
        // SAFETY: the caller's (see above); `fallback` makes wgpu ignore data it rejects.
        unsafe {
            self.device
                .create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                    label: Some(label),
                    data,
                    fallback: true,
                })
        }
    }
}
