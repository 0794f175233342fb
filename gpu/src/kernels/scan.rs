//! Exclusive prefix sum of bin counts (`scan.wgsl`): `scan_blocks`, `scan_sums`, `add_sums`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, scan_blocks, source};

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

    /// Number of blocks of `SCAN_BLOCK` counts.
    pub fn blocks(&self) -> u32 {
        scan_blocks(self.len)
    }

    pub fn record(&self, enc: &mut wgpu::CommandEncoder, group: &wgpu::BindGroup) {
        super::dispatch(enc, &self.scan_blocks, group, self.blocks());
        super::dispatch(enc, &self.scan_sums, group, 1);
        super::dispatch(enc, &self.add_sums, group, self.len.div_ceil(256).max(1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::Params;
    use crate::shader::{SCAN_BLOCK, bind};

    /// The device's scan equals the serial exclusive prefix sum for lengths around a block's
    /// edges and for one with more block totals than `scan_sums` takes in one chunk (its carry).
    #[test]
    fn the_scan_matches_a_serial_prefix_sum() {
        let (device, queue) = crate::kernels::test_device();
        let e = Effects::resolve(&regolith_fsi::config::SolverConfig::default(), &[]);
        let b = SCAN_BLOCK as usize;
        for len in [1, 255, 256, 2047, 2048, 2049, 3 * b + 17, b * b + 5] {
            let counts: Vec<u32> = (0..len as u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 29) % 5).collect();
            let scan = Scan::new(&device, &e, len as u32).expect("compiles");
            let buf = |size: usize, usage| crate::kernels::test_buffer(&device, size, usage);
            let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
            let params = buf(size_of::<Params>(), wgpu::BufferUsages::UNIFORM);
            let cnt = buf(4 * len, storage);
            queue.write_buffer(&cnt, 0, bytemuck::cast_slice(&counts));
            let start = buf(4 * (len + 1), storage);
            let sums = buf(4 * scan_blocks(len as u32) as usize, storage);
            let group = bind(&device, "scan", &scan.layout, &[(0, &params), (1, &cnt), (2, &start), (3, &sums)]);
            let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            scan.record(&mut enc, &group);
            let got = crate::kernels::test_read_u32(&device, &queue, enc, &start);
            let mut want = Vec::with_capacity(len + 1);
            let mut sum = 0u32;
            for c in &counts {
                want.push(sum);
                sum += c;
            }
            want.push(sum);
            let first = got.iter().zip(&want).position(|(g, w)| g != w);
            assert!(
                first.is_none(),
                "len {len}: start[{first:?}] differs (device {:?}, serial {:?})",
                first.map(|i| got[i]),
                first.map(|i| want[i])
            );
        }
    }
}
