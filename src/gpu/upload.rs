//! A scene's arrays on the device: uploaded once (nodes, primitives and triangle normals
//! as texture arrays, which grow by layers past one texture's size, or as storage
//! buffers, as the renderer's `Fetch` says; the small rest as storage buffers), checked
//! first against the device's limits.

use super::device::Gpu;
use super::shaders::Fetch;
use crate::gpu_types::{GpuLight, TEXTURE_WIDTH, TRAVERSAL_CWIDE, TRAVERSAL_QWIDE, TRAVERSAL_WIDE};
use crate::pack::SceneBuffers;
use crate::util::error::{Error, Result};
use crate::util::fault::AddressSpaceCap;

/// A scene's arrays on the device: uploaded once, bound into every frame rendered of it.
pub(super) struct SceneData {
    pub(super) nodes: Texels,
    pub(super) prims: Texels,
    pub(super) tri_normals: Texels,
    pub(super) planes: wgpu::Buffer,
    pub(super) materials: wgpu::Buffer,
    pub(super) lights: wgpu::Buffer,
}

/// One of the arrays the shader reads a texel at a time (`Fetch`): a texture array's
/// view, or a storage buffer.
pub(super) enum Texels {
    Texture(wgpu::TextureView),
    Buffer(wgpu::Buffer),
}

impl Texels {
    pub(super) fn binding(&self) -> wgpu::BindingResource<'_> {
        match self {
            Texels::Texture(view) => wgpu::BindingResource::TextureView(view),
            Texels::Buffer(buffer) => buffer.as_entire_binding(),
        }
    }
}

/// The bytes of the BVH the walk `traversal` reads: the wide nodes for `TRAVERSAL_WIDE`,
/// the compressed ones for `TRAVERSAL_CWIDE` and the quantised ones for
/// `TRAVERSAL_QWIDE` (which `SceneBuffers::traversal_for` picks only where they exist),
/// else the binary nodes.
/// Only the walk's own tree is asked for: each is built on first use, and the compressed
/// one brings a reordered copy of every primitive.
fn node_bytes(scene: &SceneBuffers, traversal: u32) -> &[u8] {
    match traversal {
        TRAVERSAL_WIDE => scene.gpu_wide_nodes().map(bytemuck::cast_slice),
        TRAVERSAL_CWIDE => scene.gpu_cwide().map(|c| bytemuck::cast_slice(&c.nodes)),
        TRAVERSAL_QWIDE => scene.gpu_qwide_nodes().map(bytemuck::cast_slice),
        _ => None,
    }
    .unwrap_or_else(|| bytemuck::cast_slice(&scene.nodes))
}

/// The primitives the walk `traversal` reads: in the compressed tree's order for
/// `TRAVERSAL_CWIDE`, else in the binary tree's.
fn prim_bytes(scene: &SceneBuffers, traversal: u32) -> &[u8] {
    match traversal {
        TRAVERSAL_CWIDE => scene.gpu_cwide().map(|c| bytemuck::cast_slice(&c.prims)),
        _ => None,
    }
    .unwrap_or_else(|| bytemuck::cast_slice(&scene.prims))
}

/// Device memory a scene's arrays take: the node and primitive textures (padded to whole
/// rows) or buffers (to whole texels), and the other arrays.
pub(super) fn scene_bytes(
    scene: &SceneBuffers,
    traversal: u32,
    fetch: Fetch,
    layer_rows: u32,
) -> u64 {
    let texture = |bytes: usize| match fetch {
        Fetch::Textures => {
            let (rows, layers) = texture_extent(bytes, layer_rows);
            u64::from(rows) * u64::from(layers) * u64::from(TEXTURE_WIDTH) * 16
        }
        Fetch::Buffers => texel_buffer_size(bytes),
    };
    texture(node_bytes(scene, traversal).len())
        + texture(size_of_val(&scene.prims[..]))
        + texture(scene.surface_texel_bytes())
        + [
            non_empty(&scene.planes).len(),
            non_empty(&scene.materials).len(),
            scene.gpu_light_bytes().max(size_of::<GpuLight>()),
        ]
        .iter()
        .map(|&b| b as u64)
        .sum::<u64>()
}

