//! A scene's state on the device: its arrays (`upload`), what a frame binds besides them
//! (`Bound`), the pipeline its frame's settings need (and the wave of the wavefront
//! path) and how its frames are cut. The
//! renderer makes it and moves it to other frames; the dispatch loop and `resume` trace
//! it (the loop notes in it a finer cut when dispatches run long), so it sits below all
//! three.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::cut::{Cut, PIXEL_BYTES};
use super::device::Device;
use super::pipeline::ResumePipelines;
use super::specialization::Specialization;
use super::upload::SceneData;
use super::wavefront::{Clock, ENTRIES, Wave};
use crate::counters::Counters;
use crate::gpu_types::{GpuGlobals, GpuPixelCounts, GpuTile};
use crate::util::error::Result;

/// A scene on the device with the bindings and pipeline for one frame's settings.
pub struct GpuScene {
    pub(super) data: SceneData,
    pub(super) bound: Bound,
    pub(super) pipeline: wgpu::ComputePipeline,
    pub(super) cut: Cut,
    /// Device memory held by the scene's textures and buffers, in bytes.
    pub(super) scene_bytes: u64,
    pub(super) resume: Arc<ResumePipelines>,
    pub(super) spec: Specialization,
    pub(super) dispatch_budget: Option<Duration>,
    /// The cut that dispatches over `dispatch_budget` made `trace_rows` switch to, kept
    /// for the frames after (until `set_frame` changes the cut).
    pub(super) finer: Mutex<Option<Cut>>,
    /// Bytes a node fetch of the frame's walk reads (`counters::gpu_node_bytes`).
    pub(super) node_bytes: u64,
    /// The wave the frame's wavefront kernels run in, when it takes that path
    /// (`GpuGlobals::wavefront`).
    pub(super) wave: Option<Wave>,
    /// What the last trace counted, when its frame counts (`GpuGlobals::counters`).
    pub(super) counted: Mutex<Option<Counters>>,
    /// Pixels the last trace finished in `resume` (`resumed`).
    pub(super) resumed: AtomicU64,
}

impl GpuScene {
    /// Rows of a tile and samples a pass of the dispatches traced now: the cut made for
    /// the frame, or a finer one (`DISPATCH_BUDGET`).
    pub fn dispatch_shape(&self) -> (u32, u32) {
        let cut = self.tracing_cut();
        (cut.tile_rows, cut.pass_samples)
    }

    pub(super) fn tracing_cut(&self) -> Cut {
        self.finer.lock().expect("cut lock").unwrap_or(self.cut)
    }

    /// The rays and node fetches by kind of the last frame traced, when its frame counts
    /// them (`GpuGlobals::counters`): every rows and samples traced since the frame was
    /// set, the frame's last trace only.
    pub fn counters(&self) -> Option<Counters> {
        *self.counted.lock().expect("counts lock")
    }

    /// Pixels the last trace handed to `resume` (pixel.wgsl) because their first dispatch
    /// did not finish them: those a driver's loop limit cut short (lavapipe's), and on the
    /// wavefront kernels those whose paths outgrew the wave. The tests of those pixels
    /// check that they were met, not only that the images agree.
    pub fn resumed(&self) -> u64 {
        self.resumed.load(Ordering::Relaxed)
    }

    /// Times each wavefront kernel of the frames traced from now on (timestamp queries
    /// around every dispatch, read back after each tile: the frames run slower), where
    /// the frame takes the wavefront kernels and the device has timestamps; `set_frame`
    /// stops it where it remakes the wave or changes its depth. Returns whether it will.
    pub fn time_kernels(&mut self, device: &wgpu::Device) -> bool {
        let Some(wave) = self.wave.as_mut() else {
            return false;
        };
        wave.clock = Clock::new(&Device::new(device), wave.rounds());
        wave.clock.is_some()
    }

