//! `regolith calibrate triaxial`: the virtual triaxial test on the SPH soil (AGX's test).
//!
//! A box-shaped sample (`width` × `width` × `height`) stands between six rigid plates, each a
//! box of BCE markers with free-slip (smooth) contact, so the sample deforms homogeneously as
//! between lubricated platens. Gravity is off. Each face's stress is the soil's normal force
//! on the markers beyond it over the sample's current face area; the sample's faces lie half a
//! spacing inside the plates' surfaces (the markers sit on the surfaces, the soil's first
//! layer one spacing in). But BCE markers are not a frictionless wall: beside a plate, soil
//! layers push on one another through the plate's markers too, so the side plates carry part
//! of the axial load, more as the sample shortens past their marker rows. The stresses the
//! envelope is fitted to are therefore the load the soil itself carries, from the plates'
//! forces and the particles they act on (`mean_stresses`, the Love–Weber mean stress of the
//! sample). The faces' force over area alone (AGX's reading) gives a second envelope,
//! `faces`; the particles' own volume-mean stresses a third, `bulk`.
//!
//! 1. **Consolidation.** Every plate is servo-controlled towards the confining stress σ0: it
//!    moves outward at `v = (σ − σ0) L / (2 M τ)` (L the sample's length along the plate's
//!    axis, M the constrained modulus of the soil at σ0), so that the stress relaxes to σ0
//!    with the time constant τ = `servo_crossings` × (longest side) / (P-wave speed). It ends
//!    when the mean stress on every face over the last τ is within `tolerance` of σ0.
//! 2. **Shear.** The lateral plates keep the servo; the top and bottom plates approach at a
//!    constant speed, the axial strain rate `strain_rate`, until `max_strain`.
//! 3. **Failure** (see [`super::lowpass`]): the vertical stress is low-pass filtered (a
//!    zero-phase Gaussian by default, or AGX's Butterworth of `filter_order`, whose cutoff
//!    wavelength is `filter_wavelength` of axial strain) and the failure point is its first
//!    local maximum at which it exceeds `min_ratio` × the confining stress, or, for
//!    `failure = plateau` (the default for MCC, and the fallback when no peak comes before
//!    the end), the mean over the last fifth of the test (the critical state). The same rule
//!    on the particles' volume-mean stresses gives the soil's own envelope (`bulk`).
//!
//! The failure stresses of all tests give the Mohr–Coulomb envelope with standard errors
//! ([`super::fit::mohr_coulomb`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::CommandError;
use super::fit::{MohrCoulomb, mohr_coulomb, mohr_coulomb_cohesionless};
use super::lowpass::{Failure, FailureKind, FilterKind, LowPass, first_peak, plateau};
use super::target::material_table;
use super::target::{
    JointRun, JointSettings, TargetRun, TargetSettings, calibrate_jointly, calibrate_to_target, write_calibrated,
};
use crate::input::InputError;
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use crate::runner::{Record, Task, fnv_id, forget, read_all, run_tasks};
use crate::scene::{Precision, load_scene};
use crate::sim::Simulation;
use regolith_fsi::Real;
use regolith_fsi::config::WallContact;
use regolith_fsi::math::Sym3;

/// Plate thickness in spacings (the marker layers cover a kernel support).
const PLATE_SPACINGS: f64 = 3.0;

/// The six plates, in scene order: (name, axis, outward sign).
const PLATES: [(&str, usize, f64); 6] = [
    ("x_min", 0, -1.0),
    ("x_max", 0, 1.0),
    ("y_min", 1, -1.0),
    ("y_max", 1, 1.0),
    ("bottom", 2, -1.0),
    ("top", 2, 1.0),
];

/// Interval of the shear record (s): each sample is the mean of the exchanges in it.
const SAMPLE_INTERVAL: f64 = 1e-3;

/// Fraction of the shear phase averaged for a plateau (the critical state).
const PLATEAU_FRACTION: f64 = 0.2;

/// How the failure point is picked.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureRule {
    /// The first local maximum of the filtered vertical stress (AGX's rule; a plateau when
    /// none comes before the end).
    Peak,
    /// The critical state: the mean of the filtered stresses over the last fifth of the test.
    Plateau,
}

/// Which envelope a calibration loop matches to its targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EnvelopeSource {
    /// The particles' own stresses (`bulk`): the soil's strength, what a scene run with the
    /// calibrated material gets. The default.
    Particles,
    /// The load the soil carries, from the plates' forces (the report's main envelope).
    Plates,
}

impl EnvelopeSource {
    /// What the envelope is read on, as printed and written in a calibrated material's header.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Particles => "the particles' own stresses",
            Self::Plates => "the soil's load from the plates' forces",
        }
    }
}

/// Settings of the test (the command's flags).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TriaxialSettings {
    /// Sample width along x and y (m).
    pub width: f64,
    /// Sample height along z (m).
    pub height: f64,
    /// Particle spacing d0 (m).
    pub spacing: f64,
    /// Confining (consolidation) stresses, one test each (Pa, compression positive).
    pub confining: Vec<f64>,
    /// Axial strain rate of the shear phase (1/s).
    pub strain_rate: f64,
    /// Axial strain at which the shear phase ends.
    pub max_strain: f64,
    /// Consolidation ends when every face is within this fraction of the confining stress.
    pub tolerance: f64,
    /// Servo time constant in P-wave crossings of the sample's longest side.
    pub servo_crossings: f64,
    /// Failure rule.
    pub failure: FailureRule,
    /// Low-pass filter of the failure pick.
    pub filter: FilterKind,
    /// Order of the Butterworth filter.
    pub filter_order: usize,
    /// Shortest wavelength the filter keeps, in axial strain.
    pub filter_wavelength: f64,
    /// A peak counts only where the vertical stress exceeds this multiple of the confining one.
    pub min_ratio: f64,
    /// Precision of the runs.
    #[serde(serialize_with = "precision_name")]
    pub precision: Precision,
}

fn precision_name<S: serde::Serializer>(p: &Precision, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(p.name())
}

/// The default confining stresses: AGX's ten, 5 to 50 kPa.
pub fn default_confining() -> Vec<f64> {
    (1..=10).map(|k| 5e3 * k as f64).collect()
}

impl TriaxialSettings {
    /// The defaults for a sample `width` wide: twice as high, d0 = width / 10, AGX's ten
    /// confining stresses, axial strain rate 0.2 /s to 10 % strain, servo τ =
    /// [`SERVO_CROSSINGS`] P-wave crossings, 1 % consolidation tolerance, a 4th-order filter
    /// keeping wavelengths of 1 % strain and more, peaks above 1.25 σ0 (AGX's filter order and
    /// ratio).
    pub fn for_width(width: f64) -> Self {
        Self {
            width,
            height: 2.0 * width,
            spacing: width / 10.0,
            confining: default_confining(),
            strain_rate: 0.2,
            max_strain: 0.1,
            tolerance: 0.01,
            servo_crossings: SERVO_CROSSINGS,
            failure: FailureRule::Peak,
            filter: FilterKind::Gaussian,
            filter_order: 4,
            filter_wavelength: 0.01,
            min_ratio: 1.25,
            precision: Precision::F32,
        }
    }