/// Uploads a scene's arrays: nodes, primitives and normals as `fetch` says, the rest as
/// storage. With `texture_margin`, each of the three is allocated with the address space
/// capped that far above the process's size (`GpuRenderer::with_texture_margin`).
pub(super) fn upload_scene(
    gpu: &Gpu,
    scene: &SceneBuffers,
    traversal: u32,
    fetch: Fetch,
    layer_rows: u32,
    texture_margin: Option<u64>,
) -> Result<SceneData> {
    let storage = |label: &str, bytes: &[u8]| gpu.read_only_storage(label, bytes);
    gpu.scoped("uploading the scene", || {
        let array = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        };
        let texels = |label, bytes: &[u8]| -> Result<Texels> {
            Ok(match fetch {
                Fetch::Textures => Texels::Texture(
                    texels(gpu, label, bytes, layer_rows, texture_margin)?.create_view(&array),
                ),
                Fetch::Buffers => Texels::Buffer(texel_buffer(gpu, label, bytes, texture_margin)?),
            })
        };
        Ok(SceneData {
            nodes: texels("nodes", node_bytes(scene, traversal))?,
            prims: texels("prims", prim_bytes(scene, traversal))?,
            tri_normals: texels("tri_normals", &scene.surface_texels())?,
            planes: storage("planes", non_empty(&scene.planes)),
            materials: storage("materials", non_empty(&scene.materials)),
            lights: storage("lights", non_empty(&scene.gpu_lights())),
        })
    })?
}

/// Rows of `TEXTURE_WIDTH` texels that hold `bytes` (at least one).
pub(super) fn texel_rows(bytes: usize) -> u32 {
    (bytes.div_ceil(16) as u32).div_ceil(TEXTURE_WIDTH).max(1)
}

/// The rows of each layer and the layers of a texture array holding `bytes`: one layer
/// as high as needed while that fits in `layer_rows`, else layers of `layer_rows` rows
/// (the shader finds texel `i` in layer `i >> LAYER_SHIFT`).
pub(super) fn texture_extent(bytes: usize, layer_rows: u32) -> (u32, u32) {
    let rows = texel_rows(bytes);
    if rows <= layer_rows {
        (rows, 1)
    } else {
        (layer_rows, rows.div_ceil(layer_rows))
    }
}

/// Rows of a texture layer on a device of `limits`: the highest power of two it allows,
/// so that a layer holds a power of two of texels and the shader splits an index with
/// shifts.
pub(super) fn layer_rows(limits: &wgpu::Limits) -> u32 {
    // At most 2^16 rows: a layer's texel count, 2^12 times that, stays a u32 shift.
    let max = limits.max_texture_dimension_2d.clamp(1, 1 << 16);
    1 << max.ilog2()
}

/// Texture rows written per upload step: 4 MB (see `texels`).
const UPLOAD_ROWS: u32 = 64;

/// A texture array of 16-byte texels (`TEXEL_FORMAT`) holding `bytes` row by row, layer after layer of
/// `layer_rows` rows (see `texture_extent`), zero-padded to whole rows. Written from
/// `bytes` in place, all but the last row in bands of `UPLOAD_ROWS`: a copy padded to
/// whole rows would double the host memory of the largest scenes (400 MB of primitives
/// for mount-11). With `margin`, the texture is allocated with the address space capped
/// that far above the process's size (the out-of-memory fault).
pub(super) fn texels(
    gpu: &Gpu,
    label: &str,
    bytes: &[u8],
    layer_rows: u32,
    margin: Option<u64>,
) -> Result<wgpu::Texture> {
    let (height, layers) = texture_extent(bytes.len(), layer_rows);
    let cap = margin.map(AddressSpaceCap::new).transpose()?;
    let texture = gpu.texel_array(label, TEXTURE_WIDTH, height, layers);
    drop(cap);
    let row_bytes = TEXTURE_WIDTH as usize * 16;
    // Writes `rows` rows from image row `first` on (rows never cross a layer).
    let write = |first: u32, rows: u32, data: &[u8]| {
        gpu.write_texel_rows(&texture, first / height, first % height, rows, data);
    };
    // wgpu stages each write in a buffer of its size, freed once the GPU has copied it:
    // bands of rows, each waited for, bound that second copy (lavapipe's staging memory
    // is host memory too).
    let whole = (bytes.len() / row_bytes) as u32;
    let mut first = 0;
    while first < whole {
        let n = (whole - first)
            .min(UPLOAD_ROWS)
            .min(height - first % height);
        let band = first as usize * row_bytes..(first + n) as usize * row_bytes;
        write(first, n, &bytes[band]);
        first += n;
        if first < whole {
            // A lost device surfaces at the upload's final wait.
            let _ = gpu.finish();
        }
    }
    if bytes.len() > whole as usize * row_bytes {
        let mut last = bytes[whole as usize * row_bytes..].to_vec();
        last.resize(row_bytes, 0);
        write(whole, 1, &last);
    }
    Ok(texture)
}

