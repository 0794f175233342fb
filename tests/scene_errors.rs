//! Scene validation: every example scene is valid, and each kind of mistake gets the exact
//! one-line error naming the file, line, key and what is allowed.

use std::path::PathBuf;

use regolith::scene::{load_scene, parse_set};

const BASE: &str = r#"[simulation]
end_time = 0.5
dt = "auto"

[sph]
spacing = 0.02

[[materials]]
name = "sand"
model = "drucker-prager"
density = 1600
youngs_modulus = 2e7
poisson_ratio = 0.3
friction_angle = 30.0

[container]
min = [0.0, 0.0, 0.0]
max = [0.4, 0.4, 0.5]

[terrain]
material = "sand"
depth = 0.2
"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scene_errors");
    std::fs::create_dir_all(&dir).expect("tmp");
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).expect("write");
    p
}

fn err(name: &str, text: &str) -> (PathBuf, String) {
    let p = write(name, text);
    let e = load_scene(&p, &[]).expect_err("must be rejected").to_string();
    (p, e)
}

macro_rules! case {
    ($name:ident, $from:expr, $to:expr, $expected:expr) => {
        #[test]
        fn $name() {
            assert!(BASE.contains($from), "bad test: {:?} not in BASE", $from);
            let (p, e) = err(stringify!($name), &BASE.replacen($from, $to, 1));
            assert_eq!(e, format!($expected, p.display()));
        }
    };
}

#[test]
fn base_scene_is_valid() {
    let s = load_scene(&write("base", BASE), &[]).expect("valid");
    assert_eq!(s.soil.len(), 1);
    assert_eq!(s.solver.h_factor, 1.2);
}

#[test]
fn every_example_scene_is_valid() {
    for sub in ["examples/scenes", "examples/study"] {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(sub);
        let mut n = 0;
        for entry in std::fs::read_dir(&dir).expect(sub) {
            let p = entry.expect("entry").path();
            if p.extension().and_then(|e| e.to_str()) == Some("toml") {
                load_scene(&p, &[]).unwrap_or_else(|e| panic!("{e}"));
                n += 1;
            }
        }
        assert!(n >= 1, "{sub} holds no scene");
    }
}

