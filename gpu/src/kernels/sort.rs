//! Counting sort by cell (`sort.wgsl`): `bin`, `scatter`, `order_bins`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Sort {
    pub layout: wgpu::BindGroupLayout,
    pub bin: wgpu::ComputePipeline,
    pub scatter: wgpu::ComputePipeline,
    pub order_bins: wgpu::ComputePipeline,
}

impl Sort {
    /// Pipelines for point records of `stride` words.
    pub fn new(device: &wgpu::Device, e: &Effects, stride: u32, label: &str) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(
            device,
            label,
            &[(0, Uniform), (1, Read), (2, Read), (3, ReadWrite), (4, ReadWrite), (5, Read), (6, ReadWrite)],
        );
        let src = source(e, &Variant { stride, ..Default::default() }, include_str!("sort.wgsl"), false);
        let mut p = pipelines(device, label, &src, &layout, &["bin", "scatter", "order_bins"])?.into_iter();
        let (Some(bin), Some(scatter), Some(order_bins)) = (p.next(), p.next(), p.next()) else {
            return Err(GpuError::Internal("sort pipelines"));
        };
        Ok(Self { layout, bin, scatter, order_bins })
    }
}
