#!/usr/bin/env bash
# Lint, type-check and test (arguments go to pytest). The first time (a fresh clone, as in CI),
# and again only when pyproject.toml changes or the install is broken, set up .venv with SimMeR
# and its test tools first.
set -euo pipefail
cd "$(dirname "$0")/.."
stamp=.venv/.simmer-test-installed  # written after a successful install of SimMeR[test]
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] \
    || ! .venv/bin/python -c "import importlib.metadata as m; m.version('simmer')" 2>/dev/null; then
    python3 -m venv .venv
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet -e ".[test]"
    touch "$stamp" .venv/.simmer-installed  # SimMeR[test] includes what run.sh installs
fi
export SDL_VIDEODRIVER=dummy SDL_AUDIODRIVER=dummy
.venv/bin/ruff check .
.venv/bin/ruff format --check .
.venv/bin/mypy
.venv/bin/pytest "$@"
