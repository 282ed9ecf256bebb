//! The wavefront path's pipelines and buffers: the kernels of `shaders/wavefront.wgsl`
//! (compiled once per `Specialization`, like `main`), and for an uploaded scene a wave:
//! a path per pixel sample of a tile's pass, the rays of a round (two halves), their hits
//! and shadow slots, the shadow queue, the workgroups' first rays, the counts and the
//! sizes of the indirect dispatches. The dispatches that run a wave are `waves`'.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use super::cut::Cut;
use super::device::{Device, Slot};
use super::pipeline::{Modules, compile, storage_buffers};
use super::shaders::Fetch;
use super::specialization::Specialization;
use crate::gpu_types::{GpuGlobals, WAVE_COUNT_WORDS, wave_buffer_bytes};
use crate::util::error::Result;

/// Paths a wave holds for frames cut as `cut`: a tile's pixels times a pass's samples.
pub(super) fn wave_paths(cut: &Cut) -> u32 {
    cut.tile_width * cut.tile_rows * cut.pass_samples
}

/// The kernels, in the order `Kernels` holds their pipelines (and a `Clock` its times).
pub(crate) const ENTRIES: [&str; 9] = [
    "wf_generate",
    "wf_advance",
    "wf_extend",
    "wf_scan",
    "wf_shade",
    "wf_advance_shadows",
    "wf_shadow",
    "wf_gather",
    "wf_finish",
];

/// Indices in `ENTRIES` (and in `Kernels`), by kernel (read by `waves`, native only).
#[cfg_attr(not(feature = "native"), allow(dead_code))]
pub(super) mod kernel {
    pub(in crate::gpu) const GENERATE: usize = 0;
    pub(in crate::gpu) const ADVANCE: usize = 1;
    pub(in crate::gpu) const EXTEND: usize = 2;
    pub(in crate::gpu) const SCAN: usize = 3;
    pub(in crate::gpu) const SHADE: usize = 4;
    pub(in crate::gpu) const ADVANCE_SHADOWS: usize = 5;
    pub(in crate::gpu) const SHADOW: usize = 6;
    pub(in crate::gpu) const GATHER: usize = 7;
    pub(in crate::gpu) const FINISH: usize = 8;
}

/// Compute passes a tile's wave of `rounds` rounds takes, one dispatch each: `wf_generate`,
/// every kernel between it and `wf_finish` once a round, then `wf_finish`.
pub(super) fn wave_passes(rounds: u32) -> u32 {
    2 + (ENTRIES.len() as u32 - 2) * rounds
}

/// The pipelines of the kernels, in `ENTRIES` order. Read by `waves`, which runs natively
/// only.
pub(super) type Kernels = [wgpu::ComputePipeline; ENTRIES.len()];

/// Storage buffers of group 2 (the wave), bound with group 0 to every kernel but the two
/// that size the dispatches (groups 2 and 3).
const WAVE_BINDINGS: u32 = 7;

/// Whether an adapter of `limits` binds the kernels' storage buffers, group 0 reading the
/// scene as `fetch` says: 13 or 16, past the 10 that browsers' WebGPU (and
/// `wgpu::Limits::default`) grant; frames elsewhere take the one kernel.
pub(super) fn wave_binds(limits: &wgpu::Limits, fetch: Fetch) -> bool {
    limits.max_storage_buffers_per_shader_stage >= storage_buffers(fetch) + WAVE_BINDINGS
}

/// Words of `wave_args`: the dispatch over a round's rays, then over its shadow rays.
const ARG_WORDS: u64 = 6;
/// Offset in `wave_args` of the dispatch over a round's shadow rays (read by `waves`,
/// native only).
#[cfg_attr(not(feature = "native"), allow(dead_code))]
pub(super) const SHADOW_ARGS: u64 = 12;

/// Group 2 of the kernels (the wave), group 3 (the dispatch sizes), their pipeline
/// layouts, and their pipelines compiled so far, one set per `Specialization`, shared by
/// every scene a `GpuRenderer` uploads.
pub(super) struct WavePipelines {
    layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    /// Groups 0 and 2, for the kernels that trace, shade and sum; groups 2 and 3 for the
    /// two that size the dispatches.
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
        let layout = gpu.bind_group_layout("gpurt wave", &[ReadWrite; WAVE_BINDINGS as usize]);
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
        let kernels: Arc<Kernels> = Arc::new(
            made.try_into()
                .unwrap_or_else(|_| unreachable!("one pipeline an entry")),
        );
        compiled.insert(spec, kernels.clone());
        Ok(kernels)
    }
}

/// Times a wave's dispatches with timestamp queries (`GpuScene::time_kernels`): a query
/// before and after each of a tile's `passes` compute passes, resolved and read back
/// after each tile, and the GPU time of each kernel summed in `seconds` (`ENTRIES`
/// order) over the tiles traced since.
#[cfg_attr(not(feature = "native"), allow(dead_code))]
pub(super) struct Clock {
    pub(super) queries: wgpu::QuerySet,
    pub(super) resolve: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    pub(super) passes: u32,
    pub(super) seconds: Mutex<[f64; ENTRIES.len()]>,
}

