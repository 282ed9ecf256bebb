//! Wavefront `.mtl` material libraries, which an OBJ file names with `mtllib` and whose
//! materials its `usemtl` lines give the faces after them. Each `newmtl` block is mapped
//! onto the shading model's material (`f r g b Kd Ks Shine T ior`, shared/docs/shading.md)
//! as docs/scene-format.md's table says: `Kd` is the colour and the diffuse weight, `Ks`
//! the mirror and highlight weight where `illum` asks for reflection (3 and up), `Ns` the
//! Phong exponent, `d`/`Tr` the transmission, `Ni` the index of refraction of glass
//! (`illum` 4, 6, 7), `Ke` the radiance an emitter gives off (its triangles are then
//! lights), `map_Kd` the image the colour is multiplied by (read when a face first uses
//! the material: `images`). Statements the model has no room for (other maps, ...) are
//! skipped with one warning each per file.

mod map;

use std::collections::HashMap;
use std::path::Path;

use glam::{Affine2, Vec3};

use super::io;
use super::lex::{Lexer, Token};
use super::model::{Material, MaterialId};
use super::sink::MeshOut;
use crate::util::error::{Error, Result, escape};
use crate::util::limits::{MAX_LIGHT, MAX_SHINE};

/// A library's materials by name (a later `newmtl` of a name replaces the earlier).
pub type Library = HashMap<String, Entry>;
pub use map::MapKd;

/// A library's material: the shading model's, and its `map_Kd` if it has one.
#[derive(Clone, Debug)]
pub struct Entry {
    pub material: Material,
    pub map_kd: Option<MapKd>,
}

/// What a `newmtl` block says, with the defaults of a block that says nothing.
#[derive(Clone, Debug)]
struct Block {
    kd: Vec3,
    ks: Vec3,
    ke: Vec3,
    ns: f32,
    /// Dissolve: 1 is opaque (`Tr` is `1 - d`).
    d: f32,
    ni: f32,
    illum: u32,
    map_kd: Option<MapKd>,
}

impl Default for Block {
    fn default() -> Self {
        Block {
            kd: Vec3::splat(0.8),
            ks: Vec3::ZERO,
            ke: Vec3::ZERO,
            ns: 30.0,
            d: 1.0,
            ni: 1.0,
            illum: 2,
            map_kd: None,
        }
    }
}

impl Block {
    /// The library's entry for this block.
    fn entry(self) -> Entry {
        Entry {
            material: self.material(),
            map_kd: self.map_kd,
        }
    }

    /// The shading model's material for this block (its texture is added when a face
    /// uses it).
    fn material(&self) -> Material {
        let kd = self.kd.max_element();
        // A black diffuse colour (glass often has one) keeps a white colour: the colour is
        // also the filter of light through the surface.
        let color = if kd > 0.0 { self.kd / kd } else { Vec3::ONE };
        let glass = matches!(self.illum, 4 | 6 | 7);
        Material {
            color,
            kd,
            ks: if self.illum >= 3 {
                self.ks.element_sum() / 3.0
            } else {
                0.0
            },
            shine: self.ns,
            t: 1.0 - self.d,
            ior: if glass { self.ni } else { 1.0 },
            emission: self.ke,
            texture: None,
            ambient: None,
        }
    }
}

