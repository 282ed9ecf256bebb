//! The NFF reader: Haines' NFF 3.9 (`v b l f c s p pp`), the IST P3D dialect (`pl`, `aabb`)
//! and gpurt's extensions (`mesh`, `dl`, `al`, `am`, and `aperture`/`focal` in the view).
//! The exact syntax accepted is documented in `docs/scene-format.md`.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::lex::{Lexer, Token, escape_controls};
use super::mesh::{self, MeshTransform};
use super::triangulate::triangulate;
use super::{BoxPrim, Cone, FileKind, Light, Material, MaterialId, Plane, Scene, Sphere, Triangle};
use crate::error::{Error, Result};
use crate::limits::{MAX_AREA_LIGHT_SAMPLES, MAX_IMAGE_SIDE, MAX_LIGHT, MAX_SHINE};

/// Parses NFF text. `name` is used in messages; `base` is the directory `mesh` paths are
/// relative to.
pub fn parse(src: &[u8], name: &str, base: &Path) -> Result<Scene> {
    let mut p = Parser {
        lx: Lexer::new(src, name),
        base,
        scene: Scene::new(name, super::nff_default_camera()),
        have_view: false,
        material: None,
        material_ids: HashMap::new(),
        verts: Vec::new(),
        normals: Vec::new(),
        tris: Vec::new(),
    };
    p.run()?;
    Ok(p.scene)
}

struct Parser<'a> {
    lx: Lexer<'a>,
    base: &'a Path,
    scene: Scene,
    have_view: bool,
    /// The current material (`None` until the first `f` or the first primitive).
    material: Option<MaterialId>,
    /// Exact duplicates share one id (SPD repeats `f` lines for every object).
    material_ids: HashMap<[u32; 8], MaterialId>,
    // Scratch buffers reused by every polygon.
    verts: Vec<Vec3>,
    normals: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
}

