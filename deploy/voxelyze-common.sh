# Sourced by deploy/voxelyze-check.sh and deploy/voxelyze-ensemble.sh (docs/how-to/voxelyze.md):
# what both mean by "the VoxCAD-era Voxelyze's floor on our side" and how both run that reader.
# Each caller sets `tool` (its name, for messages) before sourcing.

# The reader's floor is a spring of 2·E·s per voxel (twice ours by default) damped by
# 2·√(m·E·s): as ours, a stiffness factor of 2 with a contact damping ratio of 1/√2.
READER_FLOOR_STIFFNESS=2.0
READER_FLOOR_DAMPING=0.7071067811865476

# voxelyze_worker ROOT READER: prints the worker binary to use ($WORKER, else ROOT's release
# build) after checking that it and the reader can run.
voxelyze_worker() {
  local worker="${WORKER:-$1/target/release/worker}"
  [ -x "$worker" ] || { echo "$tool: no worker at $worker (cargo build --release, or set WORKER)" >&2; exit 2; }
  [ -x "$2" ] || { echo "$tool: $2 is not an executable" >&2; exit 2; }
  echo "$worker"
}

# require_floor_table SCENE: stops the script unless SCENE (a run's config.toml) has the
# [scene.dynamics.floor] table that reader_floor_scene rewrites.
require_floor_table() {
  grep -q '^\[scene\.dynamics\.floor\]$' "$1" || {
    echo "$tool: $1 has no [scene.dynamics.floor] table" >&2
    exit 2
  }
}

# reader_floor_scene SCENE [SED-EXPRESSION...]: prints a run's config.toml with the reader's
# whole floor (contact at the actuated size, its friction law, its spring and damping), after any
# further sed expressions given.
reader_floor_scene() {
  local scene=$1
  shift
  require_floor_table "$scene"
  local extra=()
  for expression in "$@"; do extra+=(-e "$expression"); done
  grep -Ev '^(actuated_contact|friction) = ' "$scene" |
    sed -e 's/^\[scene\.dynamics\.floor\]$/&\nactuated_contact = true\nfriction = "voxcad"/' \
        -e "s/^stiffness_factor = .*/stiffness_factor = $READER_FLOOR_STIFFNESS/" \
        -e "s/^contact = .*/contact = $READER_FLOOR_DAMPING/" "${extra[@]}"
}

# run_reader READER DIR WHAT: runs `READER -f design.vxa` in DIR and stops the script, naming
# WHAT, unless it wrote its result file.
run_reader() {
  # The reader's exit status is 1 even when it ran to the end; its result file is the sign.
  (cd "$2" && "$1" -f design.vxa > reader.log 2>&1) || true
  [ -s "$2/fitness.xml" ] || {
    echo "$tool: the reader wrote no result for $3:" >&2
    tail -5 "$2/reader.log" >&2
    exit 1
  }
}
