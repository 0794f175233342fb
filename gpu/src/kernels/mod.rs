//! The kernels: one `.wgsl` beside one `.rs` that owns its pipelines (named after the entry
//! points) and bind-group layout. Kernels are compiled once per solver from the scene's
//! [`Effects`](crate::Effects); the buffers they run on live in [`crate::GpuSph`].

pub(crate) mod active;
pub(crate) mod advance;
pub(crate) mod bodies;
pub(crate) mod classify;
pub(crate) mod dilate;
pub(crate) mod extrapolate;
pub(crate) mod forces;
pub(crate) mod pack;
pub(crate) mod permute;
pub(crate) mod rates;
pub(crate) mod scan;
pub(crate) mod sort;
pub(crate) mod step_info;
pub(crate) mod wet;

/// Workgroups per row of a wide dispatch: the 65535 one dimension is guaranteed to allow
/// (`ROW_GROUPS` in common.wgsl, where `flat` turns a thread's (x, y) back into its index).
pub(crate) const ROW_GROUPS: u32 = 65535;

/// Records one dispatch in its own compute pass (passes order the storage writes). More than
/// `ROW_GROUPS` workgroups come as rows of `ROW_GROUPS`; the kernels' bounds checks drop the
/// threads past the end.
pub(crate) fn dispatch(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    workgroups: u32,
) {
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    if workgroups <= ROW_GROUPS {
        pass.dispatch_workgroups(workgroups, 1, 1);
    } else {
        pass.dispatch_workgroups(ROW_GROUPS, workgroups.div_ceil(ROW_GROUPS), 1);
    }
}

/// The first adapter's device (lavapipe in CI), for the kernels' own tests.
#[cfg(test)]
pub(crate) fn test_device() -> (wgpu::Device, wgpu::Queue) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY))
        .into_iter()
        .next()
        .expect("a wgpu adapter (lavapipe in CI)");
    pollster::block_on(
        adapter.request_device(&wgpu::DeviceDescriptor { required_limits: adapter.limits(), ..Default::default() }),
    )
    .expect("device")
}

/// An unmapped buffer of `size` bytes, for the kernels' own tests.
#[cfg(test)]
pub(crate) fn test_buffer(device: &wgpu::Device, size: usize, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor { label: None, size: size as u64, usage, mapped_at_creation: false })
}

/// Copies `src` into a mappable buffer after the commands of `enc`, submits, waits and returns
/// its words, for the kernels' own tests.
#[cfg(test)]
pub(crate) fn test_read_u32(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut enc: wgpu::CommandEncoder,
    src: &wgpu::Buffer,
) -> Vec<u32> {
    let read = test_buffer(device, src.size() as usize, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
    enc.copy_buffer_to_buffer(src, 0, &read, 0, None);
    queue.submit([enc.finish()]);
    read.map_async(wgpu::MapMode::Read, .., |r| r.expect("mapped"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
    let view = read.get_mapped_range(..).expect("view");
    bytemuck::cast_slice(&view).to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::Params;
    use crate::shader::{Bind, Effects, Variant, bind, groups, layout, pipelines, source};

    const COUNT: &str = "
@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read_write> hits: array<atomic<u32>>;

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= arrayLength(&hits)) { return; }
    atomicAdd(&hits[i], 1u);
}
";

    /// A dispatch of more than one row of workgroups (65 535 × 64 threads) runs every index
    /// exactly once: `dispatch` splits it into rows and `flat` in common.wgsl joins them.
    #[test]
    fn a_dispatch_wider_than_a_row_runs_every_index_once() {
        let (device, queue) = test_device();
        let n = ROW_GROUPS as usize * 64 + 1000;
        let e = Effects::resolve(&regolith_fsi::config::SolverConfig::default(), &[]);
        let lay = layout(&device, "count", &[(0, Bind::Uniform), (1, Bind::ReadWrite)]);
        let src = source(&e, &Variant::default(), COUNT, false);
        let pipeline = pipelines(&device, "count", &src, &lay, &["count"]).expect("compiles").pop().expect("one");
        let buf = |size: usize, usage| test_buffer(&device, size, usage);
        let params = buf(size_of::<Params>(), wgpu::BufferUsages::UNIFORM);
        let hits = buf(n * 4, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let group = bind(&device, "count", &lay, &[(0, &params), (1, &hits)]);
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        assert!(groups(n) > ROW_GROUPS);
        dispatch(&mut enc, &pipeline, &group, groups(n));
        let hits = test_read_u32(&device, &queue, enc, &hits);
        let wrong: Vec<(usize, u32)> = hits.iter().copied().enumerate().filter(|(_, h)| *h != 1).take(5).collect();
        assert!(wrong.is_empty(), "indices run other than once (index, times): {wrong:?} of {n}");
    }
}