/// Reads a material library from `lx`, a file in folder `dir`, into `library`; what is
/// skipped goes into `warnings` (`FILE:LINE:COL: message`). A number that is not one is
/// an error.
pub fn read(
    mut lx: Lexer,
    dir: Option<&Path>,
    library: &mut Library,
    warnings: &mut Vec<String>,
) -> Result<()> {
    let mut current: Option<(String, Block)> = None;
    let mut skipped: Vec<String> = Vec::new();
    let warn = |warnings: &mut Vec<String>, lx: &Lexer, t: &Token, msg: String| {
        warnings.push(format!("{}:{}:{}: {msg}", lx.name(), t.line, t.col));
    };
    while let Some(t) = lx.next_token()? {
        let line = t.line;
        let word = String::from_utf8_lossy(lx.text(&t)).into_owned();
        if word == "newmtl" {
            let name = lx.rest_of_line(line)?;
            if name.is_empty() {
                return Err(lx.error_at(&t, "expected a material name after 'newmtl'"));
            }
            if let Some((name, block)) = current.replace((name, Block::default())) {
                library.insert(name, block.entry());
            }
            continue;
        }
        let Some((_, block)) = current.as_mut() else {
            if !skipped.contains(&word) {
                let msg = format!("'{word}' before the first 'newmtl' is skipped");
                warn(warnings, &lx, &t, msg);
                skipped.push(word);
            }
            lx.skip_line(line)?;
            continue;
        };
        let mut last = t;
        match word.as_str() {
            "Kd" | "Ks" | "Ka" | "Ke" => {
                let colour = match lx.peek()? {
                    Some(n)
                        if n.line == line
                            && lx.text(&n).first().is_some_and(u8::is_ascii_alphabetic) =>
                    {
                        None
                    }
                    _ => Some(rgb(&mut lx, &mut last, &word)?),
                };
                match (word.as_str(), colour) {
                    ("Kd", Some(c)) => block.kd = held(warnings, &lx, &t, &word, c, 1.0),
                    ("Ks", Some(c)) => block.ks = held(warnings, &lx, &t, &word, c, 1.0),
                    // Radiance, not a reflectance: above 1 where it lights a room.
                    ("Ke", Some(c)) => block.ke = held(warnings, &lx, &t, &word, c, MAX_LIGHT),
                    // The model's ambient term is `ambient * Kd * colour`: Ka has no room of
                    // its own, and the diffuse colour stands for it.
                    ("Ka", Some(_)) => {}
                    _ => {
                        if !skipped.contains(&word) {
                            let msg = format!(
                                "'{word}' given as spectral or CIE XYZ values is not read; the default is kept here and below"
                            );
                            warn(warnings, &lx, &t, msg);
                            skipped.push(word.clone());
                        }
                    }
                }
            }
            "Ns" => {
                let ns = lx.number_on_line(&mut last, "Ns")?;
                block.ns = ns.clamp(0.0, MAX_SHINE);
            }
            "d" | "Tr" => {
                // `d -halo 0.5`: the halo is a view-dependent dissolve; the value is kept.
                if lx
                    .peek()?
                    .is_some_and(|n| n.line == line && lx.text(&n) == b"-halo")
                {
                    lx.next_token()?;
                }
                let v = lx.number_on_line(&mut last, &word)?.clamp(0.0, 1.0);
                block.d = if word == "d" { v } else { 1.0 - v };
            }
            "Ni" => {
                let ni = lx.number_on_line(&mut last, "Ni")?;
                if ni <= 0.0 {
                    warn(
                        warnings,
                        &lx,
                        &t,
                        format!("Ni {ni} is not positive; using 1"),
                    );
                }
                block.ni = if ni > 0.0 { ni } else { 1.0 };
            }
            "map_Kd" => {
                block.map_kd = map::map_kd(&mut lx, &t, dir, warnings, &mut skipped)?;
                continue;
            }
            "illum" => {
                let n = lx.number_on_line(&mut last, "illum (an illumination model, 0 to 10)")?;
                block.illum = n.clamp(0.0, 10.0) as u32;
            }
            _ => {
                if !skipped.contains(&word) {
                    let msg = format!(
                        "'{word}' is not read (of the maps, the shading model reads map_Kd only); skipped here and below"
                    );
                    warn(warnings, &lx, &t, msg);
                    skipped.push(word.clone());
                }
            }
        }
        lx.skip_line(line)?;
    }
    if let Some((name, block)) = current {
        library.insert(name, block.entry());
    }
    Ok(())
}

