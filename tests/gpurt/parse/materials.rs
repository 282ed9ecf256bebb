//! OBJ materials (`mtllib`, `usemtl` and the `.mtl` library) as the readers give them to
//! bare meshes and to NFF's `mesh`, what is missing or unknown as warnings at their
//! place, and `--lenient` NFF (`ReadOptions::lenient`): foreign keywords skipped, each
//! with a warning.

use std::path::Path;

use glam::Vec3;
use gpurt::scene::{self, Material, MaterialId, ReadOptions, Scene};

use crate::common::inputs::VIEW;
use crate::common::workdir;

/// Two materials, and statements the model has no room for.
pub const MTL: &str = "# two colours\nnewmtl red\nKa 0.1 0.1 0.1\nKd 0.9 0.1 0.1\nKs 0 0 0\n\
    Ns 10\nillum 2\nmap_Kd red.png\n\nnewmtl green mirror\nKd 0.1 0.8 0.1\nKs 0.5 0.5 0.5\n\
    Ns 200\nillum 3\nmap_Kd green.png\nmap_Bump bump.png\n\nnewmtl glass\nKd 0 0 0\n\
    Ks 1 1 1\nd 0.2\nNi 1.5\nillum 7\n";

/// Two quads side by side in the plane z = 0 facing +z (OBJ is y-up): x in [-2, 0] red,
/// x in [0, 2] `green mirror`; a last triangle names a material nobody defines.
pub fn obj(mtllib: &str) -> String {
    format!(
        "# two quads\nmtllib {mtllib}\nv -2 0 0\nv 0 0 0\nv 0 2 0\nv -2 2 0\nv 2 0 0\nv 2 2 0\n\
         o left\nusemtl red\nf 1 2 3 4\no right\nusemtl green mirror\nf 2 5 6 3\n"
    )
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

fn load(path: &Path) -> Scene {
    scene::load(path).unwrap_or_else(|e| panic!("{e}"))
}

/// The material of each triangle, in order.
fn materials_of(s: &Scene) -> Vec<Material> {
    s.triangles
        .iter()
        .map(|t| s.materials[t.material.0 as usize])
        .collect()
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-6
}

#[test]
fn a_bare_obj_gets_the_materials_its_mtl_names() {
    let d = workdir("mtl-two");
    write(&d, "two.mtl", MTL);
    write(&d, "two.obj", &obj("two.mtl"));
    let s = load(&d.join("two.obj"));
    let m = materials_of(&s);
    assert_eq!(m.len(), 4);
    // Kd is the colour times the diffuse weight; Ks counts only from illum 3 up.
    assert!(
        close(m[0].color * m[0].kd, Vec3::new(0.9, 0.1, 0.1)),
        "{:?}",
        m[0]
    );
    assert_eq!(
        (m[0].ks, m[0].shine, m[0].t, m[0].ior),
        (0.0, 10.0, 0.0, 1.0)
    );
    assert_eq!(m[0], m[1]);
    assert!(
        close(m[2].color * m[2].kd, Vec3::new(0.1, 0.8, 0.1)),
        "{:?}",
        m[2]
    );
    assert_eq!((m[2].ks, m[2].shine), (0.5, 200.0));
    assert_eq!(m[2], m[3]);
    // The grey of faces without a material stays first, the ground comes last.
    assert_eq!(s.materials[0], Material::NEUTRAL_GREY);
    assert_eq!(
        s.planes[0].material,
        MaterialId(s.materials.len() as u32 - 1)
    );
    // Each statement the model cannot hold is named once, at its first place; each
    // texture that cannot be read where a face first uses its material.
    let file = d.join("two.mtl").display().to_string();
    let missing = |line, name, material| {
        format!(
            "{file}:{line}:1: texture '{name}' of material '{material}' is not used: cannot read '{name}': No such file or directory (os error 2); its faces keep the material's colour"
        )
    };
    assert_eq!(
        s.warnings,
        [
            format!(
                "{file}:16:1: 'map_Bump' is not read (of the maps, the shading model reads map_Kd only); skipped here and below"
            ),
            missing(8, "red.png", "red"),
            missing(15, "green.png", "green mirror"),
        ]
    );
}

#[test]
fn glass_and_dissolve_map_onto_transmission() {
    let d = workdir("mtl-glass");
    write(&d, "g.mtl", MTL);
    write(
        &d,
        "g.obj",
        "mtllib g.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\n",
    );
    let m = materials_of(&load(&d.join("g.obj")))[0];
    // A black diffuse colour leaves a white filter; d 0.2 lets 0.8 through, Ni bends it.
    assert_eq!((m.color, m.kd, m.ks, m.ior), (Vec3::ONE, 0.0, 1.0, 1.5));
    assert!((m.t - 0.8).abs() < 1e-6, "{m:?}");
}

#[test]
fn a_missing_library_and_an_unknown_name_are_warnings_at_their_place() {
    let d = workdir("mtl-missing");
    write(&d, "m.obj", &obj("nowhere.mtl"));
    let s = load(&d.join("m.obj"));
    let file = d.join("m.obj").display().to_string();
    assert_eq!(s.warnings.len(), 3, "{:?}", s.warnings);
    assert!(
        s.warnings[0].starts_with(&format!(
            "{file}:2:8: cannot read material library 'nowhere.mtl': "
        )),
        "{:?}",
        s.warnings
    );
    assert_eq!(
        s.warnings[1],
        format!(
            "{file}:10:1: unknown material 'red' (no material library read defines it); its faces get the default material"
        )
    );
    assert!(s.warnings[2].starts_with(&format!("{file}:13:1: unknown material 'green mirror'")));
    // Every face renders, in the grey.
    assert!(
        materials_of(&s)
            .iter()
            .all(|m| *m == Material::NEUTRAL_GREY)
    );

    // A library that is there, and a name it does not define.
    write(&d, "u.mtl", MTL);
    write(
        &d,
        "u.obj",
        &obj("u.mtl").replace("usemtl green mirror", "usemtl purple"),
    );
    let s = load(&d.join("u.obj"));
    let file = d.join("u.obj").display().to_string();
    let unknown: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.contains("unknown"))
        .collect();
    assert_eq!(
        unknown,
        [&format!(
            "{file}:13:1: unknown material 'purple' (no material library read defines it); its faces get the default material"
        )]
    );
    let m = materials_of(&s);
    assert!(close(m[0].color * m[0].kd, Vec3::new(0.9, 0.1, 0.1)));
    assert_eq!(m[2], Material::NEUTRAL_GREY);
}