    /// Checks the settings; the error names the flag and what is allowed.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        use super::positive;
        positive("--width", self.width)?;
        positive("--height", self.height)?;
        positive("--spacing", self.spacing)?;
        positive("--strain-rate", self.strain_rate)?;
        positive("--servo-crossings", self.servo_crossings)?;
        positive("--filter-wavelength", self.filter_wavelength)?;
        if self.width < 4.0 * self.spacing || self.height < 4.0 * self.spacing {
            return Err((
                "--spacing",
                format!(
                    "{} m leaves fewer than 4 spacings across the sample ({} × {} m); use ≤ {} m",
                    self.spacing,
                    self.width,
                    self.height,
                    self.width.min(self.height) / 4.0
                ),
            ));
        }
        if self.confining.is_empty() || self.confining.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(("--confining", format!("must be one or more stresses > 0 Pa (got {:?})", self.confining)));
        }
        if self.confining.len() < 2 {
            return Err((
                "--confining",
                format!("needs at least two stresses: an envelope needs two Mohr circles (got {:?})", self.confining),
            ));
        }
        if !(self.max_strain > 0.0 && self.max_strain <= 0.3) {
            return Err((
                "--max-strain",
                format!("must lie in (0, 0.3]: the plates cover a sample bulged by 15 % (got {})", self.max_strain),
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 0.5) {
            return Err(("--tolerance", format!("must lie in (0, 0.5) (got {})", self.tolerance)));
        }
        if !(1..=8).contains(&self.filter_order) {
            return Err(("--filter-order", format!("must be 1 to 8 (got {})", self.filter_order)));
        }
        if !(self.min_ratio.is_finite() && self.min_ratio >= 1.0) {
            return Err(("--min-ratio", format!("must be ≥ 1 (got {})", self.min_ratio)));
        }
        if self.filter_wavelength >= self.max_strain {
            return Err((
                "--filter-wavelength",
                format!("{} must be shorter than --max-strain {}", self.filter_wavelength, self.max_strain),
            ));
        }
        Ok(())
    }

    fn plate(&self) -> f64 {
        PLATE_SPACINGS * self.spacing
    }

    /// How far the plates reach past the sample's lateral faces, for the sample to bulge (a
    /// lateral strain of 15 %, what 30 % axial strain at constant volume gives).
    fn margin(&self) -> f64 {
        0.15 * self.width + 2.0 * self.spacing
    }
}

/// The scene of one test at confining stress `sigma0`: the material (renamed "soil"), the
/// sample and the six plates, no gravity, in an open container. A Modified Cam Clay sample
/// starts consolidated at `sigma0` (`initial_pressure`), so that its preconsolidation is `ocr`
/// times the confining stress as in a lab test; from zero stress it would consolidate along
/// its normal compression line and be normally consolidated whatever its OCR. Other models
/// start stress-free (their state does not remember a consolidation).
pub fn scene_text(
    material: &toml::Table,
    s: &TriaxialSettings,
    sigma0: f64,
    end_time: f64,
) -> Result<String, CommandError> {
    let d0 = s.spacing;
    // Whole spacings across, and a lattice offset by half a spacing so that particle centres
    // lie symmetric about the origin, d0/2 inside the faces.
    let (nw, nh) = ((s.width / d0).round().max(4.0), (s.height / d0).round().max(4.0));
    let (w, h) = (nw * d0, nh * d0);
    let (t, m) = (s.plate(), s.margin());
    let half_box = |len: f64| ((0.5 * len + 2.0 * t + m + 2.0 * d0) / d0).ceil() + 0.5;
    let (bx, bz) = (half_box(w) * d0, half_box(h) * d0);
    let mut mat = material.clone();
    mat.insert("name".into(), toml::Value::String("soil".into()));
    let mut materials = toml::Table::new();
    materials.insert("materials".into(), toml::Value::Array(vec![toml::Value::Table(mat)]));
    let materials = toml::to_string(&materials)
        .map_err(|e| CommandError::Output(format!("cannot write the test's material section: {e}")))?;
    let mut text = format!(
        "# regolith calibrate triaxial: one test (written by the command; `regolith run` runs\n\
         # the sample and plates, but the servo control and the plates' smooth contact are the\n\
         # command's).\n\
         [simulation]\n\
         end_time = {end_time}\n\
         precision = \"{prec}\"\n\
         gravity = [0.0, 0.0, 0.0]\n\n\
         [sph]\n\
         spacing = {d0}\n\n\
         {materials}\n\
         [container]\n\
         min = [{mx}, {mx}, {mz}]\n\
         max = [{bx}, {bx}, {bz}]\n\
         walls = false\n\n\
         [[soil_blocks]]\n\
         material = \"soil\"\n\
         shape = \"box\"\n\
         min = [{lx}, {lx}, {lz}]\n\
         max = [{hx}, {hx}, {hz}]\n{pressure}",
        prec = s.precision.name(),
        mx = -bx,
        mz = -bz,
        lx = -0.5 * w,
        lz = -0.5 * h,
        hx = 0.5 * w,
        hz = 0.5 * h,
        pressure =
            if model(material) == Some("mcc") { format!("initial_pressure = {sigma0:e}\n") } else { String::new() },
    );
    let dims = [w, w, h];
    for (name, axis, sign) in PLATES {
        // The side plates reach over the top and bottom plates' thickness (the edges stay
        // closed while the sample shortens); top and bottom cover the bulged sample.
        let mut size = [w + 2.0 * m, w + 2.0 * m, h + d0 + 2.0 * t];
        size[axis] = t;
        let mut pos = [0.0; 3];
        pos[axis] = sign * (0.5 * dims[axis] + 0.5 * d0 + 0.5 * t);
        text += &format!(
            "\n[[bodies]]\n\
             name = \"{name}\"\n\
             shape = {{ type = \"box\", size = [{}, {}, {}] }}\n\
             position = [{}, {}, {}]\n\
             motion = {{ type = \"prescribed\", linear_velocity = [0.0, 0.0, 0.0] }}\n\
             mass = 1.0\n",
            size[0], size[1], size[2], pos[0], pos[1], pos[2]
        );
    }
    text += "\n[output]\nmcap = false\n";
    Ok(text)
}

/// One sample of a test's record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sample {
    /// Simulated time (s).
    pub time: f64,
    /// Axial strain since the end of consolidation (shortening positive).
    pub axial_strain: f64,
    /// Volumetric strain since the end of consolidation (compaction positive).
    pub volumetric_strain: f64,
    /// Vertical stress (Pa, compression positive): the mean vertical load the soil carries,
    /// from the plates' forces on its particles (`mean_stresses`).
    pub vertical: f64,
    /// Lateral stress (Pa): the mean of the x and y loads the soil carries.
    pub lateral: f64,
    /// The faces' normal force over area alone, top and bottom (Pa): AGX's reading, which
    /// counts the load the side plates' markers carry too.
    pub face_vertical: f64,
    /// The four side faces' normal force over area (Pa): what the servo holds at σ0.
    pub face_lateral: f64,
    /// The particles' own vertical stress: the volume-weighted mean of −σzz over the sample
    /// (Pa). Walls that hold a uniformly stressed sample read 0.985 of it (the kernel's
    /// lattice sum at h = 1.2 d0); a larger gap is load the plates' markers take or give
    /// elsewhere (docs/calibration.md).
    pub bulk_vertical: f64,
    /// The particles' own lateral stress, the volume-weighted mean of −(σxx + σyy)/2 (Pa).
    pub bulk_lateral: f64,
}

/// A failure point read on one of the other stress records (the same filter and rule): the
/// particles' volume-mean stresses, or the faces' normal force over area alone.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct FailureStresses {
    /// How it was found.
    pub kind: FailureKind,
    /// Axial strain at failure.
    pub strain: f64,
    /// Vertical stress at failure (Pa, compression positive).
    pub vertical: f64,
    /// Lateral stress at failure (Pa).
    pub lateral: f64,
}

/// One test.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TriaxialTest {
    /// Confining stress asked for (Pa).
    pub confining: f64,
    /// Soil particles.
    pub particles: usize,
    /// Consolidation time (s).
    pub consolidation_time: f64,
    /// Mean stress on each face over the last servo time constant of consolidation (Pa), in
    /// the order x_min, x_max, y_min, y_max, bottom, top.
    pub consolidated_stresses: [f64; 6],
    /// Sample size after consolidation (m).
    pub consolidated_size: [f64; 3],
    /// Servo time constant (s) and the constrained modulus it assumes (Pa).
    pub servo_tau: f64,
    /// Constrained modulus of the soil at the confining stress (Pa).
    pub constrained_modulus: f64,
    /// Inertial number of the shear phase, `ε̇ d0 / √(σ0/ρ)` (quasi-static below about 1e-3).
    pub inertial_number: f64,
    /// Failure point.
    pub failure: Failure,
    /// Axial strain at failure.
    pub strain_at_failure: f64,
    /// Vertical (major principal) stress at failure (Pa).
    pub vertical_at_failure: f64,
    /// Lateral (minor principal) stress at failure (Pa).
    pub lateral_at_failure: f64,
    /// The same failure rule applied to the particles' own (volume-mean) stresses.
    pub bulk: FailureStresses,
    /// The same failure rule applied to the faces' normal force over area alone (AGX's
    /// reading).
    pub faces: FailureStresses,
    /// Particles that left the sample's box by more than a spacing (0 in a good test).
    pub escaped: usize,
    /// Soil steps.
    pub steps: u64,
    /// Wall-clock time (s).
    pub wall_time_s: f64,
    /// The test's folder.
    pub dir: String,
    /// Its plots.
    pub plots: Vec<String>,
    /// The shear record.
    #[serde(skip)]
    pub series: Vec<Sample>,
    /// The filtered vertical and lateral stresses, per sample.
    #[serde(skip)]
    pub filtered: Vec<(f64, f64)>,
}

