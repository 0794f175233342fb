//! The active region's classification on the device: `roles` and `mark` (`classify.wgsl`),
//! `dilate` (`dilate.wgsl`), `place` and `tally` (`partition.wgsl`); the scan between them is
//! [`super::scan::Scan`]. CPU twin: `regolith_fsi::cpu::ActiveRegion::classify`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Classify {
    pub roles_layout: wgpu::BindGroupLayout,
    pub roles: wgpu::ComputePipeline,
    pub mark: wgpu::ComputePipeline,
    pub dilate_layout: wgpu::BindGroupLayout,
    pub dilate: wgpu::ComputePipeline,
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
        let dilate_layout = layout(device, "dilate", &[(0, Uniform), (1, Uniform), (2, Read), (3, ReadWrite)]);
        let src = source(e, &v, include_str!("dilate.wgsl"), false);
        let dilate = pipelines(device, "dilate", &src, &dilate_layout, &["dilate"])?
            .pop()
            .ok_or(GpuError::Internal("dilate pipeline"))?;
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
        Ok(Self { roles_layout, roles, mark, dilate_layout, dilate, partition_layout, place, tally })
    }
}
