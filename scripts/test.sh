#!/usr/bin/env bash
# Runs every test of the Regolith workspace, in release mode, on a fresh machine.
#
# Installs what the tests need when it is missing: Mesa's software Vulkan driver (lavapipe),
# so that the wgpu tests run on a machine without a GPU. Needs root or sudo for that step only.
set -euo pipefail
cd "$(dirname "$0")/.."

have_vulkan() {
    local icd=no
    for f in /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json; do
        [ -e "$f" ] && icd=yes
    done
    [ "$icd" = yes ] && { ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1'; }
}

if ! have_vulkan; then
    echo "test.sh: no Vulkan driver found; installing Mesa lavapipe (mesa-vulkan-drivers libvulkan1)"
    sudo_cmd=""
    if [ "$(id -u)" -ne 0 ]; then sudo_cmd="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    $sudo_cmd apt-get update -qq
    $sudo_cmd apt-get install -y -qq --no-install-recommends mesa-vulkan-drivers libvulkan1 >/dev/null
fi

# Mesa's Vulkan loader warns on every device open without a runtime dir; give it one.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

cargo fmt --all -- --check
# Lints (missing docs included: the workspace lints make it a warning, -D warnings an error).
cargo clippy --release --workspace --all-targets -- -D warnings
# The library builds without its optional parts (CLI, wgpu, MCAP, plots), and with wgpu alone.
cargo check --release -p regolith --lib --no-default-features
cargo check --release -p regolith --lib --no-default-features --features wgpu
# The API docs build without a broken link or an undocumented public item.
# (--release: the proc macros and build scripts the release builds above made are reused.)
RUSTDOCFLAGS="-D warnings -D missing_docs" cargo doc --release --workspace --no-deps
cargo test --release --workspace --all-targets
cargo test --release --workspace --doc
# The stability suite at CI size: the hard cases of examples/hard/ within their [[expect]]
# bounds. thin_grousers and wheel_full_slip pass at CI size too but take about 2 minutes each
# on 2 cores; they run with `regolith study stability` (docs/stability.md), not here, until the
# solver is faster (issue 13).
CI_CASES=body_leaves_container,cone_fast,cut_above,cut_below,deep_bed_f32,fixed_step_forced,fixed_step_refused
CI_CASES=$CI_CASES,heavy_plate,jet_at_wall,mcc_ocr5000,mcc_small_lambda_kappa,soil_soft,soil_stiff
CI_CASES=$CI_CASES,sphere_impact,stiffness_contrast,wheel_drop,geostatic_20s,rover_slope_30
# The binary the integration tests built (`cargo run` would rebuild it without the test
# dependencies' features: four more minutes).
"${CARGO_TARGET_DIR:-target}/release/regolith" study stability --size ci --cases "$CI_CASES" --out target/stability-ci
