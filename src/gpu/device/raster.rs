//! The viewer's raster work on the device (`view/`, and `--overlay`'s image): the
//! wireframe's line pipeline and its frame uniform, images written into textures and
//! copied out, and a window's frame shown.

use super::{Device, Gpu};

impl Device<'_> {
    /// A pipeline that draws line lists of `Float32x3` vertices with WGSL `source`
    /// (entry points `vs_main` and `fs_main`) into targets of `format`, and its bind group:
    /// `uniform`, seen by both stages, at binding 0 of group 0.
    pub(crate) fn line_pipeline(
        &self,
        label: &str,
        source: &str,
        format: wgpu::TextureFormat,
        uniform: &wgpu::Buffer,
    ) -> (wgpu::RenderPipeline, wgpu::BindGroup) {
        let device = self.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: size_of::<[f32; 3]>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                })],
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::LineList,
                ..Default::default()
            },
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        (pipeline, bind_group)
    }

    /// A uniform buffer of `size` bytes that the host writes (`Gpu::write`).
    pub(crate) fn uniform(&self, label: &str, size: u64) -> wgpu::Buffer {
        use wgpu::BufferUsages as U;
        self.buffer(label, size, U::UNIFORM | U::COPY_DST)
    }

    /// An image of `width` x `height` texels of `format` to draw into, which the host
    /// writes (`Gpu::write_image`) and copies out.
    pub(crate) fn image_texture(
        &self,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
    ) -> wgpu::Texture {
        use wgpu::TextureUsages as U;
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: U::RENDER_ATTACHMENT | U::COPY_SRC | U::COPY_DST,
            view_formats: &[],
        })
    }
}

impl Gpu<'_> {
    /// Writes `texels` (4 bytes a texel, rows of the texture's width, no padding) into the
    /// whole of `texture`, in queue order.
    pub(crate) fn write_image(&self, texture: &wgpu::Texture, texels: &[u8]) {
        self.queue.write_texture(
            texture.as_image_copy(),
            texels,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * texture.width()),
                rows_per_image: Some(texture.height()),
            },
            texture.size(),
        );
    }

    /// Shows a window's frame, drawn by the work submitted before.
    pub(crate) fn show(&self, frame: wgpu::SurfaceTexture) {
        self.queue.present(frame);
    }
}
