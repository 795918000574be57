#!/usr/bin/env python3
"""Turns the bench JSON files of scripts/bench-all-maps.sh into the Markdown table of
docs/motion.md: per map the shadows-off frame and each technique's frame-by-frame ratio to it
(median and 99th percentile), worst shadow volumes first; then how many maps meet the targets
of the third series' step 3 (volumes 1.5x, maps 1.25x, 99th percentile 2x)."""
import json
import os
import statistics
import sys


def main():
    rows = []
    for path in sys.argv[1:]:
        by = {r["technique"]: r for r in json.load(open(path))}
        if not {"none", "shadow_map", "shadow_volume"} <= by.keys():
            continue
        sm, sv, off = by["shadow_map"], by["shadow_volume"], by["none"]
        name = os.path.basename(path).removesuffix(".json")
        rows.append((name, off["lights"], off["frame_ms"]["median"], sm["ratio_median"],
                     sm["ratio_p99"], sv["ratio_median"], sv["ratio_p99"]))
    rows.sort(key=lambda r: -r[5])
    print("| map | lights | shadows off ms | SM × off median | SM × off p99 | SV × off median | SV × off p99 |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print("| %s | %d | %.2f | %.2f | %.2f | %.2f | %.2f |" % r)
    if not rows:
        return
    n = len(rows)
    print()
    print("%d maps. Median over the maps: SM %.2f×, SV %.2f×." % (
        n, statistics.median(r[3] for r in rows), statistics.median(r[5] for r in rows)))
    print("Within target: SM ≤ 1.25× on %d, SV ≤ 1.5× on %d; 99th percentile ≤ 2× on %d (SM), %d (SV)." % (
        sum(r[3] <= 1.25 for r in rows), sum(r[5] <= 1.5 for r in rows),
        sum(r[4] <= 2 for r in rows), sum(r[6] <= 2 for r in rows)))
    worst_sm = max(rows, key=lambda r: r[3])
    print("Worst: SV %s (%.2f×), SM %s (%.2f×)." % (rows[0][0], rows[0][5], worst_sm[0], worst_sm[3]))


if __name__ == "__main__":
    main()
