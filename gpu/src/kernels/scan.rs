//! Exclusive prefix sum of bin counts (`scan.wgsl`): `scan_blocks`, `scan_sums`, `add_sums`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Scan {
    pub layout: wgpu::BindGroupLayout,
    pub scan_blocks: wgpu::ComputePipeline,
    pub scan_sums: wgpu::ComputePipeline,
    pub add_sums: wgpu::ComputePipeline,
    /// Counts scanned.
    pub len: u32,
}

impl Scan {
    pub fn new(device: &wgpu::Device, e: &Effects, len: u32) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(device, "scan", &[(0, Uniform), (1, Read), (2, ReadWrite), (3, ReadWrite)]);
        let src = source(e, &Variant { len, ..Default::default() }, include_str!("scan.wgsl"), false);
        let mut p = pipelines(device, "scan", &src, &layout, &["scan_blocks", "scan_sums", "add_sums"])?.into_iter();
        let (Some(scan_blocks), Some(scan_sums), Some(add_sums)) = (p.next(), p.next(), p.next()) else {
            return Err(GpuError::Internal("scan pipelines"));
        };
        Ok(Self { layout, scan_blocks, scan_sums, add_sums, len })
    }

    /// Number of 512-count blocks.
    pub fn blocks(&self) -> u32 {
        self.len.div_ceil(512).max(1)
    }

    pub fn record(&self, enc: &mut wgpu::CommandEncoder, group: &wgpu::BindGroup) {
        super::dispatch(enc, &self.scan_blocks, group, self.blocks());
        super::dispatch(enc, &self.scan_sums, group, 1);
        super::dispatch(enc, &self.add_sums, group, self.len.div_ceil(256).max(1));
    }
}
