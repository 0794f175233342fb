"""Sweeps: one scene run at many points, on Ray (one task per point) or on threads of this
process, resumable, and sliceable into shards for SLURM job arrays.

    import regolith.sweep
    rows = regolith.sweep.run(
        "examples/scenes/single_wheel.toml",
        vary={"rig.slips": [0.0, 0.2, 0.4], "sph.spacing": [0.02, 0.014]},
        out="out/slip-sweep",
    )

The points, their configuration hashes, how a point runs and how results are written are the
Rust library's (``regolith sweep`` on the command line runs the same plan): this module only
schedules them. A sweep directory holds ``results.jsonl`` (one record per finished point, or
``results.shard-I-of-N.jsonl`` per shard), ``results.csv`` (the tidy table) and
``points/<id>/`` (each point's outputs). A point whose id is already recorded is not run
again (failed ones are, with ``retry_failed``); a failed point is recorded with its error and
the others go on.

``python -m regolith.sweep SCENE --vary KEY=VALUES ...`` takes the command line of
``regolith sweep``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import threading
import time
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

from . import _regolith
from ._regolith import InputError

__all__ = ["run", "merge", "records", "toml_literal", "main"]

Values = Union[Sequence[Any], Tuple[float, float], str]


def toml_literal(v: Any) -> str:
    """A Python value as a TOML literal (bool, int, float, str, list, dict)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise InputError(f"vary: {v!r} is not a finite number")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_literal(x) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_literal(x)}" for k, x in v.items()) + "}"
    try:
        return repr(float(v))
    except (TypeError, ValueError):
        raise InputError(f"vary: {type(v).__name__} {v!r} is not a TOML value (allowed: bool, int, float, str, list, dict)")


def _vary_args(vary: Union[Mapping[str, Values], Iterable[str]]) -> List[str]:
    """``{"key": [a, b]}`` (values), ``{"key": (lo, hi)}`` (a range, for lhs) or ``"key=a,b"``
    strings, as ``--vary`` arguments."""
    if isinstance(vary, Mapping):
        out = []
        for k, v in vary.items():
            if isinstance(v, str):
                out.append(f"{k}={v}")
            elif isinstance(v, tuple) and len(v) == 2 and all(isinstance(x, (int, float)) for x in v):
                out.append(f"{k}={float(v[0])!r}:{float(v[1])!r}")
            elif isinstance(v, (list, tuple)):
                if not v:
                    raise InputError(f"vary[{k!r}]: no values")
                out.append(f"{k}=" + ",".join(toml_literal(x) for x in v))
            else:
                raise InputError(f"vary[{k!r}]: give a list of values or a (lo, hi) range")
        return out
    return [str(v) for v in vary]


def _set_args(sets: Union[Mapping[str, Any], Iterable[str], None]) -> List[str]:
    if sets is None:
        return []
    if isinstance(sets, Mapping):
        return [f"{k}={toml_literal(v)}" for k, v in sets.items()]
    return [str(s) for s in sets]


def records(out: Union[str, "os.PathLike[str]"]) -> List[Dict[str, Any]]:
    """Every record of a sweep directory (shards included), the last one of each point, in
    point order."""
    return [json.loads(r) for r in _regolith.sweep_records_json(os.fspath(out))]


def merge(out: Union[str, "os.PathLike[str]"]) -> int:
    """Joins a sweep directory's shard files into ``results.jsonl`` and ``results.csv``;
    returns the number of points."""
    return _regolith.sweep_merge(os.fspath(out))


def converge(
    out: Union[str, "os.PathLike[str]"], metric: str, over: str = "sph.spacing"
) -> List[Dict[str, Any]]:
    """Observed order and extrapolated limit of ``metric`` (a ``results.csv`` column name)
    over the resolution key ``over``: one dict per ladder (the points that differ only in
    ``over``) with ``fixed``, ``levels`` [(h, value)], ``missing``, ``convergence`` (``order``,
    ``order_range``, ``limit``, ``coefficient``, ``gci``, ``rms_residual``) or ``error``. As
    ``regolith sweep converge``; raises ``InputError`` for a key or metric the sweep lacks."""
    return json.loads(_regolith.sweep_converge_json(os.fspath(out), over, metric))


def _eta(s: float) -> str:
    s = int(round(max(s, 0.0)))
    if s >= 3600:
        return f"{s // 3600}h {(s % 3600) // 60:02d}m"
    if s >= 60:
        return f"{s // 60}m {s % 60:02d}s"
    return f"{s} s"


