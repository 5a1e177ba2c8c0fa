"""tetbench's VTK peer: renders a .vtu with one of VTK's unstructured-grid volume mappers,
offscreen, driven by tetbench over stdin/stdout (one JSON object per line each way).

Requests (each answered by one line, {"ok": true, ...} or {"ok": false, "error": "..."}):
  setup   mesh, mapper (pt | raycast | zsweep), integrator, size, transfer function points
  render  one frame with the given camera; answers the wall ms of that frame
  image   re-renders the exact camera and writes the image (f32 RGBA, premultiplied, linear,
          row 0 at the top) to a file: from the framebuffer, or (ray caster only) from VTK's
          own traversal and integrator per pixel, before VTK's 8-bit image and its display
  quit

stdout carries only the protocol; VTK's own messages go to stderr.
"""

import json
import sys
import time

PROTOCOL_OUT = sys.stdout
# Anything a library prints must not corrupt the protocol.
sys.stdout = sys.stderr


def reply(obj):
    PROTOCOL_OUT.write(json.dumps(obj) + "\n")
    PROTOCOL_OUT.flush()


try:
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (registers the OpenGL factories)
    import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401
    from vtkmodules.vtkCommonCore import (
        vtkDoubleArray, vtkLogger, vtkObject, vtkUnsignedCharArray, vtkVersion)
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    from vtkmodules.vtkRenderingCore import (
        vtkColorTransferFunction,
        vtkRenderer,
        vtkRenderWindow,
        vtkVolume,
        vtkVolumeProperty,
    )
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingVolume import (
        vtkProjectedTetrahedraMapper,
        vtkUnstructuredGridLinearRayIntegrator,
        vtkUnstructuredGridPartialPreIntegration,
        vtkUnstructuredGridPreIntegration,
        vtkUnstructuredGridVolumeRayCastMapper,
        vtkUnstructuredGridVolumeZSweepMapper,
    )
except Exception as e:  # noqa: BLE001  (any import failure means: no usable VTK)
    reply({"ok": False, "error": f"cannot import VTK in {sys.executable}: {e}"})
    sys.exit(1)

vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)

INTEGRATORS = {
    "linear": vtkUnstructuredGridLinearRayIntegrator,
    "partial-preintegration": vtkUnstructuredGridPartialPreIntegration,
    "preintegration": vtkUnstructuredGridPreIntegration,
}


