//! Limits and defaults: image side, samples, depth, ambient, and the scene readers' safety
//! limits. A leaf that imports nothing, so that the readers, the packing, the frame, both
//! renderers and the command line all read one value without depending on each other.

/// Largest image side, from a scene's `resolution` or from the caller.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Samples per pixel when none are asked for.
pub const DEFAULT_SPP: u32 = 1;
/// Most samples per pixel a frame may ask for.
pub const MAX_SPP: u32 = 4096;
/// Most threads `--threads` may ask for: far more than any machine's cores, few enough
/// that a mistyped count cannot exhaust the process's threads.
pub const MAX_THREADS: u32 = 1024;

/// Maximum ray depth when none is asked for (the eye ray counts as 1); at most `MAX_DEPTH`.
pub const DEFAULT_DEPTH: u32 = 5;
/// The deepest ray (the eye ray counting as 1). It is also the length of the renderers'
/// pending-ray stack (`gpu_types::RAY_STACK`), which a Whitted path with depth limit D
/// never overflows: it never holds more than D pending rays.
pub const MAX_DEPTH: u32 = 16;

/// Ambient light when neither the scene (`am`) nor the caller sets one (shading.md).
pub const DEFAULT_AMBIENT: f32 = 0.1;

/// Upper bound on a decompressed file: guards against gzip bombs.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// Decompressed bytes `scene::io::decompress` holds before it knows the whole size: past
/// this, it counts the rest without keeping it, and decompresses again into a buffer of the
/// exact size only if the whole is within the limit. A gzip bomb then costs at most this
/// (and the doubling of a growing buffer) on its way to being refused, instead of the
/// limit; files up to this size (every shared scene) are decompressed once.
pub const HELD_BYTES: u64 = 64 << 20;

/// Largest light, ambient and background colour component; larger ones are held to it with
/// a warning. Material colours, Kd, Ks and T are held to [0, 1]. Within these ranges every
/// pixel stays finite: shading.md sums a bounded number of bounded terms.
pub const MAX_LIGHT: f32 = 1e6;
/// Largest Phong exponent; a negative one (which would make highlights infinite) is held
/// to 0, a larger one to this.
pub const MAX_SHINE: f32 = 1e6;
/// Most samples an area light (`al`) may take along each of its edges.
pub const MAX_AREA_LIGHT_SAMPLES: u32 = 64;
