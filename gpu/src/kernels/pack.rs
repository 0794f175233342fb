//! Neighbour records and moduli (`pack.wgsl`). CPU twin: `rates::pack_soil`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Pack {
    pub layout: wgpu::BindGroupLayout,
    pub pack: wgpu::ComputePipeline,
}

impl Pack {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(
            device,
            "pack",
            &[(0, Uniform), (1, Read), (2, Read), (3, ReadWrite), (4, ReadWrite), (5, ReadWrite)],
        );
        let src = source(e, &Variant::default(), include_str!("pack.wgsl"), false);
        let pack = pipelines(device, "pack", &src, &layout, &["pack"])?.pop().ok_or(GpuError::Internal("pack"))?;
        Ok(Self { layout, pack })
    }
}
