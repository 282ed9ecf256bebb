//! Scenes that move: what BART's Animated File Format (AFF) adds to NFF, read by the NFF
//! reader (`nff::aff`) and placed here at a frame's time.
//!
//! An AFF scene is a still part, read into the scene as any NFF scene is, and groups
//! that move: the contents of every block with an animated transform (`x name { }`) in
//! it, kept in their own coordinates with the chain of transforms above them, and placed
//! at each frame's time (`Animation::place`). Keyframes (`k name { }`) give a named
//! transform its translation, rotation and scale (T * R * S) on splines (`spline`), and
//! its visibility; `k camera` moves the camera, `la name` a light. The data are the
//! model's (`model::Animation`); what places them at a time is here.

use glam::{DAffine3, DVec3};

use super::flat::FlatScene;
pub use super::model::{Animation, Group, Link, MovingLight, TimeRange, Track};
use super::model::{Camera, Scene};
use super::place::{Placed, Placement};
use super::sink::{Collect, Sink};

impl Animation {
    /// Whether nothing moves (a scene with an `a` statement and no animated block).
    pub fn is_still(&self) -> bool {
        self.groups.is_empty() && self.lights.is_empty() && self.camera.is_none()
    }

    /// The time a still image of the scene shows when none is asked for: the start of
    /// its range, else 0.
    pub fn default_time(&self) -> f64 {
        self.range.map_or(0.0, |r| r.start)
    }

    /// The primitives that move, in their place at time `t`, into `prims`, and the planes
    /// and lights they hold into `scene`; what is hidden at `t` is left out. The camera
    /// is `camera_at`'s. Returns which groups were placed (the same ones in two frames
    /// place the same primitives in the same order, which a refit relies on).
    pub fn place(&self, prims: &mut dyn Sink, scene: &mut Scene, t: f64) -> Vec<bool> {
        let mut shown = Vec::with_capacity(self.groups.len());
        for g in &self.groups {
            let p = self.chain(&g.chain, t).and_then(Placement::new);
            shown.push(p.is_some());
            let Some(p) = p else {
                continue;
            };
            g.prims.emit(&mut Placed::new(prims, Some(p)));
            scene
                .planes
                .extend(g.planes.iter().filter_map(|pl| p.plane(*pl)));
            scene.lights.extend(g.lights.iter().map(|l| p.light(*l)));
        }
        for l in &self.lights {
            let track = &self.tracks[l.track];
            if let Some(p) = Placement::new(track.transform(t)).filter(|_| track.visible(t)) {
                scene.lights.push(p.light(l.light));
            }
        }
        shown
    }

    /// `still` (a scene's still part, as read) with what moves placed at time `t`, and
    /// its camera moved where `move_camera` (else the camera stays: one given apart).
    pub fn flat_at(&self, still: &FlatScene, t: f64, move_camera: bool) -> FlatScene {
        let mut flat = still.clone();
        self.place(&mut flat.prims, &mut flat.scene, t);
        if move_camera {
            flat.scene.camera = self.camera_at(&flat.scene.camera, t);
        }
        flat
    }

    /// The transform a chain makes at time `t`; `None` while a track of it is hidden.
    fn chain(&self, chain: &[Link], t: f64) -> Option<DAffine3> {
        chain
            .iter()
            .try_fold(DAffine3::IDENTITY, |m, link| match *link {
                Link::Fixed(a) => Some(m * a),
                Link::Moving(i) => {
                    let track = &self.tracks[i];
                    track.visible(t).then(|| m * track.transform(t))
                }
            })
    }

    /// `camera` moved by the `camera` track at time `t`, as BART's previewer moves it: the
    /// eye to the track's translation, and where the track turns, the view along its
    /// local -z with its local y up (at the view's distance); where it does not turn,
    /// the view keeps its direction.
    pub fn camera_at(&self, camera: &Camera, t: f64) -> Camera {
        let mut c = camera.clone();
        let Some(track) = self.camera.map(|i| &self.tracks[i]) else {
            return c;
        };
        let look = camera.at - camera.from;
        if let Some(s) = &track.translation {
            c.from = s.at(t).as_vec3();
        }
        c.at = c.from + look;
        if let Some(r) = &track.rotation {
            let q = r.at(t);
            let dir = (q * DVec3::NEG_Z).as_vec3();
            c.at = c.from + dir * look.length();
            c.up = (q * DVec3::Y).as_vec3();
        }
        c
    }
}

impl Scene {
    /// The scene at time `t`: what moves placed as still primitives, the camera moved; a
    /// still scene as it is.
    pub fn at(mut self, t: f64) -> Scene {
        let Some(anim) = self.animation.take() else {
            return self;
        };
        let mut moved = Collect::default();
        anim.place(&mut moved, &mut self, t);
        moved.append_to(&mut self);
        self.camera = anim.camera_at(&self.camera, t);
        self
    }
}
