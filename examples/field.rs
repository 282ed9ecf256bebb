//! Large generated scenes for the memory benchmarks (`benches/scene-memory.sh`), none of them
//! from the SPD, so that the readers and the tree are measured on scenes they were not
//! tuned on:
//!
//!     cargo run --release --example field -- terrain N [nff|obj|stl|ply] > out
//!     cargo run --release --example field -- spheres N > out.nff
//!
//! `terrain N` is a height field of N x N cells, two triangles a cell (2 N^2 triangles:
//! N = 1000 gives two million), its heights a sum of a few waves, as NFF `p 3` polygons,
//! an OBJ mesh (shared vertices, `f` faces), a binary STL, or a binary PLY (shared
//! vertices). `spheres N` is a field of N x N spheres of varying radius on a plane
//! (N = 1000 gives a million). Both stream out as they are generated.

use std::io::{self, BufWriter, Write};

fn height(x: f64, y: f64) -> f64 {
    0.08 * (x * 7.3).sin() * (y * 5.1).cos()
        + 0.03 * (x * 23.0 + y * 17.0).sin()
        + 0.01 * (x * 71.0).cos() * (y * 67.0).sin()
}

const VIEW: &str = "v\nfrom 0.5 -0.9 0.9\nat 0.5 0.5 0\nup 0 0 1\nangle 40\nhither 0.001\n\
                    resolution 256 256\nb 0.2 0.3 0.5\nl 0.2 -0.5 2\nl 1 0.2 1.5\n";

pub fn terrain(n: usize, format: &str, out: &mut impl Write) -> io::Result<()> {
    let p = |i: usize, j: usize| {
        let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
        [x as f32, y as f32, height(x, y) as f32]
    };
    match format {
        "nff" => {
            out.write_all(VIEW.as_bytes())?;
            out.write_all(b"f 0.6 0.55 0.4 0.8 0.1 10 0 1\n")?;
            for j in 0..n {
                for i in 0..n {
                    let [a, b, c, d] = [p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)];
                    for tri in [[a, b, c], [a, c, d]] {
                        out.write_all(b"p 3\n")?;
                        for v in tri {
                            writeln!(out, "{} {} {}", v[0], v[1], v[2])?;
                        }
                    }
                }
            }
        }
        "obj" => {
            writeln!(out, "# terrain of {n} x {n} cells")?;
            for j in 0..=n {
                for i in 0..=n {
                    let v = p(i, j);
                    writeln!(out, "v {} {} {}", v[0], v[1], v[2])?;
                }
            }
            let id = |i: usize, j: usize| j * (n + 1) + i + 1;
            for j in 0..n {
                for i in 0..n {
                    let [a, b, c, d] = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                    writeln!(out, "f {a} {b} {c}\nf {a} {c} {d}")?;
                }
            }
        }
        "stl" => {
            out.write_all(&[0; 80])?;
            out.write_all(&(2 * n as u32 * n as u32).to_le_bytes())?;
            for j in 0..n {
                for i in 0..n {
                    let [a, b, c, d] = [p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)];
                    for tri in [[a, b, c], [a, c, d]] {
                        out.write_all(&[0; 12])?; // no facet normal: shaded flat
                        for v in tri {
                            for x in v {
                                out.write_all(&x.to_le_bytes())?;
                            }
                        }
                        out.write_all(&[0; 2])?;
                    }
                }
            }
        }
        "ply" => {
            let (verts, faces) = ((n + 1) * (n + 1), 2 * n * n);
            write!(
                out,
                "ply\nformat binary_little_endian 1.0\ncomment terrain of {n} x {n} cells\n\
                 element vertex {verts}\nproperty float x\nproperty float y\nproperty float z\n\
                 element face {faces}\nproperty list uchar uint vertex_indices\nend_header\n"
            )?;
            for j in 0..=n {
                for i in 0..=n {
                    for x in p(i, j) {
                        out.write_all(&x.to_le_bytes())?;
                    }
                }
            }
            let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
            for j in 0..n {
                for i in 0..n {
                    let [a, b, c, d] = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                    for tri in [[a, b, c], [a, c, d]] {
                        out.write_all(&[3])?;
                        for v in tri {
                            out.write_all(&v.to_le_bytes())?;
                        }
                    }
                }
            }
        }
        other => {
            return Err(io::Error::other(format!(
                "unknown terrain format {other}: nff, obj, stl or ply"
            )));
        }
    }
    Ok(())
}

pub fn spheres(n: usize, out: &mut impl Write) -> io::Result<()> {
    out.write_all(VIEW.as_bytes())?;
    out.write_all(b"f 0.7 0.7 0.7 1 0 1 0 1\npl 0 0 0  1 0 0  0 1 0\n")?;
    out.write_all(b"f 0.8 0.3 0.2 0.7 0.3 30 0 1\n")?;
    let step = 1.0 / n as f64;
    for j in 0..n {
        for i in 0..n {
            let (x, y) = ((i as f64 + 0.5) * step, (j as f64 + 0.5) * step);
            let r = step * (0.25 + 0.2 * (0.5 + 0.5 * (x * 37.0 + y * 11.0).sin()));
            writeln!(out, "s {} {} {} {}", x as f32, y as f32, r as f32, r as f32)?;
        }
    }
    Ok(())
}

fn main() -> io::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = || io::Error::other("usage: field terrain N [nff|obj|stl|ply] | field spheres N");
    let n: usize = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .filter(|&n| n > 0)
        .ok_or_else(usage)?;
    let stdout = io::stdout();
    let mut out = BufWriter::with_capacity(1 << 20, stdout.lock());
    match args[0].as_str() {
        "terrain" => terrain(n, args.get(2).map_or("nff", String::as_str), &mut out)?,
        "spheres" => spheres(n, &mut out)?,
        _ => return Err(usage()),
    }
    out.flush()
}