case!(
    no_simulation,
    "[simulation]\nend_time = 0.5\ndt = \"auto\"\n",
    "",
    "{}: key `simulation`: section [simulation] is required (at least end_time)"
);
case!(
    end_time_negative,
    "end_time = 0.5",
    "end_time = -1.0",
    "{}:2: key `simulation.end_time`: must be > 0 s (got -1)"
);
case!(
    gravity_up,
    "dt = \"auto\"",
    "dt = \"auto\"\ngravity = [0.0, 0.0, 9.81]",
    "{}:4: key `simulation.gravity`: must not point up (z ≤ 0; soil is layered along −z, tilt g for a slope) (got [0.0, 0.0, 9.81])"
);
case!(
    dt_word,
    "dt = \"auto\"",
    "dt = \"fast\"",
    "{}:3: key `simulation.dt`: must be \"auto\" or a step in s in (0, end_time = 0.5] (got \"fast\")"
);
case!(
    cfl_with_fixed_dt,
    "dt = \"auto\"",
    "dt = 1e-4\ncfl = 0.2",
    "{}:4: key `simulation.cfl`: and max_dt apply to dt = \"auto\" only; remove them or set dt = \"auto\""
);
case!(cfl_range, "dt = \"auto\"", "cfl = 1.5", "{}:3: key `simulation.cfl`: must be in (0, 1] (got 1.5)");
case!(
    unknown_integrator,
    "dt = \"auto\"",
    "integrator = \"rk4\"",
    "{}:3: key `simulation.integrator`: unknown variant `rk4`, expected `rk2` or `euler`"
);
case!(
    euler_refused,
    "dt = \"auto\"",
    "integrator = \"euler\"",
    "{}:3: key `simulation.integrator`: \"euler\" is unstable for soil at rest (a geostatic bed blows apart); use \"rk2\""
);
case!(
    unknown_section,
    "[sph]",
    "[fluid]\nx = 1\n[sph]",
    "{}:5: key `fluid`: unknown field `fluid`, expected one of `simulation`, `sph`, `materials`, `container`, `terrain`, `soil_blocks`, `water_blocks`, `bodies`, `rig`, `output`, `vehicles`, `expect`, `study`, `accuracy` (unknown keys are errors so that nothing is silently ignored)"
);
case!(
    output_every_below_exchange,
    "depth = 0.2\n",
    "depth = 0.2\n\n[output]\nevery = 0.0001\n",
    "{}:25: key `output.every`: must be at least simulation.exchange_interval = 0.001 s: frames are taken between exchanges (got 0.0001)"
);
case!(
    output_decimate_zero,
    "depth = 0.2\n",
    "depth = 0.2\n\n[output]\ndecimate = 0\n",
    "{}:25: key `output.decimate`: must be an integer ≥ 1: record every n-th particle (got 0)"
);
case!(
    output_roi_half,
    "depth = 0.2\n",
    "depth = 0.2\n\n[output]\nroi_min = [0.0, 0.0, 0.0]\n",
    "{}:24: key `output.roi_max`: is required with roi_min (the region of interest is a box)"
);
case!(
    output_roi_inverted,
    "depth = 0.2\n",
    "depth = 0.2\n\n[output]\nroi_min = [0.0, 0.0, 0.0]\nroi_max = [0.1, -0.1, 0.1]\n",
    "{}:26: key `output.roi_max`: must be finite and above roi_min on every axis (got [0.0, 0.0, 0.0] .. [0.1, -0.1, 0.1])"
);
case!(
    output_unknown_key,
    "depth = 0.2\n",
    "depth = 0.2\n\n[output]\nrate = 10\n",
    "{}:25: key `output.rate`: unknown field `rate`, expected one of `dir`, `every`, `mcap`, `particles`, `decimate`, `roi_min`, `roi_max` (unknown keys are errors so that nothing is silently ignored)"
);
case!(
    spacing_missing,
    "spacing = 0.02",
    "h_factor = 1.2",
    "{}:5: key `sph.spacing`: is required: initial particle spacing in m, > 0"
);
case!(
    h_factor_range,
    "spacing = 0.02",
    "spacing = 0.02\nh_factor = 3.0",
    "{}:7: key `sph.h_factor`: must be in [1.0, 2.0] (h/d0; got 3)"
);
case!(
    bce_layers_zero,
    "spacing = 0.02",
    "spacing = 0.02\nbce_layers = 0",
    "{}:7: key `sph.bce_layers`: must be an integer in 1..=8 (got 0)"
);
case!(
    threshold_range,
    "spacing = 0.02",
    "spacing = 0.02\nfree_surface_threshold = 3.5",
    "{}:7: key `sph.free_surface_threshold`: must be in (0, 1): the smallest eigenvalue of Σ V (x_b − x_a) ⊗ ∇W is 1 inside the soil (got 3.5)"
);
case!(
    free_surface_without_effect,
    "spacing = 0.02",
    "spacing = 0.02\nfree_surface = false",
    "{}:7: key `sph.free_surface`: changes nothing here: the free-surface flags act only with free_surface_stress = \"zero\" or PPST shifting (shifting = \"ppst\" or \"ppst+xsph\")"
);
case!(
    shifting_unknown,
    "spacing = 0.02",
    "spacing = 0.02\nshifting = \"ppsts\"",
    "{}:7: key `sph.shifting`: unknown variant `ppsts`, expected one of `none`, `xsph`, `ppst`, `ppst+xsph`"
);
case!(
    xsph_epsilon_without_xsph,
    "spacing = 0.02",
    "spacing = 0.02\nshifting = \"ppst\"\nxsph_epsilon = 0.3",
    "{}:8: key `sph.xsph_epsilon`: applies only when shifting includes \"xsph\""
);
case!(
    neighbor_skin_out_of_range,
    "spacing = 0.02",
    "spacing = 0.02\nneighbor_skin = 1.5",
    "{}:7: key `sph.neighbor_skin`: must be in [0, 1] (a multiple of h; 0 rebuilds the lists every step; got 1.5)"
);
#[test]
fn neighbor_skin_on_wgpu() {
    let text = BASE.replacen("dt = \"auto\"", "dt = \"auto\"\nbackend = \"wgpu\"\nprecision = \"f32\"", 1).replacen(
        "spacing = 0.02",
        "spacing = 0.02\nneighbor_skin = 0.3",
        1,
    );
    let (p, e) = err("neighbor_skin_on_wgpu", &text);
    assert_eq!(
        e,
        format!(
            "{}:9: key `sph.neighbor_skin`: the wgpu backend rebuilds its neighbour lists every step: use 0 or backend \"cpu\"",
            p.display()
        )
    );
}
case!(
    material_without_name,
    "name = \"sand\"\n",
    "",
    "{}:8: key `materials[0].name`: is required: the name terrain and soil blocks refer to"
);
case!(
    material_rule_in_scene,
    "poisson_ratio = 0.3",
    "poisson_ratio = 0.6",
    "{}:13: key `materials[0].poisson_ratio`: must satisfy 0 < ν < 0.5 (got 0.6)"
);
case!(
    material_unknown_key,
    "poisson_ratio = 0.3",
    "poisson = 0.3",
    "{}:13: key `materials[0].poisson`: unknown field `poisson`, expected one of `name`, `file`, `model`, `density`, `youngs_modulus`, `poisson_ratio`, `friction_angle`, `cohesion`, `mu_i_friction_angle`, `mu_i_i0`, `grain_diameter`, `grain_density`, `permeability`, `sound_speed`, `viscosity`, `mcc_m`, `mcc_kappa`, `mcc_lambda`, `mcc_cr`, `mcc_cc`, `mcc_v_lambda`, `ocr`, `mcc_clamp_moduli`, `mcc_pc_floor` (unknown keys are errors so that nothing is silently ignored)"
);
case!(
    terrain_unknown_material,
    "material = \"sand\"",
    "material = \"gravel\"",
    "{}:21: key `terrain.material`: \"gravel\" is not a defined material (defined: sand)"
);
case!(
    container_inverted,
    "max = [0.4, 0.4, 0.5]",
    "max = [0.4, -0.4, 0.5]",
    "{}:18: key `container.max`: must exceed container.min by at least 4 × sph.spacing = 0.08 m along each axis (axis y spans -0.4 m)"
);
case!(
    terrain_too_deep,
    "depth = 0.2",
    "depth = 0.7",
    "{}:22: key `terrain.depth`: must be in [2 × sph.spacing = 0.04, container height = 0.5] m (got 0.7)"
);
case!(
    terrain_without_container,
    "[container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.4, 0.5]\n",
    "",
    "{}:17: key `terrain`: needs a [container]: the bed fills the container floor"
);
case!(
    terrain_depth_and_heightmap,
    "depth = 0.2",
    "depth = 0.2\nheightmap = \"h.csv\"",
    "{}:22: key `terrain.depth`: and terrain.heightmap are both given: give one"
);
#[test]
fn heightmap_missing_file() {
    let (p, e) = err("heightmap_missing_file", &BASE.replacen("depth = 0.2", "heightmap = \"no-such-map.csv\"", 1));
    let map = p.parent().expect("dir").join("no-such-map.csv");
    assert_eq!(
        e,
        format!(
            "{}:22: key `terrain.heightmap`: {}: cannot read: No such file or directory (os error 2)",
            p.display(),
            map.display()
        )
    );
}
case!(
    no_soil,
    "[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n",
    "",
    "{}: the scene has no soil: add [terrain] or [[soil_blocks]]"
);
case!(
    block_outside,
    "[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n",
    "[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.6, 0.2, 0.2]\n",
    "{}:22: key `soil_blocks[0].shape`: the block [[0.0, 0.0, 0.0] .. [0.6, 0.2, 0.2]] must lie inside the container [[0.0, 0.0, 0.0] .. [0.4, 0.4, 0.5]]"
);
case!(
    block_with_a_tension,
    "[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n",
    "[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\ninitial_pressure = -5.0\n",
    "{}:25: key `soil_blocks[0].initial_pressure`: must be a compression > 0 Pa (got -5); leave it out for the geostatic state"
);
case!(
    cylinder_without_radius,
    "[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n",
    "[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"cylinder\"\nbase_center = [0.2, 0.2, 0.0]\nheight = 0.1\n",
    "{}:20: key `soil_blocks[0].radius`: is required for a cylinder (m)"
);
case!(
    cylinder_with_box_keys,
    "[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n",
    "[[soil_blocks]]\nmaterial = \"sand\"\nshape = \"cylinder\"\nmin = [0.0, 0.0, 0.0]\n",
    "{}:23: key `soil_blocks[0].min`: applies to shape = \"box\" only; a cylinder takes base_center, radius and height"
);
case!(
    unused_material,
    "[container]",
    "[[materials]]\nname = \"clay\"\nmodel = \"elastic\"\ndensity = 1800\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\n\n[container]",
    "{}:17: key `materials[1].name`: material \"clay\" is defined but not used by any soil"
);
case!(
    duplicate_material,
    "[container]",
    "[[materials]]\nname = \"sand\"\nmodel = \"elastic\"\ndensity = 1800\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\n\n[container]",
    "{}:17: key `materials[1].name`: \"sand\" is defined twice; material names must be unique"
);