/// An OBJ file's materials as its `mtllib` and `usemtl` lines name them.
#[derive(Default)]
pub struct ObjMaterials {
    library: Library,
    /// What the names used so far gave (`usemtl`), and the names no library defines
    /// (warned of).
    used: HashMap<String, (MaterialId, Affine2)>,
    unknown: Vec<String>,
}

impl ObjMaterials {
    /// `mtllib NAME...` at token `t`: reads each library, relative to the OBJ's folder. A
    /// library that cannot be read is a warning at the name; one that reads badly is an
    /// error in it.
    pub fn mtllib(&mut self, lx: &mut Lexer, t: &Token, out: &mut MeshOut) -> Result<()> {
        let mut names = Vec::new();
        while let Some(n) = lx.token_on_line(t.line)? {
            names.push((String::from_utf8_lossy(lx.text(&n)).into_owned(), n));
        }
        // Names are separated by blanks, but a single name with blanks in it exists too.
        let whole = names
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(" ");
        if names.len() > 1 && out.dir.is_some_and(|d| d.join(&whole).is_file()) {
            names.truncate(1);
            names[0].0 = whole;
        }
        for (name, at) in names {
            let path = out.dir.map(|d| d.join(&name));
            let input = match path.as_deref().map(io::open) {
                Some(Ok(input)) => input,
                failed => {
                    let why = match failed {
                        Some(Err(Error::Io { source, .. })) => source.to_string(),
                        Some(Err(e)) => e.to_string(),
                        _ => "the OBJ was not read from a file".into(),
                    };
                    out.warnings.push(format!(
                        "{}:{}:{}: cannot read material library '{}': {why}; its materials are not used",
                        lx.name(),
                        at.line,
                        at.col,
                        escape(name.as_bytes())
                    ));
                    continue;
                }
            };
            let path = path.expect("opened");
            let file = path.display().to_string();
            read(
                Lexer::through(input, &file, out.window),
                path.parent(),
                &mut self.library,
                out.warnings,
            )?;
        }
        Ok(())
    }

    /// `usemtl NAME` at token `t`: the material of the faces after it, and the map of
    /// their texture coordinates onto its texture (`map_Kd -s -o`). A name no library
    /// defines is a warning (the first time it is used), and its faces get the default. A
    /// texture that cannot be had is a warning naming it and the material, whose colour
    /// the faces keep.
    pub fn usemtl(
        &mut self,
        lx: &mut Lexer,
        t: &Token,
        out: &mut MeshOut,
    ) -> Result<(MaterialId, Affine2)> {
        let name = lx.rest_of_line(t.line)?;
        if let Some(&used) = self.used.get(&name) {
            return Ok(used);
        }
        let Some(entry) = self.library.get(&name) else {
            if !self.unknown.contains(&name) {
                out.warnings.push(format!(
                    "{}:{}:{}: unknown material '{}' (no material library read defines it); its faces get the default material",
                    lx.name(),
                    t.line,
                    t.col,
                    escape(name.as_bytes())
                ));
                self.unknown.push(name);
            }
            return Ok((out.default, Affine2::IDENTITY));
        };
        let (mut m, mut uv) = (entry.material, Affine2::IDENTITY);
        if let Some(map) = &entry.map_kd {
            match map::texture(map, out) {
                Ok(i) => (m.texture, uv) = (Some(i), map.uv),
                Err(why) => out.warnings.push(format!(
                    "{}: texture '{}' of material '{}' is not used: {why}; its faces keep the material's colour",
                    map.at,
                    escape(map.path.as_bytes()),
                    escape(name.as_bytes())
                )),
            }
        }
        let used = (out.palette.id(out.materials, m), uv);
        self.used.insert(name, used);
        Ok(used)
    }
}

