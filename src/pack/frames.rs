//! The frames of a scene that moves, packed one after another (`commands::sequence`,
//! the viewer's playback). The still part's records and tree are made once; each frame
//! places the moving part, refits its last tree to the new places where the same
//! primitives are shown and the refit has not worn the tree (`bvh::refit::cost`), else
//! builds it anew, and joins the two trees under one root. BART's kitchen moves 7k of its
//! 110k triangles: rebuilding all of them each frame took as long as a third of the trace.
//!
//! A frame's image does not depend on which tree it got: every walk finds the nearest hit
//! whatever the tree, and the emitters are listed from the records before the moving
//! part is put in its tree's order.

use crate::bvh::refit::{cost, join, refit};
use crate::bvh::{self, FlatBvh, Quality};
use crate::gpu_types::{GpuPrim, GpuTriNormals, GpuTriUvs, PRIM_TRIANGLE, TRAVERSAL_STACK};
use crate::scene::animation::Animation;
use crate::scene::flat::{self, Flat, FlatScene};
use crate::scene::{Bounds, Sink};
use crate::util::error::{Error, Result};

use super::build::{build_tree, permute};
use super::{
    Packed, SceneBuffers, Textures, assemble, check_surfaces, emitters, pack_flat, pack_textures,
};

/// How each frame's tree is made (`GPURT_FRAME_TREE`; `Auto` where unset).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeMode {
    /// The whole scene's tree built anew each frame, as a still scene's is.
    Whole,
    /// The still part's tree kept; the moving part's built anew each frame.
    Rebuild,
    /// The still part's tree kept; the moving part's refitted whenever the same
    /// primitives are shown, however worn.
    Refit,
    /// As `Refit` while the refitted tree costs at most `WORN_LIMIT` times what it did
    /// when built, else as `Rebuild`.
    Auto,
}

impl TreeMode {
    pub fn from_env() -> std::result::Result<TreeMode, String> {
        match std::env::var("GPURT_FRAME_TREE").as_deref() {
            Err(_) | Ok("") | Ok("auto") => Ok(TreeMode::Auto),
            Ok("whole") => Ok(TreeMode::Whole),
            Ok("rebuild") => Ok(TreeMode::Rebuild),
            Ok("refit") => Ok(TreeMode::Refit),
            Ok(v) => Err(format!(
                "GPURT_FRAME_TREE={v}: expected auto, refit, rebuild or whole"
            )),
        }
    }
}

/// How far a refit may wear the moving part's tree, as its cost (`bvh::refit::cost`)
/// over its cost when built, before it is built anew. Cautious: BART's robots refitted
/// for 200 frames wore to 1.72 and traced no slower than trees built each frame
/// (docs/farm.md), but a refit that scatters leaves costs rays without bound.
pub const WORN_LIMIT: f64 = 1.3;

/// How one frame's tree was made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrameTree {
    /// Built over the whole scene (`TreeMode::Whole`, or a joined tree too deep for the
    /// walks' stack).
    Whole,
    /// The moving part's built anew (or nothing moves into view).
    Rebuilt,
    /// The moving part's last tree refitted, worn to this cost over its built cost.
    Refitted(f64),
}

/// The still part, packed once: its records in its tree's leaf order, triangles still by
/// their corners, texture-coordinate slots counted from its own normals.
struct Still {
    records: Vec<GpuPrim>,
    normals: Vec<GpuTriNormals>,
    uvs: Vec<GpuTriUvs>,
    tree: FlatBvh,
    bounds: Bounds,
    quality: Quality,
}

/// The moving part's tree as last built or refitted, `order` kept (each frame places the
/// moving records in the model's order), with what it was built over.
struct Moving {
    tree: FlatBvh,
    shown: Vec<bool>,
    built_cost: f64,
    quality: Quality,
}

/// Packs the frames of one animated scene.
pub struct FramePacker {
    /// The scene without its bounded primitives and textures (`Whole`: with them).
    still_scene: FlatScene,
    /// The scene's textures, packed once (`Whole`: each frame).
    textures: Textures,
    /// `None` under `TreeMode::Whole`.
    still: Option<Still>,
    moving: Option<Moving>,
    animation: Animation,
    move_camera: bool,
    /// Camera samples a frame traces (`bvh::Quality::chosen`).
    samples: u64,
    mode: TreeMode,
}

impl FramePacker {
    /// The frames of `animation` over `still`, each tracing `samples` camera samples, of
    /// which about `frames` are expected (the still part's tree is built for all of
    /// them); the camera moves with the animation where `move_camera`.
    pub fn new(
        still: FlatScene,
        animation: Animation,
        move_camera: bool,
        samples: u64,
        frames: u64,
        mode: TreeMode,
    ) -> Result<FramePacker> {
        let (still_scene, still, textures) = if mode == TreeMode::Whole {
            (still, None, Textures::default())
        } else {
            let FlatScene { mut scene, prims } = still;
            let textures = pack_textures(&std::mem::take(&mut scene.textures)).map_err(|msg| {
                Error::Scene {
                    file: scene.name.clone(),
                    msg,
                }
            })?;
            let bounds = prims.bounds();
            let (mut records, normals, uvs) = prims.into_records();
            let quality = Quality::chosen(records.len(), samples.saturating_mul(frames))
                .map_err(Error::Render)?;
            let mut tree = build_tree(&records, quality, None);
            permute(&mut records, std::mem::take(&mut tree.order));
            let still = Still {
                records,
                normals,
                uvs,
                tree,
                bounds,
                quality,
            };
            let scene = FlatScene {
                scene,
                prims: Flat::new(),
            };
            (scene, Some(still), textures)
        };
        Ok(FramePacker {
            still_scene,
            textures,
            still,
            moving: None,
            animation,
            move_camera,
            samples,
            mode,
        })
    }

