#!/usr/bin/env bash
# Regenerates the viewer screenshots docs/viewer.md shows (the built-in scene only: nothing of
# OpenArena's), by driving `shadowlab view` with a script under a virtual X server.
#
#   needs: a release build (cargo build --release), xvfb-run (Debian: xvfb xauth)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/shadowlab
[ -x "$bin" ] || { echo "error: $bin missing: run cargo build --release first" >&2; exit 1; }
command -v xvfb-run >/dev/null || { echo "error: xvfb-run missing: apt-get install xvfb xauth" >&2; exit 1; }
out=docs/screenshots
script=$(mktemp)
trap 'rm -f "$script"' EXIT
cat > "$script" <<SCRIPT
wait 2
screenshot $out/viewer-builtin.png
set technique=shadow_volume
overlay timings on
wait 3
screenshot $out/viewer-timings.png
walkthrough 3
wait 3
screenshot $out/viewer-walkthrough.png
walkthrough off
view stencil
wait 2
screenshot $out/viewer-stencil.png
view scene
set technique=shadow_map
light 1 shadow_volume
view depth
wait 2
screenshot $out/viewer-depth.png
quit
SCRIPT
xvfb-run -a -s "-screen 0 1280x800x24" "$bin" view --script "$script"
echo "wrote $out/viewer-{builtin,timings,walkthrough,stencil,depth}.png"
