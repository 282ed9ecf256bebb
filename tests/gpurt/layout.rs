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
        layout!("Node", GpuNode, [min, offset, max, count_axis]),
        layout!("WideNode", GpuWideNode, [lo, hi, entry]),
        layout!("Material", GpuMaterial, [color, kd, ks, shine, t, ior]),
        layout!("Light", GpuLight, [pos, kind, u, nu, v, nv, color, _pad]),
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
                _pad,
            ]
        ),
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
                scatter
            ]
        ),
    ]
}

#[test]
fn shared_structs_match_wgsl_layout() {
    let (module, _) = shaders::validate().expect("shader validates");
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
    let (module, _) = shaders::validate().expect("shader validates");
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

/// Constants the two sides must agree on.
#[test]
fn shared_constants_match() {
    let (module, _) = shaders::validate().expect("shader validates");
    let u32s = [
        ("TRAVERSAL_STACK", TRAVERSAL_STACK as u32),
        ("WIDE_LEAF", WIDE_LEAF),
        ("WIDE_EMPTY", WIDE_EMPTY),
        ("TEXTURE_WIDTH", TEXTURE_WIDTH),
        ("RAY_STACK", RAY_STACK as u32),
        ("PRIM_SPHERE", PRIM_SPHERE),
        ("PRIM_TRIANGLE", PRIM_TRIANGLE),
        ("PRIM_CONE", PRIM_CONE),
        ("PRIM_BOX", PRIM_BOX),
        ("PRIM_KIND_SHIFT", PRIM_KIND_SHIFT),
        ("PRIM_MATERIAL_MASK", PRIM_MATERIAL_MASK),
        ("LIGHT_POINT", LIGHT_POINT),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
        ("LIGHT_AREA", LIGHT_AREA),
        ("AOV_COLOR", AOV_COLOR),
        ("AOV_NORMAL", AOV_NORMAL),
        ("AOV_DEPTH", AOV_DEPTH),
        ("AOV_COST", AOV_COST),
        ("PLANE_FLAG", gpurt::cpu::types::PLANE_FLAG),
        ("NO_PRIM", gpurt::cpu::types::NO_PRIM),
        ("PIXEL_CUT_SHORT", PIXEL_CUT_SHORT),
        ("WORKGROUP_SIDE", WORKGROUP_SIDE),
        ("WORKGROUP_INVOCATIONS", WORKGROUP_INVOCATIONS),
    ];
    for (name, value) in u32s {
        assert_eq!(
            wgsl_const(&module, name),
            naga::Literal::U32(value),
            "{name}"
        );
    }
    let f32s = [
        ("NO_HIT", gpurt::cpu::types::NO_HIT),
        ("SLAB_WIDEN", gpurt::cpu::intersect::SLAB_WIDEN),
    ];
    for (name, value) in f32s {
        assert_eq!(
            wgsl_const(&module, name),
            naga::Literal::F32(value),
            "{name}"
        );
    }
}

/// WGSL functions without a CPU twin, and why.
const WGSL_ONLY: &[(&str, &str)] = &[
    ("prim_kind", "reads the tag the CPU matches on directly"),
    ("prim_material", "reads the tag the CPU masks directly"),
    ("texel", "texture fetch: the CPU indexes the arrays"),
    ("load_node", "texture fetch: the CPU indexes the arrays"),
    ("load_prim", "texture fetch: the CPU indexes the arrays"),
    (
        "load_tri_normals",
        "texture fetch: the CPU indexes the arrays",
    ),
    ("load_prim_tag", "texture fetch: the CPU indexes the arrays"),
    (
        "load_wide_node",
        "texture fetch: the CPU indexes the arrays",
    ),
    ("node_count", "bit field the CPU's GpuNode methods read"),
    ("node_axis", "bit field the CPU's GpuNode methods read"),
    ("cone_valid", "inlined in the CPU's intersect_cone"),
    ("max_element", "glam's Vec3::max_element"),
    ("min_element", "glam's Vec3::min_element"),
    ("sign_of", "f32::signum"),
    ("main", "the entry point; the CPU's is sample_sum"),
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
        "gpu_walk",
        "Bindings for the binary walk: the CPU renders through the wide tree (wide.rs)",
    ),
    (
        "closest_in_leaf",
        "a leaf's primitives, shared by the CPU's binary and wide walks; inline in WGSL",
    ),
    (
        "transmit_leaf",
        "a leaf's primitives, shared by the CPU's binary and wide walks; inline in WGSL",
    ),
    (
        "stack_high_water",
        "the tests' probe of the stack bound; the shader's slice is sized from it",
    ),
    (
        "intersect_triangles4",
        "four triangles in SIMD lanes for the CPU's leaves; a GPU lane tests one",
    ),
];

/// Names of the functions defined in `src` (Rust or WGSL), in order, up to a test module.
fn function_names(src: &str) -> Vec<String> {
    src.lines()
        .take_while(|l| !l.starts_with("#[cfg(test)]"))
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l
                .strip_prefix("pub(crate) ")
                .or_else(|| l.strip_prefix("pub "))
                .unwrap_or(l);
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
    let (module, _) = shaders::validate().expect("shader validates");
    let known: Vec<String> = module
        .functions
        .iter()
        .filter_map(|(_, f)| f.name.clone())
        .chain(module.entry_points.iter().map(|e| e.name.clone()))
        .collect();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seen = Vec::new();
    for (file, text) in shaders::FILES {
        let stem = file.trim_end_matches(".wgsl");
        let wgsl = function_names(text);
        for f in &wgsl {
            assert!(known.contains(f), "{file}: naga does not list {f}");
        }
        seen.extend(wgsl.iter().cloned());
        let cpu_src = std::fs::read_to_string(root.join(format!("src/cpu/{stem}.rs")))
            .expect("the CPU twin exists");
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
}
