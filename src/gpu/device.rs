//! The wgpu calls every other part of the renderer makes through one door: error scopes
//! that turn wgpu's errors into `Error::Gpu`, waiting on the device, mapping a readback
//! buffer, and a buffer made from bytes without wgpu's panicking helper. Kept apart so
//! that what a failure of the device looks like is decided once (the viewer uses them too).

use crate::error::{Error, Result};

/// Runs `f` inside validation and out-of-memory error scopes, turning any captured error
/// into `Error::Gpu` (never a silent black image). An out-of-memory error is the one
/// reported when both come: a resource that could not be allocated is invalid, and every
/// later use of it is a validation error that hides the cause.
#[cfg(not(target_arch = "wasm32"))]
pub(crate) fn scoped<T>(device: &wgpu::Device, what: &str, f: impl FnOnce() -> T) -> Result<T> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = f();
    let v = pollster::block_on(validation.pop());
    let o = pollster::block_on(oom.pop());
    match o.or(v) {
        Some(e) => Err(Error::Gpu(format!("{what}: {}", error_chain(&e)))),
        None => Ok(out),
    }
}

/// `scoped` in the browser, where a scope's errors arrive only after control has gone back
/// to the page's event loop, and no thread may block for them: `f` runs unscoped, and the
/// device's uncaptured-error handler (installed by the page, `web/`) reports what fails.
#[cfg(target_arch = "wasm32")]
pub(crate) fn scoped<T>(_: &wgpu::Device, _: &str, f: impl FnOnce() -> T) -> Result<T> {
    Ok(f())
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

/// Blocks until the GPU has finished everything submitted.
pub(crate) fn wait(device: &wgpu::Device) -> Result<()> {
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| Error::Gpu(format!("waiting for the GPU: {e}")))
}

/// Maps the first `bytes` of a readback buffer, hands them to `f`, unmaps. Natively the
/// mapping is complete once the device has been waited for, and the await returns at
/// once; in the browser, where waiting on the device does nothing, the await gives way to
/// the page's event loop until the browser has mapped the buffer.
pub(crate) async fn read_mapped_async<T>(
    device: &wgpu::Device,
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
    wait(device)?;
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

/// `read_mapped_async` for a caller that may block (not the browser's).
#[cfg(feature = "native")]
pub(crate) fn read_mapped<T>(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    bytes: u64,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    pollster::block_on(read_mapped_async(device, buffer, bytes, f))
}

/// A buffer holding `contents`: `DeviceExt::create_buffer_init` without its panic. On a
/// lost device wgpu hands back an invalid buffer that cannot be mapped, and its helper
/// unwraps the mapping; here the copy is skipped, and the error scope around the call
/// (`scoped`) reports the invalid buffer as an error naming what was being done.
pub(crate) fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let align = wgpu::COPY_BUFFER_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (contents.len() as u64).next_multiple_of(align).max(align),
        usage,
        mapped_at_creation: true,
    });
    // Every caller's contents are whole 4-byte words, as a mapped range must be.
    if let Ok(mut view) = buffer.slice(..contents.len() as u64).get_mapped_range_mut() {
        view.copy_from_slice(contents);
    }
    buffer.unmap();
    buffer
}
