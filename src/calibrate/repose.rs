//! The static angle of repose of the discretised soil: the lifted hollow-cylinder test.
//!
//! A column of soil stands on a base disc inside a hollow cylinder of the same radius. The
//! cylinder is lifted at constant speed; the soil runs out under it, what falls off the base
//! leaves the domain below (a sink: the container has no walls), and the pile left on the base
//! relaxes. The pile is then analysed as in AGX's test: `n_slices` vertical half-planes at
//! azimuths `ψ_i = i · 360°/n_slices`, on each `n_cells` vertical cylindrical cells of radius
//! `R_cell` centred at `r_j = j R_b / (n_cells + 1)`; per cell the highest particle; per slice
//! a least-squares line of z on r over the cells on the slope, whose arctangent is that slice's
//! angle; the mean, standard deviation, minimum and maximum over the slices.
//!
//! Departures from a DEM test, stated: the soil starts as a column in its geostatic state
//! (there is no emission phase: an SPH continuum is not poured grain by grain); the base is a
//! rough wall (the soil holds to it as to itself, like AGX's base with the particle–particle
//! contact); the cylinder is a smooth wall (free slip, as AGX's zero-friction cylinder).
//!
//! Which cells count: those whose highest particle lies more than 1.5 d0 above the base (a
//! cell holding only the bottom layer is bare base, not slope). Otherwise AGX's rule: every
//! cell of the slice, apex included. A slice needs three such cells for a line. The column is
//! 2 R tall by default: a squat column (h/R < 1.7, Lube et al. 2004) collapses to a truncated
//! cone whose flat crest would flatten the fitted line.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::CommandError;
use super::fit::{FitError, line};
use super::target::{TargetRun, TargetSettings, calibrate_to_target, material_table, write_calibrated};
use crate::input::InputError;
use crate::output::plot::{Figure, Panel, Series};
use crate::output::write_figure;
use crate::scene::{Precision, load_scene};
use crate::sim::Simulation;
use regolith_fsi::Real;
use regolith_fsi::config::WallContact;

/// Scene keys the test sets from its own flags or builds itself, which `--set` may not
/// change (the analysis would not follow): key and where it comes from.
const OWN_KEYS: [(&str, &str); 6] = [
    ("sph.spacing", "--spacing"),
    ("simulation.precision", "--precision"),
    ("materials", "the material file (--material)"),
    ("container", "--radius and --height"),
    ("soil_blocks", "--radius and --height"),
    ("bodies", "--radius, --height and --lift-speed"),
];

/// Segments of the cylinder's polygonal mesh.
const TUBE_SEGMENTS: usize = 48;

/// Settings of the test (the command's flags).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReposeSettings {
    /// Radius of the base disc and inner radius of the cylinder, R_b (m).
    pub radius: f64,
    /// Height of the soil column (m).
    pub height: f64,
    /// Particle spacing d0 (m).
    pub spacing: f64,
    /// Lifting speed of the cylinder (m/s).
    pub lift_speed: f64,
    /// Longest time the pile relaxes after the cylinder has cleared it (s); it stops earlier
    /// once the pile is at rest (see [`ReposeSettings::rest_speed`]).
    pub relax_time: f64,
    /// Slices of the analysis.
    pub slices: usize,
    /// Cells per slice.
    pub cells: usize,
    /// Cell radius R_cell (m).
    pub cell_radius: f64,
    /// Precision of the run.
    #[serde(serialize_with = "precision_name")]
    pub precision: Precision,
    /// Overrides of the test's scene keys (`--set`), applied after the command writes it.
    #[serde(serialize_with = "sets_text")]
    pub sets: Vec<(String, toml::Value)>,
}

fn sets_text<S: serde::Serializer>(sets: &[(String, toml::Value)], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(sets.iter().map(|(k, v)| format!("{k}={v}")))
}

fn precision_name<S: serde::Serializer>(p: &Precision, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(p.name())
}

impl ReposeSettings {
    /// The defaults for a base of radius `radius`: d0 = R/15 (AGX recommends a base radius of
    /// at least 30 particle radii), a column 2 R high (it collapses to a cone with an apex),
    /// lifted at 0.1 m/s, relaxed until at rest or for at most 3 s; 20 slices × 15 cells of
    /// radius d0.
    pub fn for_radius(radius: f64) -> Self {
        let spacing = radius / 15.0;
        Self {
            radius,
            height: 2.0 * radius,
            spacing,
            lift_speed: 0.1,
            relax_time: 3.0,
            slices: 20,
            cells: 15,
            cell_radius: spacing,
            precision: Precision::F32,
            sets: Vec::new(),
        }
    }

