//! An active region on the device (see `regolith_fsi::active`): the classification, made on
//! the device by the twin of the CPU's [`ActiveRegion::classify`], and the check after each
//! step (`cover`) that the awake particles are still in the cells they may be in.
//!
//! A classification is eleven dispatches and one 16-byte read: `roles` (box test, speed,
//! cells held), six one-axis dilations of the held cells (the cells awake particles may be
//! in, then the extended band), `mark` (extended roles, one key per particle in its role's
//! segment), an exclusive scan of the keys (`Scan`, the one the cell sort uses), `place`
//! (each record to its place, frozen unless awake) and `tally` (the four counts). The device
//! then sorts, searches and steps only the awake and extended particles (first in the
//! particle buffer, extended ones flagged `FLAG_FROZEN`).

use regolith_fsi::cpu::ActiveRegion;

use crate::GpuError;
use crate::kernels::{active::Cover, classify::Classify, dilate::Dilate, dispatch, scan::Scan};
use crate::layout::{ActiveBox, ClassifyParams};
use crate::shader::{Effects, USAGE, bind, buffer, groups, scan_blocks};

/// The buffers a classification and the per-step check share with the solver.
pub(crate) struct Shared<'a> {
    pub params: &'a wgpu::Buffer,
    pub parts: &'a wgpu::Buffer,
    pub tmp: &'a wgpu::Buffer,
    pub info: &'a wgpu::Buffer,
}

/// What the classification's buffers are sized for.
pub(crate) struct Sizes {
    /// Cells of the neighbour grid.
    pub cells: usize,
    /// Particles the solver's buffers hold room for.
    pub capacity: usize,
    /// Boxes (one per FSI body).
    pub boxes: usize,
    /// Cells a neighbour search scans on each side.
    pub reach: u32,
}

pub(crate) struct ActiveParts {
    pub k: Cover,
    /// `cover`'s bindings: the particles, the step record and the cells awake particles may
    /// be in until the next classification (1 per cell; `record` writes them).
    pub group: wgpu::BindGroup,
    c: Classify,
    d: Dilate,
    scan: Scan,
    params: wgpu::Buffer,
    boxes: wgpu::Buffer,
    held: wgpu::Buffer,
    keys: wgpu::Buffer,
    counts: wgpu::Buffer,
    /// The four role counts, read back after a classification.
    pub counts_read: wgpu::Buffer,
    roles: wgpu::BindGroup,
    dilations: Vec<wgpu::BindGroup>,
    scan_group: wgpu::BindGroup,
    partition: wgpu::BindGroup,
}

