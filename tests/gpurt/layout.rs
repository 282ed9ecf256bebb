//! Every struct shared with WGSL has the same size and field offsets in Rust and in the
//! shader, as naga's layouter computes them for the joined source; the shared constants
//! agree; and every WGSL function has its CPU twin of the same name, in the same order.

use std::mem::{offset_of, size_of};

use gpurt::gpu::shaders;
use gpurt::gpu_types::*;

/// (WGSL name, Rust size, [(field, Rust offset)]).
type Layout = (&'static str, usize, Vec<(&'static str, usize)>);

macro_rules! layout {
    ($wgsl:literal, $ty:ty, [$($field:ident),* $(,)?]) => {
        ($wgsl, size_of::<$ty>(), vec![$((stringify!($field), offset_of!($ty, $field))),*])
    };
}

fn rust_layouts() -> Vec<Layout> {
    vec![
        layout!("Prim", GpuPrim, [p0, f0, p1, f1, p2, tag]),
        layout!(
            "TriNormals",
            GpuTriNormals,
            [n0, _pad0, n1, _pad1, n2, _pad2]
        ),
        layout!("TriUvs", GpuTriUvs, [uv0, uv1, uv2, _pad]),
        layout!("Node", GpuNode, [min, offset, max, count_axis]),
        layout!("WideNode", GpuWideNode, [lo, hi, entry]),
        layout!(
            "CwideNode",
            GpuCwideNode,
            [origin, exp_inner, child_base, prim_base, tags, quant]
        ),
        layout!(
            "WavePath",
            GpuWavePath,
            [colour, rays, counts, cut, _pad0, _pad1, _pad2]
        ),
        layout!("WaveRay", GpuWaveRay, [origin, weight, dir, path]),
        layout!(
            "WaveHit",
            GpuWaveHit,
            [hit, nodes, flags, children, ambient]
        ),
        layout!(
            "WaveShadow",
            GpuWaveShadow,
            [origin, dist, dir, flags, light, nodes]
        ),
        layout!(
            "PixelCounts",
            GpuPixelCounts,
            [
                eye_rays,
                eye_nodes,
                shadow_rays,
                shadow_nodes,
                secondary_rays,
                secondary_nodes,
                _pad
            ]
        ),
        layout!(
            "Material",
            GpuMaterial,
            [
                color, kd, ks, shine, t, ior, emission, texture, ambient, _pad
            ]
        ),
        layout!("Light", GpuLight, [pos, kind, u, nu, v, nv, color, first]),
        layout!(
            "Globals",
            GpuGlobals,
            [
                cam_pos,
                hither,
                cam_forward,
                pixel_pitch,
                cam_right,
                aperture,
                cam_up,
                focal,
                background,
                epsilon,
                ambient,
                max_depth,
                width,
                height,
                spp,
                seed,
                n_nodes,
                n_planes,
                n_lights,
                aov,
                traversal,
                counters,
                wavefront,
                shading,
                textures_at,
                _pad
            ]
        ),
        layout!("Texture", GpuTexture, [first, width, height, wrap]),
        layout!(
            "Tile",
            GpuTile,
            [
                x,
                y,
                width,
                height,
                out_base,
                out_stride,
                sample_start,
                sample_count,
                scatter,
                group_side
            ]
        ),
    ]
}

#[test]
fn shared_structs_match_wgsl_layout() {
    let (module, _) = shaders::validate(shaders::Fetch::Textures).expect("shader validates");
    let mut layouter = naga::proc::Layouter::default();
    layouter
        .update(module.to_ctx())
        .expect("naga computes the layout");
    for (name, size, fields) in rust_layouts() {
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("struct {name} missing from the WGSL"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{name} is not a struct in WGSL");
        };
        assert_eq!(*span as usize, size, "{name}: WGSL size vs Rust size");
        assert_eq!(
            layouter[handle].size as usize, size,
            "{name}: naga layout size"
        );
        let wgsl: Vec<(String, usize)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
            .collect();
        let rust: Vec<(String, usize)> = fields.iter().map(|(f, o)| (f.to_string(), *o)).collect();
        assert_eq!(wgsl, rust, "{name}: fields and offsets (WGSL vs Rust)");
    }
}

