"""Make the bundled diagnosis example with the project's synthetic-machine generator.

    python examples/make_diagnosis_example.py

A vertical machining centre (5-node network, Z axis) whose true structure follows its
temperatures through a first-order lag the nominal model does not have (`thermal_lag`). Writes:

- `vmc_nominal.toml`  the user's nominal machine: every parameter 15-35 % off, no lag
- `vmc_run.csv`       a 20-hour run at 1-minute sampling (stepped spindle speeds), noisy sensors
                      (0.03 °C) and probe (0.15 µm)
- `vmc_holdout.csv`   a second, 12-hour run under a random duty cycle, for `--holdout`

`thermerr diagnose examples/vmc_run.csv --machine examples/vmc_nominal.toml --out out/diagnosis`
should name `thermal_lag` and write `out/diagnosis/report.html`. Needs scipy.
"""

from __future__ import annotations

from pathlib import Path

from thermerr_rs import synthetic as syn
from thermerr_rs._io import write_atomic


def main() -> None:
    here = Path(__file__).resolve().parents[1] / "python" / "thermerr_rs" / "examples"  # shipped in the wheel; examples/ links to it
    case = syn.make_case("vmc", "thermal_lag", 7, train_duty="stepped", test_duty="random")
    write_atomic(here / "vmc_nominal.toml", "# nominal model of the synthetic VMC (made by make_diagnosis_example.py)\n" + case.nominal_toml())
    syn.write_run_csv(here / "vmc_run.csv", case.train)
    syn.write_run_csv(here / "vmc_holdout.csv", case.test)
    print(f"hidden: {case.hidden} {case.params}; wrote vmc_nominal.toml, vmc_run.csv, vmc_holdout.csv in {here}")


if __name__ == "__main__":
    main()
