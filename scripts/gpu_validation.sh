#!/usr/bin/env bash
# The GRC-1 wheel-slope study at GPU size, in one command, on a machine with a real GPU
# (issue 45, item 5). CI does not run it: on a CPU-only machine wgpu falls back to lavapipe,
# which is far too slow for this size.
#
# Runs examples/study/wheel_slope_grc1.toml with the wgpu backend at d0 = D0 (1 cm by default,
# the file's own spacing) on a bed LENGTH m long (1.6 m: the wheel climbs at most 0.7 m in
# SECONDS s per slope) at the seven slopes of the NASA GRC 2022 tests, then writes
# $OUT/wheel_slope_grc1.md: measured slip beside the experiment at each slope, the miss, and
# the wall time per simulated second. Every run is bounded by `timeout` so that the whole
# script stays under 10 minutes; a slope that does not finish is reported as such.
#
#   scripts/gpu_validation.sh [OUT]      (env: D0, SECONDS_PER_SLOPE, LENGTH, BUDGET_S)
set -euo pipefail
cd "$(dirname "$0")/.."

OUT="${1:-out/gpu_validation}"
D0="${D0:-0.01}"
SECONDS_PER_SLOPE="${SECONDS_PER_SLOPE:-3.0}"
LENGTH="${LENGTH:-1.6}"
BUDGET_S="${BUDGET_S:-540}"
SLOPES=(0.0 5.0 10.0 15.0 20.0 25.0 30.0)
mkdir -p "$OUT"

cargo build --release --bin regolith
BIN=target/release/regolith
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader >"$OUT/device.txt" 2>/dev/null || echo "unknown GPU" >"$OUT/device.txt"

start=$(date +%s)
per=$((BUDGET_S / ${#SLOPES[@]}))
for s in "${SLOPES[@]}"; do
    dir="$OUT/slope_$s"
    timeout "${per}s" "$BIN" run examples/study/wheel_slope_grc1.toml --backend wgpu --quiet --out "$dir" \
        --set "sph.spacing=$D0" --set "container.max=[$LENGTH,0.8,0.8]" \
        --set "simulation.end_time=$SECONDS_PER_SLOPE" --set "rig.slopes=[$s]" >"$dir.log" 2>&1 ||
        echo "slope $s: did not finish within ${per} s (see $dir.log)"
done
echo "total wall time: $(($(date +%s) - start)) s"

python3 - "$OUT" "$D0" "$SECONDS_PER_SLOPE" <<'EOF'
import json, os, sys
out, d0, per = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
# NASA GRC 2022 single-wheel tests (MGRU3 / VIPER wheel on GRC-1), as the case file cites them.
experiment = {0.0: 0.025, 5.0: 0.051, 10.0: 0.104, 15.0: 0.355, 20.0: 0.738, 25.0: 0.838, 30.0: 0.897}
device = open(os.path.join(out, "device.txt")).read().strip()
rows = []
for slope, ref in experiment.items():
    path = os.path.join(out, f"slope_{slope}", "summary.json")
    if not os.path.exists(path):
        rows.append(f"| {slope:.0f}° | not finished | {ref:.3f} | | |")
        continue
    s = json.load(open(path))
    run = s["rig"]["steady_state"][0]
    slip = run["measured_slip"]
    cost = s["wall_time_s"] / max(s["sim_time"], 1e-12)
    rows.append(f"| {slope:.0f}° | {slip:.3f} ± {run.get('slip_std', 0):.3f} | {ref:.3f} | {slip - ref:+.3f} | {cost:.1f} |")
with open(os.path.join(out, "wheel_slope_grc1.md"), "w") as f:
    f.write(f"# GRC-1 wheel slopes on the GPU (wgpu, {device}), d0 = {d0} m, {per} s a slope\n\n")
    f.write("| slope | measured slip | experiment | miss | wall s per simulated s |\n|---|---|---|---|---|\n")
    f.write("\n".join(rows) + "\n")
print(open(os.path.join(out, "wheel_slope_grc1.md")).read())
EOF