/// The plane struct pads with three named u32 in WGSL and an array in Rust.
#[test]
fn plane_layout_matches() {
    let (module, _) = shaders::validate(shaders::Fetch::Textures).expect("shader validates");
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("Plane"))
        .expect("Plane in WGSL");
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("Plane is not a struct");
    };
    assert_eq!(*span as usize, size_of::<GpuPlane>());
    let offsets: Vec<usize> = members.iter().map(|m| m.offset as usize).collect();
    assert_eq!(
        &offsets[..3],
        &[
            offset_of!(GpuPlane, normal),
            offset_of!(GpuPlane, d),
            offset_of!(GpuPlane, material)
        ]
    );
}

/// The value of a WGSL `const` whose initialiser is a literal.
fn wgsl_const(module: &naga::Module, name: &str) -> naga::Literal {
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("const {name} missing from the WGSL"));
    match module.global_expressions[c.init] {
        naga::Expression::Literal(l) => l,
        ref e => panic!("const {name} is not a literal: {e:?}"),
    }
}

/// The constants the two sides share (`gpu_types::WGSL_CONSTANTS`, each named by its own
/// identifier) have their Rust value in the shader naga reads from the generated source,
/// of the same type (an `f32` to the bit).
#[test]
fn shared_constants_match() {
    let (module, _) = shaders::validate(shaders::Fetch::Textures).expect("shader validates");
    assert!(WGSL_CONSTANTS.len() > 40, "the list of shared constants");
    for &(name, value) in WGSL_CONSTANTS {
        let want = match value {
            WgslValue::U32(v) => naga::Literal::U32(v),
            WgslValue::F32(v) => naga::Literal::F32(v),
        };
        let got = wgsl_const(&module, name);
        assert_eq!(got, want, "{name}");
        if let (naga::Literal::F32(g), naga::Literal::F32(w)) = (got, want) {
            assert_eq!(g.to_bits(), w.to_bits(), "{name}: the bits of the f32");
        }
    }
    assert_eq!(
        wgsl_const(&module, "TRACE_STACK"),
        naga::Literal::U32(RAY_STACK as u32),
        "the validated source has the longest ray stack"
    );
}

/// `text` without its `//` comments.
fn strip_comments(text: &str) -> String {
    text.lines()
        .map(|l| l.find("//").map_or(l, |i| &l[..i]))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The numeric literals of WGSL code, as written: `2048u`, `0x80000000u`, `1.5e-3f`.
fn literals(code: &str) -> Vec<String> {
    let b = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let hex = b[i..].starts_with(b"0x") || b[i..].starts_with(b"0X");
        let mut j = i + 1;
        while j < b.len()
            && (b[j].is_ascii_alphanumeric()
                || b[j] == b'.'
                || (!hex && matches!(b[j], b'+' | b'-') && matches!(b[j - 1], b'e' | b'E')))
        {
            j += 1;
        }
        out.push(code[i..j].to_string());
        i = j;
    }
    out
}

/// The value of a WGSL numeric literal, as a u32 or as an f32 (`None` for others).
fn literal_value(lit: &str) -> Option<WgslValue> {
    if let Some(hex) = lit.strip_prefix("0x").or_else(|| lit.strip_prefix("0X")) {
        let digits = hex.trim_end_matches(['u', 'i']);
        return u32::from_str_radix(digits, 16).ok().map(WgslValue::U32);
    }
    if lit.contains(['.', 'e', 'E']) || lit.ends_with('f') {
        let digits = lit.trim_end_matches(['f', 'h']);
        return digits.parse::<f32>().ok().map(WgslValue::F32);
    }
    let digits = lit.trim_end_matches(['u', 'i']);
    digits.parse::<u32>().ok().map(WgslValue::U32)
}

/// No WGSL file declares a constant shared with Rust, or writes the value of one as a
/// literal of its own: each is written once, in Rust, into the generated header. Small
/// integers (below 256) are ordinary numbers in code, and are checked by name only.
#[test]
fn no_wgsl_file_writes_a_shared_constant() {
    for (file, text) in shaders::FILES {
        let code = strip_comments(text);
        for &(name, value) in WGSL_CONSTANTS {
            for decl in ["const", "override", "let", "var<private>"] {
                assert!(
                    !code.contains(&format!("{decl} {name}:"))
                        && !code.contains(&format!("{decl} {name} ")),
                    "shaders/{file} declares {name}, which only src/gpu_types.rs may define"
                );
            }
            let distinctive = match value {
                WgslValue::U32(v) => v >= 256,
                WgslValue::F32(v) => v.fract() != 0.0 || v.abs() >= 256.0,
            };
            if !distinctive {
                continue;
            }
            for lit in literals(&code) {
                let same = match (literal_value(&lit), value) {
                    (Some(WgslValue::U32(a)), WgslValue::U32(b)) => a == b,
                    (Some(WgslValue::F32(a)), WgslValue::F32(b)) => a.to_bits() == b.to_bits(),
                    _ => false,
                };
                assert!(
                    !same,
                    "shaders/{file} writes {lit}, the value of {name}: use the constant"
                );
            }
        }
    }
}

