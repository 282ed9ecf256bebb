//! The instruction sets the CPU renderer's SIMD code is compiled for, and their names in
//! `GPURT_SIMD`: one list for the packet kernels (`packet::Kernels`, which also say which
//! of them this machine runs) and for the single-ray walks (`isa::single_ray_v4`).

/// The instruction sets the packet kernels are compiled for, widest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    Avx512,
    Avx2,
    Sse,
    /// Plain arrays of four (NEON on AArch64, through LLVM).
    Portable,
}

impl Isa {
    pub const ALL: [Isa; 4] = [Isa::Avx512, Isa::Avx2, Isa::Sse, Isa::Portable];

    /// Its name in `GPURT_SIMD` and `--stats`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Avx512 => "avx512",
            Isa::Avx2 => "avx2",
            Isa::Sse => "sse",
            Isa::Portable => "portable",
        }
    }

    /// The instruction set of that name, if any.
    pub fn named(name: &str) -> Option<Isa> {
        Isa::ALL.into_iter().find(|i| i.name() == name)
    }

    /// Rays a packet holds.
    pub fn lanes(self) -> usize {
        match self {
            Isa::Avx512 => 16,
            Isa::Avx2 => 8,
            Isa::Sse | Isa::Portable => 4,
        }
    }
}