/// The failure rule a material gets by default: the critical-state plateau for Modified Cam
/// Clay (it hardens or softens towards it), the first peak otherwise.
pub fn default_rule(material: &Path) -> Result<FailureRule, InputError> {
    let m = material_table(material)?;
    Ok(match model(&m) {
        Some("mcc") => FailureRule::Plateau,
        _ => FailureRule::Peak,
    })
}

/// Writes the scene into `dir` and runs one test at confining stress `sigma0`.
pub fn run_test(
    material: &toml::Table,
    s: &TriaxialSettings,
    sigma0: f64,
    dir: &Path,
) -> Result<TriaxialTest, CommandError> {
    std::fs::create_dir_all(dir).map_err(|e| CommandError::Output(format!("cannot create {}: {e}", dir.display())))?;
    // The scene's end time only bounds the run; the servo loop decides when it stops.
    let end = 1e3;
    let path = dir.join("scene.toml");
    let text = scene_text(material, s, sigma0, end)?;
    std::fs::write(&path, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", path.display())))?;
    let scene = load_scene(&path, &[])?;
    let mut test = match s.precision {
        Precision::F32 => run_scene::<f32>(&scene, s, sigma0),
        Precision::F64 => run_scene::<f64>(&scene, s, sigma0),
    }?;
    test.dir = dir.display().to_string();
    test.plots = write_test(&test, dir)?.iter().map(|p| p.display().to_string()).collect();
    Ok(test)
}

/// A test's `series.csv` and stress–strain plot, in its folder.
fn write_test(t: &TriaxialTest, dir: &Path) -> Result<Vec<PathBuf>, CommandError> {
    let out_err = |e: String| CommandError::Output(e);
    let csv = dir.join("series.csv");
    let text: String = std::iter::once(
        "time,axial_strain,volumetric_strain,vertical_stress,lateral_stress,vertical_filtered,lateral_filtered,face_vertical_stress,face_lateral_stress,bulk_vertical_stress,bulk_lateral_stress\n"
            .to_string(),
    )
    .chain(t.series.iter().zip(&t.filtered).map(|(r, (fv, fh))| {
        format!(
            "{},{},{},{},{},{},{},{},{},{},{}\n",
            r.time,
            r.axial_strain,
            r.volumetric_strain,
            r.vertical,
            r.lateral,
            fv,
            fh,
            r.face_vertical,
            r.face_lateral,
            r.bulk_vertical,
            r.bulk_lateral
        )
    }))
    .collect();
    std::fs::write(&csv, text).map_err(|e| out_err(format!("cannot write {}: {e}", csv.display())))?;
    write_figure(&stress_strain_figure(t), dir, "stress_strain").map_err(|e| out_err(e.to_string()))
}

/// The particles' volume-weighted mean stress, vertical and lateral (Pa, compression
/// positive).
fn bulk_stresses<T: Real>(sim: &Simulation<T>) -> [f64; 2] {
    let f = &sim.system.fluid;
    let (mut v, mut sz, mut sh) = (0.0, 0.0, 0.0);
    for ((s, m), rho) in f.stresses().iter().zip(f.masses()).zip(f.densities()) {
        let vol = m.as_f64() / rho.as_f64();
        v += vol;
        sz -= vol * s.zz.as_f64();
        sh -= 0.5 * vol * (s.xx.as_f64() + s.yy.as_f64());
    }
    if v > 0.0 { [sz / v, sh / v] } else { [0.0; 2] }
}

/// The plates' surfaces facing the sample, per axis (min side, max side), m.
fn surfaces<T: Real>(sim: &Simulation<T>, t: f64) -> [[f64; 2]; 3] {
    let o: Vec<[f64; 3]> = sim.bodies().map(|b| sim.body_state(b).origin).collect();
    [0, 1, 2].map(|a| [o[2 * a][a] + 0.5 * t, o[2 * a + 1][a] - 0.5 * t])
}

/// Stress on each face of the sample (compression positive): the soil's force along the
/// face's outward normal on every marker at or beyond the face's plate surface, whichever
/// plate it belongs to, over the face's current area. The plates overlap at the sample's
/// edges (each reaches past the others so that the corners stay closed as the sample
/// deforms), and there the soil pushes on the markers of two plates at once: a per-plate
/// force would miss the part of a face's load that the neighbouring plate's markers carry.
/// `sf` are the plate surfaces, `size` the sample's size.
fn face_stresses<T: Real>(sim: &Simulation<T>, sf: [[f64; 2]; 3], size: [f64; 3], d0: f64) -> [f64; 6] {
    let f = &sim.system.fluid;
    let mut force = [0.0; 6];
    for (x, fm) in f.marker_positions().iter().zip(f.marker_forces()) {
        let (x, fm) = ([x.x.as_f64(), x.y.as_f64(), x.z.as_f64()], [fm.x.as_f64(), fm.y.as_f64(), fm.z.as_f64()]);
        for (k, (_, axis, sign)) in PLATES.iter().enumerate() {
            let surface = sf[*axis][(*sign > 0.0) as usize];
            if sign * (x[*axis] - surface) >= -0.25 * d0 {
                force[k] += sign * fm[*axis];
            }
        }
    }
    std::array::from_fn(|k| {
        let axis = PLATES[k].1;
        force[k] / (size[(axis + 1) % 3] * size[(axis + 2) % 3])
    })
}

/// The sample's mean normal stresses (x, y, z; Pa, compression positive) from the plates'
/// forces on the soil, normal and tangential: the mean over the sample of the load its
/// particles pass to one another across each plane, by their equilibrium.
///
/// With no gravity and no inertia the particles' pair forces balance the walls' forces
/// `F_a` on them, so their moment `Σ_pairs r ∘ f` equals `−Σ_a x_a ∘ F_a`, which the markers'
/// forces and pair moments give ([`regolith_fsi::SphSolver::marker_moments`]). A pair's
/// `r_i f_i` is its force integrated over the planes normal to `i` between its two particles,
/// so the moment is the load the soil carries across those planes, integrated from the lowest
/// particle centre to the highest: divided by the face area and that span (the sample's
/// length less a spacing), it is the mean stress the soil carries.
///
/// Each force is taken at the particle it acts on, not at the marker. Beside a wall, BCE
/// markers pass load from one soil layer to the next (a marker pushes the particles above it
/// up and those below it down, with no net force of its own): that load bypasses the soil,
/// and the faces' force over area counts it while this moment does not. That share, and the
/// tangential pull of the markers' rows as the sample shortens past them, is what a lab
/// corrects a load cell's reading for as side friction (docs/calibration.md).
fn mean_stresses<T: Real>(sim: &Simulation<T>, sf: [[f64; 2]; 3], size: [f64; 3], d0: f64) -> [f64; 3] {
    let f = &sim.system.fluid;
    let mid = sf.map(|[lo, hi]| 0.5 * (lo + hi));
    let mut moment = [0.0; 3];
    for ((x, fm), q) in f.marker_positions().iter().zip(f.marker_forces()).zip(f.marker_moments()) {
        let (x, fm, q) = (
            [x.x.as_f64(), x.y.as_f64(), x.z.as_f64()],
            [fm.x.as_f64(), fm.y.as_f64(), fm.z.as_f64()],
            [q.x.as_f64(), q.y.as_f64(), q.z.as_f64()],
        );
        for a in 0..3 {
            moment[a] += (x[a] - mid[a]) * fm[a] + q[a];
        }
    }
    std::array::from_fn(|a| moment[a] / (size[(a + 1) % 3] * size[(a + 2) % 3] * (size[a] - d0)))
}

/// What one exchange of the test reads.
struct Reading {
    /// The sample's size (m).
    size: [f64; 3],
    /// Each face's stress (Pa), in the order of [`PLATES`].
    faces: [f64; 6],
    /// The exchange's length (s).
    dt: f64,
    /// The soil's mean load per area along x, y, z (Pa), `mean_stresses`.
    soil: [f64; 3],
}

fn run_scene<T: Real>(
    scene: &crate::scene::Scene,
    s: &TriaxialSettings,
    sigma0: f64,
) -> Result<TriaxialTest, CommandError> {
    let started = Instant::now();
    let run_err = |e: String| CommandError::Run(format!("{}: {e}", scene.path.display()));
    let mut sim = Simulation::<T>::new(scene).map_err(|e| run_err(e.to_string()))?;
    let (d0, t) = (s.spacing, s.plate());
    free_slip_plates(&mut sim).map_err(run_err)?;
    let f = &sim.system.fluid;
    let particles = f.len();
    let density = f.materials().first().map_or(1.0, |m| m.density.as_f64());
    let modulus = match (f.materials().first(), f.states().first()) {
        (Some(m), Some(st)) => m.moduli(&Sym3::iso(T::of(-sigma0)), st).p_wave().as_f64(),
        _ => return Err(run_err("the sample has no particle".into())),
    };
    if !(modulus.is_finite() && modulus > 0.0) {
        return Err(run_err(format!(
            "the soil's constrained modulus at the confining stress {sigma0} Pa is {modulus} Pa; the servo needs a stiff sample"
        )));
    }
    let size0 = sample_size(surfaces(&sim, t), d0);
    let longest = size0.iter().copied().fold(0.0, f64::max);
    let wave_speed = (modulus / density).sqrt();
    let tau = s.servo_crossings * longest / wave_speed;
    // Exchanges of a quarter sample interval: the face stresses come from the markers'
    // forces of each exchange's last step, and a record sample is the mean of its four.
    sim.system.exchange_interval = 0.25 * SAMPLE_INTERVAL;
    let window_time = tau;
    let mut servo = Servo { sigma0, modulus, tau, t_i: 4.0 * tau, integral: [0.0; 6] };
    let probe = Probe { t, d0, run_err: &run_err };
    let consolidated = consolidate(&mut sim, &mut servo, &probe, s.tolerance, window_time)?;
    let consolidation_time = sim.time();
    let size_c = sample_size(surfaces(&sim, t), d0);
    // Shear.
    let series = shear(&mut sim, &mut servo, &probe, size_c, 0.5 * s.strain_rate * size_c[2], s.max_strain)?;
    let Picks { failure, h_f, fv, fh, bulk_failure, bulk_h, face_failure, face_h } =
        pick_failures(&series, s, sigma0, &run_err)?;
    let (strain_f, v_f) = (series[failure.index].axial_strain, failure.value);
    // Particles that left the sample (through a gap between plates).
    let sf = surfaces(&sim, t);
    let f = &sim.system.fluid;
    let escaped = f
        .positions()
        .iter()
        .filter(|p| {
            let p = [p.x.as_f64(), p.y.as_f64(), p.z.as_f64()];
            (0..3).any(|a| p[a] < sf[a][0] - d0 || p[a] > sf[a][1] + d0)
        })
        .count();
    Ok(TriaxialTest {
        confining: sigma0,
        particles,
        consolidation_time,
        consolidated_stresses: consolidated,
        consolidated_size: size_c,
        servo_tau: tau,
        constrained_modulus: modulus,
        inertial_number: s.strain_rate * d0 / (sigma0 / density).sqrt(),
        failure,
        strain_at_failure: strain_f,
        vertical_at_failure: v_f,
        lateral_at_failure: h_f,
        bulk: FailureStresses {
            strain: series[bulk_failure.index].axial_strain,
            vertical: bulk_failure.value,
            lateral: bulk_h,
            kind: bulk_failure.kind,
        },
        faces: FailureStresses {
            strain: series[face_failure.index].axial_strain,
            vertical: face_failure.value,
            lateral: face_h,
            kind: face_failure.kind,
        },
        escaped,
        steps: f.steps(),
        wall_time_s: started.elapsed().as_secs_f64(),
        dir: String::new(),
        plots: Vec::new(),
        filtered: fv.into_iter().zip(fh).collect(),
        series,
    })
}

/// The sample's size along each axis (m): the span between the plates' surfaces `sf` less one
/// spacing, as every reading of the test takes it.
fn sample_size(sf: [[f64; 2]; 3], d0: f64) -> [f64; 3] {
    sf.map(|[lo, hi]| hi - lo - d0)
}

/// Free slip on every plate: the normal of each marker is its plate's inward normal. The
/// markers' pair moments are recorded (the soil's mean stresses need them).
fn free_slip_plates<T: Real>(sim: &mut Simulation<T>) -> Result<(), String> {
    let bodies = &sim.system.interface.bodies;
    if bodies.len() != 6 {
        return Err(format!("the test needs its six plates as FSI bodies, found {}", bodies.len()));
    }
    let markers = bodies.last().map_or(0, |b| b.markers.end);
    let mut normals = vec![[0.0; 3]; markers];
    for (b, (_, axis, sign)) in bodies.iter().zip(PLATES) {
        for k in b.markers.clone() {
            normals[k][axis] = -sign;
        }
    }
    let mut contact = vec![WallContact::Rough];
    contact.extend([WallContact::Smooth; 6]);
    sim.system.fluid.set_wall_contact(&contact, &normals).map_err(|e| e.to_string())?;
    sim.system.fluid.record_marker_moments().map_err(|e| e.to_string())?;
    Ok(())
}

/// The plates' servo. PI control: v = sign · L/(2 M τ) · (e + ∫e dt / T_i), e = σ − σ0. For a
/// sample of constrained modulus M the error then obeys e'' + e'/τ + e/(τ T_i) = 0, critically
/// damped at T_i = 4τ; the integral supplies the steady plate speed that a sample flowing at a
/// constant rate needs, so the lateral stress holds σ0 through the shear instead of lagging by
/// the proportional offset.
struct Servo {
    sigma0: f64,
    modulus: f64,
    tau: f64,
    t_i: f64,
    integral: [f64; 6],
}

impl Servo {
    /// Sets each plate's velocity from its face stress; with `axial`, the two z plates close
    /// at that speed instead.
    fn steer<T: Real>(
        &mut self,
        sim: &mut Simulation<T>,
        stresses: &[f64; 6],
        size: [f64; 3],
        dt: f64,
        axial: Option<f64>,
    ) {
        let bodies: Vec<_> = sim.bodies().collect();
        for (k, b) in bodies.into_iter().enumerate() {
            let (_, axis, sign) = PLATES[k];
            let v = match axial {
                Some(v) if axis == 2 => -sign * v,
                _ => {
                    let e = stresses[k] - self.sigma0;
                    self.integral[k] += e * dt;
                    sign * (e + self.integral[k] / self.t_i) * size[axis] / (2.0 * self.modulus * self.tau)
                }
            };
            let mut lin = [0.0; 3];
            lin[axis] = v;
            sim.set_body_velocity(b, lin, [0.0; 3]);
        }
    }
}

/// How an exchange is read: the plates' thickness, the spacing and the run's error.
struct Probe<'a> {
    t: f64,
    d0: f64,
    run_err: &'a dyn Fn(String) -> CommandError,
}

