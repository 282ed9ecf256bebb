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

/// Upper bound on a gzip file's decompressed bytes: guards against gzip bombs. The
/// readers stream, so a bomb no longer costs memory, but it would cost time (a plain
/// file is as long as it is on disk, and has no limit).
pub const MAX_FILE_BYTES: u64 = 4 << 30;
/// Most texels a scene's textures may hold together (16 bytes each on the device and in
/// memory: 1 GiB).
pub const MAX_TEXELS: u64 = 1 << 26;
/// Most bytes an image file of a texture may have, and most its decoder may allocate:
/// `MAX_TEXELS` of sixteen-bit RGBA.
pub const MAX_IMAGE_BYTES: u64 = MAX_TEXELS * 8;
/// Most bytes of glTF JSON read (a `.gltf`, or a `.glb`'s JSON chunk): the JSON is parsed
/// whole, and only data URIs make it this large, each held three times over while it is
/// parsed and decoded. A buffer of more belongs in a `.bin` file or a `.glb`'s binary chunk.
pub const MAX_GLTF_JSON_BYTES: u64 = 256 << 20;

/// Longest token the text readers take (a number, keyword or path is far shorter): a
/// longer one, such as a binary file read as text, is an error, not a growing buffer.
pub const MAX_TOKEN_BYTES: usize = 64 << 10;

/// Most bounded primitives (spheres, triangles, cones, boxes) a scene may hold: well
/// within every index of the packed layout, and about 27 GB at the peak of its loading.
pub const MAX_PRIMITIVES: usize = 1 << 28;

/// Most vertices of one polygon (NFF `p`, `pp`; an OBJ face), held until it is
/// triangulated: where the rest of the file's length is unknown (gzip), a lying count is
/// caught here instead of by the vertices running out.
pub const MAX_POLYGON_VERTICES: u32 = 1 << 20;

/// Most vertex positions, and most normals, an OBJ file may define: they are held until
/// the file ends, since a face may refer to any of them.
pub const MAX_MESH_VERTICES: usize = 1 << 28;

/// Largest light, ambient and background colour component; larger ones are held to it with
/// a warning. Material colours, Kd, Ks and T are held to [0, 1]. Within these ranges every
/// pixel stays finite: shading.md sums a bounded number of bounded terms.
pub const MAX_LIGHT: f32 = 1e6;
/// Largest Phong exponent; a negative one (which would make highlights infinite) is held
/// to 0, a larger one to this.
pub const MAX_SHINE: f32 = 1e6;
/// Most samples an area light (`al`) may take along each of its edges.
pub const MAX_AREA_LIGHT_SAMPLES: u32 = 64;
