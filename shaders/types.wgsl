// types.wgsl: the structs shared with Rust (mirrors src/gpu_types.rs; keep in sync, the
// layout test compares both through naga's reflection), the bindings, and the counter-based
// hash both renderers draw samples from (CPU twin: src/cpu/types.rs).
//
// The constants shared with Rust (PRIM_*, LIGHT_*, AOV_*, PHASE_*, NO_HIT, PLANE_FLAG,
// NO_PRIM, WIDE_LEAF, TRAVERSAL_STACK, RAY_STACK, ...) are not written here: each is
// defined once in src/gpu_types.rs and declared in the generated header before this file
// (src/gpu/shaders.rs).

struct Prim {
    p0: vec3<f32>,
    f0: f32,
    p1: vec3<f32>,
    f1: f32,
    p2: vec3<f32>,
    tag: u32,
}

struct TriNormals {
    n0: vec3<f32>,
    _pad0: u32,
    n1: vec3<f32>,
    _pad1: u32,
    n2: vec3<f32>,
    _pad2: u32,
}

struct TriUvs {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    _pad: array<u32, 6>,
}

struct Node {
    min: vec3<f32>,
    offset: u32,
    max: vec3<f32>,
    count_axis: u32,
}

// A node of the four-wide tree (TRAVERSAL_WIDE): the four children's boxes by axis and
// each child's traversal-stack entry (src/gpu_types.rs: GpuWideNode).
struct WideNode {
    lo: array<vec4<f32>, 3>,
    hi: array<vec4<f32>, 3>,
    entry: vec4<u32>,
}

// A node of the compressed eight-wide tree (TRAVERSAL_CWIDE): the grid its children's
// boxes are quantised on, the first inner child and first primitive of its leaves, a
// tag byte per lane, and the quantised boxes, a byte per lane (src/gpu_types.rs:
// GpuCwideNode, which says how they decode).
struct CwideNode {
    origin: vec3<f32>,
    exp_inner: u32,
    child_base: u32,
    prim_base: u32,
    tags: vec2<u32>,
    quant: array<vec4<u32>, 3>,
}