impl Probe<'_> {
    /// One exchange and what it reads.
    fn exchange<T: Real>(&self, sim: &mut Simulation<T>) -> Result<Reading, CommandError> {
        let t0 = sim.time();
        sim.step_max(None).map_err(|e| (self.run_err)(e.to_string()))?;
        let sf = surfaces(sim, self.t);
        let size = sample_size(sf, self.d0);
        Ok(Reading {
            size,
            faces: face_stresses(sim, sf, size, self.d0),
            dt: sim.time() - t0,
            soil: mean_stresses(sim, sf, size, self.d0),
        })
    }
}

/// Consolidation: the servo holds every face at σ0 until the faces' mean over the last
/// `window_time` is within `tolerance` of it (after two time constants at least); the mean
/// face stresses then.
fn consolidate<T: Real>(
    sim: &mut Simulation<T>,
    servo: &mut Servo,
    probe: &Probe,
    tolerance: f64,
    window_time: f64,
) -> Result<[f64; 6], CommandError> {
    let (sigma0, tau) = (servo.sigma0, servo.tau);
    let max_time = 40.0 * tau;
    let mut history: Vec<(f64, [f64; 6])> = Vec::new();
    Ok(loop {
        let Reading { size, faces: st, dt, .. } = probe.exchange(sim)?;
        history.push((sim.time(), st));
        let now = sim.time();
        let first = history.partition_point(|(time, _)| *time < now - window_time);
        let tail = &history[first..];
        let mean: [f64; 6] = std::array::from_fn(|k| tail.iter().map(|r| r.1[k]).sum::<f64>() / tail.len() as f64);
        if now > 2.0 * tau && mean.iter().all(|m| (m - sigma0).abs() <= tolerance * sigma0) {
            break mean;
        }
        if now > max_time {
            let mean: Vec<String> = mean.iter().map(|m| format!("{m:.4e}")).collect();
            return Err((probe.run_err)(format!(
                "consolidation to {sigma0} Pa did not settle within {:.0} % in {:.3} s (40 servo time constants): face stresses {} Pa",
                100.0 * tolerance,
                max_time,
                mean.join(", ")
            )));
        }
        servo.steer(sim, &st, size, dt, None);
    })
}

