#!/usr/bin/env python3
"""Turns `shadowlab check` JSON lines (stdin or files) into a Markdown table and a summary:
per map the error of each technique with the planner on and off, and the planner's mask
differences beyond the edge band (all its decisions, and only those that claim to change no
pixel: `conservative_beyond_edge_band`) and the volumes' error beside the pixels whose answer
alpha-tested casters' holes decide (`error_beside_alpha_percent`, which geometric volumes cannot
follow); then per run the median and worst error over the maps, and the same beside alpha."""
import json
import statistics
import sys


def lines(paths):
    sources = [open(p) for p in paths] if paths else [sys.stdin]
    for source in sources:
        for line in source:
            line = line.strip()
            if line.startswith("{"):
                yield json.loads(line)


def main():
    maps = list(lines(sys.argv[1:]))
    runs = [("shadow_map", True), ("shadow_map", False), ("shadow_volume", True), ("shadow_volume", False)]
    print("| map | lights | open edges | SM % | SM % (no planner) | SV % | SV % (no planner) "
          "| SV % beside alpha | planner Δ px SM / SV | conservative Δ px SM / SV |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    by_run = {r: [] for r in runs}
    beside_alpha = {r: [] for r in runs}
    failed = []
    for m in maps:
        name = m["map"].removeprefix("maps/").removesuffix(".bsp")
        if m.get("error"):
            failed.append((name, m["error"]))
            print(f"| {name} | – | – | – | – | – | – | – | – | {m['error']} |")
            continue
        errors = {}
        sv_cell = "–"
        for r in m["runs"]:
            key = (r["technique"], r["planner"])
            errors[key] = r["error_percent"]
            by_run[key].append((r["error_percent"], name))
            # Lines written before the field existed count their whole error.
            beside = r.get("error_beside_alpha_percent", r["error_percent"])
            beside_alpha[key].append((beside, name))
            if key == ("shadow_volume", True):
                sv_cell = f"{beside:.3f}"
        delta = {p["technique"]: p["beyond_edge_band"] for p in m["planner"]}
        kept = {p["technique"]: p.get("conservative_beyond_edge_band", 0) for p in m["planner"]}
        cells = " | ".join(f"{errors[r]:.3f}" for r in runs)
        print(f"| {name} | {m['lights']} | {m['open_edges']} | {cells} | {sv_cell} | "
              f"{delta.get('shadow_map', 0)} / {delta.get('shadow_volume', 0)} | "
              f"{kept.get('shadow_map', 0)} / {kept.get('shadow_volume', 0)} |")
    print()
    print("| run | maps | median error % | worst error % (map) |")
    print("|---|---:|---:|---|")
    for suffix, table in [("", by_run), (", beside alpha", beside_alpha)]:
        for (technique, planner), values in table.items():
            if not values:
                continue
            worst = max(values)
            label = f"{technique}, planner {'on' if planner else 'off'}{suffix}"
            print(f"| {label} | {len(values)} | {statistics.median(v for v, _ in values):.3f} | "
                  f"{worst[0]:.3f} ({worst[1]}) |")
    deltas = [(p["beyond_edge_band"], p["technique"], m["map"]) for m in maps if not m.get("error")
              for p in m["planner"]]
    kept = [(p.get("conservative_beyond_edge_band", 0), p["technique"], m["map"]) for m in maps
            if not m.get("error") for p in m["planner"]]
    if deltas:
        worst = max(deltas)
        print(f"\nplanner's worst mask difference beyond the edge band: {worst[0]} px "
              f"({worst[1]}, {worst[2]}); its conservative decisions alone: {max(kept)[0]} px "
              f"({max(kept)[1]}, {max(kept)[2]}); maps that could not be checked: {len(failed)}")


if __name__ == "__main__":
    main()
