#!/usr/bin/env python3
"""Sums up a scripts/gpu-check.sh folder as one Markdown report (standard output): the GL,
the test suite's outcome, and per benchmark scene each technique's frame time and error with
the passes' times and the clock that timed them. docs/gpu.md says how to read it."""

import json
import re
import sys
from pathlib import Path


def load_json(path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        return {"error": str(e)}


def tests_section(folder):
    log = folder / "tests.log"
    if not log.exists():
        return ["Not run (`--no-tests`)."]
    status = (folder / "tests.status").read_text().split() if (folder / "tests.status").exists() else ["?", "?"]
    lines = [f"`cargo test --release --no-fail-fast`: exit {status[0]}, {status[1]} s."]
    binaries, failed = [], []
    current = None
    for line in log.read_text(errors="replace").splitlines():
        m = re.match(r"\s*Running (\S+)", line)
        if m:
            current = m.group(1)
        m = re.match(r"test result: (\w+)\. (\d+) passed; (\d+) failed.*finished in ([\d.]+)s", line)
        if m and current:
            binaries.append((current, m.group(1), m.group(2), m.group(3), m.group(4)))
        m = re.match(r"---- (\S+) stdout ----", line)
        if m:
            failed.append(f"{current}: {m.group(1)}")
    lines += ["", "| test binary | result | passed | failed | seconds |", "|---|---|---:|---:|---:|"]
    lines += [f"| {b} | {r} | {p} | {f} | {s} |" for b, r, p, f, s in binaries]
    if failed:
        lines += ["", "Failed (their output is in tests.log):", ""] + [f"- {f}" for f in failed]
    return lines


def bench_section(path):
    rows = load_json(path)
    if not isinstance(rows, list):
        return [f"{path.name}: no results ({rows.get('error', 'unreadable')}); see {path.with_suffix('.txt').name}."]
    lines = []
    first = rows[0] if rows else {}
    lines.append(
        f"{first.get('width')}x{first.get('height')}, {first.get('frames')} frames, "
        f"{first.get('lights')} lights; passes timed by the **{first.get('clock')}** clock."
    )
    lines += [
        "",
        "| configuration | frame ms (median / p95 / p99) | CPU ms | ms, 2 in flight | waits per frame | × shadows off | error | error excl. boundary |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        f = r["frame_ms"]
        e = r.get("error", {})
        lines.append(
            f"| {r['label']} | {f['median']:.2f} / {f['p95']:.2f} / {f.get('p99', float('nan')):.2f} "
            f"| {r.get('submit_ms', {}).get('median', float('nan')):.2f} "
            f"| {r.get('pipelined_ms', float('nan')):.2f} "
            f"| {r.get('syncs_per_frame', {}).get('total', float('nan')):.1f} "
            f"| {r['ratio_to_shadows_off']:.2f} | {100 * e.get('total', 0):.3f}% "
            f"| {100 * e.get('total_excl_boundary', 0):.3f}% |"
        )
    passes = sorted({p for r in rows for p in r.get("pass_ms", {}) if not re.match(r"light\d", p)})
    if passes:
        lines += ["", "Median ms per pass (`lights.X`: summed over the frame's lights):", ""]
        lines.append("| technique | " + " | ".join(passes) + " |")
        lines.append("|---|" + "---:|" * len(passes))
        for r in rows:
            cells = [f"{r['pass_ms'][p]:.2f}" if p in r.get("pass_ms", {}) else "" for p in passes]
            lines.append(f"| {r['label']} | " + " | ".join(cells) + " |")
    return lines


def main():
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    info = load_json(folder / "info.json")
    out = ["# shadowlab GPU check", ""]
    commit = (folder / "commit.txt").read_text().split("\n")[0] if (folder / "commit.txt").exists() else "?"
    out.append(f"Commit {commit}.")
    out += ["", "## The GL", ""]
    for key in ["backend", "api", "renderer", "vendor", "version"]:
        out.append(f"- {key}: {info.get(key, '?')}")
    missing = [f["key"] for f in info.get("features", []) if not f.get("supported")]
    out.append(f"- missing features (fallbacks): {', '.join(missing) or 'none'}")
    timer = next((f for f in info.get("features", []) if f.get("key") == "timer_query"), {})
    out.append(f"- timer queries: {'trusted' if timer.get('supported') else 'not trusted'} ({timer.get('detail', '?')})")
    out += ["", "## Test suite", ""] + tests_section(folder)
    out += ["", "## Benchmark flythroughs", ""]
    for path in sorted(folder.glob("bench-*.json")):
        out += [f"### {path.stem[len('bench-'):]}", ""] + bench_section(path) + [""]
    print("\n".join(out))


if __name__ == "__main__":
    main()
