//! The one door to wgpu's device and queue: every other module of the renderer asks these
//! two types for what it needs, in the renderer's own terms (a scene's arrays, a frame's
//! constants and outputs, readbacks, the shader's layouts and pipelines, submissions), and
//! never calls a method of `wgpu::Device` or `wgpu::Queue` itself
//! (`tests/gpurt/architecture.rs` checks it). So what a failure of the device looks like
//! (error scopes, waits, mappings) and how each kind of resource is made is decided once,
//! and the other modules read as the renderer's logic. The viewer uses `Device` too.
//!
//! `Device` borrows the device: what is made on it, error scopes, waits and readbacks.
//! `Gpu` adds the queue: writes and submissions. Both are made where a public entry point
//! receives wgpu's device and queue, and handed down. What is made is apart:
//! `resources` (buffers and textures of each kind the renderer uses) and `pipelines`
//! (bind group layouts, shader modules, pipelines and their cache).

mod pipelines;
#[cfg(feature = "native")]
mod raster;
mod resources;

use std::ops::Deref;

use crate::util::error::{Error, Result};

pub(crate) use pipelines::Slot;
pub(crate) use resources::TEXEL_FORMAT;

/// Longest the host waits for the GPU to finish what it was given (`Device::wait`): far
/// beyond any submission's work, which is cut to a fraction of a second on a GPU
/// (`DISPATCH_BUDGET` a dispatch) and to about a second of lavapipe's time (2^18 pixel
/// samples), deep glass and many area lights included.
pub const WAIT_LIMIT: std::time::Duration = std::time::Duration::from_secs(600);

/// `WAIT_LIMIT`, or `GPURT_WAIT_LIMIT` (seconds) where set: shorter to turn a stalled GPU
/// into errors soon (the device script's test runs), or to test the limit.
fn wait_limit() -> Result<std::time::Duration> {
    match std::env::var("GPURT_WAIT_LIMIT").as_deref() {
        Err(_) | Ok("") => Ok(WAIT_LIMIT),
        Ok(v) => match v.parse::<f64>() {
            Ok(s) if s > 0.0 && s <= 1e9 => Ok(std::time::Duration::from_secs_f64(s)),
            _ => Err(Error::Render(format!(
                "GPURT_WAIT_LIMIT={v}: expected seconds above 0"
            ))),
        },
    }
}

/// The device, borrowed: what the renderer makes on it, error scopes, waits and readbacks.
#[derive(Clone, Copy)]
pub(crate) struct Device<'a> {
    device: &'a wgpu::Device,
}

/// The device and its queue: a `Device` that also writes to buffers and textures and
/// submits work.
#[derive(Clone, Copy)]
pub(crate) struct Gpu<'a> {
    device: Device<'a>,
    queue: &'a wgpu::Queue,
}

impl<'a> Deref for Gpu<'a> {
    type Target = Device<'a>;
    fn deref(&self) -> &Device<'a> {
        &self.device
    }
}

impl<'a> Device<'a> {
    pub(crate) fn new(device: &'a wgpu::Device) -> Self {
        Device { device }
    }

