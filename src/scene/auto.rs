//! A ready-to-render scene around a bare mesh (`gpurt part.stl`): a three-quarter view that
//! frames the mesh, a light near the camera, a neutral grey material and a ground plane.
//!
//! The framing fits the corners of the mesh's bounding box, as the camera projects them,
//! to `FILL` of the frame in the dimension where they reach furthest, centred; a render
//! of another resolution than the scene's (`--width`, `--height`, the viewer's window)
//! fits them again for its own aspect ratio (`fitted`), since the vertical angle stays.

use glam::Vec3;

use super::bounds::Bounds;
use super::model::nff_default_camera;
use super::model::{Camera, Light, Material, MaterialId, Plane, Scene, Triangle};
use crate::util::error::{Error, Result};

/// The part of the frame's width or height the framed mesh fills.
pub const FILL: f32 = 0.875;

/// The background of a scene made around a mesh, and of a glTF model.
pub const BACKGROUND: Vec3 = Vec3::new(0.25, 0.3, 0.38);

/// The bare-mesh camera's vertical field of view, degrees.
const ANGLE: f32 = 40.0;

/// STL files come from CAD tools, which are z-up; OBJ files are mostly y-up, and so are
/// PLY files (the Stanford scans: the bunny, the dragon, the armadillo); glTF is y-up by
/// its specification.
pub fn up_axis_for(name: &str) -> Vec3 {
    let lower = name.to_ascii_lowercase();
    let lower = lower.strip_suffix(".gz").unwrap_or(&lower);
    if [".obj", ".ply", ".gltf", ".glb"]
        .iter()
        .any(|e| lower.ends_with(e))
    {
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
    let mut camera = Camera {
        from: center + dir * radius * 3.0,
        at: center,
        up,
        angle: ANGLE,
        hither: 0.0,
        width: 512,
        height: 512,
        aperture: 0.0,
        focal: None,
        fit: Some([b.min, b.max]),
    };
    fit(&mut camera, 512, 512);
    let distance = (camera.from - camera.at).length();
    scene.camera = camera;
    scene.background = BACKGROUND;
    // Above and to the side of the camera, so shadows fall visibly on the ground; a mesh
    // with emitters is lit by them alone, as its authors lit it.
    if !scene.emits() {
        let light = scene.camera.from + (up * 0.6 + side.cross(up) * 0.3) * distance;
        scene.lights.push(Light::Point {
            position: light,
            color: Some(Vec3::ONE),
        });
    }
    let ground = MaterialId(scene.materials.len() as u32);
    scene.materials.push(Material {
        color: Vec3::splat(0.9),
        kd: 0.9,
        ks: 0.0,
        shine: 1.0,
        t: 0.0,
        ior: 1.0,
        emission: Vec3::ZERO,
        texture: None,
        ambient: None,
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

/// `camera` for a render of `width` x `height`: refitted to its box when it frames one
/// (`Camera::fit`) and the size is not the one it was fitted for; else unchanged.
pub fn fitted(camera: &Camera, width: u32, height: u32) -> Camera {
    let mut c = camera.clone();
    if c.fit.is_some() && (width, height) != (c.width, c.height) {
        fit(&mut c, width, height);
    }
    c
}

/// Moves `camera` along its line of sight and sideways, keeping its direction, up and
/// angle, until the corners of its box (`Camera::fit`) fill `FILL` of a `width` x
/// `height` frame, centred.
fn fit(camera: &mut Camera, width: u32, height: u32) {
    let Some([min, max]) = camera.fit else {
        return;
    };
    let corners: [Vec3; 8] = std::array::from_fn(|i| {
        Vec3::select(
            glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
            max,
            min,
        )
    });
    let center = 0.5 * (min + max);
    let radius = (0.5 * (max - min).length()).max(1e-6);
    let dir = (camera.from - camera.at).normalize();
    let forward = -dir;
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    // The frame's half width and height at unit distance: `angle` spans the centres of the
    // outermost rows (shading.md), the frame's edge is half a pixel further out.
    let rows = (height.max(2) - 1) as f32;
    let pitch = 2.0 * (camera.angle.to_radians() * 0.5).tan() / rows;
    let half = [
        0.5 * pitch * width.max(1) as f32,
        0.5 * pitch * height.max(1) as f32,
    ];
    // The corners' projected extent from `from`, in tangents: [min x, max x, min y, max y].
    let extent = |from: Vec3| {
        let mut e = [f32::MAX, f32::MIN, f32::MAX, f32::MIN];
        for p in corners {
            let d = p - from;
            let z = d.dot(forward);
            let (x, y) = (d.dot(right) / z, d.dot(up) / z);
            e = [e[0].min(x), e[1].max(x), e[2].min(y), e[3].max(y)];
        }
        e
    };
    // How far out of the frame's centre the corners reach, as a part of the frame.
    let reach = |e: [f32; 4]| {
        let x = e[0].abs().max(e[1].abs()) / half[0];
        let y = e[2].abs().max(e[3].abs()) / half[1];
        x.max(y)
    };
    // The reach falls as the camera backs off; outside the bounding sphere every corner
    // is in front of it. Bisect for the distance where it is FILL, then aim at the centre
    // of what is seen and bisect again: perspective makes the near end look larger.
    let mut at = center;
    let mut distance = radius;
    for round in 0..4 {
        let (mut lo, mut hi) = (radius * 1.0001, radius * 4.0);
        while reach(extent(at + dir * hi)) > FILL && hi < radius * 1e6 {
            hi *= 2.0;
        }
        if reach(extent(at + dir * lo)) <= FILL {
            hi = lo;
        }
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            if reach(extent(at + dir * mid)) > FILL {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        distance = hi;
        if round == 3 {
            break;
        }
        let e = extent(at + dir * distance);
        let (cx, cy) = (0.5 * (e[0] + e[1]), 0.5 * (e[2] + e[3]));
        at += (right * cx + up * cy) * distance;
    }
    camera.at = at;
    camera.from = at + dir * distance;
    camera.hither = distance * 1e-3;
    camera.width = width;
    camera.height = height;
}
