#!/usr/bin/env bash
# rotrod's two entry points for a fresh machine (see README):
#   ./run.sh demo [options]       set up .venv if needed, then run the main job
#   ./run.sh test [pytest args]   set up .venv if needed, then lint, type-check and run the tests
# The virtual environment is created on first use and reused while constraints.txt
# and setup.py are unchanged. Everything comes from PyPI with exact pins. The message
# packages rotrod_interfaces/ and simulation_interfaces/ are built into it
# (tools/build_interfaces.py: cmake, ninja and the ROS build wheels from PyPI, a C/C++
# compiler from the system) whenever their files change.
set -euo pipefail
cd "$(dirname "$0")"
ROOT=$(pwd)
VENV=${ROTROD_VENV:-$ROOT/.venv}

pick_python() {
  # ROS 2 Jazzy wheels exist for CPython 3.10 to 3.13.
  for cand in ${PYTHON:-} python3 python3.12 python3.11 python3.13 python3.10; do
    if command -v "$cand" >/dev/null 2>&1 &&
       "$cand" -c 'import sys; sys.exit(not (3, 10) <= sys.version_info[:2] <= (3, 13))'; then
      echo "$cand"; return 0
    fi
  done
  echo "rotrod needs CPython 3.10-3.13 (ROS 2 Jazzy wheels); none found" >&2
  return 1
}

setup_venv() {
  local stamp="$VENV/.rotrod-setup" want
  want=$(cat constraints.txt setup.py | sha256sum | cut -d' ' -f1)
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
    return 0
  fi
  echo "rotrod: setting up $VENV (first run only; a few minutes)" >&2
  "$(pick_python)" -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet -c constraints.txt setuptools wheel
  "$VENV/bin/python" -m pip install --quiet --no-build-isolation -c constraints.txt \
    -e ".[ros,viz,bag,dev,sweep]"
  echo "$want" > "$stamp"
}

build_interfaces() {
  # rotrod_interfaces and simulation_interfaces, each built only when its files changed
  "$VENV/bin/python" tools/build_interfaces.py --prefix "$VENV"
}

cmd=${1:-}
[ $# -gt 0 ] && shift
case "$cmd" in
  demo)
    setup_venv
    build_interfaces
    exec "$VENV/bin/python" -m rotrod_core.cli demo "$@"
    ;;
  test)
    setup_venv
    build_interfaces
    export PATH="$VENV/bin:$PATH"
    echo "== ruff (lint, style, docstrings)" >&2
    "$VENV/bin/ruff" check .
    echo "== mypy (types; settings in pyproject.toml)" >&2
    "$VENV/bin/mypy"
    echo "== pytest" >&2
    # Tests that start ROS nodes keep DDS on this machine: a private network
    # namespace where the kernel permits it (see test/ros_harness.py).
    exec "$VENV/bin/python" test/isolate.py "$VENV/bin/python" -m pytest "$@"
    ;;
  *)
    echo "usage: ./run.sh demo [options] | ./run.sh test [pytest args]" >&2
    exit 2
    ;;
esac