#[test]
fn materials_can_come_from_files_relative_to_the_scene() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scene_errors");
    std::fs::create_dir_all(&dir).expect("tmp");
    std::fs::write(dir.join("soil.toml"), "model = \"drucker-prager\"\ndensity = 1500\nyoungs_modulus = 1e7\npoisson_ratio = 0.25\nfriction_angle = 35.0\n").expect("write");
    let text = BASE.replacen("model = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e7\npoisson_ratio = 0.3\nfriction_angle = 30.0\n", "file = \"soil.toml\"\n", 1);
    let s = load_scene(&write("from_file", &text), &[]).expect("valid");
    assert_eq!(s.materials[0].params.density, Some(1500.0));
    let mixed = text.replacen("file = \"soil.toml\"", "file = \"soil.toml\"\ndensity = 1700", 1);
    let (p, e) = err("from_file_mixed", &mixed);
    assert_eq!(
        e,
        format!(
            "{}:10: key `materials[0].file`: a material read from a file takes only `name` and `file` here; put the other keys in the file",
            p.display()
        )
    );
}

#[test]
fn set_overrides_apply_and_report_their_origin() {
    let p = write("set", BASE);
    let s = load_scene(
        &p,
        &[parse_set("simulation.end_time=0.25").expect("set"), parse_set("materials[0].density=1700").expect("set")],
    )
    .expect("valid");
    assert_eq!(s.end_time, 0.25);
    assert_eq!(s.materials[0].params.density, Some(1700.0));
    let e = load_scene(&p, &[parse_set("sph.spacing=-1").expect("set")]).expect_err("bad").to_string();
    assert_eq!(e, format!("{}: key `sph.spacing`: must be > 0 m (got -1) (value from --set)", p.display()));
    let e = load_scene(&p, &[parse_set("materials[4].density=1").expect("set")]).expect_err("bad").to_string();
    assert_eq!(e, "--set: materials[4].density: `materials` has 1 entries; index 4 is out of range");
}

