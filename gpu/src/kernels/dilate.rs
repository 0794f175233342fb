//! Cell masks grown by a cube (`dilate.wgsl`), one axis per pass: `dilate`.

use crate::GpuError;
use crate::layout::DilateParams;
use crate::shader::{Bind, Effects, Variant, bind, buffer, layout, pipelines, source};

/// One pass of a chain: the axis, the radius in cells, the mask read and the mask written.
pub(crate) type Pass<'a> = (u32, u32, &'a wgpu::Buffer, &'a wgpu::Buffer);

pub(crate) struct Dilate {
    pub layout: wgpu::BindGroupLayout,
    pub dilate: wgpu::ComputePipeline,
}

impl Dilate {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(device, "dilate", &[(0, Uniform), (1, Uniform), (2, Read), (3, ReadWrite)]);
        let src = source(e, &Variant::default(), include_str!("dilate.wgsl"), false);
        let dilate =
            pipelines(device, "dilate", &src, &layout, &["dilate"])?.pop().ok_or(GpuError::Internal("dilate"))?;
        Ok(Self { layout, dilate })
    }

    /// Bind groups for `passes` in order, each with its own small uniform (`params` is the
    /// solver's `Params`, for the grid's dimensions).
    pub fn chain(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &wgpu::Buffer,
        passes: &[Pass<'_>],
    ) -> Vec<wgpu::BindGroup> {
        passes
            .iter()
            .map(|&(axis, radius, src, dst)| {
                let usage = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
                let u = buffer(device, "dilate.params", size_of::<DilateParams>() as u64, usage);
                queue.write_buffer(&u, 0, bytemuck::bytes_of(&DilateParams { axis, radius, pad: [0; 2] }));
                bind(device, "dilate", &self.layout, &[(0, params), (1, &u), (2, src), (3, dst)])
            })
            .collect()
    }
}