    /// Checks the settings; the error names the flag and what is allowed.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        use super::positive;
        positive("--radius", self.radius)?;
        positive("--height", self.height)?;
        positive("--spacing", self.spacing)?;
        positive("--lift-speed", self.lift_speed)?;
        positive("--cell-radius", self.cell_radius)?;
        if !(self.relax_time.is_finite() && self.relax_time >= 0.0) {
            return Err(("--relax-time", format!("must be a finite number ≥ 0 s (got {})", self.relax_time)));
        }
        if self.radius < 4.0 * self.spacing || self.height < 4.0 * self.spacing {
            return Err((
                "--spacing",
                format!(
                    "{} m leaves fewer than 4 spacings across the radius ({} m) or the height ({} m); use ≤ {} m",
                    self.spacing,
                    self.radius,
                    self.height,
                    self.radius.min(self.height) / 4.0
                ),
            ));
        }
        if self.slices == 0 {
            return Err(("--slices", "must be at least 1".into()));
        }
        if self.cells < 3 {
            return Err(("--cells", format!("must be at least 3 (a line needs three cells; got {})", self.cells)));
        }
        for (key, _) in &self.sets {
            let own_key =
                |own: &str| key.strip_prefix(own).is_some_and(|rest| rest.is_empty() || rest.starts_with(['.', '[']));
            if let Some((own, flag)) = OWN_KEYS.iter().find(|(own, _)| own_key(own)) {
                return Err(("--set", format!("`{key}` is the test's own ({own}): set it with {flag}, not --set")));
            }
        }
        Ok(())
    }

    /// Time the cylinder takes to clear the column (its lower rim two spacings above the
    /// column's top), s.
    pub fn lift_time(&self) -> f64 {
        (self.height + 2.0 * self.spacing) / self.lift_speed
    }
}

/// One slice's fit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SliceFit {
    /// Azimuth ψ (degrees).
    pub psi_deg: f64,
    /// The angle of repose of the slice (degrees); `None` with fewer than three cells on the
    /// slope.
    pub angle_deg: Option<f64>,
    /// Its standard error from the line fit (degrees).
    pub se_deg: Option<f64>,
    /// (r, z) of the highest particle of each cell on the slope (m; r from the axis, z above
    /// the base).
    pub tops: Vec<[f64; 2]>,
    /// Index of the selected particle of each of those cells (into the analysed points).
    #[serde(skip)]
    pub selected: Vec<usize>,
    /// Fitted line z = intercept + slope r, when there is one.
    #[serde(skip)]
    pub line: Option<(f64, f64)>,
}

/// The analysis of a pile.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PileAnalysis {
    /// Mean angle over the slices with a fit (degrees).
    pub mean_deg: f64,
    /// Standard deviation of the slices' angles (degrees; 0 with one slice).
    pub std_deg: f64,
    /// Smallest slice angle (degrees).
    pub min_deg: f64,
    /// Largest slice angle (degrees).
    pub max_deg: f64,
    /// Height of the pile's highest particle above the base (m).
    pub top_z: f64,
    /// Per slice.
    pub slices: Vec<SliceFit>,
}

/// Why a pile has no angle.
#[derive(Debug, thiserror::Error)]
pub enum PileError {
    /// No slice had three cells on the slope.
    #[error(
        "no slice has three cells on the slope ({points} particles on the base, highest {top:.4} m above it): the pile is flat or gone; use a finer --spacing or a taller --height"
    )]
    NoSlope {
        /// Particles analysed.
        points: usize,
        /// Height of the highest (m).
        top: f64,
    },
    /// A line fit failed.
    #[error("slice at {psi:.1}°: {source}")]
    Fit {
        /// Azimuth (degrees).
        psi: f64,
        /// Why.
        source: FitError,
    },
}

