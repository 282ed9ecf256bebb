//! Axis-aligned bounds, each bounded primitive's `bounds()`, and the scene's bounded
//! primitives in the one order the BVH, the packed buffers and the tests share. Planes are
//! infinite and have none. Apart from the model because they are geometry worked out from
//! it, not data a reader fills in.

use glam::Vec3;

use super::model::{BoxPrim, Cone, Scene, Sphere, Triangle};

/// Axis-aligned bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds {
    pub const EMPTY: Bounds = Bounds {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn union(mut self, o: Bounds) -> Bounds {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
        self
    }
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
}

impl Sphere {
    pub fn bounds(&self) -> Bounds {
        let r = Vec3::splat(self.radius.abs());
        Bounds {
            min: self.center - r,
            max: self.center + r,
        }
    }
}

impl Triangle {
    pub fn bounds(&self) -> Bounds {
        Bounds {
            min: self.v[0].min(self.v[1]).min(self.v[2]),
            max: self.v[0].max(self.v[1]).max(self.v[2]),
        }
    }
}

impl Cone {
    /// Bounds of the two cap discs (a slight over-estimate, always conservative).
    pub fn bounds(&self) -> Bounds {
        let axis = (self.apex - self.base).normalize_or_zero();
        // Extent of a unit disc perpendicular to `axis`, per coordinate axis.
        let disc = (Vec3::ONE - axis * axis).max(Vec3::ZERO).powf(0.5);
        let rb = disc * self.base_radius.abs();
        let ra = disc * self.apex_radius.abs();
        Bounds {
            min: (self.base - rb).min(self.apex - ra),
            max: (self.base + rb).max(self.apex + ra),
        }
    }
}

impl BoxPrim {
    pub fn bounds(&self) -> Bounds {
        Bounds {
            min: self.min,
            max: self.max,
        }
    }
}

/// A bounded primitive of a scene (`Scene::bounded_prims`).
#[derive(Clone, Copy, Debug)]
pub enum Bounded<'a> {
    Sphere(&'a Sphere),
    Triangle(&'a Triangle),
    Cone(&'a Cone),
    Box(&'a BoxPrim),
}

impl Bounded<'_> {
    pub fn bounds(&self) -> Bounds {
        match self {
            Bounded::Sphere(s) => s.bounds(),
            Bounded::Triangle(t) => t.bounds(),
            Bounded::Cone(c) => c.bounds(),
            Bounded::Box(b) => b.bounds(),
        }
    }
}

impl Scene {
    /// Bounds of every bounded primitive (planes are infinite and excluded).
    pub fn bounds(&self) -> Bounds {
        self.bounded_prims()
            .fold(Bounds::EMPTY, |b, p| b.union(p.bounds()))
    }

    /// Every bounded primitive in the one order the BVH is built over and the packed
    /// buffers, the tests and the benchmarks index them by: spheres, triangles, cones,
    /// boxes.
    pub fn bounded_prims(&self) -> impl Iterator<Item = Bounded<'_>> {
        let spheres = self.spheres.iter().map(Bounded::Sphere);
        let triangles = self.triangles.iter().map(Bounded::Triangle);
        let cones = self.cones.iter().map(Bounded::Cone);
        let boxes = self.boxes.iter().map(Bounded::Box);
        spheres.chain(triangles).chain(cones).chain(boxes)
    }

    /// Number of bounded primitives (what the BVH is built over).
    pub fn bounded_count(&self) -> usize {
        self.spheres.len() + self.triangles.len() + self.cones.len() + self.boxes.len()
    }
}
