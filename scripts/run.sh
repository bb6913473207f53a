#!/usr/bin/env bash
# Run the simulator (arguments go to `simmer run`). The first time, and again only when
# pyproject.toml changes or the install is broken, scripts/setup.py sets up .venv with SimMeR
# first (an editable install: changes to the code need no reinstall).
set -euo pipefail
cd "$(dirname "$0")/.."
python3 scripts/setup.py
exec .venv/bin/simmer run "$@"
