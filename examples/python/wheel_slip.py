"""A single-wheel slip sweep from Python: drawbar pull, torque and sinkage at each slip of the
single-wheel rig (examples/scenes/single_wheel.toml), one run per slip, on Ray or on threads.

    python examples/python/wheel_slip.py [--slips 0,0.2,0.4,0.6] [--spacing 0.01]
        [--runner ray|threads] [--address auto] [--out out/wheel_slip]

Each slip is a point of a regolith.sweep (resumable: rerun the command and only the points
not yet recorded run). Prints the table, writes OUT/results.csv and, with matplotlib,
OUT/wheel_slip.png.
"""

import argparse
import os
import pathlib

import regolith.sweep

HERE = pathlib.Path(__file__).resolve().parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(HERE.parent / "scenes" / "single_wheel.toml"))
    ap.add_argument("--slips", default="0,0.2,0.4,0.6")
    ap.add_argument("--spacing", type=float, help="particle spacing d0 (m); default: the scene's")
    ap.add_argument("--end-time", type=float, help="seconds per slip; default: the scene's")
    ap.add_argument("--runner", choices=["ray", "threads"], default="ray")
    ap.add_argument("--address", help="Ray cluster (default: a local instance)")
    ap.add_argument("--out", default="out/wheel_slip")
    a = ap.parse_args()
    sets = {}
    if a.spacing:
        sets["sph.spacing"] = a.spacing
    if a.end_time:
        sets["simulation.end_time"] = a.end_time
    slips = [float(s) for s in a.slips.split(",")]
    rows = regolith.sweep.run(
        a.scene,
        vary={"rig.slips": slips},
        sets=sets,
        out=a.out,
        runner=a.runner,
        address=a.address,
    )
    table = []
    print(f"{'slip':>6} {'DBP (N)':>9} {'torque (N m)':>13} {'sinkage (mm)':>13}")
    for r in rows:
        if r["status"] != "ok":
            print(f"point {r['point']}: {r['error']}")
            continue
        run = r["summary"]["rig"]["steady_state"][0]
        table.append((run["slip"], run["drawbar_pull"], run["torque"], run["sinkage"]))
        print(f"{run['slip']:6.2f} {run['drawbar_pull']:9.3f} {run['torque']:13.4f} {run['sinkage'] * 1e3:13.2f}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    if table:
        fig, ax = plt.subplots(figsize=(5, 3.5))
        ax.plot([t[0] for t in table], [t[1] for t in table], "o-")
        ax.set_xlabel("slip")
        ax.set_ylabel("drawbar pull (N)")
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "wheel_slip.png"), dpi=120)


if __name__ == "__main__":
    main()
