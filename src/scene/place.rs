//! Primitives moved by an affine transform on their way into a sink (`Placed`): a mesh
//! file by its `mesh` statement's transform, the contents of an AFF `xs` block by its
//! static transform, an animated group by its transform at a frame's time.
//!
//! Triangles and planes take any transform. A sphere or a cone stays a sphere or a cone:
//! its radius is scaled by the transform's mean scale (the cube root of its determinant),
//! exact where the scale is uniform, which is what scenes use on them. A box stays a box
//! where the transform keeps the axes; turned off them, it becomes its twelve triangles.

use glam::{DAffine3, Mat3, Vec2, Vec3};

use super::bounds::Bounds;
use super::model::{BoxPrim, Cone, Light, MaterialId, Plane, Sphere, unit};
use super::sink::Sink;

/// An affine transform made ready to place primitives.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    m: Mat3,
    /// Normals transform by the inverse transpose (a non-uniform scale bends them).
    nm: Mat3,
    translate: Vec3,
    /// A negative scale mirrors, which turns triangles' winding: `triangle` turns it
    /// back, so that their front (an emitter's) stays the side it was.
    mirrored: bool,
    /// The factor radii are scaled by.
    scale: f32,
    /// Whether each axis goes onto an axis (a box stays a box).
    keeps_axes: bool,
}

impl Placement {
    /// The placement by `a`; `None` where it flattens space (a zero scale), which would
    /// leave nothing to see.
    pub fn new(a: DAffine3) -> Option<Placement> {
        let m = a.matrix3.as_mat3();
        let det = m.determinant();
        if det == 0.0 || !det.is_finite() || !a.translation.is_finite() {
            return None;
        }
        let cols = [m.x_axis, m.y_axis, m.z_axis];
        let keeps_axes = cols
            .iter()
            .all(|c| c.to_array().iter().filter(|v| **v != 0.0).count() == 1);
        Some(Placement {
            m,
            nm: m.inverse().transpose(),
            translate: a.translation.as_vec3(),
            mirrored: det < 0.0,
            scale: det.abs().cbrt(),
            keeps_axes,
        })
    }

    pub fn point(&self, p: Vec3) -> Vec3 {
        self.m * p + self.translate
    }

    /// A surface normal (or a light's direction), as a unit vector; `None` where the
    /// transform leaves it without a direction.
    pub fn normal(&self, n: Vec3) -> Option<Vec3> {
        unit(self.nm * n)
    }

    /// Whether a sphere's or a cone's radius is scaled exactly (the transform scales
    /// every direction alike).
    pub fn uniform(&self) -> bool {
        let s = self.m.transpose() * self.m;
        let d = Vec3::new(s.x_axis.x, s.y_axis.y, s.z_axis.z);
        let off = [s.x_axis.y, s.x_axis.z, s.y_axis.z];
        let tol = 1e-4 * d.max_element();
        (d - Vec3::splat(d.x)).abs().max_element() <= tol && off.iter().all(|v| v.abs() <= tol)
    }

    /// A triangle's corners placed, and its normals and texture coordinates (which the
    /// placement does not move) kept at their corners.
    #[allow(clippy::type_complexity)]
    pub fn triangle(
        &self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
    ) -> ([Vec3; 3], Option<[Vec3; 3]>, Option<[Vec2; 3]>) {
        fn turn<T>(mirrored: bool, [a, b, c]: [T; 3]) -> [T; 3] {
            if mirrored { [a, c, b] } else { [a, b, c] }
        }
        let v = v.map(|p| self.point(p));
        // A normal the transform leaves without a direction makes the triangle flat.
        let n = n.and_then(|[a, b, c]| Some([self.normal(a)?, self.normal(b)?, self.normal(c)?]));
        let m = self.mirrored;
        (turn(m, v), n.map(|n| turn(m, n)), uv.map(|uv| turn(m, uv)))
    }

    pub fn sphere(&self, s: Sphere) -> Sphere {
        Sphere {
            center: self.point(s.center),
            radius: s.radius * self.scale,
            material: s.material,
        }
    }

    pub fn cone(&self, c: Cone) -> Cone {
        Cone {
            base: self.point(c.base),
            base_radius: c.base_radius * self.scale,
            apex: self.point(c.apex),
            apex_radius: c.apex_radius * self.scale,
            material: c.material,
        }
    }

    /// A box into `sink`: a box where the axes stay axes, else its twelve triangles.
    pub fn cuboid(&self, b: BoxPrim, sink: &mut dyn Sink) {
        if self.keeps_axes {
            let (p, q) = (self.point(b.min), self.point(b.max));
            sink.cuboid(BoxPrim {
                min: p.min(q),
                max: p.max(q),
                material: b.material,
            });
            return;
        }
        for v in box_triangles(b.min, b.max) {
            let (v, _, _) = self.triangle(v, None, None);
            sink.triangle(v, None, None, b.material);
        }
    }

