"""Studies and calibrations on the shared runner: the stability suite's cases and a triaxial
envelope's tests as Ray tasks, from the CLI and from Python, resumable, with the same verdicts
and envelope as the threads runner."""

import json
import os
import sys

import pytest

import regolith.batch
from conftest import REPO

CASES = ["fixed_step_refused", "jet_at_wall"]


def _verdicts(out):
    table = json.loads((out / "stability.json").read_text())
    return {r["case"]: (r["pass"], [c["check"] for c in r["checks"]]) for r in table}


def _records(out):
    return [json.loads(l) for l in (out / "results.jsonl").read_text().splitlines() if l.strip()]


def test_stability_cases_run_as_ray_tasks_from_the_cli_and_resume(cli, tmp_path):
    env = {**os.environ, "REGOLITH_PYTHON": sys.executable}
    ray_out, threads_out = tmp_path / "ray", tmp_path / "threads"
    r = cli(
        "study", "stability", "--runner", "ray", "--num-cpus", "1", "--cases", ",".join(CASES),
        "--out", ray_out, cwd=REPO, env=env,
    )
    assert "2 of 2 cases pass" in r.stdout, r.stdout + r.stderr
    recs = _records(ray_out)
    assert sorted(x["out"] for x in recs) == CASES and all(x["status"] == "ok" for x in recs)
    # The same cases on threads of the CLI: the same checks and verdicts.
    cli("study", "stability", "--cases", ",".join(CASES), "--out", threads_out, cwd=REPO)
    assert _verdicts(ray_out) == _verdicts(threads_out)
    # Resumed from Python: nothing runs again, the table is rewritten from the records.
    text = regolith.batch.stability(
        CASES, size="ci", cases_dir=REPO / "examples" / "hard", out=ray_out, runner="ray", num_cpus=1,
        resume=True, quiet=True,
    )
    assert "2 of 2 cases pass" in text
    assert _records(ray_out) == recs


def test_a_wrong_batch_raises_input_error_with_the_cli_line(tmp_path):
    with pytest.raises(regolith.InputError, match=r"--cases: no case \"nope\""):
        regolith.batch.stability(["nope"], cases_dir=REPO / "examples" / "hard", out=tmp_path, runner="threads")
    with pytest.raises(regolith.InputError, match="--target-phi"):
        regolith.batch.run(
            ["calibrate", "triaxial", "--material", "m.toml", "--target-phi", "30"], runner="threads"
        )


def test_triaxial_tests_run_as_ray_tasks_and_give_the_threads_envelope(materials, tmp_path):
    """Two tests of a tiny sample (128 particles, 2 % strain) as Ray tasks; the envelope from
    their records equals the one the threads runner fits, to the round-off of rayon sums over
    a different number of threads."""
    opts = {"width": 0.04, "spacing": 0.01, "max_strain": 0.02}
    sand = materials / "sand_dp.toml"
    text = regolith.batch.triaxial(
        sand, confining=[1e4, 2e4], options=opts, out=tmp_path / "ray", runner="ray", num_cpus=1, quiet=True
    )
    assert "triaxial envelope of 2 tests" in text
    ray_fit = json.loads((tmp_path / "ray" / "triaxial.json").read_text())
    regolith.batch.triaxial(
        sand, confining=[1e4, 2e4], options=opts, out=tmp_path / "threads", runner="threads", jobs=2, quiet=True
    )
    threads_fit = json.loads((tmp_path / "threads" / "triaxial.json").read_text())
    assert len(ray_fit["tests"]) == 2
    for k in ("verticalStress", "consolidationStress"):
        for a, b in zip(ray_fit[k], threads_fit[k]):
            assert abs(a - b) <= 1e-3 * abs(b), (k, ray_fit[k], threads_fit[k])
    assert abs(ray_fit["phi"] - threads_fit["phi"]) <= 0.05


def test_accuracy_points_run_as_ray_tasks_into_their_case_folders(tmp_path):
    """The geostatic bed's quick ladder (4 points) as Ray tasks: each record lands in the
    case's folder, the study's tables come out, and a second call runs nothing."""
    cases_dir = REPO / "examples" / "study"
    text = regolith.batch.accuracy(
        ["geostatic_bed"], budget="quick", cases_dir=cases_dir, out=tmp_path, runner="ray", num_cpus=1, quiet=True
    )
    assert "geostatic_bed: order" in text, text
    recs = _records(tmp_path / "geostatic_bed")
    assert len(recs) == 4 and all(r["status"] == "ok" for r in recs)
    rows = (tmp_path / "accuracy.csv").read_text().splitlines()
    assert len(rows) == 1 + 4
    again = regolith.batch.accuracy(
        ["geostatic_bed"], budget="quick", cases_dir=cases_dir, out=tmp_path, runner="ray", num_cpus=1, quiet=True
    )
    assert again == text
    assert _records(tmp_path / "geostatic_bed") == recs
