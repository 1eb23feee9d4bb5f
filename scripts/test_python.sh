#!/usr/bin/env bash
# The Python package's tests, after `cargo test --release` (the README's test command runs both):
# the package installed with `pip install .` into a fresh virtual environment
# (target/python-venv) and run against the `caustic` binary the Rust suite built, so the two are
# compared with each other.
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/python-venv
rm -rf "$venv"
python3 -m venv "$venv"
"$venv/bin/python" -m pip install --quiet --upgrade pip
start=$(date +%s)
"$venv/bin/python" -m pip install --quiet . pytest numpy
echo "pip install . took $(( $(date +%s) - start )) s"
CAUSTIC_BIN="$PWD/target/release/caustic" "$venv/bin/python" -m pytest python/tests -q
