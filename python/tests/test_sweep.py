"""Sweeps: on a local Ray instance (from Python and from the CLI), resumed after a kill, with a
failed point, and in SLURM-style shards merged."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

import regolith.sweep

# A single-wheel slip sweep sized to about 2 s a point on 2 cores.
SMALL = {"sph.spacing": 0.02, "simulation.end_time": 0.1, "output.every": 0.1}
SLIPS = [0.0, 0.2, 0.4, 0.6]


def _sets():
    return [f"{k}={regolith.sweep.toml_literal(v)}" for k, v in SMALL.items()]


def _lines(path):
    if not path.exists():
        return []
    return [json.loads(l) for l in path.read_text().splitlines() if l.strip()]


def test_slip_sweep_on_local_ray_writes_one_row_per_point(scenes, tmp_path):
    rows = regolith.sweep.run(
        scenes / "single_wheel.toml",
        vary={"rig.slips": SLIPS},
        sets=SMALL,
        out=tmp_path,
        runner="ray",
        num_cpus=1,
        quiet=True,
    )
    assert [r["status"] for r in rows] == ["ok"] * 4
    assert [r["overrides"]["rig.slips"] for r in rows] == [[s] for s in SLIPS]
    csv = (tmp_path / "results.csv").read_text().splitlines()
    assert len(csv) == 1 + 4
    header = csv[0].split(",")
    assert {"point", "id", "status", "set:rig.slips", "wall_s", "error"} <= set(header)
    # The rig's per-slip result is a column of the tidy table.
    assert any(h.startswith("rig.") for h in header)
    for r in rows:
        assert (tmp_path / r["out"] / "summary.json").exists()
        assert r["summary"]["rig"]["type"] == "wheel"


def test_a_killed_sweep_resumes_with_the_points_not_recorded(scenes, tmp_path):
    """SIGINT after two records: what finished stays recorded, the rerun runs only the other
    two. Points 0 and 1 are three times shorter than 2 and 3 (2 and 3 still take seconds), so
    however many points Ray runs at once (it sizes itself to the machine's cores) the interrupt
    lands while 2 and 3 still run."""
    args = [sys.executable, "-m", "regolith.sweep", str(scenes / "single_wheel.toml"), "--out", str(tmp_path)]
    args += ["--vary", "simulation.end_time=0.05,0.06,0.15,0.16", "--num-cpus", "1"]
    for s in _sets():
        if not s.startswith("simulation.end_time"):
            args += ["--set", s]
    args += ["--set", "output.every=0.05"]
    # The sweep's own SIGINT disposition is the user's: a test run from a background job
    # (CI's) inherits SIGINT ignored, as a nohup'd sweep would. Ctrl-C in a terminal is what
    # is tested, so the child starts with the default disposition.
    default_sigint = lambda: signal.signal(signal.SIGINT, signal.SIG_DFL)
    first = subprocess.Popen(args, stderr=subprocess.PIPE, text=True, preexec_fn=default_sigint)
    results = tmp_path / "results.jsonl"
    deadline = time.monotonic() + 240
    while len(_lines(results)) < 2 and time.monotonic() < deadline and first.poll() is None:
        time.sleep(0.02)
    first.send_signal(signal.SIGINT)
    _, err1 = first.communicate(timeout=120)
    done = len(_lines(results))
    assert done == 2, f"killed after {done} points: {err1[-2000:]}"
    assert sorted(r["point"] for r in _lines(results)) == [0, 1], "the short points finished first"
    assert first.returncode == 130, err1[-2000:]
    assert "rerun the same command" in err1
    second = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert second.returncode == 0, second.stderr[-2000:]
    assert f"{done} already recorded, {4 - done} to run" in second.stderr
    recs = _lines(results)
    assert len(recs) == 4, "each point recorded once"
    assert sorted(r["point"] for r in recs) == [0, 1, 2, 3]
    assert len((tmp_path / "results.csv").read_text().splitlines()) == 5


def test_cli_runs_a_ray_sweep_and_records_a_bad_point_as_failed(cli, scenes, tmp_path):
    """From the CLI on Ray: a point with a spacing that does not validate is recorded with the
    one-line error; the other point finishes; the exit code says a point failed."""
    env = {**os.environ, "REGOLITH_PYTHON": sys.executable}
    sets = [a for s in _sets() if not s.startswith("sph.spacing") for a in ("--set", s)]
    r = cli(
        "sweep", scenes / "single_wheel.toml", "--vary", "sph.spacing=0.02,-1", "--vary", "rig.slips=0.2",
        *sets, "--num-cpus", "1", "--out", tmp_path, "--quiet", check=False, env=env,
    )
    assert r.returncode == 1, r.stderr
    recs = regolith.sweep.records(tmp_path)
    assert [x["status"] for x in recs] == ["ok", "failed"]
    assert "sph.spacing" in recs[1]["error"] and "must be > 0" in recs[1]["error"]
    assert "\n" not in recs[1]["error"]
    assert "1 failed" in r.stdout


def _comparable(rec):
    """A record without what depends on the clock, the process or the output folder (the peak
    memory is recorded only for points that ran alone, and differs from run to run)."""
    rec = dict(rec)
    rec.pop("wall_s")
    rec.pop("peak_mem_bytes", None)
    s = dict(rec.pop("summary"))
    for k in ("wall_time_s", "particle_steps_per_s", "outputs", "scene"):
        s.pop(k, None)
    rec["summary"] = s
    return rec


def _assert_same(a, b, where="record"):
    """Equal, floats to 1e-9 relative: sums over particles (mass, sinkage, forces) are rayon
    reductions whose order depends on how many threads a point ran on (--jobs 2 gives each
    point one thread, a shard two), so they agree to round-off, not bit for bit."""
    if isinstance(a, float) and isinstance(b, (int, float)):
        assert abs(a - b) <= 1e-9 * max(abs(a), abs(b), 1e-30), f"{where}: {a} != {b}"
    elif isinstance(a, dict) and isinstance(b, dict):
        assert a.keys() == b.keys(), f"{where}: keys {sorted(a)} != {sorted(b)}"
        for k in a:
            _assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list) and isinstance(b, list):
        assert len(a) == len(b), f"{where}: length {len(a)} != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            _assert_same(x, y, f"{where}[{i}]")
    else:
        assert a == b, f"{where}: {a!r} != {b!r}"


def _cell(c):
    try:
        return float(c)
    except ValueError:
        return c


def test_shards_merged_equal_the_unsharded_sweep(cli, scenes, tmp_path):
    common = [scenes / "single_wheel.toml", "--vary", "rig.slips=" + ",".join(map(str, SLIPS[:3]))]
    common += [a for s in _sets() for a in ("--set", s)] + ["--runner", "threads", "--quiet"]
    cli("sweep", *common, "--jobs", "2", "--out", tmp_path / "whole")
    for i in (1, 2):
        cli("sweep", *common, "--shard", f"{i}/2", "--out", tmp_path / "sharded")
    assert not (tmp_path / "sharded" / "results.csv").exists(), "shards write only their own records"
    assert len(_lines(tmp_path / "sharded" / "results.shard-1-of-2.jsonl")) == 2
    assert len(_lines(tmp_path / "sharded" / "results.shard-2-of-2.jsonl")) == 1
    r = cli("sweep", "merge", tmp_path / "sharded")
    assert "merged 3 points" in r.stdout
    whole = [_comparable(x) for x in regolith.sweep.records(tmp_path / "whole")]
    merged = [_comparable(x) for x in _lines(tmp_path / "sharded" / "results.jsonl")]
    _assert_same(merged, whole)
    header = (tmp_path / "whole" / "results.csv").read_text().splitlines()[0].split(",")
    drop = {i for i, h in enumerate(header) if h in ("wall_s", "peak_mem_bytes", "wall_time_s", "particle_steps_per_s", "scene")}
    table = lambda p: [[_cell(c) for i, c in enumerate(l.split(",")) if i not in drop] for l in p.read_text().splitlines()]
    _assert_same(table(tmp_path / "sharded" / "results.csv"), table(tmp_path / "whole" / "results.csv"), "csv")


def test_slurm_array_environment_picks_the_shard(cli, scenes, tmp_path):
    common = [scenes / "single_wheel.toml", "--vary", "rig.slips=0.0,0.2,0.4"]
    common += [a for s in _sets() for a in ("--set", s)] + ["--runner", "threads", "--quiet", "--out", tmp_path]
    env = {**os.environ, "SLURM_ARRAY_TASK_ID": "3", "SLURM_ARRAY_TASK_COUNT": "3", "SLURM_ARRAY_TASK_MIN": "1"}
    cli("sweep", *common, env=env)
    recs = _lines(tmp_path / "results.shard-3-of-3.jsonl")
    assert [r["point"] for r in recs] == [2]
    bad = cli("sweep", *common, "--shard", "4/3", check=False)
    assert bad.returncode == 2 and bad.stderr.startswith("error: --shard: `4/3`")


def test_the_python_examples_run(tmp_path):
    """examples/python/: the cone probe (push, hold, withdraw) and the slip sweep, sized down."""
    examples = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python")
    r = subprocess.run(
        [sys.executable, os.path.join(examples, "cone_probe.py"), "--spacing", "0.008", "--depth", "0.01",
         "--hold", "0.02", "--out", str(tmp_path / "cone")],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    lines = (tmp_path / "cone" / "cone_probe.csv").read_text().splitlines()
    phases = {l.split(",")[1] for l in lines[1:]}
    assert phases == {"push", "hold", "withdraw"}, phases
    r = subprocess.run(
        [sys.executable, os.path.join(examples, "wheel_slip.py"), "--slips", "0.2,0.4", "--spacing", "0.02",
         "--end-time", "0.1", "--runner", "threads", "--out", str(tmp_path / "wheel")],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    assert "DBP (N)" in r.stdout and len((tmp_path / "wheel" / "results.csv").read_text().splitlines()) == 3


def test_a_spacing_ladder_converges_from_python_and_the_cli(cli, scenes, tmp_path):
    """Three spacings of the cone scene: one ladder, three levels, from Python and from
    `regolith sweep converge` alike (the same JSON); a metric the sweep lacks is an InputError."""
    sets = ["--set", "simulation.end_time=0.1", "--runner", "threads", "--jobs", "2", "--quiet"]
    cli("sweep", scenes / "cone_penetrometer.toml", "--vary", "sph.spacing=0.012,0.01,0.008", *sets, "--out", tmp_path)
    ladders = regolith.sweep.converge(tmp_path, "rig.max_force_n")
    assert len(ladders) == 1
    l = ladders[0]
    assert l["fixed"] == {"simulation.end_time": 0.1}
    assert [h for h, _ in l["levels"]] == [0.012, 0.01, 0.008]
    assert (l["convergence"] is None) != (l["error"] is None), l
    r = cli("sweep", "converge", tmp_path, "--metric", "rig.max_force_n")
    assert "convergence of 1 ladder(s)" in r.stdout
    on_disk = json.loads((tmp_path / "convergence.json").read_text())
    assert on_disk["ladders"] == ladders
    with pytest.raises(regolith.InputError, match="--metric: no finished point"):
        regolith.sweep.converge(tmp_path, "rig.no_such_value")
