#!/bin/sh
# Times shadow maps and shadow volumes against the shadows-off frame on every map of the data
# set, as `check` loads it (first spawn point, the map's light entities or placed lights), over
# half a turn in place (the first 64 frames of `--path turn`): one bench JSON per map in OUT.
# Then `scripts/bench-maps-table.py OUT/*.json` makes the table of docs/motion.md.
#
#   scripts/bench-all-maps.sh [OUT] [extra bench arguments...]
#
# Needs the data set (scripts/fetch-openarena.sh) and a release build on PATH or in
# target/release. About 25 minutes on 2 cores at 320x240; a map already in OUT is skipped.
set -eu
out=${1:-bench-maps}
[ $# -gt 0 ] && shift
data=${SHADOWLAB_DATA:-$HOME/.cache/shadowlab/openarena}
bin=$(command -v shadowlab || echo target/release/shadowlab)
[ -d "$data/baseoa" ] || { echo "no data set at $data: run scripts/fetch-openarena.sh" >&2; exit 1; }
mkdir -p "$out/scenes"
for pk3 in "$data"/baseoa/*.pk3; do
    python3 -c 'import sys, zipfile; [print(n) for n in zipfile.ZipFile(sys.argv[1]).namelist() if n.startswith("maps/") and n.endswith(".bsp")]' "$pk3"
done | sort -u | while read -r bsp; do
    name=$(basename "$bsp" .bsp)
    [ -f "$out/$name.json" ] && continue
    printf 'name = "%s"\n[map]\nbsp = "%s"\n[camera]\nspawn = 0\n[lights]\nfrom = "entities_or_placed"\n' \
        "$name" "$bsp" > "$out/scenes/$name.toml"
    echo "$name" >&2
    "$bin" bench --scene "$out/scenes/$name.toml" --path turn --frames 64 --warmup 2 \
        --size 320x240 --set estimate.samples=0 --sweep technique=none,shadow_map,shadow_volume \
        --json "$out/$name.json" "$@" > "$out/$name.txt" 2>&1 || echo "$name failed: see $out/$name.txt" >&2
done
