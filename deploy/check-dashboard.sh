#!/usr/bin/env bash
# The live dashboard in a real browser (run by .ci/run): headless Chromium (Debian's package,
# installed if missing) driven by Playwright for Python (PyPI, in a virtualenv under target/)
# runs tests/browser against the workspace's debug binaries, which `cargo test` built. The
# screenshots are left in target/dashboard/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
source deploy/checker-tools.sh
debian_package chromium chromium
venv="$root/target/browser-venv"
python_tools "$venv" "playwright, pytest" playwright pytest
cargo build --quiet --locked --bin coordinator
AMORPH_BIN_DIR="$root/target/debug" CHROMIUM="$(command -v chromium)" \
  "$venv/bin/python" -m pytest tests/browser -q -s -p no:cacheprovider
