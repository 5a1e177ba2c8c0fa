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

# (category, thread regex, dso regex, symbol regex); the first rule that matches wins.
RULES = [
    ("LLVM shader compilation", r".*", r"libLLVM", r".*"),
    ("harness per row (readback, PNG, f32 image, metrics)", r".*", r".*",
     r"png::|fdeflate|miniz_oxide|zstd|lz4|blake3|harness::metrics|harness::samples|"
     r"image::|crc32|adler|serde_json|csv::|harness::results|read_rgba32f|heatmap"),
    ("llvmpipe rasteriser: JIT fragment shaders", r"^llvmpipe|^lp", r"\[unknown\]|\[JIT\]|perf-\d+\.map", r".*"),
    ("llvmpipe rasteriser: tiles, blending, clears", r"^llvmpipe|^lp", r".*", r".*"),
    ("llvmpipe vertex processing and triangle setup", r".*", r".*",
     r"^(draw_|lp_setup|llvmpipe_|lp_rast_|lp_scene|vbuf|vsplit|vcache|fetch_|emit_|"
     r"clip_|do_triangle|triangle|setup_)"),
    ("llvmpipe JIT vertex/compute shaders (submitting thread)", r".*", r"\[unknown\]|\[JIT\]|perf-\d+\.map", r".*"),
    ("lavapipe command execution (copies, compute dispatch, state)", r".*", r"libvulkan_lvp|libgallium|lvp", r".*"),
    ("wgpu (encoding, validation, submission)", r".*", r".*", r"wgpu|naga|ash::|gpu_alloc|gpu_descriptor"),
    ("our host work (sorts, classification, packing)", r".*", r"tetbench", r"render_core|gator_pt|havs|fragment_pt|raycast|splat|datasets"),
    ("memcpy/memset (libc)", r".*", r"libc", r"mem(cpy|set|move)"),
]
OTHER = "other"
LINE = re.compile(r"^\s*([0-9.]+)%\s+(\S.*?)\s{2,}(\S+)\s+\[(.)\]\s+(.*)$")


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
            pct, comm, dso, _, sym = m.groups()
            samples.append((float(pct), comm.strip(), dso, sym.strip()))
    return samples


def median(v):
    v = sorted(v)
    n = len(v)
    return None if n == 0 else (v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2)


def frame_figures(run_dir):
    try:
        rows = json.loads((run_dir / "results.json").read_text())["rows"]
    except (OSError, KeyError, ValueError):
        return None
    rows = [r for r in rows if not r.get("error")]
    if not rows:
        return None
    r = rows[0]
    stages = dict(kv.split("=", 1) for kv in r.get("stages", "").split(";") if "=" in kv)
    return {
        "settings": r.get("settings"),
        "tets": r.get("tets"),
        "total_ms": r.get("total_ms"),
        "cpu_ms": r.get("cpu_ms"),
        "wait_ms": float(stages["wait"]) if "wait" in stages else None,
        "frames": r.get("frames"),
        "harness_ms": r.get("harness_ms"),
    }


def fmt(v, digits=1):
    return "–" if v is None else f"{v:.{digits}f}"


def main():
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "out/profile")
    reports = sorted(out.glob("*.report.txt"))
    if not reports:
        sys.exit(f"profile_summary.py: no *.report.txt in {out}")
    lines = ["# Profiles (scripts/profile.sh)", "",
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
        f = frame_figures(out / f"{name}.run") or {}
        lines += [f"## {algorithm} on {dataset} at {resolution}²", ""]
        lines.append(
            f"settings `{f.get('settings')}`, {f.get('tets')} tets: frame {fmt(f.get('total_ms'))} ms "
            f"(host CPU {fmt(f.get('cpu_ms'))} ms, waiting for the GPU {fmt(f.get('wait_ms'))} ms); "
            f"harness outside the frames {fmt(f.get('harness_ms'))} ms for the row's "
            f"{f.get('frames')} frames")
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
