#!/usr/bin/env bash
# Lint, type-check and test (arguments go to pytest). The first time (a fresh clone, as in CI),
# and again only when pyproject.toml changes or the install is broken, scripts/setup.py sets up
# .venv with SimMeR and its test tools first.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 scripts/setup.py --test
export SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy
.venv/bin/ruff check .
.venv/bin/ruff format --check .
.venv/bin/mypy
# -m "": every test, the slow ones too (plain `pytest` leaves out those marked slow or fresh).
.venv/bin/pytest -m "" "$@"
