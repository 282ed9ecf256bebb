//! Independent expectations: values a test computes on its own, in f64 and from the
//! scene rather than from the renderer's buffers, to hold a render against: the eye rays
//! of docs/shading.md, where a ray crosses a sphere or a triangle, the shading of a lone
//! sphere, and a film's column means.

use glam::{DVec3, Vec3};
use gpurt::film::Film;
use gpurt::frame::Shading;
use gpurt::limits::DEFAULT_AMBIENT;
use gpurt::scene::{Light, Scene};

pub fn d(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// The eye rays of shading.md, in f64, from the scene's camera (not from `GpuGlobals`).
pub struct Camera {
    pub from: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
    pub pitch: f64,
    pub width: u32,
    pub height: u32,
    pub hither: f64,
}

impl Camera {
    pub fn of(scene: &Scene) -> Camera {
        Camera::sized(scene, scene.camera.width, scene.camera.height)
    }

    /// The scene's camera making an image of `width` x `height` pixels (a render's
    /// options may set another size than the scene's): the angle spans the centres of the
    /// top and bottom rows.
    pub fn sized(scene: &Scene, width: u32, height: u32) -> Camera {
        let c = &scene.camera;
        let forward = (d(c.at) - d(c.from)).normalize();
        let right = forward.cross(d(c.up)).normalize();
        Camera {
            from: d(c.from),
            forward,
            right,
            up: right.cross(forward),
            pitch: 2.0 * (0.5 * (c.angle as f64).to_radians()).tan() / (height.max(2) - 1) as f64,
            width,
            height,
            hither: c.hither as f64,
        }
    }

    /// Direction through the centre of pixel `(x, y)`, y down.
    pub fn dir(&self, x: u32, y: u32) -> DVec3 {
        let sx = (x as f64 + 0.5 - 0.5 * self.width as f64) * self.pitch;
        let sy = (0.5 * self.height as f64 - (y as f64 + 0.5)) * self.pitch;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }

    pub fn pixels(&self) -> impl Iterator<Item = (u32, u32)> + use<> {
        let (w, h) = (self.width, self.height);
        (0..h).flat_map(move |y| (0..w).map(move |x| (x, y)))
    }
}

/// A sphere crossing: the nearer distance past `tmin`, and how clearly the ray hits or
/// misses (discriminant over r^2: near 0 at the silhouette, where f32 and f64 may disagree).
pub fn sphere_hit(o: DVec3, dir: DVec3, c: DVec3, r: f64, tmin: f64) -> (Option<f64>, f64) {
    let oc = o - c;
    let b = oc.dot(dir);
    let disc = b * b - (oc.length_squared() - r * r);
    let clarity = disc / (r * r);
    if disc < 0.0 {
        return (None, clarity);
    }
    let h = disc.sqrt();
    let t = [-b - h, -b + h].into_iter().find(|&t| t > tmin);
    (t, clarity)
}

/// The specular highlight of docs/model.md at a point with unit normal `n` facing the
/// incoming direction `dir`, towards the light direction `l`: Phong, `Ks max(R.L, 0)^Shine`
/// with `R` the mirrored ray, or Blinn-Phong, `Ks max(N.H, 0)^Shine` with
/// `H = normalize(L + V)`, V = -dir.
pub fn highlight(shading: Shading, n: DVec3, dir: DVec3, l: DVec3, ks: f64, shine: f64) -> f64 {
    let c = match shading {
        Shading::Phong => (dir - 2.0 * n.dot(dir) * n).dot(l),
        Shading::BlinnPhong => n.dot((l - dir).normalize()),
    };
    ks * c.max(0.0).powf(shine)
}

/// What docs/shading.md says the eye ray through the centre of pixel `(x, y)` shows of a
/// scene of one opaque sphere (convex: it never shadows itself, and what it mirrors is the
/// background) lit by uncoloured point lights: the background where the ray clearly
/// misses, ambient + sum over lights of I (Kd C N.L + `highlight`) + Ks background where
/// it clearly hits, with I = 1/sqrt(n_lights); `None` near the silhouette, where f32 and
/// f64 may disagree.
pub fn lone_sphere(scene: &Scene, cam: &Camera, x: u32, y: u32, shading: Shading) -> Option<DVec3> {
    let [sphere] = &scene.spheres[..] else {
        panic!("{}: one sphere expected", scene.name)
    };
    let (c, r) = (d(sphere.center), sphere.radius as f64);
    let m = scene.materials[sphere.material.0 as usize];
    assert_eq!(m.t, 0.0, "an opaque sphere");
    let bg = d(scene.background);
    let dir = cam.dir(x, y);
    let (t, clarity) = sphere_hit(cam.from, dir, c, r, cam.hither);
    if clarity.abs() < 1e-3 {
        return None;
    }
    let Some(t) = t else { return Some(bg) };
    let (kd_c, ks) = (m.kd as f64 * d(m.color), m.ks as f64);
    let ambient = d(scene.ambient.unwrap_or(Vec3::splat(DEFAULT_AMBIENT)));
    let p = cam.from + t * dir;
    let n = (p - c) / r;
    let intensity = 1.0 / (scene.lights.len() as f64).sqrt();
    let mut colour = ambient * kd_c + ks * bg;
    for light in &scene.lights {
        let Light::Point {
            position,
            color: None,
        } = light
        else {
            panic!("{}: uncoloured point lights expected", scene.name)
        };
        let l = (d(*position) - p).normalize();
        if n.dot(l) > 0.0 {
            let spec = highlight(shading, n, dir, l, ks, m.shine as f64);
            colour += intensity * (kd_c * n.dot(l) + DVec3::splat(spec));
        }
    }
    Some(colour)
}

/// Where the line `o + t dir` (`dir` a unit vector) crosses the plane of triangle `v`, if
/// it does inside the triangle by at least `margin` in each barycentric coordinate and
/// not at a grazing angle (the cosine to the normal at least `margin`): `Some(t)`, `t` of
/// either sign. A negative `margin` widens the triangle instead: `None` then says the
/// line clearly misses it.
pub fn triangle_hit(o: DVec3, dir: DVec3, v: [DVec3; 3], margin: f64) -> Option<f64> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let n = e1.cross(e2);
    if n.length() == 0.0 || (margin > 0.0 && dir.dot(n).abs() < margin * n.length()) {
        return None;
    }
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = o - v[0];
    let q = s.cross(e1);
    let (u, w) = (s.dot(p) / det, dir.dot(q) / det);
    (u > margin && w > margin && 1.0 - u - w > margin).then(|| e2.dot(q) / det)
}

/// Mean of one column of the film's first channel.
pub fn column_mean(film: &Film, x: u32) -> f64 {
    (0..film.height)
        .map(|y| f64::from(film.get(x, y)[0]))
        .sum::<f64>()
        / f64::from(film.height)
}
