//! Soil rates (`rates.wgsl`), one pipeline per stage kind: `first` adds the free-surface
//! measure, flags and pair count. CPU twin: `rates::soil_rates`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Rates {
    pub layout: wgpu::BindGroupLayout,
    pub first: wgpu::ComputePipeline,
    pub second: wgpu::ComputePipeline,
}

impl Rates {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let layout = layout(
            device,
            "soil_rates",
            &[
                (0, Uniform),
                (1, Read),
                (2, Read),
                (3, Read),
                (4, Read),
                (5, Read),
                (6, ReadWrite),
                (7, ReadWrite),
                (8, ReadWrite),
            ],
        );
        let build = |fs: bool, label: &str| -> Result<wgpu::ComputePipeline, GpuError> {
            let src = source(e, &Variant { fs, ..Default::default() }, include_str!("rates.wgsl"), false);
            pipelines(device, label, &src, &layout, &["soil_rates"])?.pop().ok_or(GpuError::Internal("soil_rates"))
        };
        Ok(Self { first: build(true, "soil_rates[fs]")?, second: build(false, "soil_rates")?, layout })
    }
}
