//! PLY reader (the Stanford polygon format of 3D scanners, the Stanford repository and
//! mesh tools): ASCII and binary of either byte order.
//!
//! What is read: the `vertex` element's `x y z`, its `nx ny nz` (shading normals, smooth
//! as NFF's `pp` patches) and its `red green blue`; the `face` element's `vertex_indices`
//! (or `vertex_index`) list, each face triangulated as OBJ polygons are, and its own
//! `red green blue` where it has them. Every other element and property is read past.
//!
//! Colours are per face: a face's own colour, else the mean of its corners', becomes its
//! material's colour (the neutral grey's terms otherwise). Both renderers shade a triangle
//! in one material; colours interpolated across it would need a colour for each corner in
//! the triangle records, 36 bytes more a triangle, for the few files that carry them.
//!
//! Written here rather than with a crate (`ply-rs` reads the whole file into maps of
//! properties, and has not been released since 2020) because the body must stream into
//! the sink, counts the file cannot hold must be refused before anything is allocated, and
//! errors must point at a line and column (the header, ASCII bodies) or a byte (binary).

mod body;
mod header;

use glam::Vec3;

use super::io::Input;
use super::lex::Lexer;
use super::model::{Material, MaterialId, unit};
use super::sink::MeshOut;
use super::triangulate::triangulate;
use crate::util::error::{Error, Result};
use crate::util::limits::{MAX_MESH_VERTICES, MAX_POLYGON_VERTICES, MAX_PRIMITIVES};
use body::{Body, Pos};
use header::{Element, Format, Kind, Scalar};

/// Reads a PLY file's faces into `out` as they are read, through a window of
/// `out.window` bytes where given.
pub fn read(input: Input, name: &str, out: &mut MeshOut) -> Result<()> {
    let mut lx = Lexer::through(input, name, out.window);
    let header = header::read(&mut lx)?;
    let mut body = match header.format {
        Format::Ascii => Body::ascii(lx),
        Format::Binary(big) => {
            let len = lx.input_len();
            let Some((rest, offset)) = lx.rest_after_line()? else {
                return Err(Error::Scene {
                    file: name.to_string(),
                    msg: "the file ends on the 'end_header' line, before any data".into(),
                });
            };
            Body::binary(rest, (offset, len), big, name, out.window)
        }
    };
    let mut mesh = Vertices::default();
    let mut faces = 0u64;
    for el in &header.elements {
        let least = el.least_bytes(header.format);
        if let Some(left) = body.remaining()
            && el.count.saturating_mul(least) > left
        {
            let msg = format!(
                "{} '{}' elements of at least {least} bytes each: more than the rest of the file holds ({left} bytes)",
                el.count, el.name
            );
            return Err(body.header_error(&el.at, msg));
        }
        match el.name.as_str() {
            "vertex" => {
                if el.count > MAX_MESH_VERTICES as u64 {
                    let msg = format!("more than {MAX_MESH_VERTICES} vertices");
                    return Err(body.header_error(&el.at, msg));
                }
                mesh = Vertices::read(&mut body, el)?;
            }
            "face" => {
                if el.count > MAX_PRIMITIVES as u64 {
                    let msg = format!("more than {MAX_PRIMITIVES} faces");
                    return Err(body.header_error(&el.at, msg));
                }
                faces += el.count;
                read_faces(&mut body, el, &mesh, out)?;
            }
            // Read past; an element without properties takes no bytes, however many.
            _ if el.props.is_empty() => {}
            _ => {
                let mut values = vec![0.0; el.props.len()];
                for _ in 0..el.count {
                    body.scalars(el, &mut values)?;
                }
            }
        }
    }
    body.finish()?;
    if faces == 0 {
        return Err(Error::Scene {
            file: name.to_string(),
            msg: "no faces: a PLY point cloud has no surface to render".into(),
        });
    }
    Ok(())
}

/// The `vertex` element as read: positions, and normals and colours where every vertex
/// has them.
#[derive(Default)]
struct Vertices {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    colours: Vec<Vec3>,
}

