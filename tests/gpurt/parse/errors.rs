//! NFF errors: every error class reported at its exact line and column with a message
//! naming what was expected and what was found, absurd counts refused at the count, and
//! random damage to every reader's input giving Ok or Err, never a panic.

use std::panic::{AssertUnwindSafe, catch_unwind};

use gpurt::scene::io::FileKind;
use gpurt::scene::{self, nff, obj, stl};

use super::ply::Format;

use crate::common::inputs::{VIEW, ascii_stl, assert_error, header, parse_error, tetra, write};
use crate::common::{shared_scenes, temp_dir};

#[test]
fn truncated_entity_points_at_the_end_of_the_file() {
    assert_error(
        &format!("{VIEW}s 0 0 0"),
        6,
        8,
        &["sphere radius", "end of file"],
    );
    assert_error(
        &format!("{VIEW}p 3\n0.5 0.5 0.5\n1.5 0.5"),
        8,
        8,
        &["polygon vertex 2 of 3", "end of file"],
    );
    assert_error(
        &format!("{VIEW}pp 3\n0.0 0.0 0.0 0.0 0.0 1.0\n1.0 0.0 0.0 0.0 0.0"),
        8,
        20,
        &["normal of patch vertex 2 of 3", "end of file"],
    );
    // A file cut short by far more than a number is caught at the polygon's count.
    assert_error(
        &format!("{VIEW}p 3\n0 0 0\n1 0\n"),
        6,
        3,
        &["polygon of 3 vertices", "bytes left"],
    );
}

/// Another tracer's word for a statement is told NFF's, and where to look for lenience.
#[test]
fn another_tracers_word_is_told_the_nff_statement() {
    assert_error(
        &format!("{VIEW}sphere 0 0 0 1\n"),
        6,
        1,
        &["'sphere'", "NFF's statement for that is 's'", "--lenient"],
    );
    assert_error(&format!("{VIEW}Polygon 3\n"), 6, 1, &["is 'p'"]);
}

#[test]
fn polygon_with_fewer_vertices_than_its_count() {
    // The fourth vertex's first number is the next entity's keyword.
    assert_error(
        &format!("{VIEW}p 5\n0 0 0\n1 0 0\n1 1 0\ns 0 0 0 1\n"),
        10,
        1,
        &["polygon vertex 4 of 5", "'s'"],
    );
}

#[test]
fn absurd_counts_are_rejected_at_the_count() {
    assert_error(
        &format!("{VIEW}p 4000000000\n0 0 0\n1 0 0\n1 1 0\n"),
        6,
        3,
        &["4000000000", "bytes left"],
    );
    assert_error(
        &format!("{VIEW}pp 99999999999\n"),
        6,
        4,
        &["patch vertex count", "below 2^32", "'99999999999'"],
    );
    assert_error(
        &format!("{VIEW}p -3\n0 0 0\n1 0 0\n1 1 0\n"),
        6,
        3,
        &["non-negative", "'-3'"],
    );
    assert_error(&format!("{VIEW}p 3.5\n"), 6, 3, &["non-negative integer"]);
}

#[test]
fn non_numbers_and_non_finite_numbers() {
    assert_error(
        &format!("{VIEW}s 0 0 zero 1\n"),
        6,
        7,
        &["sphere centre", "(a number)", "'zero'"],
    );
    assert_error(&format!("{VIEW}s 0 nan 0 1\n"), 6, 5, &["finite", "'nan'"]);
    assert_error(&format!("{VIEW}s 0 0 0 inf\n"), 6, 9, &["radius", "finite"]);
    assert_error(&format!("{VIEW}s -inf 0 0 1\n"), 6, 3, &["finite"]);
    // Overflows f32 to infinity.
    assert_error(
        &format!("{VIEW}s 0 0 0 1e39\n"),
        6,
        9,
        &["finite", "'1e39'"],
    );
    assert_error(
        &format!("{VIEW}f 1 1 1 0.5 0.5 3 0 1.5.1\n"),
        6,
        21,
        &["index of refraction"],
    );
}

