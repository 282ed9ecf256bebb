//! The readers read their input as a stream through a buffer of fixed size: every shared
//! and bundled scene reads the same through a tiny buffer, through the usual one and held
//! whole in one buffer as the readers used to hold it; a scene read straight into the
//! renderers' records packs to the very buffers the data model packs to; and statements
//! cut by the buffer's end read as if they were not, in every reader, plain and gzip.

use std::io::Write;
use std::path::Path;

use glam::Vec3;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::io::{self, Input};
use gpurt::scene::lex::Lexer;
use gpurt::scene::options::ReadOptions;
use gpurt::scene::{self, Collect, Scene, Triangle, nff, stl};

use crate::common::inputs::{VIEW, gzip, write};
use crate::common::{files_with, own_scenes, shared_scenes, temp_dir};

/// The scene file at `path` read through a lexer whose buffer holds `bytes`.
fn read_nff_through(path: &Path, bytes: usize) -> Scene {
    let name = path.display().to_string();
    let input = io::open(path).expect("opens");
    let mut prims = Collect::default();
    let base = path.parent().unwrap();
    let lx = Lexer::with_buffer(input, &name, bytes);
    let mut scene =
        nff::read(lx, base, &mut prims, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    prims.into_scene(&mut scene);
    scene
}

/// Everything both renderers read, field by field.
fn assert_same_buffers(a: &SceneBuffers, b: &SceneBuffers, what: &str) {
    assert_eq!(a.prims, b.prims, "{what}: primitives");
    assert_eq!(a.nodes, b.nodes, "{what}: nodes");
    assert_eq!(a.tri_normals, b.tri_normals, "{what}: normals");
    assert_eq!(a.planes, b.planes, "{what}: planes");
    assert_eq!(a.materials, b.materials, "{what}: materials");
    assert_eq!(a.lights, b.lights, "{what}: lights");
    assert_eq!(a.bounds, b.bounds, "{what}: bounds");
    assert_eq!(a.epsilon.to_bits(), b.epsilon.to_bits(), "{what}: epsilon");
    assert_eq!(a.camera, b.camera, "{what}: camera");
    assert_eq!(
        (a.background, a.ambient, a.bvh_depth),
        (b.background, b.ambient, b.bvh_depth),
        "{what}"
    );
}

#[test]
fn every_scene_reads_the_same_through_any_buffer_and_packs_the_same_from_records() {
    let mut files = files_with(&own_scenes(), &[".nff", ".stl"]);
    if let Some(dir) = shared_scenes() {
        files.extend(files_with(&dir, &[""]));
    }
    let mut checked = 0;
    for path in &files {
        let what = path.display().to_string();
        let streamed = scene::load(path).unwrap_or_else(|e| panic!("{what}: {e}"));
        if scene::io::FileKind::of(path) == scene::io::FileKind::Nff {
            // Whole, as the reader held files before it streamed them: no refill ever.
            let len = scene::io::read_file(path).expect("reads").len();
            assert_eq!(read_nff_through(path, len + 1), streamed, "{what}: whole");
            // A buffer of 777 bytes cuts tokens, comments and line ends everywhere.
            assert_eq!(read_nff_through(path, 777), streamed, "{what}: 777 bytes");
        }
        let c = &streamed.camera;
        let samples = u64::from(c.width) * u64::from(c.height);
        let from_model = pack::pack_for(streamed, samples).expect("packs");
        let flat = scene::load_flat(path).expect("loads into records");
        let from_records = pack::pack_flat(flat, samples).expect("packs");
        assert_same_buffers(&from_records, &from_model, &what);
        checked += 1;
    }
    assert!(checked >= 9, "{checked} scenes");
}

/// The packing check above finds a difference when there is one: one primitive more
/// in the records gives other buffers.
#[test]
fn the_packing_comparison_fails_on_another_scene() {
    let path = own_scenes().join("spheres.nff");
    let a = pack::pack(scene::load(&path).unwrap()).unwrap();
    let mut moved = scene::load(&path).unwrap();
    moved.spheres[0].radius *= 1.0001;
    let b = pack::pack(moved).unwrap();
    let same = std::panic::catch_unwind(|| assert_same_buffers(&a, &b, "moved"));
    assert!(same.is_err());
}

/// The usual buffer: 256 KiB.
const BUFFER: usize = 256 << 10;

/// Bytes in memory fill the buffer exactly: a sphere whose numbers the buffer's end cuts
/// `cut` bytes into it reads as a whole.
#[test]
fn a_statement_cut_by_the_buffers_end_reads_as_a_whole() {
    for cut in [1, 2, 5, 9, 13, 26] {
        let mut src = VIEW.as_bytes().to_vec();
        while src.len() + 40 < BUFFER - cut {
            src.extend_from_slice(b"# filler of the buffer's first fill\n");
        }
        src.resize(BUFFER - cut, b' ');
        src.extend_from_slice(b"s 1.2500 -2.750 3.125 0.5\r\ns 7 8 9 1\n# end\n");
        let s = nff::parse(&src, "s.nff", Path::new(".")).unwrap();
        let got: Vec<(Vec3, f32)> = s.spheres.iter().map(|s| (s.center, s.radius)).collect();
        let want = [
            (Vec3::new(1.25, -2.75, 3.125), 0.5),
            (Vec3::new(7.0, 8.0, 9.0), 1.0),
        ];
        assert_eq!(got, want, "cut {cut}");
    }
}

/// Files of several buffers' worth of statements of every reader, plain and gzip (read
/// in pieces of whatever size the decoder gives): wherever the buffer's ends fall, every
/// statement reads with its own numbers.
#[test]
fn files_larger_than_the_buffer_read_every_statement_in_every_reader() {
    let dir = temp_dir("straddle");
    let n = 40_000;
    let mut nff_src = VIEW.to_string();
    let mut obj_src = String::from("# a strip\n");
    let mut stl_src = String::from("solid strip\n");
    for i in 0..n {
        let (x, y) = (i as f32 + 0.5, (i % 97) as f32 * 0.25);
        nff_src.push_str(&format!("s {x} {y} -{} 0.{}\n", i % 13, i % 9 + 1));
        obj_src.push_str(&format!("v {i} {} 0\n", i % 2));
        if i >= 2 {
            obj_src.push_str(&format!("f {} {} {i}\n", i - 1, i + 1));
        }
        stl_src.push_str(&format!(
            "facet normal 0 0 1\n outer loop\n  vertex {x} {y} 0\n  vertex {} {y} 0\n  \
             vertex {x} {} 0\n endloop\nendfacet\n",
            x + 1.0,
            y + 1.0
        ));
    }
    stl_src.push_str("endsolid strip\n");
    assert!(nff_src.len() > 3 * BUFFER && obj_src.len() > 3 * BUFFER);
    let files = [
        ("s.nff", nff_src.as_bytes()),
        ("q.obj", obj_src.as_bytes()),
        ("t.stl", stl_src.as_bytes()),
    ];
    for (name, src) in files {
        for (file, bytes) in [
            (name.to_string(), src.to_vec()),
            (format!("{name}.gz"), gzip(src)),
        ] {
            write(&dir.join(&file), &bytes);
            let s = scene::load(&dir.join(&file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            if name.ends_with(".nff") {
                assert_eq!(s.spheres.len(), n, "{file}");
                for (i, s) in s.spheres.iter().enumerate() {
                    let want =
                        Vec3::new(i as f32 + 0.5, (i % 97) as f32 * 0.25, -((i % 13) as f32));
                    assert_eq!(s.center, want, "{file}: sphere {i}");
                    assert_eq!(s.radius, (i % 9 + 1) as f32 / 10.0, "{file}: sphere {i}");
                }
            } else if name.ends_with(".obj") {
                assert_eq!(s.triangles.len(), n - 2, "{file}");
                for (k, t) in s.triangles.iter().enumerate() {
                    let xs = t.v.map(|v| v.x);
                    assert_eq!(
                        xs,
                        [k as f32, k as f32 + 2.0, k as f32 + 1.0],
                        "{file}: {k}"
                    );
                }
            } else {
                assert_eq!(s.triangles.len(), n, "{file}");
                for (i, t) in s.triangles.iter().enumerate() {
                    let o = Vec3::new(i as f32 + 0.5, (i % 97) as f32 * 0.25, 0.0);
                    assert_eq!(t.v, [o, o + Vec3::X, o + Vec3::Y], "{file}: facet {i}");
                }
            }
        }
    }
}

/// A binary STL larger than its reader's buffers, plain and gzip (whose size is not known
/// before it is read): the same triangles as one read from memory, and a truncated or
/// over-long one reported at the same byte as there.
#[test]
fn binary_stl_streams_and_reports_its_size_errors_plain_and_gzip() {
    let dir = temp_dir("stl-stream");
    let tris: Vec<Triangle> = (0..20_000)
        .map(|i| {
            let o = Vec3::new(i as f32, (i % 7) as f32, 0.5);
            Triangle {
                v: [o, o + Vec3::X, o + Vec3::Y],
                n: (i % 2 == 0).then(|| Box::new([Vec3::Z; 3])),
                material: scene::MaterialId(0),
                uv: None,
            }
        })
        .collect();
    let bin = stl::write_binary(&tris, &[b'x'; 80]);
    assert!(bin.len() > 3 * BUFFER);
    let cut = bin[..bin.len() - 30].to_vec();
    let long = [bin.clone(), vec![1; 7]].concat();
    for (name, bytes) in [("b.stl", bin.clone()), ("b.stl.gz", gzip(&bin))] {
        write(&dir.join(name), &bytes);
        let s = scene::load(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.triangles, tris, "{name}");
    }
    for (bytes, offset) in [(cut, bin.len() - 30), (long, 80)] {
        let in_memory = stl::parse(&bytes, "x.stl").unwrap_err().to_string();
        assert!(
            in_memory.contains(&format!("at byte {offset}:")),
            "{in_memory}"
        );
        for (name, file) in [("x.stl", bytes.clone()), ("x.stl.gz", gzip(&bytes))] {
            write(&dir.join(name), &file);
            let e = scene::load(&dir.join(name)).unwrap_err().to_string();
            let msg = |m: &str| m.split_once(": ").map(|(_, m)| m.to_string());
            assert_eq!(msg(&e), msg(&in_memory), "{name}");
        }
    }
}

/// A gzip stream's members, zero padding after them and junk after that, when the
/// stream is read as the readers read it (in pieces) rather than whole.
#[test]
fn gzip_streams_in_pieces_as_whole() {
    let src = format!("{VIEW}s 0 0 0 1\n");
    let gz = [gzip(src.as_bytes()), gzip(b"s 1 1 1 1\n"), vec![0; 3000]].concat();
    let mut input = Input::bytes(&gz);
    let mut out = Vec::new();
    let mut piece = [0u8; 3];
    loop {
        let n = std::io::Read::read(&mut input.reader, &mut piece).unwrap();
        if n == 0 {
            break;
        }
        out.extend_from_slice(&piece[..n]);
    }
    assert_eq!(out, format!("{src}s 1 1 1 1\n").into_bytes());
    let s = nff::parse(&gz, "g.nff", Path::new(".")).unwrap();
    assert_eq!(s.spheres.len(), 2);
    let mut junk = gz.clone();
    junk.push(7);
    let e = nff::parse(&junk, "g.nff", Path::new(".")).unwrap_err();
    assert!(e.to_string().starts_with("g.nff: "), "{e}");
}

/// What `gpurt info` reads a large file with keeps nothing of its primitives: the same
/// counts and bounds as the whole scene.
#[test]
fn the_summary_counts_and_bounds_what_the_scene_holds() {
    let dir = temp_dir("summary");
    let mut f = std::fs::File::create(dir.join("many.nff")).unwrap();
    f.write_all(VIEW.as_bytes()).unwrap();
    for i in 0..2000 {
        writeln!(f, "s {i} 0 0 0.5\np 3\n0 0 {i}\n1 0 {i}\n0 1 {i}").unwrap();
    }
    f.write_all(b"c 0 0 0 1 0 0 2 0.5\naabb 0 1 0 1 -3 4\n")
        .unwrap();
    drop(f);
    let whole = scene::load(&dir.join("many.nff")).unwrap();
    let summary = scene::summary(&dir.join("many.nff")).unwrap();
    assert_eq!(summary.counts(), [2000, 2000, 1, 1]);
    assert_eq!(summary.bounds(), whole.bounds());
    assert!(summary.scene.spheres.is_empty() && summary.scene.triangles.is_empty());
    assert_eq!(summary.scene.materials, whole.materials);
}

/// A parse error quotes its line through any buffer: whole where the buffer holds the
/// line, from `...` where a small buffer has dropped the line's start; an error at a token
/// read long before (the `v` of a degenerate view) quotes it too.
#[test]
fn errors_quote_their_line_through_any_buffer() {
    let excerpt = |src: &str, bytes: usize| {
        let lx = Lexer::with_buffer(Input::bytes(src.as_bytes()), "t.nff", bytes);
        match nff::read(
            lx,
            Path::new("."),
            &mut Collect::default(),
            &Default::default(),
        ) {
            Err(gpurt::Error::Parse {
                excerpt: Some(x), ..
            }) => x,
            other => panic!("{bytes}: {other:?}"),
        }
    };
    let bad = format!("{VIEW}s 0 0 zero 1\n");
    for bytes in [64, 4096, 1 << 20] {
        let x = excerpt(&bad, bytes);
        assert_eq!(x.text, "s 0 0 zero 1", "{bytes}");
        assert_eq!(&x.text[x.span.clone()], "zero", "{bytes}");
    }
    let x = excerpt(&bad, 8);
    assert!(x.text.starts_with("..."), "{x:?}");
    assert_eq!(&x.text[x.span.clone()], "zero", "{x:?}");
    let degenerate = format!(
        "v\nfrom 1 2 3\nat 1 2 3\nup 0 0 1\nangle 45\n{}",
        "# c\n".repeat(5000)
    );
    let x = excerpt(&degenerate, 1 << 20);
    assert_eq!((x.text.as_str(), x.span.clone()), ("v", 0..1));
}

/// Every reader through a tiny window (`ReadOptions::window`), as through the usual one:
/// an OBJ with its `.mtl` library (materials, comments, every face form, polygons), an
/// ASCII and a binary STL, and an NFF that includes all three with `mesh`. Windows of 61
/// bytes and up cut tokens, lines and binary records everywhere.
#[test]
fn obj_mtl_stl_and_mesh_includes_read_the_same_through_a_tiny_window() {
    let dir = temp_dir("tiny-window");
    let mut mtl = String::new();
    let mut obj = String::from("# a fan of polygons\nmtllib lib.mtl\n");
    for m in 0..12 {
        mtl.push_str(&format!(
            "# material {m}\nnewmtl m{m}\nKd 0.{m} 0.5 0.25\nKs 0.125 0.125 0.125\nNs {}\n\n",
            10 + m
        ));
    }
    for i in 0..300 {
        let (x, y) = ((i % 17) as f32 * 0.5, (i / 17) as f32 * 0.25);
        obj.push_str(&format!(
            "v {x} {y} {}\nvt 0.{} 0.5\nvn 0 0 1\n",
            i % 3,
            i % 10
        ));
    }
    for i in 1..296 {
        if i % 25 == 1 {
            obj.push_str(&format!("usemtl m{}\n", i % 12));
        }
        obj.push_str(&match i % 4 {
            0 => format!("f {i} {} {}\n", i + 1, i + 2),
            1 => format!("f {i}/{i} {}/{} {}/{}\n", i + 1, i + 1, i + 2, i + 2),
            2 => format!("f {i}//{i} {}//{} {}//{}\n", i + 1, i + 1, i + 2, i + 2),
            _ => format!("f {i}/{i}/{i} {} {} {}  # a quad\n", i + 1, i + 3, i + 2),
        });
    }
    let tris: Vec<Triangle> = (0..400)
        .map(|i| {
            let o = Vec3::new(i as f32 * 0.1, (i % 7) as f32, 0.5);
            Triangle {
                v: [o, o + Vec3::X, o + Vec3::Y],
                n: (i % 2 == 0).then(|| Box::new([Vec3::Z; 3])),
                material: scene::MaterialId(0),
                uv: None,
            }
        })
        .collect();
    let mut ascii = String::from("solid fan\n");
    for t in &tris {
        let [a, b, c] = t.v;
        ascii.push_str(&format!(
            "facet normal 0 0 1\n outer loop\n  vertex {} {} {}\n  vertex {} {} {}\n  \
             vertex {} {} {}\n endloop\nendfacet\n",
            a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z
        ));
    }
    ascii.push_str("endsolid fan\n");
    let nff = format!(
        "{VIEW}f 1 0 0 1 0 0 0 0\nmesh fan.obj translate 0 0 1\nf 0 1 0 1 0 0 0 0\n\
         mesh fan.stl scale 2\nmesh bin.stl rotate 0 0 30\n"
    );
    write(&dir.join("lib.mtl"), mtl.as_bytes());
    write(&dir.join("fan.obj"), obj.as_bytes());
    write(&dir.join("fan.stl"), ascii.as_bytes());
    write(&dir.join("bin.stl"), &stl::write_binary(&tris, &[b'x'; 80]));
    write(&dir.join("all.nff"), nff.as_bytes());
    for name in ["fan.obj", "fan.stl", "bin.stl", "all.nff"] {
        let path = dir.join(name);
        let usual = scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(usual.triangles.len() >= 295, "{name}");
        if name == "fan.obj" {
            assert!(
                usual.materials.len() > 10,
                "{name}: the library's materials"
            );
        }
        for window in [61, 97, 333, 4099] {
            let opts = ReadOptions {
                window: Some(window),
                ..ReadOptions::default()
            };
            let tiny = scene::load_with(&path, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(tiny, usual, "{name} through {window} bytes");
        }
    }
    // The comparison sees a change: one vertex moved in the library-less copy.
    let moved = obj.replacen("v 0 0 0\n", "v 0 0 0.5\n", 1);
    write(&dir.join("moved.obj"), moved.as_bytes());
    assert_ne!(
        scene::load(&dir.join("moved.obj")).unwrap(),
        scene::load(&dir.join("fan.obj")).unwrap()
    );
}
