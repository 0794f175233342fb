#!/usr/bin/env bash
# The speed benches at GPU size, in one command, on a machine with a real GPU (issue 46,
# item 3). CI does not run it: on a CPU-only machine wgpu falls back to lavapipe, which would
# take hours at these sizes.
#
# Runs `regolith bench` with the wgpu backend:
#   - the block (MCC, f32, RK2, neighbour lists rebuilt every step) at about 1 M, 4 M and
#     16 M particles (SIZES), and the same block at the first size on the CPU for reference;
#   - the wheel-long bench (a grousered wheel at 30 % slip on a WHEEL_LENGTH m bed, the
#     active region off and on) on wgpu and on the CPU;
# then writes $OUT/gpu_bench.md: particle-steps/s of each run beside the goal (1e8 on an
# H100-class GPU for the block), the device, the CPU and the commit. Every run is bounded by
# `timeout` so that the runs together stay under BUDGET_S seconds (the build not counted); a
# run that does not finish is reported as such, and the others still run.
#
#   scripts/gpu_bench.sh [OUT]
#   env: SIZES ("1000000 4000000 16000000"), STEPS (20), WARMUP (3), WHEEL_LENGTH (10),
#        WHEEL_STEPS (20), WHEEL_WARMUP (5), BUDGET_S (420: with a release build of 2–3 minutes
#        on a 16-core host, the whole command stays under 10 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."

OUT="${1:-out/gpu_bench}"
SIZES="${SIZES:-1000000 4000000 16000000}"
STEPS="${STEPS:-20}"
WARMUP="${WARMUP:-3}"
WHEEL_LENGTH="${WHEEL_LENGTH:-10}"
WHEEL_STEPS="${WHEEL_STEPS:-20}"
WHEEL_WARMUP="${WHEEL_WARMUP:-5}"
BUDGET_S="${BUDGET_S:-420}"
mkdir -p "$OUT"

cargo build --release --bin regolith
BIN=target/release/regolith
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader >"$OUT/device.txt" 2>/dev/null || echo "unknown GPU" >"$OUT/device.txt"
{ lscpu | grep -m1 'Model name' | sed 's/.*: *//'; nproc; git rev-parse --short HEAD 2>/dev/null || echo unknown; } >"$OUT/host.txt"

# Each run gets an equal share of what is left of the budget when it starts.
start=$(date +%s)
runs=()
for n in $SIZES; do runs+=("block_wgpu_$n"); done
first=${SIZES%% *}
runs+=("block_cpu_$first" wheel_long_wgpu wheel_long_cpu)
left=${#runs[@]}
bench() {
    local name=$1
    shift
    local remaining=$((BUDGET_S - ($(date +%s) - start)))
    local share=$((remaining / left))
    left=$((left - 1))
    if [ "$share" -lt 10 ]; then
        echo "$name: skipped, the budget is spent" | tee "$OUT/$name.log"
        return
    fi
    timeout "${share}s" "$BIN" bench "$@" --json "$OUT/$name.json" >"$OUT/$name.log" 2>&1 ||
        echo "$name: did not finish within ${share} s (see $OUT/$name.log)"
    tail -n 1 "$OUT/$name.log"
}
for n in $SIZES; do
    bench "block_wgpu_$n" --particles "$n" --model mcc --precision f32 --backend wgpu --skin 0 \
        --steps "$STEPS" --warmup "$WARMUP"
done
bench "block_cpu_$first" --particles "$first" --model mcc --precision f32 --backend cpu --skin 0 \
    --steps "$STEPS" --warmup "$WARMUP"
for b in wgpu cpu; do
    bench "wheel_long_$b" --scene wheel-long --length "$WHEEL_LENGTH" --active both --backend "$b" --skin 0 \
        --steps "$WHEEL_STEPS" --warmup "$WHEEL_WARMUP"
done
echo "total wall time: $(($(date +%s) - start)) s"

python3 - "$OUT" "${runs[@]}" <<'EOF'
import json, os, sys
out, names = sys.argv[1], sys.argv[2:]
device = open(os.path.join(out, "device.txt")).read().strip()
cpu, threads, commit = (open(os.path.join(out, "host.txt")).read().split("\n") + ["", "", ""])[:3]
rows = []
for name in names:
    path = os.path.join(out, f"{name}.json")
    if not os.path.exists(path):
        rows.append(f"| {name} | not finished (see {name}.log) | | | | | |")
        continue
    for r in json.load(open(path)):
        scene = r.get("scene", "wheel-long")
        goal = "≥ 1e8" if scene == "block" and r["backend"] == "wgpu" else ""
        verdict = ("✔" if r["particle_steps_per_s"] >= 1e8 else "✘") if goal else ""
        label = scene + ("" if "active" not in r else " (active region " + ("on" if r["active"] else "off") + ")")
        rows.append(
            f"| {name} | {label}, {r['backend']}, {r['particles']} particles, {r['markers']} markers | "
            f"{r['steps']} steps in {r['seconds']:.2f} s | {r['particle_steps_per_s']:.3e} | "
            f"{r['sim_s_per_wall_s']:.3e} | {goal} | {verdict} |"
        )
with open(os.path.join(out, "gpu_bench.md"), "w") as f:
    f.write(f"# GPU benches (wgpu on {device}; host {cpu}, {threads} threads; commit {commit})\n\n")
    f.write("| run | what | timed | particle-steps/s | simulated s per wall s | goal | |\n|---|---|---|---|---|---|---|\n")
    f.write("\n".join(rows) + "\n")
print(open(os.path.join(out, "gpu_bench.md")).read())
EOF