    /// The GPU time each wavefront kernel took, in seconds, by name (`wf_generate`, ...),
    /// over the frames traced since `time_kernels`; none where they are not timed.
    pub fn kernel_times(&self) -> Option<Vec<(&'static str, f64)>> {
        let clock = self.wave.as_ref()?.clock.as_ref()?;
        let seconds = *clock.seconds.lock().expect("clock lock");
        Some(ENTRIES.into_iter().zip(seconds).collect())
    }

    /// Device memory held by the scene and a band's output and readback buffers, in bytes.
    pub fn device_bytes(&self) -> u64 {
        let wave = self.wave.as_ref().map_or(0, |w| w.bytes);
        self.scene_bytes + 2 * self.cut.band_bytes() + wave
    }
}

/// What a frame binds besides the scene: its constants (a buffer rewritten when only
/// the camera or the other constants change), the tiles, and a band's output and the
/// buffer it is read back through (remade when the image size or the cut changes).
pub(super) struct Bound {
    pub(super) bind_group: wgpu::BindGroup,
    pub(super) globals: wgpu::Buffer,
    /// One `GpuTile` per dispatch of a band, `tile_stride` bytes apart (dynamic offsets).
    pub(super) tile_buf: wgpu::Buffer,
    pub(super) tile_stride: u32,
    pub(super) output: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    /// The band's `GpuPixelCounts` and the buffer they are read back through, when the
    /// frame counts (`GpuGlobals::counters`); one unused entry each otherwise.
    pub(super) counts: wgpu::Buffer,
    pub(super) counts_back: wgpu::Buffer,
    pub(super) counting: bool,
}

impl Bound {
    /// Encodes the clearing of the output (and counts) of a band of `pixels` pixels,
    /// before its first samples: each pass adds to what the passes before left.
    pub(super) fn clear(&self, enc: &mut wgpu::CommandEncoder, pixels: u64) {
        enc.clear_buffer(&self.output, 0, Some(pixels * PIXEL_BYTES));
        if self.counting {
            let count_bytes = pixels * size_of::<GpuPixelCounts>() as u64;
            enc.clear_buffer(&self.counts, 0, Some(count_bytes));
        }
    }
}

/// Creates a frame's constants and tile slots, its band output and readback buffers, and the bind
/// group that joins them to the scene's arrays.
pub(super) fn bind(
    gpu: &Device,
    layout: &wgpu::BindGroupLayout,
    data: &SceneData,
    globals: &GpuGlobals,
    out_bytes: u64,
    tile_slots: u32,
) -> Result<Bound> {
    gpu.scoped("binding the frame", || {
        let globals_buf = gpu.constants("globals", bytemuck::bytes_of(globals));
        let tile_size = size_of::<GpuTile>() as u64;
        let (tile_buf, tile_stride) = gpu.uniform_records("tiles", tile_size, tile_slots);
        let output = gpu.output("output", out_bytes);
        let readback = gpu.readback("readback", out_bytes);
        // Twice the output when counting (`GpuPixelCounts` is twice `PixelOut`).
        let count_bytes = match globals.counters {
            0 => size_of::<GpuPixelCounts>() as u64,
            _ => out_bytes / PIXEL_BYTES * size_of::<GpuPixelCounts>() as u64,
        };
        let counts = gpu.output("counts", count_bytes);
        let counts_back = gpu.readback("counts readback", count_bytes);
        let resources = vec![
            globals_buf.as_entire_binding(),
            wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer: &tile_buf,
                offset: 0,
                size: wgpu::BufferSize::new(tile_size),
            }),
            data.nodes.binding(),
            data.prims.binding(),
            data.tri_normals.binding(),
            data.planes.as_entire_binding(),
            data.materials.as_entire_binding(),
            data.lights.as_entire_binding(),
            output.as_entire_binding(),
            counts.as_entire_binding(),
        ];
        let bind_group = gpu.bind_group("gpurt", layout, resources);
        Bound {
            bind_group,
            globals: globals_buf,
            tile_buf,
            tile_stride,
            output,
            readback,
            counts,
            counts_back,
            counting: globals.counters != 0,
        }
    })
}
