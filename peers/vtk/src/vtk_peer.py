"""tetbench's VTK peer: renders a .vtu with one of VTK's unstructured-grid volume mappers,
offscreen, as an external renderer speaking tetbench's protocol version 1
(docs/external-renderers.md): one JSON object per line on stdin, one reply line on stdout.

Settings (hello): mapper (pt | raycast | zsweep), integrator (linear | partial-preintegration |
preintegration), readout (framebuffer | rays: the ray caster's own per-pixel integration in
float, before VTK's 8-bit image and its display), et (on | off: early ray termination of the
rays readout).

How tetbench's scene maps onto VTK's (the conventions the outside check needed):
* Extinction: tetbench's kappa(s) is per unit of the bounding-box diagonal (optics.length_unit);
  VTK attenuates by opacity / ScalarOpacityUnitDistance per world unit. With K = max kappa,
  opacity = kappa / K and unit distance = length_unit / K attenuate alike, opacities in [0, 1].
* Control points: VTK's linear and partial pre-integration integrators split a segment only at
  the opacity function's points, so colour and opacity use the protocol's shared points
  (optics.points), each carrying both values; between them both functions are linear.
* Colour: RGB interpolation over the raw scalar x = scalar_min + s (scalar_max - scalar_min).
* Camera: same eye, focal point, up, vertical view angle (or parallel scale) and clipping range.
  VTK's ray caster samples pixel X at NDC 2X/W - 1, half a pixel off the protocol's pixel
  centres; for readout=rays a window centre of (1/W, 1/H) moves its rays onto the centres; for
  the displayed image, display_alignment also undoes the display's (W - 1)/W scaling.
* The framebuffer readouts of the ray caster and ZSweep declare their accuracy in the hello
  (FRAMEBUFFER_ACCURACY): their display filter and ZSweep's vertex snapping are VTK's.
* Every timed frame is a full re-render: the camera turns about the up axis by +-NUDGE_DEG on
  alternate frames so no mapper reuses a sort (counter camera_nudge_deg); read_image renders
  once more at the exact camera.

stdout carries only the protocol; VTK's own messages go to stderr.
"""

import json
import os
import sys
import time

PROTOCOL_OUT = sys.stdout
# Anything a library prints must not corrupt the protocol.
sys.stdout = sys.stderr
# Offscreen through EGL (Mesa's llvmpipe without a GPU): no X display needed.
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

NUDGE_DEG = 0.01


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
    from vtkmodules.vtkCommonTransforms import vtkTransform
    from vtkmodules.vtkRenderingVolume import (
        vtkProjectedTetrahedraMapper,
        vtkUnstructuredGridLinearRayIntegrator,
        vtkUnstructuredGridPartialPreIntegration,
        vtkUnstructuredGridPreIntegration,
        vtkUnstructuredGridVolumeRayCastMapper,
        vtkUnstructuredGridVolumeZSweepMapper,
    )
except Exception as e:  # noqa: BLE001  (any import failure means: no usable VTK)
    print(f"cannot import VTK in {sys.executable}: {e}", file=sys.stderr)
    # Answer the hello with the reason, so tetbench can say it.
    sys.stdin.readline()
    reply({"type": "error", "message": f"cannot import VTK in {sys.executable}: {e}"})
    sys.exit(1)

vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)

INTEGRATORS = {
    "linear": vtkUnstructuredGridLinearRayIntegrator,
    "partial-preintegration": vtkUnstructuredGridPartialPreIntegration,
    "preintegration": vtkUnstructuredGridPreIntegration,
}
DEFAULTS = {"mapper": "raycast", "integrator": "linear", "readout": "framebuffer", "et": "on"}
CHOICES = {"mapper": ["pt", "raycast", "zsweep"], "integrator": list(INTEGRATORS),
           "readout": ["framebuffer", "rays"], "et": ["on", "off"]}


def display_alignment(w, h):
    """A clip-space transform for the ray caster's displayed image. VTK casts ray i through
    NDC 2i/W - 1 (a pixel corner), stores the W x H image as a texture and draws it with its
    first and last texel centres on the viewport's edges, so display pixel x shows the image
    at (x + 1/2)(W - 1)/W. Shrinking NDC by (W - 1)/W and moving it by -1/W puts ray i at
    i W/(W - 1), where the display shows it: each pixel centre then falls between the rays
    around it (the texture's bilinear filter still blends a silhouette pixel with its
    neighbour). Applied last, in clip space (vtkCamera's UserTransform)."""
    m = vtkTransform()
    m.SetMatrix([(w - 1) / w, 0, 0, -1.0 / w,
                 0, (h - 1) / h, 0, -1.0 / h,
                 0, 0, 1, 0,
                 0, 0, 0, 1])
    return m


