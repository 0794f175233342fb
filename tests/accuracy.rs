//! `regolith study accuracy`: the quick budget (what CI runs) over the geostatic bed and the
//! squat column collapse, the reading and checking of case files, and run-to-run identity of
//! a point.

use std::path::{Path, PathBuf};

use regolith::accuracy::{AccuracyOptions, BUDGETS, CSV_COLUMNS, accuracy, case::read_case};
use regolith::study::StudyError;
use regolith::sweep::{Plan, lookup};

fn study_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/study")
}

#[test]
fn the_quick_budget_shows_errors_falling_with_d0_and_complete_rows() {
    let out = crate::common::out_dir("accuracy_quick");
    let opts = AccuracyOptions {
        cases_dir: study_dir(),
        cases: vec!["geostatic_bed".into(), "column_a05".into()],
        budget: "quick".into(),
        jobs: 1,
        out: out.clone(),
        quiet: true,
    };
    let a = accuracy(&opts).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.cases.len(), 2);
    for c in &a.cases {
        let ladder: Vec<_> = c.rows.iter().filter(|r| r.knob == "d0").collect();
        assert!(ladder.len() >= 4, "{}: {} ladder levels", c.case, ladder.len());
        for r in &c.rows {
            eprintln!(
                "{} {}={}: measured {:.5} reference {:.5} rel {:+.3} % wall {:.1} s",
                c.case,
                r.knob,
                r.setting,
                r.measured,
                r.reference,
                100.0 * r.rel_error,
                r.wall_s
            );
            assert!(r.failure.is_none(), "{} {}: {:?}", c.case, r.setting, r.failure);
            assert!(r.error.is_finite() && r.rel_error.is_finite(), "{}: error {}", c.case, r.error);
            assert!(r.wall_s > 0.0 && r.steps > 0 && r.particle_steps > 0.0);
            assert!(r.command.starts_with("regolith run ") && r.command.contains("--set sph.spacing="));
            assert!(r.peak_mem_bytes.is_some_and(|b| b > 0), "one job: each point's peak memory is measured");
        }
        eprintln!("{}: order {:.3} ({:?}), range {:?}", c.case, c.order.order, c.order.note, c.order.range);
        assert!(c.order.order > 0.5, "{}: observed order {:.3} over the ladder (≤ 0.5)", c.case, c.order.order);
        assert!(!c.pareto.is_empty(), "{}: a Pareto front", c.case);
    }
    let csv = std::fs::read_to_string(out.join("accuracy.csv")).expect("accuracy.csv");
    assert_eq!(csv.lines().next(), Some(CSV_COLUMNS.join(",").as_str()));
    assert_eq!(csv.lines().count(), 1 + a.cases.iter().map(|c| c.rows.len()).sum::<usize>());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("accuracy.json")).expect("json")).expect("parses");
    assert_eq!(json["cases"].as_array().map(Vec::len), Some(2));
    let md = std::fs::read_to_string(out.join("accuracy.md")).expect("accuracy.md");
    assert!(md.contains("## Recommendations") && md.contains("## geostatic_bed") && md.contains("## column_a05"));
    for stem in ["geostatic_bed_convergence", "geostatic_bed_cost", "column_a05_convergence", "column_a05_cost"] {
        assert!(out.join(format!("{stem}.png")).is_file() && out.join(format!("{stem}.svg")).is_file(), "{stem}");
    }
    // Resuming runs nothing: every point is recorded, and the tables come out the same.
    let t0 = std::time::Instant::now();
    let again = accuracy(&opts).unwrap_or_else(|e| panic!("{e}"));
    assert!(t0.elapsed().as_secs_f64() < 5.0, "a finished study was run again");
    assert_eq!(std::fs::read_to_string(out.join("accuracy.csv")).expect("csv"), csv);
    assert_eq!(again.cases[0].order.order.to_bits(), a.cases[0].order.order.to_bits());
}