impl ActiveParts {
    /// Kernels and buffers for `size`: 32 bytes per particle of capacity (role, cell, three
    /// keys and their scan) and 20 per grid cell. No buffer holds more than 12 bytes per
    /// particle, against the records' 80, so any device the records fit takes them.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        e: &Effects,
        s: &Shared<'_>,
        size: &Sizes,
    ) -> Result<Self, GpuError> {
        let Sizes { cells: n_cells, capacity, boxes: n_boxes, reach } = *size;
        let mk = |label: &str, words: usize, usage: wgpu::BufferUsages| buffer(device, label, 4 * words as u64, usage);
        let uniform = wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST;
        let k = Cover::new(device, e)?;
        let c = Classify::new(device, e)?;
        let d = Dilate::new(device, e)?;
        let len = 3 * capacity.max(1);
        let scan = Scan::new(device, e, len as u32)?;
        let cells = mk("active.cells", n_cells, USAGE);
        let held = mk("active.held", n_cells, USAGE);
        let ping = mk("active.dilate.a", n_cells, USAGE);
        let pong = mk("active.dilate.b", n_cells, USAGE);
        let near = mk("active.near", n_cells, USAGE);
        let role = mk("active.role", capacity, USAGE);
        let cell_of = mk("active.cell_of", capacity, USAGE);
        let keys = mk("active.keys", len, USAGE);
        let kstart = mk("active.kstart", len + 1, USAGE);
        let sums = mk("active.sums", scan_blocks(len as u32) as usize, USAGE);
        let counts = mk("active.counts", 4, USAGE);
        let counts_read = mk("active.counts.read", 4, wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        let params = mk("active.params", size_of::<ClassifyParams>() / 4, uniform);
        let boxes = mk("active.boxes", n_boxes * size_of::<ActiveBox>() / 4, USAGE);
        let group = bind(device, "cover", &k.layout, &[(0, s.params), (1, s.parts), (2, &cells), (3, s.info)]);
        let roles = bind(
            device,
            "classify",
            &c.roles_layout,
            &[
                (0, s.params),
                (1, &params),
                (2, s.parts),
                (3, &boxes),
                (4, &role),
                (5, &cell_of),
                (6, &held),
                (7, &near),
                (8, &keys),
            ],
        );
        // Grown by the slack into `cells`, then by the search reach into `near` (a cube
        // dilation by a then b is one by a + b).
        let slack = ActiveRegion::SLACK as u32;
        let steps = [
            (0, slack, &held, &ping),
            (1, slack, &ping, &pong),
            (2, slack, &pong, &cells),
            (0, reach, &cells, &ping),
            (1, reach, &ping, &pong),
            (2, reach, &pong, &near),
        ];
        let dilations = d.chain(device, queue, s.params, &steps);
        let scan_group = bind(device, "scan", &scan.layout, &[(0, s.params), (1, &keys), (2, &kstart), (3, &sums)]);
        let partition = bind(
            device,
            "partition",
            &c.partition_layout,
            &[(0, s.params), (1, &role), (2, &kstart), (3, s.parts), (4, s.tmp), (5, &counts), (6, s.info)],
        );
        Ok(Self {
            k,
            group,
            c,
            d,
            scan,
            params,
            boxes,
            held,
            keys,
            counts,
            counts_read,
            roles,
            dilations,
            scan_group,
            partition,
        })
    }

    /// Records a classification of the `n` particles with `region`'s boxes where they are now:
    /// the records in their new order land in the solver's scratch buffer (`Shared::tmp`, for
    /// the caller to copy back), the four role counts in `counts_read`, and the number the next
    /// sort takes in the step record.
    pub fn record(
        &self,
        queue: &wgpu::Queue,
        enc: &mut wgpu::CommandEncoder,
        region: &ActiveRegion,
        n: usize,
        n_cells: usize,
    ) {
        let boxes: Vec<ActiveBox> = region
            .boxes()
            .iter()
            .map(|b| {
                let f = |v: [f64; 3]| v.map(|x| x as f32);
                ActiveBox {
                    center: f(b.center),
                    h0: b.half[0] as f32,
                    a0: f(b.axes[0]),
                    h1: b.half[1] as f32,
                    a1: f(b.axes[1]),
                    h2: b.half[2] as f32,
                    a2: f(b.axes[2]),
                    pad: 0.0,
                }
            })
            .collect();
        if !boxes.is_empty() {
            queue.write_buffer(&self.boxes, 0, bytemuck::cast_slice(&boxes));
        }
        let (v2, travel) = region.domain().map_or((f32::INFINITY, 0.0), |d| {
            let s = &d.settings;
            ((s.sleep_speed * s.sleep_speed) as f32, s.travel as f32)
        });
        let p = ClassifyParams { n_boxes: boxes.len() as u32, v2, travel, pad: 0 };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        enc.clear_buffer(&self.held, 0, None);
        // The three segments of `n` keys: every place and count is a sum over them alone, so
        // the keys past them (an earlier classification's, when there were more particles)
        // need no clearing.
        if n > 0 {
            enc.clear_buffer(&self.keys, 0, Some(12 * n as u64));
        }
        dispatch(enc, &self.c.roles, &self.roles, groups(n));
        for g in &self.dilations {
            dispatch(enc, &self.d.dilate, g, groups(n_cells));
        }
        dispatch(enc, &self.c.mark, &self.roles, groups(n));
        self.scan.record(enc, &self.scan_group);
        dispatch(enc, &self.c.place, &self.partition, groups(n));
        dispatch(enc, &self.c.tally, &self.partition, 1);
        enc.copy_buffer_to_buffer(&self.counts, 0, &self.counts_read, 0, Some(16));
    }
}
