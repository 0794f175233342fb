//! Soil contact of walls and bodies (`soil_contact`): a block sliding on a smooth floor keeps
//! its momentum; on a Coulomb floor of coefficient μ it decelerates at μ g; a rough floor (the
//! default) holds it. A container sets its floor and side walls apart. The wgpu twin of the
//! contact is checked in `tests/wgpu_parity.rs`; bodies take only rough contact (one-line error).

use crate::common;

use regolith::build::build_soil;

/// An elastic block 0.1 × 0.1 × 0.05 m sliding along x at 1 m/s on the floor of a long box
/// whose walls have `contact`. Returns (time, mean x velocity) after each step.
fn slide(contact: &str, end: f64) -> Vec<(f64, f64)> {
    slide_in("[0.8, 0.2, 0.2]", "[0.05, 0.05, 0.0]", "[0.15, 0.15, 0.05]", contact, end)
}

/// The same block filling a channel 0.1 m wide: it slides along both side walls.
fn slide_in_channel(contact: &str, end: f64) -> Vec<(f64, f64)> {
    slide_in("[0.8, 0.1, 0.2]", "[0.05, 0.0, 0.0]", "[0.15, 0.1, 0.05]", contact, end)
}

fn slide_in(container_max: &str, lo: &str, hi: &str, contact: &str, end: f64) -> Vec<(f64, f64)> {
    let text = format!(
        "[simulation]\nend_time = {end}\nprecision = \"f64\"\n\n[sph]\nspacing = 0.01\n\n\
         [[materials]]\nname = \"block\"\nmodel = \"elastic\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = {container_max}\nsoil_contact = {contact}\n\n\
         [[soil_blocks]]\nmaterial = \"block\"\nshape = \"box\"\nmin = {lo}\nmax = {hi}\nvelocity = [1.0, 0.0, 0.0]\n"
    );
    let scene = common::scene(&text);
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let mass: f64 = m.solver.masses().iter().sum();
    let mut out = vec![(0.0, m.solver.momentum()[0] / mass)];
    let mut t = 0.0;
    while t < end {
        t += m.solver.step(Some(end - t)).expect("step").dt;
        out.push((t, m.solver.momentum()[0] / mass));
    }
    assert_eq!(m.solver.active(), m.solver.len(), "nothing leaves the box");
    out
}

fn at(series: &[(f64, f64)], t: f64) -> f64 {
    series.iter().min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs())).map_or(f64::NAN, |p| p.1)
}

#[test]
fn a_block_keeps_its_momentum_on_a_smooth_floor_and_decelerates_at_mu_g_on_a_frictional_one() {
    let smooth = slide("\"smooth\"", 0.15);
    let mu = 0.3;
    let friction = slide(&format!("{{ friction = {mu} }}"), 0.2);
    let rough = slide("\"rough\"", 0.15);
    for (name, s) in [("smooth", &smooth), ("friction", &friction), ("rough", &rough)] {
        let samples: Vec<String> =
            [0.0, 0.01, 0.02, 0.05, 0.1, 0.15].iter().map(|&t| format!("{:.3}", at(s, t))).collect();
        eprintln!("{name}: v at 0, 0.01, 0.02, 0.05, 0.1, 0.15 s: {}", samples.join(", "));
    }
    let (v_s, v_f, v_r) = (at(&smooth, 0.15), at(&friction, 0.15), at(&rough, 0.15));
    // Deceleration: the least-squares slope of v(t) over the whole slide, 0–0.2 s (Coulomb
    // friction gives v0 − μ g t while the block slides; it stops at v0 / (μ g) = 0.34 s).
    let pts: Vec<(f64, f64)> = friction.iter().copied().filter(|p| p.0 <= 0.2).collect();
    let n = pts.len() as f64;
    let (mt, mv) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let stt: f64 = pts.iter().map(|p| (p.0 - mt).powi(2)).sum();
    let stv: f64 = pts.iter().map(|p| (p.0 - mt) * (p.1 - mv)).sum();
    let decel = -stv / stt;
    let g = 9.81;
    eprintln!(
        "after 0.15 s: smooth {v_s:.4} m/s, μ = {mu} {v_f:.4} m/s (deceleration {decel:.3} m/s² vs μ g = {:.3}), rough {v_r:.4} m/s",
        mu * g
    );
    // Smooth: only the normal approach is resisted, so the block keeps its speed (1 % allows
    // the artificial viscosity of the first contact).
    assert!((v_s - 1.0).abs() < 0.01, "smooth floor: {v_s} m/s after 0.15 s (from 1 m/s)");
    // Coulomb: μ g within 5 % (the normal traction rings as the block settles onto the floor).
    assert!((decel / (mu * g) - 1.0).abs() < 0.05, "deceleration {decel:.3} m/s² vs μ g = {:.3}", mu * g);
    // And v(0.15 s) itself, against v0 − μ g t = 0.559 m/s.
    assert!((v_f - (1.0 - mu * g * 0.15)).abs() < 0.05, "μ floor: {v_f} m/s at 0.15 s vs 0.559");
    // Rough (no slip): the floor grips the block's base, which rings back and forth.
    assert!(v_r < v_f, "rough {v_r} m/s should be slower than μ = {mu} {v_f} m/s");
}