    /// What moves.
    pub fn animation(&self) -> &Animation {
        &self.animation
    }

    /// The scene at time `t`, packed, and how its tree was made.
    pub fn pack(&mut self, t: f64) -> Result<(SceneBuffers, FrameTree)> {
        let Some(still) = &self.still else {
            let flat = self
                .animation
                .flat_at(&self.still_scene, t, self.move_camera);
            return Ok((pack_flat(flat, self.samples)?, FrameTree::Whole));
        };
        let mut scene = self.still_scene.scene.clone();
        let mut moving = Flat::new();
        let shown = self.animation.place(&mut moving, &mut scene, t);
        if self.move_camera {
            scene.camera = self.animation.camera_at(&scene.camera, t);
        }
        check_surfaces(
            &scene,
            still.normals.len() + moving.normals(),
            still.uvs.len() + moving.uvs(),
        )?;
        let bounds = still.bounds.union(moving.bounds());
        let (mut records, normals, uvs) = join_records(still, moving);
        // Listed before the moving part is put in its tree's order, so that the emitters'
        // order (which their samples follow) does not depend on the tree.
        let emitters = emitters::emitters(&records, &scene.materials);
        let n_still = still.records.len();
        let mut how = self.moving_tree(&mut records[n_still..], shown)?;
        let still = self.still.as_ref().expect("checked above");
        let empty = FlatBvh::default();
        let moved = self.moving.as_ref().map_or(&empty, |m| &m.tree);
        let mut tree = join(&still.tree, n_still as u32, moved);
        // The build of the larger part, for `--stats`.
        let mut quality = match &self.moving {
            Some(m) if moved.order.len() > n_still => m.quality,
            _ => still.quality,
        };
        // Each part fits the walks' stack, but one more level may not: then the whole.
        if tree.depth >= TRAVERSAL_STACK {
            quality = Quality::chosen(records.len(), self.samples).map_err(Error::Render)?;
            tree = build_tree(&records, quality, None);
            permute(&mut records, std::mem::take(&mut tree.order));
            how = FrameTree::Whole;
        }
        let packed = Packed {
            records,
            tri_normals: normals,
            tri_uvs: uvs,
            emitters,
            tree,
            quality,
            bounds,
            textures: Some(self.textures.clone()),
            copies: 0,
        };
        Ok((assemble(scene, packed)?, how))
    }

    /// Puts the moving `records` (in the model's order) in their tree's leaf order, the
    /// last frame's tree refitted where it may be, else one built anew.
    fn moving_tree(&mut self, records: &mut [GpuPrim], shown: Vec<bool>) -> Result<FrameTree> {
        let bounds = |r: &GpuPrim| bvh::aabb(flat::record_bounds(r));
        let same = self
            .moving
            .as_ref()
            .is_some_and(|m| m.shown == shown && m.tree.order.len() == records.len());
        if same && self.mode != TreeMode::Rebuild {
            let m = self.moving.as_mut().expect("checked above");
            let order = &m.tree.order;
            refit(&mut m.tree.nodes, |k| bounds(&records[order[k] as usize]));
            let worn = match (cost(&m.tree.nodes), m.built_cost) {
                (c, b) if b > 0.0 => c / b,
                (c, _) if c > 0.0 => f64::INFINITY,
                _ => 1.0,
            };
            if self.mode == TreeMode::Refit || worn <= WORN_LIMIT {
                permute(records, m.tree.order.clone());
                return Ok(FrameTree::Refitted(worn));
            }
        }
        self.moving = None;
        if records.is_empty() {
            return Ok(FrameTree::Rebuilt);
        }
        let quality = Quality::chosen(records.len(), self.samples).map_err(Error::Render)?;
        let tree = build_tree(records, quality, None);
        permute(records, tree.order.clone());
        self.moving = Some(Moving {
            built_cost: cost(&tree.nodes),
            tree,
            shown,
            quality,
        });
        Ok(FrameTree::Rebuilt)
    }
}

/// The still part's records then the moving part's (in the model's order), with their
/// normals and texture coordinates one after the other: each record's slots moved to
/// where its normals and coordinates now are (the shader reads every normal, then every
/// coordinate, from one array: `SceneBuffers::surface_texels`).
fn join_records(still: &Still, moving: Flat) -> (Vec<GpuPrim>, Vec<GpuTriNormals>, Vec<GpuTriUvs>) {
    let (moved, moved_normals, moved_uvs) = moving.into_records();
    let (n_still, u_still) = (still.normals.len() as f32, still.uvs.len() as f32);
    let n_moved = moved_normals.len() as f32;
    // Slots, as `Flat::into_records` numbers them: a normal's from 0, a coordinate's
    // from the part's own count of normals; -1 for none.
    let shift = |p: &GpuPrim, normal: f32, uv: f32| {
        let mut p = *p;
        if p.kind() == PRIM_TRIANGLE {
            if p.f1 >= 0.0 {
                p.f1 += normal;
            }
            if p.f0 >= 0.0 {
                p.f0 += uv;
            }
        }
        p
    };
    let mut records = Vec::with_capacity(still.records.len() + moved.len());
    records.extend(still.records.iter().map(|p| shift(p, 0.0, n_moved)));
    records.extend(moved.iter().map(|p| shift(p, n_still, n_still + u_still)));
    let mut normals = still.normals.clone();
    normals.extend(moved_normals);
    let mut uvs = still.uvs.clone();
    uvs.extend(moved_uvs);
    (records, normals, uvs)
}
