#!/usr/bin/env bash
# Installs the independent programs the deploy/check-*.sh scripts run (Debian's admesh and
# chromium, lib3mf and Playwright from PyPI), so that .ci/run can fetch them while it compiles:
# the downloads wait on the network, the build on the cores. Each check script still installs
# what it finds missing, so a failure here only moves the work there.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
source deploy/checker-tools.sh
debian_package admesh admesh
debian_package chromium chromium
python_tools "$root/target/exports-venv" lib3mf lib3mf
python_tools "$root/target/browser-venv" "playwright, pytest" playwright pytest