#[test]
fn a_container_sets_its_floor_apart_from_its_side_walls() {
    // A block filling a channel slides along both side walls. Smooth everywhere: nothing
    // brakes it. Rough walls over a smooth floor: the walls alone brake it. Smooth walls over
    // a rough floor: the floor holds it as it holds the open block. A μ floor between smooth
    // walls is refused (one coefficient for the walls' markers; the error is checked below).
    let free = slide_in_channel("\"smooth\"", 0.1);
    let walls_only = slide_in_channel("{ floor = \"smooth\", walls = \"rough\" }", 0.1);
    let floor_only = slide_in_channel("{ floor = \"rough\", walls = \"smooth\" }", 0.1);
    let open_rough = slide("\"rough\"", 0.1);
    let (v_free, v_w) = (at(&free, 0.1), at(&walls_only, 0.1));
    // How far the block slid in the first 0.1 s (∫ v dt).
    let slid = |s: &[(f64, f64)]| {
        s.windows(2).filter(|w| w[1].0 <= 0.1).map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0)).sum::<f64>()
    };
    let (x_f, x_open) = (slid(&floor_only), slid(&open_rough));
    eprintln!(
        "channel, v(0.1 s) from 1 m/s: smooth {v_free:.4}, rough walls on a smooth floor {v_w:.4} m/s; slid in 0.1 s: \
         smooth walls on a rough floor {:.1} mm, open block on a rough floor {:.1} mm, smooth channel {:.1} mm",
        1e3 * x_f,
        1e3 * x_open,
        1e3 * slid(&free)
    );
    assert!((v_free - 1.0).abs() < 0.01, "smooth channel: {v_free} m/s after 0.1 s (from 1 m/s)");
    assert!(v_w < 0.9, "rough side walls should brake the block: {v_w} m/s after 0.1 s");
    // The rough floor grips the base of either block, which then rings back and forth about
    // where it was caught: it slides a few millimetres, not the 100 mm of the smooth channel.
    assert!(x_f.abs() < 0.02 && x_open.abs() < 0.02, "slid {x_f} m (channel) and {x_open} m (open) on a rough floor");
}

#[test]
fn a_rough_contact_is_bit_identical_to_none_and_wrong_contacts_are_one_line_errors() {
    // `soil_contact = "rough"` written out changes nothing.
    let a = slide("\"rough\"", 0.01);
    let text = "[simulation]\nend_time = 0.01\nprecision = \"f64\"\n\n[sph]\nspacing = 0.01\n\n\
         [[materials]]\nname = \"block\"\nmodel = \"elastic\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.8, 0.2, 0.2]\n\n\
         [[soil_blocks]]\nmaterial = \"block\"\nshape = \"box\"\nmin = [0.05, 0.05, 0.0]\nmax = [0.15, 0.15, 0.05]\nvelocity = [1.0, 0.0, 0.0]\n";
    let scene = common::scene(text);
    let mut m = build_soil::<f64>(&scene).expect("builds");
    let mass: f64 = m.solver.masses().iter().sum();
    let mut t = 0.0;
    let mut b = vec![(0.0, m.solver.momentum()[0] / mass)];
    while t < 0.01 {
        t += m.solver.step(Some(0.01 - t)).expect("step").dt;
        b.push((t, m.solver.momentum()[0] / mass));
    }
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.1.to_bits(), y.1.to_bits());
    }
    let err = |c: &str| {
        let t = text.replace("max = [0.8, 0.2, 0.2]\n", &format!("max = [0.8, 0.2, 0.2]\nsoil_contact = {c}\n"));
        let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("inline.toml");
        regolith::scene::load_scene_source(&p, &t, &[]).expect_err("refused").to_string()
    };
    assert!(err("\"slippery\"").contains("key `container.soil_contact`: \"slippery\" is not a contact; allowed:"));
    assert!(err("{ friction = -1.0 }").contains("friction must be finite and ≥ 0"));
    assert!(
        err("{ floor = \"smooth\", walls = { friction = 0.2 } }")
            .contains("key `container.soil_contact`: floor (\"smooth\") and walls ({ friction = 0.2 }) differ and neither is rough"),
        "{}",
        err("{ floor = \"smooth\", walls = { friction = 0.2 } }")
    );
}

#[test]
fn non_rough_bodies_are_refused_in_one_line() {
    let text = "[simulation]\nend_time = 0.01\nprecision = \"f32\"\n\n[sph]\nspacing = 0.02\nneighbor_skin = 0.0\n\n\
         [[materials]]\nname = \"s\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 2e6\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\nsoil_contact = \"smooth\"\n\n[terrain]\nmaterial = \"s\"\ndepth = 0.1\n";
    let body = text.replace("soil_contact = \"smooth\"\n", "")
        + "\n[[bodies]]\nname = \"plate\"\nshape = { type = \"box\", size = [0.05, 0.05, 0.02] }\nmass = 1.0\nposition = [0.1, 0.1, 0.15]\nsoil_contact = \"smooth\"\n";
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("inline.toml");
    let e = regolith::scene::load_scene_source(&p, &body, &[]).expect_err("refused").to_string();
    assert!(e.contains("key `bodies[0].soil_contact`: bodies have rough soil contact only so far"), "{e}");
}
