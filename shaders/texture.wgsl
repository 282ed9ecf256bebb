// texture.wgsl: what a hit's texture gives its material: the texture coordinates there,
// and a texture sampled bilinearly with the wraps the formats name (CPU twin:
// src/cpu/texture.rs). The texels travel after the triangles' normals and texture
// coordinates (docs/gpu.md, binding 4).

// The texture coordinates of uv slot i, a record of the normals' three texels.
fn load_tri_uvs(i: u32) -> TriUvs {
    let a = normal_texel(3u * i);
    let b = normal_texel(3u * i + 1u);
    return TriUvs(bitcast<vec2<f32>>(a.xy), bitcast<vec2<f32>>(a.zw), bitcast<vec2<f32>>(b.xy), array<u32, 6>());
}

// The header of texture i (src/gpu_types.rs: GpuTexture).
fn load_texture(i: u32) -> Texture {
    let t = normal_texel(globals.textures_at + i);
    return Texture(t.x, t.y, t.z, t.w);
}

// Texel k of the textures' (counted from the first header), linear RGB.
fn load_texel(k: u32) -> vec3<f32> {
    return bitcast<vec3<f32>>(normal_texel(globals.textures_at + k).xyz);
}

// The texture coordinates at `hit`, interpolated from its triangle's corners; zero where
// the primitive has none.
fn hit_uv(hit: Hit) -> vec2<f32> {
    if (!TRIANGLES || (PLANES && (hit.prim & PLANE_FLAG) != 0u)) {
        return vec2<f32>(0.0);
    }
    let p = load_prim(hit.prim);
    if (prim_kind(p) != PRIM_TRIANGLE || p.f0 < 0.0) {
        return vec2<f32>(0.0);
    }
    let t = load_tri_uvs(u32(p.f0));
    return (1.0 - hit.u - hit.v) * t.uv0 + hit.u * t.uv1 + hit.v * t.uv2;
}

// Texel i along an axis of n texels whose coordinates wrap by `mode` (WRAP_*).
fn wrap_index(i: i32, n: u32, mode: u32) -> u32 {
    let m = i32(n);
    if (mode == WRAP_CLAMP) {
        return u32(clamp(i, 0, m - 1));
    }
    if (mode == WRAP_MIRROR) {
        var k = i % (2 * m);
        if (k < 0) {
            k += 2 * m;
        }
        return u32(select(k, 2 * m - 1 - k, k >= m));
    }
    var k = i % m;
    if (k < 0) {
        k += m;
    }
    return u32(k);
}

// Coordinate c along an axis of n texels, reduced to one period of its wrap (so that the
// texel indices stay small whatever c is), in texels with their centres at whole numbers.
fn texel_coordinate(c: f32, n: u32, mode: u32) -> f32 {
    var r: f32;
    if (mode == WRAP_CLAMP) {
        r = clamp(c, 0.0, 1.0);
    } else if (mode == WRAP_MIRROR) {
        r = c - 2.0 * floor(0.5 * c);
    } else {
        r = c - floor(c);
    }
    return r * f32(n) - 0.5;
}

// Texture i at `uv` (v up, the image's rows from the top), filtered bilinearly.
fn texture_sample(i: u32, uv: vec2<f32>) -> vec3<f32> {
    let t = load_texture(i);
    let wrap_u = t.wrap & 3u;
    let wrap_v = (t.wrap >> 2u) & 3u;
    let x = texel_coordinate(uv.x, t.width, wrap_u);
    let y = texel_coordinate(1.0 - uv.y, t.height, wrap_v);
    let fx = x - floor(x);
    let fy = y - floor(y);
    let xa = wrap_index(i32(floor(x)), t.width, wrap_u);
    let xb = wrap_index(i32(floor(x)) + 1, t.width, wrap_u);
    let row_a = t.first + wrap_index(i32(floor(y)), t.height, wrap_v) * t.width;
    let row_b = t.first + wrap_index(i32(floor(y)) + 1, t.height, wrap_v) * t.width;
    let top = mix(load_texel(row_a + xa), load_texel(row_a + xb), fx);
    let bottom = mix(load_texel(row_b + xa), load_texel(row_b + xb), fx);
    return mix(top, bottom, fy);
}

// Material m where `hit` meets it: its colour and its ambient colour times its
// texture's there.
fn textured(m: Material, hit: Hit) -> Material {
    var t = m;
    if (TEXTURES && m.texture != NO_TEXTURE) {
        let texel = texture_sample(m.texture, hit_uv(hit));
        t.color = m.color * texel;
        t.ambient = m.ambient * texel;
    }
    return t;
}