#[test]
fn unknown_keywords_and_stray_numbers_are_named() {
    assert_error(&format!("{VIEW}sphere 0 0 0 1\n"), 6, 1, &["'sphere'"]);
    assert_error(&format!("{VIEW}\n\n   cyl 1\n"), 8, 4, &["'cyl'"]);
    // The `l x y z intensity r g b` variant leaves a number where a keyword belongs.
    assert_error(
        &format!("{VIEW}l 1 2 3 0.5 1 1 1\n"),
        6,
        17,
        &["number '1'", "keyword"],
    );
    // Whole keywords only: `ppp` is not `pp`.
    assert_error(&format!("{VIEW}ppp 3\n"), 6, 1, &["'ppp'"]);
}

#[test]
fn sense8_nff_header_is_rejected() {
    assert_error("nff\nversion 2.0\n", 1, 1, &["Sense8"]);
    assert_error("# a comment first\n  nff\n", 2, 3, &["Sense8"]);
    // Only as the very first token: later it is just an unknown keyword.
    let (_, _, msg) = parse_error(&format!("{VIEW}nff\n"));
    assert!(!msg.contains("Sense8"), "{msg}");
}

#[test]
fn other_entity_errors() {
    assert_error(
        &format!("{VIEW}\nf 1 1 1 0.5 0.5 3 0.5 0\n"),
        7,
        1,
        &["index of refraction"],
    );
    assert_error(
        &format!("{VIEW}pl 0 0 0 1 1 1 2 2 2\n"),
        6,
        1,
        &["collinear"],
    );
    assert_error(&format!("{VIEW}dl 0 0 0\n"), 6, 1, &["zero direction"]);
    assert_error(
        &format!("{VIEW}al 0 0 5 1 0 0 0 1 0 1 1 1 0 4\n"),
        6,
        28,
        &["samples"],
    );
    assert_error(
        &format!("{VIEW}al 0 0 5 1 0 0 2 0 0 1 1 1 4 4\n"),
        6,
        1,
        &["parallel"],
    );
}

// ---------------------------------------------------------------------------------------
// Mutation: random damage must give Ok or Err, never a panic
// ---------------------------------------------------------------------------------------

/// xorshift64: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens worth inserting: digits and number parts, every keyword of every reader, counts
/// that lie, and line structure.
const INSERTS: &[&str] = &[
    "0",
    "1",
    "7",
    "9",
    "-",
    "e",
    "E",
    ".",
    "+",
    " ",
    "\n",
    "\r",
    "\r\n",
    "#",
    "nan",
    "inf",
    "1e39",
    "-3",
    "4000000000",
    "99999999999",
    "v",
    "b",
    "l",
    "f",
    "c",
    "s",
    "p",
    "pp",
    "pl",
    "aabb",
    "mesh",
    "dl",
    "al",
    "am",
    "from",
    "at",
    "up",
    "angle",
    "hither",
    "resolution",
    "aperture",
    "focal",
    "translate",
    "rotate",
    "scale",
    "nff",
    "p 3",
    "pp 3",
    "p 200",
    "mesh part.stl",
    "mesh part.obj",
    "mesh nope.stl",
    "solid",
    "endsolid",
    "facet",
    "normal",
    "outer",
    "loop",
    "vertex",
    "endloop",
    "endfacet",
    "vn",
    "vt",
    "f 1 2 3",
    "f 1//1 2//2 3//3",
    "f -1 -2 -3",
    "f 1/1/1 2/2/2 3/3/3",
    "/",
    "//",
    "o",
    "g",
    "usemtl",
    "mtllib x.mtl",
    "\0",
    "\u{ff}",
];

fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len() + 1);
        match rng.below(7) {
            // Replace a byte, or flip one bit of it.
            0 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
            }
            1 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
            // Delete a short run.
            2 => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                b.drain(at.min(end)..end);
            }
            // Insert a token.
            3 | 4 => {
                let t = INSERTS[rng.below(INSERTS.len())];
                b.splice(at..at, t.bytes());
            }
            // Duplicate the line around `at`.
            5 => {
                let start = b[..at]
                    .iter()
                    .rposition(|&c| c == b'\n')
                    .map_or(0, |i| i + 1);
                let end = b[at..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |i| at + i + 1);
                let line = b[start..end].to_vec();
                b.splice(start..start, line);
            }
            // Truncate.
            _ => b.truncate(at),
        }
    }
    b
}

