"""Fixtures of the convshadow module's tests: the repository, the command line built by cargo,
and a run of it."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

# Small renders of the default scene: about 0.1 s each on two cores.
SMALL = {"width": 64, "height": 48, "slabs": 96}


def _cli_path():
    """The `convshadow` binary: $CONVSHADOW_BIN, else target/release of $CARGO_TARGET_DIR or of
    the repository (`cargo build --release` puts it there)."""
    if os.environ.get("CONVSHADOW_BIN"):
        return pathlib.Path(os.environ["CONVSHADOW_BIN"])
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    if not target.is_absolute():
        target = REPO / target
    return target / "release" / "convshadow"


@pytest.fixture(scope="session")
def cli():
    """Runs the command line; returns the CompletedProcess (text mode, never raises)."""
    path = _cli_path()
    if not path.is_file():
        pytest.fail(
            f"{path}: no convshadow binary; build it with `cargo build --release` "
            "or set CONVSHADOW_BIN"
        )

    def run(*args):
        return subprocess.run(
            [str(path), *map(str, args)], capture_output=True, text=True, check=False
        )

    return run


def flags(overrides):
    """The command-line flags of `render`'s keyword arguments (`slabs=96` → `--slabs 96`,
    `subpixel_shadows=False` → `--subpixel-shadows false`)."""
    out = []
    for key, value in overrides.items():
        text = str(value).lower() if isinstance(value, bool) else str(value)
        out += ["--" + key.replace("_", "-"), text]
    return out