/// Analyses a pile: `points` are particle centres relative to the centre of the base's top
/// face (z up), `base_radius` R_b, `spacing` d0 (which cells count as slope, see the module).
pub fn analyse_pile(
    points: &[[f64; 3]],
    base_radius: f64,
    spacing: f64,
    slices: usize,
    cells: usize,
    cell_radius: f64,
) -> Result<PileAnalysis, PileError> {
    let top_z = points.iter().map(|p| p[2]).fold(f64::NEG_INFINITY, f64::max);
    let r2 = cell_radius * cell_radius;
    let mut fits = Vec::with_capacity(slices);
    for i in 0..slices {
        let psi = i as f64 * 360.0 / slices as f64;
        let (s, c) = psi.to_radians().sin_cos();
        let mut tops = Vec::new();
        let mut selected = Vec::new();
        for j in 1..=cells {
            let rj = j as f64 * base_radius / (cells + 1) as f64;
            let (cx, cy) = (rj * c, rj * s);
            let best = points
                .iter()
                .enumerate()
                .filter(|(_, p)| (p[0] - cx).powi(2) + (p[1] - cy).powi(2) <= r2)
                .max_by(|a, b| a.1[2].total_cmp(&b.1[2]));
            if let Some((k, p)) = best
                && p[2] > 1.5 * spacing
                && !selected.contains(&k)
            {
                tops.push([(p[0] * p[0] + p[1] * p[1]).sqrt(), p[2]]);
                selected.push(k);
            }
        }
        let (angle_deg, se_deg, fitted) = if tops.len() >= 3 {
            let r: Vec<f64> = tops.iter().map(|t| t[0]).collect();
            let z: Vec<f64> = tops.iter().map(|t| t[1]).collect();
            match line(&r, &z) {
                Ok(l) => {
                    // θ = atan(−b); dθ/db = −1/(1 + b²).
                    let angle = (-l.slope).atan().to_degrees();
                    let se = l.se_slope.map(|se| (se / (1.0 + l.slope * l.slope)).to_degrees());
                    (Some(angle), se, Some((l.intercept, l.slope)))
                }
                // The cells' tops stand on one radius: no slope in this slice.
                Err(FitError::Degenerate) => (None, None, None),
                Err(source) => return Err(PileError::Fit { psi, source }),
            }
        } else {
            (None, None, None)
        };
        fits.push(SliceFit { psi_deg: psi, angle_deg, se_deg, tops, selected, line: fitted });
    }
    let angles: Vec<f64> = fits.iter().filter_map(|f| f.angle_deg).collect();
    if angles.is_empty() {
        return Err(PileError::NoSlope { points: points.len(), top: top_z });
    }
    let n = angles.len() as f64;
    let mean = angles.iter().sum::<f64>() / n;
    let std = if angles.len() > 1 {
        (angles.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    Ok(PileAnalysis {
        mean_deg: mean,
        std_deg: std,
        min_deg: angles.iter().copied().fold(f64::INFINITY, f64::min),
        max_deg: angles.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        top_z,
        slices: fits,
    })
}

/// A closed, outward-oriented polygonal tube (OBJ text): inner faces tangent to the circle of
/// radius `inner`, outer ones to `outer`, from z = 0 to z = `height`, `n` segments.
pub fn tube_obj(inner: f64, outer: f64, height: f64, n: usize) -> String {
    let k = 1.0 / (std::f64::consts::PI / n as f64).cos();
    let mut s = String::from("# hollow cylinder of regolith calibrate repose\n");
    // Vertices: outer bottom, outer top, inner bottom, inner top, each n around.
    for (r, z) in [(outer, 0.0), (outer, height), (inner, 0.0), (inner, height)] {
        for i in 0..n {
            let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
            s.push_str(&format!("v {} {} {}\n", r * k * t.cos(), r * k * t.sin(), z));
        }
    }
    let (ob, ot, ib, it) = (1, 1 + n, 1 + 2 * n, 1 + 3 * n);
    for i in 0..n {
        let j = (i + 1) % n;
        for f in [
            [ob + i, ob + j, ot + j],
            [ob + i, ot + j, ot + i],
            [ib + i, it + j, ib + j],
            [ib + i, it + i, it + j],
            [it + i, ot + i, ot + j],
            [it + i, ot + j, it + j],
            [ib + i, ob + j, ob + i],
            [ib + i, ib + j, ob + j],
        ] {
            s.push_str(&format!("f {} {} {}\n", f[0], f[1], f[2]));
        }
    }
    s
}

/// The scene of the test: the material (a table read from the material file, renamed "soil"),
/// the column, the base disc, the cylinder (`tube.obj` beside the scene) and an open container.
pub fn scene_text(material: &toml::Table, s: &ReposeSettings) -> Result<String, CommandError> {
    let d0 = s.spacing;
    // Whole spacings, so that the lattice puts a layer of soil one spacing above the base.
    let snap = |x: f64| (x / d0).ceil() * d0;
    let half = snap(s.radius + 4.0 * d0);
    let mut mat = material.clone();
    mat.insert("name".into(), toml::Value::String("soil".into()));
    let mut materials = toml::Table::new();
    materials.insert("materials".into(), toml::Value::Array(vec![toml::Value::Table(mat)]));
    let materials = toml::to_string(&materials)
        .map_err(|e| CommandError::Output(format!("cannot write the test's material section: {e}")))?;
    let base_thickness = 2.0 * d0;
    let tube_height = s.height + 2.0 * d0;
    Ok(format!(
        "# regolith calibrate repose: the lifted hollow-cylinder test (written by the command;\n\
         # `regolith run` runs it as it ran, except the cylinder's smooth contact, which the\n\
         # command sets).\n\
         [simulation]\n\
         end_time = {end}\n\
         precision = \"{prec}\"\n\n\
         [sph]\n\
         spacing = {d0}\n\n\
         {materials}\n\
         [container]\n\
         min = [{m}, {m}, {zmin}]\n\
         max = [{half}, {half}, {zmax}]\n\
         walls = false\n\n\
         [[soil_blocks]]\n\
         material = \"soil\"\n\
         shape = \"cylinder\"\n\
         base_center = [0.0, 0.0, 0.0]\n\
         radius = {rs}\n\
         height = {h}\n\n\
         [[bodies]]\n\
         name = \"base\"\n\
         shape = {{ type = \"cylinder\", radius = {rb}, length = {bt}, axis = \"z\" }}\n\
         position = [0.0, 0.0, {bz}]\n\
         motion = {{ type = \"fixed\" }}\n\
         mass = 1.0\n\n\
         [[bodies]]\n\
         name = \"cylinder\"\n\
         shape = {{ type = \"mesh\", file = \"tube.obj\" }}\n\
         position = [0.0, 0.0, 0.0]\n\
         motion = {{ type = \"prescribed\", linear_velocity = [0.0, 0.0, {v}] }}\n\
         mass = 1.0\n\n\
         [output]\n\
         mcap = false\n",
        end = s.lift_time() + s.relax_time,
        prec = s.precision.name(),
        d0 = d0,
        materials = materials,
        m = -half,
        half = half,
        zmin = -snap(base_thickness + 2.0 * d0),
        zmax = snap(tube_height + 2.0 * d0),
        rs = s.radius - 0.75 * d0,
        h = s.height,
        rb = s.radius,
        bt = base_thickness,
        bz = -0.5 * base_thickness,
        v = s.lift_speed,
    ) + &format!("# cylinder: inner radius {} m, wall {} m, height {} m\n", s.radius, 2.0 * d0, tube_height))
}

/// Where the soil ended.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PileRun {
    /// Particles at the start.
    pub particles: usize,
    /// On the base at the end (the pile): above it and within d0 of its rim.
    pub on_base: usize,
    /// Fallen past the base's rim to below its top (into the sink, or on the way to it).
    pub sunk: usize,
    /// Beyond the rim but still above the base's top: falling off at the end.
    pub falling: usize,
    /// Below the base's top but inside its rim: through the base (a leak; 0 in a good test).
    pub through_base: usize,
    /// Above the column's initial top: carried by the cylinder or thrown (0 in a good test).
    pub lifted: usize,
    /// Whether the pile came to rest (root-mean-square speed of the pile below
    /// [`ReposeSettings::rest_speed`]) before the relaxation time ran out.
    pub settled: bool,
    /// Root-mean-square speed of the pile at the end (m/s).
    pub final_rms_speed: f64,
    /// Largest speed of a pile particle at the end (m/s).
    pub final_max_speed: f64,
    /// Simulated time (s).
    pub end_time: f64,
    /// Soil steps.
    pub steps: u64,
    /// Wall-clock time (s).
    pub wall_time_s: f64,
    /// Pile particle centres relative to the base's top centre (m).
    #[serde(skip)]
    pub pile: Vec<[f64; 3]>,
    /// Every particle at the end: position and class (`on_base`, `sunk`, …).
    #[serde(skip)]
    pub all: Vec<([f64; 3], &'static str)>,
    /// Per exchange: time (s), particles on the base, pile rms and largest speed (m/s).
    #[serde(skip)]
    pub series: Vec<[f64; 4]>,
}

impl ReposeSettings {
    /// The pile is at rest when its root-mean-square speed is below `10⁻³ √(g R)` (1 mm/s for
    /// R = 0.1 m): a thousandth of the speed scale of the collapse.
    pub fn rest_speed(&self) -> f64 {
        1e-3 * (9.81 * self.radius).sqrt()
    }
}

/// Writes the scene and mesh into `dir` and runs the test.
pub fn run_test(material: &toml::Table, s: &ReposeSettings, dir: &Path) -> Result<PileRun, CommandError> {
    std::fs::create_dir_all(dir).map_err(|e| CommandError::Output(format!("cannot create {}: {e}", dir.display())))?;
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).map_err(|e| CommandError::Output(format!("cannot write {}: {e}", p.display())))?;
        Ok::<PathBuf, CommandError>(p)
    };
    write("tube.obj", &tube_obj(s.radius, s.radius + 2.0 * s.spacing, s.height + 2.0 * s.spacing, TUBE_SEGMENTS))?;
    let scene_path = write("scene.toml", &scene_text(material, s)?)?;
    let scene = load_scene(&scene_path, &s.sets)?;
    match s.precision {
        Precision::F32 => run_scene::<f32>(&scene, s),
        Precision::F64 => run_scene::<f64>(&scene, s),
    }
}

