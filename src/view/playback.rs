//! An animated scene (AFF) in the viewer: which of its frames is shown, stepping and
//! playing through them, and each frame's scene packed for the renderers. Playing shows
//! each frame as soon as its first pass is traced, then moves to the next, looping.

use crate::pack::SceneBuffers;
use crate::pack::frames::FramePacker;
use crate::scene::animation::TimeRange;
use crate::util::error::Result;

pub struct Playback {
    /// Packs each frame, the still part's tree made once (`pack::frames`).
    packer: FramePacker,
    range: TimeRange,
    frame: u32,
    pub playing: bool,
}

impl Playback {
    /// The frames `packer` packs; `None` where nothing moves or there is no time range
    /// to step through.
    pub fn new(packer: FramePacker) -> Option<Playback> {
        let animation = packer.animation();
        let range = animation.range.filter(|_| !animation.is_still())?;
        Some(Playback {
            packer,
            range,
            frame: 0,
            playing: false,
        })
    }

    pub fn frame(&self) -> u32 {
        self.frame
    }

    pub fn time(&self) -> f64 {
        self.range.time(self.frame)
    }

    /// Moves `by` frames, wrapping around the ends.
    pub fn step(&mut self, by: i64) {
        let n = i64::from(self.range.frames);
        self.frame = (i64::from(self.frame) + by).rem_euclid(n) as u32;
    }

    /// The current frame's scene, packed.
    pub fn buffers(&mut self) -> Result<SceneBuffers> {
        let t = self.time();
        Ok(self.packer.pack(t)?.0)
    }

    /// For the title: `frame 12/48, t 0.511, playing`.
    pub fn describe(&self) -> String {
        format!(
            "frame {}/{}, t {:.3}, {}",
            self.frame,
            self.range.frames,
            self.time(),
            if self.playing { "playing" } else { "paused" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pack::frames::TreeMode;
    use crate::scene::{FlatScene, nff};

    fn orbit() -> Playback {
        let src = "v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 45\na 0 2 5\nx b {\n s 0 0 0 1\n}\n\
                   k b {\n transl 4\n 0 0 0 0 0 0 0\n 1 0 0 0 0 0 0\n 2 2 0 0 0 0 0\n 3 2 0 0 0 0 0\n}\n";
        let mut scene = nff::parse(src.as_bytes(), "t.aff", std::path::Path::new(".")).unwrap();
        let anim = *scene.animation.take().unwrap();
        let still = FlatScene::from_scene(scene);
        let packer = FramePacker::new(still, anim, true, 1, 5, TreeMode::Auto).unwrap();
        Playback::new(packer).unwrap()
    }

    #[test]
    fn steps_wrap_around_and_each_frame_is_placed_at_its_time() {
        let mut p = orbit();
        assert_eq!((p.frame(), p.time()), (0, 0.0));
        p.step(-1);
        assert_eq!((p.frame(), p.time()), (4, 2.0));
        p.step(2);
        assert_eq!((p.frame(), p.time()), (1, 0.5));
        p.step(3);
        let b = p.buffers().unwrap();
        assert_eq!(b.prims.len(), 1);
        assert!(p.describe().starts_with("frame 4/5, t 2.000, paused"));
    }
}
