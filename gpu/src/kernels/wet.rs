//! The phase coupling of wet scenes (`wet.wgsl`): built only when the scene has water. Each
//! entry point has its own bind-group layout with the bindings it uses (the widest,
//! `wet_rates`, needs 11 storage buffers). CPU twin: `cpu::wet`.

use crate::GpuError;
use crate::shader::{Bind, Effects, Variant, layout, pipelines, source};

/// One entry point: its pipeline and layout.
pub(crate) struct Entry {
    pub layout: wgpu::BindGroupLayout,
    pub pipeline: wgpu::ComputePipeline,
}

pub(crate) struct Wet {
    pub phases: Entry,
    pub marker_solids: Entry,
    pub porosity: Entry,
    pub soil_pressures: Entry,
    pub extrapolate: Entry,
    /// First stage (free-surface flags, pair count, drag rate) and second.
    pub rates: [Entry; 2],
    pub marker_forces: Entry,
    pub init_water: Entry,
    pub water_stress: Entry,
}

/// The bindings of each entry point (numbers as in `wet.wgsl`; the access is the one the
/// module declares).
pub(crate) mod bindings {
    pub const PHASES: &[u32] = &[0, 7, 9, 10, 11];
    pub const MARKER_SOLIDS: &[u32] = &[0, 1, 2, 5, 11, 12, 13, 14];
    pub const POROSITY: &[u32] = &[0, 1, 2, 5, 9, 11, 12, 13];
    pub const SOIL_PRESSURES: &[u32] = &[0, 1, 2, 9, 11];
    pub const EXTRAPOLATE: &[u32] = &[0, 1, 2, 3, 4, 5, 7, 11, 12, 13, 17];
    pub const RATES: &[u32] = &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12];
    pub const MARKER_FORCES: &[u32] = &[0, 1, 2, 3, 4, 5, 11, 12, 15, 16];
    pub const PARTICLE_STATE: &[u32] = &[0, 7, 9, 11];
}

/// The storage buffers the widest entry point binds.
pub(crate) const MOST_STORAGE_BUFFERS: u32 = 11;

fn access(binding: u32) -> Bind {
    match binding {
        0 => Bind::Uniform,
        1 | 3 | 4 | 7 | 8 | 9 | 11 | 12 | 16 => Bind::ReadWrite,
        _ => Bind::Read,
    }
}

impl Wet {
    pub fn new(device: &wgpu::Device, e: &Effects) -> Result<Self, GpuError> {
        use bindings::*;
        let build = |entry: &str, fs: bool, label: &str, used: &[u32]| -> Result<Entry, GpuError> {
            let entries: Vec<(u32, Bind)> = used.iter().map(|&b| (b, access(b))).collect();
            let layout = layout(device, label, &entries);
            let src = source(e, &Variant { fs, ..Default::default() }, include_str!("wet.wgsl"), false);
            let pipeline = pipelines(device, label, &src, &layout, &[entry])?.pop().ok_or(GpuError::Internal("wet"))?;
            Ok(Entry { layout, pipeline })
        };
        Ok(Self {
            phases: build("phases", false, "phases", PHASES)?,
            marker_solids: build("marker_solids", false, "marker_solids", MARKER_SOLIDS)?,
            porosity: build("porosity", false, "porosity", POROSITY)?,
            soil_pressures: build("soil_pressures", false, "soil_pressures", SOIL_PRESSURES)?,
            extrapolate: build("wet_extrapolate", false, "wet_extrapolate", EXTRAPOLATE)?,
            rates: [build("wet_rates", true, "wet_rates[fs]", RATES)?, build("wet_rates", false, "wet_rates", RATES)?],
            marker_forces: build("wet_marker_forces", false, "wet_marker_forces", MARKER_FORCES)?,
            init_water: build("init_water", false, "init_water", PARTICLE_STATE)?,
            water_stress: build("water_stress", false, "water_stress", PARTICLE_STATE)?,
        })
    }

    /// The variant names, for `regolith check`.
    pub fn names() -> [&'static str; 10] {
        [
            "phases",
            "marker_solids",
            "porosity",
            "soil_pressures",
            "wet_extrapolate",
            "wet_rates[fs]",
            "wet_rates",
            "wet_marker_forces",
            "init_water",
            "water_stress",
        ]
    }
}
