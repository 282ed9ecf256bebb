//! CPU twin of `shaders/texture.wgsl`: what a hit's texture gives its material, the
//! texture coordinates there and a texture sampled bilinearly with the wraps the formats
//! name.

use glam::{Vec2, Vec3};

use super::types::{Bindings, Hit};
use crate::gpu_types::*;

/// The texture coordinates at `hit`, interpolated from its triangle's corners; zero where
/// the primitive has none.
pub fn hit_uv(b: &Bindings, hit: &Hit) -> Vec2 {
    if hit.prim & PLANE_FLAG != 0 {
        return Vec2::ZERO;
    }
    let p = &b.prims[hit.prim as usize];
    if p.kind() != PRIM_TRIANGLE || p.f0 < 0.0 {
        return Vec2::ZERO;
    }
    // The uv records follow the normals' in the shader's texels.
    let t = &b.tri_uvs[p.f0 as usize - b.tri_normals.len()];
    (1.0 - hit.u - hit.v) * t.uv0 + hit.u * t.uv1 + hit.v * t.uv2
}

/// Texel `i` along an axis of `n` texels whose coordinates wrap by `mode` (`WRAP_*`).
pub fn wrap_index(i: i32, n: u32, mode: u32) -> u32 {
    let m = n as i32;
    if mode == WRAP_CLAMP {
        return i.clamp(0, m - 1) as u32;
    }
    if mode == WRAP_MIRROR {
        let mut k = i % (2 * m);
        if k < 0 {
            k += 2 * m;
        }
        return (if k >= m { 2 * m - 1 - k } else { k }) as u32;
    }
    let mut k = i % m;
    if k < 0 {
        k += m;
    }
    k as u32
}

/// Coordinate `c` along an axis of `n` texels, reduced to one period of its wrap (so that
/// the texel indices stay small whatever `c` is), in texels with their centres at whole
/// numbers.
pub fn texel_coordinate(c: f32, n: u32, mode: u32) -> f32 {
    let r = if mode == WRAP_CLAMP {
        c.clamp(0.0, 1.0)
    } else if mode == WRAP_MIRROR {
        c - 2.0 * (0.5 * c).floor()
    } else {
        c - c.floor()
    };
    r * n as f32 - 0.5
}

/// Texture `i` at `uv` (v up, the image's rows from the top), filtered bilinearly.
pub fn texture_sample(b: &Bindings, i: u32, uv: Vec2) -> Vec3 {
    let t = &b.textures[i as usize];
    let (wrap_u, wrap_v) = (t.wrap & 3, (t.wrap >> 2) & 3);
    let x = texel_coordinate(uv.x, t.width, wrap_u);
    let y = texel_coordinate(1.0 - uv.y, t.height, wrap_v);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let xa = wrap_index(x.floor() as i32, t.width, wrap_u);
    let xb = wrap_index(x.floor() as i32 + 1, t.width, wrap_u);
    let row_a = t.first + wrap_index(y.floor() as i32, t.height, wrap_v) * t.width;
    let row_b = t.first + wrap_index(y.floor() as i32 + 1, t.height, wrap_v) * t.width;
    // Texel k counts from the first texture's header, as the shader's do.
    let texel = |k: u32| b.texels[k as usize - b.textures.len()].truncate();
    // WGSL's `mix`.
    let mix = |a: Vec3, c: Vec3, t: f32| a * (1.0 - t) + c * t;
    let top = mix(texel(row_a + xa), texel(row_a + xb), fx);
    let bottom = mix(texel(row_b + xa), texel(row_b + xb), fx);
    mix(top, bottom, fy)
}

/// Material `m` where `hit` meets it: its colour and its ambient colour times its
/// texture's there.
pub fn textured(b: &Bindings, m: &GpuMaterial, hit: &Hit) -> GpuMaterial {
    let mut t = *m;
    if m.texture != NO_TEXTURE {
        let texel = texture_sample(b, m.texture, hit_uv(b, hit));
        t.color = m.color * texel;
        t.ambient = m.ambient * texel;
    }
    t
}
