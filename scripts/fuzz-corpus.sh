#!/usr/bin/env bash
# Builds the fuzz targets' seed corpora in fuzz/corpus/<target>/ from the OpenArena data that
# scripts/fetch-openarena.sh fetched ($SHADOWLAB_DATA, else ~/.cache/shadowlab/openarena), the
# repo's own scene files, and small seeds written here. fuzz/corpus is gitignored: nothing
# fetched is committed. Without the data the targets still get the written seeds.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
data=${SHADOWLAB_DATA:-$HOME/.cache/shadowlab/openarena}
out=$root/fuzz/corpus
mkdir -p "$out"
if ! ls "$data"/baseoa/*.pk3 >/dev/null 2>&1; then
    echo "note: no OpenArena data in $data (scripts/fetch-openarena.sh fetches it);" \
        "writing the hand-made seeds only" >&2
fi
python3 - "$data" "$out" "$root" <<'PY'
import glob, hashlib, io, os, struct, sys, zipfile

data, out, root = sys.argv[1:4]
counts = {}

def seed(target, content, name=None):
    if isinstance(content, str):
        content = content.encode()
    d = os.path.join(out, target)
    os.makedirs(d, exist_ok=True)
    # Content-addressed like libFuzzer's own corpus files, so that reruns add nothing twice.
    name = name or hashlib.sha1(content).hexdigest()
    with open(os.path.join(d, name), "wb") as f:
        f.write(content)
    counts[target] = counts.get(target, 0) + 1

paks = sorted(glob.glob(os.path.join(data, "baseoa", "*.pk3"))) + sorted(
    glob.glob(os.path.join(data, "missionpack", "*.pk3")))
entries = []  # (pak, info)
for p in paks:
    try:
        z = zipfile.ZipFile(p)
    except zipfile.BadZipFile:
        continue
    for i in z.infolist():
        if not i.is_dir():
            entries.append((z, i))

def pick(suffix, limit, max_bytes):
    """The `limit` smallest entries ending in `suffix`, each at most `max_bytes`."""
    found = [(i.file_size, z, i) for z, i in entries
             if i.filename.lower().endswith(suffix) and 0 < i.file_size <= max_bytes]
    found.sort(key=lambda t: (t[0], t[2].filename))
    # Spread over the sizes rather than only the smallest.
    if len(found) > limit:
        step = len(found) / limit
        found = [found[int(k * step)] for k in range(limit)]
    return [z.read(i) for _, z, i in found]

for b in pick(".shader", 40, 64 << 10):
    seed("shader", b)
for b in pick(".md3", 60, 256 << 10):
    seed("md3", b)
for b in pick(".skin", 40, 16 << 10):
    seed("skin", b)
for b in pick("animation.cfg", 20, 16 << 10):
    seed("animation_cfg", b)
bsps = pick(".bsp", 8, 2 << 20)
for b in bsps:
    seed("bsp", b)
    # The entity lump is lump 0: offset and length right after "IBSP" and the version.
    if len(b) >= 16 and b[:4] == b"IBSP":
        off, length = struct.unpack_from("<ii", b, 8)
        if 0 <= off and 0 < length <= len(b) - off:
            seed("entities", b[off:off + length].rstrip(b"\0"))
    # Patch control grids: surfaces (lump 13, 104 bytes each) of type 2, vertices lump 10.
    if len(b) >= 8 + 17 * 8 and b[:4] == b"IBSP":
        lumps = [struct.unpack_from("<ii", b, 8 + 8 * k) for k in range(17)]
        (so, sl), (vo, vl) = lumps[13], lumps[10]
        made = 0
        for s in range(sl // 104):
            r = so + 104 * s
            if r + 104 > len(b) or made >= 4:
                break
            kind, fv, nv = struct.unpack_from("<i", b, r + 8)[0], *struct.unpack_from("<ii", b, r + 12)
            w, h = struct.unpack_from("<ii", b, r + 96)
            if kind != 2 or not (0 < w < 256 and 0 < h < 256) or w * h != nv:
                continue
            verts = b[vo + 44 * fv: vo + 44 * (fv + nv)]
            if len(verts) == 44 * nv:
                seed("patch", bytes([w, h, 4]) + verts)
                made += 1
for b in pick(".rtlights", 20, 64 << 10):
    seed("rtlights", b)

# Small pk3s made of a few real entries (the real archives are far too big to mutate), and
# archives that are hostile by construction.
def make_zip(files, method=zipfile.ZIP_DEFLATED):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as z:
        for name, content in files:
            z.writestr(name, content)
    return buf.getvalue()

small = [(i.filename, z.read(i)) for z, i in entries if 0 < i.file_size <= 2048][:60]
for k in range(0, len(small), 4):
    seed("pk3", make_zip(small[k:k + 4]))
    seed("pk3", make_zip(small[k:k + 2], zipfile.ZIP_STORED))
seed("pk3", make_zip([]))
seed("pk3", make_zip([("scripts/a.shader", "textures/a { }\n"), ("maps/", "")]))
seed("pk3", make_zip([("../../etc/passwd", "x"), ("..\\boot.ini", "y"), ("/abs/path", "z"),
                      ("MAPS/X.BSP", "IBSP"), ("maps/x.bsp", "ibsp")]))
seed("pk3", make_zip([("zeros.bin", b"\0" * (1 << 20))]))
seed("pk3", make_zip([("f%d" % n, b"") for n in range(300)], zipfile.ZIP_STORED))

# Written seeds where the data has none.
seed("rtlights", "0 0 64 256 1 1 1 0 0 0 0 \"\" 1 0.25 1 1 0\n"
                  "!64 128 32 300 0.5 0.8 1 1 90 0 0 \"cubemaps/x\" 1 0.25 1 1 3\n")
seed("rtlights", "128 -64 96 200 1 0.5 0.25\n")
for t in glob.glob(os.path.join(root, "assets", "**", "*.rtlights"), recursive=True):
    seed("rtlights", open(t, "rb").read())
for t in glob.glob(os.path.join(root, "assets", "**", "*.toml"), recursive=True):
    seed("scene_file", open(t, "rb").read())
seed("scene_file", 'name = "x"\nbase = "empty"\n[[light]]\nposition = [0, 0, 64]\nradius = 300\n'
                   'kind = "spot"\ndirection = [0, 0, -1]\ncutoff = 40\n[camera]\n'
                   'position = [0, -200, 80]\n[options]\ntechnique = "volumes"\n')
seed("camera_path", "# shadowlab camera path: x y z yaw pitch\n0 0 64 0 0\n16 0 64 5 -2.5\n")
seed("camera_path", "1e3 -2e3 3.5 360 89 # a comment\n\n-0 0 0 -90 -89\n")
seed("viewer_script", "wait 2\nscreenshot a.png\nset technique=none\nwait 2\nframe b.png\n"
                      "overlay volumes on\nview stencil\nwalkthrough 3\nwalkthrough off\nquit\n")
seed("viewer_script", "camera 0 0 64 90 -10\nlight 0 volumes\nlight 1 default\nselect 0\n"
                      "face 2\nreplay p.path\nrecord r.path\nrecord stop\nerror\n# c\nview depth\n")
seed("entities", '{\n"classname" "worldspawn"\n}\n{\n"classname" "light"\n"origin" "0 0 64"\n'
                 '"light" "300"\n"_color" "1 0.5 0.5"\n}\n{\n"classname" "info_player_deathmatch"\n'
                 '"origin" "32 32 24"\n"angle" "90"\n}\n')
seed("skin", "tag_head,\nh_head,models/players/x/h.tga\nu_torso,models/players/x/u.tga\n")
seed("animation_cfg", "sex m\nheadoffset 0 0 0\nfootsteps normal\n" +
     "".join("%d %d %d %d\n" % (k * 10, 10, 0, 15) for k in range(25)))
seed("shader", "textures/x/y\n{\n\tsurfaceparm nonsolid\n\tcull none\n\t{\n\t\tmap $lightmap\n"
               "\t\trgbGen identity\n\t}\n\t{\n\t\tmap textures/x/y.tga\n\t\tblendFunc GL_DST_COLOR GL_ZERO\n"
               "\t\talphaFunc GE128\n\t}\n}\n")
seed("patch", bytes([3, 3, 4]) + b"".join(struct.pack("<10f4B", x * 8, y * 8, (x * y) % 3, x, y,
                                                       0, 0, 0, 0, 1, 255, 255, 255, 255)
                                           for y in range(3) for x in range(3)))
seed("patch", bytes([5, 3, 0x82]) + struct.pack("<10f4B", *([1.0] * 10), 1, 2, 3, 4) * 15)
seed("bsp", b"IBSP" + struct.pack("<i", 46) + b"\0" * (17 * 8))
seed("md3", b"IDP3" + struct.pack("<i", 15) + b"\0" * 100)

for t in sorted(counts):
    print(f"{t:14} {counts[t]:4} seeds -> {os.path.join(out, t)}")
PY
