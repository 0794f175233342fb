//! The active region's classification on the device: `roles` and `mark` (`classify.wgsl`),
//! `place` and `tally` (`partition.wgsl`); the dilations between them are
//! [`super::dilate::Dilate`], the scan [`super::scan::Scan`]. CPU twin: `regolith_fsi::cpu::ActiveRegion::classify`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Classify {
    pub roles_layout: wgpu::BindGroupLayout,
    pub roles: wgpu::ComputePipeline,
    pub mark: wgpu::ComputePipeline,
    pub partition_layout: wgpu::BindGroupLayout,
    pub place: wgpu::ComputePipeline,
    pub tally: wgpu::ComputePipeline,
}

impl Classify {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let v = Variant::default();
        let roles_layout = layout(
            device,
            "classify",
            &[
                (0, Uniform),
                (1, Uniform),
                (2, Read),
                (3, Read),
                (4, ReadWrite),
                (5, ReadWrite),
                (6, ReadWrite),
                (7, Read),
                (8, ReadWrite),
            ],
        );
        let src = source(e, &v, include_str!("classify.wgsl"), false);
        let mut p = pipelines(device, "classify", &src, &roles_layout, &["roles", "mark"])?.into_iter();
        let (Some(roles), Some(mark)) = (p.next(), p.next()) else {
            return Err(GpuError::Internal("classify pipelines"));
        };
        let partition_layout = layout(
            device,
            "partition",
            &[(0, Uniform), (1, Read), (2, Read), (3, Read), (4, ReadWrite), (5, ReadWrite), (6, ReadWrite)],
        );
        let src = source(e, &v, include_str!("partition.wgsl"), false);
        let mut p = pipelines(device, "partition", &src, &partition_layout, &["place", "tally"])?.into_iter();
        let (Some(place), Some(tally)) = (p.next(), p.next()) else {
            return Err(GpuError::Internal("partition pipelines"));
        };
        Ok(Self { roles_layout, roles, mark, partition_layout, place, tally })
    }
}