/// Where a particle is at the end (see [`PileRun`]).
fn classify(p: [f64; 3], s: &ReposeSettings) -> &'static str {
    let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
    let rim = s.radius + s.spacing;
    if p[2] > s.height + 2.0 * s.spacing {
        "lifted"
    } else if p[2] > 0.0 {
        if r <= rim { "on_base" } else { "falling" }
    } else if r > s.radius {
        "sunk"
    } else {
        "through_base"
    }
}

/// Root-mean-square and largest speed of the particles on the base, and their count.
fn pile_speeds<T: Real>(f: &dyn regolith_fsi::SphSolver<T>, s: &ReposeSettings) -> (usize, f64, f64) {
    let (mut n, mut sum2, mut max2) = (0usize, 0.0f64, 0.0f64);
    for (p, u) in f.positions().iter().zip(f.velocities()) {
        if classify([p.x.as_f64(), p.y.as_f64(), p.z.as_f64()], s) == "on_base" {
            let v2 = u.x.as_f64().powi(2) + u.y.as_f64().powi(2) + u.z.as_f64().powi(2);
            n += 1;
            sum2 += v2;
            max2 = max2.max(v2);
        }
    }
    (n, if n > 0 { (sum2 / n as f64).sqrt() } else { 0.0 }, max2.sqrt())
}