/// The shear: the z plates close at `v_axial` while the servo holds the sides at σ0, one
/// sample (the mean of its exchanges) per [`SAMPLE_INTERVAL`] until the axial strain reaches
/// `max_strain`.
fn shear<T: Real>(
    sim: &mut Simulation<T>,
    servo: &mut Servo,
    probe: &Probe,
    size_c: [f64; 3],
    v_axial: f64,
    max_strain: f64,
) -> Result<Vec<Sample>, CommandError> {
    let volume_c = size_c[0] * size_c[1] * size_c[2];
    let mut series = Vec::new();
    let (mut size, mut st, mut dt) = (size_c, [servo.sigma0; 6], 0.0);
    let (mut acc, mut acc_mean, mut n_acc, mut next) = ([0.0f64; 6], [0.0f64; 3], 0usize, sim.time() + SAMPLE_INTERVAL);
    loop {
        servo.steer(sim, &st, size, dt, Some(v_axial));
        let soil;
        Reading { size, faces: st, dt, soil } = probe.exchange(sim)?;
        for k in 0..6 {
            acc[k] += st[k];
        }
        for k in 0..3 {
            acc_mean[k] += soil[k];
        }
        n_acc += 1;
        if sim.time() < next - 1e-12 {
            continue;
        }
        next += SAMPLE_INTERVAL;
        let m = acc.map(|a| a / n_acc as f64);
        let mean = acc_mean.map(|a| a / n_acc as f64);
        (acc, acc_mean, n_acc) = ([0.0; 6], [0.0; 3], 0);
        let axial_strain = 1.0 - size[2] / size_c[2];
        let bulk = bulk_stresses(sim);
        series.push(Sample {
            time: sim.time(),
            axial_strain,
            volumetric_strain: 1.0 - size[0] * size[1] * size[2] / volume_c,
            vertical: mean[2],
            lateral: 0.5 * (mean[0] + mean[1]),
            face_vertical: 0.5 * (m[4] + m[5]),
            face_lateral: 0.25 * (m[0] + m[1] + m[2] + m[3]),
            bulk_vertical: bulk[0],
            bulk_lateral: bulk[1],
        });
        if axial_strain >= max_strain {
            break;
        }
    }
    Ok(series)
}

/// The failure points of the three readings (soil, bulk, faces) and the filtered soil series.
struct Picks {
    failure: Failure,
    h_f: f64,
    fv: Vec<f64>,
    fh: Vec<f64>,
    bulk_failure: Failure,
    bulk_h: f64,
    face_failure: Failure,
    face_h: f64,
}

/// Failure on the filtered series: the first peak (with `FailureRule::Peak`) or the plateau.
fn pick_failures(
    series: &[Sample],
    s: &TriaxialSettings,
    sigma0: f64,
    run_err: &dyn Fn(String) -> CommandError,
) -> Result<Picks, CommandError> {
    let de = s.strain_rate * SAMPLE_INTERVAL;
    let cutoff = 2.0 * de / s.filter_wavelength;
    let filter = LowPass::new(s.filter, s.filter_order, cutoff).map_err(|e| {
        CommandError::Input(InputError::flag(
            "--strain-rate",
            format!(
                "{e}: {} /s over a sample interval of {SAMPLE_INTERVAL} s is {de:.2e} strain per sample, too coarse for --filter-wavelength {}",
                s.strain_rate, s.filter_wavelength
            ),
        ))
    })?;
    let half = ((s.filter_wavelength / de).round() as usize).max(1);
    let floor = s.min_ratio * sigma0;
    let pick = |vertical: &dyn Fn(&Sample) -> f64, lateral: &dyn Fn(&Sample) -> f64| {
        let fv = filter.filtfilt(&series.iter().map(vertical).collect::<Vec<_>>());
        let fh = filter.filtfilt(&series.iter().map(lateral).collect::<Vec<_>>());
        let peak = match s.failure {
            FailureRule::Peak => first_peak(&fv, half, floor),
            FailureRule::Plateau => None,
        };
        let found = match peak {
            Some(i) => Some((Failure { kind: FailureKind::Peak, index: i, value: fv[i] }, fh[i])),
            None => plateau(&fv, PLATEAU_FRACTION).map(|(i, v)| {
                let h = fh[i..].iter().sum::<f64>() / (fh.len() - i) as f64;
                (Failure { kind: FailureKind::Plateau, index: i, value: v }, h)
            }),
        };
        found.map(|f| (f, fv, fh)).ok_or_else(|| run_err("the shear phase recorded no sample".into()))
    };
    let ((failure, h_f), fv, fh) = pick(&|r| r.vertical, &|r| r.lateral)?;
    let ((bulk_failure, bulk_h), _, _) = pick(&|r| r.bulk_vertical, &|r| r.bulk_lateral)?;
    let ((face_failure, face_h), _, _) = pick(&|r| r.face_vertical, &|r| r.face_lateral)?;
    Ok(Picks { failure, h_f, fv, fh, bulk_failure, bulk_h, face_failure, face_h })
}

/// What `regolith calibrate triaxial` reads.
#[derive(Clone, Debug)]
pub struct TriaxialInputs {
    /// Material file.
    pub material: PathBuf,
    /// Test settings.
    pub settings: TriaxialSettings,
    /// Output folder.
    pub out: PathBuf,
    /// Tests run at once (threads of this process).
    pub jobs: usize,
    /// Keep the tests already recorded (same material, settings and confining stress) in the
    /// output folder (per round of the φ loop) and run only the others.
    pub resume: bool,
    /// Adjust the material's friction angle until the sample's measured φ is this (degrees).
    pub target_phi: Option<f64>,
    /// The loop accepts a φ within this many degrees of the target, or within its standard
    /// error if that is larger.
    pub tolerance_phi: f64,
    /// Adjust the material's cohesion until the sample's measured c is this (Pa); with
    /// `target_phi` too, both are adjusted together.
    pub target_c: Option<f64>,
    /// The loop accepts a c within this many pascals of the target, or within its standard
    /// error if that is larger; `None`: [`C_TOLERANCE_FRACTION`] of the target, at least
    /// [`C_TOLERANCE_MIN`].
    pub tolerance_c: Option<f64>,
    /// The envelope the loop matches to the targets.
    pub matching: EnvelopeSource,
}

/// Default time constant of the plates' servo, in P-wave crossings of the sample's longest
/// side.
pub const SERVO_CROSSINGS: f64 = 3.0;

/// Default smallest tolerance of the φ loop (degrees).
pub const PHI_TOLERANCE: f64 = 0.5;

/// Default smallest tolerance of the c loop, as a fraction of the target cohesion.
pub const C_TOLERANCE_FRACTION: f64 = 0.05;

/// Default smallest tolerance of the c loop (Pa), whatever the target.
pub const C_TOLERANCE_MIN: f64 = 50.0;

/// Cohesions the c loop may try (Pa).
pub const C_RANGE: (f64, f64) = (0.0, 1e8);

