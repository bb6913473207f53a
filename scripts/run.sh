#!/usr/bin/env bash
# Set up a virtual environment with SimMeR, then run the simulator (arguments go to `simmer run`).
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e .
exec .venv/bin/simmer run "$@"