fn run_scene<T: Real>(scene: &crate::scene::Scene, s: &ReposeSettings) -> Result<PileRun, CommandError> {
    let started = Instant::now();
    let run_err = |e: String| CommandError::Run(format!("{}: {e}", scene.path.display()));
    let mut sim = Simulation::<T>::new(scene).map_err(|e| run_err(e.to_string()))?;
    // The cylinder slides: free slip on its markers, with the normal of the face each one is
    // nearest (inner wall, outer wall, rims), in the body frame, which only translates.
    let d0 = s.spacing;
    let (inner, outer, top) = (s.radius, s.radius + 2.0 * d0, s.height + 2.0 * d0);
    let bodies = &sim.system.interface.bodies;
    let markers = bodies.last().map_or(0, |b| b.markers.end);
    let mut normals = vec![[0.0; 3]; markers];
    if let Some(tube) = bodies.get(1) {
        for (k, l) in tube.markers.clone().zip(&tube.local) {
            let r = (l[0] * l[0] + l[1] * l[1]).sqrt().max(f64::MIN_POSITIVE);
            let radial = [l[0] / r, l[1] / r, 0.0];
            let faces = [
                ((r - inner).abs(), radial.map(|x| -x)),
                ((outer - r).abs(), radial),
                (l[2].abs(), [0.0, 0.0, -1.0]),
                ((top - l[2]).abs(), [0.0, 0.0, 1.0]),
            ];
            normals[k] = faces.iter().min_by(|a, b| a.0.total_cmp(&b.0)).map_or([0.0; 3], |f| f.1);
        }
    }
    sim.system
        .fluid
        .set_wall_contact(&[WallContact::Rough, WallContact::Rough, WallContact::Smooth], &normals)
        .map_err(|e| run_err(e.to_string()))?;
    let (lifted_at, end) = (s.lift_time(), scene.end_time);
    let mut series = Vec::new();
    let mut settled = false;
    while sim.time() < end * (1.0 - 1e-12) {
        sim.step_max(Some(end - sim.time())).map_err(|e| run_err(e.to_string()))?;
        let (n, rms, max) = pile_speeds(sim.system.fluid.as_ref(), s);
        series.push([sim.time(), n as f64, rms, max]);
        if sim.time() >= lifted_at && rms < s.rest_speed() {
            settled = true;
            break;
        }
    }
    let f = &sim.system.fluid;
    let (n_pile, rms, max) = pile_speeds(f.as_ref(), s);
    let mut run = PileRun {
        particles: f.len(),
        on_base: n_pile,
        sunk: 0,
        falling: 0,
        through_base: 0,
        lifted: 0,
        settled,
        final_rms_speed: rms,
        final_max_speed: max,
        end_time: sim.time(),
        steps: f.steps(),
        wall_time_s: 0.0,
        pile: Vec::new(),
        all: Vec::new(),
        series,
    };
    for p in f.positions() {
        let p = [p.x.as_f64(), p.y.as_f64(), p.z.as_f64()];
        let class = classify(p, s);
        match class {
            "on_base" => run.pile.push(p),
            "sunk" => run.sunk += 1,
            "falling" => run.falling += 1,
            "through_base" => run.through_base += 1,
            _ => run.lifted += 1,
        }
        run.all.push((p, class));
    }
    run.wall_time_s = started.elapsed().as_secs_f64();
    Ok(run)
}

/// What `regolith calibrate repose` reads.
#[derive(Clone, Debug)]
pub struct ReposeInputs {
    /// Material file.
    pub material: PathBuf,
    /// Test settings.
    pub settings: ReposeSettings,
    /// Output folder.
    pub out: PathBuf,
    /// Adjust the material's friction angle until the pile stands at this angle (degrees).
    pub target_angle: Option<f64>,
    /// Smallest tolerance of the loop (degrees; [`ANGLE_TOLERANCE`] by default).
    pub tolerance: f64,
}

/// Friction angles the calibration loop may try (degrees).
pub const PHI_RANGE: (f64, f64) = (1.0, 65.0);

/// Most SPH tests the calibration loop runs.
pub const MAX_EVALUATIONS: usize = 6;

