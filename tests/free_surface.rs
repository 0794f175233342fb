//! The free-surface indicator flags the top layer of a resting bed and nothing below it, for
//! both kernels and the usual range of h/d0 — the anchor's default flagged nothing. Particles
//! touching walls are in contact, not free. Detached particles carry no stress; in the `zero`
//! mode flagged particles carry none either, in the default `keep` mode they keep theirs.

mod common;

use regolith::build::build_soil;

fn bed(kernel: &str, h_factor: f64, extra: &str) -> String {
    format!(
        "[simulation]\nend_time = 1.0\nprecision = \"f64\"\n\n[sph]\nspacing = 0.02\nkernel = \"{kernel}\"\nh_factor = {h_factor}\nbce_layers = 4\n{extra}\n\
         [[materials]]\nname = \"sand\"\nmodel = \"drucker-prager\"\ndensity = 1600\nyoungs_modulus = 1e7\npoisson_ratio = 0.3\nfriction_angle = 30.0\n\n\
         [container]\nmin = [0.0, 0.0, 0.0]\nmax = [0.4, 0.4, 0.4]\n\n[terrain]\nmaterial = \"sand\"\ndepth = 0.2\n\n\
         [[soil_blocks]]\nmaterial = \"sand\"\nshape = \"box\"\nmin = [0.18, 0.18, 0.34]\nmax = [0.2, 0.2, 0.36]\n"
    )
}

#[test]
fn flags_the_top_layer_and_nothing_deep() {
    for kernel in ["wendland", "cubic"] {
        for hf in [1.2, 1.3, 1.5] {
            let scene = common::scene(&bed(kernel, hf, ""));
            let d0 = scene.solver.spacing;
            let mut m = build_soil::<f64>(&scene).expect("builds");
            m.solver.step(None).expect("step");
            let s = m.solver.as_cpu().expect("a CPU scene");
            let n = s.active();
            // The single particle floating above the bed (z ≈ 0.36) is detached.
            let top_z = 10.0 * d0;
            let (mut top, mut top_flagged, mut deep_flagged) = (0, 0, 0);
            for i in 0..n {
                let p = s.positions()[i].as_f64();
                if p[2] > 0.3 {
                    assert!(s.detached()[i] && s.free_surface()[i], "the isolated particle is detached");
                    assert_eq!(s.stresses()[i].as_f64(), [0.0; 6], "a detached particle carries no stress");
                    continue;
                }
                // Away from the walls (no marker within the support 2h).
                let reach = 2.0 * hf * d0;
                let wall_distance = p[0].min(0.4 - p[0]).min(p[1]).min(0.4 - p[1]);
                let near_wall = wall_distance < reach - 1e-9;
                let far_from_wall = wall_distance > reach + 1e-9;
                if (p[2] - top_z).abs() < 0.25 * d0 {
                    if far_from_wall {
                        top += 1;
                        top_flagged += usize::from(s.free_surface()[i]);
                    }
                } else if s.free_surface()[i] {
                    deep_flagged += 1;
                }
                if near_wall {
                    assert!(!s.free_surface()[i], "a particle touching the wall markers is in contact, not free");
                }
            }
            assert!(top > 50);
            assert_eq!(top_flagged, top, "{kernel} h/d0 = {hf}: top layer not fully flagged");
            assert_eq!(deep_flagged, 0, "{kernel} h/d0 = {hf}: particles below the top layer flagged");
            // Default mode keeps the surface stress (the top layer's own weight).
            let kept =
                (0..n).filter(|&i| s.free_surface()[i] && !s.detached()[i]).all(|i| s.stresses()[i].as_f64()[2] < 0.0);
            assert!(kept, "keep mode zeroed a surface stress");
        }
    }
}

#[test]
fn zero_mode_zeroes_surface_stress() {
    let scene = common::scene(&bed("wendland", 1.2, "free_surface_stress = \"zero\"\n"));
    let mut m = build_soil::<f32>(&scene).expect("builds");
    m.solver.step(None).expect("step");
    let s = m.solver.as_cpu().expect("a CPU scene");
    let flagged: Vec<usize> = (0..s.active()).filter(|&i| s.free_surface()[i]).collect();
    assert!(flagged.len() > 50);
    for i in flagged {
        assert_eq!(s.stresses()[i].as_f64(), [0.0; 6]);
    }
}
