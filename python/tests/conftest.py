"""Shared fixtures: the repository's scenes and the `regolith` binary the Rust tests built."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


def regolith_bin() -> str:
    """The CLI: REGOLITH_BIN, else target/release/regolith (CARGO_TARGET_DIR respected)."""
    if os.environ.get("REGOLITH_BIN"):
        return os.environ["REGOLITH_BIN"]
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    exe = target / "release" / "regolith"
    if not exe.exists():
        pytest.fail(f"{exe} not built: run `cargo build --release` first (scripts/test.sh does)")
    return str(exe)


@pytest.fixture(scope="session")
def cli():
    exe = regolith_bin()

    def call(*args, check=True, **kw):
        r = subprocess.run([exe, *map(str, args)], capture_output=True, text=True, **kw)
        if check and r.returncode != 0:
            raise AssertionError(f"regolith {' '.join(map(str, args))} exited {r.returncode}: {r.stderr}")
        return r

    return call


@pytest.fixture(scope="session")
def scenes() -> pathlib.Path:
    return REPO / "examples" / "scenes"


@pytest.fixture(scope="session")
def materials() -> pathlib.Path:
    return REPO / "examples" / "materials"
