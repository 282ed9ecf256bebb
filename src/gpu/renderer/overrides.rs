//! The renderer's settings chosen in code rather than by its adapter and the
//! environment: for the tests, which check on lavapipe what another adapter would do
//! (layers, dispatch budgets, a GPU's cut, every walk and both kinds of kernels), and for
//! the out-of-memory fault.

use std::time::Duration;

use super::GpuRenderer;
use crate::gpu::cut::Shape;
use crate::gpu::policy::gpu_shape;
use crate::gpu_types::{POOL_MAX_SIDE, WORKGROUP_SIDE};

impl GpuRenderer {
    /// This renderer splitting the node and primitive textures into layers of `rows`
    /// rows (a power of two, at most the device's), as a scene too large for one layer
    /// is split: lets the tests check many layers on small scenes.
    pub fn with_layer_rows(self, rows: u32) -> Self {
        assert!(rows.is_power_of_two() && rows <= self.layer_rows);
        GpuRenderer {
            layer_rows: rows,
            ..self
        }
    }

    /// This renderer allocating each texture (or buffer, `Fetch::Buffers`) of a scene's
    /// nodes, primitives and normals with the process's address space capped `margin`
    /// bytes above its size (the out-of-memory fault, `fault.rs`): on a software adapter,
    /// whose device memory is the process's own, one larger than that cannot be
    /// allocated. Only the allocations run capped, not the copies into
    /// them, which lavapipe compiles code for.
    pub fn with_texture_margin(self, margin: u64) -> Self {
        GpuRenderer {
            texture_margin: Some(margin),
            ..self
        }
    }

    /// This renderer holding each dispatch to `budget` (instead of `DISPATCH_BUDGET` on
    /// GPUs and none on software adapters): lets the tests make lavapipe refine its cut.
    pub fn with_dispatch_budget(self, budget: Duration) -> Self {
        GpuRenderer {
            dispatch_budget: Some(budget),
            ..self
        }
    }

    /// This renderer cutting frames as on a GPU (`policy::gpu_shape`: strips of the
    /// frame's width, several samples a pass), with dispatches of at most
    /// `dispatch_samples` pixel samples, whatever its adapter: lets the tests trace
    /// frames in several strips on lavapipe.
    pub fn with_gpu_shape(self, dispatch_samples: u64) -> Self {
        GpuRenderer {
            shape: Shape {
                dispatch_samples,
                ..gpu_shape()
            },
            ..self
        }
    }

    /// This renderer walking the BVH as `traversal` says, whatever its adapter.
    pub fn with_traversal(self, traversal: u32) -> Self {
        GpuRenderer { traversal, ..self }
    }

    /// This renderer tracing colour frames through the wavefront kernels (`true`) where
    /// a frame can take them (`policy::wavefront_for`), or the one kernel (`false`),
    /// whatever its adapter.
    pub fn with_wavefront(self, wavefront: bool) -> Self {
        GpuRenderer { wavefront, ..self }
    }

    /// This renderer's one kernel tracing colour frames through its `pooled` entry point
    /// (`policy::pooled_for`), or through `main`.
    pub fn with_pooled(self, pooled: bool) -> Self {
        GpuRenderer { pooled, ..self }
    }

    /// This renderer tracing shadow rays (`true`, as every renderer does) or none, every
    /// light reaching every surface that faces it (`false`): `gpurt bench` times the
    /// shading of a frame's hits apart from their shadow rays so. Colour frames then take
    /// the one kernel.
    pub fn with_shadow_rays(self, shadow_rays: bool) -> Self {
        GpuRenderer {
            shadow_rays,
            ..self
        }
    }

    /// This renderer's `pooled` workgroups each tracing a square of `side` pixels a side,
    /// a multiple of `WORKGROUP_SIDE` up to `POOL_MAX_SIDE` (`GPURT_POOL_SIDE`).
    pub fn with_pool_side(self, side: u32) -> Self {
        assert!(side.is_multiple_of(WORKGROUP_SIDE) && (1..=POOL_MAX_SIDE).contains(&side));
        GpuRenderer {
            shape: Shape {
                pool_side: side,
                ..self.shape
            },
            ..self
        }
    }
}
