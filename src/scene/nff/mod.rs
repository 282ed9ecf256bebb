//! The NFF reader: Haines' NFF 3.9 (`v b l f c s p pp`), the IST P3D dialect (`pl`, `aabb`)
//! and gpurt's extensions (`mesh`, `dl`, `al`, `am`, and `aperture`/`focal` in the view).
//! The exact syntax accepted is documented in `docs/scene-format.md`.
//!
//! This module holds the statement loop; beside it are the shapes (`shapes`), the lights
//! (`lights`), the `v` camera block (`view`), the materials with the ranges colours are
//! held to (`material`), the `mesh` include (`include`) and BART's AFF (`aff`,
//! `textured`, `indexed_mesh`, `blocks`).

mod aff;
mod blocks;
mod include;
mod indexed_mesh;
mod keys;
mod keywords;
mod lights;
mod material;
mod shapes;
mod textured;
mod view;

use std::collections::HashSet;
use std::path::Path;

use glam::Vec3;

use crate::scene::lex::{Lexer, Token, parse_f32};
use crate::scene::model::{MaterialId, Scene, nff_default_camera};
use crate::scene::options::ReadOptions;
use crate::scene::palette::Palette;
use crate::scene::sink::{Collect, Sink};
use crate::util::error::Result;
use crate::util::limits::{MAX_LIGHT, MAX_PRIMITIVES};
use keywords::{STATEMENTS, VIEW_KEYWORDS, closest, nff_word_for};

/// Parses NFF text (gzip-compressed or not). `name` is used in messages; `base` is the
/// directory `mesh` paths are relative to.
pub fn parse(src: &[u8], name: &str, base: &Path) -> Result<Scene> {
    parse_with(src, name, base, &ReadOptions::default())
}

/// `parse` with reading options (`--lenient`).
pub fn parse_with(src: &[u8], name: &str, base: &Path, opts: &ReadOptions) -> Result<Scene> {
    let mut prims = Collect::default();
    let mut scene = read(Lexer::new(src, name), base, &mut prims, opts)?;
    prims.into_scene(&mut scene);
    Ok(scene)
}

/// Reads NFF from `lx`, giving every bounded primitive to `sink` as it is read; returns
/// the rest of the scene (camera, lights, materials, planes, warnings), whose vectors of
/// bounded primitives are empty.
pub fn read(lx: Lexer, base: &Path, sink: &mut dyn Sink, opts: &ReadOptions) -> Result<Scene> {
    let name = lx.name();
    let mut p = Parser {
        lx,
        base,
        sink,
        lenient: opts.lenient,
        window: opts.window,
        scene: Scene::new(name, nff_default_camera()),
        have_view: false,
        material: None,
        palette: Palette::default(),
        verts: Vec::new(),
        normals: Vec::new(),
        tris: Vec::new(),
        blocks: blocks::Blocks::default(),
        depth_floor: 0,
        warned: HashSet::new(),
    };
    p.run()?;
    Ok(p.scene)
}

/// A token's bytes copied out of the lexer when they are short enough to be a keyword
/// (the longest, `resolution`, has 10), so that the statement can read on; empty otherwise.
fn keyword(text: &[u8]) -> ([u8; 16], usize) {
    let mut word = [0; 16];
    if text.len() > word.len() {
        return (word, 0);
    }
    word[..text.len()].copy_from_slice(text);
    (word, text.len())
}

struct Parser<'a> {
    lx: Lexer<'a>,
    base: &'a Path,
    sink: &'a mut dyn Sink,
    /// Unknown keywords are skipped with a warning (`ReadOptions::lenient`).
    lenient: bool,
    /// The window a `mesh` include is read through (`ReadOptions::window`).
    window: Option<usize>,
    scene: Scene,
    have_view: bool,
    /// The current material (`None` until the first `f` or the first primitive).
    material: Option<MaterialId>,
    /// Exact duplicates share one id (SPD repeats `f` lines for every object).
    palette: Palette,
    // Scratch buffers reused by every polygon.
    verts: Vec<Vec3>,
    normals: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
    /// The open transform blocks and the animation being read (AFF).
    blocks: blocks::Blocks,
    /// How many blocks were open when this file began: it closes only its own.
    depth_floor: usize,
    /// Warnings given once per scene, not at every statement they concern.
    warned: HashSet<String>,
}

