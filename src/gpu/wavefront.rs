//! The wavefront path's pipelines and buffers: the kernels of `shaders/wavefront.wgsl`
//! (compiled once per `Specialization`, like `main`), and for an uploaded scene a wave:
//! one `WaveState` per pixel of a tile, the kernels' queues, their lengths and the sizes
//! of their indirect dispatches. The dispatch loop that runs a wave is `waves`.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use super::device::{Device, Slot};
use super::pipeline::{Modules, compile};
use super::specialization::Specialization;
use crate::error::Result;
use crate::gpu_types::wave_state_bytes;

/// The kernels, in the order `Kernels` holds their pipelines.
const ENTRIES: [&str; 6] = [
    "wf_generate",
    "wf_advance_rays",
    "wf_extend",
    "wf_shadow",
    "wf_advance_shade",
    "wf_shade",
];

/// The pipelines of the kernels, in `ENTRIES` order. Read by `waves`, which runs natively
/// only (it waits on the device between rounds, which the browser cannot).
#[cfg_attr(not(feature = "native"), allow(dead_code))]
pub(super) struct Kernels {
    pub(super) generate: wgpu::ComputePipeline,
    pub(super) advance_rays: wgpu::ComputePipeline,
    pub(super) extend: wgpu::ComputePipeline,
    pub(super) shadow: wgpu::ComputePipeline,
    pub(super) advance_shade: wgpu::ComputePipeline,
    pub(super) shade: wgpu::ComputePipeline,
}

/// Words of `wave_counts` (the halves of the three queues, their lengths as inputs, their
/// lengths as they fill) and of `wave_args` (three indirect dispatch sizes).
pub(super) const COUNT_WORDS: u64 = 9;
const ARG_WORDS: u64 = 9;

/// Group 2 of the kernels (the wave), their pipeline layout (groups 0 and 2), and their
/// pipelines compiled so far, one set per `Specialization`, shared by every scene a
/// `GpuRenderer` uploads.
pub(super) struct WavePipelines {
    layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    /// Groups 0 and 2, for the kernels that trace and shade; groups 2 and 3 for the two
    /// that advance the queues.
    pipeline_layout: wgpu::PipelineLayout,
    advance_layout: wgpu::PipelineLayout,
    modules: Arc<Modules>,
    compiled: Mutex<HashMap<Specialization, Arc<Kernels>>>,
}

impl WavePipelines {
    pub(super) fn new(
        gpu: &Device,
        main_layout: &wgpu::BindGroupLayout,
        modules: Arc<Modules>,
    ) -> Self {
        use Slot::ReadWrite;
        let layout = gpu.bind_group_layout("gpurt wave", &[ReadWrite; 3]);
        let args_layout = gpu.bind_group_layout("gpurt wave dispatches", &[ReadWrite]);
        let pipeline_layout =
            gpu.pipeline_layout("gpurt wave", &[Some(main_layout), None, Some(&layout)]);
        let advance_layout = gpu.pipeline_layout(
            "gpurt wave advance",
            &[None, None, Some(&layout), Some(&args_layout)],
        );
        WavePipelines {
            layout,
            args_layout,
            pipeline_layout,
            advance_layout,
            modules,
            compiled: Mutex::new(HashMap::new()),
        }
    }

    /// The kernels for a specialisation, compiled the first time.
    pub(super) fn get(&self, gpu: &Device, spec: Specialization) -> Result<Arc<Kernels>> {
        let mut compiled = self.compiled.lock().expect("not poisoned");
        if let Some(k) = compiled.get(&spec) {
            return Ok(k.clone());
        }
        let mut made = Vec::with_capacity(ENTRIES.len());
        for entry in ENTRIES {
            let layout = match entry.starts_with("wf_advance") {
                true => &self.advance_layout,
                false => &self.pipeline_layout,
            };
            made.push(compile(gpu, layout, &self.modules, entry, spec, None)?);
        }
        let [generate, advance_rays, extend, shadow, advance_shade, shade] =
            <[_; 6]>::try_from(made).unwrap_or_else(|_| unreachable!("one pipeline an entry"));
        let kernels = Arc::new(Kernels {
            generate,
            advance_rays,
            extend,
            shadow,
            advance_shade,
            shade,
        });
        compiled.insert(spec, kernels.clone());
        Ok(kernels)
    }
}

/// A scene's wave on the device: room for `capacity` pixels, the kernels it runs, and
/// the buffer its queue lengths are read back through (read by `waves`, native only).
#[cfg_attr(not(feature = "native"), allow(dead_code))]
pub(super) struct Wave {
    pub(super) kernels: Arc<Kernels>,
    pub(super) group: wgpu::BindGroup,
    pub(super) args_group: wgpu::BindGroup,
    pub(super) counts: wgpu::Buffer,
    pub(super) counts_back: wgpu::Buffer,
    pub(super) args: wgpu::Buffer,
    pub(super) capacity: u32,
    /// Device memory the wave holds, in bytes.
    pub(super) bytes: u64,
}

impl Wave {
    /// A wave of `capacity` pixels for the kernels of `spec` (whose ray stack holds
    /// `spec.trace_stack` rays).
    pub(super) fn new(
        gpu: &Device,
        pipelines: &WavePipelines,
        spec: Specialization,
        capacity: u32,
    ) -> Result<Wave> {
        let kernels = pipelines.get(gpu, spec)?;
        gpu.scoped("making the wave", || {
            let pixels = u64::from(capacity.max(1));
            let state_bytes = pixels * wave_state_bytes(spec.trace_stack);
            let state = gpu.output("wave state", state_bytes);
            // Three queues of two halves.
            let queues = gpu.output("wave queues", 6 * 4 * pixels);
            let counts = gpu.output("wave counts", 4 * COUNT_WORDS);
            let counts_back = gpu.readback("wave counts readback", 4 * COUNT_WORDS);
            let args = gpu.indirect_args("wave dispatches", 4 * ARG_WORDS);
            let group = gpu.bind_group(
                "gpurt wave",
                &pipelines.layout,
                [&state, &queues, &counts]
                    .map(|b| b.as_entire_binding())
                    .into(),
            );
            let args_group = gpu.bind_group(
                "gpurt wave dispatches",
                &pipelines.args_layout,
                vec![args.as_entire_binding()],
            );
            Wave {
                kernels,
                group,
                args_group,
                counts,
                counts_back,
                args,
                capacity,
                bytes: state_bytes + 6 * 4 * pixels + 8 * COUNT_WORDS + 4 * ARG_WORDS,
            }
        })
    }
}
