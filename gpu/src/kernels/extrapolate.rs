//! Boundary-marker extrapolation (`extrapolate.wgsl`). CPU twin: `rates::extrapolate_markers`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Extrapolate {
    pub layout: wgpu::BindGroupLayout,
    pub extrapolate: wgpu::ComputePipeline,
}

impl Extrapolate {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(
            device,
            "extrapolate",
            &[(0, Uniform), (1, Read), (2, Read), (3, Read), (4, Read), (5, Read), (6, ReadWrite), (7, Read)],
        );
        let src = source(e, &Variant::default(), include_str!("extrapolate.wgsl"), false);
        let extrapolate = pipelines(device, "extrapolate", &src, &layout, &["extrapolate"])?
            .pop()
            .ok_or(GpuError::Internal("extrapolate"))?;
        Ok(Self { layout, extrapolate })
    }
}
