//! Mesh files (STL, OBJ) as triangle lists, and the transform the `mesh` statement applies.

use glam::{Mat3, Vec3};

use super::io::FileKind;
use super::model::{Mesh, Triangle, unit};
use super::{obj, stl};
use crate::error::Result;

/// Parses a mesh file's bytes (already decompressed) into triangles with material 0.
pub fn parse_mesh(bytes: &[u8], kind: FileKind, name: &str) -> Result<Mesh> {
    match kind {
        FileKind::Stl => Ok(Mesh {
            triangles: stl::parse(bytes, name)?,
            warnings: Vec::new(),
        }),
        FileKind::Obj => obj::parse_with_warnings(bytes, name),
        FileKind::Nff => unreachable!("NFF is not a mesh format"),
    }
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
        if *self == MeshTransform::default() {
            return;
        }
        let m = self.linear();
        // Normals transform by the inverse transpose (non-uniform scale bends them).
        let nm = m.inverse().transpose();
        for t in tris {
            t.v = t.v.map(|p| m * p + self.translate);
            // A normal the transform leaves without a direction makes the triangle flat.
            t.n = t.n.take().and_then(|n| {
                let unit = |v| unit(nm * v);
                let [a, b, c] = *n;
                Some(Box::new([unit(a)?, unit(b)?, unit(c)?]))
            });
        }
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
        }];
        xf.apply(&mut t);
        // X scaled to 2, rotated onto +Y, moved by 10 in x.
        assert!((t[0].v[0] - Vec3::new(10.0, 2.0, 0.0)).length() < 1e-5);
        assert!((t[0].v[1] - Vec3::new(9.0, 0.0, 0.0)).length() < 1e-5);
        assert!((t[0].n.as_ref().unwrap()[0] - Vec3::Y).length() < 1e-5);
    }
}