#[test]
fn a_point_run_twice_gives_the_same_error_bit_for_bit() {
    let path = study_dir().join("geostatic_bed.toml");
    let source = std::fs::read_to_string(&path).expect("case");
    let case = read_case("geostatic_bed", &path, &source, "quick").unwrap_or_else(|e| panic!("{e}"));
    let coarse = case.points[0].overrides.clone();
    let plan = Plan::from_overrides(&path, vec![coarse.clone(), coarse]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(plan.points[0].id, plan.points[1].id, "the same overrides hash alike");
    let value = |dir: &str| {
        let r = plan.run_point(&plan.points[0], &crate::common::out_dir(dir));
        assert!(r.ok(), "{:?}", r.error);
        let s = r.summary.expect("summary");
        lookup(&s, &case.measure).and_then(serde_json::Value::as_f64).expect("measured")
    };
    let (a, b) = (value("accuracy_twice_a"), value("accuracy_twice_b"));
    assert_eq!(a.to_bits(), b.to_bits(), "{a} then {b}");
}

#[test]
fn every_shipped_case_reads_at_each_of_its_budgets() {
    let mut n = 0;
    for entry in std::fs::read_dir(study_dir()).expect("examples/study") {
        let p = entry.expect("entry").path();
        let text = std::fs::read_to_string(&p).expect("text");
        if !text.contains("[accuracy]") {
            continue;
        }
        let name = p.file_stem().expect("stem").to_string_lossy().into_owned();
        for b in BUDGETS {
            if text.contains(&format!("[accuracy.{b}]")) {
                let c = read_case(&name, &p, &text, b).unwrap_or_else(|e| panic!("{e}"));
                assert!(c.ladder.len() >= 4);
                n += 1;
            }
        }
    }
    assert!(n >= 4, "{n} case budgets");
}

fn case_error(body: &str) -> String {
    let dir = crate::common::out_dir("accuracy_bad_case");
    let path = dir.join("bad.toml");
    let base = std::fs::read_to_string(study_dir().join("geostatic_bed.toml")).expect("case");
    let head = &base[..base.find("[accuracy]").expect("section")];
    std::fs::write(&path, format!("{head}{body}")).expect("write");
    let opts = AccuracyOptions {
        cases_dir: dir.clone(),
        cases: vec!["bad".into()],
        budget: "quick".into(),
        jobs: 1,
        out: dir.join("out"),
        quiet: true,
    };
    match accuracy(&opts) {
        Err(StudyError::Input(e)) => {
            let m = e.to_string();
            assert!(!m.contains('\n'), "one line: {m}");
            m.replace(&format!("{}", path.display()), "FILE")
        }
        other => panic!("expected an input error, got {other:?}"),
    }
}

const GOOD: &str = "[accuracy]\nquantity = \"q\"\nmeasure = \"geostatic.sigma_v_ratio\"\nreference = 1.0\n\
                    reference_kind = \"closed-form\"\nsource = \"s\"\n";

#[test]
fn wrong_case_files_are_one_line_errors_naming_the_key() {
    let ladder = "[accuracy.quick]\nladder = [0.048, 0.033941, 0.024, 0.016971]\n";
    assert!(
        case_error(&format!("{GOOD}[accuracy.quick]\nladder = [0.048, 0.024, 0.012]\n"))
            .contains("key `accuracy.quick.ladder`: has 3 levels; a ladder needs at least 4")
    );
    assert!(
        case_error(&format!("{GOOD}[accuracy.quick]\nladder = [0.048, 0.04, 0.024, 0.012]\n"))
            .contains("allowed: √2 or 2")
    );
    assert!(case_error(&format!("{GOOD}{ladder}baseline = 0.02\n")).contains("key `accuracy.quick.baseline`"));
    assert!(case_error(&format!("{}{ladder}", GOOD.replace("closed-form", "guess"))).contains(
        "key `accuracy.reference_kind`: \"guess\" is not a kind; allowed: closed-form, experiment, self-convergence"
    ));
    assert!(
        case_error(&format!("{}{ladder}", GOOD.replace("reference = 1.0\n", "")))
            .contains("needs exactly one of reference")
    );
    // A knob that is not a scene key is reported before anything runs, with the scene's message.
    let m = case_error(&format!("{GOOD}{ladder}knobs = {{ \"sph.kernal\" = [\"cubic\"] }}\n"));
    assert!(m.contains("kernal"), "{m}");
    assert!(
        case_error(&format!("{GOOD}[accuracy.standard]\nladder = [0.048, 0.024, 0.012, 0.006]\n"))
            .contains("has no [accuracy.quick] section")
    );
    assert!(case_error(&format!("{GOOD}{ladder}bogus = 1\n")).contains("bogus"));
}

#[test]
fn study_flags_are_checked() {
    let opts = |budget: &str, cases: Vec<String>, jobs: usize| AccuracyOptions {
        cases_dir: study_dir(),
        cases,
        budget: budget.into(),
        jobs,
        out: Path::new(env!("CARGO_TARGET_TMPDIR")).join("accuracy_flags"),
        quiet: true,
    };
    let msg = |o: AccuracyOptions| match accuracy(&o) {
        Err(StudyError::Input(e)) => e.to_string(),
        other => panic!("expected an input error, got {other:?}"),
    };
    assert_eq!(msg(opts("huge", vec![], 1)), "--budget: \"huge\" is not a budget; allowed: quick, standard, full");
    assert!(msg(opts("quick", vec!["nope".into()], 1)).starts_with("--cases: no case \"nope\""));
    assert!(msg(opts("quick", vec![], 0)).starts_with("--jobs: 0 points at once"));
    // A scene of the folder that is no accuracy case, named: it says so.
    assert!(msg(opts("quick", vec!["wheel_slope_grc1".into()], 1)).contains("has no [accuracy] section"));
}
