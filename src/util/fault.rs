//! Faults the command line can be made to meet (`GPURT_FAULT`), so that its tests check
//! end to end what a user would see when a GPU fails: an error naming the step, a
//! non-zero exit, no output file. Each fault is a real failure of the device or its
//! driver, brought about at a chosen moment; nothing here fakes an error. One more is
//! a real waste of memory, so that the test guarding the renderer's peak memory can show
//! that it catches one.

use crate::util::error::{Error, Result};

/// A fault `GPURT_FAULT` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// `lose-device`: the device is destroyed once the first band of a render is in.
    LoseDevice,
    /// `out-of-memory`: the device is opened with small memory blocks (`memory_hints`),
    /// and each texture (or storage buffer, `Fetch::Buffers`) of the scene's nodes,
    /// primitives and normals is allocated with the process's address space capped
    /// at its size plus `OUT_OF_MEMORY_MARGIN` (`AddressSpaceCap`,
    /// `GpuRenderer::with_texture_margin`), so that the driver fails to allocate one
    /// larger than that, as on a device whose memory is full. A software adapter's device
    /// memory is the process's own (lavapipe cannot run out otherwise: its allocations
    /// are overcommitted, docs/gpu.md); on a GPU the cap meets only wgpu's host side.
    OutOfMemory,
    /// `keep-primitives`: a copy of the scene's primitives is made once the scene is
    /// packed and held until the image is written, as a copy kept past its use would be
    /// (tests/gpurt/memory.rs shows that its guard fails then).
    KeepPrimitives,
}

/// Room the `out-of-memory` fault leaves each texture allocation: a texture larger than
/// this cannot be allocated, provided it is also larger than glibc's 32 MiB mmap
/// threshold (a smaller one may come from heap space already mapped, freed by the BVH
/// build) and than wgpu's first memory block (8 MiB with `memory_hints`).
pub const OUT_OF_MEMORY_MARGIN: u64 = 8 << 20;

impl Fault {
    /// The fault `GPURT_FAULT` names, if any.
    pub fn from_env() -> Result<Option<Fault>> {
        match std::env::var("GPURT_FAULT").as_deref() {
            Err(_) | Ok("") => Ok(None),
            Ok("lose-device") => Ok(Some(Fault::LoseDevice)),
            Ok("out-of-memory") => Ok(Some(Fault::OutOfMemory)),
            Ok("keep-primitives") => Ok(Some(Fault::KeepPrimitives)),
            Ok(v) => Err(Error::Render(format!(
                "GPURT_FAULT={v}: expected `lose-device`, `out-of-memory` or `keep-primitives`"
            ))),
        }
    }
}

/// How wgpu should size its device memory blocks: as usual, but for the `out-of-memory`
/// fault, which wants each texture of a scene in an allocation of its own (a texture
/// suballocated from a block allocated earlier would need no new memory). With
/// `MemoryUsage` blocks start at 8 MiB, and a larger texture gets its own allocation.
pub fn memory_hints() -> wgpu::MemoryHints {
    match Fault::from_env() {
        Ok(Some(Fault::OutOfMemory)) => wgpu::MemoryHints::MemoryUsage,
        _ => wgpu::MemoryHints::default(),
    }
}

/// The process's address space capped (`RLIMIT_AS`) at its present size plus a margin,
/// until dropped, when the previous limit comes back. Linux only: the present size is
/// read from /proc.
pub struct AddressSpaceCap {
    #[cfg(target_os = "linux")]
    previous: libc::rlimit,
}

impl AddressSpaceCap {
    #[cfg(target_os = "linux")]
    pub fn new(margin: u64) -> Result<Self> {
        let fail = |what: &str| Error::Render(format!("capping the address space: {what}"));
        let status = std::fs::read_to_string("/proc/self/status")
            .map_err(|e| fail(&format!("/proc/self/status: {e}")))?;
        let size: u64 = status
            .lines()
            .find_map(|l| l.strip_prefix("VmSize:"))
            .and_then(|v| v.trim().strip_suffix("kB")?.trim().parse().ok())
            .ok_or_else(|| fail("no VmSize in /proc/self/status"))?;
        let mut previous = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: both pointers are to live `rlimit`s.
        unsafe {
            if libc::getrlimit(libc::RLIMIT_AS, &mut previous) != 0 {
                return Err(fail(&std::io::Error::last_os_error().to_string()));
            }
            let cap = libc::rlimit {
                rlim_cur: (size * 1024 + margin).min(previous.rlim_cur),
                rlim_max: previous.rlim_max,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &cap) != 0 {
                return Err(fail(&std::io::Error::last_os_error().to_string()));
            }
        }
        Ok(AddressSpaceCap { previous })
    }

    #[cfg(not(target_os = "linux"))]
    pub fn new(_margin: u64) -> Result<Self> {
        Err(Error::Render(
            "GPURT_FAULT=out-of-memory caps the address space, which needs Linux".into(),
        ))
    }
}

impl Drop for AddressSpaceCap {
    fn drop(&mut self) {
        // SAFETY: a pointer to a live `rlimit`, the limit read before the cap.
        #[cfg(target_os = "linux")]
        unsafe {
            libc::setrlimit(libc::RLIMIT_AS, &self.previous);
        }
    }
}
