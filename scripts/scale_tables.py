#!/usr/bin/env python3
"""gpu.md's scale and per-frame floor sections (scripts/gpu.sh, issue 43).

Usage: scale_tables.py DEST

Reads DEST/scale/RES/results.csv (the scale step's runs), DEST/floor/floor-RES.json (`tetbench
calibrate --floor --json`) and DEST/floor/tiny-RES/results.csv (every algorithm on a one-cell
mesh) and prints Markdown: one row per result row, and the floor beside them. The floor is
reported, never subtracted from a row.
"""

import csv
import json
import sys
from pathlib import Path


def cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def number(row, key):
    try:
        return float(row.get(key) or "nan")
    except ValueError:
        return float("nan")


def fmt(value, digits):
    return "–" if value != value else f"{value:.{digits}f}"


def runs(folder):
    """(resolution, rows) of every RES/results.csv under `folder`, by resolution."""
    found = []
    for results in sorted(folder.glob("*/results.csv")):
        with results.open(newline="") as f:
            found.append((results.parent.name, list(csv.DictReader(f))))
    return sorted(found, key=lambda r: int("".join(c for c in r[0] if c.isdigit()) or 0))


def scale_section(dest):
    out = ["## Scale", ""]
    scale = runs(dest / "scale")
    if not scale:
        return out + ["No scale run finished (see the step's exit above).", ""]
    out += [
        "Every algorithm's default variants, viewpoint +x+y+z, the median of the rounds "
        "(`scale/RES/`, with each run's report and charts):",
        "",
        "| algorithm | settings | data set | tets | viewport | total_ms | M tets/s | limit fraction | bound by |",
        "|---|---|---|---:|---|---:|---:|---:|---|",
    ]
    for _, rows in scale:
        for r in rows:
            if r.get("error"):
                tail = f"failed: {cell(r['error'])} | | | |"
                out.append(
                    f"| {cell(r['algorithm'])} | {cell(r['settings'])} | {cell(r['dataset'])} "
                    f"| {r['tets']} | {r['width']}² | {tail}"
                )
                continue
            out.append(
                f"| {cell(r['algorithm'])} | {cell(r['settings'])} | {cell(r['dataset'])} "
                f"| {r['tets']} | {r['width']}² | {fmt(number(r, 'total_ms'), 3)} "
                f"| {fmt(number(r, 'tets_per_sec') * 1e-6, 1)} "
                f"| {fmt(number(r, 'limit_fraction'), 2)} | {cell(r.get('bound_by', ''))} |"
            )
    return out + [""]


def floor_section(dest):
    out = [
        "## Per-frame floor",
        "",
        "What a frame costs before any algorithm works (`tetbench calibrate --floor`), and "
        "every algorithm on a one-cell mesh (box:5). Reported beside the scale rows, never "
        "subtracted from them.",
        "",
    ]
    floors = sorted(
        (dest / "floor").glob("floor-*.json"),
        key=lambda p: int("".join(c for c in p.stem if c.isdigit()) or 0),
    )
    if not floors:
        out += ["No floor was measured (see the step's exit above).", ""]
    for path in floors:
        floor = json.loads(path.read_text())
        out += [
            f"{cell(floor['adapter'])} at {floor['width']}², {floor['reps']} repetitions a step:",
            "",
            "| step | median (µs) | fastest (µs) |",
            "|---|---:|---:|",
        ]
        out += [
            f"| {cell(s['step'])} | {s['median_us']:.1f} | {s['min_us']:.1f} |"
            for s in floor["steps"]
        ]
        if floor.get("render_pass_us") is not None and floor.get("compute_pass_us") is not None:
            out += [
                "",
                f"One empty pass: render {floor['render_pass_us']:.1f} µs, compute "
                f"{floor['compute_pass_us']:.1f} µs (the fastest 64-pass step less the fastest "
                "`submit + wait`, over 64).",
            ]
        out.append("")
    tiny = runs(dest / "floor")
    if tiny:
        out += [
            "| algorithm | settings | viewport | total_ms (median) | total_ms (fastest) |",
            "|---|---|---|---:|---:|",
        ]
        for _, rows in tiny:
            for r in rows:
                out.append(
                    f"| {cell(r['algorithm'])} | {cell(r['settings'])} | {r['width']}² "
                    f"| {fmt(number(r, 'total_ms'), 3)} | {fmt(number(r, 'total_ms_min'), 3)} |"
                    if not r.get("error")
                    else f"| {cell(r['algorithm'])} | {cell(r['settings'])} | {r['width']}² "
                    f"| failed: {cell(r['error'])} | |"
                )
        out.append("")
    return out


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: scale_tables.py DEST")
    dest = Path(sys.argv[1])
    print("\n".join(scale_section(dest) + floor_section(dest)))


if __name__ == "__main__":
    main()
