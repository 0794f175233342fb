//! Step bookkeeping (`step_info.wgsl`): `reset`, `maxima`, `choose_dt`. CPU twin:
//! `CpuSph::choose_dt`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct StepInfo {
    pub layout: wgpu::BindGroupLayout,
    pub reset: wgpu::ComputePipeline,
    pub maxima: wgpu::ComputePipeline,
    pub choose_dt: wgpu::ComputePipeline,
}

impl StepInfo {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(device, "step_info", &[(0, Uniform), (1, Read), (2, Read), (3, ReadWrite)]);
        let src = source(e, &Variant::default(), include_str!("step_info.wgsl"), false);
        let mut p = pipelines(device, "step_info", &src, &layout, &["reset", "maxima", "choose_dt"])?.into_iter();
        let (Some(reset), Some(maxima), Some(choose_dt)) = (p.next(), p.next(), p.next()) else {
            return Err(GpuError::Internal("step_info pipelines"));
        };
        Ok(Self { layout, reset, maxima, choose_dt })
    }
}
