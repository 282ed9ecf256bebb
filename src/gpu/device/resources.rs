//! Buffers and textures, of the kinds the renderer uses: storage the shaders read (a
//! scene's arrays), a frame's constants and its uniform records, outputs and the buffers
//! they are read back through, and the texture arrays that hold a scene's large arrays.

use super::{Device, Gpu};

/// The format of the node, primitive and normal textures: 16 bytes a texel, bound as
/// read-only storage textures (`Texels` in `shaders/types.wgsl`, which says why).
pub(crate) const TEXEL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

impl Device<'_> {
    /// A buffer holding `contents`: `DeviceExt::create_buffer_init` without its panic. On
    /// a lost device wgpu hands back an invalid buffer that cannot be mapped, and its
    /// helper unwraps the mapping; here the copy is skipped, and the error scope around
    /// the call (`scoped`) reports the invalid buffer as an error naming what was being
    /// done.
    pub(crate) fn buffer_from(
        &self,
        label: &str,
        contents: &[u8],
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        let align = wgpu::COPY_BUFFER_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (contents.len() as u64).next_multiple_of(align).max(align),
            usage,
            mapped_at_creation: true,
        });
        // Every caller's contents are whole 4-byte words, as a mapped range must be.
        if let Ok(mut view) = buffer.slice(..contents.len() as u64).get_mapped_range_mut() {
            view.copy_from_slice(contents);
        }
        buffer.unmap();
        buffer
    }

    /// `count` timestamp queries and the buffer they resolve into (to be copied to a
    /// `readback`), where the device has timestamps (`TIMESTAMP_QUERY`; the context asks
    /// for them where the adapter has them); else none.
    pub(crate) fn timestamps(
        &self,
        label: &str,
        count: u32,
    ) -> Option<(wgpu::QuerySet, wgpu::Buffer)> {
        use wgpu::BufferUsages as U;
        if !self
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
        {
            return None;
        }
        let set = self.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some(label),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let resolve = self.buffer(label, 8 * u64::from(count), U::QUERY_RESOLVE | U::COPY_SRC);
        Some((set, resolve))
    }

    pub(super) fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }

    /// Storage the shaders read, holding `contents` (a scene's small arrays, a list of
    /// pixels to resume).
    pub(crate) fn read_only_storage(&self, label: &str, contents: &[u8]) -> wgpu::Buffer {
        self.buffer_from(label, contents, wgpu::BufferUsages::STORAGE)
    }

    /// Storage the shaders read and the host rewrites (`Gpu::write`): a frame's
    /// constants.
    pub(crate) fn constants(&self, label: &str, contents: &[u8]) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        self.buffer_from(label, contents, U::STORAGE | U::COPY_DST)
    }

    /// `count` uniform records of `size` bytes each, at offsets a dynamic offset can
    /// reach (`record_stride`); the host writes them. Returns the buffer and the stride.
    pub(crate) fn uniform_records(
        &self,
        label: &str,
        size: u64,
        count: u32,
    ) -> (wgpu::Buffer, u32) {
        let stride =
            (size as u32).next_multiple_of(self.limits().min_uniform_buffer_offset_alignment);
        let bytes = u64::from(stride) * u64::from(count.max(1));
        use wgpu::BufferUsages as U;
        (self.buffer(label, bytes, U::UNIFORM | U::COPY_DST), stride)
    }

    /// Storage the shaders write, that can be cleared, written by the host and copied to a
    /// `readback`.
    pub(crate) fn output(&self, label: &str, size: u64) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        self.buffer(label, size, U::STORAGE | U::COPY_SRC | U::COPY_DST)
    }

    /// Storage the shaders write the sizes of indirect dispatches into
    /// (`ComputePass::dispatch_workgroups_indirect`).
    pub(crate) fn indirect_args(&self, label: &str, size: u64) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        self.buffer(label, size, U::STORAGE | U::INDIRECT | U::COPY_DST)
    }

    /// Storage the shaders read and the host fills with `Gpu::write` after making it: a
    /// scene's nodes, primitives or normals (`Fetch::Buffers`), written in bands so that
    /// the host never holds a second copy of the whole array.
    pub(crate) fn texel_buffer(&self, label: &str, size: u64) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        self.buffer(label, size, U::STORAGE | U::COPY_DST)
    }

    /// A buffer an `output` is copied into, to be `read` by the host.
    pub(crate) fn readback(&self, label: &str, size: u64) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        self.buffer(label, size, U::MAP_READ | U::COPY_DST)
    }

    /// A texture array of `TEXEL_FORMAT` texels, `width` by `height` a layer, that the
    /// shaders read and the host fills (`Gpu::write_texel_rows`).
    pub(crate) fn texel_array(
        &self,
        label: &str,
        width: u32,
        height: u32,
        layers: u32,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: TEXEL_FORMAT,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    }
}

impl Gpu<'_> {
    /// Writes `rows` whole rows of a `texel_array`, from row `row` of layer `layer`, in
    /// queue order; `bytes` holds exactly those rows.
    pub(crate) fn write_texel_rows(
        &self,
        texture: &wgpu::Texture,
        layer: u32,
        row: u32,
        rows: u32,
        bytes: &[u8],
    ) {
        let width = texture.width();
        self.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: row,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                // 16 bytes a texel (`TEXEL_FORMAT`).
                bytes_per_row: Some(width * 16),
                rows_per_image: Some(rows),
            },
            wgpu::Extent3d {
                width,
                height: rows,
                depth_or_array_layers: 1,
            },
        );
    }
}