/// `triaxial.json`, with AGX's field names for the envelope and the failure stresses.
#[derive(Clone, Debug, Serialize)]
pub struct TriaxialReport {
    /// "triaxial_test".
    pub test: &'static str,
    /// The material file.
    pub material: String,
    /// The material's friction angle and cohesion as typed (degrees, Pa), when it has them.
    pub material_phi: Option<f64>,
    /// The material's cohesion (Pa).
    pub material_c: Option<f64>,
    /// Measured cohesion (Pa).
    pub c: f64,
    /// Measured friction angle (degrees).
    pub phi: f64,
    /// Standard error of c (Pa); `null` with fewer than three tests.
    #[serde(rename = "standardError_c")]
    pub standard_error_c: Option<f64>,
    /// Standard error of φ (degrees).
    #[serde(rename = "standardError_phi")]
    pub standard_error_phi: Option<f64>,
    /// Friction angle of the cohesionless envelope through the origin (degrees): for a
    /// critical state (Cam Clay, `q = M p`) the angle to compare with asin(3M / (6 + M)).
    #[serde(rename = "phi_c0")]
    pub phi_cohesionless: f64,
    /// Its standard error (degrees); `null` with one test.
    #[serde(rename = "standardError_phi_c0")]
    pub standard_error_phi_cohesionless: Option<f64>,
    /// Lateral stress at failure of each test (Pa).
    #[serde(rename = "consolidationStress")]
    pub consolidation_stress: Vec<f64>,
    /// Vertical stress at failure of each test (Pa).
    #[serde(rename = "verticalStress")]
    pub vertical_stress: Vec<f64>,
    /// Axial strain at failure of each test.
    #[serde(rename = "strainAtFailure")]
    pub strain_at_failure: Vec<f64>,
    /// The envelope of the particles' own stresses at failure (the same rule on the
    /// volume-mean stresses): the soil's strength without what the plates' markers add or
    /// miss.
    pub bulk: super::Envelope,
    /// The envelope of the faces' normal force over area alone at failure (AGX's reading,
    /// which also counts the load the plates' markers pass between soil layers).
    pub faces: super::Envelope,
    /// The particles' cohesionless envelope through the origin (degrees; for Cam Clay the
    /// critical-state angle to compare with asin(3M / (6 + M))).
    #[serde(rename = "bulk_phi_c0")]
    pub bulk_phi_cohesionless: f64,
    /// Its standard error (degrees); `null` with one test.
    #[serde(rename = "bulk_standardError_phi_c0")]
    pub bulk_standard_error_phi_cohesionless: Option<f64>,
    /// The filter (AGX's `FilterParameters`): order, cutoff as a fraction of Nyquist, and the
    /// shortest strain wavelength kept.
    #[serde(rename = "FilterParameters")]
    pub filter: FilterReport,
    /// Every test.
    pub tests: Vec<TriaxialTest>,
    /// Settings.
    pub settings: TriaxialSettings,
    /// Plots written.
    pub plots: Vec<String>,
    /// The one-parameter calibration loop (`--target-phi` or `--target-c` alone).
    pub calibration: Option<TargetRun>,
    /// The material key that loop adjusted (`friction_angle` or `cohesion`).
    pub calibration_parameter: Option<&'static str>,
    /// The joint loop (`--target-phi` with `--target-c`).
    pub joint_calibration: Option<JointRun>,
    /// The envelope the loop matched (`null` without a loop).
    pub calibration_envelope: Option<EnvelopeSource>,
    /// The calibrated material file, when the loop converged.
    pub calibrated_material: Option<String>,
}

/// The filter's parameters as reported.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct FilterReport {
    /// "gaussian" or "butterworth".
    pub filter: FilterKind,
    /// Butterworth order (`null` for a Gaussian).
    pub filter_order: Option<usize>,
    /// Cutoff, fraction of the Nyquist frequency of the per-exchange record.
    pub critical_frequency: f64,
    /// Shortest wavelength kept, axial strain.
    pub wavelength_strain: f64,
    /// A peak counts only above this multiple of the confining stress.
    pub min_vert_stress_to_cons_stress_ratio: f64,
    /// "peak" or "plateau".
    pub failure_rule: FailureRule,
}

/// The material's `model` key.
fn model(m: &toml::Table) -> Option<&str> {
    m.get("model").and_then(|v| v.as_str())
}

fn number(m: &toml::Table, key: &str) -> Option<f64> {
    m.get(key).and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
}

/// The tests of one envelope (one per confining stress), as tasks of the shared runner
/// ([`crate::runner::run_tasks`]): each records its [`TriaxialTest`] in the folder's
/// `results.jsonl`, so a rerun with `resume` runs only the tests not yet recorded, and the
/// Python package's Ray runner can schedule them one Ray task each.
#[derive(Clone, Debug)]
pub struct TriaxialPlan {
    /// The folder: `test_NN/` per test, `results.jsonl`.
    pub dir: PathBuf,
    /// The tests, in the order of the confining stresses.
    pub tests: Vec<TestTask>,
}

/// One test of a [`TriaxialPlan`].
#[derive(Clone, Debug)]
pub struct TestTask {
    index: usize,
    id: String,
    /// Its confining stress (Pa).
    pub confining: f64,
    material: toml::Table,
    settings: TriaxialSettings,
}

/// What a test's record means, in its id: a record of an older meaning (the faces' stresses
/// as the main reading, before session 17) gets another id, so `--resume` runs its test again
/// instead of mixing readings in one envelope.
const RECORD_FORMAT: &str = "triaxial record 2: soil's load, faces, bulk";

impl TriaxialPlan {
    /// One test per confining stress of `s`, on `material`, in `dir`.
    pub fn new(material: &toml::Table, s: &TriaxialSettings, dir: &Path) -> Result<Self, CommandError> {
        let settings = serde_json::to_string(s).map_err(|e| CommandError::Run(format!("settings: {e}")))?;
        let material_text = material.to_string();
        let tests = s
            .confining
            .iter()
            .enumerate()
            .map(|(index, &confining)| TestTask {
                index,
                id: fnv_id(&[
                    material_text.as_bytes(),
                    settings.as_bytes(),
                    &confining.to_bits().to_le_bytes(),
                    env!("CARGO_PKG_VERSION").as_bytes(),
                    RECORD_FORMAT.as_bytes(),
                ]),
                confining,
                material: material.clone(),
                settings: s.clone(),
            })
            .collect();
        Ok(Self { dir: dir.to_path_buf(), tests })
    }

    /// Every test's recorded result, in order, and the envelope through them. A test that
    /// failed or has no record is an error naming its confining stress.
    pub fn finish(&self) -> Result<(Vec<TriaxialTest>, MohrCoulomb), CommandError> {
        let records = read_all(&self.dir)?;
        let mut tests = Vec::new();
        let mut missing = Vec::new();
        for t in &self.tests {
            let why = match records.iter().find(|r| r.id == t.id) {
                Some(r) if r.ok() => match r.summary.clone().map(serde_json::from_value::<TriaxialTest>) {
                    Some(Ok(test)) => {
                        tests.push(test);
                        continue;
                    }
                    _ => "its record holds no result".to_string(),
                },
                Some(r) => r.error.clone().unwrap_or_else(|| "failed".into()),
                None => "not run".into(),
            };
            missing.push(format!("σ3 = {:.4e} Pa: {why}", t.confining));
        }
        if !missing.is_empty() {
            return Err(CommandError::Run(format!("triaxial tests not carried out: {}", missing.join("; "))));
        }
        let s3: Vec<f64> = tests.iter().map(|t| t.lateral_at_failure).collect();
        let s1: Vec<f64> = tests.iter().map(|t| t.vertical_at_failure).collect();
        let fit = mohr_coulomb(&s3, &s1).map_err(|e| {
            CommandError::Run(format!("the failure stresses σ3 = {s3:?} Pa, σ1 = {s1:?} Pa give no envelope: {e}"))
        })?;
        Ok((tests, fit))
    }
}

