//! The `mesh PATH [translate ..] [rotate ..] [scale ..] [nomtl]` statement: an STL or OBJ
//! file read (relative to the scene's directory, gzip-aware) and transformed; its faces get
//! the materials an OBJ's `usemtl` names, and the current material where it names none
//! (or everywhere, with `nomtl`). Beside it, AFF's include (`i level file`): another AFF
//! or NFF file read in place, inside the open blocks, with the current material, unless
//! its level is above the detail level (`d`). The two statements that read another scene
//! file.

use std::path::Path;

use glam::Vec3;

use super::{Parser, keyword};
use crate::scene::io::{self, FileKind};
use crate::scene::lex::{Lexer, Token};
use crate::scene::mesh::{self, MeshTransform};
use crate::scene::model::{Scene, nff_default_camera};
use crate::scene::place::Placed;
use crate::scene::sink::MeshOut;
use crate::util::error::{Error, Result, escape};

/// Includes nested deeper than this are refused (a file that includes itself).
const MAX_INCLUDE_DEPTH: u32 = 32;

impl Parser<'_> {
    pub(super) fn mesh(&mut self, tok: &Token) -> Result<()> {
        let ptok = self.lx.expect_token("mesh file path")?;
        let raw = String::from_utf8_lossy(self.lx.text(&ptok)).into_owned();
        let rel = raw.trim_matches('"');
        let mut xf = MeshTransform::default();
        let mut mtl = true;
        while let Some(t) = self.lx.peek()? {
            let (word, len) = keyword(self.lx.text(&t));
            match &word[..len] {
                b"translate" => {
                    self.lx.next_token()?;
                    xf.translate = self.lx.vec3("mesh translation")?;
                }
                b"rotate" => {
                    self.lx.next_token()?;
                    xf.rotate_deg = self.lx.vec3("mesh rotation in degrees")?;
                }
                b"scale" => {
                    self.lx.next_token()?;
                    let s = self.lx.number("mesh scale")?;
                    xf.scale = if self.lx.peek_is_number()? {
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
                b"nomtl" => {
                    self.lx.next_token()?;
                    mtl = false;
                }
                _ => break,
            }
        }
        let path = self.base.join(rel);
        let kind = FileKind::of(&path);
        if matches!(kind, FileKind::Nff | FileKind::Gltf) {
            return Err(self.lx.error_at(
                &ptok,
                format!(
                    "mesh file '{}' must end in .stl, .obj or .ply (optionally .gz)",
                    escape(rel.as_bytes())
                ),
            ));
        }
        let material = self.current_material();
        // What keeps the file from being read is reported at the path in the scene.
        let cannot_read = |e: Error| {
            let why = match e {
                Error::Io { source, .. } => source.to_string(),
                Error::Scene { msg, .. } => msg,
                other => return other,
            };
            self.lx.error_at(
                &ptok,
                format!(
                    "cannot read mesh file '{}': {why}",
                    escape(path.as_os_str().as_encoded_bytes())
                ),
            )
        };
        let input = io::open(&path).map_err(cannot_read)?;
        let name = path.display().to_string();
        let mut route = super::blocks::Route::new(&mut *self.sink, &mut self.blocks);
        let mut placed = Placed::new(&mut route, xf.placement());
        let mut out = MeshOut {
            sink: &mut placed,
            warnings: &mut self.scene.warnings,
            materials: &mut self.scene.materials,
            palette: &mut self.palette,
            textures: &mut self.scene.textures,
            default: material,
            mtl,
            dir: path.parent(),
            window: self.window,
        };
        let read = mesh::read(input, kind, &name, &mut out);
        let placed = placed.placed;
        read.map_err(cannot_read)?;
        if placed == 0 {
            self.warn(
                tok,
                &format!("mesh '{}' has no triangles", escape(rel.as_bytes())),
            );
        }
        Ok(())
    }

    /// `d level`: includes of a higher detail level are skipped from here on.
    pub(super) fn detail_level(&mut self) -> Result<()> {
        let (level, _) = self.lx.count("detail level")?;
        self.blocks.detail = level;
        Ok(())
    }

    /// `i level file`: another AFF (or NFF) file read here, inside the open blocks, with
    /// the current material; skipped when its level is above the detail level (`d`).
    pub(super) fn include(&mut self, _tok: &Token) -> Result<()> {
        let (level, _) = self.lx.count("include detail level")?;
        let ptok = self.lx.expect_token("included file name")?;
        if level > self.blocks.detail {
            return Ok(());
        }
        let raw = String::from_utf8_lossy(self.lx.text(&ptok)).into_owned();
        let path = self.base.join(raw.trim_matches('"'));
        if self.blocks.depth >= MAX_INCLUDE_DEPTH {
            return Err(self.lx.error_at(
                &ptok,
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)"),
            ));
        }
        let input = io::open(&path).map_err(|e| {
            self.lx.error_at(
                &ptok,
                format!(
                    "cannot read included file '{}': {}",
                    escape(path.as_os_str().as_encoded_bytes()),
                    match e {
                        Error::Io { source, .. } => source.to_string(),
                        other => other.to_string(),
                    }
                ),
            )
        })?;
        let name = path.display().to_string();
        let dir = path.parent().unwrap_or(Path::new("."));
        let blank = || Scene::new(String::new(), nff_default_camera());
        let mut child = Parser {
            lx: Lexer::through(input, &name, self.window),
            base: dir,
            sink: &mut *self.sink,
            lenient: self.lenient,
            window: self.window,
            scene: std::mem::replace(&mut self.scene, blank()),
            have_view: self.have_view,
            material: self.material,
            palette: std::mem::take(&mut self.palette),
            verts: Vec::new(),
            normals: Vec::new(),
            tris: Vec::new(),
            blocks: std::mem::take(&mut self.blocks),
            depth_floor: 0,
            warned: std::mem::take(&mut self.warned),
        };
        child.blocks.depth += 1;
        child.depth_floor = child.blocks.stack.len();
        let read = child.statements();
        self.scene = child.scene;
        self.have_view = child.have_view;
        self.material = child.material;
        self.palette = child.palette;
        self.blocks = child.blocks;
        self.blocks.depth -= 1;
        self.warned = child.warned;
        read
    }
}