/// The literal scanner finds what the old shader wrote for these constants.
#[test]
fn the_literal_scanner_sees_shared_values() {
    let old = "const NO_HIT: f32 = 3.40282347e+38;\nlet x = y & 0x0fffffffu; // 2048u\n\
               let w = 1.0000152587890625 * a2048u + 2048u;";
    let found: Vec<Option<WgslValue>> = literals(&strip_comments(old))
        .iter()
        .map(|l| literal_value(l))
        .collect();
    assert_eq!(
        found,
        [
            Some(WgslValue::F32(NO_HIT)),
            Some(WgslValue::U32(PRIM_MATERIAL_MASK)),
            Some(WgslValue::F32(SLAB_WIDEN)),
            Some(WgslValue::U32(RESUME_BUDGET)),
        ]
    );
}

/// WGSL functions without a CPU twin, and why.
const WGSL_ONLY: &[(&str, &str)] = &[
    ("prim_kind", "reads the tag the CPU matches on directly"),
    ("prim_material", "reads the tag the CPU masks directly"),
    ("texel", "texture fetch: the CPU indexes the arrays"),
    (
        "node_texel",
        "texture or buffer fetch: the CPU indexes the arrays",
    ),
    (
        "prim_texel",
        "texture or buffer fetch: the CPU indexes the arrays",
    ),
    (
        "normal_texel",
        "texture or buffer fetch: the CPU indexes the arrays",
    ),
    ("load_node", "texture fetch: the CPU indexes the arrays"),
    ("load_prim", "texture fetch: the CPU indexes the arrays"),
    (
        "load_tri_normals",
        "texture fetch: the CPU indexes the arrays",
    ),
    ("load_tri_uvs", "texture fetch: the CPU indexes the arrays"),
    ("load_texture", "texture fetch: the CPU indexes the arrays"),
    ("load_texel", "texture fetch: the CPU indexes the arrays"),
    ("load_prim_tag", "texture fetch: the CPU indexes the arrays"),
    (
        "load_wide_node",
        "texture fetch: the CPU indexes the arrays",
    ),
    (
        "load_cwide_node",
        "texture fetch: the CPU indexes the arrays",
    ),
    ("node_count", "bit field the CPU's GpuNode methods read"),
    ("node_axis", "bit field the CPU's GpuNode methods read"),
    ("cone_valid", "inlined in the CPU's intersect_cone"),
    ("max_element", "glam's Vec3::max_element"),
    ("min_element", "glam's Vec3::min_element"),
    ("sign_of", "f32::signum"),
    (
        "workgroup_block",
        "the block of a GPU workgroup; the CPU loops over pixels",
    ),
    (
        "block_pixel",
        "the pixel of a GPU invocation; the CPU loops over pixels",
    ),
    (
        "pool_pixel",
        "the pixel of a pooled workgroup's square; the CPU loops over pixels",
    ),
    (
        "trace_ray",
        "one ray of trace's loop, which pooled shares; the CPU's trace keeps its loop whole",
    ),
    ("main", "the entry point; the CPU's is sample_sum"),
    (
        "pooled",
        "GPU only: main's samples shared out among a workgroup's lanes",
    ),
    (
        "resume",
        "GPU only: continues pixels cut short by a driver's loop limit",
    ),
];