/// The size of the texel buffer holding `bytes`: whole 16-byte texels, at least one (wgpu
/// binds no empty buffer).
fn texel_buffer_size(bytes: usize) -> u64 {
    bytes.max(16).next_multiple_of(16) as u64
}

/// Bytes written per upload step of a texel buffer: 4 MB, as a texture's `UPLOAD_ROWS`.
const UPLOAD_BYTES: usize = 4 << 20;

/// A storage buffer of 16-byte texels holding `bytes`, zero-padded to whole texels (at
/// least one). Allocated first, with `margin` as `texels` has it (the allocation alone
/// under the cap, as for a texture), then written from `bytes` in place in waited bands
/// of `UPLOAD_BYTES`, so that wgpu's staging copies stay small.
fn texel_buffer(gpu: &Gpu, label: &str, bytes: &[u8], margin: Option<u64>) -> Result<wgpu::Buffer> {
    let size = texel_buffer_size(bytes.len()) as usize;
    let cap = margin.map(AddressSpaceCap::new).transpose()?;
    let buffer = gpu.texel_buffer(label, size as u64);
    drop(cap);
    // Whole bands, then the rest padded to a whole texel.
    let whole = bytes.len() / UPLOAD_BYTES * UPLOAD_BYTES;
    for (k, band) in bytes[..whole].chunks(UPLOAD_BYTES).enumerate() {
        gpu.write(&buffer, (k * UPLOAD_BYTES) as u64, band);
        // A lost device surfaces at the upload's final wait.
        let _ = gpu.finish();
    }
    if whole < size {
        let mut last = bytes[whole..].to_vec();
        last.resize(size - whole, 0);
        gpu.write(&buffer, whole as u64, &last);
    }
    Ok(buffer)
}

/// wgpu cannot bind an empty buffer: empty arrays are uploaded as one zeroed element
/// (the shader never reads it, since the counts in `GpuGlobals` are zero).
pub(super) fn non_empty<T: bytemuck::Pod>(v: &[T]) -> &[u8] {
    const ZERO: [u8; 64] = [0; 64];
    if v.is_empty() {
        &ZERO[..size_of::<T>().max(4)]
    } else {
        bytemuck::cast_slice(v)
    }
}

