"""Studies and calibrations whose runs are independent — the stability suite's cases, a
triaxial envelope's tests — on Ray (one task per run) or on threads of this process, through
the same runner as sweeps.

    import regolith.batch
    print(regolith.batch.stability(cases=["jet_at_wall", "soil_soft"], size="ci", out="out/stab"))
    print(regolith.batch.triaxial("examples/materials/sand.toml", confining=[1e4, 2e4, 3e4]))

A batch is named by its command line, as after ``regolith`` (``["study", "stability", "--size",
"ci"]``): the Rust library reads and checks it exactly as the CLI does, lists its runs, runs
each (in a Ray task here) and writes the tables from the records. Each finished run is one
line of the output folder's ``results.jsonl``; with ``resume=True`` the runs already
recorded there (same inputs, same version) are not run again. ``regolith study stability
--runner ray`` and ``regolith calibrate triaxial --runner ray`` call this module.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Any, Iterable, List, Optional, Sequence

from . import _regolith
from ._regolith import InputError, RunError
from .sweep import _Progress, _schedule_ray, _schedule_threads

__all__ = ["run", "stability", "accuracy", "triaxial", "main"]


def run(
    args: Sequence[str],
    *,
    runner: str = "ray",
    address: Optional[str] = None,
    num_cpus: float = 1.0,
    num_gpus: float = 0.0,
    jobs: int = 1,
    resume: bool = False,
    retry_failed: bool = False,
    quiet: bool = False,
) -> str:
    """Runs the batch ``args`` (a ``study stability``, ``study accuracy``, ``calibrate triaxial``
    or ``calibrate plate`` command line)
    and returns the text the CLI prints. Raises ``InputError`` for a wrong argument and
    ``RunError`` when a stability case fails its bounds or a run could not be carried out
    (after every other run has finished and the tables are written)."""
    args = [os.fspath(a) if isinstance(a, os.PathLike) else str(a) for a in args]
    if runner not in ("ray", "threads"):
        raise InputError(f"runner: {runner!r} (allowed: 'ray', 'threads')")
    if runner == "threads" and (address is not None or num_gpus):
        raise InputError("address, num_gpus: apply to runner='ray' only")
    if not (num_cpus > 0 and num_gpus >= 0 and jobs >= 1):
        raise InputError(f"num_cpus must be > 0, num_gpus >= 0 and jobs >= 1 (got {num_cpus}, {num_gpus}, {jobs})")
    info = json.loads(_regolith.batch_runs_json(args))
    pending = _regolith.batch_pending(args, resume, retry_failed)
    slots = jobs if runner == "threads" else max(1, int((os.cpu_count() or 1) // max(num_cpus, 1)))
    # Keyed by configuration id: the accuracy study numbers its points per case.
    labels = {r["id"]: r["label"] for r in info["runs"]}
    folders = {r["id"]: r["folder"] for r in info["runs"]}
    what = info["what"]
    if not quiet:
        how = f"Ray ({address or 'local instance'})" if runner == "ray" else f"{jobs} thread(s)"
        print(
            f"{what}: {len(info['runs'])} runs, {len(info['runs']) - len(pending)} already recorded, "
            f"{len(pending)} to run on {how}",
            file=sys.stderr,
            flush=True,
        )
    progress = _Progress(len(pending), slots, quiet, what=what, labels=labels)

    def record(line: str, running: int) -> None:
        rec = json.loads(line)
        _regolith.sweep_append(folders[rec["id"]], line, None)
        progress.done(rec, running)

    calls = [("batch_run", (args, i)) for i in pending]
    if calls:
        if runner == "ray":
            _schedule_ray(calls, record, address, num_cpus, num_gpus)
        else:
            _schedule_threads(calls, record, jobs)
    return _regolith.batch_finish(args)


def _flag_list(flag: str, values: Optional[Iterable[Any]]) -> List[str]:
    if values is None:
        return []
    values = [str(v) for v in values]
    if not values:
        raise InputError(f"{flag.lstrip('-').replace('-', '_')}: give at least one value")
    return [flag, ",".join(values)]


def stability(
    cases: Optional[Iterable[str]] = None,
    *,
    size: str = "ci",
    cases_dir: Optional[str] = None,
    out: str = "out/stability",
    **runner: Any,
) -> str:
    """The stability suite (``regolith study stability``): ``cases`` (default all) of
    ``cases_dir`` (default ``examples/hard``) at ``size`` (``"ci"`` or ``"full"``), each
    checked against its bounds. ``runner`` takes the keywords of ``run``."""
    args = ["study", "stability", "--size", str(size), "--out", os.fspath(out)]
    args += _flag_list("--cases", cases)
    if cases_dir is not None:
        args += ["--cases-dir", os.fspath(cases_dir)]
    return run(args, **runner)


def accuracy(
    cases: Optional[Iterable[str]] = None,
    *,
    budget: str = "standard",
    cases_dir: Optional[str] = None,
    out: str = "out/accuracy",
    **runner: Any,
) -> str:
    """The accuracy study (``regolith study accuracy``): ``cases`` (default every case of
    ``cases_dir``, ``examples/study``, with a section for ``budget``: ``"quick"``,
    ``"standard"`` or ``"full"``). Each point is recorded in its case's folder; the study
    always resumes (a finished point is never run again). ``runner`` takes the keywords of
    ``run`` (not ``resume``)."""
    args = ["study", "accuracy", "--budget", str(budget), "--out", os.fspath(out)]
    args += _flag_list("--cases", cases)
    if cases_dir is not None:
        args += ["--cases-dir", os.fspath(cases_dir)]
    return run(args, **runner)


def triaxial(
    material: str,
    *,
    out: str = "out/calibrate-triaxial",
    confining: Optional[Iterable[float]] = None,
    options: Optional[dict] = None,
    **runner: Any,
) -> str:
    """A virtual triaxial envelope (``regolith calibrate triaxial``) of ``material``, one test
    per ``confining`` stress (Pa). ``options`` maps the command's other flags, without their
    dashes, to values (``{"spacing": 0.01, "strain_rate": 0.2, "failure": "peak"}``).
    ``runner`` takes the keywords of ``run``. Returns the envelope as printed; ``triaxial.json``
    in ``out`` holds it all."""
    args = ["calibrate", "triaxial", "--material", os.fspath(material), "--out", os.fspath(out)]
    args += _flag_list("--confining", confining)
    for k, v in (options or {}).items():
        args += ["--" + str(k).replace("_", "-"), str(v)]
    return run(args, **runner)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The Ray side of ``regolith study stability --runner ray`` and ``regolith calibrate
    triaxial --runner ray``: ``argv`` is that command line (after ``regolith``). Exit code 2
    for a wrong input, 1 for a failed case or run, 130 when interrupted."""
    argv = list(sys.argv[1:] if argv is None else argv)
    ap = argparse.ArgumentParser(prog="regolith (Ray runner)", allow_abbrev=False, add_help=False)
    ap.add_argument("--runner", choices=["ray", "threads"], default="ray")
    ap.add_argument("--address")
    ap.add_argument("--num-cpus", type=float, default=1.0)
    ap.add_argument("--num-gpus", type=float, default=0.0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--resume", action="store_true")
    ap.add_argument("--retry-failed", action="store_true")
    ap.add_argument("--quiet", action="store_true")
    a, rest = ap.parse_known_args(argv)
    try:
        text = run(
            rest,
            runner=a.runner,
            address=a.address,
            num_cpus=a.num_cpus,
            num_gpus=a.num_gpus,
            jobs=a.jobs,
            resume=a.resume,
            retry_failed=a.retry_failed,
            quiet=a.quiet,
        )
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except RunError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted; rerun the same command with --resume to run what is not yet recorded", file=sys.stderr)
        return 130
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