/// CPU functions without a WGSL twin, and why.
const CPU_ONLY: &[(&str, &str)] = &[
    (
        "new",
        "constructors (Walk, Bindings); WGSL writes the struct",
    ),
    (
        "total",
        "RayCounts: the CPU counts rays by kind, the GPU one total",
    ),
    (
        "add",
        "RayCounts: the CPU counts rays by kind, the GPU one total",
    ),
    ("sample_sum", "the CPU's per-pixel driver, `main` in WGSL"),
    (
        "wave_sums",
        "the rounds of the wavefront kernels, which the host dispatches (gpu/waves.rs)",
    ),
    (
        "counters",
        "RayCounts as the counts by kind the GPU keeps (`counters::Counters`)",
    ),
    (
        "gpu_walk",
        "Bindings for the binary walk: the CPU renders through the wide tree (wide.rs)",
    ),
    (
        "stack_high_water",
        "the tests' probe of the stack bound; the shader's slice is sized from it",
    ),
    (
        "lanes_of",
        "the set bits of a lane mask, for the CPU's SIMD leaf tests and packets",
    ),
    (
        "leaf_words",
        "a leaf's primitives as SIMD lanes for the CPU's four-at-once tests",
    ),
    (
        "transposed",
        "a leaf's primitives as SIMD lanes for the CPU's four-at-once tests",
    ),
    (
        "intersect_spheres4",
        "four spheres in SIMD lanes for the CPU's leaves; a GPU lane tests one",
    ),
    (
        "triangles4",
        "four triangles of a CPU leaf block (bvh::blocks) in SIMD lanes; a GPU lane tests one",
    ),
    (
        "intersect_triangles4",
        "four triangles in SIMD lanes for the CPU's leaves; a GPU lane tests one",
    ),
    (
        "closest_in_prims",
        "closest_hit's leaf loop, which the CPU's leaf test (fast/leaf.rs) falls back to",
    ),
    (
        "closest_plane",
        "closest_hit's planes, which the CPU's eight-wide walk (fast/wide_ray.rs) starts from too",
    ),
    (
        "transmit_planes",
        "transmission's planes, which the CPU's occlusion packets test lane by lane first",
    ),
];

/// Names of the functions defined in `src` (Rust or WGSL), in order, up to a test module;
/// not a trait's methods (the CPU's seams, such as `shade::Tracer`, which WGSL has no need
/// of).
fn function_names(src: &str) -> Vec<String> {
    let mut in_trait = false;
    src.lines()
        .take_while(|l| !l.starts_with("#[cfg(test)]"))
        .filter(|l| {
            in_trait = (in_trait || l.starts_with("pub trait ") || l.starts_with("trait "))
                && !l.starts_with('}');
            !in_trait
        })
        .filter_map(|l| {
            let l = l.trim_start();
            // `pub`, `pub(crate)`, `pub(super)`, `pub(in path)`.
            let l = match l.strip_prefix("pub(") {
                Some(rest) => rest.split_once(") ").map_or(l, |(_, f)| f),
                None => l.strip_prefix("pub ").unwrap_or(l),
            };
            let rest = l.strip_prefix("fn ")?;
            let end = rest.find(|c: char| !(c.is_alphanumeric() || c == '_'))?;
            Some(rest[..end].to_string())
        })
        .collect()
}

/// Every WGSL function has a CPU function of the same name in the same-named module, in
/// the same order, but for the documented exceptions (and naga knows every WGSL one).
#[test]
fn wgsl_functions_have_cpu_twins_in_order() {
    let (module, _) = shaders::validate(shaders::Fetch::Textures).expect("shader validates");
    let known: Vec<String> = module
        .functions
        .iter()
        .filter_map(|(_, f)| f.name.clone())
        .chain(module.entry_points.iter().map(|e| e.name.clone()))
        .collect();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let (mut seen, mut seen_cpu) = (Vec::new(), Vec::new());
    for (file, text) in shaders::FILES {
        let stem = file.trim_end_matches(".wgsl");
        let wgsl = function_names(text);
        for f in &wgsl {
            assert!(known.contains(f), "{file}: naga does not list {f}");
        }
        seen.extend(wgsl.iter().cloned());
        let cpu_src = std::fs::read_to_string(root.join(format!("src/cpu/{stem}.rs")))
            .expect("the CPU twin exists");
        seen_cpu.extend(function_names(&cpu_src));
        let keep = |names: Vec<String>, except: &[(&str, &str)]| -> Vec<String> {
            names
                .into_iter()
                .filter(|n| !except.iter().any(|(e, _)| e == n))
                .collect()
        };
        assert_eq!(
            keep(wgsl, WGSL_ONLY),
            keep(function_names(&cpu_src), CPU_ONLY),
            "shaders/{file} and src/cpu/{stem}.rs define different functions (or in another order)"
        );
    }
    for (name, _) in WGSL_ONLY {
        assert!(seen.iter().any(|s| s == name), "stale exception {name}");
    }
    for (name, _) in CPU_ONLY {
        assert!(seen_cpu.iter().any(|s| s == name), "stale exception {name}");
    }
}
