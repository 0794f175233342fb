//! Integration with the plastic correction (`advance.wgsl` with the rheology modules the
//! scene's materials need: `dp.wgsl`, `mcc.wgsl`). CPU twin: `CpuSph::advance`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Advance {
    pub layout: wgpu::BindGroupLayout,
    /// To the midpoint (RK2 only).
    pub stage: Option<wgpu::ComputePipeline>,
    /// To the end of the step.
    pub finish: wgpu::ComputePipeline,
}

impl Advance {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(
            device,
            "advance",
            &[(0, Uniform), (1, ReadWrite), (2, ReadWrite), (3, Read), (4, Read), (5, ReadWrite)],
        );
        let build = |stage: bool, label: &str| -> Result<wgpu::ComputePipeline, GpuError> {
            let src = source(e, &Variant { stage, ..Default::default() }, include_str!("advance.wgsl"), true);
            pipelines(device, label, &src, &layout, &["advance"])?.pop().ok_or(GpuError::Internal("advance"))
        };
        let stage = if e.rk2 { Some(build(true, "advance[stage]")?) } else { None };
        Ok(Self { finish: build(false, "advance")?, stage, layout })
    }
}