#[test]
fn a_bad_number_in_a_library_is_an_error_in_the_library() {
    let d = workdir("mtl-bad");
    write(&d, "b.mtl", "newmtl red\nKd 0.9 zero 0.1\n");
    write(&d, "b.obj", &obj("b.mtl"));
    let e = scene::load(&d.join("b.obj")).unwrap_err().to_string();
    let file = d.join("b.mtl").display().to_string();
    assert!(
        e.starts_with(&format!(
            "{file}:2:8: expected Kd (a finite number), found 'zero'"
        )),
        "{e}"
    );
}

#[test]
fn in_an_nff_mesh_usemtl_wins_over_the_current_f_unless_nomtl() {
    let d = workdir("mtl-mesh");
    write(&d, "two.mtl", MTL);
    write(
        &d,
        "two.obj",
        &obj("two.mtl").replace("o left\nusemtl red\n", ""),
    );
    let nff = |extra: &str| format!("{VIEW}f 0 0 1 1 0 0 0 0\nmesh two.obj{extra}\n");
    write(&d, "a.nff", &nff(""));
    write(&d, "b.nff", &nff(" scale 2 nomtl"));
    let blue = |m: &Material| m.color == Vec3::new(0.0, 0.0, 1.0);
    // The left quad names no material: it keeps the NFF's; the right one is the library's.
    let m = materials_of(&load(&d.join("a.nff")));
    assert!(blue(&m[0]) && blue(&m[1]), "{m:?}");
    assert!(
        close(m[2].color * m[2].kd, Vec3::new(0.1, 0.8, 0.1)),
        "{m:?}"
    );
    // `nomtl`: the NFF's everywhere, and the library is not even read.
    let s = load(&d.join("b.nff"));
    assert!(materials_of(&s).iter().all(blue));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

/// An NFF written for another tracer: keywords gpurt does not know, with arguments.
pub const FOREIGN: &str = "Q 1 2 3\nfp 3\n0 0 0\n1 0 0\n0 1 0\nobj teapot.obj\n\
    s 0 0 0 1\nQ 4 5 6\ns 2 0 0 0.5\n";

#[test]
fn lenient_skips_foreign_keywords_to_the_next_known_one_with_a_warning_each() {
    let d = workdir("lenient");
    let src = format!("{VIEW}f 1 0 0 1 0 0 0 0\n{FOREIGN}");
    write(&d, "x.nff", &src);
    let path = d.join("x.nff");
    let file = path.display().to_string();
    // By default the first one ends the read.
    let e = scene::load(&path).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "{file}:7:1: expected an entity keyword, found 'Q'"
        )),
        "{e}"
    );
    let lenient = ReadOptions {
        lenient: true,
        ..ReadOptions::default()
    };
    let s = scene::load_with(&path, &lenient).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.spheres.len(), 2);
    let skipped: Vec<_> = s
        .warnings
        .iter()
        .map(|w| w.split(": ").next().unwrap().to_string())
        .collect();
    assert_eq!(skipped, [7, 8, 12, 14].map(|l| format!("{file}:{l}:1")));
    assert!(
        s.warnings[1]
            .ends_with("unknown keyword 'fp' skipped, with what follows it up to the next keyword"),
        "{:?}",
        s.warnings
    );
    // The summary (`gpurt info`) and the records read the same.
    let sum = scene::summary_with(&path, &lenient).unwrap();
    assert_eq!(sum.scene.warnings, s.warnings);
    assert_eq!(sum.prims.counts()[0], 2);
    // A stray number is still an error: it is no keyword.
    write(&d, "n.nff", &format!("{VIEW}Q 1\ns 0 0 0 1 7\n"));
    let e = scene::load_with(&d.join("n.nff"), &lenient)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(":7:11: expected an entity keyword, found the number '7'"),
        "{e}"
    );
}
