//! A ready-to-render scene around a bare mesh (`gpurt part.stl`): a three-quarter view that
//! frames the mesh, a light near the camera, a neutral grey material and a ground plane.

use glam::Vec3;

use super::bounds::Bounds;
use super::model::{
    Camera, Light, Material, MaterialId, Plane, Scene, Triangle, nff_default_camera,
};
use crate::error::{Error, Result};

/// STL files come from CAD tools, which are z-up; OBJ files are mostly y-up.
pub fn up_axis_for(name: &str) -> Vec3 {
    let lower = name.to_ascii_lowercase();
    let lower = lower.strip_suffix(".gz").unwrap_or(&lower);
    if lower.ends_with(".obj") {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

pub fn scene_for_mesh(name: &str, mut tris: Vec<Triangle>) -> Result<Scene> {
    let mut scene = Scene::new(name, nff_default_camera());
    scene.materials.push(Material::NEUTRAL_GREY);
    scene.triangles.append(&mut tris);
    let b = scene.bounds();
    frame_mesh(&mut scene, b)?;
    Ok(scene)
}

/// Gives `scene`, which holds a bare mesh with bounds `b` and its materials (the grey of
/// faces without one first), its camera, light, ground material and ground plane.
pub fn frame_mesh(scene: &mut Scene, b: Bounds) -> Result<()> {
    if b.is_empty() {
        return Err(Error::Scene {
            file: scene.name.clone(),
            msg: "the mesh has no triangles".into(),
        });
    }
    let up = up_axis_for(&scene.name);
    let center = b.center();
    let radius = (0.5 * b.extent().length()).max(1e-6);
    // Three-quarter view: 45 degrees around the up axis, 30 degrees above the horizon.
    let (side, front) = if up == Vec3::Z {
        (Vec3::X, Vec3::NEG_Y)
    } else {
        (Vec3::X, Vec3::Z)
    };
    let dir = ((side + front).normalize() * 30f32.to_radians().cos()
        + up * 30f32.to_radians().sin())
    .normalize();
    let angle = 40.0f32;
    let distance = radius / (0.5 * angle.to_radians()).sin() * 1.05;
    let from = center + dir * distance;
    scene.camera = Camera {
        from,
        at: center,
        up,
        angle,
        hither: distance * 1e-3,
        width: 512,
        height: 512,
        aperture: 0.0,
        focal: None,
    };
    scene.background = Vec3::new(0.25, 0.3, 0.38);
    // Above and to the side of the camera, so shadows fall visibly on the ground.
    let light = from + (up * 0.6 + side.cross(up) * 0.3) * distance;
    scene.lights.push(Light::Point {
        position: light,
        color: Some(Vec3::ONE),
    });
    let ground = MaterialId(scene.materials.len() as u32);
    scene.materials.push(Material {
        color: Vec3::splat(0.9),
        kd: 0.9,
        ks: 0.0,
        shine: 1.0,
        t: 0.0,
        ior: 1.0,
    });
    // A little below the mesh's lowest point (a thousandth of its size), so that a flat
    // mesh lying on that plane does not z-fight with the ground.
    let floor = b.min.dot(up) - 1e-3 * radius;
    scene.planes.push(Plane {
        point: up * floor,
        normal: up,
        material: ground,
    });
    Ok(())
}
