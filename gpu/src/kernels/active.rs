//! The active region's per-step check (`active.wgsl`): `cover`. CPU twin:
//! `CpuSph::awake_still_covered`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Cover {
    pub layout: wgpu::BindGroupLayout,
    pub cover: wgpu::ComputePipeline,
}

impl Cover {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(device, "cover", &[(0, Uniform), (1, Read), (2, Read), (3, ReadWrite)]);
        let src = source(e, &Variant::default(), include_str!("active.wgsl"), false);
        let cover = pipelines(device, "cover", &src, &layout, &["cover"])?.pop().ok_or(GpuError::Internal("cover"))?;
        Ok(Self { layout, cover })
    }
}
