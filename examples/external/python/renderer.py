#!/usr/bin/env python3
"""An external renderer for tetbench in Python with numpy (protocol version 1,
docs/external-renderers.md): a CPU ray caster with exact ray-cell intersection.

For every tet, the pixels whose centres its projection can cover are taken from its screen
bounding box; each such pixel ray is clipped against the tet's four face planes (barycentric
coordinates are linear along a ray, so the segment inside the tet is where all four stay
>= 0), which gives the exact segment and the scalar at both of its ends. Each segment is
integrated with a few midpoint sub-steps of the emission-absorption model (colour and
extinction constant per sub-step, setting `substeps`), then the segments are sorted per pixel
and composited front to back, all as whole-array numpy operations: the transmittance in front
of a segment is exp(-(the optical depth of the segments before it in its pixel)), a cumulative
sum per pixel.

The mesh comes as raw arrays (capabilities.mesh_formats = ["raw"]). Flags that break a
convention on purpose, to see the conformance check name it: --flip-rows (row 0 at the
bottom), --straight-alpha (colour not premultiplied), --mirror (left-handed camera);
--declare-accuracy declares 20 dB in the hello, the lowest accuracy the protocol allows.

    tetbench external check "python3 examples/external/python/renderer.py"
"""

import json
import math
import sys
import time

import numpy as np

PROTOCOL_OUT = sys.stdout
sys.stdout = sys.stderr  # stdout carries the protocol only
FLAGS = set(sys.argv[1:])
PAIRS_PER_CHUNK = 1 << 21  # (tet, pixel) pairs handled at once: bounds the memory


def reply(obj):
    PROTOCOL_OUT.write(json.dumps(obj) + "\n")
    PROTOCOL_OUT.flush()


def normalise(v):
    return v / np.linalg.norm(v)


