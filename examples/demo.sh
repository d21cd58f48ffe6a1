#!/usr/bin/env bash
# The README's main command: set up a virtualenv, build and install thermerr_rs, and run the main
# jobs on the bundled examples. Needs Python >= 3.10 with pip and venv, and a Rust toolchain.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 -m venv .venv
# shellcheck disable=SC1091
. .venv/bin/activate
python -m pip install -q --upgrade pip
mkdir -p out
echo "== 0. Building the Rust extension and installing thermerr_rs into .venv"
echo "   (the first build compiles ~150 crates: about 5 minutes on 2 cores; cargo's progress follows,"
echo "   the whole log is in out/build.log)"
# pip is silent while cargo runs; its verbose log carries cargo's lines, shown as they come
python -m pip install -v ".[report]" 2>&1 | tee out/build.log \
    | awk '/ Compiling | Finished |Successfully installed|^error/ { print "   " $0; fflush() }'


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
echo "== 3. Seed 004: an SVR tuned by chicken swarm optimisation (spindle at 3000 rpm, tested at 2000 rpm)"
thermerr fit examples/spindle_3000rpm.csv --axis E_z --model svr --tune cso \
    --sensors T_front_bearing,T_headstock,T_column,T_bed --test examples/spindle_2000rpm.csv --out out/svr.json

echo
echo "== 4. Which element's stiffness governs the axis? (key thermal stiffness, seed 001, on the MLR)"
thermerr stiffness out/mlr.json examples/hmc_run1.csv

echo
echo "== 5. The SVR on the edge: the lean Rust predictor (no Python) streams the held-out run"
cargo build --release -q -p thermerr-edge
"$(cargo metadata --format-version 1 --no-deps | python -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')/release/thermerr-edge" \
    out/svr.json examples/spindle_2000rpm.csv | head -5

echo
echo "Open out/diagnosis/report.html for the diagnosis; the models are in out/*.json."