class _Progress:
    def __init__(self, total: int, slots: int, quiet: bool, what: str = "sweep", labels=None) -> None:
        self.total, self.slots, self.quiet = total, max(slots, 1), quiet
        # ``labels``: run id -> what a line calls it (default ``point N``).
        self.what, self.labels = what, labels or {}
        self.ok = self.failed = 0
        self.t0 = time.monotonic()

    def done(self, rec: Dict[str, Any], running: int) -> None:
        if rec["status"] == "ok":
            self.ok += 1
        else:
            self.failed += 1
        if self.quiet:
            return
        n = self.ok + self.failed
        left = self.total - n
        eta = (time.monotonic() - self.t0) / max(n, 1) * left / self.slots if left else 0.0
        what = "ok" if rec["status"] == "ok" else f"FAILED: {rec.get('error', '')}"
        label = self.labels.get(rec["id"], f"point {rec['point']}")
        print(
            f"{self.what}: {label} ({rec['id']}) {what} in {rec['wall_s']:.1f} s; "
            f"{n}/{self.total} done, {running} running, {self.failed} failed, ETA {_eta(eta)}",
            file=sys.stderr,
            flush=True,
        )


def _native_task(name: str, args: Tuple[Any, ...], rayon_threads: int, cwd: str) -> str:
    # Each run's solver uses as many rayon threads as the task was given CPUs.
    os.environ.setdefault("RAYON_NUM_THREADS", str(max(rayon_threads, 1)))
    # Relative paths (scenes, case folders, outputs) mean what they meant to the driver, on
    # its machine or on a cluster node that shares its file system.
    if os.path.isdir(cwd):
        os.chdir(cwd)
    from regolith import _regolith as native

    return getattr(native, name)(*args)


