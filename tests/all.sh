#!/usr/bin/env bash
# Every test: the Rust workspace's (cargo test), then the Python package's (pytest), with the
# package built and installed into a fresh virtual environment as a user's `pip install ./python`
# would. Needs Python >= 3.9 with venv and pip; PyPI for maturin, numpy, pytest, cma and pymoo.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --workspace --locked
python="${PYTHON:-python3}"
venv=target/python-tests
rm -rf "$venv"
"$python" -m venv "$venv"
"$venv/bin/pip" install --quiet --upgrade pip
# The package is built with the dev profile, whose crates `cargo test` just compiled with the same
# features (shared/Cargo.toml says how): only pyo3, numpy and the module compile, about 20 s, where
# the release build a user's `pip install ./python` makes takes minutes here. Same code, and the
# dev profile compiles the physics as release does (Cargo.toml): the tests took 83 s (2026-12-07,
# 2-core AMD EPYC).
MATURIN_PEP517_ARGS="--profile dev" "$venv/bin/pip" install --quiet "./python[test,examples]"
# The tests run from the package's own folder, against the installed wheel (not the sources),
# and compare with the worker that cargo test just built.
AMORPH_BIN_DIR="$PWD/target/debug" "$venv/bin/python" -m pytest python/tests -q -p no:cacheprovider
