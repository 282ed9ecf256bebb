//! Mesh files (STL, OBJ, PLY) read into a sink, and the transform the `mesh` statement applies
//! to them on their way in (`Placed`).

use glam::{Mat3, Vec2, Vec3};

use super::bounds::Bounds;
use super::io::{FileKind, Input};
use super::lex::Lexer;
use super::model::{BoxPrim, Cone, MaterialId, Mesh, Sphere, Triangle, unit};
use super::sink::{MeshOut, Sink};
use super::{obj, ply, stl};
use crate::util::error::Result;

/// Reads a mesh file's triangles into `out` as they are read (`name` in messages).
pub fn read(input: Input, kind: FileKind, name: &str, out: &mut MeshOut) -> Result<()> {
    match kind {
        FileKind::Stl => stl::read(input, name, out.sink, (out.default, out.window)),
        FileKind::Obj => obj::read(Lexer::through(input, name, out.window), out),
        FileKind::Ply => ply::read(input, name, out),
        FileKind::Nff | FileKind::Gltf => Err(crate::util::error::Error::Scene {
            file: name.to_string(),
            msg: "a scene, not a mesh file (STL, OBJ or PLY)".into(),
        }),
    }
}

/// Parses a mesh file's bytes (gzip-compressed or not) into triangles with material 0;
/// an OBJ's materials are not read.
pub fn parse_mesh(bytes: &[u8], kind: FileKind, name: &str) -> Result<Mesh> {
    MeshOut::collect(|out| read(Input::bytes(bytes), kind, name, out))
}

/// `mesh PATH translate x y z rotate rx ry rz scale s`: applied scale, then rotation about
/// X, then Y, then Z (degrees), then translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshTransform {
    pub translate: Vec3,
    pub rotate_deg: Vec3,
    pub scale: Vec3,
}

impl Default for MeshTransform {
    fn default() -> Self {
        MeshTransform {
            translate: Vec3::ZERO,
            rotate_deg: Vec3::ZERO,
            scale: Vec3::ONE,
        }
    }
}

impl MeshTransform {
    /// The linear part: Rz * Ry * Rx * S.
    pub fn linear(&self) -> Mat3 {
        let r = self.rotate_deg * (std::f32::consts::PI / 180.0);
        Mat3::from_rotation_z(r.z)
            * Mat3::from_rotation_y(r.y)
            * Mat3::from_rotation_x(r.x)
            * Mat3::from_diagonal(self.scale)
    }

    pub fn apply(&self, tris: &mut [Triangle]) {
        let Some(m) = self.matrices() else { return };
        for t in tris {
            let (v, n, uv) = m.place(t.v, t.n.as_deref().copied(), t.uv.as_deref().copied());
            t.v = v;
            t.n = n.map(Box::new);
            t.uv = uv.map(Box::new);
        }
    }

    /// The matrices that place points and normals; `None` for the identity.
    fn matrices(&self) -> Option<Placement> {
        if *self == MeshTransform::default() {
            return None;
        }
        let m = self.linear();
        Some(Placement {
            m,
            // Normals transform by the inverse transpose (non-uniform scale bends them).
            nm: m.inverse().transpose(),
            translate: self.translate,
            mirrored: m.determinant() < 0.0,
        })
    }
}

#[derive(Clone, Copy)]
struct Placement {
    m: Mat3,
    nm: Mat3,
    translate: Vec3,
    /// A negative scale mirrors the mesh, which turns its triangles' winding: `place`
    /// turns it back, so that their front (an emitter's) stays the side it was.
    mirrored: bool,
}

impl Placement {
    /// The corners placed, and their normals and texture coordinates (which the
    /// placement does not move) kept at their corners.
    #[allow(clippy::type_complexity)]
    fn place(
        &self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
    ) -> ([Vec3; 3], Option<[Vec3; 3]>, Option<[Vec2; 3]>) {
        fn turn<T>(mirrored: bool, [a, b, c]: [T; 3]) -> [T; 3] {
            if mirrored { [a, c, b] } else { [a, b, c] }
        }
        let v = v.map(|p| self.m * p + self.translate);
        // A normal the transform leaves without a direction makes the triangle flat.
        let n = n.and_then(|[a, b, c]| {
            let unit = |v| unit(self.nm * v);
            Some([unit(a)?, unit(b)?, unit(c)?])
        });
        let m = self.mirrored;
        (turn(m, v), n.map(|n| turn(m, n)), uv.map(|uv| turn(m, uv)))
    }
}

/// A mesh on its way into a scene: every triangle transformed.
pub struct Placed<'a> {
    sink: &'a mut dyn Sink,
    placement: Option<Placement>,
    /// Triangles placed.
    pub placed: usize,
}

impl<'a> Placed<'a> {
    pub fn new(sink: &'a mut dyn Sink, xf: &MeshTransform) -> Self {
        Placed {
            sink,
            placement: xf.matrices(),
            placed: 0,
        }
    }
}

impl Sink for Placed<'_> {
    fn triangle(
        &mut self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
        material: MaterialId,
    ) {
        let (v, n, uv) = match &self.placement {
            Some(p) => p.place(v, n, uv),
            None => (v, n, uv),
        };
        self.placed += 1;
        self.sink.triangle(v, n, uv, material);
    }
    // Mesh files hold triangles only.
    fn sphere(&mut self, s: Sphere) {
        self.sink.sphere(s);
    }
    fn cone(&mut self, c: Cone) {
        self.sink.cone(c);
    }
    fn cuboid(&mut self, b: BoxPrim) {
        self.sink.cuboid(b);
    }
    fn count(&self) -> usize {
        self.sink.count()
    }
    fn bounds(&self) -> Bounds {
        self.sink.bounds()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::MaterialId;

    #[test]
    fn scale_then_rotate_then_translate() {
        let xf = MeshTransform {
            translate: Vec3::new(10.0, 0.0, 0.0),
            rotate_deg: Vec3::new(0.0, 0.0, 90.0),
            scale: Vec3::new(2.0, 1.0, 1.0),
        };
        let mut t = [Triangle {
            v: [Vec3::X, Vec3::Y, Vec3::Z],
            n: Some(Box::new([Vec3::X; 3])),
            material: MaterialId(0),
            uv: None,
        }];
        xf.apply(&mut t);
        // X scaled to 2, rotated onto +Y, moved by 10 in x.
        assert!((t[0].v[0] - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5);
        assert!((t[0].v[1] - Vec3::new(9.0, 0.0, 0.0)).length() < 1e-5);
        assert!((t[0].n.as_ref().unwrap()[0] - Vec3::Y).length() < 1e-5);
    }

    /// A negative scale mirrors the triangle; its winding is turned back, so that its
    /// front faces the mirror image of where it faced, with its normals kept at their
    /// corners.
    #[test]
    fn a_mirroring_scale_keeps_the_front() {
        let n = [Vec3::X, Vec3::Y, Vec3::Z];
        let mut t = [Triangle {
            v: [Vec3::ZERO, Vec3::X, Vec3::Y],
            n: Some(Box::new(n)),
            material: MaterialId(0),
            uv: None,
        }];
        assert_eq!(t[0].cross(), Vec3::Z);
        let xf = MeshTransform {
            scale: Vec3::new(1.0, 1.0, -1.0),
            ..MeshTransform::default()
        };
        xf.apply(&mut t);
        assert_eq!(t[0].cross(), -Vec3::Z);
        assert_eq!(t[0].v, [Vec3::ZERO, Vec3::Y, Vec3::X]);
        assert_eq!(*t[0].n.as_deref().unwrap(), [n[0], -n[2], n[1]]);
    }
}