impl Task for TestTask {
    fn index(&self) -> usize {
        self.index
    }
    fn id(&self) -> &str {
        &self.id
    }
    fn label(&self) -> String {
        format!("test {} (σ3 = {:.4e} Pa)", self.index + 1, self.confining)
    }
    fn run(&self, out: &Path, _alone: bool) -> Record {
        let start = Instant::now();
        let name = format!("test_{:02}", self.index + 1);
        let mut rec = Record {
            point: self.index,
            id: self.id.clone(),
            status: "failed".into(),
            overrides: [("confining".to_string(), serde_json::json!(self.confining))].into_iter().collect(),
            wall_s: 0.0,
            peak_mem_bytes: None,
            error: None,
            out: name.clone(),
            summary: None,
        };
        match run_test(&self.material, &self.settings, self.confining, &out.join(&name)) {
            Ok(t) => {
                eprintln!(
                    "  σ3 = {:.4e} Pa: failure ({:?}) at σ1 = {:.4e} Pa, σ3 = {:.4e} Pa, axial strain {:.4} ({:.1} s)",
                    self.confining,
                    t.failure.kind,
                    t.vertical_at_failure,
                    t.lateral_at_failure,
                    t.strain_at_failure,
                    t.wall_time_s
                );
                match serde_json::to_value(&t) {
                    Ok(v) => {
                        rec.status = "ok".into();
                        rec.summary = Some(v);
                    }
                    Err(e) => rec.error = Some(format!("its result does not serialise: {e}")),
                }
            }
            Err(e) => rec.error = Some(crate::input::report(&e)),
        }
        rec.wall_s = start.elapsed().as_secs_f64();
        rec
    }
}

/// Runs the tests of one envelope (those not yet recorded, with `resume`) on `jobs` threads,
/// and fits the envelope.
fn run_all(
    material: &toml::Table,
    s: &TriaxialSettings,
    out: &Path,
    jobs: usize,
    resume: bool,
) -> Result<(Vec<TriaxialTest>, MohrCoulomb), CommandError> {
    let plan = TriaxialPlan::new(material, s, out)?;
    if !resume {
        forget(out)?;
    }
    run_tasks("triaxial", &plan.tests, out, None, jobs, true, true)?;
    plan.finish()
}

