#!/usr/bin/env python3
"""Reads .vtu files with VTK's own reader (vtkXMLUnstructuredGridReader) and checks that each
holds exactly the mesh datasets/examples/vtkio_measure.rs wrote: the same f32 points, the same
tets (all VTK_TETRA, 4 ids each) and the same f32 point scalar, bit for bit.

Usage: python3 scripts/vtk_readback.py OUT_DIR   (after `cargo run --release -p datasets
--example vtkio_measure -- OUT_DIR`; needs the `vtk` and `numpy` packages, e.g. in a venv).
Not used by the test suite.
"""
import sys
from pathlib import Path

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/vtkio")
points = np.fromfile(out / "points.f32", dtype="<f4").reshape(-1, 3)
tets = np.fromfile(out / "tets.u32", dtype="<u4").reshape(-1, 4)
scalars = np.fromfile(out / "scalars.f32", dtype="<f4")
print(f"VTK {vtk.vtkVersion.GetVTKVersion()}; mesh: {len(points)} points, {len(tets)} tets")
ok_all = True
for name in ["ours.vtu", "ours-base64.vtu", "vtkio.vtu"]:
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(str(out / name))
    r.Update()
    g = r.GetOutput()
    p = vtk_to_numpy(g.GetPoints().GetData())
    conn = vtk_to_numpy(g.GetCells().GetConnectivityArray())
    offs = vtk_to_numpy(g.GetCells().GetOffsetsArray())
    types = vtk_to_numpy(g.GetCellTypes())
    arr = g.GetPointData().GetArray(0)
    s = vtk_to_numpy(arr)
    checks = {
        "points": p.dtype == np.float32 and np.array_equal(p, points),
        "tets": np.array_equal(offs, np.arange(0, 4 * len(tets) + 1, 4))
        and np.array_equal(conn.reshape(-1, 4), tets),
        "types": bool(np.all(types == vtk.VTK_TETRA)) and len(types) == len(tets),
        "scalars": s.dtype == np.float32 and np.array_equal(s, scalars),
    }
    ok = all(checks.values())
    ok_all &= ok
    print(f"{name}: {'identical' if ok else 'DIFFERENT'} {checks} (array {arr.GetName()!r}, {p.dtype}/{s.dtype})")
sys.exit(0 if ok_all else 1)
