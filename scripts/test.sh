#!/usr/bin/env bash
# Every test of incal: the Rust workspace, then the Python package built
# from this checkout and installed in a virtualenv of its own
# (target/py-venv), tested with pytest against the CLI built by the Rust
# tests. Needs cargo and python3 (3.9 or later) with venv; pip fetches
# maturin, pytest, numpy and pandas from PyPI.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== Rust: cargo test --workspace --locked"
cargo test --workspace --locked

echo "== Python: the incal package in target/py-venv"
venv=target/py-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install --quiet --disable-pip-version-check -r crates/incal-py/requirements-test.txt
"$venv/bin/pip" install --quiet --disable-pip-version-check --force-reinstall --no-deps crates/incal-py
echo "== Python: pytest crates/incal-py/tests"
INCAL_BIN="$PWD/target/debug/incal" "$venv/bin/python" -m pytest -q crates/incal-py/tests
