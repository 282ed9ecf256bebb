//! How a renderer is made for an adapter: its strategy (the walk, the kernels and the
//! way of reading the scene) from the adapter's tuning where `gpurt tune` kept one, else
//! from `policy::defaults`, the environment over either; its layouts, pipeline cache and
//! wavefront pipelines; and that strategy in words for `--stats`.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use web_time::Instant;

use super::GpuRenderer;
use crate::gpu::cut::DISPATCH_BUDGET;
use crate::gpu::device::Device;
use crate::gpu::pipeline::{
    DiskCache, Modules, ResumePipelines, bind_group_layout, pipeline_layouts, resume_group_layout,
};
use crate::gpu::policy::{
    Kernels, Strategy, defaults, fetch_for, kernels_for, shape_for, stack_floor, traversal_for,
};
use crate::gpu::shaders::Fetch;
use crate::gpu::tuning;
use crate::gpu::upload;
use crate::gpu::wavefront::{WavePipelines, wave_binds};
use crate::gpu_types::TRAVERSAL_NAMES;
use crate::pack::SceneBuffers;
use crate::util::error::Result;

impl GpuRenderer {
    /// Sets up the layouts. Shader modules and pipelines are made on first use by `render` (or
    /// `prepare`). `adapter_info` keys the on-disk pipeline cache, used when the device has
    /// `PIPELINE_CACHE`, and the adapter's tuning (`tuning::load`): pass `None` to skip
    /// both, for `policy::defaults`. A tuning file that cannot be read is an error.
    pub fn new(device: &wgpu::Device, adapter_info: Option<&wgpu::AdapterInfo>) -> Result<Self> {
        Self::setup(device, adapter_info, |_, chosen| {
            fetch_for(chosen.fetch, true)
        })
    }

    /// `new`, for frames of `scene`: where its nodes, primitives or normals would not fit
    /// one of the device's storage buffers, its shaders read them from textures, which
    /// grow by layers, whatever the adapter (`policy::fetch_for`).
    pub fn for_scene(
        device: &wgpu::Device,
        adapter_info: Option<&wgpu::AdapterInfo>,
        scene: &SceneBuffers,
    ) -> Result<Self> {
        Self::setup(device, adapter_info, |gpu, chosen| {
            let traversal = scene.traversal_for(traversal_for(chosen.traversal)?);
            let fit = upload::fits_buffers(&gpu.limits(), scene, traversal);
            fetch_for(chosen.fetch, fit)
        })
    }

    /// Whether this renderer reads `scene` as `for_scene` would have it: false only where
    /// it reads buffers and one of the scene's arrays would not fit one.
    pub fn suits(&self, device: &wgpu::Device, scene: &SceneBuffers) -> bool {
        let limits = Device::new(device).limits();
        let traversal = scene.traversal_for(self.traversal);
        self.fetch == Fetch::Textures || upload::fits_buffers(&limits, scene, traversal)
    }

    /// `new`, its shaders reading the scene's nodes, primitives and normals as `fetch`
    /// says whatever the adapter and its tuning.
    pub fn fetching(
        device: &wgpu::Device,
        adapter_info: Option<&wgpu::AdapterInfo>,
        fetch: Fetch,
    ) -> Result<Self> {
        Self::setup(device, adapter_info, |_, _| Ok(fetch))
    }

    /// A renderer taking the adapter's tuning where `adapter_info` is given and one is
    /// kept, else `policy::defaults`, each overridden from the environment, and reading
    /// the scene as `fetch` says given that strategy.
    fn setup(
        device: &wgpu::Device,
        adapter_info: Option<&wgpu::AdapterInfo>,
        fetch: impl FnOnce(&Device, &Strategy) -> Result<Fetch>,
    ) -> Result<Self> {
        let start = Instant::now();
        let gpu = &Device::new(device);
        let software = gpu.runs_on_cpu();
        let tuning = adapter_info.map(tuning::load).transpose()?.flatten();
        let chosen = tuning.as_ref().map_or(defaults(software), |t| t.strategy);
        let fetch = fetch(gpu, &chosen)?;
        let cache_file = DiskCache::file(gpu, adapter_info);
        let layout = bind_group_layout(gpu, fetch);
        let resume_layout = resume_group_layout(gpu);
        let (pipeline_layout, resume_pipeline_layout, cache) =
            gpu.scoped("compiling the shader", || {
                let (main, resume) = pipeline_layouts(gpu, &layout, &resume_layout);
                (
                    main,
                    resume,
                    cache_file.map(|file| DiskCache::open(gpu, file)),
                )
            })?;
        let modules = Arc::new(Modules::new(fetch));
        // Made only where the adapter binds them: a browser's WebGPU does not.
        let wave = match wave_binds(&gpu.limits(), fetch) {
            true => Some(gpu.scoped("compiling the shader", || {
                Arc::new(WavePipelines::new(gpu, &layout, modules.clone()))
            })?),
            false => None,
        };
        let kernels = kernels_for(chosen.kernels)?;
        Ok(GpuRenderer {
            resume: Arc::new(ResumePipelines {
                layout: resume_layout,
                pipeline_layout: resume_pipeline_layout,
                modules: modules.clone(),
                compiled: Mutex::new(HashMap::new()),
            }),
            layout,
            pipeline_layout,
            modules,
            cache,
            pipelines: Mutex::new(HashMap::new()),
            compile_time: Mutex::new(start.elapsed()),
            shape: shape_for(software)?,
            stack_floor: stack_floor()?,
            traversal: traversal_for(chosen.traversal)?,
            fetch,
            tuning,
            wave,
            wavefront: kernels == Kernels::Wavefront,
            pooled: kernels == Kernels::Pooled,
            shadow_rays: true,
            layer_rows: upload::layer_rows(&gpu.limits()),
            dispatch_budget: (!software).then_some(DISPATCH_BUDGET),
            texture_margin: None,
        })
    }

    /// The walk, kernels and fetch this renderer takes (each scene's walk as
    /// `SceneBuffers::traversal_for` allows; the kernels where a frame can take them).
    pub fn strategy(&self) -> Strategy {
        let kernels = match (self.pooled, self.wavefront) {
            (true, _) => Kernels::Pooled,
            (false, true) => Kernels::Wavefront,
            (false, false) => Kernels::Main,
        };
        Strategy {
            traversal: self.traversal,
            kernels,
            fetch: self.fetch,
        }
    }

    /// `strategy` in words, and where it comes from, for `--stats`.
    pub fn describe_strategy(&self) -> String {
        let s = self.strategy();
        let from = match &self.tuning {
            Some(t) => format!("tuned on {}; {}", t.measured, t.file.display()),
            None => "the defaults; `gpurt tune` measures this adapter".to_string(),
        };
        format!(
            "walk {}, kernels {}, scene data from {} ({from})",
            TRAVERSAL_NAMES[s.traversal as usize],
            s.kernels.name(),
            s.fetch.name()
        )
    }
}
