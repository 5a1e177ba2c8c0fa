#!/usr/bin/env python3
"""Summarises the profiles of scripts/profile.sh: DIR/*.report.txt (perf report --stdio
--no-children --sort comm,dso,sym) and DIR/*.run/results.json, into DIR/profile.md.

Every CPU sample goes into one category by thread, library and symbol (the rules are below, in
the order they are tried). The frame times come from the run's own results (median of the timed
frames): `wait` there is the time the host thread waited for the GPU, off the CPU, which a
cpu-clock profile cannot see.
"""
import json
import pathlib
import re
import sys

# (category, thread regex, dso regex, symbol regex); the first rule that matches wins. Debian
# ships lavapipe stripped (no internal symbols, and no debug package reachable here), so its code
# is split by thread: llvmpipe's worker threads (`llvmpipe-N`) rasterise binned triangles, run the
# JIT-compiled fragment shaders and blend; the vertex/setup half of a draw (vertex fetch, JIT
# vertex shader, clipping, triangle setup, binning) runs on lavapipe's queue thread, and compute
# dispatches on its compute threads, all of which carry the process's name.
WORKER = r"^llvmpipe"
QUEUE_AND_COMPUTE = r"^(?!llvmpipe)"
JIT = r"^\[JIT\]|^\[unknown\]|perf-\d+\.map"
RULES = [
    ("LLVM shader compilation", r".*", r"libLLVM", r".*"),
    ("llvmpipe workers: JIT fragment shaders and blending", WORKER, JIT, r".*"),
    ("llvmpipe workers: rasterisation, tile load/store, clears", WORKER, r"libvulkan_lvp|libgallium", r".*"),
    ("llvmpipe workers: other (kernel, libc)", WORKER, r".*", r".*"),
    ("harness per row (readback, PNG, f32 image, metrics)", r".*", r".*",
     r"png::|fdeflate|miniz_oxide|zstd|lz4|blake3|harness::|image::|crc32|adler|serde_json|"
     r"csv::|read_rgba32f|to_srgb8|image_error|ZSTD|heatmap"),
    ("queue and compute threads: JIT vertex and compute shaders", QUEUE_AND_COMPUTE, JIT, r".*"),
    ("queue and compute threads: lavapipe (command execution, vertex fetch, setup, binning, copies)",
     QUEUE_AND_COMPUTE, r"libvulkan_lvp|libgallium", r".*"),
    ("wgpu (encoding, validation, submission)", r".*", r".*", r"wgpu|naga|ash::|gpu_alloc|gpu_descriptor"),
    ("our host work (sorts, classification, packing, counters)", r".*", r"tetbench",
     r"render_core|gator_pt|havs|fragment_pt|raycast|splat|datasets|radix|rayon"),
    ("kernel (page faults, scheduling, futex)", r".*", r"kernel", r".*"),
    ("libc and libm (memcpy, math)", r".*", r"libc|libm", r".*"),
]
OTHER = "other"
# `perf report -t '|' -F sample,comm,dso,sym`: " 234  |tetbench  |tetbench  |[.] symbol". Sample
# counts, not percentages: JIT code spreads over thousands of addresses, each under the 0.01 %
# that a percentage column can show, and would be lost.
LINE = re.compile(r"^\s*([0-9]+)\s*\|([^|]*)\|([^|]*)\|\[(.)\]\s*(.*)$")


def classify(comm, dso, sym):
    for name, c, d, s in RULES:
        if re.search(c, comm) and re.search(d, dso) and re.search(s, sym):
            return name
    return OTHER


def read_report(path):
    samples = []
    for line in path.read_text(errors="replace").splitlines():
        m = LINE.match(line)
        if m:
            count, comm, dso, _, sym = m.groups()
            samples.append((float(count), comm.strip(), dso.strip(), sym.strip()))
    total = sum(s[0] for s in samples) or 1.0
    return [(100.0 * c / total, comm, dso, sym) for c, comm, dso, sym in samples]


def median(v):
    v = sorted(v)
    n = len(v)
    return None if n == 0 else (v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2)


def frame_figures(run_dir):
    """One dict per successful row of the profiled run (every variant of the default grid)."""
    try:
        rows = json.loads((run_dir / "results.json").read_text())["rows"]
    except (OSError, KeyError, ValueError):
        return []
    figures = []
    for r in rows:
        if r.get("error"):
            continue
        stages = dict(kv.split("=", 1) for kv in (r.get("stages") or "").split(";") if "=" in kv)
        counters = dict(kv.split("=", 1) for kv in (r.get("counters") or "").split(";") if "=" in kv)
        settings = r.get("settings")
        if isinstance(settings, dict):
            settings = ";".join(f"{k}={v}" for k, v in settings.items())
        figures.append({
            "settings": settings,
            "tets": r.get("tets"),
            "total_ms": r.get("total_ms"),
            "cpu_ms": r.get("cpu_ms"),
            "wait_ms": float(stages["wait"]) if "wait" in stages else None,
            "frames": r.get("frames"),
            "harness_ms": r.get("harness_ms"),
            "fragments": float(counters["fragments"]) if "fragments" in counters else None,
        })
    return figures


def fmt(v, digits=1):
    return "–" if v is None else f"{v:.{digits}f}"


def main():
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/profile")
    reports = sorted(out.glob("*.report.txt"))
    if not reports:
        sys.exit(f"profile_summary.py: no *.report.txt in {out}")
    lines = ["# Profile tables (generated by scripts/profile.sh; read with profile.md)", "",
             "Share of the CPU samples of the frames and rows (loading and preparing excluded) per "
             "category; frame times from the run's own rows (median of the timed frames).", ""]
    for rep in reports:
        name = rep.name[: -len(".report.txt")]
        algorithm, dataset, resolution = name.split("__")
        samples = read_report(rep)
        shares = {}
        for pct, comm, dso, sym in samples:
            k = classify(comm, dso, sym)
            shares[k] = shares.get(k, 0.0) + pct
        top = sorted(samples, reverse=True)[:8]
        rows = frame_figures(out / f"{name}.run")
        lines += [f"## {algorithm} on {dataset} at {resolution}²", ""]
        if rows:
            lines += ["| variant | tets | fragments | frame ms | ns per fragment | host CPU ms | GPU wait ms | harness ms per frame |",
                      "|---|---:|---:|---:|---:|---:|---:|---:|"]
            for f in rows:
                per_frame = (f["harness_ms"] / f["frames"]) if f.get("harness_ms") is not None and f.get("frames") else None
                ns = (f["total_ms"] * 1e6 / f["fragments"]) if f.get("fragments") and f.get("total_ms") else None
                frags = f"{f['fragments']:,.0f}" if f.get("fragments") else "–"
                lines.append(f"| `{f['settings']}` | {f['tets']} | {frags} | {fmt(f['total_ms'])} | {fmt(ns)} | {fmt(f['cpu_ms'])} | "
                             f"{fmt(f['wait_ms'])} | {fmt(per_frame)} |")
        lines += ["", "| category | share of CPU samples |", "|---|---:|"]
        for k, v in sorted(shares.items(), key=lambda kv: -kv[1]):
            lines.append(f"| {k} | {v:.1f} % |")
        lines += ["", "Largest symbols:", "", "| share | thread | library | symbol |", "|---:|---|---|---|"]
        for pct, comm, dso, sym in top:
            lines.append(f"| {pct:.1f} % | {comm} | {dso} | `{sym[:90]}` |")
        lines.append("")
    (out / "profile.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