struct Plane {
    normal: vec3<f32>,
    d: f32,
    material: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct Material {
    color: vec3<f32>,
    kd: f32,
    ks: f32,
    shine: f32,
    t: f32,
    ior: f32,
    emission: vec3<f32>,
    texture: u32,
    ambient: vec3<f32>,
    _pad: u32,
}

struct Texture {
    first: u32,
    width: u32,
    height: u32,
    wrap: u32,
}

struct Light {
    pos: vec3<f32>,
    kind: u32,
    u: vec3<f32>,
    nu: u32,
    v: vec3<f32>,
    nv: u32,
    color: vec3<f32>,
    first: u32,
}

struct Globals {
    cam_pos: vec3<f32>,
    hither: f32,
    cam_forward: vec3<f32>,
    pixel_pitch: f32,
    cam_right: vec3<f32>,
    aperture: f32,
    cam_up: vec3<f32>,
    focal: f32,
    background: vec3<f32>,
    epsilon: f32,
    ambient: vec3<f32>,
    max_depth: u32,
    width: u32,
    height: u32,
    spp: u32,
    seed: u32,
    n_nodes: u32,
    n_planes: u32,
    n_lights: u32,
    aov: u32,
    traversal: u32,
    counters: u32,
    wavefront: u32,
    shading: u32,
    textures_at: u32,
    _pad: array<u32, 3>,
}

struct Tile {
    x: u32,
    y: u32,
    width: u32,
    height: u32,
    out_base: u32,
    out_stride: u32,
    sample_start: u32,
    sample_count: u32,
    scatter: u32,
    // Pixels a side of the square one workgroup traces (`pooled`; `main` covers 8x8).
    group_side: u32,
}

// What one pixel's rays cost, by kind (COUNTERS): rays traced and BVH nodes fetched
// (src/gpu_types.rs: GpuPixelCounts).
struct PixelCounts {
    eye_rays: u32,
    eye_nodes: u32,
    shadow_rays: u32,
    shadow_nodes: u32,
    secondary_rays: u32,
    secondary_nodes: u32,
    _pad: array<u32, 2>,
}

// One traced pixel: the sum of its samples traced so far in this band (the host divides)
// and the number of rays traced for it, PIXEL_CUT_SHORT set if any loop was cut.
struct PixelOut {
    color: vec3<f32>,
    rays: u32,
}

// Set when a loop ends without reaching its own exit: the driver stopped it (lavapipe
// ends every loop once an invocation has run 65535 loop iterations in all). Each loop
// checks after itself; the pixel is then reported, never written darker in silence.
var<private> cut_short: bool;

// BVH nodes this invocation's walks have fetched (COUNTERS), and its counts so far: the
// callers of the walks (trace, light_sample, aov) attribute the fetches to a kind of ray.
var<private> fetched: u32;
var<private> counts: PixelCounts;

// Loop iterations this invocation has run, counted where the work is (traversal steps,
// primitive tests, light samples, rays): `resume` suspends a pixel once it passes
// RESUME_BUDGET. Lavapipe's limit counts the iterations of all eight invocations of a
// SIMD batch together, so eight budgets plus one traversal must stay under 65535.
var<private> work: u32;

// A pixel whose work continues across dispatches (`resume` in pixel.wgsl): its samples so
// far, the sample under way with its pending rays, and the hit whose lights are being
// sampled. Mirrors GpuPixelState in src/gpu_types.rs.
struct PixelState {
    sum: vec3<f32>,
    sample: u32,
    colour: vec3<f32>,
    rng: u32,
    lit: vec3<f32>,
    rays: u32,
    point: vec3<f32>,
    sp: u32,
    ng: vec3<f32>,
    light: u32,
    ns: vec3<f32>,
    light_sample: u32,
    albedo: vec3<f32>,
    _pad: u32,
    ray_in: Pending,
    material: u32,
    entering: u32,
    phase: u32,
    cut: u32,
    counts: PixelCounts,
    stack: array<Pending, RAY_STACK>,
}

// The pixels to resume (x | y << RESUME_Y_SHIFT), their states, and how many are still unfinished
// after this dispatch. Bound only for `resume`.
@group(1) @binding(0) var<storage, read> resume_pixels: array<u32>;
@group(1) @binding(1) var<storage, read_write> resume_state: array<PixelState>;
@group(1) @binding(2) var<storage, read_write> resume_pending: atomic<u32>;

// Specialisation: the host compiles one pipeline per combination the scene needs
// (src/gpu/specialization.rs, `Specialization`). Each flag only removes code the scene cannot
// reach, and the CPU twin keeps every branch. It matters on lavapipe, which executes both
// sides of every `if` under a lane mask: a sphere test used to pay for the triangle, cone
// and box tests beside it.
override SPHERES: bool = true;
override TRIANGLES: bool = true;
override CONES: bool = true;
override BOXES: bool = true;
override PLANES: bool = true;
// Some triangle carries shading normals.
override NORMALS: bool = true;
override DIRECTIONAL_LIGHTS: bool = true;
override AREA_LIGHTS: bool = true;
// Some material emits: its surfaces are seen with their own light and its triangles are
// lights (LIGHT_EMITTER).
override EMITTERS: bool = true;
// Some material has a texture.
override TEXTURES: bool = true;
// Some material has Ks > 0 / T > 0.
override REFLECTION: bool = true;
override REFRACTION: bool = true;
// Aperture > 0.
override LENS: bool = true;
// More than one sample per pixel.
override MULTISAMPLE: bool = true;
// globals.aov, as a constant.
override AOV: u32 = AOV_COLOR;
// globals.shading, as a constant: a Phong pipeline holds no Blinn-Phong code.
override SHADING: u32 = SHADING_PHONG;
// globals.traversal == TRAVERSAL_PAIRS, as a constant.
override PAIRS: bool = false;
// globals.traversal == TRAVERSAL_WIDE or TRAVERSAL_QWIDE, as a constant: node_texels
// then holds WideNodes, or with QWIDE the same nodes quantised (`qwide_node`).
override WIDE: bool = false;
override QWIDE: bool = false;
// globals.traversal == TRAVERSAL_CWIDE, as a constant: node_texels then holds CwideNodes
// and prim_texels the primitives in their order.
override CWIDE: bool = false;
// Entries of each invocation's slice of traversal_stack: what the scene's walk needs, at
// most TRAVERSAL_STACK (src/gpu/specialization.rs).
override STACK: u32 = TRAVERSAL_STACK;
// globals.counters != 0, as a constant: count rays and node fetches by kind (`counters`).
override COUNTERS: bool = false;
// false: lights reach every surface that faces them and no shadow ray is traced (`gpurt
// bench`'s `shaded` pass, which times the shading of hits apart from their shadow rays).
override SHADOW_RAYS: bool = true;
// log2 of the texels in a layer of node_texels and prim_texels (the device's limits).
override LAYER_SHIFT: u32 = 25u;

// Storage, not uniform: lavapipe specialises a shader on the uniform values its branches
// read (Mesa's uniform inlining), so a uniform `globals` compiled the shader again (0.8 s)
// for every scene and image size.
@group(0) @binding(0) var<storage, read> globals: Globals;
@group(0) @binding(1) var<uniform> tile: Tile;
// BVH nodes and primitives, the data every traversal step reads, and the triangles'
// shading normals: the very bytes of `array<Node>` (`array<WideNode>` for the wide walk),
// `array<Prim>` and `array<TriNormals>` (2, 7 and 3 texels each), fetched a 16-byte
// texel at a time by `node_texel`, `prim_texel` and `normal_texel`. The host keeps one of
// the two blocks below (src/gpu/shaders.rs, `Fetch`), as the bind group layout it made
// says. Textures on software adapters: lavapipe loads a storage buffer one component and
// one invocation at a time, but a texel with one 16-byte load a lane; read-only storage
// textures rather than sampled ones, whose fetch works out each lane's mip level and
// strides first (docs/gpu.md, item 2; the host's side is `upload::TEXEL_FORMAT`), in
// layers of 2^LAYER_SHIFT texels, rows of TEXTURE_WIDTH. Storage buffers on hardware
// GPUs, which read them through the same caches without the texture unit's tiled
// layout and addressing.
// fetch: textures {
alias Texels = texture_storage_2d_array<rgba32uint, read>;
@group(0) @binding(2) var node_texels: Texels;
@group(0) @binding(3) var prim_texels: Texels;
@group(0) @binding(4) var normal_texels: Texels;

// Texel `i` of a texture array: layers of 2^LAYER_SHIFT texels, rows of TEXTURE_WIDTH
// (both powers of two, so the divisions are shifts).
fn texel(texels: Texels, i: u32) -> vec4<u32> {
    let j = i & ((1u << LAYER_SHIFT) - 1u);
    return textureLoad(texels, vec2<u32>(j % TEXTURE_WIDTH, j / TEXTURE_WIDTH), i >> LAYER_SHIFT);
}

fn node_texel(i: u32) -> vec4<u32> {
    return texel(node_texels, i);
}

fn prim_texel(i: u32) -> vec4<u32> {
    return texel(prim_texels, i);
}

fn normal_texel(i: u32) -> vec4<u32> {
    return texel(normal_texels, i);
}
// } fetch: textures
// fetch: buffers {
@group(0) @binding(2) var<storage, read> node_texels: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> prim_texels: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> normal_texels: array<vec4<u32>>;

fn node_texel(i: u32) -> vec4<u32> {
    return node_texels[i];
}

fn prim_texel(i: u32) -> vec4<u32> {
    return prim_texels[i];
}

fn normal_texel(i: u32) -> vec4<u32> {
    return normal_texels[i];
}
// } fetch: buffers
@group(0) @binding(5) var<storage, read> planes: array<Plane>;
@group(0) @binding(6) var<storage, read> materials: array<Material>;
@group(0) @binding(7) var<storage, read> lights: array<Light>;
@group(0) @binding(8) var<storage, read_write> output: array<PixelOut>;
// The band's PixelCounts, beside `output` (COUNTERS; a single unused entry otherwise).
@group(0) @binding(9) var<storage, read_write> counters: array<PixelCounts>;

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

struct Hit {
    t: f32,
    prim: u32,
    u: f32,
    v: f32,
    cost: u32,
}

fn prim_kind(p: Prim) -> u32 {
    return p.tag >> PRIM_KIND_SHIFT;
}

fn prim_material(p: Prim) -> u32 {
    return p.tag & PRIM_MATERIAL_MASK;
}


fn load_node(i: u32) -> Node {
    let a = node_texel(2u * i);
    let b = node_texel(2u * i + 1u);
    return Node(bitcast<vec3<f32>>(a.xyz), a.w, bitcast<vec3<f32>>(b.xyz), b.w);
}

fn load_wide_node(i: u32) -> WideNode {
    let b = 7u * i;
    return WideNode(
        array<vec4<f32>, 3>(
            bitcast<vec4<f32>>(node_texel(b)),
            bitcast<vec4<f32>>(node_texel(b + 1u)),
            bitcast<vec4<f32>>(node_texel(b + 2u)),
        ),
        array<vec4<f32>, 3>(
            bitcast<vec4<f32>>(node_texel(b + 3u)),
            bitcast<vec4<f32>>(node_texel(b + 4u)),
            bitcast<vec4<f32>>(node_texel(b + 5u)),
        ),
        node_texel(b + 6u),
    );
}

fn load_cwide_node(i: u32) -> CwideNode {
    let b = 5u * i;
    let head = node_texel(b);
    let bases = node_texel(b + 1u);
    return CwideNode(
        bitcast<vec3<f32>>(head.xyz),
        head.w,
        bases.x,
        bases.y,
        bases.zw,
        array<vec4<u32>, 3>(node_texel(b + 2u), node_texel(b + 3u), node_texel(b + 4u)),
    );
}

fn load_tri_normals(i: u32) -> TriNormals {
    let a = normal_texel(3u * i);
    let b = normal_texel(3u * i + 1u);
    let c = normal_texel(3u * i + 2u);
    return TriNormals(
        bitcast<vec3<f32>>(a.xyz),
        0u,
        bitcast<vec3<f32>>(b.xyz),
        0u,
        bitcast<vec3<f32>>(c.xyz),
        0u,
    );
}

fn load_prim(i: u32) -> Prim {
    let a = prim_texel(3u * i);
    let b = prim_texel(3u * i + 1u);
    let c = prim_texel(3u * i + 2u);
    return Prim(
        bitcast<vec3<f32>>(a.xyz),
        bitcast<f32>(a.w),
        bitcast<vec3<f32>>(b.xyz),
        bitcast<f32>(b.w),
        bitcast<vec3<f32>>(c.xyz),
        c.w,
    );
}

// The tag (kind and material) of primitive i: the last word of its third texel.
fn load_prim_tag(i: u32) -> u32 {
    return prim_texel(3u * i + 2u).w;
}

fn node_count(n: Node) -> u32 {
    return n.count_axis & NODE_COUNT_MASK;
}

fn node_axis(n: Node) -> u32 {
    return n.count_axis >> NODE_AXIS_SHIFT;
}

// PCG hash (Jarzynski & Olano 2020); u32 arithmetic wraps, as on the CPU.
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn rng_seed(pixel: u32, sample: u32, seed: u32) -> u32 {
    return pcg_hash(pixel ^ pcg_hash(sample ^ pcg_hash(seed)));
}

// Next uniform number in [0, 1) with 24 bits, advancing the stream.
fn rand(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}