#[test]
fn random_mutations_never_panic_a_reader() {
    let dir = temp_dir("mutation");
    // Mesh files for `mesh` statements in the mutated NFF text.
    let tris = tetra();
    let bin = stl::write_binary(&tris, &header(b"solid part"));
    write(&dir.join("part.stl"), &bin);
    let obj_src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nvn 0 0 1\nvt 0 0\nf 1//1 2//1 3//1 4//1\nf 1/1 2/1 5/1\nf -1 -2 -3\n";
    write(&dir.join("part.obj"), obj_src.as_bytes());

    enum Reader {
        Nff,
        Stl,
        Obj,
        Ply,
        Gltf,
    }
    let ext = format!(
        "{VIEW}hither 0.1\nresolution 64 48\naperture 0.1\nfocal 4\nam 0.1 0.1 0.1\ndl 0 0 -1\nal 0 0 5 1 0 0 0 1 0 1 1 1 2 2\nf 1 1 1 1 0 1 0 1\nmesh part.stl translate 1 2 3 rotate 0 0 90 scale 2\nmesh part.obj scale 1 2 3\npl 0 0 -1 1 0 -1 0 1 -1\naabb 0 1 0 1 0 1\nc 0 0 0 1 0 0 1 0.5\npp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"
    );
    let mut inputs: Vec<(String, Reader, Vec<u8>)> = vec![
        ("extensions.nff".into(), Reader::Nff, ext.into_bytes()),
        ("part.stl".into(), Reader::Stl, bin.clone()),
        (
            "part-ascii.stl".into(),
            Reader::Stl,
            ascii_stl(&tris).into_bytes(),
        ),
        ("part.obj".into(), Reader::Obj, obj_src.as_bytes().to_vec()),
    ];
    for (format, coloured) in [
        (Format::Ascii, false),
        (Format::Little, true),
        (Format::Big, false),
    ] {
        let bytes = super::ply::write(&super::ply::mesh(), format, coloured);
        inputs.push(("part.ply".into(), Reader::Ply, bytes));
    }
    for (name, bytes) in super::gltf::samples() {
        inputs.push((name.into(), Reader::Gltf, bytes));
    }
    if let Some(shared) = shared_scenes() {
        for f in [
            "spd/balls-1.nff",
            "spd/gears-1.nff",
            "spd/rings-1.nff",
            "spd/teapot-2.nff",
            "spd/tetra-3.nff",
            "spd/tree-1.nff",
            "p3d/mount_low.nff",
            "p3d/balls_low.nff",
        ] {
            let bytes = std::fs::read(shared.join(f)).expect("shared scene reads");
            inputs.push((f.into(), Reader::Nff, bytes));
        }
    }

    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let started = std::time::Instant::now();
    let (mut ok, mut err) = (0, 0);
    // A few hundred milliseconds by default; `GPURT_MUTATIONS=N` runs a longer soak.
    let mutations: usize = std::env::var("GPURT_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    for k in 0..mutations {
        let (name, reader, input) = &inputs[k % inputs.len()];
        let bytes = mutate(&mut rng, input);
        let result = catch_unwind(AssertUnwindSafe(|| match reader {
            Reader::Nff => nff::parse(&bytes, name, &dir).map(|s| s.triangles.len()),
            Reader::Stl => stl::parse(&bytes, name).map(|t| t.len()),
            Reader::Obj => obj::parse(&bytes, name).map(|t| t.len()),
            Reader::Ply => {
                scene::parse(&bytes, FileKind::Ply, name, &dir).map(|s| s.triangles.len())
            }
            Reader::Gltf => {
                scene::parse(&bytes, FileKind::Gltf, name, &dir).map(|s| s.triangles.len())
            }
        }));
        match result {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(_)) => err += 1,
            Err(_) => {
                let keep = dir.join(format!("panic-{k}-{}", name.replace('/', "_")));
                write(&keep, &bytes);
                panic!(
                    "mutation {k} of {name} made the reader panic; input kept at {}",
                    keep.display()
                );
            }
        }
    }
    // The mutations must exercise both outcomes, or they test nothing.
    assert!(
        ok > mutations / 20 && err > mutations / 20,
        "ok {ok}, err {err}"
    );
    eprintln!(
        "{mutations} mutations: {ok} parsed, {err} rejected, in {:?}",
        started.elapsed()
    );
}
