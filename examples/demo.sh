#!/usr/bin/env bash
# The README's main command: set up a virtualenv, build and install thermerr_rs, and run the main
# jobs on the bundled examples. Needs Python >= 3.10 with pip and venv, and a Rust toolchain.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 -m venv .venv
# shellcheck disable=SC1091
. .venv/bin/activate
python -m pip install -q --upgrade pip
python -m pip install -q ".[report]"
mkdir -p out

echo
echo "== 1. What does the machine model get wrong? (VMC, 20 h run, nominal model 15-35 % off)"
thermerr diagnose examples/vmc_run.csv --machine examples/vmc_nominal.toml --out out/diagnosis

echo
echo "== 2. Sensor selection and a compensation model (HMC, 20 sensors, held-out second run)"
thermerr fit examples/hmc_run1.csv --axis E_z --model rbf --sensors auto --test examples/hmc_run2.csv --out out/rbf.json
echo
echo "-- the same 4 sensors, multiple linear regression:"
thermerr fit examples/hmc_run1.csv --axis E_z --model mlr --sensors auto --test examples/hmc_run2.csv --out out/mlr.json --quiet

echo
echo "Open out/diagnosis/report.html for the diagnosis; the models are in out/rbf.json and out/mlr.json."