class Renderer:
    def __init__(self):
        self.settings = {"substeps": "4"}
        self.image = None

    def hello(self, req):
        for key, value in req.get("settings", {}).items():
            if key not in self.settings:
                raise ValueError(f"unknown setting {key!r} (known: substeps)")
            if not value.isdigit() or int(value) < 1:
                raise ValueError(f"substeps={value!r}: a whole number >= 1")
            self.settings[key] = value
        self.substeps = int(self.settings["substeps"])
        hello = {"type": "hello", "protocol": 1, "name": "numpy ray-cell caster", "version": "1",
                 "settings": self.settings,
                 "capabilities": {"projections": ["perspective", "orthographic"],
                                  "mesh_formats": ["raw"]}}
        if "--declare-accuracy" in FLAGS:
            # The most lenient declaration the protocol allows: the check must still name a
            # broken convention under it.
            hello["accuracy"] = {"min_psnr_db": 20, "reason": "--declare-accuracy (a test)"}
        return hello

    def prepare(self, req):
        mesh, optics = req["mesh"], req["optics"]
        raw = mesh["raw"]
        pts = np.fromfile(raw["points"], dtype="<f4").astype(np.float64).reshape(-1, 3)
        tets = np.fromfile(raw["tets"], dtype="<u4").astype(np.int64).reshape(-1, 4)
        values = np.fromfile(raw["scalars"], dtype="<f4").astype(np.float64)
        if len(pts) != mesh["points"] or len(tets) != mesh["tets"] or len(values) != len(pts):
            raise ValueError("the raw mesh files do not have the announced sizes")
        lo, hi = optics["scalar_min"], optics["scalar_max"]
        s = np.clip((values - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.zeros_like(values)
        v = pts[tets]  # (tets, 4, 3)
        edges = np.stack([v[:, 1] - v[:, 0], v[:, 2] - v[:, 0], v[:, 3] - v[:, 0]], axis=2)
        # Barycentric coordinates 1..3 of p: inv @ (p - v0); coordinate 0 is 1 - their sum.
        self.inv = np.linalg.inv(edges)
        self.v0 = v[:, 0]
        self.s = s[tets]  # normalised scalar at each tet's vertices
        self.verts = v
        tf = np.array(optics["points"], dtype=np.float64)  # [s, r, g, b, kappa]: linear between
        self.tf_s, self.tf_rgb = tf[:, 0], tf[:, 1:4]
        # Extinction per world unit: kappa is per unit of the bounding-box diagonal.
        self.tf_tau = tf[:, 4] / optics["length_unit"]
        return {"type": "prepared", "tets": len(tets),
                "persistent_bytes": int(self.inv.nbytes + self.v0.nbytes + self.s.nbytes)}

    def rays(self, cam):
        """Ray origins and directions of every pixel centre, row 0 at the top."""
        w, h = cam["width"], cam["height"]
        eye, target = np.array(cam["eye"]), np.array(cam["target"])
        f = normalise(target - eye)
        r = normalise(np.cross(f, np.array(cam["up"])))
        u = np.cross(r, f)
        if "--mirror" in FLAGS:
            r = -r  # a left-handed camera: right = up x forward
        ndc_x = 2.0 * (np.arange(w) + 0.5) / w - 1.0
        ndc_y = 1.0 - 2.0 * (np.arange(h) + 0.5) / h
        nx, ny = np.meshgrid(ndc_x, ndc_y)  # (h, w)
        aspect = w / h
        if cam["projection"] == "perspective":
            t = math.tan(math.radians(cam["fovy_deg"]) / 2.0)
            d = f + (nx * t * aspect)[..., None] * r + (ny * t)[..., None] * u
            d /= np.linalg.norm(d, axis=2, keepdims=True)
            o = np.broadcast_to(eye, d.shape)
        else:
            hh = cam["ortho_half_height"]
            o = eye + (nx * hh * aspect)[..., None] * r + (ny * hh)[..., None] * u
            d = np.broadcast_to(f, o.shape)
        return o.reshape(-1, 3), d.reshape(-1, 3), (eye, f, r, u)

    def screen_boxes(self, cam, basis):
        """Per tet, the range of pixels whose centres its projection may cover."""
        w, h = cam["width"], cam["height"]
        eye, f, r, u = basis
        rel = self.verts - eye
        z, x, y = rel @ f, rel @ r, rel @ u
        if cam["projection"] == "perspective":
            t = math.tan(math.radians(cam["fovy_deg"]) / 2.0)
            front = z > 1e-9 * np.abs(rel).max()
            zs = np.where(front, z, 1.0)
            px = (x / (zs * t * w / h) + 1.0) * 0.5 * w
            py = (1.0 - y / (zs * t)) * 0.5 * h
            any_front, all_front = front.any(axis=1), front.all(axis=1)
        else:
            hh = cam["ortho_half_height"]
            px = (x / (hh * w / h) + 1.0) * 0.5 * w
            py = (1.0 - y / hh) * 0.5 * h
            any_front = all_front = np.ones(len(rel), dtype=bool)
        x0 = np.ceil(px.min(axis=1) - 0.5)
        x1 = np.floor(px.max(axis=1) - 0.5)
        y0 = np.ceil(py.min(axis=1) - 0.5)
        y1 = np.floor(py.max(axis=1) - 0.5)
        # A tet crossing the eye plane projects without bounds: try every pixel.
        part = any_front & ~all_front
        x0, y0 = np.where(part, 0, x0), np.where(part, 0, y0)
        x1, y1 = np.where(part, w - 1, x1), np.where(part, h - 1, y1)
        x0, x1 = np.clip(x0, 0, w).astype(np.int64), np.clip(x1, -1, w - 1).astype(np.int64)
        y0, y1 = np.clip(y0, 0, h).astype(np.int64), np.clip(y1, -1, h - 1).astype(np.int64)
        nx, ny = np.maximum(x1 - x0 + 1, 0), np.maximum(y1 - y0 + 1, 0)
        return x0, y0, nx, np.where(any_front, nx * ny, 0)

    def segments(self, tet, pix, o, d):
        """Clips each pair's ray to its tet: (pixel, t_in, optical depth, premultiplied rgb)."""
        a123 = np.einsum("nij,nj->ni", self.inv[tet], o[pix] - self.v0[tet])
        b123 = np.einsum("nij,nj->ni", self.inv[tet], d[pix])
        a = np.concatenate([1.0 - a123.sum(axis=1, keepdims=True), a123], axis=1)
        b = np.concatenate([-b123.sum(axis=1, keepdims=True), b123], axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            root = -a / b
        t_in = np.where(b > 0, root, -np.inf).max(axis=1)
        t_out = np.where(b < 0, root, np.inf).min(axis=1)
        parallel_outside = ((b == 0) & (a < 0)).any(axis=1)
        keep = (t_out > t_in) & ~parallel_outside & np.isfinite(t_in) & np.isfinite(t_out)
        tet, pix, a, b = tet[keep], pix[keep], a[keep], b[keep]
        t_in, t_out = t_in[keep], t_out[keep]
        sv = self.s[tet]
        s_in = ((a + t_in[:, None] * b) * sv).sum(axis=1)
        s_out = ((a + t_out[:, None] * b) * sv).sum(axis=1)
        n = self.substeps
        step = (t_out - t_in) / n
        rgb = np.zeros((len(tet), 3))
        depth = np.zeros(len(tet))
        for j in range(n):
            sj = s_in + (j + 0.5) / n * (s_out - s_in)
            tau = np.interp(sj, self.tf_s, self.tf_tau) * step
            colour = np.stack([np.interp(sj, self.tf_s, self.tf_rgb[:, c]) for c in range(3)], 1)
            rgb += (np.exp(-depth) * -np.expm1(-tau))[:, None] * colour
            depth += tau
        return pix, t_in, depth, rgb

    def render(self, req):
        t0, c0 = time.perf_counter(), time.process_time()
        cam = req["camera"]
        w, h = cam["width"], cam["height"]
        o, d, basis = self.rays(cam)
        x0, y0, nx, counts = self.screen_boxes(cam, basis)
        parts = []
        order = np.nonzero(counts)[0]
        ends = np.cumsum(counts[order])
        start = 0
        while start < len(order):
            stop = max(start + 1, int(np.searchsorted(ends, ends[start] + PAIRS_PER_CHUNK)))
            idx = order[start:stop]
            c = counts[idx]
            tet = np.repeat(idx, c)
            k = np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c)
            wx = nx[tet]
            pix = (y0[tet] + k // wx) * w + x0[tet] + k % wx
            parts.append(self.segments(tet, pix, o, d))
            start = stop
        image = np.zeros((w * h, 4))
        total = 0
        if parts:
            pix, t_in, depth, rgb = (np.concatenate(p) for p in zip(*parts))
            total = len(pix)
            by = np.lexsort((t_in, pix))
            pix, depth, rgb = pix[by], depth[by], rgb[by]
            # Optical depth in front of each segment within its pixel.
            run = np.cumsum(depth)
            first = np.r_[True, pix[1:] != pix[:-1]]
            base = np.maximum.accumulate(np.where(first, run - depth, 0.0))
            front = run - depth - base
            weight = np.exp(-front)
            for ch in range(3):
                image[:, ch] = np.bincount(pix, weights=weight * rgb[:, ch], minlength=w * h)
            image[:, 3] = -np.expm1(-np.bincount(pix, weights=depth, minlength=w * h))
        self.image = image.reshape(h, w, 4).astype(np.float32)
        # One reading of each clock: CPU time summed over numpy's threads may exceed the wall
        # time, and two wall readings apart let a loaded machine make cpu_ms > wall_ms.
        wall_ms = (time.perf_counter() - t0) * 1e3
        cpu_ms = min((time.process_time() - c0) * 1e3, wall_ms)
        return {"type": "rendered", "wall_ms": wall_ms, "cpu_ms": cpu_ms,
                "counters": {"segments": total}}

    def read_image(self, req):
        if self.image is None:
            raise RuntimeError("read_image before render")
        img = self.image.copy()
        if "--flip-rows" in FLAGS:
            img = img[::-1]
        if "--straight-alpha" in FLAGS:
            a = img[..., 3:4]
            img[..., :3] = np.where(a > 1e-6, img[..., :3] / np.maximum(a, 1e-6), img[..., :3])
        np.ascontiguousarray(img, dtype="<f4").tofile(req["path"])
        return {"type": "image"}


def main():
    renderer = Renderer()
    handlers = {"hello": renderer.hello, "prepare": renderer.prepare,
                "render": renderer.render, "read_image": renderer.read_image}
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            req = json.loads(line)
            if req.get("type") == "shutdown":
                reply({"type": "bye"})
                return
            handler = handlers.get(req.get("type"))
            if handler is None:
                raise ValueError(f"unknown request type {req.get('type')!r}")
            reply(handler(req))
        except Exception as e:  # noqa: BLE001  (tetbench fails the row with the message)
            reply({"type": "error", "message": f"{type(e).__name__}: {e}"})


if __name__ == "__main__":
    main()
