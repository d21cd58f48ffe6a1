"""The thermal network's identification and diagnosis give the same bits on every machine.

Their verdicts on a real run can move with the last bit of the arithmetic (docs/machine-model.md,
"The same numbers on every machine"), so the core computes them without CPU-dispatched kernels
and without the C library's exp, ln and pow. glibc chooses its exp/log/pow by the CPU (an FMA
variant rounds some results differently); its ``glibc.cpu.hwcaps`` tunable makes this process's
libm the one a CPU without FMA gets, which is how this test plays "another machine" here. The
CPU-dispatched linear algebra (AVX2 or not) is checked bit for bit by the Rust unit test
``linalg::tests::gram_is_every_pair_s_dot_to_the_bit``; a CPU without AVX2 was tried with
``qemu-x86_64 -cpu Nehalem`` (docs).
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest

from thermerr_rs import examples

NO_FMA = "glibc.cpu.hwcaps=-AVX2,-FMA"

# a hash of the C library's exp and log over a grid: differs between its FMA and plain kernels
LIBM_PROBE = (
    "import math, hashlib; h = hashlib.sha256()\n"
    "for k in range(200000):\n"
    "    x = -50.0 + 100.0 * k / 200000.0\n"
    "    h.update(math.exp(x).hex().encode()); h.update(math.log(x + 60.0).hex().encode())\n"
    "print(h.hexdigest())"
)


def _run(args: list[str], cwd: Path, no_fma: bool) -> str:
    env = dict(os.environ)
    env.pop("GLIBC_TUNABLES", None)
    if no_fma:
        env["GLIBC_TUNABLES"] = NO_FMA
    p = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return p.stdout


@pytest.fixture(scope="module")
def other_libm() -> None:
    if platform.system() != "Linux" or platform.libc_ver()[0] != "glibc":
        pytest.skip("needs glibc, whose tunables select its libm kernels")
    probe = [sys.executable, "-c", LIBM_PROBE]
    if _run(probe, Path.cwd(), False) == _run(probe, Path.cwd(), True):
        pytest.skip("this CPU or glibc gives the same exp/log with and without FMA kernels")


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-c", "import sys; from thermerr_rs.cli import main; sys.exit(main())", *args]


def _reports(d: Path) -> dict[str, object]:
    out = {}
    for f in sorted(d.glob("*report.json")):
        r = json.loads(f.read_text())
        r.pop("stage_s", None)  # times
        out[f.name] = r
    return out


def test_init_and_diagnose_do_not_depend_on_the_c_library_s_kernels(other_libm: None, tmp_path: Path) -> None:
    run = examples.path("lathe_run.csv")
    got = {}
    for no_fma in (False, True):
        d = tmp_path / ("plain" if no_fma else "native")
        d.mkdir()
        _run(_cli("init", str(run), "--out", "m.toml", "--quiet"), d, no_fma)
        _run(_cli("diagnose", str(run), "--machine", "m.toml", "--out", "diag", "--quiet"), d, no_fma)
        got[no_fma] = ((d / "m.toml").read_text(), _reports(d / "diag"))
    assert got[False][0] == got[True][0], "thermerr init wrote another machine file"
    assert got[False][1] == got[True][1], "thermerr diagnose reported other numbers"
