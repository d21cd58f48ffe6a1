"""The bundled example runs and machine models (the files ``examples/`` links to), shipped in the
wheel so that a ``pip install`` user can run the README's commands: ``thermerr examples DIR``
copies them out, :func:`path` names one in place."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .._io import write_atomic
from ..errors import ThermerrError


def names() -> list[str]:
    """The bundled files: runs (``*.csv``) and machine models (``*.toml``)."""
    root = resources.files(__name__)
    return sorted(p.name for p in root.iterdir() if p.name.endswith((".csv", ".toml")))


def path(name: str) -> Path:
    """The path of a bundled file, e.g. ``path("vmc_run.csv")``."""
    if name not in names():
        raise ThermerrError(f"no bundled example named {name!r} (there are: {', '.join(names())})")
    return Path(str(resources.files(__name__).joinpath(name)))


def copy_to(directory: str | Path) -> list[Path]:
    """Copy every bundled file into ``directory`` (created if needed); existing files of the same
    name are replaced, each atomically. Returns the written paths."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name in names():
        written.append(write_atomic(out / name, path(name).read_bytes()))
    return written
