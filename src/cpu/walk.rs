//! CPU twin of `shaders/walk.wgsl`: where a traversal of the BVH stands and its stack,
//! shared by the walks of `traverse` and `cwide`.

use super::types::{Bindings, Ray};
use crate::gpu_types::TRAVERSAL_STACK;

/// Where a traversal stands: the node to visit next and the nodes waiting on its stack;
/// for the compressed walk, the group of inner children still to visit of the node
/// entered last and the primitives of its leaves still to test, the groups above them on
/// the stack, two words each (see traverse.wgsl).
pub(super) struct Walk {
    pub(super) node: u32,
    pub(super) sp: usize,
    pub(super) stack: [u32; TRAVERSAL_STACK],
    /// Entries of the stack ever written, kept or not (`stack_high_water`): what the
    /// shader's slice must hold.
    pub(super) high: usize,
    pub(super) group: (u32, u32),
    pub(super) leaves: (u32, u32),
    /// The ray's octant: bit 2 set when it goes towards -x, bit 1 -y, bit 0 -z.
    pub(super) octant: u32,
    /// Nodes fetched (the shader's private `fetched`).
    pub(super) fetched: u32,
}

/// The walk from the root: for the compressed walk, a group holding the root alone, as an
/// inner child in lane 0.
pub(super) fn start_walk(ray: &Ray) -> Walk {
    let neg = |v: f32| u32::from(v < 0.0);
    let octant = neg(ray.dir.x) << 2 | neg(ray.dir.y) << 1 | neg(ray.dir.z);
    Walk {
        node: 0,
        sp: 0,
        stack: [0; TRAVERSAL_STACK],
        high: 0,
        group: (0, 1 << 8 | 1 << octant),
        leaves: (0, 0),
        octant,
        fetched: 0,
    }
}

impl Walk {
    /// Writes stack entry `k`.
    pub(super) fn stack_store(&mut self, k: usize, entry: u32) {
        self.stack[k] = entry;
        self.high = self.high.max(k + 1);
    }

    /// Takes the next waiting node; false when the traversal is done.
    pub(super) fn pop(&mut self) -> bool {
        if self.sp == 0 {
            return false;
        }
        self.sp -= 1;
        self.node = self.stack[self.sp];
        true
    }

    /// Takes the group of children waiting on the compressed walk's stack; false when
    /// none is.
    pub(super) fn pop_group(&mut self) -> bool {
        if self.sp == 0 {
            return false;
        }
        self.sp -= 1;
        let k = 2 * self.sp;
        self.group = (self.stack[k], self.stack[k + 1]);
        true
    }

    /// Goes on after a leaf's primitives: the next waiting node, or for the compressed
    /// walk, which holds what waits itself, simply on. False when the traversal is done.
    pub(super) fn walk_on(&mut self, b: &Bindings) -> bool {
        if b.gpu_cwide.is_some() {
            return true;
        }
        self.pop()
    }
}