/// Default smallest tolerance of the loop (degrees). The slices' standard error (0.3–0.6° at
/// 20 slices) understates how much a pile angle moves from one test to the next (about ±1° at
/// R = 8 d0: docs/calibration.md), so the loop accepts a miss of up to this much.
pub const ANGLE_TOLERANCE: f64 = 1.0;

/// AGX's summary block.
#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct ReposeSummary {
    /// Mean over the slices (degrees).
    pub average_angle_of_repose: f64,
    /// Standard deviation over the slices (degrees).
    pub standard_deviation: f64,
    /// Smallest (degrees).
    pub min_angle_of_repose: f64,
    /// Largest (degrees).
    pub max_angle_of_repose: f64,
}

/// `repose.json`.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct ReposeReport {
    /// "static_angle_of_repose_test".
    pub test: &'static str,
    /// The material file.
    pub material: String,
    /// The material's friction angle (degrees), when it has one.
    pub friction_angle: Option<f64>,
    /// AGX's summary.
    pub ResultsFromIndividualAnglesOfRepose: ReposeSummary,
    /// One angle per slice with a fit (degrees).
    pub IndividualAnglesOfRepose: Vec<f64>,
    /// Settings.
    pub settings: ReposeSettings,
    /// Where the soil ended.
    pub run: PileRun,
    /// The analysis.
    pub analysis: PileAnalysis,
    /// The scene as run.
    pub scene: String,
    /// Plots written.
    pub plots: Vec<String>,
    /// The calibration loop (`--target-angle`): each friction angle tried, the pile angle and
    /// its standard error (the slices' standard deviation over √n), whether it converged.
    pub calibration: Option<TargetRun>,
    /// The calibrated material file, when the loop converged.
    pub calibrated_material: Option<String>,
}

/// Runs the test, analyses the pile, writes `repose.json`, `particles.csv` (every particle at
/// the end with its class), `series.csv` (the pile's count and speeds per exchange) and the
/// plots. With a target angle, runs the calibration loop over the friction angle (each test
/// in `iteration_<k>/`), then reports the last test and writes `material.toml` when it
/// converged.
pub fn calibrate_repose(inp: &ReposeInputs) -> Result<ReposeReport, CommandError> {
    let s = &inp.settings;
    s.check().map_err(|(flag, msg)| CommandError::Input(InputError::flag(flag, msg)))?;
    let material = material_table(&inp.material)?;
    let Some(target) = inp.target_angle else {
        let run = run_test(&material, s, &inp.out)?;
        return report(inp, &inp.out, &material, run, None, None);
    };
    if !(target.is_finite() && target > 0.0 && target < 90.0) {
        return Err(
            InputError::flag("--target-angle", format!("must be between 0 and 90 degrees (got {target})")).into()
        );
    }
    let phi0 = friction_angle(&material).ok_or_else(|| {
        InputError::key(&inp.material, "friction_angle", "is needed for --target-angle: the loop adjusts it")
    })?;
    if !(inp.tolerance.is_finite() && inp.tolerance > 0.0) {
        return Err(InputError::flag("--tolerance", format!("must be > 0 degrees (got {})", inp.tolerance)).into());
    }
    let settings =
        TargetSettings { target, tolerance_floor: inp.tolerance, range: PHI_RANGE, max_evaluations: MAX_EVALUATIONS };
    let mut last = None;
    let mut k = 0;
    let loop_run = calibrate_to_target(&settings, phi0, |phi| {
        k += 1;
        let mut m = material.clone();
        m.insert("friction_angle".into(), phi.into());
        let dir = inp.out.join(format!("iteration_{k}"));
        let run = run_test(&m, s, &dir)?;
        if !run.settled {
            return Err(CommandError::Run(format!(
                "{} (friction_angle = {phi}, {}): the pile was still moving after --relax-time {} s (rms speed {:.2e} m/s, at rest below {:.2e}); give a longer --relax-time",
                inp.material.display(),
                dir.display(),
                s.relax_time,
                run.final_rms_speed,
                s.rest_speed()
            )));
        }
        let a = analyse_pile(&run.pile, s.radius, s.spacing, s.slices, s.cells, s.cell_radius)
            .map_err(|e| CommandError::Run(format!("{} (friction_angle = {phi}): {e}", inp.material.display())))?;
        let n = a.slices.iter().filter(|f| f.angle_deg.is_some()).count() as f64;
        let se = a.std_deg / n.sqrt();
        eprintln!("  φ = {phi:.3}°: pile at {:.2}° ± {:.2}° (target {target}°)", a.mean_deg, se);
        let out = (a.mean_deg, se);
        last = Some((m, run, dir));
        Ok::<_, CommandError>(out)
    })?;
    let Some((m, run, dir)) = last else {
        return Err(CommandError::Run(format!("{}: the calibration loop ran no test", inp.material.display())));
    };
    let written = match loop_run.converged {
        Some(phi) => Some(write_calibrated(
            &inp.material,
            &[("friction_angle", phi)],
            &format!(
                "`regolith calibrate repose --target-angle {target}{}`: friction_angle set so that the SPH pile stands\n# at the target angle (see repose.json)",
                inp.settings.sets.iter().map(|(k, v)| format!(" --set {k}={v}")).collect::<String>()
            ),
            &inp.out.join("material.toml"),
        )?),
        None => None,
    };
    report(inp, &dir, &m, run, Some(loop_run), written)
}

