#!/usr/bin/env bash
# Installs what the VTK peers need (see ensure_vtk_python in scripts/common.sh): Python's vtk
# package into .venv-vtk/ and Mesa's EGL for offscreen rendering. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/common.sh
ensure_vtk_python
ensure_numpy_python
"$TETBENCH_VTK_PYTHON" -c 'import vtk; print("VTK", vtk.vtkVersion.GetVTKVersion(), "in", __import__("sys").prefix)'