/// Runs the tests, fits the envelope and writes `triaxial.json`, per test `test_NN/` with its
/// scene, `series.csv` and the stress–strain plot, and the Mohr-circle plot. With a target φ,
/// runs the calibration loop over the material's friction angle (each round in
/// `iteration_<k>/`) and writes `material.toml` when it converges.
pub fn calibrate_triaxial(inp: &TriaxialInputs) -> Result<TriaxialReport, CommandError> {
    let s = &inp.settings;
    s.check().map_err(|(flag, msg)| CommandError::Input(InputError::flag(flag, msg)))?;
    if inp.jobs == 0 {
        return Err(InputError::flag("--jobs", "0 tests at once runs nothing; allowed: 1 or more").into());
    }
    let material = material_table(&inp.material)?;
    if inp.target_phi.is_none() && inp.target_c.is_none() {
        let (tests, fit) = run_all(&material, s, &inp.out, inp.jobs, inp.resume)?;
        return report(inp, &inp.out, &material, tests, fit, Calibration::None, None);
    }
    let targets = Targets::check(inp, &material)?;
    // One round: the tests of one material in `iteration_<k>/`.
    let mut last = None;
    let mut k = 0;
    let mut round = |set: &[(&'static str, f64)]| -> Result<MohrCoulomb, CommandError> {
        k += 1;
        let mut m = material.clone();
        for (key, v) in set {
            m.insert((*key).into(), (*v).into());
        }
        let dir = inp.out.join(format!("iteration_{k}"));
        let (tests, fit) = run_all(&m, s, &dir, inp.jobs, inp.resume)?;
        let measured = match inp.matching {
            EnvelopeSource::Plates => fit,
            EnvelopeSource::Particles => {
                let (b3, b1): (Vec<f64>, Vec<f64>) = tests.iter().map(|t| (t.bulk.lateral, t.bulk.vertical)).unzip();
                mohr_coulomb(&b3, &b1)
                    .map_err(|e| CommandError::Run(format!("the particles' failure stresses give no envelope: {e}")))?
            }
        };
        let typed: Vec<String> = set.iter().map(|(key, v)| format!("{key} = {v:.4}")).collect();
        eprintln!(
            "  {}: sample φ = {:.2}° ± {:.2}°, c = {:.1} ± {:.1} Pa (on {})",
            typed.join(", "),
            measured.phi,
            measured.se_phi.unwrap_or(0.0),
            measured.c,
            measured.se_c.unwrap_or(0.0),
            inp.matching.describe()
        );
        last = Some((m, tests, fit, dir));
        Ok(measured)
    };
    let on = inp.matching.describe();
    let why = |what: &str| {
        format!(
            "`regolith calibrate triaxial {what}`: set so that the SPH sample's\n# triaxial envelope on {on} meets the target (see triaxial.json)"
        )
    };
    let (calibration, written) = match targets {
        Targets::Joint { phi, c, tolerance_c, start } => {
            let settings = JointSettings {
                parameters: ["friction_angle", "cohesion"],
                target: [phi, c],
                tolerance_floor: [inp.tolerance_phi, tolerance_c],
                range: [super::repose::PHI_RANGE, C_RANGE],
                max_evaluations: super::repose::MAX_EVALUATIONS,
            };
            let run = calibrate_jointly(&settings, start, |p| {
                let fit = round(&[("friction_angle", p[0]), ("cohesion", p[1])])?;
                Ok::<_, CommandError>(([fit.phi, fit.c], [fit.se_phi.unwrap_or(0.0), fit.se_c.unwrap_or(0.0)]))
            })?;
            let written = match &run.converged {
                Some(p) => Some(write_calibrated(
                    &inp.material,
                    &[("friction_angle", p[0]), ("cohesion", p[1])],
                    &why(&format!("--target-phi {phi} --target-c {c}")),
                    &inp.out.join("material.toml"),
                )?),
                None => None,
            };
            (Calibration::Joint(run), written)
        }
        Targets::One { key, target, tolerance, range, start } => {
            let settings = TargetSettings {
                target,
                tolerance_floor: tolerance,
                range,
                max_evaluations: super::repose::MAX_EVALUATIONS,
            };
            let is_phi = key == "friction_angle";
            let run = calibrate_to_target(&settings, start, |v| {
                let fit = round(&[(key, v)])?;
                Ok::<_, CommandError>(if is_phi {
                    (fit.phi, fit.se_phi.unwrap_or(0.0))
                } else {
                    (fit.c, fit.se_c.unwrap_or(0.0))
                })
            })?;
            let flag = if is_phi { "--target-phi" } else { "--target-c" };
            let written = match run.converged {
                Some(v) => Some(write_calibrated(
                    &inp.material,
                    &[(key, v)],
                    &why(&format!("{flag} {target}")),
                    &inp.out.join("material.toml"),
                )?),
                None => None,
            };
            (Calibration::One(key, run), written)
        }
    };
    let Some((m, tests, fit, dir)) = last else {
        return Err(CommandError::Run(format!("{}: the calibration loop ran no test", inp.material.display())));
    };
    report(inp, &dir, &m, tests, fit, calibration, written)
}

/// What a calibration asks for, checked.
enum Targets {
    /// One key.
    One { key: &'static str, target: f64, tolerance: f64, range: (f64, f64), start: f64 },
    /// φ and c together.
    Joint { phi: f64, c: f64, tolerance_c: f64, start: [f64; 2] },
}

impl Targets {
    fn check(inp: &TriaxialInputs, material: &toml::Table) -> Result<Self, CommandError> {
        let flags = match (inp.target_phi, inp.target_c) {
            (Some(_), Some(_)) => "--target-phi and --target-c need",
            (Some(_), None) => "--target-phi needs",
            _ => "--target-c needs",
        };
        if inp.settings.confining.len() < 3 {
            return Err(InputError::flag(
                "--confining",
                format!("{flags} at least three confining stresses (the loop uses the envelope's standard errors)"),
            )
            .into());
        }
        if let Some(t) = inp.target_phi {
            if !(t.is_finite() && t > 0.0 && t < 90.0) {
                return Err(
                    InputError::flag("--target-phi", format!("must be between 0 and 90 degrees (got {t})")).into()
                );
            }
            if !(inp.tolerance_phi.is_finite() && inp.tolerance_phi > 0.0) {
                return Err(InputError::flag(
                    "--tolerance",
                    format!("must be > 0 degrees (got {})", inp.tolerance_phi),
                )
                .into());
            }
        }
        let phi0 = || {
            number(material, "friction_angle").ok_or_else(|| {
                CommandError::from(InputError::key(
                    &inp.material,
                    "friction_angle",
                    "is needed for --target-phi: the loop adjusts it",
                ))
            })
        };
        let Some(c) = inp.target_c else {
            let target = inp.target_phi.unwrap_or_default();
            return Ok(Self::One {
                key: "friction_angle",
                target,
                tolerance: inp.tolerance_phi,
                range: super::repose::PHI_RANGE,
                start: phi0()?,
            });
        };
        if !(c.is_finite() && c >= 0.0 && c <= C_RANGE.1) {
            return Err(
                InputError::flag("--target-c", format!("must be between 0 and {:e} Pa (got {c})", C_RANGE.1)).into()
            );
        }
        let tolerance_c = inp.tolerance_c.unwrap_or((C_TOLERANCE_FRACTION * c).max(C_TOLERANCE_MIN));
        if !(tolerance_c.is_finite() && tolerance_c > 0.0) {
            return Err(InputError::flag("--tolerance-c", format!("must be > 0 Pa (got {tolerance_c})")).into());
        }
        let model = model(material).unwrap_or("");
        if model != "drucker-prager" {
            return Err(InputError::key(
                &inp.material,
                "model",
                format!("is \"{model}\"; --target-c adjusts `cohesion`, a key of drucker-prager materials only"),
            )
            .into());
        }
        // A cohesionless material starts at the target (a proportional step needs c > 0).
        let c0 = number(material, "cohesion").filter(|v| *v > 0.0).unwrap_or(c.max(tolerance_c));
        Ok(match inp.target_phi {
            Some(phi) => Self::Joint { phi, c, tolerance_c, start: [phi0()?, c0] },
            None => Self::One { key: "cohesion", target: c, tolerance: tolerance_c, range: C_RANGE, start: c0 },
        })
    }
}

/// The calibration a report carries.
enum Calibration {
    None,
    One(&'static str, TargetRun),
    Joint(JointRun),
}

/// The envelope of tests already run and recorded in `inp.out` (by the Ray runner, say):
/// fits it and writes `triaxial.json` and the Mohr-circle plot, as [`calibrate_triaxial`] does
/// after running them. A test without a finished record is an error naming it.
pub fn envelope_of_recorded(inp: &TriaxialInputs) -> Result<TriaxialReport, CommandError> {
    let material = material_table(&inp.material)?;
    let (tests, fit) = TriaxialPlan::new(&material, &inp.settings, &inp.out)?.finish()?;
    report(inp, &inp.out, &material, tests, fit, Calibration::None, None)
}

fn report(
    inp: &TriaxialInputs,
    dir: &Path,
    material: &toml::Table,
    tests: Vec<TriaxialTest>,
    fit: MohrCoulomb,
    calibration: Calibration,
    calibrated_material: Option<String>,
) -> Result<TriaxialReport, CommandError> {
    let (calibration, calibration_parameter, joint_calibration) = match calibration {
        Calibration::None => (None, None, None),
        Calibration::One(key, run) => (Some(run), Some(key), None),
        Calibration::Joint(run) => (None, None, Some(run)),
    };
    let s = &inp.settings;
    let out_err = |e: String| CommandError::Output(e);
    let mut plots: Vec<PathBuf> = tests.iter().flat_map(|t| t.plots.iter().map(PathBuf::from)).collect();
    let s3: Vec<f64> = tests.iter().map(|t| t.lateral_at_failure).collect();
    let s1: Vec<f64> = tests.iter().map(|t| t.vertical_at_failure).collect();
    plots.extend(write_figure(&super::mohr_figure(&s3, &s1, &fit), dir, "mohr").map_err(|e| out_err(e.to_string()))?);
    let (phi0, se_phi0) = mohr_coulomb_cohesionless(&s3, &s1).map_err(|e| {
        CommandError::Run(format!("the failure stresses σ3 = {s3:?} Pa, σ1 = {s1:?} Pa give no envelope: {e}"))
    })?;
    let envelope_of = |what: &str, failure: &dyn Fn(&TriaxialTest) -> FailureStresses| {
        let (s3, s1): (Vec<f64>, Vec<f64>) = tests.iter().map(|t| (failure(t).lateral, failure(t).vertical)).unzip();
        let no_envelope = |e: super::fit::FitError| {
            CommandError::Run(format!("{what} failure stresses σ3 = {s3:?} Pa, σ1 = {s1:?} Pa give no envelope: {e}"))
        };
        let through_origin = mohr_coulomb_cohesionless(&s3, &s1).map_err(no_envelope)?;
        let (e, _) = super::Envelope::fit(&s3, &s1).map_err(no_envelope)?;
        Ok::<_, CommandError>((e, through_origin))
    };
    let (bulk, (bulk_phi0, bulk_se_phi0)) = envelope_of("the particles'", &|t| t.bulk)?;
    let (faces, _) = envelope_of("the faces'", &|t| t.faces)?;
    let de = s.strain_rate * SAMPLE_INTERVAL;
    let report = TriaxialReport {
        test: "triaxial_test",
        material: inp.material.display().to_string(),
        material_phi: number(material, "friction_angle"),
        material_c: number(material, "cohesion"),
        c: fit.c,
        phi: fit.phi,
        standard_error_c: fit.se_c,
        standard_error_phi: fit.se_phi,
        phi_cohesionless: phi0,
        standard_error_phi_cohesionless: se_phi0,
        consolidation_stress: s3,
        vertical_stress: s1,
        strain_at_failure: tests.iter().map(|t| t.strain_at_failure).collect(),
        bulk,
        faces,
        bulk_phi_cohesionless: bulk_phi0,
        bulk_standard_error_phi_cohesionless: bulk_se_phi0,
        filter: FilterReport {
            filter: s.filter,
            filter_order: (s.filter == FilterKind::Butterworth).then_some(s.filter_order),
            critical_frequency: 2.0 * de / s.filter_wavelength,
            wavelength_strain: s.filter_wavelength,
            min_vert_stress_to_cons_stress_ratio: s.min_ratio,
            failure_rule: s.failure,
        },
        tests,
        settings: s.clone(),
        plots: plots.iter().map(|p| p.display().to_string()).collect(),
        calibration_envelope: (calibration.is_some() || joint_calibration.is_some()).then_some(inp.matching),
        calibration,
        calibration_parameter,
        joint_calibration,
        calibrated_material,
    };
    std::fs::create_dir_all(&inp.out).map_err(|e| out_err(format!("cannot create {}: {e}", inp.out.display())))?;
    let json = inp.out.join("triaxial.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| out_err(e.to_string()))?;
    std::fs::write(&json, text).map_err(|e| out_err(format!("cannot write {}: {e}", json.display())))?;
    Ok(report)
}

/// Vertical and lateral stress against axial strain, raw and filtered, with the failure point.
pub fn stress_strain_figure(t: &TriaxialTest) -> Figure {
    let e: Vec<f64> = t.series.iter().map(|r| r.axial_strain).collect();
    let pts = |f: &dyn Fn(usize) -> f64| e.iter().enumerate().map(|(i, x)| (*x, f(i))).collect::<Vec<_>>();
    Figure {
        panels: vec![Panel {
            title: format!("triaxial test, confining {:.3e} Pa", t.confining),
            x_label: "axial strain".into(),
            y_label: "stress (Pa)".into(),
            x_log: false,
            y_log: false,
            series: vec![
                Series::points("vertical, soil's load", pts(&|i| t.series[i].vertical)),
                Series::points("lateral, soil's load", pts(&|i| t.series[i].lateral)),
                Series::line("vertical, filtered", pts(&|i| t.filtered[i].0)),
                Series::line("lateral, filtered", pts(&|i| t.filtered[i].1)),
                Series::line("vertical, faces alone", pts(&|i| t.series[i].face_vertical)),
                Series::line("vertical, particles' mean", pts(&|i| t.series[i].bulk_vertical)),
                Series::line("lateral, particles' mean", pts(&|i| t.series[i].bulk_lateral)),
                Series::points(
                    format!("failure ({:?}): σ1 = {:.3e} Pa", t.failure.kind, t.vertical_at_failure),
                    vec![(t.strain_at_failure, t.vertical_at_failure)],
                ),
            ],
            x_range: None,
            y_range: None,
        }],
    }
}