#[test]
fn check_cli_exit_codes() {
    let run =
        |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_regolith")).args(args).output().expect("run");
    let ok = run(&["check", "examples/scenes/geostatic_box.toml"]);
    assert_eq!(ok.status.code(), Some(0), "{}", String::from_utf8_lossy(&ok.stderr));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("effects: rheology {mcc}"));
    let bad = run(&["check", "examples/scenes/geostatic_box.toml", "--set", "sph.kernel=\"gauss\""]);
    assert_eq!(bad.status.code(), Some(2));
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("key `sph.kernel`: unknown variant `gauss`"), "{err}");
    let missing = run(&["check", "no/such/scene.toml"]);
    assert_eq!(missing.status.code(), Some(2));
    let markers = run(&["check", "examples/scenes/geostatic_box.toml", "--set", "sph.body_markers=\"middle\""]);
    assert_eq!(markers.status.code(), Some(2));
    let err = String::from_utf8_lossy(&markers.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("key `sph.body_markers`: unknown variant `middle`, expected `surface` or `inset`"), "{err}");
}

const BODY: &str = "\n[[bodies]]\nname = \"wheel\"\nshape = { type = \"wheel\", radius = 0.1, width = 0.05 }\nmass = 2.0\nposition = [0.2, 0.2, 0.4]\n\n[rig]\ntype = \"wheel\"\nbody = \"wheel\"\nload = 30.0\nangular_velocity = 1.0\nslips = [0.0, 0.3]\n";

