//! The kernels: one `.wgsl` beside one `.rs` that owns its pipelines (named after the entry
//! points) and bind-group layout. Kernels are compiled once per solver from the scene's
//! [`Effects`](crate::Effects); the buffers they run on live in [`crate::GpuSph`].

pub(crate) mod active;
pub(crate) mod advance;
pub(crate) mod bodies;
pub(crate) mod extrapolate;
pub(crate) mod forces;
pub(crate) mod pack;
pub(crate) mod permute;
pub(crate) mod rates;
pub(crate) mod scan;
pub(crate) mod sort;
pub(crate) mod step_info;
pub(crate) mod wet;

/// Records one dispatch in its own compute pass (passes order the storage writes).
pub(crate) fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    workgroups: u32,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(workgroups, 1, 1);
}