impl Vertices {
    fn read(body: &mut Body, el: &Element) -> Result<Vertices> {
        let xyz = |names: [&[&str]; 3]| names.map(|n| el.scalar(n));
        let [x, y, z] = xyz([&["x"], &["y"], &["z"]]);
        let (Some(x), Some(y), Some(z)) = (x, y, z) else {
            return Err(body.header_error(&el.at, "a 'vertex' element without x, y and z"));
        };
        let normal = match xyz([&["nx"], &["ny"], &["nz"]]) {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        };
        let colour = match xyz([
            &["red", "r", "diffuse_red"],
            &["green", "g", "diffuse_green"],
            &["blue", "b", "diffuse_blue"],
        ]) {
            [Some(a), Some(b), Some(c)] => Some([a, b, c]),
            _ => None,
        };
        let mut v = Vertices::default();
        let mut values = vec![0.0; el.props.len()];
        for i in 0..el.count {
            body.scalars(el, &mut values)?;
            let vec = |[a, b, c]: [(usize, Scalar); 3]| {
                Vec3::new(values[a.0] as f32, values[b.0] as f32, values[c.0] as f32)
            };
            let p = vec([x, y, z]);
            if !p.is_finite() {
                let msg = format!("vertex {i} is not finite: {p}");
                return Err(body.error(body.last(), msg));
            }
            v.positions.push(p);
            if let Some(n) = normal {
                v.normals.push(vec(n));
            }
            if let Some(c) = colour {
                let c = vec(c) / c[0].1.full() as f32;
                if !c.is_finite() {
                    return Err(
                        body.error(body.last(), format!("vertex {i}'s colour is not finite"))
                    );
                }
                v.colours.push(c);
            }
        }
        Ok(v)
    }
}

/// The face element's index list, and its own colour where it has one.
fn read_faces(body: &mut Body, el: &Element, mesh: &Vertices, out: &mut MeshOut) -> Result<()> {
    let list = el.props.iter().position(|p| {
        matches!(p.kind, Kind::List { .. })
            && matches!(p.name.as_str(), "vertex_indices" | "vertex_index")
    });
    let Some(list) = list else {
        return Err(body.header_error(&el.at, "a 'face' element without a vertex_indices list"));
    };
    let colour = ["red", "green", "blue"].map(|n| el.scalar(&[n]));
    let colour = match colour {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    let (mut poly, mut poly_n, mut idx) = (Vec::new(), Vec::new(), Vec::new());
    let mut corners: Vec<(u32, Pos)> = Vec::new();
    let mut values = vec![0.0; el.props.len()];
    let n_vertices = mesh.positions.len();
    for f in 0..el.count {
        corners.clear();
        body.face(el, list, &mut values, &mut corners)?;
        if corners.len() > MAX_POLYGON_VERTICES as usize {
            let msg = format!("face {f} has more than {MAX_POLYGON_VERTICES} corners");
            return Err(body.error(corners[0].1, msg));
        }
        poly.clear();
        poly_n.clear();
        for &(i, at) in &corners {
            let Some(&p) = mesh.positions.get(i as usize) else {
                let msg =
                    format!("face {f} refers to vertex {i}; the file has {n_vertices} before it");
                return Err(body.error(at, msg));
            };
            poly.push(p);
            if let Some(&n) = mesh.normals.get(i as usize) {
                poly_n.push(unit(n).unwrap_or(Vec3::ZERO));
            }
        }
        let material = match colour {
            Some(c) => {
                let c = Vec3::from(c.map(|(k, s)| values[k] as f32 / s.full() as f32));
                if !c.is_finite() {
                    return Err(body.error(body.last(), format!("face {f}'s colour is not finite")));
                }
                face_material(out, c)
            }
            None if !mesh.colours.is_empty() => {
                let sum: Vec3 = corners.iter().map(|&(i, _)| mesh.colours[i as usize]).sum();
                face_material(out, sum / corners.len().max(1) as f32)
            }
            None => out.default,
        };
        idx.clear();
        if poly.len() < 3 || !triangulate(&poly, &mut idx) {
            let at = corners.first().map_or(body.last(), |c| c.1);
            out.warnings.push(format!(
                "{}: degenerate face {f} with {} corners dropped",
                body.place(at),
                poly.len()
            ));
            continue;
        }
        if out.sink.count() + idx.len() > MAX_PRIMITIVES {
            return Err(body.error(
                corners[0].1,
                format!("more than {MAX_PRIMITIVES} triangles"),
            ));
        }
        let smooth = poly_n.len() == poly.len() && poly_n.iter().all(|n| n.length_squared() > 0.0);
        for &[a, b, c] in &idx {
            let ix = [a, b, c].map(|i| i as usize);
            let n = smooth.then(|| ix.map(|i| poly_n[i]));
            out.sink.triangle(ix.map(|i| poly[i]), n, None, material);
        }
    }
    Ok(())
}

/// The material of a face of colour `c`: the neutral grey's terms in that colour. A
/// colour out of [0, 1] (a float channel written as 0 to 255) is clamped.
fn face_material(out: &mut MeshOut, c: Vec3) -> MaterialId {
    let color = c.clamp(Vec3::ZERO, Vec3::ONE);
    out.palette.id(
        out.materials,
        Material {
            color,
            ..Material::NEUTRAL_GREY
        },
    )
}
