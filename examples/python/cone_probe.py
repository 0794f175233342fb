"""A penetrometer probe scripted from Python: push the ASTM 30° cone into dry sand at 3 cm/s
to a depth of 3 cm, hold it, withdraw it, reading the soil's force between steps.

    python examples/python/cone_probe.py [--spacing 0.004] [--out out/cone_probe]

Writes OUT/cone_probe.csv (time, phase, tip travel, force) and, when matplotlib is installed,
OUT/cone_probe.png (force against depth). The Rust twin is examples/cone_script.rs.
"""

import argparse
import csv
import os
import pathlib

import regolith

HERE = pathlib.Path(__file__).resolve().parent
HEIGHT = 0.03784  # cone height (m), from the scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default=str(HERE.parent / "scenes" / "cone_probe.toml"))
    ap.add_argument("--spacing", type=float, help="particle spacing d0 (m); default: the scene's")
    ap.add_argument("--speed", type=float, default=0.03, help="push and withdraw speed (m/s)")
    ap.add_argument("--depth", type=float, default=0.03, help="tip travel before the hold (m)")
    ap.add_argument("--hold", type=float, default=0.1, help="hold time (s)")
    ap.add_argument("--out", default="out/cone_probe")
    a = ap.parse_args()
    overrides = {"sph.spacing": a.spacing} if a.spacing else {}
    scene = regolith.load_scene(a.scene, overrides=overrides)
    sim = regolith.Simulation(scene)
    cone = sim.body("cone")
    tip0 = cone.position[2] - 0.5 * HEIGHT
    rows, phase, hold_until = [], "push", 0.0
    while sim.time < scene.end_time:
        travel = tip0 - (cone.position[2] - 0.5 * HEIGHT)
        if phase == "push" and travel >= a.depth:
            cone.set_velocity([0.0, 0.0, 0.0])
            phase, hold_until = "hold", sim.time + a.hold
        elif phase == "push":
            cone.set_velocity([0.0, 0.0, -a.speed])
        elif phase == "hold" and sim.time >= hold_until:
            cone.set_velocity([0.0, 0.0, a.speed])
            phase = "withdraw"
        elif phase == "withdraw" and travel <= 0.0:
            break
        sim.step()
        rows.append((sim.time, phase, travel, cone.fsi_force[2]))
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "cone_probe.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time", "phase", "tip_travel", "force_z"])
        w.writerows(rows)
    peak = max(r[3] for r in rows)
    print(f"{len(rows)} exchanges to t = {sim.time:.3f} s; peak force {peak:.3f} N; wrote {path}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not installed: no plot")
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    for ph, colour in (("push", "C0"), ("hold", "C1"), ("withdraw", "C2")):
        pts = [(r[2] * 1e3, r[3]) for r in rows if r[1] == ph]
        if pts:
            ax.plot(*zip(*pts), ".", ms=2, color=colour, label=ph)
    ax.set_xlabel("tip travel (mm)")
    ax.set_ylabel("soil force on the cone (N)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "cone_probe.png"), dpi=120)
    print(f"wrote {os.path.join(a.out, 'cone_probe.png')}")


if __name__ == "__main__":
    main()
