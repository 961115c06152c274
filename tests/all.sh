#!/usr/bin/env bash
# Every test: the Rust workspace, then the Python package in a fresh virtual environment
# (built from this checkout with maturin through pip) and its pytest suite.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== cargo test --workspace --release"
cargo test --workspace --release

VENV="${DALEMBERT_VENV:-.venv}"
echo "== Python package into ${VENV}"
if [ ! -x "${VENV}/bin/python" ]; then
  python3 -m venv "${VENV}"
fi
"${VENV}/bin/python" -m pip install -q --upgrade pip
"${VENV}/bin/python" -m pip install -q "./crates/dalembert-python[test]"
echo "== pytest"
"${VENV}/bin/python" -m pytest -q crates/dalembert-python/tests