fn body_err(name: &str, from: &str, to: &str) -> (PathBuf, String) {
    let text = format!("{BASE}{BODY}");
    assert!(text.contains(from), "bad test: {from:?}");
    err(name, &text.replacen(from, to, 1))
}

#[test]
fn body_and_rig_scene_is_valid() {
    let s = load_scene(&write("body_ok", &format!("{BASE}{BODY}")), &[]).expect("valid");
    assert_eq!(s.bodies.len(), 1);
    assert!(s.rig.is_some());
}

#[test]
fn body_and_rig_errors() {
    let cases: [(&str, &str, &str, &str); 13] = [
        (
            "mass = 2.0",
            "mass = 2.0\nactive_margin = -0.05",
            "{}:28: key `bodies[0].active_margin`: must be >= 0 m (got -0.05)",
            "active_margin_negative",
        ),
        (
            "mass = 2.0",
            "mass = 2.0\nfsi = false\nactive_margin = 0.05",
            "{}:29: key `bodies[0].active_margin`: is set but fsi = false (only FSI bodies have active boxes)",
            "active_margin_without_fsi",
        ),
        (
            "shape = { type = \"wheel\", radius = 0.1, width = 0.05 }\n",
            "",
            "{}:24: key `bodies[0].shape`: is required: { type = \"box\" | \"sphere\" | \"cylinder\" | \"cone\" | \"mesh\" | \"wheel\", ... }",
            "shape_missing",
        ),
        (
            "mass = 2.0",
            "mass = 2.0\ndensity = 1000.0",
            "{}:27: key `bodies[0].mass`: and density are both given: give one",
            "mass_and_density",
        ),
        (
            "radius = 0.1, width",
            "radius = -0.1, width",
            "{}:26: key `bodies[0].shape.radius`: must be > 0 m (got -0.1)",
            "negative_radius",
        ),
        (
            "body = \"wheel\"",
            "body = \"rover\"",
            "{}:32: key `rig.body`: \"rover\" is not a body of the scene",
            "rig_unknown_body",
        ),
        (
            "slips = [0.0, 0.3]",
            "slips = [0.0, 1.3]",
            "{}:35: key `rig.slips`: must be in [0, 1] (got 1.3)",
            "slip_range",
        ),
        (
            "slips = [0.0, 0.3]",
            "slips = [0.0, 0.3]\nslopes = [10.0]",
            "{}:35: key `rig.slips`: and slopes are both given: prescribe slips, tow the carriage, or drive up slopes",
            "slips_and_slopes",
        ),
        (
            "slips = [0.0, 0.3]",
            "slips = [0.0, 0.3]\nslip_radius = -0.1",
            "{}:36: key `rig.slip_radius`: must be > 0 m (got -0.1)",
            "slip_radius_negative",
        ),
        (
            "slips = [0.0, 0.3]",
            "slopes = [0.0, 75.0]",
            "{}:35: key `rig.slopes`: must be in [0, 60) degrees (got 75)",
            "slope_range",
        ),
        (
            "slips = [0.0, 0.3]",
            "slips = [0.0, 0.3]\nspeed = 0.1",
            "{}:36: key `rig.speed`: does not apply to a wheel rig",
            "rig_foreign_key",
        ),
        (
            "position = [0.2, 0.2, 0.4]",
            "position = [0.2, 0.2, 0.4]\nmotion = { type = \"fixed\" }",
            "{}:29: key `bodies[0].motion`: is set, but the wheel rig drives body \"wheel\"; remove it",
            "rig_body_motion",
        ),
        (
            "{ type = \"wheel\", radius = 0.1, width = 0.05 }",
            "{ type = \"box\", size = [0.1, 0.1, 0.1] }",
            "{}:32: key `rig.body`: \"wheel\" must be a wheel: shape type = \"wheel\" (or a cylinder with axis = \"y\")",
            "rig_wrong_shape",
        ),
    ];
    for (from, to, expected, name) in cases {
        let (p, e) = body_err(name, from, to);
        assert_eq!(e, expected.replace("{}", &p.display().to_string()), "case {name}");
    }
    // Slope mode tilts gravity itself, so the scene's must point along −z.
    let text = format!("{BASE}{BODY}").replacen("slips = [0.0, 0.3]", "slopes = [5.0]", 1).replacen(
        "dt = \"auto\"",
        "dt = \"auto\"\ngravity = [-1.0, 0.0, -9.0]",
        1,
    );
    let (p, e) = err("slopes_with_tilted_gravity", &text);
    let want = "{}:36: key `rig.slopes`: tilt simulation.gravity themselves: give gravity along −z (got [-1.0, 0.0, -9.0]) and the rig tilts it per slope";
    assert_eq!(e, want.replace("{}", &p.display().to_string()));
}

