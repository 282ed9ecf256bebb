//! What a frame takes on this adapter: which walk of the BVH, chosen per adapter by what
//! was measured and overridable from the environment for measuring the walks side by
//! side; and how the frame is cut into work.

use super::cut::Cut;
use crate::error::{Error, Result};
use crate::gpu_types::{GpuGlobals, TRAVERSAL_NAMES, TRAVERSAL_WIDE};

/// The traversal for an adapter: `TRAVERSAL_WIDE` on every adapter (each scene falls back
/// to pairs where its wide tree does not fit the stack). On the H100 a ray's time goes to
/// waiting on node fetches, and the four-wide tree halves the chain of them: 1.2 to 1.5
/// times faster than pairs, which was 1.2 to 1.4 times faster than single. On lavapipe it
/// is 2 to 19% faster than single (docs/gpu.md has the figures). The compressed
/// eight-wide walk (`TRAVERSAL_CWIDE`) is not the default until measured on a GPU.
/// `GPURT_TRAVERSAL` (`single`, `pairs`, `wide` or `cwide`: `TRAVERSAL_NAMES`) overrides
/// it, for measuring them on one adapter.
pub(super) fn traversal_from_env() -> Result<u32> {
    match std::env::var("GPURT_TRAVERSAL").as_deref() {
        Err(_) | Ok("") => Ok(TRAVERSAL_WIDE),
        Ok(v) => match TRAVERSAL_NAMES.iter().position(|&n| n == v) {
            Some(t) => Ok(t as u32),
            None => Err(Error::Render(format!(
                "GPURT_TRAVERSAL={v}: expected one of {}",
                TRAVERSAL_NAMES.join(", ")
            ))),
        },
    }
}

/// How a frame of `globals`' size and samples is cut on this device. Software adapters
/// get small bands so that Ctrl-C and the progress bar respond within a second, and one
/// sample per pass: lavapipe ends every loop once an invocation has run 65535 loop
/// iterations in all, and one sample of an ordinary scene needs far fewer. GPUs take up
/// to 16 samples per pass, and a band is the most one submission should hold.
pub(super) fn cut_for(limits: &wgpu::Limits, globals: &GpuGlobals, software: bool) -> Cut {
    let (pass_samples, band_samples) = if software {
        (1, 1 << 18)
    } else {
        (16, 1 << 26)
    };
    Cut::new(
        globals.width,
        globals.height,
        globals.spp,
        pass_samples,
        band_samples,
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size),
        // Software adapters split a dispatch among their threads in fixed runs; a GPU's
        // own scheduler balances, and neighbouring blocks share its caches.
        software,
    )
}
