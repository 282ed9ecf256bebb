//! The shading's `Tracer` (`shade.rs`) that walks every ray alone when it is asked for,
//! the shader's way; `coherent.rs` has the other, which answers the rays it traced
//! beforehand in packets from those answers, which are the same.

use glam::Vec3;

use super::wide_ray;
use crate::cpu::shade::Tracer;
use crate::cpu::types::{Bindings, Hit, Ray};

/// Every ray walked alone, when it is asked for.
pub struct Alone;

impl Tracer for Alone {
    #[inline]
    fn closest_hit(&mut self, b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
        wide_ray::closest_hit(b, ray, tmin, tmax)
    }
    #[inline]
    fn transmission(&mut self, b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3 {
        wide_ray::transmission(b, ray, tmax, nodes, &mut None)
    }
}