impl Clock {
    /// A clock for waves of `rounds` rounds (`wave_passes` a tile), where the device has
    /// timestamps and a query set holds them.
    pub(super) fn new(gpu: &Device, rounds: u32) -> Option<Clock> {
        let passes = wave_passes(rounds);
        if 2 * passes > wgpu::QUERY_SET_MAX_QUERIES {
            return None;
        }
        let (queries, resolve) = gpu.timestamps("wave clock", 2 * passes)?;
        let readback = gpu.readback("wave clock readback", 16 * u64::from(passes));
        Some(Clock {
            queries,
            resolve,
            readback,
            passes,
            seconds: Mutex::new([0.0; ENTRIES.len()]),
        })
    }
}

/// A scene's wave on the device: room for `capacity` paths (pixel samples) of a scene
/// with `lights` lights, the kernels it runs, and the rounds a wave takes, one per depth
/// (read by `waves`, native only).
#[cfg_attr(not(feature = "native"), allow(dead_code))]
pub(super) struct Wave {
    pub(super) kernels: Arc<Kernels>,
    pub(super) group: wgpu::BindGroup,
    pub(super) args_group: wgpu::BindGroup,
    pub(super) counts: wgpu::Buffer,
    pub(super) args: wgpu::Buffer,
    pub(super) capacity: u32,
    pub(super) lights: u32,
    pub(super) depth: u32,
    /// Times the kernels when set (`GpuScene::time_kernels`).
    pub(super) clock: Option<Clock>,
    /// Device memory the wave holds, in bytes.
    pub(super) bytes: u64,
}

impl Wave {
    /// The rounds a tile's wave takes: one a depth, at least one.
    pub(super) fn rounds(&self) -> u32 {
        self.depth.max(1)
    }

    /// A wave of `capacity` paths for the kernels of `spec`, for frames of `globals`.
    pub(super) fn new(
        gpu: &Device,
        pipelines: &WavePipelines,
        spec: Specialization,
        capacity: u32,
        globals: &GpuGlobals,
    ) -> Result<Wave> {
        let lights = globals.n_lights;
        let kernels = pipelines.get(gpu, spec)?;
        gpu.scoped("making the wave", || {
            let sizes = wave_buffer_bytes(u64::from(capacity.max(1)), u64::from(lights));
            let labels = [
                "wave paths",
                "wave rays",
                "wave hits",
                "wave shadows",
                "wave shadow queue",
                "wave scan",
            ];
            let mut buffers: Vec<_> = labels
                .iter()
                .zip(sizes)
                .map(|(label, size)| gpu.output(label, size))
                .collect();
            let counts_bytes = 4 * u64::from(WAVE_COUNT_WORDS);
            buffers.push(gpu.output("wave counts", counts_bytes));
            let args = gpu.indirect_args("wave dispatches", 4 * ARG_WORDS);
            let group = gpu.bind_group(
                "gpurt wave",
                &pipelines.layout,
                buffers.iter().map(|b| b.as_entire_binding()).collect(),
            );
            let args_group = gpu.bind_group(
                "gpurt wave dispatches",
                &pipelines.args_layout,
                vec![args.as_entire_binding()],
            );
            let counts = buffers.pop().expect("the counts were pushed last");
            Wave {
                kernels,
                group,
                args_group,
                counts,
                args,
                capacity,
                lights,
                depth: globals.max_depth,
                clock: None,
                bytes: sizes.iter().sum::<u64>() + counts_bytes + 4 * ARG_WORDS,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{ENTRIES, Fetch, kernel, wave_binds};

    /// Each kernel's index names its entry point.
    #[test]
    fn the_kernel_indices_name_their_entries() {
        let named = [
            (kernel::GENERATE, "wf_generate"),
            (kernel::ADVANCE, "wf_advance"),
            (kernel::EXTEND, "wf_extend"),
            (kernel::SCAN, "wf_scan"),
            (kernel::SHADE, "wf_shade"),
            (kernel::ADVANCE_SHADOWS, "wf_advance_shadows"),
            (kernel::SHADOW, "wf_shadow"),
            (kernel::GATHER, "wf_gather"),
            (kernel::FINISH, "wf_finish"),
        ];
        assert_eq!(named.len(), ENTRIES.len());
        for (i, name) in named {
            assert_eq!(ENTRIES[i], name);
        }
    }

    /// The default of 10 storage buffers a stage (WebGPU's) binds the kernels neither way
    /// of reading the scene; 13 binds them with the scene in textures only, 16 both ways.
    #[test]
    fn the_kernels_bind_where_the_adapter_has_the_storage_buffers() {
        let limits = |n| wgpu::Limits {
            max_storage_buffers_per_shader_stage: n,
            ..wgpu::Limits::default()
        };
        for (n, textures, buffers) in [(10, false, false), (13, true, false), (16, true, true)] {
            assert_eq!(wave_binds(&limits(n), Fetch::Textures), textures, "{n}");
            assert_eq!(wave_binds(&limits(n), Fetch::Buffers), buffers, "{n}");
        }
        assert!(!wave_binds(&wgpu::Limits::default(), Fetch::Textures));
    }
}
