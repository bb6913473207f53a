#!/usr/bin/env bash
# Run the simulator (arguments go to `simmer run`). The first time, and again only when
# pyproject.toml changes or the install is broken, set up .venv with SimMeR first (an editable
# install: changes to the code need no reinstall).
set -euo pipefail
cd "$(dirname "$0")/.."
stamp=.venv/.simmer-installed  # written after a successful install; compared with pyproject.toml
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] \
    || ! .venv/bin/python -c "import importlib.metadata as m; m.version('simmer')" 2>/dev/null; then
    python3 -m venv .venv
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet -e .
    touch "$stamp"
fi
exec .venv/bin/simmer run "$@"