/// `r [g b]`: one number is a grey.
fn rgb(lx: &mut Lexer, last: &mut Token, what: &str) -> Result<Vec3> {
    let r = lx.number_on_line(last, what)?;
    if lx.peek()?.is_none_or(|n| n.line != last.line) {
        return Ok(Vec3::splat(r));
    }
    let g = lx.number_on_line(last, what)?;
    let b = lx.number_on_line(last, what)?;
    Ok(Vec3::new(r, g, b))
}

/// `c` held to [0, `hi`], with a warning when it was outside.
fn held(warnings: &mut Vec<String>, lx: &Lexer, t: &Token, what: &str, c: Vec3, hi: f32) -> Vec3 {
    let h = c.clamp(Vec3::ZERO, Vec3::splat(hi));
    if h != c {
        warnings.push(format!(
            "{}:{}:{}: {what} {} {} {} is outside [0, {hi}]; using {} {} {}",
            lx.name(),
            t.line,
            t.col,
            c.x,
            c.y,
            c.z,
            h.x,
            h.y,
            h.z
        ));
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::model::Wrap;

    pub(super) fn library(src: &str) -> (Library, Vec<String>) {
        let mut lib = Library::new();
        let mut warnings = Vec::new();
        let dir = Some(Path::new("models"));
        read(
            Lexer::new(src.as_bytes(), "m.mtl"),
            dir,
            &mut lib,
            &mut warnings,
        )
        .unwrap();
        (lib, warnings)
    }

    #[test]
    fn blocks_map_onto_the_shading_model() {
        let (lib, warnings) = library(
            "# two\nnewmtl red\nKd 0.8 0.2 0.2\nKs 0.5 0.5 0.5\nNs 100\nillum 2\n\
             newmtl glass pane\nKd 0 0 0\nKs 1 1 1\nd 0.1\nNi 1.5\nillum 7\nmap_Kd a.png\n\
             newmtl mirror\nKd 0.1\nKs 0.9 0.6 0.3\nillum 3\nmap_Kd b.png\nTr 0.25\n\
             newmtl light\nKd 0.78\nKe 17 12 4\n",
        );
        let red = lib["red"].material;
        assert_eq!((red.kd, red.ks, red.t, red.ior), (0.8, 0.0, 0.0, 1.0));
        assert!(
            (red.color * red.kd - Vec3::new(0.8, 0.2, 0.2))
                .abs()
                .max_element()
                < 1e-6
        );
        let glass = lib["glass pane"].material;
        assert_eq!((glass.color, glass.kd), (Vec3::ONE, 0.0));
        assert_eq!((glass.ks, glass.ior, glass.shine), (1.0, 1.5, 30.0));
        assert!((glass.t - 0.9).abs() < 1e-6);
        let mirror = lib["mirror"].material;
        assert!((mirror.ks - 0.6).abs() < 1e-6 && mirror.kd == 0.1);
        // Tr without glass: dissolve, straight through.
        assert_eq!((mirror.t, mirror.ior), (0.25, 1.0));
        // `Ke` is radiance: kept above 1; the others emit nothing.
        let light = lib["light"].material;
        assert_eq!(light.emission, Vec3::new(17.0, 12.0, 4.0));
        assert!(light.emits() && !red.emits() && !glass.emits());
        assert!(warnings.is_empty(), "{warnings:?}");
        let map = lib["mirror"].map_kd.as_ref().unwrap();
        assert_eq!((map.path.as_str(), map.wrap), ("b.png", Wrap::Repeat));
        assert_eq!(map.dir.as_deref(), Some(Path::new("models")));
        assert!(lib["red"].map_kd.is_none());
    }

    #[test]
    fn a_bad_number_is_an_error_at_its_place() {
        let mut lib = Library::new();
        let e = read(
            Lexer::new(b"newmtl a\nKd 1 x 1\n", "m.mtl"),
            None,
            &mut lib,
            &mut Vec::new(),
        );
        assert_eq!(
            e.unwrap_err().to_string(),
            "m.mtl:2:6: expected Kd (a finite number), found 'x'"
        );
    }
}
