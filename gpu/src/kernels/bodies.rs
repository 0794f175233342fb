//! Body exchange on the device (`bodies.wgsl`): `place` (markers from body states) and `wrench`
//! (per-body force and torque). CPU twins: `BodyState::point`, `SphSolver::body_wrenches`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Bodies {
    pub layout: wgpu::BindGroupLayout,
    pub place: wgpu::ComputePipeline,
    pub wrench: wgpu::ComputePipeline,
}

impl Bodies {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout =
            layout(device, "bodies", &[(0, Uniform), (1, Read), (2, Read), (3, ReadWrite), (4, Read), (5, ReadWrite)]);
        let src = source(e, &Variant::default(), include_str!("bodies.wgsl"), false);
        let mut p = pipelines(device, "bodies", &src, &layout, &["place", "wrench"])?.into_iter();
        let (Some(place), Some(wrench)) = (p.next(), p.next()) else {
            return Err(GpuError::Internal("body pipelines"));
        };
        Ok(Self { layout, place, wrench })
    }
}
