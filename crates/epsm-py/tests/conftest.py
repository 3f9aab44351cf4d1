"""Shared fixtures: the repository's paths and the `epsm` command."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
DATA = pathlib.Path(__file__).resolve().parent / "data"


@pytest.fixture(scope="session")
def epsm_cli():
    """Runs the `epsm` binary (EPSM_BIN, else target/release/epsm) and
    returns its standard output; a failure fails the test."""
    exe = pathlib.Path(os.environ.get("EPSM_BIN", ROOT / "target" / "release" / "epsm"))
    assert exe.is_file(), f"{exe} is missing: cargo build --release -p epsm-cli"

    def run(*args):
        done = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stdout

    return run


def cli_value(output, key):
    """The value of the `key value` line `key` of `epsm match`'s output."""
    for line in output.splitlines():
        if line.startswith(key + " "):
            return line[len(key) + 1 :]
    raise AssertionError(f"no `{key}` line in {output}")