#[test]
fn mesh_bodies_need_a_readable_watertight_file() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scene_errors");
    std::fs::create_dir_all(&dir).expect("tmp");
    // An open box: five faces of a cube.
    std::fs::write(dir.join("open.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n").expect("write");
    let body = "\n[[bodies]]\nname = \"lid\"\nshape = { type = \"mesh\", file = \"open.obj\", scale = 0.1 }\nmass = 1.0\nposition = [0.2, 0.2, 0.4]\n";
    let (p, e) = err("mesh_open", &format!("{BASE}{body}"));
    assert!(
        e.starts_with(&format!(
            "{}:26: key `bodies[0].shape.file`: {}: the mesh is not watertight",
            p.display(),
            dir.join("open.obj").display()
        )),
        "{e}"
    );
    let missing = body.replace("open.obj", "nowhere.stl");
    let (p, e) = err("mesh_missing", &format!("{BASE}{missing}"));
    assert!(
        e.starts_with(&format!(
            "{}:26: key `bodies[0].shape.file`: {}: cannot read",
            p.display(),
            dir.join("nowhere.stl").display()
        )),
        "{e}"
    );
}

case!(
    active_key_without_enabled,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\ntravel = 0.05\n",
    "{}:9: key `sph.active.travel`: is set but enabled is not true"
);
case!(
    active_travel_zero,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\ntravel = 0.0\n",
    "{}:10: key `sph.active.travel`: must be > 0 m (got 0)"
);
case!(
    active_sleep_speed_negative,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\nsleep_speed = -1.0\n",
    "{}:10: key `sph.active.sleep_speed`: must be >= 0 m/s (got -1)"
);
case!(
    active_free_flow_negative,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\nfree_flow_time = -0.5\n",
    "{}:10: key `sph.active.free_flow_time`: must be >= 0 s (got -0.5)"
);
case!(
    active_margin_negative,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\nmargin = -0.1\n",
    "{}:10: key `sph.active.margin`: must be >= 0 m (got -0.1)"
);
case!(
    active_depth_factor_range,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\ndepth_factor = 20.0\n",
    "{}:10: key `sph.active.depth_factor`: must be in [0, 10] (got 20)"
);
case!(
    active_margin_and_depth_factor,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\nmargin = 0.1\ndepth_factor = 1.0\n",
    "{}:11: key `sph.active.depth_factor`: and margin are exclusive: margin replaces 2h + depth_factor x size"
);
case!(
    active_unknown_key,
    "spacing = 0.02\n",
    "spacing = 0.02\n\n[sph.active]\nenabled = true\nradius = 0.1\n",
    "{}:10: key `sph.active.radius`: unknown field `radius`, expected one of `enabled`, `margin`, `depth_factor`, `travel`, `sleep_speed`, `free_flow_time` (unknown keys are errors so that nothing is silently ignored)"
);

const WET: &str = "permeability = 1e-3\ngrain_density = 2650.0\n\n[[materials]]\nname = \"water\"\nmodel = \"water\"\ndensity = 1000\nsound_speed = 50\nviscosity = 1e-3\n\n[container]";

