//! An independent Whitted tracer in f64 for small scenes of spheres and flat triangles
//! under point, directional and area lights and emitters (docs/model.md's emissive
//! triangles): docs/shading.md written out again from the
//! parsed scene (not from the renderer's buffers or code), recursion where the renderers
//! iterate, every crossing tested against every shape. It answers `None` for a pixel where
//! f32 and f64 may honestly disagree: a ray on the path (eye, mirrored, refracted or to a
//! light) passing near a sphere's silhouette or a triangle's edge, a refraction near the
//! critical angle, a light near the horizon of the surface, and an area light partly hidden
//! or partly below the horizon, and the same of an emitter (the renderers estimate those
//! integrals from a few jittered samples, this tracer integrates them on fine grids).

use glam::{DVec3, Vec3};
use gpurt::frame::Shading;
use gpurt::limits::DEFAULT_AMBIENT;
use gpurt::scene::{Light, Scene};

use super::oracle::{Camera, d, highlight, sphere_hit, triangle_hit};

/// How clearly a ray must hit or miss a shape (the discriminant over r^2 for a sphere,
/// barycentric distance to an edge and cosine to the plane for a triangle), and how far a
/// light must stand above the horizon, for the answer to count.
const MARGIN: f64 = 1e-3;

/// Side of the grid of points on which an area light is integrated, and the cuts of each
/// side of an emitter's triangle (into `GRID^2` triangles, integrated at their centroids).
const GRID: u32 = 24;

/// What a pixel's paths met, to show that a test covered what it meant to.
#[derive(Clone, Copy, Debug, Default)]
pub struct Met {
    pub triangle: bool,
    pub refraction: bool,
    pub directional: bool,
    pub area: bool,
    /// Light from an emitter's triangles.
    pub emitter: bool,
    /// Light reached through a transmitting occluder, dimmed but not blocked.
    pub tinted_shadow: bool,
}

/// Too close to call in f32.
struct Unsure;

enum Shape {
    Sphere(DVec3, f64),
    Triangle([DVec3; 3]),
}

struct Surface {
    material: usize,
    shape: Shape,
}

struct Hit {
    t: f64,
    /// Geometric normal on the outward side (spheres) or the plane's (triangles).
    normal: DVec3,
    material: usize,
    triangle: bool,
}

pub struct Whitted<'a> {
    scene: &'a Scene,
    shading: Shading,
    max_depth: u32,
    surfaces: Vec<Surface>,
    /// docs/model.md's secondary-ray offset: 5e-6 of the bounds' diagonal.
    eps: f64,
    ambient: DVec3,
    /// The intensity of a light given without a colour: 1/sqrt(number of lights).
    grey: DVec3,
    /// The triangles of emissive materials, and their radiance.
    emitters: Vec<([DVec3; 3], DVec3)>,
}

