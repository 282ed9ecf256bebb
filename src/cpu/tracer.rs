//! Where the shading code (`shade.rs`, `main.rs`) gets the answers of the rays it traces:
//! each walked alone (`Alone`, the shader's way), or, for the rays the renderer traced
//! beforehand in packets (`coherent.rs`), those answers, which are the same.

use glam::Vec3;

use super::traverse;
use super::types::{Bindings, Hit, Ray};

/// `closest_hit` and `transmission`, as the shading code asks for them.
pub trait Tracer {
    fn closest_hit(&mut self, b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit;
    /// Adds the node fetches of the shadow ray's walk to `nodes`.
    fn transmission(&mut self, b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3;
}

/// Every ray walked alone, when it is asked for.
pub struct Alone;

impl Tracer for Alone {
    #[inline]
    fn closest_hit(&mut self, b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
        traverse::closest_hit(b, ray, tmin, tmax)
    }
    #[inline]
    fn transmission(&mut self, b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3 {
        traverse::transmission(b, ray, tmax, nodes)
    }
}
