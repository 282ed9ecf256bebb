//! The transform blocks of an AFF scene as the reader goes through them (`Blocks`), and
//! where they send what is read (`Route`): outside any block, into the sink; in blocks
//! with fixed transforms only, placed into the sink; under an animated transform, into
//! that block's group of the animation, in the block's own coordinates, to be placed at
//! each frame's time.

use glam::{DAffine3, Vec2, Vec3};

use crate::scene::bounds::Bounds;
use crate::scene::lex::Token;
use crate::scene::model::{
    BoxPrim, Cone, Group, MaterialId, MovingLight, Sphere, TimeRange, Track,
};
use crate::scene::place::{Placed, Placement};
use crate::scene::sink::Sink;

/// Where what is read goes, from the innermost open block.
#[derive(Clone, Copy)]
pub(super) enum Target {
    /// Placed by the blocks' fixed transforms, composed.
    Fixed(DAffine3, Placement),
    /// Into a group of the animation.
    Group(usize),
}

pub(super) struct Open {
    /// The block's statement (`x` or `xs`), for the message if it is never closed.
    pub(super) tok: Token,
    pub(super) target: Target,
}

/// A transform name, and where it was first used, for the message if it has no keys.
pub(super) struct Name {
    pub(super) name: String,
    pub(super) track: Option<Track>,
    pub(super) used: Option<(String, u32, u32)>,
}

/// The open blocks and the animation being read.
#[derive(Default)]
pub(super) struct Blocks {
    pub(super) stack: Vec<Open>,
    pub(super) names: Vec<Name>,
    pub(super) groups: Vec<Group>,
    pub(super) lights: Vec<MovingLight>,
    pub(super) range: Option<TimeRange>,
    /// Primitives in groups so far (counted against the limit with the sink's).
    pub(super) moving: usize,
    /// The detail level includes are read up to (`d`).
    pub(super) detail: u32,
    /// How deep the file being read is included.
    pub(super) depth: u32,
}

impl Blocks {
    /// Primitives read into groups so far.
    pub(super) fn moving(&self) -> usize {
        self.moving
    }

    pub(super) fn target(&self) -> Option<Target> {
        self.stack.last().map(|o| o.target)
    }

    /// The index of transform `name`, recording its first use at `used` when given.
    pub(super) fn name(&mut self, name: &str, used: Option<(String, u32, u32)>) -> usize {
        let i = match self.names.iter().position(|n| n.name == name) {
            Some(i) => i,
            None => {
                self.names.push(Name {
                    name: name.to_string(),
                    track: None,
                    used: None,
                });
                self.names.len() - 1
            }
        };
        if self.names[i].used.is_none() {
            self.names[i].used = used;
        }
        i
    }
}

/// The sink the parser's primitives go to, through the open blocks.
pub(super) struct Route<'x> {
    sink: &'x mut dyn Sink,
    blocks: &'x mut Blocks,
}

impl<'x> Route<'x> {
    pub(super) fn new(sink: &'x mut dyn Sink, blocks: &'x mut Blocks) -> Self {
        Route { sink, blocks }
    }

    fn out(&mut self) -> Placed<'_> {
        match self.blocks.target() {
            None => Placed::new(self.sink, None),
            Some(Target::Fixed(_, p)) => Placed::new(self.sink, Some(p)),
            Some(Target::Group(g)) => {
                self.blocks.moving += 1;
                Placed::new(&mut self.blocks.groups[g].prims, None)
            }
        }
    }
}

impl Sink for Route<'_> {
    fn sphere(&mut self, s: Sphere) {
        self.out().sphere(s);
    }
    fn triangle(
        &mut self,
        v: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: Option<[Vec2; 3]>,
        material: MaterialId,
    ) {
        self.out().triangle(v, n, uv, material);
    }
    fn cone(&mut self, c: Cone) {
        self.out().cone(c);
    }
    fn cuboid(&mut self, b: BoxPrim) {
        self.out().cuboid(b);
    }
    fn count(&self) -> usize {
        self.sink.count() + self.blocks.moving
    }
    fn bounds(&self) -> Bounds {
        self.sink.bounds()
    }
}