    /// Runs `f` inside validation, internal and out-of-memory error scopes, turning any
    /// captured error into `Error::Gpu` naming `what` was being done (never a silent black
    /// image, nor wgpu's panic for an uncaptured error). An internal error is a driver's
    /// or a shader translator's (a pipeline its GLSL compiler refuses). An out-of-memory
    /// error is the one reported when several come: a resource that could not be allocated
    /// is invalid, and every later use of it is a validation error that hides the cause.
    #[cfg(not(target_arch = "wasm32"))]
    pub(crate) fn scoped<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let v = pollster::block_on(validation.pop());
        let i = pollster::block_on(internal.pop());
        let o = pollster::block_on(oom.pop());
        match o.or(i).or(v) {
            Some(e) => Err(Error::Gpu(format!("{what}: {}", error_chain(&e)))),
            None => Ok(out),
        }
    }

    /// `scoped` in the browser, where a scope's errors arrive only after control has gone
    /// back to the page's event loop, and no thread may block for them: `f` runs unscoped,
    /// and the device's uncaptured-error handler (installed by the page, `web/`) reports
    /// what fails.
    #[cfg(target_arch = "wasm32")]
    pub(crate) fn scoped<T>(&self, _what: &str, f: impl FnOnce() -> T) -> Result<T> {
        Ok(f())
    }

    /// Blocks until the GPU has finished everything submitted, or fails once it has
    /// waited `wait_limit()`: a device that stops finishing its work (a driver's fault,
    /// a device lost whose fences never signal) ends the render with an error, never a
    /// hang.
    pub(crate) fn wait(&self) -> Result<()> {
        let limit = wait_limit()?;
        let wait = wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(limit),
        };
        self.device.poll(wait).map(|_| ()).map_err(|e| match e {
            wgpu::PollError::Timeout => Error::Gpu(format!(
                "the GPU did not finish its work within {} s: the device is hung or lost \
                 (GPURT_WAIT_LIMIT sets the limit)",
                limit.as_secs_f64()
            )),
            e => Error::Gpu(format!("waiting for the GPU: {e}")),
        })
    }

    /// Maps the first `bytes` of a readback buffer (`readback`) once the work submitted
    /// before has run, hands them to `f`, unmaps. Natively the mapping is complete once the
    /// device has been waited for, and the await returns at once; in the browser, where
    /// waiting on the device does nothing, the await gives way to the page's event loop
    /// until the browser has mapped the buffer.
    pub(crate) async fn read_async<T>(
        &self,
        buffer: &wgpu::Buffer,
        bytes: u64,
        f: impl FnOnce(&[u8]) -> T,
    ) -> Result<T> {
        let slice = buffer.slice(..bytes);
        let (tx, rx) = futures_channel::oneshot::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        // A lost device or a hung submission surfaces here as a poll error.
        self.wait()?;
        rx.await
            .map_err(|_| Error::Gpu("readback was never completed".into()))?
            .map_err(|e| Error::Gpu(format!("reading back: {e}")))?;
        let out = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| Error::Gpu(format!("reading back: {e}")))?;
            f(&view)
        };
        buffer.unmap();
        Ok(out)
    }

    /// `read_async` for a caller that may block (not the browser's).
    #[cfg(feature = "native")]
    pub(crate) fn read<T>(
        &self,
        buffer: &wgpu::Buffer,
        bytes: u64,
        f: impl FnOnce(&[u8]) -> T,
    ) -> Result<T> {
        pollster::block_on(self.read_async(buffer, bytes, f))
    }

    // ---- what the device is ----

    /// Destroys the device, work in flight included: `GPURT_FAULT=lose-device`'s fault
    /// (`util/fault.rs`), which the tests bring about to see a lost device reported.
    #[cfg(feature = "native")]
    pub(crate) fn lose(&self) {
        self.device.destroy();
    }

    /// Whether the device is a CPU (lavapipe and the like): the renderer cuts its work
    /// smaller there, and sets no dispatch budget.
    pub(crate) fn runs_on_cpu(&self) -> bool {
        self.device.adapter_info().device_type == wgpu::DeviceType::Cpu
    }

    /// The adapter's name, for messages.
    pub(crate) fn adapter_name(&self) -> String {
        self.device.adapter_info().name
    }

    /// The device's limits (the sizes of textures, bindings and buffers it allows).
    pub(crate) fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }

    /// An encoder for a submission (`Gpu::run`).
    pub(crate) fn encoder(&self) -> wgpu::CommandEncoder {
        self.device.create_command_encoder(&Default::default())
    }
}

impl<'a> Gpu<'a> {
    pub(crate) fn new(device: &'a wgpu::Device, queue: &'a wgpu::Queue) -> Self {
        Gpu {
            device: Device::new(device),
            queue,
        }
    }

    /// Writes `bytes` into `buffer` at `offset`, in queue order: after the submissions
    /// before, before those after.
    pub(crate) fn write(&self, buffer: &wgpu::Buffer, offset: u64, bytes: &[u8]) {
        self.queue.write_buffer(buffer, offset, bytes);
    }

    /// Submits what `enc` encoded, after the writes queued before.
    pub(crate) fn run(&self, enc: wgpu::CommandEncoder) {
        self.queue.submit([enc.finish()]);
    }

    /// Nanoseconds a tick of a timestamp query (`Device::timestamps`) lasts (read by the
    /// wavefront's dispatch loop, native only).
    #[cfg_attr(not(feature = "native"), allow(dead_code))]
    pub(crate) fn timestamp_period(&self) -> f32 {
        self.queue.get_timestamp_period()
    }

    /// Submits the writes queued so far, with no other work.
    pub(crate) fn flush(&self) {
        self.queue.submit([]);
    }

    /// Submits the writes queued so far and waits for everything submitted.
    pub(crate) fn finish(&self) -> Result<()> {
        self.flush();
        self.wait()
    }
}

/// An error with its causes, on one line: wgpu's `Display` says "Validation Error" and
/// then the same causes again, indented over several lines, so only its first line is kept.
#[cfg(not(target_arch = "wasm32"))]
fn error_chain(e: &dyn std::error::Error) -> String {
    let shown = e.to_string();
    let mut s = shown.lines().next().unwrap_or_default().to_string();
    let mut source = e.source();
    while let Some(cause) = source {
        s.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    s
}