impl Parser<'_> {
    fn run(&mut self) -> Result<()> {
        let mut first = true;
        while let Some(tok) = self.lx.next_token() {
            let is_first = std::mem::replace(&mut first, false);
            match tok.text {
                b"v" => self.view(&tok)?,
                b"b" => {
                    let c = self.lx.vec3("background colour")?;
                    self.scene.background = self.hold3(&tok, "background colour", c, MAX_LIGHT);
                }
                b"l" => {
                    let position = self.lx.vec3("light position")?;
                    let color = self.optional_colour("light colour")?;
                    let color = color.map(|c| self.hold3(&tok, "light colour", c, MAX_LIGHT));
                    self.scene.lights.push(Light::Point { position, color });
                }
                b"dl" => {
                    let direction = self.lx.vec3("light direction")?;
                    if direction.length_squared() == 0.0 {
                        return Err(self
                            .lx
                            .error_at(&tok, "directional light with a zero direction"));
                    }
                    let color = self.optional_colour("light colour")?;
                    let color = color.map(|c| self.hold3(&tok, "light colour", c, MAX_LIGHT));
                    self.scene.lights.push(Light::Directional {
                        direction: direction.normalize(),
                        color,
                    });
                }
                b"al" => self.area_light(&tok)?,
                b"am" => {
                    let c = self.lx.vec3("ambient colour")?;
                    self.scene.ambient = Some(self.hold3(&tok, "ambient colour", c, MAX_LIGHT));
                }
                b"f" => self.fill(&tok)?,
                b"c" => self.cone()?,
                b"s" => {
                    let center = self.lx.vec3("sphere centre")?;
                    let radius = self.lx.number("sphere radius")?;
                    let material = self.current_material();
                    if radius == 0.0 {
                        self.warn(&tok, "sphere of radius 0 dropped");
                    } else {
                        self.scene.spheres.push(Sphere {
                            center,
                            radius: radius.abs(),
                            material,
                        });
                    }
                }
                b"p" => self.polygon(&tok, false)?,
                b"pp" => self.polygon(&tok, true)?,
                b"pl" => self.plane(&tok)?,
                b"aabb" => self.aabb()?,
                b"mesh" => self.mesh(&tok)?,
                b"nff" if is_first => {
                    return Err(self.lx.error_at(
                        &tok,
                        "this is a Sense8 NFF file (starts with 'nff'), not Haines' NFF",
                    ));
                }
                _ if super::lex::parse_f32(tok.text).is_some() => {
                    // Usually a light in the `l x y z intensity r g b` variant, or a count
                    // that is smaller than the numbers that follow it.
                    return Err(self.lx.error_at(
                        &tok,
                        format!(
                            "expected an entity keyword, found the number {} (too many numbers for the entity before it?)",
                            tok.show()
                        ),
                    ));
                }
                _ => {
                    return Err(self.lx.error_at(
                        &tok,
                        format!("expected an entity keyword, found {}", tok.show()),
                    ));
                }
            }
        }
        if !self.have_view {
            return Err(self.lx.error_here(
                "expected a view ('v' with from/at/up/angle), found none in the file",
            ));
        }
        Ok(())
    }

    /// `v` held to `[0, hi]`, with a warning naming the line when it was outside.
    fn hold(&mut self, tok: &Token, what: &str, v: f32, hi: f32) -> f32 {
        if (0.0..=hi).contains(&v) {
            return v;
        }
        let held = v.clamp(0.0, hi);
        self.warn(
            tok,
            &format!("{what} {v} is outside [0, {hi}]; using {held}"),
        );
        held
    }

    /// Each component of `v` held to `[0, hi]`, with one warning when any was outside.
    fn hold3(&mut self, tok: &Token, what: &str, v: Vec3, hi: f32) -> Vec3 {
        let held = v.clamp(Vec3::ZERO, Vec3::splat(hi));
        if held != v {
            self.warn(
                tok,
                &format!(
                    "{what} {} {} {} is outside [0, {hi}]; using {} {} {}",
                    v.x, v.y, v.z, held.x, held.y, held.z
                ),
            );
        }
        held
    }

    fn warn(&mut self, tok: &Token, msg: &str) {
        let w = format!("{}:{}:{}: {msg}", self.lx.name(), tok.line, tok.col);
        self.scene.warnings.push(w);
    }

    fn optional_colour(&mut self, what: &str) -> Result<Option<Vec3>> {
        if self.lx.peek_is_number() {
            Ok(Some(self.lx.vec3(what)?))
        } else {
            Ok(None)
        }
    }

    fn current_material(&mut self) -> MaterialId {
        match self.material {
            Some(m) => m,
            None => {
                let id = self.intern(Material::DEFAULT);
                self.material = Some(id);
                id
            }
        }
    }

    fn intern(&mut self, m: Material) -> MaterialId {
        let key = [
            m.color.x, m.color.y, m.color.z, m.kd, m.ks, m.shine, m.t, m.ior,
        ]
        .map(f32::to_bits);
        let materials = &mut self.scene.materials;
        *self.material_ids.entry(key).or_insert_with(|| {
            materials.push(m);
            MaterialId(materials.len() as u32 - 1)
        })
    }

    fn view(&mut self, vtok: &Token) -> Result<()> {
        let mut cam = super::nff_default_camera();
        let (mut from, mut at, mut up, mut angle) = (None, None, None, None);
        let mut resolution = None;
        while let Some(t) = self.lx.peek() {
            match t.text {
                b"from" | b"at" | b"up" | b"angle" | b"hither" | b"resolution" | b"aperture"
                | b"focal" => {}
                _ => break,
            }
            self.lx.next_token();
            match t.text {
                b"from" => from = Some(self.lx.vec3("'from' coordinate")?),
                b"at" => at = Some(self.lx.vec3("'at' coordinate")?),
                b"up" => up = Some(self.lx.vec3("'up' coordinate")?),
                b"angle" => {
                    let a = self.lx.peek();
                    let v = self.lx.number("view angle in degrees")?;
                    if !(v > 0.0 && v < 180.0) {
                        let a = a.expect("number was read");
                        return Err(self.lx.error_at(
                            &a,
                            format!("expected a view angle in (0, 180) degrees, found {v}"),
                        ));
                    }
                    angle = Some(v);
                }
                b"hither" => {
                    let h = self.lx.number("hither distance")?;
                    cam.hither = h.max(0.0);
                }
                b"resolution" => {
                    let (w, wt) = self.lx.count("resolution width")?;
                    let (h, ht) = self.lx.count("resolution height")?;
                    for (v, t) in [(w, wt), (h, ht)] {
                        if v == 0 || v > MAX_IMAGE_SIDE {
                            return Err(self.lx.error_at(
                                &t,
                                format!(
                                    "expected a resolution between 1 and {MAX_IMAGE_SIDE}, found {v}"
                                ),
                            ));
                        }
                    }
                    resolution = Some((w, h));
                }
                b"aperture" => cam.aperture = self.lx.number("lens aperture")?.abs(),
                b"focal" => {
                    let f = self.lx.peek();
                    let d = self.lx.number("focal distance")?;
                    if d <= 0.0 {
                        let f = f.expect("number was read");
                        return Err(self.lx.error_at(
                            &f,
                            format!("expected a positive focal distance, found {d}"),
                        ));
                    }
                    cam.focal = Some(d);
                }
                _ => unreachable!(),
            }
        }
        let missing = [
            ("from", from.is_none()),
            ("at", at.is_none()),
            ("up", up.is_none()),
            ("angle", angle.is_none()),
        ];
        if let Some((what, _)) = missing.iter().find(|(_, m)| *m) {
            return Err(self.lx.error_at(
                vtok,
                format!("view is missing '{what}' (from, at, up and angle are required)"),
            ));
        }
        cam.from = from.unwrap();
        cam.at = at.unwrap();
        cam.up = up.unwrap();
        cam.angle = angle.unwrap();
        if let Some((w, h)) = resolution {
            cam.width = w;
            cam.height = h;
        }
        let dir = cam.at - cam.from;
        if dir.length_squared() == 0.0 {
            return Err(self
                .lx
                .error_at(vtok, "degenerate view: 'from' and 'at' are the same point"));
        }
        let side = dir.normalize().cross(cam.up.normalize_or_zero());
        if side.length() < 1e-6 {
            return Err(self.lx.error_at(
                vtok,
                "degenerate view: 'up' is zero or parallel to the view direction",
            ));
        }
        if self.have_view {
            self.warn(vtok, "second view replaces the first");
        }
        self.have_view = true;
        self.scene.camera = cam;
        Ok(())
    }

    fn fill(&mut self, tok: &Token) -> Result<()> {
        let color = self.lx.vec3("material colour")?;
        let color = self.hold3(tok, "material colour", color, 1.0);
        let kd = self.lx.number("Kd")?;
        let kd = self.hold(tok, "Kd", kd, 1.0);
        let ks = self.lx.number("Ks")?;
        let ks = self.hold(tok, "Ks", ks, 1.0);
        let shine = self.lx.number("Shine")?;
        let shine = self.hold(tok, "Shine", shine, MAX_SHINE);
        let t = self.lx.number("T")?;
        let t = self.hold(tok, "T", t, 1.0);
        let ior = self.lx.number("index of refraction")?;
        if t > 0.0 && ior <= 0.0 {
            return Err(self.lx.error_at(
                tok,
                format!("a transmitting material (T = {t}) needs a positive index of refraction, found {ior}"),
            ));
        }
        let m = Material {
            color,
            kd,
            ks,
            shine,
            t,
            // T = 0 makes ior meaningless (SPD writes 0): keep a harmless value.
            ior: if t > 0.0 { ior } else { 1.0 },
        };
        self.material = Some(self.intern(m));
        Ok(())
    }

    fn cone(&mut self) -> Result<()> {
        let base = self.lx.vec3("cone base centre")?;
        let base_radius = self.lx.number("cone base radius")?;
        let apex = self.lx.vec3("cone apex centre")?;
        let apex_radius = self.lx.number("cone apex radius")?;
        let material = self.current_material();
        self.scene.cones.push(Cone {
            base,
            base_radius: base_radius.abs(),
            apex,
            apex_radius: apex_radius.abs(),
            material,
        });
        Ok(())
    }

    fn polygon(&mut self, tok: &Token, patch: bool) -> Result<()> {
        let kind = if patch { "patch" } else { "polygon" };
        let what = if patch {
            "patch vertex count"
        } else {
            "polygon vertex count"
        };
        let (n, ntok) = self.lx.count(what)?;
        // Each vertex needs at least 3 (or 6) one-character numbers and separators: a count
        // the rest of the file cannot hold is a lie, reported before anything is allocated.
        let min_bytes = n as u64 * if patch { 12 } else { 6 };
        if min_bytes > self.lx.remaining() as u64 + 1 {
            return Err(self.lx.error_at(
                &ntok,
                format!(
                    "{kind} vertex count {n} is more than the rest of the file can hold ({} bytes)",
                    self.lx.remaining()
                ),
            ));
        }
        self.verts.clear();
        self.normals.clear();
        for i in 0..n {
            let mut what = VertexWhat {
                kind,
                index: i + 1,
                count: n,
                normal: false,
            };
            self.verts.push(self.lx.vec3(&what)?);
            if patch {
                what.normal = true;
                self.normals.push(self.lx.vec3(&what)?);
            }
        }
        let material = self.current_material();
        self.tris.clear();
        if n < 3 || !triangulate(&self.verts, &mut self.tris) {
            self.warn(tok, &format!("degenerate {kind} with {n} vertices dropped"));
            return Ok(());
        }
        // Shading normals are kept as unit vectors; a patch with a normal that has no
        // direction (zero) would shade to 0 / 0, so it is read as a flat polygon.
        let mut zero = None;
        for (i, n) in self.normals.iter_mut().enumerate() {
            match super::unit(*n) {
                Some(u) => *n = u,
                None => zero = zero.or(Some(i + 1)),
            }
        }
        if let Some(i) = zero {
            let msg = format!("normal of patch vertex {i} is zero; the patch is shaded flat");
            self.warn(tok, &msg);
        }
        let smooth = patch && zero.is_none();
        for &[a, b, c] in &self.tris {
            let (a, b, c) = (a as usize, b as usize, c as usize);
            let n = smooth.then(|| Box::new([self.normals[a], self.normals[b], self.normals[c]]));
            self.scene.triangles.push(Triangle {
                v: [self.verts[a], self.verts[b], self.verts[c]],
                n,
                material,
            });
        }
        Ok(())
    }

    fn plane(&mut self, tok: &Token) -> Result<()> {
        let a = self.lx.vec3("plane point 1")?;
        let b = self.lx.vec3("plane point 2")?;
        let c = self.lx.vec3("plane point 3")?;
        let n = (b - a).cross(c - a);
        if n.length_squared() == 0.0 || !n.is_finite() {
            return Err(self
                .lx
                .error_at(tok, "degenerate plane: its three points are collinear"));
        }
        let material = self.current_material();
        self.scene.planes.push(Plane {
            point: a,
            normal: n.normalize(),
            material,
        });
        Ok(())
    }

    fn aabb(&mut self) -> Result<()> {
        let mut lo = [0.0f32; 3];
        let mut hi = [0.0f32; 3];
        const WHAT: [[&str; 2]; 3] = [
            ["box x min", "box x max"],
            ["box y min", "box y max"],
            ["box z min", "box z max"],
        ];
        for (axis, [wmin, wmax]) in WHAT.iter().enumerate() {
            let a = self.lx.number(wmin)?;
            let b = self.lx.number(wmax)?;
            lo[axis] = a.min(b);
            hi[axis] = a.max(b);
        }
        let material = self.current_material();
        self.scene.boxes.push(BoxPrim {
            min: Vec3::from(lo),
            max: Vec3::from(hi),
            material,
        });
        Ok(())
    }

    fn area_light(&mut self, tok: &Token) -> Result<()> {
        let corner = self.lx.vec3("area light corner")?;
        let u = self.lx.vec3("area light edge u")?;
        let v = self.lx.vec3("area light edge v")?;
        let color = self.lx.vec3("area light colour")?;
        let color = self.hold3(tok, "area light colour", color, MAX_LIGHT);
        let (nu, nut) = self.lx.count("area light samples along u")?;
        let (nv, nvt) = self.lx.count("area light samples along v")?;
        for (n, t) in [(nu, nut), (nv, nvt)] {
            if n == 0 || n > MAX_AREA_LIGHT_SAMPLES {
                return Err(self.lx.error_at(
                    &t,
                    format!(
                        "expected area light samples between 1 and {MAX_AREA_LIGHT_SAMPLES}, found {n}"
                    ),
                ));
            }
        }
        if u.cross(v).length_squared() == 0.0 {
            return Err(self
                .lx
                .error_at(tok, "degenerate area light: its edges are parallel or zero"));
        }
        self.scene.lights.push(Light::Area {
            corner,
            u,
            v,
            color,
            samples: [nu, nv],
        });
        Ok(())
    }

    fn mesh(&mut self, tok: &Token) -> Result<()> {
        let ptok = self.lx.expect_token("mesh file path")?;
        let raw = String::from_utf8_lossy(ptok.text);
        let rel = raw.trim_matches('"');
        let mut xf = MeshTransform::default();
        while let Some(t) = self.lx.peek() {
            match t.text {
                b"translate" => {
                    self.lx.next_token();
                    xf.translate = self.lx.vec3("mesh translation")?;
                }
                b"rotate" => {
                    self.lx.next_token();
                    xf.rotate_deg = self.lx.vec3("mesh rotation in degrees")?;
                }
                b"scale" => {
                    self.lx.next_token();
                    let s = self.lx.number("mesh scale")?;
                    xf.scale = if self.lx.peek_is_number() {
                        Vec3::new(
                            s,
                            self.lx.number("mesh scale y")?,
                            self.lx.number("mesh scale z")?,
                        )
                    } else {
                        Vec3::splat(s)
                    };
                    if xf.scale.cmpeq(Vec3::ZERO).any() {
                        return Err(self.lx.error_at(&t, "mesh scale must not be zero"));
                    }
                }
                _ => break,
            }
        }
        let path = self.base.join(rel);
        let kind = FileKind::of(&path);
        if kind == FileKind::Nff {
            return Err(self.lx.error_at(
                &ptok,
                format!(
                    "mesh file '{}' must end in .stl or .obj (optionally .gz)",
                    escape_controls(rel)
                ),
            ));
        }
        let bytes = super::read_file(&path).map_err(|e| {
            let why = match e {
                Error::Io { source, .. } => source.to_string(),
                Error::Scene { msg, .. } => msg,
                other => return other,
            };
            self.lx.error_at(
                &ptok,
                format!(
                    "cannot read mesh file '{}': {why}",
                    escape_controls(&path.display().to_string())
                ),
            )
        })?;
        let mesh = mesh::parse_mesh(&bytes, kind, &path.display().to_string())?;
        self.scene.warnings.extend(mesh.warnings);
        let mut tris = mesh.triangles;
        if tris.is_empty() {
            self.warn(
                tok,
                &format!("mesh '{}' has no triangles", escape_controls(rel)),
            );
        }
        let material = self.current_material();
        xf.apply(&mut tris);
        for t in &mut tris {
            t.material = material;
        }
        self.scene.triangles.append(&mut tris);
        Ok(())
    }
}

/// "polygon vertex 3 of 5" (or "normal of patch vertex ..."), formatted only for a message:
/// building this string for every vertex read cost more than parsing the vertex.
struct VertexWhat {
    kind: &'static str,
    index: u32,
    count: u32,
    normal: bool,
}

impl std::fmt::Display for VertexWhat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.normal {
            f.write_str("normal of ")?;
        }
        write!(f, "{} vertex {} of {}", self.kind, self.index, self.count)
    }
}
