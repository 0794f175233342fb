//! Gathers into cell order (`permute.wgsl`): `permute_particles`, `set_active`,
//! `gather_markers`, each over its own layout.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

pub(crate) struct Permute {
    pub particles_layout: wgpu::BindGroupLayout,
    pub active_layout: wgpu::BindGroupLayout,
    pub markers_layout: wgpu::BindGroupLayout,
    pub permute_particles: wgpu::ComputePipeline,
    pub set_active: wgpu::ComputePipeline,
    pub gather_markers: wgpu::ComputePipeline,
}

impl Permute {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use Bind::*;
        let src = source(e, &Variant::default(), include_str!("permute.wgsl"), false);
        let particles_layout =
            layout(device, "permute_particles", &[(0, Uniform), (1, Read), (2, Read), (3, Read), (4, ReadWrite)]);
        let active_layout = layout(device, "set_active", &[(0, Uniform), (2, Read), (5, ReadWrite)]);
        let markers_layout =
            layout(device, "gather_markers", &[(0, Uniform), (1, Read), (2, Read), (6, Read), (7, ReadWrite)]);
        let one = |l: &wgpu::BindGroupLayout, entry: &str| -> Result<wgpu::ComputePipeline, GpuError> {
            pipelines(device, "permute", &src, l, &[entry])?.pop().ok_or(GpuError::Internal("permute pipeline"))
        };
        Ok(Self {
            permute_particles: one(&particles_layout, "permute_particles")?,
            set_active: one(&active_layout, "set_active")?,
            gather_markers: one(&markers_layout, "gather_markers")?,
            particles_layout,
            active_layout,
            markers_layout,
        })
    }
}
