//! The NFF reader's shapes: spheres (`s`), cones and cylinders (`c`), polygons and
//! patches (`p`, `pp`: triangulated, a patch's vertex normals kept), P3D's infinite planes
//! (`pl`) and boxes (`aabb`), each with the current material.

use glam::Vec3;

use super::{Parser, blocks};
use crate::scene::lex::Token;
use crate::scene::model::{BoxPrim, Cone, Plane, Sphere, unit};
use crate::scene::sink::Sink;
use crate::scene::triangulate::triangulate;
use crate::util::error::Result;
use crate::util::limits::MAX_POLYGON_VERTICES;

impl Parser<'_> {
    pub(super) fn sphere(&mut self, tok: &Token) -> Result<()> {
        let center = self.lx.vec3("sphere centre")?;
        let radius = self.lx.number("sphere radius")?;
        let material = self.current_material();
        if radius == 0.0 {
            self.warn(tok, "sphere of radius 0 dropped");
        } else {
            self.room(tok, 1)?;
            self.route().sphere(Sphere {
                center,
                radius: radius.abs(),
                material,
            });
        }
        Ok(())
    }

    pub(super) fn cone(&mut self, tok: &Token) -> Result<()> {
        let base = self.lx.vec3("cone base centre")?;
        let base_radius = self.lx.number("cone base radius")?;
        let apex = self.lx.vec3("cone apex centre")?;
        let apex_radius = self.lx.number("cone apex radius")?;
        let material = self.current_material();
        self.room(tok, 1)?;
        self.route().cone(Cone {
            base,
            base_radius: base_radius.abs(),
            apex,
            apex_radius: apex_radius.abs(),
            material,
        });
        Ok(())
    }

    pub(super) fn polygon(&mut self, tok: &Token, patch: bool) -> Result<()> {
        let kind = if patch { "patch" } else { "polygon" };
        let what = if patch {
            "patch vertex count"
        } else {
            "polygon vertex count"
        };
        let (n, ntok) = self.lx.count(what)?;
        // Each vertex needs at least 3 (or 6) one-character numbers and separators: a count
        // the rest of the file cannot hold is a lie, reported before anything is allocated.
        let min_bytes = n as u64 * if patch { 12 } else { 6 };
        if let Some(rest) = self.lx.remaining().filter(|&rest| min_bytes > rest + 1) {
            return Err(self.lx.error_at(
                &ntok,
                format!(
                    "{kind} of {n} vertices, but the file has only {rest} bytes left: too few to hold them (is the count right?)"
                ),
            ));
        }
        // Where the rest is unknown (gzip), the vertices are held only up to a limit.
        if n > MAX_POLYGON_VERTICES {
            return Err(self.lx.error_at(
                &ntok,
                format!("{kind} vertex count {n} is above the limit of {MAX_POLYGON_VERTICES}"),
            ));
        }
        self.verts.clear();
        self.normals.clear();
        for i in 0..n {
            let mut what = VertexWhat {
                kind,
                index: i + 1,
                count: n,
                normal: false,
            };
            self.verts.push(self.lx.vec3(&what)?);
            if patch {
                what.normal = true;
                self.normals.push(self.lx.vec3(&what)?);
            }
        }
        let material = self.current_material();
        self.tris.clear();
        if n < 3 || !triangulate(&self.verts, &mut self.tris) {
            self.warn(tok, &format!("degenerate {kind} with {n} vertices dropped"));
            return Ok(());
        }
        // Shading normals are kept as unit vectors; a patch with a normal that has no
        // direction (zero) would shade to 0 / 0, so it is read as a flat polygon.
        let mut zero = None;
        for (i, n) in self.normals.iter_mut().enumerate() {
            match unit(*n) {
                Some(u) => *n = u,
                None => zero = zero.or(Some(i + 1)),
            }
        }
        if let Some(i) = zero {
            let msg = format!("normal of patch vertex {i} is zero; the patch is shaded flat");
            self.warn(tok, &msg);
        }
        let smooth = patch && zero.is_none();
        self.room(tok, self.tris.len())?;
        let mut out = blocks::Route::new(&mut *self.sink, &mut self.blocks);
        for &[a, b, c] in &self.tris {
            let (a, b, c) = (a as usize, b as usize, c as usize);
            let n = smooth.then(|| [self.normals[a], self.normals[b], self.normals[c]]);
            let v = [self.verts[a], self.verts[b], self.verts[c]];
            out.triangle(v, n, None, material);
        }
        Ok(())
    }

    pub(super) fn plane(&mut self, tok: &Token) -> Result<()> {
        let a = self.lx.vec3("plane point 1")?;
        let b = self.lx.vec3("plane point 2")?;
        let c = self.lx.vec3("plane point 3")?;
        let n = (b - a).cross(c - a);
        if n.length_squared() == 0.0 || !n.is_finite() {
            return Err(self
                .lx
                .error_at(tok, "degenerate plane: its three points are collinear"));
        }
        let material = self.current_material();
        self.put_plane(Plane {
            point: a,
            normal: n.normalize(),
            material,
        });
        Ok(())
    }

    pub(super) fn aabb(&mut self, tok: &Token) -> Result<()> {
        let mut lo = [0.0f32; 3];
        let mut hi = [0.0f32; 3];
        const WHAT: [[&str; 2]; 3] = [
            ["box x min", "box x max"],
            ["box y min", "box y max"],
            ["box z min", "box z max"],
        ];
        for (axis, [wmin, wmax]) in WHAT.iter().enumerate() {
            let a = self.lx.number(wmin)?;
            let b = self.lx.number(wmax)?;
            lo[axis] = a.min(b);
            hi[axis] = a.max(b);
        }
        let material = self.current_material();
        self.room(tok, 1)?;
        self.route().cuboid(BoxPrim {
            min: Vec3::from(lo),
            max: Vec3::from(hi),
            material,
        });
        Ok(())
    }
}

/// "polygon vertex 3 of 5" (or "normal of patch vertex ..."), formatted only for a message:
/// building this string for every vertex read cost more than parsing the vertex.
struct VertexWhat {
    kind: &'static str,
    index: u32,
    count: u32,
    normal: bool,
}

impl std::fmt::Display for VertexWhat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.normal {
            f.write_str("normal of ")?;
        }
        write!(f, "{} vertex {} of {}", self.kind, self.index, self.count)
    }
}
