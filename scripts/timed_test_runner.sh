#!/usr/bin/env bash
# Cargo's runner for the test binaries when scripts/test.sh runs them (it sets
# CARGO_TARGET_<host>_RUNNER to this file): each binary runs with libtest's per-test times
# (`test NAME ... ok <12.345s>`), so that test.sh can list the slowest tests at the end.
# `--report-time` is an unstable libtest option; libtest accepts it when RUSTC_BOOTSTRAP is set
# in the environment of the test process. It is set here, for the run only: nothing is
# compiled with it, so the builds (and their fingerprints) are the same as without the runner.
set -euo pipefail
exe="$1"
shift
RUSTC_BOOTSTRAP=1 exec "$exe" "$@" -Z unstable-options --report-time