class Peer:
    def __init__(self):
        self.window = None

    def setup(self, req):
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(req["vtu"])
        reader.Update()
        grid = reader.GetOutput()
        if grid.GetNumberOfCells() == 0:
            raise RuntimeError(f"VTK read no cells from {req['vtu']}")
        scalars = grid.GetPointData().GetScalars()
        if scalars is None:
            raise RuntimeError(f"{req['vtu']} has no point scalars")
        self.grid, self.scalars = grid, scalars

        colour = vtkColorTransferFunction()
        # tetbench interpolates colour linearly in RGB (exact integration needs it).
        colour.SetColorSpaceToRGB()
        colour.ClampingOn()
        opacity = vtkPiecewiseFunction()
        opacity.ClampingOn()
        for x, r, g, b, o in req["points"]:
            colour.AddRGBPoint(x, r, g, b)
            opacity.AddPoint(x, o)
        prop = vtkVolumeProperty()
        prop.SetColor(colour)
        prop.SetScalarOpacity(opacity)
        prop.SetScalarOpacityUnitDistance(req["unit_distance"])
        prop.SetInterpolationTypeToLinear()
        prop.ShadeOff()

        kind = req["mapper"]
        if kind == "pt":
            mapper = vtkProjectedTetrahedraMapper()
        elif kind == "zsweep":
            mapper = vtkUnstructuredGridVolumeZSweepMapper()
            mapper.SetRayIntegrator(INTEGRATORS[req.get("integrator") or "linear"]())
        elif kind == "raycast":
            mapper = vtkUnstructuredGridVolumeRayCastMapper()
            mapper.SetRayIntegrator(INTEGRATORS[req["integrator"]]())
            # One ray per pixel, always (VTK would otherwise coarsen to meet a frame rate).
            mapper.AutoAdjustSampleDistancesOff()
            mapper.SetImageSampleDistance(1.0)
        else:
            raise RuntimeError(f"unknown mapper {kind!r}")
        mapper.SetInputData(grid)
        self.mapper, self.kind = mapper, kind

        volume = vtkVolume()
        volume.SetMapper(mapper)
        volume.SetProperty(prop)
        self.volume = volume

        renderer = vtkRenderer()
        renderer.SetBackground(0.0, 0.0, 0.0)
        renderer.SetBackgroundAlpha(0.0)
        renderer.AddVolume(volume)
        window = vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetAlphaBitPlanes(1)
        window.SetMultiSamples(0)
        window.AddRenderer(renderer)
        window.SetSize(req["width"], req["height"])
        self.renderer, self.window = renderer, window
        self.width, self.height = req["width"], req["height"]
        window.Render()
        caps = window.ReportCapabilities() or ""
        gl = next((line.split(":", 1)[1].strip() for line in caps.splitlines()
                   if line.startswith("OpenGL renderer string")), "")
        return {
            "cells": grid.GetNumberOfCells(),
            "points": grid.GetNumberOfPoints(),
            "vtk_version": vtkVersion.GetVTKVersion(),
            "window": window.GetClassName(),
            "gl_renderer": gl,
        }

    def set_camera(self, req, nudge_deg=0.0):
        cam = self.renderer.GetActiveCamera()
        cam.SetPosition(*req["eye"])
        cam.SetFocalPoint(*req["focal"])
        cam.SetViewUp(*req["up"])
        if req.get("parallel_scale") is not None:
            cam.ParallelProjectionOn()
            cam.SetParallelScale(req["parallel_scale"])
        else:
            cam.ParallelProjectionOff()
            cam.SetViewAngle(req["view_angle"])
        cam.SetWindowCenter(*req["window_center"])
        if nudge_deg:
            cam.Azimuth(nudge_deg)
            cam.OrthogonalizeViewUp()
        cam.SetClippingRange(req["near"], req["far"])

    def draw(self):
        t0 = time.perf_counter()
        self.window.Render()
        self.window.WaitForCompletion()
        return (time.perf_counter() - t0) * 1e3

    def resize(self, size):
        w, h = int(size[0]), int(size[1])
        if (w, h) != (self.width, self.height):
            self.window.SetSize(w, h)
            self.width, self.height = w, h

    def render(self, req):
        self.resize(req["size"])
        self.set_camera(req["camera"], req.get("nudge_deg", 0.0))
        return {"ms": self.draw()}

    def framebuffer(self):
        w, h = self.width, self.height
        data = vtkUnsignedCharArray()
        self.window.GetRGBACharPixelData(0, 0, w - 1, h - 1, 0, data)
        rgba = vtk_to_numpy(data).reshape(h, w, 4)[::-1].astype(np.float32) / 255.0
        return rgba

    def rays(self, early_termination):
        """VTK's per-pixel loop (vtkUnstructuredGridVolumeRayCastMapper::CastRays) without its
        8-bit store: the same iterator and integrator, colour kept in float."""
        if self.window is None:
            raise RuntimeError("image before setup")
        if self.kind != "raycast":
            raise RuntimeError("readout=rays needs the ray cast mapper")
        func = self.mapper.GetRayCastFunction()
        integrator = self.mapper.GetRayIntegrator()
        func.Initialize(self.renderer, self.volume)
        integrator.Initialize(self.volume, self.scalars)
        it = func.NewIterator()
        lengths = vtkDoubleArray()
        near = self.scalars.NewInstance()
        far = self.scalars.NewInstance()
        w, h = self.width, self.height
        out = np.zeros((h, w, 4), dtype=np.float32)
        for j in range(h):
            for i in range(w):
                it.SetBounds(0.0, 1.0)
                it.Initialize(i, j)
                color = [0.0, 0.0, 0.0, 0.0]
                while True:
                    n = it.GetNextIntersections(None, lengths, self.scalars, near, far)
                    if n < 1:
                        break
                    integrator.Integrate(lengths, near, far, color)
                    if early_termination and color[3] >= 0.99:
                        break
                out[h - 1 - j, i] = color
        func.Finalize()
        return out

    def image(self, req):
        self.resize(req["size"])
        self.set_camera(req["camera"])
        self.draw()
        t0 = time.perf_counter()
        if req["readout"] == "rays":
            img = self.rays(req.get("early_termination", True))
        else:
            img = self.framebuffer()
        np.ascontiguousarray(img, dtype="<f4").tofile(req["path"])
        return {"ms": (time.perf_counter() - t0) * 1e3}


def main():
    vtkObject.GlobalWarningDisplayOn()
    peer = Peer()
    reply({"ok": True, "vtk_version": vtkVersion.GetVTKVersion(), "python": sys.version.split()[0]})
    for line in sys.stdin:
        line = line.strip()
        if not line:
            continue
        try:
            req = json.loads(line)
            cmd = req.get("cmd")
            if cmd == "quit":
                reply({"ok": True})
                break
            handler = {"setup": peer.setup, "render": peer.render, "image": peer.image}.get(cmd)
            if handler is None:
                raise RuntimeError(f"unknown request {cmd!r}")
            answer = handler(req)
            answer["ok"] = True
            reply(answer)
        except Exception as e:  # noqa: BLE001  (reported to tetbench, which fails the row)
            reply({"ok": False, "error": f"{type(e).__name__}: {e}"})


if __name__ == "__main__":
    main()