fn friction_angle(m: &toml::Table) -> Option<f64> {
    m.get("friction_angle").and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
}

fn report(
    inp: &ReposeInputs,
    dir: &Path,
    material: &toml::Table,
    run: PileRun,
    calibration: Option<TargetRun>,
    calibrated_material: Option<String>,
) -> Result<ReposeReport, CommandError> {
    let s = &inp.settings;
    let out_err = |e: String| CommandError::Output(e);
    let write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).map_err(|e| out_err(format!("cannot write {}: {e}", p.display())))
    };
    write(
        "particles.csv",
        std::iter::once("x,y,z,class\n".to_string())
            .chain(run.all.iter().map(|(p, c)| format!("{},{},{},{c}\n", p[0], p[1], p[2])))
            .collect(),
    )?;
    write(
        "series.csv",
        std::iter::once("time,on_base,rms_speed,max_speed\n".to_string())
            .chain(run.series.iter().map(|r| format!("{},{},{},{}\n", r[0], r[1], r[2], r[3])))
            .collect(),
    )?;
    let analysis = analyse_pile(&run.pile, s.radius, s.spacing, s.slices, s.cells, s.cell_radius)
        .map_err(|e| CommandError::Run(format!("{}: {e}", inp.material.display())))?;
    let mut plots =
        write_figure(&profile_figure(&run.pile, &analysis, s), dir, "profile").map_err(|e| out_err(e.to_string()))?;
    plots.extend(
        write_figure(&top_view_figure(&run.pile, &analysis), dir, "top_view").map_err(|e| out_err(e.to_string()))?,
    );
    let report = ReposeReport {
        test: "static_angle_of_repose_test",
        material: inp.material.display().to_string(),
        friction_angle: friction_angle(material),
        ResultsFromIndividualAnglesOfRepose: ReposeSummary {
            average_angle_of_repose: analysis.mean_deg,
            standard_deviation: analysis.std_deg,
            min_angle_of_repose: analysis.min_deg,
            max_angle_of_repose: analysis.max_deg,
        },
        IndividualAnglesOfRepose: analysis.slices.iter().filter_map(|f| f.angle_deg).collect(),
        settings: s.clone(),
        run,
        analysis,
        scene: dir.join("scene.toml").display().to_string(),
        plots: plots.iter().map(|p| p.display().to_string()).collect(),
        calibration,
        calibrated_material,
    };
    let json = inp.out.join("repose.json");
    let text = serde_json::to_string_pretty(&report).map_err(|e| out_err(e.to_string()))?;
    std::fs::write(&json, text).map_err(|e| out_err(format!("cannot write {}: {e}", json.display())))?;
    Ok(report)
}

/// The pile in the r–z plane (every particle, the selected tops and each slice's line).
pub fn profile_figure(pile: &[[f64; 3]], a: &PileAnalysis, s: &ReposeSettings) -> Figure {
    let all: Vec<(f64, f64)> = pile.iter().map(|p| ((p[0] * p[0] + p[1] * p[1]).sqrt(), p[2])).collect();
    let tops: Vec<(f64, f64)> = a.slices.iter().flat_map(|f| f.tops.iter().map(|t| (t[0], t[1]))).collect();
    let mut series = vec![Series::points("particles", all), Series::points("highest per cell", tops)];
    // The mean line through the mean intercept, and the extreme slices.
    let lines: Vec<(f64, f64)> = a.slices.iter().filter_map(|f| f.line).collect();
    if !lines.is_empty() {
        let b0 = lines.iter().map(|l| l.0).sum::<f64>() / lines.len() as f64;
        let t = a.mean_deg.to_radians().tan();
        series.push(Series::line(
            format!("mean {:.1}° ± {:.1}°", a.mean_deg, a.std_deg),
            vec![(0.0, b0), (s.radius, b0 - t * s.radius)],
        ));
    }
    Figure {
        panels: vec![Panel {
            title: "Pile profile (all slices)".into(),
            x_label: "r (m)".into(),
            y_label: "z above the base (m)".into(),
            series,
            x_range: Some((0.0, s.radius * 1.05)),
            y_range: Some((0.0, s.height * 1.05)),
            ..Default::default()
        }],
    }
}

