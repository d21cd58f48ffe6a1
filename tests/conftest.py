from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


@pytest.fixture
def example_run1() -> Path:
    return EXAMPLES / "hmc_run1.csv"


@pytest.fixture
def example_run2() -> Path:
    return EXAMPLES / "hmc_run2.csv"


@pytest.fixture
def write_csv(tmp_path: Path):
    """Write text (or bytes) to a CSV file in tmp_path and return its path."""

    def _write(content: str | bytes, name: str = "run.csv") -> Path:
        p = tmp_path / name
        if isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content, encoding="utf-8")
        return p

    return _write


@pytest.fixture(scope="session")
def edge_bin() -> Path:
    """The release binary of thermerr-edge (built once per session if missing;
    THERMERR_EDGE_BIN overrides)."""
    if os.environ.get("THERMERR_EDGE_BIN"):
        return Path(os.environ["THERMERR_EDGE_BIN"])
    if shutil.which("cargo") is None:
        pytest.skip("cargo is not available to build thermerr-edge")
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "thermerr-edge"], cwd=ROOT, check=True)
    meta = json.loads(subprocess.run(["cargo", "metadata", "--format-version", "1", "--no-deps"], cwd=ROOT,
                                     check=True, capture_output=True, text=True).stdout)
    return Path(meta["target_directory"]) / "release" / "thermerr-edge"