#[test]
fn a_wet_scene_is_valid() {
    let text = BASE.replacen("friction_angle = 30.0\n\n[container]", &format!("friction_angle = 30.0\n{WET}"), 1)
        + "\n[[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.4, 0.2]\n";
    let s = load_scene(&write("wet", &text), &[]).expect("valid");
    assert_eq!(s.soil.len(), 2);
    assert!(regolith::scene::describe(&s).contains("water: pore pressure and drag coupling on, drag svf"));
    let text = text.replacen("spacing = 0.02", "spacing = 0.02\ndrag = \"particle\"", 1);
    let s = load_scene(&write("wet_particle", &text), &[]).expect("valid");
    assert_eq!(s.solver.drag, regolith::fsi::config::Drag::Particle);
    assert!(regolith::scene::describe(&s).contains("drag particle"));
}

/// A wet scene with `from` replaced by `to`: its error.
fn wet_err(name: &str, from: &str, to: &str) -> (PathBuf, String) {
    let text = BASE.replacen("friction_angle = 30.0\n\n[container]", &format!("friction_angle = 30.0\n{WET}"), 1)
        + "\n[[water_blocks]]\nmaterial = \"water\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.4, 0.2]\n";
    assert!(text.contains(from), "bad test: {from:?}");
    err(name, &text.replacen(from, to, 1))
}

#[test]
fn wet_scene_mistakes_are_one_line_errors() {
    let cases = [
        (
            "wet_terrain_water",
            "material = \"sand\"\ndepth",
            "material = \"water\"\ndepth",
            ":30: key `terrain.material`: is water: the bed is soil; put water in [[water_blocks]]",
        ),
        (
            "wet_block_soil",
            "material = \"water\"\nshape",
            "material = \"sand\"\nshape",
            ":34: key `water_blocks[0].material`: \"sand\" is a soil: water blocks take a material with model = \"water\"",
        ),
        (
            "wet_no_permeability",
            "permeability = 1e-3\ngrain_density = 2650.0\n",
            "",
            ":8: key `materials[0].permeability`: is required for \"sand\": the scene has water, which flows through every soil (give permeability in m/s and grain_density)",
        ),
        (
            "wet_initial_pressure",
            "shape = \"box\"\nmin = [0.0, 0.0, 0.0]",
            "shape = \"box\"\ninitial_pressure = 1e3\nmin = [0.0, 0.0, 0.0]",
            ":36: key `water_blocks[0].initial_pressure`: applies to soil blocks; water starts hydrostatic from the water above it",
        ),
        (
            "wet_active",
            "spacing = 0.02",
            "spacing = 0.02\n\n[sph.active]\nenabled = true",
            ":8: key `sph.active`: is not available with water yet: remove [sph.active] from a wet scene",
        ),
    ];
    for (name, from, to, expected) in cases {
        let (p, e) = wet_err(name, from, to);
        assert_eq!(e, format!("{}{expected}", p.display()), "{name}");
    }
    let dry = BASE.to_string()
        + "\n[[bodies]]\nname = \"filter\"\nshape = { type = \"box\", size = [0.1, 0.1, 0.02] }\nmass = 1.0\nposition = [0.2, 0.2, 0.3]\nmotion = { type = \"fixed\" }\nfsi = true\npermeable = true\n";
    let (p, e) = err("dry_permeable", &dry);
    assert_eq!(
        e,
        format!("{}:31: key `bodies[0].permeable`: needs water in the scene ([[water_blocks]])", p.display())
    );
    let (p, e) = err(
        "dry_drag",
        &BASE.replacen(
            "spacing = 0.02",
            "spacing = 0.02
drag = \"particle\"",
            1,
        ),
    );
    assert_eq!(
        e,
        format!(
            "{}:7: key `sph.drag`: applies to scenes with water ([[water_blocks]]); remove it from a dry scene",
            p.display()
        )
    );
    let (p, e) = wet_err("wet_drag_name", "spacing = 0.02", "spacing = 0.02\ndrag = \"bang\"");
    assert!(e.starts_with(&format!("{}:7", p.display())) && e.contains("drag") && e.contains("svf"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}