# What the framebuffer readouts cannot reach, declared in the hello so that the conformance
# check judges them at this accuracy (docs/external-renderers.md, "Declared accuracy").
FRAMEBUFFER_ACCURACY = {
    "raycast": "VTK draws its 8-bit ray-cast image as a bilinearly filtered texture: a "
               "silhouette between pixel centres spreads over the neighbouring pixel",
    "zsweep": "ZSweep snaps every vertex to the pixel grid (integer screen coordinates) and VTK "
              "draws its 8-bit image as a bilinearly filtered texture",
}
FRAMEBUFFER_MIN_PSNR_DB = 28.0


class Peer:
    def __init__(self):
        self.window = None
        self.settings = dict(DEFAULTS)

    def hello(self, req):
        if req.get("protocol") != 1:
            raise RuntimeError(f"this peer speaks protocol 1, not {req.get('protocol')}")
        for key, value in (req.get("settings") or {}).items():
            if key not in CHOICES:
                raise RuntimeError(f"unknown setting {key!r}; known: {', '.join(CHOICES)}")
            if value not in CHOICES[key]:
                raise RuntimeError(f"{key}={value!r}: one of {', '.join(CHOICES[key])}")
            self.settings[key] = value
        if self.settings["readout"] == "rays" and self.settings["mapper"] != "raycast":
            raise RuntimeError("readout=rays needs mapper=raycast")
        reply = {"type": "hello", "protocol": 1, "name": f"vtk-{self.settings['mapper']}",
                 "version": f"VTK {vtkVersion.GetVTKVersion()} on Python {sys.version.split()[0]}",
                 "settings": self.settings,
                 "capabilities": {"projections": ["perspective", "orthographic"],
                                  "mesh_formats": ["vtu"]}}
        reason = FRAMEBUFFER_ACCURACY.get(self.settings["mapper"])
        if reason and self.settings["readout"] == "framebuffer":
            reply["accuracy"] = {"min_psnr_db": FRAMEBUFFER_MIN_PSNR_DB, "reason": reason}
        return reply

    def prepare(self, req):
        vtu = req["mesh"]["vtu"]
        reader = vtkXMLUnstructuredGridReader()
        reader.SetFileName(vtu)
        reader.Update()
        grid = reader.GetOutput()
        if grid.GetNumberOfCells() == 0:
            raise RuntimeError(f"VTK read no cells from {vtu}")
        scalars = grid.GetPointData().GetScalars()
        if scalars is None:
            raise RuntimeError(f"{vtu} has no point scalars")
        self.grid, self.scalars = grid, scalars

        optics = req["optics"]
        points = optics["points"]
        k_max = max(p[4] for p in points)
        k_max = k_max if k_max > 0 else 1.0
        lo, hi = optics["scalar_min"], optics["scalar_max"]
        colour = vtkColorTransferFunction()
        # tetbench interpolates colour linearly in RGB (exact integration needs it).
        colour.SetColorSpaceToRGB()
        colour.ClampingOn()
        opacity = vtkPiecewiseFunction()
        opacity.ClampingOn()
        for s, r, g, b, kappa in points:
            x = lo + s * (hi - lo)
            colour.AddRGBPoint(x, r, g, b)
            opacity.AddPoint(x, kappa / k_max)
        prop = vtkVolumeProperty()
        prop.SetColor(colour)
        prop.SetScalarOpacity(opacity)
        prop.SetScalarOpacityUnitDistance(optics["length_unit"] / k_max)
        prop.SetInterpolationTypeToLinear()
        prop.ShadeOff()

        kind = self.settings["mapper"]
        integrator = INTEGRATORS[self.settings["integrator"]]
        if kind == "pt":
            mapper = vtkProjectedTetrahedraMapper()
        elif kind == "zsweep":
            mapper = vtkUnstructuredGridVolumeZSweepMapper()
            mapper.SetRayIntegrator(integrator())
        else:
            mapper = vtkUnstructuredGridVolumeRayCastMapper()
            mapper.SetRayIntegrator(integrator())
            # One ray per pixel, always (VTK would otherwise coarsen to meet a frame rate).
            mapper.AutoAdjustSampleDistancesOff()
            mapper.SetImageSampleDistance(1.0)
        mapper.SetInputData(grid)
        self.mapper, self.kind = mapper, kind

        volume = vtkVolume()
        volume.SetMapper(mapper)
        volume.SetProperty(prop)
        self.volume = volume

        if self.window is not None:
            self.window.Finalize()
        renderer = vtkRenderer()
        renderer.SetBackground(0.0, 0.0, 0.0)
        renderer.SetBackgroundAlpha(0.0)
        renderer.AddVolume(volume)
        window = vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetAlphaBitPlanes(1)
        window.SetMultiSamples(0)
        window.AddRenderer(renderer)
        window.SetSize(64, 64)
        self.renderer, self.window = renderer, window
        self.width, self.height = 64, 64
        window.Render()
        caps = window.ReportCapabilities() or ""
        gl = next((line.split(":", 1)[1].strip() for line in caps.splitlines()
                   if line.startswith("OpenGL renderer string")), "")
        print(f"vtk peer: {kind} on {window.GetClassName()} ({gl}), "
              f"{grid.GetNumberOfCells()} cells", file=sys.stderr)
        return {"type": "prepared", "tets": grid.GetNumberOfCells(), "persistent_bytes": 0}

    def set_camera(self, cam, nudge_deg=0.0):
        w, h = int(cam["width"]), int(cam["height"])
        if (w, h) != (self.width, self.height):
            self.window.SetSize(w, h)
            self.width, self.height = w, h
        vc = self.renderer.GetActiveCamera()
        vc.SetPosition(*cam["eye"])
        vc.SetFocalPoint(*cam["target"])
        vc.SetViewUp(*cam["up"])
        if cam["projection"] == "orthographic":
            vc.ParallelProjectionOn()
            vc.SetParallelScale(cam["ortho_half_height"])
        else:
            vc.ParallelProjectionOff()
            vc.SetViewAngle(cam["fovy_deg"])
        vc.SetWindowCenter(0.0, 0.0)
        vc.SetUserTransform(None)
        if self.kind == "raycast" and self.settings["readout"] == "rays":
            # The ray caster samples pixel corners; this moves its rays onto the pixel centres.
            vc.SetWindowCenter(1.0 / w, 1.0 / h)
        elif self.kind == "raycast":
            vc.SetUserTransform(display_alignment(w, h))
        if nudge_deg:
            vc.Azimuth(nudge_deg)
            vc.OrthogonalizeViewUp()
        vc.SetClippingRange(cam["near"], cam["far"])

    def draw(self):
        t0 = time.perf_counter()
        self.window.Render()
        self.window.WaitForCompletion()
        return (time.perf_counter() - t0) * 1e3

    def render(self, req):
        if self.window is None:
            raise RuntimeError("render before prepare")
        nudge = NUDGE_DEG if req.get("frame", 0) % 2 == 0 else -NUDGE_DEG
        self.camera = req["camera"]
        self.set_camera(self.camera, nudge)
        return {"type": "rendered", "wall_ms": self.draw(),
                "counters": {"camera_nudge_deg": NUDGE_DEG}}

    def behind_camera(self):
        cam = self.renderer.GetActiveCamera()
        eye = np.array(cam.GetPosition())
        forward = np.array(cam.GetDirectionOfProjection())
        b = self.volume.GetBounds()
        corners = np.array([[b[i], b[2 + j], b[4 + k]] for i in (0, 1) for j in (0, 1)
                            for k in (0, 1)])
        return bool(((corners - eye) @ forward <= 0).all())

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
        w, h = self.width, self.height
        if self.behind_camera():
            # VTK's mapper casts no ray at a volume behind the camera (its image size is empty);
            # its ray functions crash when asked to.
            return np.zeros((h, w, 4), dtype=np.float32)
        func = self.mapper.GetRayCastFunction()
        integrator = self.mapper.GetRayIntegrator()
        func.Initialize(self.renderer, self.volume)
        integrator.Initialize(self.volume, self.scalars)
        it = func.NewIterator()
        lengths = vtkDoubleArray()
        near = self.scalars.NewInstance()
        far = self.scalars.NewInstance()
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

    def read_image(self, req):
        if self.window is None:
            raise RuntimeError("read_image before render")
        self.set_camera(self.camera)
        self.draw()
        if self.settings["readout"] == "rays":
            img = self.rays(self.settings["et"] == "on")
        else:
            img = self.framebuffer()
        np.ascontiguousarray(img, dtype="<f4").tofile(req["path"])
        return {"type": "image"}


def main():
    vtkObject.GlobalWarningDisplayOn()
    peer = Peer()
    handlers = {"hello": peer.hello, "prepare": peer.prepare, "render": peer.render,
                "read_image": peer.read_image}
    for line in sys.stdin:
        line = line.strip()
        if not line:
            continue
        try:
            req = json.loads(line)
            kind = req.get("type")
            if kind == "shutdown":
                reply({"type": "bye"})
                break
            handler = handlers.get(kind)
            if handler is None:
                raise RuntimeError(f"unknown request {kind!r}")
            reply(handler(req))
        except Exception as e:  # noqa: BLE001  (reported to tetbench, which fails the row)
            reply({"type": "error", "message": f"{type(e).__name__}: {e}"})


if __name__ == "__main__":
    main()