    /// A plane placed; `None` cannot happen for a placement (its matrix is invertible),
    /// but a normal is checked all the same.
    pub fn plane(&self, p: Plane) -> Option<Plane> {
        Some(Plane {
            point: self.point(p.point),
            normal: self.normal(p.normal)?,
            material: p.material,
        })
    }

    /// A light placed: a point light's position, a directional light's direction, an
    /// area light's corner and edges.
    pub fn light(&self, l: Light) -> Light {
        match l {
            Light::Point { position, color } => Light::Point {
                position: self.point(position),
                color,
            },
            Light::Directional { direction, color } => Light::Directional {
                direction: unit(self.m * direction).unwrap_or(direction),
                color,
            },
            Light::Area {
                corner,
                u,
                v,
                color,
                samples,
            } => Light::Area {
                corner: self.point(corner),
                u: self.m * u,
                v: self.m * v,
                color,
                samples,
            },
        }
    }
}

/// The twelve triangles of the box `lo..hi`, each wound counter-clockwise seen from
/// outside (also how `examples/rays.rs` hands a box to Embree).
pub fn box_triangles(lo: Vec3, hi: Vec3) -> [[Vec3; 3]; 12] {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 != 0 { hi.x } else { lo.x },
            if i & 2 != 0 { hi.y } else { lo.y },
            if i & 4 != 0 { hi.z } else { lo.z },
        )
    };
    // Each face's corners in order around it, counter-clockwise from outside.
    const FACES: [[usize; 4]; 6] = [
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    let mut out = [[Vec3::ZERO; 3]; 12];
    for (f, [a, b, cc, d]) in FACES.iter().enumerate() {
        out[2 * f] = [c(*a), c(*b), c(*cc)];
        out[2 * f + 1] = [c(*a), c(*cc), c(*d)];
    }
    out
}

/// Primitives on their way into a sink, every one placed.
pub struct Placed<'a> {
    sink: &'a mut dyn Sink,
    placement: Option<Placement>,
    /// Triangles placed.
    pub placed: usize,
}

impl<'a> Placed<'a> {
    /// `sink` behind `placement` (`None`: the identity, nothing moved).
    pub fn new(sink: &'a mut dyn Sink, placement: Option<Placement>) -> Self {
        Placed {
            sink,
            placement,
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
            Some(p) => p.triangle(v, n, uv),
            None => (v, n, uv),
        };
        self.placed += 1;
        self.sink.triangle(v, n, uv, material);
    }
    fn sphere(&mut self, s: Sphere) {
        let s = self.placement.map_or(s, |p| p.sphere(s));
        self.sink.sphere(s);
    }
    fn cone(&mut self, c: Cone) {
        let c = self.placement.map_or(c, |p| p.cone(c));
        self.sink.cone(c);
    }
    fn cuboid(&mut self, b: BoxPrim) {
        match &self.placement {
            Some(p) => p.cuboid(b, self.sink),
            None => self.sink.cuboid(b),
        }
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
    use crate::scene::Collect;
    use glam::{DMat3, DVec3};

    /// Turned off the axes, a box becomes twelve triangles that face out and close it.
    #[test]
    fn a_turned_box_becomes_its_triangles() {
        let turn = DAffine3::from_mat3(DMat3::from_rotation_z(0.3));
        let p = Placement::new(turn).unwrap();
        let mut tris = Collect::default();
        let b = BoxPrim {
            min: Vec3::ZERO,
            max: Vec3::ONE,
            material: MaterialId(0),
        };
        p.cuboid(b, &mut tris);
        let tris = tris.into_triangles();
        assert_eq!(tris.len(), 12);
        let centre = p.point(Vec3::splat(0.5));
        let mut area = 0.0;
        for t in &tris {
            let out = (t.v[0] + t.v[1] + t.v[2]) / 3.0 - centre;
            assert!(t.cross().dot(out) > 0.0, "faces out");
            area += t.area();
        }
        assert!((area - 6.0).abs() < 1e-4);
        // Kept on the axes, it stays one box, its corners sorted.
        let flip = Placement::new(DAffine3::from_scale(DVec3::new(-2.0, 1.0, 1.0))).unwrap();
        let mut boxes = Collect::default();
        flip.cuboid(b, &mut boxes);
        assert_eq!(boxes.count(), 1);
        assert_eq!(boxes.bounds().min, Vec3::new(-2.0, 0.0, 0.0));
    }

    #[test]
    fn a_zero_scale_places_nothing_and_radii_take_the_mean_scale() {
        assert!(Placement::new(DAffine3::from_scale(DVec3::new(1.0, 0.0, 1.0))).is_none());
        let p = Placement::new(DAffine3::from_scale(DVec3::splat(2.0))).unwrap();
        assert!(p.uniform());
        let s = p.sphere(Sphere {
            center: Vec3::X,
            radius: 1.5,
            material: MaterialId(0),
        });
        assert_eq!((s.center, s.radius), (Vec3::new(2.0, 0.0, 0.0), 3.0));
        let squash = Placement::new(DAffine3::from_scale(DVec3::new(1.0, 8.0, 1.0))).unwrap();
        assert!(!squash.uniform());
    }
}