impl<'a> Whitted<'a> {
    /// Panics on what it does not model: planes, cones, boxes, vertex normals.
    pub fn new(scene: &'a Scene, shading: Shading, max_depth: u32) -> Self {
        assert!(
            scene.planes.is_empty() && scene.cones.is_empty() && scene.boxes.is_empty(),
            "spheres and triangles only"
        );
        let spheres = scene.spheres.iter().map(|s| Surface {
            material: s.material.0 as usize,
            shape: Shape::Sphere(d(s.center), s.radius as f64),
        });
        let triangles = scene.triangles.iter().map(|t| {
            assert!(t.n.is_none(), "flat triangles only");
            Surface {
                material: t.material.0 as usize,
                shape: Shape::Triangle(t.v.map(d)),
            }
        });
        let surfaces: Vec<Surface> = spheres.chain(triangles).collect();
        let emitters = (scene.triangles.iter())
            .map(|t| {
                (
                    t.v.map(d),
                    d(scene.materials[t.material.0 as usize].emission),
                )
            })
            .filter(|&(_, radiance)| radiance != DVec3::ZERO)
            .collect();
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for s in &surfaces {
            let (a, b) = match s.shape {
                Shape::Sphere(c, r) => (c - r, c + r),
                Shape::Triangle(v) => (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2])),
            };
            (lo, hi) = (lo.min(a), hi.max(b));
        }
        Whitted {
            scene,
            shading,
            max_depth,
            surfaces,
            eps: 5e-6 * (hi - lo).length(),
            ambient: d(scene.ambient.unwrap_or(Vec3::splat(DEFAULT_AMBIENT))),
            grey: DVec3::splat(1.0 / (scene.lights.len() as f64).sqrt()),
            emitters,
        }
    }

    /// The colour of pixel `(x, y)`'s centre and what its paths met, `None` where f32 and
    /// f64 may disagree.
    pub fn pixel(&self, cam: &Camera, x: u32, y: u32) -> Option<(DVec3, Met)> {
        let mut met = Met::default();
        let c = self.trace(cam.from, cam.dir(x, y), cam.hither, 1, &mut met);
        c.ok().map(|c| (c, met))
    }

    /// The nearest crossing past `tmin`; `Unsure` when a shape is grazed nearer than it.
    fn closest(&self, o: DVec3, dir: DVec3, tmin: f64) -> Result<Option<Hit>, Unsure> {
        let mut best: Option<Hit> = None;
        let mut unsure = f64::INFINITY;
        for s in &self.surfaces {
            let (t, normal, triangle) = match s.shape {
                Shape::Sphere(c, r) => {
                    let (t, clarity) = sphere_hit(o, dir, c, r, tmin);
                    if clarity.abs() < MARGIN {
                        // Grazed: f32 may see the other answer, about at the tangent.
                        unsure = unsure.min((c - o).dot(dir));
                        continue;
                    }
                    let Some(t) = t else { continue };
                    (t, (o + t * dir - c) / r, false)
                }
                Shape::Triangle(v) => {
                    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
                    match triangle_hit(o, dir, v, MARGIN) {
                        Some(t) => (t, n, true),
                        None => {
                            if let Some(t) = triangle_hit(o, dir, v, -MARGIN)
                                && t > tmin
                            {
                                unsure = unsure.min(t);
                            }
                            continue;
                        }
                    }
                }
            };
            if t > tmin && best.as_ref().is_none_or(|b| t < b.t) {
                best = Some(Hit {
                    t,
                    normal,
                    material: s.material,
                    triangle,
                });
            }
        }
        match best {
            Some(b) if unsure <= b.t * (1.0 + MARGIN) => Err(Unsure),
            None if unsure.is_finite() => Err(Unsure),
            b => Ok(b),
        }
    }

    /// The fraction of each channel of light that crosses the segment from `o` along `dir`
    /// up to `far`: each crossing of a surface multiplies it by T C (0 where T is 0).
    fn transmission(&self, o: DVec3, dir: DVec3, far: f64) -> Result<DVec3, Unsure> {
        let mut through = DVec3::ONE;
        for s in &self.surfaces {
            let crossings = match s.shape {
                Shape::Sphere(c, r) => {
                    let (_, clarity) = sphere_hit(o, dir, c, r, 0.0);
                    if clarity.abs() < MARGIN && (c - o).dot(dir) > 0.0 {
                        return Err(Unsure);
                    }
                    if clarity < 0.0 {
                        continue;
                    }
                    let (b, h) = ((o - c).dot(dir), (clarity * r * r).sqrt());
                    [-b - h, -b + h]
                        .into_iter()
                        .filter(|&t| t > 0.0 && t < far)
                        .count() as i32
                }
                Shape::Triangle(v) => match triangle_hit(o, dir, v, MARGIN) {
                    Some(t) => i32::from(t > 0.0 && t < far),
                    None => {
                        if triangle_hit(o, dir, v, -MARGIN).is_some_and(|t| t > 0.0 && t < far) {
                            return Err(Unsure);
                        }
                        0
                    }
                },
            };
            let m = &self.scene.materials[s.material];
            let tint = m.t as f64 * d(m.color);
            through *= DVec3::new(
                tint.x.powi(crossings),
                tint.y.powi(crossings),
                tint.z.powi(crossings),
            );
        }
        Ok(through)
    }

    fn trace(
        &self,
        o: DVec3,
        dir: DVec3,
        tmin: f64,
        depth: u32,
        met: &mut Met,
    ) -> Result<DVec3, Unsure> {
        let Some(hit) = self.closest(o, dir, tmin)? else {
            return Ok(d(self.scene.background));
        };
        met.triangle |= hit.triangle;
        let m = self.scene.materials[hit.material];
        let (kd_c, ks, tr) = (m.kd as f64 * d(m.color), m.ks as f64, m.t as f64);
        let p = o + hit.t * dir;
        let entering = hit.normal.dot(dir) < 0.0;
        let n = if entering { hit.normal } else { -hit.normal };
        let above = p + self.eps * n;
        // The material's own ambient colour (AFF's `fm`), else Kd times its colour.
        let mut colour = self.ambient * m.ambient.map_or(kd_c, d);
        // An emissive surface is seen with its radiance from its front.
        if entering {
            colour += d(m.emission);
        }
        let at = At {
            above,
            n,
            dir,
            kd_c,
            ks,
            shine: m.shine as f64,
        };
        for light in &self.scene.lights {
            colour += match *light {
                Light::Point { position, color } => {
                    let to = d(position) - above;
                    let c = color.map_or(self.grey, d);
                    self.lit(&at, to.normalize(), to.length(), met)?
                        .map_or(DVec3::ZERO, |(through, shade)| through * c * shade)
                }
                Light::Directional { direction, color } => {
                    let c = color.map_or(self.grey, d);
                    let l = -d(direction).normalize();
                    let lit = self.lit(&at, l, f64::INFINITY, met)?;
                    met.directional |= lit.is_some();
                    lit.map_or(DVec3::ZERO, |(through, shade)| through * c * shade)
                }
                Light::Area {
                    corner,
                    u,
                    v,
                    color,
                    ..
                } => {
                    let add = self.area(&at, [corner, u, v].map(d), met)?;
                    met.area |= add != DVec3::ZERO;
                    d(color) * add
                }
            };
        }
        for &(v, radiance) in &self.emitters {
            let add = self.emitter(&at, v, met)?;
            met.emitter |= add != DVec3::ZERO;
            colour += radiance * add;
        }
        if ks > 0.0 && depth < self.max_depth {
            let r = dir - 2.0 * n.dot(dir) * n;
            colour += ks * self.trace(above, r, 0.0, depth + 1, met)?;
        }
        if tr > 0.0 && depth < self.max_depth {
            let eta = if entering {
                1.0 / m.ior as f64
            } else {
                m.ior as f64
            };
            let cos_i = -n.dot(dir);
            let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
            if k.abs() < MARGIN {
                return Err(Unsure);
            }
            let (next, from) = if k < 0.0 {
                (dir + 2.0 * cos_i * n, above)
            } else {
                met.refraction = true;
                (eta * dir + (eta * cos_i - k.sqrt()) * n, p - self.eps * n)
            };
            colour += tr * self.trace(from, next, 0.0, depth + 1, met)?;
        }
        Ok(colour)
    }

    /// A light in unit direction `l` at distance `far` seen from `at`: `None` below the
    /// horizon, else the fraction of it that crosses the shadow ray and what each unit of
    /// it adds (Kd C N.L plus the highlight).
    fn lit(
        &self,
        at: &At,
        l: DVec3,
        far: f64,
        met: &mut Met,
    ) -> Result<Option<(DVec3, DVec3)>, Unsure> {
        let cos = at.n.dot(l);
        if cos.abs() < MARGIN {
            return Err(Unsure);
        }
        if cos < 0.0 {
            return Ok(None);
        }
        let through = self.transmission(at.above, l, far)?;
        if through != DVec3::ONE && through != DVec3::ZERO {
            met.tinted_shadow = true;
        }
        let spec = highlight(self.shading, at.n, at.dir, l, at.ks, at.shine);
        Ok(Some((through, at.kd_c * cos + DVec3::splat(spec))))
    }

    /// An area light's share per unit of its colour: the mean over the parallelogram
    /// `corner + a u + b v` of what a point light there would add, integrated on a `GRID` x
    /// `GRID` grid of cell centres. `Unsure` where the grid's points disagree on the shadow or
    /// the horizon: there the renderers' few jittered samples estimate a step, not a smooth
    /// integrand, and differ from the mean by more than rounding.
    fn area(&self, at: &At, [corner, u, v]: [DVec3; 3], met: &mut Met) -> Result<DVec3, Unsure> {
        let mut sum = DVec3::ZERO;
        let mut first: Option<Option<DVec3>> = None;
        for i in 0..GRID {
            for j in 0..GRID {
                let (a, b) = (
                    (i as f64 + 0.5) / GRID as f64,
                    (j as f64 + 0.5) / GRID as f64,
                );
                let to = corner + a * u + b * v - at.above;
                let lit = self.lit(at, to.normalize(), to.length(), met)?;
                let seen = lit.map(|(through, _)| through);
                if *first.get_or_insert(seen) != seen {
                    return Err(Unsure);
                }
                sum += lit.map_or(DVec3::ZERO, |(through, shade)| through * shade);
            }
        }
        Ok(sum / (GRID * GRID) as f64)
    }

    /// An emitter triangle's share per unit of its radiance: the integral over the
    /// triangle of what a point light there would add, times the cosine at the emitter
    /// over pi r^2 (its front only), on the centroids of its `GRID^2` equal triangles.
    /// `Unsure` as for an area light, and where a point lies near the emitter's horizon.
    fn emitter(&self, at: &At, v: [DVec3; 3], met: &mut Met) -> Result<DVec3, Unsure> {
        let (u, w) = (v[1] - v[0], v[2] - v[0]);
        let area = 0.5 * u.cross(w).length();
        let front = u.cross(w).normalize();
        let g = GRID as f64;
        // Barycentric (a, b) of each small triangle's centroid: the upright ones of each
        // row, and the upside-down ones between them.
        let upright = (0..GRID).flat_map(|i| (0..GRID - i).map(move |j| (i, j, 1.0 / 3.0)));
        let flipped = (0..GRID).flat_map(|i| (0..GRID - i - 1).map(move |j| (i, j, 2.0 / 3.0)));
        let mut sum = DVec3::ZERO;
        let mut first: Option<Option<DVec3>> = None;
        for (i, j, c) in upright.chain(flipped) {
            let q = v[0] + (i as f64 + c) / g * u + (j as f64 + c) / g * w;
            let to = q - at.above;
            let (l, r) = (to.normalize(), to.length());
            let cos_e = -front.dot(l);
            if cos_e.abs() < MARGIN {
                return Err(Unsure);
            }
            // Stops short of the emitter, which the ray would otherwise meet at its end.
            let lit = if cos_e > 0.0 {
                self.lit(at, l, r * (1.0 - 1e-9), met)?
            } else {
                None
            };
            let seen = lit.map(|(through, _)| through);
            if *first.get_or_insert(seen) != seen {
                return Err(Unsure);
            }
            sum += lit.map_or(DVec3::ZERO, |(through, shade)| {
                through * shade * cos_e / (std::f64::consts::PI * r * r)
            });
        }
        Ok(sum * area / (g * g))
    }
}

/// A surface point being shaded: the point lifted off it towards the side the lights must
/// be on, the normal facing the ray, the ray's direction and the material's terms.
struct At {
    above: DVec3,
    n: DVec3,
    dir: DVec3,
    kd_c: DVec3,
    ks: f64,
    shine: f64,
}
