#!/usr/bin/env bash
# The test command: set-up, lint (ruff, the import contracts), the documentation site (mkdocs
# build --strict into site/: a broken link, anchor or docstring reference fails it; the docs
# tests read that build), then the whole suite (GPU tests run on the adapter wgpu finds;
# lavapipe on a machine without a GPU). Under CI=true the suite fails unless the adapter is
# lavapipe (llvmpipe), so GPU tests can never silently skip.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/setup.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
.venv/bin/ruff check vrneural tests demo scripts
.venv/bin/ruff format --check vrneural tests demo scripts
.venv/bin/lint-imports --no-cache   # the import contracts in pyproject.toml: no cycles, layers
bash scripts/docs.sh build --quiet
export VRNEURAL_DOCS_SITE="$PWD/site"
# The suite's status, then os._exit: interpreter teardown after a whole-suite run (wgpu-native,
# torch, Mitsuba and glfw objects all alive) segfaulted once in CI after every test had passed
# (docs/quality-research.md, "Notes"); pytest.main has finished its own teardown by then.
exec .venv/bin/python -c 'import os, sys, pytest
rc = pytest.main(sys.argv[1:])
sys.stdout.flush(); sys.stderr.flush()
os._exit(int(rc))' -q "$@"