/// The pile seen from above, the selected particles marked.
pub fn top_view_figure(pile: &[[f64; 3]], a: &PileAnalysis) -> Figure {
    let all: Vec<(f64, f64)> = pile.iter().map(|p| (p[0], p[1])).collect();
    let sel: Vec<(f64, f64)> =
        a.slices.iter().flat_map(|f| f.selected.iter().map(|&k| (pile[k][0], pile[k][1]))).collect();
    Figure {
        panels: vec![Panel {
            title: "Top view: particles on the base, the highest of each cell marked".into(),
            x_label: "x (m)".into(),
            y_label: "y (m)".into(),
            series: vec![Series::points("particles", all), Series::points("selected", sel)],
            ..Default::default()
        }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cone of angle θ and base radius R on a lattice of spacing d0.
    fn cone(theta_deg: f64, radius: f64, d0: f64) -> Vec<[f64; 3]> {
        let t = theta_deg.to_radians().tan();
        let n = (radius / d0).ceil() as i64;
        let mut pts = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                let (x, y) = (i as f64 * d0, j as f64 * d0);
                let r = (x * x + y * y).sqrt();
                if r > radius {
                    continue;
                }
                let top = (radius - r) * t;
                let mut z = d0;
                while z <= top {
                    pts.push([x, y, z]);
                    z += d0;
                }
                // The surface particle exactly on the cone.
                pts.push([x, y, top.max(d0)]);
            }
        }
        pts
    }

    #[test]
    fn a_cone_gives_its_angle_in_every_slice() {
        for theta in [20.0, 35.0, 45.0] {
            let a = analyse_pile(&cone(theta, 0.1, 0.004), 0.1, 0.004, 20, 15, 0.004).unwrap();
            assert!((a.mean_deg - theta).abs() < 0.5, "θ = {theta}: mean {}", a.mean_deg);
            assert!(a.max_deg - a.min_deg < 1.5, "θ = {theta}: spread {}..{}", a.min_deg, a.max_deg);
            assert_eq!(a.slices.len(), 20);
            assert!(a.slices.iter().all(|s| s.tops.len() >= 3));
        }
    }

    #[test]
    fn a_flat_layer_has_no_slope() {
        let flat: Vec<[f64; 3]> = (0..100).map(|i| [(i % 10) as f64 * 0.01, (i / 10) as f64 * 0.01, 0.01]).collect();
        let e = analyse_pile(&flat, 0.1, 0.01, 4, 5, 0.01).unwrap_err();
        assert!(e.to_string().contains("no slice has three cells on the slope"), "{e}");
    }

    #[test]
    fn the_tube_mesh_is_closed_and_outward() {
        let obj = tube_obj(0.1, 0.12, 0.2, 12);
        let v: Vec<[f64; 3]> = obj
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let x: Vec<f64> = l.split(' ').map(|s| s.parse().unwrap()).collect();
                [x[0], x[1], x[2]]
            })
            .collect();
        let f: Vec<[usize; 3]> = obj
            .lines()
            .filter_map(|l| l.strip_prefix("f "))
            .map(|l| {
                let x: Vec<usize> = l.split(' ').map(|s| s.parse::<usize>().unwrap() - 1).collect();
                [x[0], x[1], x[2]]
            })
            .collect();
        // Every directed edge appears once and its reverse once: closed and consistently wound.
        let mut edges = std::collections::HashMap::new();
        for t in &f {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        assert!(edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1)));
        // Signed volume (divergence theorem) = the annulus' volume (polygonal, circumscribed).
        let vol: f64 = f
            .iter()
            .map(|t| {
                let (a, b, c) = (v[t[0]], v[t[1]], v[t[2]]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum();
        let k = 12.0 * (std::f64::consts::PI / 12.0).tan();
        let expect = k * (0.12f64.powi(2) - 0.1f64.powi(2)) * 0.2;
        assert!((vol - expect).abs() < 1e-9 * expect.abs().max(1.0), "{vol} vs {expect}");
    }

    #[test]
    fn wrong_settings_name_their_flag() {
        let mut s = ReposeSettings::for_radius(0.1);
        assert!(s.check().is_ok());
        s.spacing = 0.05;
        assert_eq!(s.check().unwrap_err().0, "--spacing");
        let mut s = ReposeSettings::for_radius(0.1);
        s.lift_speed = -1.0;
        assert_eq!(s.check().unwrap_err().0, "--lift-speed");
        let mut s = ReposeSettings::for_radius(0.1);
        s.cells = 2;
        assert_eq!(s.check().unwrap_err().0, "--cells");
        // Keys the test builds itself are refused; others pass (the scene checks their values).
        for (key, refused) in [
            ("sph.spacing", true),
            ("materials[0].density", true),
            ("bodies[1].position", true),
            ("container.max", true),
            ("sph.artificial_viscosity", false),
            ("sph.spacing_extra", false),
            ("simulation.precision", true),
        ] {
            let mut s = ReposeSettings::for_radius(0.1);
            s.sets = vec![(key.into(), toml::Value::Float(0.0))];
            assert_eq!(s.check().is_err(), refused, "{key}");
        }
    }
}
