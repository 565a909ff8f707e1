#!/usr/bin/env bash
# Assembles the offline image build contexts: for each of coordinator and worker, a root filesystem
# holding the binary (debug info stripped), exactly the shared libraries it links and the dynamic
# loader, found with ldd on this machine, plus the Dockerfile (FROM scratch). No image is pulled.
#
#   deploy/stage.sh [release|debug]    (default release; debug reuses what `cargo test
#                                        --workspace` built)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
profile="${1:-release}"
cd "$root"
case "$profile" in
  release) cargo build --release --locked --bin coordinator --bin worker; dir=release ;;
  # After `cargo test --workspace` this compiles nothing: the features agree (shared/Cargo.toml).
  debug) cargo build --locked --bin coordinator --bin worker; dir=debug ;;
  *) echo "stage.sh: profile must be release or debug, not '$profile'" >&2; exit 2 ;;
esac
for bin in coordinator worker; do
  ctx="$root/deploy/.build/$bin"
  rm -rf "$ctx"
  mkdir -p "$ctx/rootfs/results" "$ctx/rootfs/config" "$ctx/rootfs/tmp"
  chmod 1777 "$ctx/rootfs/tmp" "$ctx/rootfs/results"
  objcopy --strip-debug "target/$dir/$bin" "$ctx/rootfs/$bin"
  # Every library ldd resolves (the "=> /path" column) and the loader (a bare absolute path).
  ldd "target/$dir/$bin" | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' |
    while read -r lib; do cp -L --parents "$lib" "$ctx/rootfs/"; done
  sed "s/@BIN@/$bin/g" "$root/deploy/offline.Dockerfile" > "$ctx/Dockerfile"
  echo "staged $bin: $(du -sh "$ctx/rootfs" | cut -f1) ($(find "$ctx/rootfs" -type f | wc -l) files)"
done
