#!/usr/bin/env bash
# Set up a fresh Debian machine for mfflap's tests and run them: OpenFOAM (the solvers the
# full tier runs), gcc (it compiles the generated Fluent UDFs) and Chromium with its
# WebDriver (the full tier renders the HTML report in it) from Debian, mfflap, its
# CFD records (./data) and its test and documentation tools; then ruff, the fast tier and
# the full tier.
#
#   scripts/install-and-test.sh           set up, then run both tiers
#   scripts/install-and-test.sh --fast    set up, then run the fast tier only
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v pimpleFoam >/dev/null 2>&1 || ! command -v gcc >/dev/null 2>&1 \
    || ! command -v setpriv >/dev/null 2>&1 || ! command -v chromedriver >/dev/null 2>&1; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  # util-linux's setpriv (essential on Debian, named in case an image left it out) ties
  # each solver to the process that started it
  $sudo apt-get install -y -qq openfoam gcc libc6-dev util-linux chromium chromium-driver \
    >/dev/null
fi

python -m pip install -q --upgrade pip
python -m pip install -q -e '.[test]' -e ./data
ruff check .
lint-imports                                # the layers (.importlinter)
python -m pytest -q                         # the fast tier: no OpenFOAM, no slow tests
if [ "${1:-}" != "--fast" ]; then
  # the rest of the full tier (the two runs together are `pytest --full`)
  python -m pytest -q -m "openfoam or slow"  # the replays (pytest --replays) are not in it
fi
