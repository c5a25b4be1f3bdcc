"""Shared helpers: the repository's paths and the quadcl binary the parity tests
run beside the package (QUADCL_BIN, else target/release or target/debug)."""

import os
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def quadcl_binary():
    if os.environ.get("QUADCL_BIN"):
        return os.environ["QUADCL_BIN"]
    for profile in ("release", "debug"):
        path = ROOT / "target" / profile / "quadcl"
        if path.exists():
            return str(path)
    pytest.fail("no quadcl binary: build it (cargo build --release) or set QUADCL_BIN")


@pytest.fixture
def root():
    return ROOT