def run(
    scene: Union[str, "os.PathLike[str]"],
    vary: Union[Mapping[str, Values], Iterable[str]],
    *,
    out: Union[str, "os.PathLike[str]"] = "out/sweep",
    sets: Union[Mapping[str, Any], Iterable[str], None] = None,
    design: str = "grid",
    samples: Optional[int] = None,
    seed: int = 0,
    runner: str = "ray",
    address: Optional[str] = None,
    num_cpus: float = 1.0,
    num_gpus: float = 0.0,
    jobs: int = 1,
    shard: Optional[str] = None,
    retry_failed: bool = False,
    quiet: bool = False,
) -> List[Dict[str, Any]]:
    """Runs a sweep and returns every record of its directory (see ``records``).

    ``vary`` maps dotted scene keys to lists of values (a grid crosses them; the first key
    varies slowest) or, with ``design="lhs"`` and ``samples``, to ``(lo, hi)`` ranges or lists
    (a Latin hypercube seeded by ``seed``). ``sets`` are overrides common to every point. A
    scalar for a key that holds an array in the scene (``rig.slips``) stands for the
    one-element array.

    ``runner="ray"`` runs each point as a Ray task with ``num_cpus`` / ``num_gpus``: on a new
    local Ray instance, or on the cluster at ``address`` (``"auto"``, ``"ray://host:10001"``).
    ``runner="threads"`` runs ``jobs`` points at a time in this process. ``shard="i/n"`` runs
    only the points ``p`` with ``p % n == i - 1`` and writes ``results.shard-i-of-n.jsonl``
    (``merge`` joins them); inside a SLURM array job the shard defaults to the task's.
    """
    scene = os.fspath(scene)
    out = os.fspath(out)
    vargs, sargs = _vary_args(vary), _set_args(sets)
    if design not in ("grid", "lhs"):
        raise InputError(f"design: {design!r} (allowed: 'grid', 'lhs')")
    if runner not in ("ray", "threads"):
        raise InputError(f"runner: {runner!r} (allowed: 'ray', 'threads')")
    if runner == "threads" and (address is not None or num_gpus):
        raise InputError("address, num_gpus: apply to runner='ray' only")
    if not (num_cpus > 0 and num_gpus >= 0 and jobs >= 1):
        raise InputError(f"num_cpus must be > 0, num_gpus >= 0 and jobs >= 1 (got {num_cpus}, {num_gpus}, {jobs})")
    if shard is None:
        shard = _regolith.slurm_shard()
    plan = json.loads(_regolith.sweep_plan_json(scene, sargs, vargs, design, samples, seed))
    common = (scene, sargs, vargs, design, samples, seed)
    os.makedirs(out, exist_ok=True)
    pending = _regolith.sweep_pending(*common, out, shard, retry_failed)
    in_shard = [p for p in plan if shard is None or p["point"] % int(shard.split("/")[1]) == int(shard.split("/")[0]) - 1]
    slots = jobs if runner == "threads" else max(1, int((os.cpu_count() or 1) // max(num_cpus, 1)))
    if not quiet:
        where = f" in shard {shard}" if shard else ""
        how = f"Ray ({address or 'local instance'})" if runner == "ray" else f"{jobs} thread(s)"
        print(
            f"sweep: {len(in_shard)} points{where}, {len(in_shard) - len(pending)} already recorded, "
            f"{len(pending)} to run on {how}",
            file=sys.stderr,
            flush=True,
        )
    progress = _Progress(len(pending), slots, quiet)

    def record(line: str, running: int) -> None:
        _regolith.sweep_append(out, line, shard)
        progress.done(json.loads(line), running)

    calls = [("sweep_run_point", (*common, p, out)) for p in pending]
    if calls:
        if runner == "ray":
            _schedule_ray(calls, record, address, num_cpus, num_gpus)
        else:
            _schedule_threads(calls, record, jobs)
    if shard is None:
        _regolith.sweep_write_csv(out)
    return records(out)


def _schedule_threads(calls, record, jobs: int) -> None:
    """Runs each ``(native function name, args)`` call on ``jobs`` threads (the native calls
    release the GIL), handing each returned record line to ``record(line, still_running)``."""
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    with ThreadPoolExecutor(max_workers=jobs) as ex:
        futs = {ex.submit(getattr(_regolith, name), *args) for name, args in calls}
        while futs:
            finished, futs = wait(futs, return_when=FIRST_COMPLETED)
            for f in finished:
                record(f.result(), len(futs))


def _schedule_ray(calls, record, address, num_cpus, num_gpus) -> None:
    """Runs each ``(native function name, args)`` call as one Ray task with ``num_cpus`` /
    ``num_gpus``, on a new local instance or the cluster at ``address``, handing each returned
    record line to ``record(line, still_running)`` as it finishes."""
    try:
        import ray
    except ImportError as e:
        raise InputError(f"runner='ray' needs Ray ({e}); install it (pip install ray) or use runner='threads'") from None
    # A process started with SIGINT ignored (nohup, a background job of a script) keeps
    # ignoring it; otherwise Ctrl-C must stop the runs (see below).
    sigint_ignored = signal.getsignal(signal.SIGINT) == signal.SIG_IGN
    started = not ray.is_initialized()
    if started:
        if address is None:
            ray.init(include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, log_to_driver=False)
    # Ctrl-C / SIGINT must stop at once: Ray may replace the SIGINT handler when it starts,
    # and a ray.wait without a timeout blocks in C++ where no Python handler runs. So the
    # default handler (KeyboardInterrupt) goes back in, the wait polls, and the tasks still
    # running are cancelled on the way out (their records are simply not written).
    previous = None
    if not sigint_ignored and threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    refs: List[Any] = []
    try:
        task = ray.remote(num_cpus=num_cpus, num_gpus=num_gpus, max_retries=0)(_native_task)
        threads = max(1, int(num_cpus))
        cwd = os.getcwd()
        refs = [task.remote(name, args, threads, cwd) for name, args in calls]
        while refs:
            finished, refs = ray.wait(refs, num_returns=1, timeout=0.2)
            for r in finished:
                record(ray.get(r), len(refs))
    except KeyboardInterrupt:
        for r in refs:
            ray.cancel(r, force=True)
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        if started:
            ray.shutdown()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """``regolith sweep`` from Python: ``SCENE --vary KEY=VALUES ... [--out DIR]`` or
    ``merge DIR``. Exit code 2 for a wrong input, 1 when a point failed."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["merge"]:
        ap = argparse.ArgumentParser(prog="regolith sweep merge")
        ap.add_argument("dir")
        a = ap.parse_args(argv[1:])
        try:
            n = merge(a.dir)
        except InputError as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        print(f"merged {n} points into {os.path.join(a.dir, 'results.jsonl')} and results.csv")
        return 0
    ap = argparse.ArgumentParser(prog="regolith sweep", description="Run one scene at many points.")
    ap.add_argument("scene")
    ap.add_argument("--vary", action="append", default=[], metavar="KEY=VALUES")
    ap.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--design", choices=["grid", "lhs"], default="grid")
    ap.add_argument("--samples", type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--runner", choices=["ray", "threads"], default="ray")
    ap.add_argument("--address")
    ap.add_argument("--num-cpus", type=float, default=1.0)
    ap.add_argument("--num-gpus", type=float, default=0.0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--shard")
    ap.add_argument("--retry-failed", action="store_true")
    ap.add_argument("--out", default="out/sweep")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    try:
        rows = run(
            a.scene,
            a.vary,
            out=a.out,
            sets=a.sets,
            design=a.design,
            samples=a.samples,
            seed=a.seed,
            runner=a.runner,
            address=a.address,
            num_cpus=a.num_cpus,
            num_gpus=a.num_gpus,
            jobs=a.jobs,
            shard=a.shard,
            retry_failed=a.retry_failed,
            quiet=a.quiet,
        )
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("sweep interrupted; rerun the same command to run the points not yet recorded", file=sys.stderr)
        return 130
    failed = [r for r in rows if r["status"] != "ok"]
    target = os.path.join(a.out, "results.csv" if a.shard is None else "results.shard-*.jsonl")
    print(f"sweep: {len(rows)} points recorded ({len(failed)} failed); results in {target}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
