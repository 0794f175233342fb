//! `regolith sweep`: the plan and the threads runner are the library's ([`crate::sweep`]);
//! the Ray runner is the Python package's `regolith.sweep`, started here with the same
//! arguments once they have been checked.

use std::path::Path;

use super::ray::{check_ray_flags, run_module};
use super::{DesignArg, Failure, RunnerArg, SweepArgs};
use crate::input::InputError;
use crate::sweep::{Design, Plan, Shard, merge as merge_dir, parse_vary, run_local};

pub(super) fn converge(dir: &Path, over: &str, metric: &str) -> Result<(), Failure> {
    let ladders = crate::sweep::converge(dir, over, metric)?;
    for l in &ladders {
        let fixed: Vec<String> = l.fixed.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let at = if fixed.is_empty() { "all points".to_string() } else { fixed.join(" ") };
        let levels: Vec<String> = l.levels.iter().map(|(h, f)| format!("{h}: {f:.6e}")).collect();
        match &l.convergence {
            Some(c) => println!(
                "{at}: {metric} → {:.6e} ± {:.2e} (GCI), order {:.2} (triplets {:.2}–{:.2}) over {} levels [{}]",
                c.limit,
                c.gci,
                c.order,
                c.order_range.0,
                c.order_range.1,
                l.levels.len(),
                levels.join(", ")
            ),
            None => println!("{at}: no estimate: {} [{}]", l.error.as_deref().unwrap_or("?"), levels.join(", ")),
        }
        if !l.missing.is_empty() {
            println!("  points without a value (failed or lacking {metric}): {:?}", l.missing);
        }
    }
    let path = dir.join("convergence.json");
    let doc = serde_json::json!({ "over": over, "metric": metric, "ladders": ladders });
    let text =
        serde_json::to_string_pretty(&doc).map_err(|e| Failure::Run(anyhow::anyhow!("convergence.json: {e}")))?;
    std::fs::write(&path, text).map_err(|e| Failure::Run(anyhow::anyhow!("writing {}: {e}", path.display())))?;
    println!("convergence of {} ladder(s) in {}", ladders.len(), path.display());
    Ok(())
}

pub(super) fn merge(dir: &Path) -> Result<(), Failure> {
    let n = merge_dir(dir)?;
    println!("merged {n} points into {} and results.csv", dir.join("results.jsonl").display());
    Ok(())
}

pub(super) fn run(a: SweepArgs) -> Result<(), Failure> {
    let scene =
        a.scene.clone().ok_or_else(|| InputError::flag("SCENE", "a sweep needs a scene file (or `merge DIR`)"))?;
    let sets = a
        .sets
        .iter()
        .map(|s| crate::scene::parse_set(s).map_err(|m| InputError::flag("--set", m)))
        .collect::<Result<Vec<_>, _>>()?;
    let vary = a.vary.iter().map(|v| parse_vary(v)).collect::<Result<Vec<_>, _>>()?;
    let design = match (a.design, a.samples) {
        (DesignArg::Grid, None) => Design::Grid,
        (DesignArg::Grid, Some(_)) => return Err(InputError::flag("--samples", "applies to --design lhs only").into()),
        (DesignArg::Lhs, Some(samples)) => Design::Lhs { samples, seed: a.seed },
        (DesignArg::Lhs, None) => return Err(InputError::flag("--samples", "is required with --design lhs").into()),
    };
    let shard = match &a.shard {
        Some(s) => Some(Shard::parse(s)?),
        None => Shard::from_slurm(|k| std::env::var(k).ok())?,
    };
    // Checked here whatever the runner: a wrong key or value is known before anything starts.
    let plan = Plan::new(&scene, &sets, &vary, design)?;
    match a.runner {
        RunnerArg::Threads => {
            for (flag, given) in [
                ("--address", a.address.is_some()),
                ("--num-cpus", a.num_cpus.is_some()),
                ("--num-gpus", a.num_gpus.is_some()),
            ] {
                if given {
                    return Err(InputError::flag(flag, "applies to --runner ray only").into());
                }
            }
            let jobs = a.jobs.unwrap_or(1);
            if jobs == 0 {
                return Err(InputError::flag("--jobs", "must be at least 1").into());
            }
            let o = run_local(&plan, &a.out, shard, jobs, a.retry_failed, a.quiet)?;
            let target = if shard.is_some() {
                "results.shard-*.jsonl (join with `regolith sweep merge`)"
            } else {
                "results.csv"
            };
            println!(
                "sweep: {} points, {} already recorded, {} ran ({} failed); results in {}",
                o.points,
                o.skipped,
                o.ok + o.failed,
                o.failed,
                a.out.join(target).display()
            );
            if o.failed > 0 {
                return Err(Failure::Run(anyhow::anyhow!(
                    "{} of the sweep's points failed (see results.jsonl)",
                    o.failed
                )));
            }
            Ok(())
        }
        RunnerArg::Ray => {
            check_ray_flags(a.jobs, a.num_cpus, a.num_gpus)?;
            ray(&a, shard)
        }
    }
}

/// Starts `python -m regolith.sweep` with the sweep's arguments and passes its exit code on.
fn ray(a: &SweepArgs, shard: Option<Shard>) -> Result<(), Failure> {
    let mut args: Vec<String> = Vec::new();
    let scene = a.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
    args.push(scene);
    for v in &a.vary {
        args.extend(["--vary".into(), v.clone()]);
    }
    for s in &a.sets {
        args.extend(["--set".into(), s.clone()]);
    }
    if a.design == DesignArg::Lhs {
        args.extend(["--design".into(), "lhs".into(), "--seed".into(), a.seed.to_string()]);
    }
    if let Some(n) = a.samples {
        args.extend(["--samples".into(), n.to_string()]);
    }
    if let Some(addr) = &a.address {
        args.extend(["--address".into(), addr.clone()]);
    }
    if let Some(n) = a.num_cpus {
        args.extend(["--num-cpus".into(), n.to_string()]);
    }
    if let Some(n) = a.num_gpus {
        args.extend(["--num-gpus".into(), n.to_string()]);
    }
    if let Some(s) = shard {
        args.extend(["--shard".into(), format!("{}/{}", s.index, s.count)]);
    }
    if a.retry_failed {
        args.push("--retry-failed".into());
    }
    if a.quiet {
        args.push("--quiet".into());
    }
    args.extend(["--out".into(), a.out.display().to_string()]);
    let (python, status) = run_module("sweep", &args)?;
    match status.code() {
        Some(0) => Ok(()),
        Some(2) => Err(Failure::Reported(2)),
        Some(130) => Err(Failure::Interrupted("sweep interrupted; rerun it to run the points not yet recorded".into())),
        _ => Err(Failure::Run(anyhow::anyhow!("the Ray sweep ({python} -m regolith.sweep) failed: {status}"))),
    }
}
