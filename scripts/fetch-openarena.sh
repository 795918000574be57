#!/usr/bin/env bash
# Fetches OpenArena's game data (GPL-2+) from Debian's packages into a cache outside the
# repository and keeps only the .pk3 files. Idempotent: a complete cache is left as it is.
#
#   cache: $SHADOWLAB_DATA, else ~/.cache/shadowlab/openarena (the binary looks there too)
#   needs: apt-get (Debian/Ubuntu), dpkg-deb, tar; works as root or not
set -euo pipefail

dest="${SHADOWLAB_DATA:-$HOME/.cache/shadowlab/openarena}"
packages=(openarena-data openarena-081-maps openarena-081-misc openarena-081-textures
          openarena-081-players openarena-085-data)
stamp="$dest/.fetched"
wanted="${packages[*]}"

if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$wanted" ]; then
    echo "OpenArena data already in $dest ($(find "$dest" -name '*.pk3' | wc -l) pk3 files)"
    exit 0
fi

command -v apt-get >/dev/null || { echo "error: apt-get not found (Debian or Ubuntu needed)" >&2; exit 1; }
mkdir -p "$dest"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"

echo "downloading ${packages[*]} ..."
if ! apt-get download "${packages[@]}"; then
    # The package lists may be missing on a fresh machine; refreshing them needs root.
    if [ "$(id -u)" -eq 0 ]; then
        apt-get update -qq
    elif command -v sudo >/dev/null; then
        sudo apt-get update -qq
    else
        echo "error: apt-get download failed; run 'apt-get update' as root and retry" >&2
        exit 1
    fi
    apt-get download "${packages[@]}"
fi

for deb in ./*.deb; do
    echo "unpacking $(basename "$deb")"
    mkdir -p x
    # Only the .pk3 archives are kept.
    dpkg-deb --fsys-tarfile "$deb" | tar -x -C x --wildcards '*.pk3'
done

# The packages install under usr/share/games/openarena/<mod>/; keep <mod>/file.pk3.
root="x/usr/share/games/openarena"
[ -d "$root" ] || { echo "error: no pk3 files found under $root" >&2; exit 1; }
( cd "$root" && find . -name '*.pk3' -print0 ) | while IFS= read -r -d '' f; do
    mkdir -p "$dest/$(dirname "$f")"
    cp -f "$root/$f" "$dest/$f"
done
echo "$wanted" > "$stamp"
echo "OpenArena data in $dest ($(find "$dest" -name '*.pk3' | wc -l) pk3 files, $(du -sh "$dest" | cut -f1))"