/// The arrays the shader reads a texel at a time, named, and their sizes in bytes.
fn texel_arrays(scene: &SceneBuffers, traversal: u32) -> [(&'static str, usize); 3] {
    [
        ("BVH nodes", node_bytes(scene, traversal).len()),
        ("primitives", size_of_val(&scene.prims[..])),
        (
            "triangle normals and texture coordinates",
            scene.surface_texel_bytes(),
        ),
    ]
}

/// Whether each of those arrays, for the walk `traversal`, fits one storage buffer of a
/// device of `limits` (`Fetch::Buffers`; textures grow by layers instead).
pub(super) fn fits_buffers(limits: &wgpu::Limits, scene: &SceneBuffers, traversal: u32) -> bool {
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    texel_arrays(scene, traversal)
        .iter()
        .all(|&(_, bytes)| texel_buffer_size(bytes) <= limit)
}

/// Refuses scenes that need a larger texture, storage binding or buffer than the device
/// allows, naming the limit and the size needed.
pub(super) fn check_sizes(
    limits: &wgpu::Limits,
    scene: &SceneBuffers,
    traversal: u32,
    out_bytes: u64,
    fetch: Fetch,
    layer_rows: u32,
) -> Result<()> {
    let max_side = limits.max_texture_dimension_2d;
    let texel_arrays = texel_arrays(scene, traversal);
    if fetch == Fetch::Buffers {
        return check_buffers(limits, scene, texel_arrays, out_bytes);
    }
    if max_side < TEXTURE_WIDTH {
        return Err(Error::Gpu(format!(
            "the scene's BVH nodes and primitives travel in textures {TEXTURE_WIDTH} texels \
             wide, but this adapter's max_texture_dimension_2d is {max_side}; render it with \
             --backend cpu"
        )));
    }
    let max_layers = limits.max_texture_array_layers;
    for (what, bytes) in texel_arrays {
        let (_, layers) = texture_extent(bytes, layer_rows);
        if layers > max_layers {
            return Err(Error::Gpu(format!(
                "the scene's {what} need {layers} texture layers of {layer_rows} rows, but \
                 this adapter's max_texture_array_layers is {max_layers}; render it with \
                 --backend cpu"
            )));
        }
    }
    check_buffers(limits, scene, [], out_bytes)
}

/// `check_sizes` for the arrays in storage buffers: the small ones, the output band, and
/// `texel_arrays` where the scene's large arrays are buffers too.
fn check_buffers<const N: usize>(
    limits: &wgpu::Limits,
    scene: &SceneBuffers,
    texel_arrays: [(&str, usize); N],
    out_bytes: u64,
) -> Result<()> {
    let max_binding = limits.max_storage_buffer_binding_size;
    let max_buffer = limits.max_buffer_size;
    let arrays = [
        ("planes", size_of_val(&scene.planes[..]) as u64),
        ("materials", size_of_val(&scene.materials[..]) as u64),
        ("lights", scene.gpu_light_bytes() as u64),
        ("output band", out_bytes),
    ];
    // Textures may hold the large arrays where a buffer cannot: they grow by layers.
    let arrays = arrays.map(|(what, bytes)| (what, bytes, ""));
    let texel_arrays = texel_arrays
        .map(|(what, bytes)| (what, texel_buffer_size(bytes), "GPURT_FETCH=textures or "));
    for (what, bytes, textures) in arrays.into_iter().chain(texel_arrays) {
        let limit = max_binding.min(max_buffer);
        if bytes > limit {
            return Err(Error::Gpu(format!(
                "the scene's {what} need {bytes} bytes in one storage buffer, but this adapter's \
                 max_storage_buffer_binding_size is {max_binding} (max_buffer_size {max_buffer}); \
                 render it with {textures}--backend cpu"
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu_types::{TRAVERSAL_NAMES, TRAVERSAL_PAIRS, TRAVERSAL_SINGLE};
    use crate::scene::nff;

    /// A scene fits buffers while its largest texel array (here its 7 primitives, 336
    /// bytes, or the wide tree's nodes) is within both the binding and the buffer limit.
    #[test]
    fn buffers_fit_while_the_largest_array_is_within_the_limits() {
        let src = b"v from 0 -5 1 at 0 0 0 up 0 0 1 angle 40 resolution 8 8
            l 1 -2 3
            f 1 0 0 1 0 1 0 1
            s 0 0 0 1  s 2 0 0 0.5  s -2 0 0 0.5  s 0 0 2 0.3  s 0 2 0 0.4  s 1 1 1 0.2
            s 3 3 3 0.1";
        let scene = nff::parse(src, "t.nff", std::path::Path::new(".")).unwrap();
        let b = crate::pack::pack(scene).unwrap();
        let largest = texel_arrays(&b, TRAVERSAL_WIDE)
            .iter()
            .map(|&(_, bytes)| texel_buffer_size(bytes))
            .max()
            .unwrap();
        assert!(largest >= 336, "{largest}");
        let limits = |binding: u64, buffer: u64| wgpu::Limits {
            max_storage_buffer_binding_size: binding,
            max_buffer_size: buffer,
            ..wgpu::Limits::default()
        };
        assert!(fits_buffers(&limits(largest, largest), &b, TRAVERSAL_WIDE));
        assert!(!fits_buffers(
            &limits(largest - 16, 1 << 30),
            &b,
            TRAVERSAL_WIDE
        ));
        assert!(!fits_buffers(
            &limits(1 << 30, largest - 16),
            &b,
            TRAVERSAL_WIDE
        ));
    }

    /// What a walk uploads comes from its own tree, and no other tree is built: the
    /// compressed one brings a reordered copy of every primitive (a 2M-triangle scene's
    /// upload held 128 MB more for it when every walk built it).
    #[test]
    fn a_walk_builds_only_the_tree_it_uploads() {
        let src = b"v from 0 -5 1 at 0 0 0 up 0 0 1 angle 40 resolution 8 8
            l 1 -2 3
            f 1 0 0 1 0 1 0 1
            s 0 0 0 1  s 2 0 0 0.5  s -2 0 0 0.5  s 0 0 2 0.3  s 0 2 0 0.4  s 1 1 1 0.2";
        for (traversal, built) in [
            (TRAVERSAL_SINGLE, (false, false, false)),
            (TRAVERSAL_PAIRS, (false, false, false)),
            (TRAVERSAL_WIDE, (true, false, false)),
            (TRAVERSAL_CWIDE, (false, true, false)),
            (TRAVERSAL_QWIDE, (true, false, true)),
        ] {
            let scene = nff::parse(src, "t.nff", std::path::Path::new(".")).unwrap();
            let b = crate::pack::pack(scene).unwrap();
            let (nodes, prims) = (node_bytes(&b, traversal), prim_bytes(&b, traversal));
            assert!(!nodes.is_empty() && prims.len() == size_of_val(&b.prims[..]));
            let name = TRAVERSAL_NAMES[traversal as usize];
            assert_eq!(b.trees_built(), built, "{name}");
        }
    }
}
