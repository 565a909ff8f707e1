# Sourced by the deploy/check-*.sh scripts: the independent programs a check runs, installed once.

# debian_package COMMAND PACKAGE: installs Debian's PACKAGE unless COMMAND is already on PATH.
debian_package() {
  if ! command -v "$1" >/dev/null; then
    apt-get update -qq >/dev/null && apt-get install -y -qq "$2" >/dev/null
  fi
}

# python_tools VENV MODULES PACKAGE...: a virtualenv at VENV where `import MODULES` works,
# installing the PyPI PACKAGEs into a new one if it does not.
python_tools() {
  local venv="$1" modules="$2"
  shift 2
  if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import $modules" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --disable-pip-version-check "$@"
  fi
}