impl Parser<'_> {
    fn run(&mut self) -> Result<()> {
        self.statements()?;
        if !self.have_view {
            return Err(self.lx.error_here(
                "expected a view ('v' with from/at/up/angle), found none in the file",
            ));
        }
        self.finish_animation()
    }

    /// The statements of one file (the scene's, or one it includes).
    fn statements(&mut self) -> Result<()> {
        let mut first = true;
        while let Some(tok) = self.lx.next_token()? {
            let is_first = std::mem::replace(&mut first, false);
            // BART's AFF also starts a comment with `%` where a statement may start.
            if self.lx.text(&tok).starts_with(b"%") {
                self.lx.skip_line(tok.line)?;
                continue;
            }
            let (word, len) = keyword(self.lx.text(&tok));
            match &word[..len] {
                b"v" => self.view(&tok)?,
                b"b" => {
                    let c = self.lx.vec3("background colour")?;
                    self.scene.background = self.hold3(&tok, "background colour", c, MAX_LIGHT);
                }
                b"l" => self.point_light(&tok)?,
                b"dl" => self.directional_light(&tok)?,
                b"al" => self.area_light(&tok)?,
                b"am" => {
                    let c = self.lx.vec3("ambient colour")?;
                    self.scene.ambient = Some(self.hold3(&tok, "ambient colour", c, MAX_LIGHT));
                }
                b"f" => self.fill(&tok)?,
                b"c" => self.cone(&tok)?,
                b"s" => self.sphere(&tok)?,
                b"p" => self.polygon(&tok, false)?,
                b"pp" => self.polygon(&tok, true)?,
                b"pl" => self.plane(&tok)?,
                b"aabb" => self.aabb(&tok)?,
                b"mesh" => self.mesh(&tok)?,
                // BART's AFF (`aff`).
                b"a" => self.time_range(&tok)?,
                b"k" => self.keyframes(&tok)?,
                b"x" => self.open_moving(&tok)?,
                b"xs" => self.open_fixed(&tok)?,
                b"}" => self.close_block(&tok)?,
                b"la" => self.moving_light(&tok)?,
                b"fm" => self.fill_material(&tok)?,
                b"tt" => self.textured_triangle(&tok, false)?,
                b"ttp" | b"tpp" => self.textured_triangle(&tok, true)?,
                b"tpa" => self.animated_triangle(&tok)?,
                b"m" => self.indexed_mesh(&tok)?,
                b"i" => self.include(&tok)?,
                b"d" => self.detail_level()?,
                b"nff" if is_first => {
                    return Err(self.lx.error_at(
                        &tok,
                        "this is a Sense8 NFF file (starts with 'nff'), not Haines' NFF",
                    ));
                }
                _ if parse_f32(self.lx.text(&tok)).is_some() => {
                    // Usually a light in the `l x y z intensity r g b` variant, or a count
                    // that is smaller than the numbers that follow it.
                    return Err(self.lx.error_at(
                        &tok,
                        format!(
                            "expected an entity keyword, found the number {} (too many numbers for the entity before it?)",
                            self.lx.show(&tok)
                        ),
                    ));
                }
                _ if self.lenient => self.skip_unknown(&tok)?,
                _ => {
                    let text = self.lx.text(&tok);
                    let meant = closest(text, &STATEMENTS)
                        .or_else(|| closest(text, &VIEW_KEYWORDS).map(|_| "v"));
                    let hint = match (nff_word_for(text), meant) {
                        (Some(k), _) => format!(
                            "; NFF's statement for that is '{k}' (--lenient skips the \
                             statements gpurt does not read)"
                        ),
                        (None, Some("v")) => "; a view keyword belongs in a 'v' block".to_string(),
                        (None, Some(k)) => format!("; did you mean '{k}'?"),
                        (None, None) => String::new(),
                    };
                    return Err(self.lx.error_at(
                        &tok,
                        format!(
                            "expected an entity keyword, found {}{hint}",
                            self.lx.show(&tok)
                        ),
                    ));
                }
            }
        }
        self.check_closed()
    }

    fn warn(&mut self, tok: &Token, msg: &str) {
        let w = format!("{}:{}:{}: {msg}", self.lx.name(), tok.line, tok.col);
        self.scene.warnings.push(w);
    }

    /// `warn`, the first time only: for what applies to every statement of a kind.
    fn warn_once(&mut self, tok: &Token, msg: &str) {
        if self.warned.insert(msg.to_string()) {
            self.warn(tok, msg);
        }
    }

    /// `--lenient`: an unknown keyword and what follows it up to the next keyword are
    /// skipped, with a warning naming it. The next keyword is one gpurt knows, or a word
    /// that starts a line (another foreign statement: `obj teapot.obj` takes a word).
    fn skip_unknown(&mut self, tok: &Token) -> Result<()> {
        let msg = format!(
            "unknown keyword {} skipped, with what follows it up to the next keyword",
            self.lx.show(tok)
        );
        self.warn(tok, &msg);
        let mut line = tok.line;
        while let Some(t) = self.lx.peek()? {
            let text = self.lx.text(&t);
            let known = STATEMENTS.iter().any(|k| k.as_bytes() == text);
            if known || (t.line != line && parse_f32(text).is_none()) {
                break;
            }
            line = t.line;
            self.lx.next_token()?;
        }
        Ok(())
    }

    /// Refuses a count read at `tok` outside `1..=max`, naming what it counts (`noun`).
    fn within(&self, (n, tok): (u32, Token), noun: &str, max: u32) -> Result<()> {
        if n == 0 || n > max {
            return Err(self.lx.error_at(
                &tok,
                format!("expected {noun} between 1 and {max}, found {n}"),
            ));
        }
        Ok(())
    }

    /// Refuses a statement that would take the scene past `MAX_PRIMITIVES`.
    fn room(&self, tok: &Token, more: usize) -> Result<()> {
        if self.sink.count() + self.blocks.moving() + more > MAX_PRIMITIVES {
            return Err(self.lx.error_at(
                tok,
                format!("the scene has more than {MAX_PRIMITIVES} bounded primitives (the limit)"),
            ));
        }
        Ok(())
    }
}
