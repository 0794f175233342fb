//! Marker forces (`forces.wgsl`). CPU twin: `rates::marker_forces`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Forces {
    pub layout: wgpu::BindGroupLayout,
    pub marker_forces: wgpu::ComputePipeline,
}

impl Forces {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(
            device,
            "marker_forces",
            &[(0, Uniform), (1, Read), (2, Read), (3, Read), (4, Read), (5, Read), (6, ReadWrite), (7, Read)],
        );
        let src = source(e, &Variant::default(), include_str!("forces.wgsl"), false);
        let marker_forces = pipelines(device, "marker_forces", &src, &layout, &["marker_forces"])?
            .pop()
            .ok_or(GpuError::Internal("marker_forces"))?;
        Ok(Self { layout, marker_forces })
    }
}
