#!/usr/bin/env python3
"""Independent count of a Quake 3 map's faces and triangles, to check `shadowlab inspect`.

Reads the pk3 archives with Python's zipfile (later archives override earlier ones, as in
Quake 3), parses the IBSP header, models and surfaces lumps itself, and counts world model 0
the way the paper renders it: polygons and meshes from their index counts, patches as
((width-1)/2 * level) x ((height-1)/2 * level) quads of two triangles, flares as billboards.

usage: count-bsp.py DATA_DIR MAP [--level N]
prints one JSON object with faces, triangles, vertices.raw, lightmaps, leaves, clusters.
"""
import json
import os
import struct
import sys
import zipfile


def find_bsp(data_dir, name):
    base = os.path.join(data_dir, "baseoa")
    if not os.path.isdir(base):
        base = data_dir
    want = name.lower() if name.lower().endswith(".bsp") else f"maps/{name.lower()}.bsp"
    found = None
    for pak in sorted(p for p in os.listdir(base) if p.lower().endswith(".pk3")):
        with zipfile.ZipFile(os.path.join(base, pak)) as z:
            for info in z.infolist():
                if info.filename.lower() == want:
                    found = z.read(info)
    if found is None:
        sys.exit(f"{want} not found under {base}")
    return found


def count(data, level):
    magic, version = struct.unpack_from("<4si", data, 0)
    assert magic == b"IBSP" and version == 46, "not an IBSP v46 file"
    lumps = [struct.unpack_from("<ii", data, 8 + 8 * k) for k in range(17)]
    model_off, _ = lumps[7]
    first_surface, num_surfaces = struct.unpack_from("<ii", data, model_off + 24)
    surf_off, _ = lumps[13]
    faces = {"polygon": 0, "patch": 0, "mesh": 0, "billboard": 0}
    tris = {"polygon": 0, "mesh": 0, "patch": 0}
    raw = 0
    for k in range(first_surface, first_surface + num_surfaces):
        rec = surf_off + 104 * k
        kind = struct.unpack_from("<i", data, rec + 8)[0]
        num_verts, _, num_indexes = struct.unpack_from("<iii", data, rec + 16)
        width, height = struct.unpack_from("<ii", data, rec + 96)
        if kind == 1:
            faces["polygon"] += 1
            tris["polygon"] += num_indexes // 3
            raw += num_verts
        elif kind == 3:
            faces["mesh"] += 1
            tris["mesh"] += num_indexes // 3
            raw += num_verts
        elif kind == 2:
            faces["patch"] += 1
            columns = (width - 1) // 2 * level
            rows = (height - 1) // 2 * level
            tris["patch"] += columns * rows * 2
            raw += (columns + 1) * (rows + 1)
        elif kind == 4:
            faces["billboard"] += 1
    tris["total"] = tris["polygon"] + tris["mesh"] + tris["patch"]
    vis_off, vis_len = lumps[16]
    clusters = struct.unpack_from("<i", data, vis_off)[0] if vis_len >= 8 else 0
    return {
        "faces": faces,
        "triangles": tris,
        "vertices": {"raw": raw},
        "lightmaps": lumps[14][1] // (128 * 128 * 3),
        "leaves": lumps[4][1] // 48,
        "clusters": clusters,
    }


def main():
    args = sys.argv[1:]
    level = 8
    if "--level" in args:
        i = args.index("--level")
        level = int(args[i + 1])
        del args[i : i + 2]
    if len(args) != 2:
        sys.exit(__doc__)
    result = count(find_bsp(args[0], args[1]), level)
    result["map"] = os.path.splitext(os.path.basename(args[1]))[0]
    print(json.dumps(result))


if __name__ == "__main__":
    main()
