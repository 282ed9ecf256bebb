//! Mesh files (STL, OBJ, PLY) read into a sink, and the transform the `mesh` statement applies
//! to them on their way in (its `Placement`, through `place::Placed`).

use glam::{DAffine3, Mat3, Vec3};

use super::io::{FileKind, Input};
use super::lex::Lexer;
use super::model::{Mesh, Triangle};
use super::place::Placement;
use super::sink::MeshOut;
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
        let Some(p) = self.placement() else { return };
        for t in tris {
            let (v, n, uv) = p.triangle(t.v, t.n.as_deref().copied(), t.uv.as_deref().copied());
            t.v = v;
            t.n = n.map(Box::new);
            t.uv = uv.map(Box::new);
        }
    }

    /// The placement this transform makes; `None` for the identity (nothing moves) and
    /// for a zero scale (which the reader refuses).
    pub fn placement(&self) -> Option<Placement> {
        if *self == MeshTransform::default() {
            return None;
        }
        let linear = self.linear().as_dmat3();
        Placement::new(DAffine3::from_mat3_translation(
            linear,
            self.translate.as_dvec3(),
        ))
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
