"""Pictures like the paper's Figures 8-10, made by keymesh and rendered
off-screen with VTK (vtkRenderWindow, SetOffScreenRendering(1)) into
docs/results/*.png. Called by bench/run.py; prints one JSON line (a list of
rows, one per picture, or a "skipped" row with the reason).

  fig8   the large dataset after `keymesh pipeline --coarsen --curvature
         --subdivide 1`, coloured by mean curvature (red high, blue low)
  fig9   a coarse sphere contour and its Bezier (PN triangle) subdivision
  fig10  a dual mesh (blue skeleton, drawn 2 % outward so that the surface
         does not hide its chords) over its contour (green), Spherical
         Distance field 24^3

Debian's VTK renders through X: with no DISPLAY, Xvfb (package xvfb) is
started for the rendering when it is installed; otherwise the pictures are
skipped with that reason.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import datasets  # noqa: E402


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def report(cmd, path):
    run(cmd + ["--report", path])
    return json.load(open(path))


def start_display():
    """Returns (process or None, reason or None)."""
    if os.environ.get("DISPLAY"):
        return None, None
    xvfb = shutil.which("Xvfb")
    if not xvfb:
        return None, "no DISPLAY and no Xvfb (Debian's VTK 9.1 renders through X; install xvfb)"
    for n in range(91, 99):
        if os.path.exists(f"/tmp/.X11-unix/X{n}") or os.path.exists(f"/tmp/.X{n}-lock"):
            continue
        p = subprocess.Popen([xvfb, f":{n}", "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(50):
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):
                os.environ["DISPLAY"] = f":{n}"
                return p, None
            time.sleep(0.1)
        p.terminate()
    return None, "Xvfb did not start"


def render(actors, path, size=(640, 480), view=None, bar=None):
    import vtk
    rw = vtk.vtkRenderWindow()
    rw.SetOffScreenRendering(1)
    rw.SetSize(*size)
    ports = actors if isinstance(actors[0], list) else [actors]
    for i, group in enumerate(ports):
        ren = vtk.vtkRenderer()
        ren.SetViewport(i / len(ports), 0, (i + 1) / len(ports), 1)
        ren.SetBackground(1, 1, 1)
        for a in group:
            ren.AddActor(a)
        if bar is not None and i == len(ports) - 1:
            ren.AddActor2D(bar)
        ren.ResetCamera()
        cam = ren.GetActiveCamera()
        if view:
            view(cam)
            ren.ResetCamera()
        cam.Zoom(1.3)
        rw.AddRenderer(ren)
    rw.Render()
    w2i = vtk.vtkWindowToImageFilter()
    w2i.SetInput(rw)
    w2i.Update()
    png = vtk.vtkPNGWriter()
    png.SetFileName(path)
    png.SetCompressionLevel(9)
    png.SetInputConnection(w2i.GetOutputPort())
    png.Write()
    rw.Finalize()
    try:  # a palette PNG: a third of the size, pictures stay under 200 KB
        from PIL import Image
        Image.open(path).convert("RGB").quantize(colors=192, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    except ImportError:
        pass


def read(path):
    import vtk
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def surface_actor(poly, color=(0.85, 0.85, 0.85), field=None, lut_range=None, edges=False):
    import vtk
    m = vtk.vtkPolyDataMapper()
    m.SetInputData(poly)
    a = vtk.vtkActor()
    a.SetMapper(m)
    if field:
        poly.GetPointData().SetActiveScalars(field)
        m.SetScalarModeToUsePointFieldData()
        m.SelectColorArray(field)
        m.ScalarVisibilityOn()
        lut = vtk.vtkLookupTable()
        lut.SetHueRange(0.667, 0.0)  # blue (low) to red (high)
        lut.Build()
        m.SetLookupTable(lut)
        m.SetScalarRange(*lut_range)
        m.UseLookupTableScalarRangeOff()
    else:
        m.ScalarVisibilityOff()
        a.GetProperty().SetColor(*color)
    if edges:
        a.GetProperty().EdgeVisibilityOn()
        a.GetProperty().SetEdgeColor(0.2, 0.2, 0.2)
    return a


def wire_actor(poly, color, width=2.0):
    import vtk
    m = vtk.vtkPolyDataMapper()
    m.SetInputData(poly)
    m.ScalarVisibilityOff()
    a = vtk.vtkActor()
    a.SetMapper(m)
    a.GetProperty().SetRepresentationToWireframe()
    a.GetProperty().SetColor(*color)
    a.GetProperty().SetLineWidth(width)
    a.GetProperty().LightingOff()
    return a


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--keymesh", required=True)
    ap.add_argument("--work", required=True, help="folder holding the datasets built by datasets.py")
    ap.add_argument("--big", default="big432", help="the dataset of Figure 8")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    km = a.keymesh
    os.makedirs(a.out, exist_ok=True)
    xvfb, reason = start_display()
    if reason:
        print(json.dumps([{"bench": "skipped", "tool": "figures", "reason": reason}]))
        return
    rows = []
    try:
        import numpy as np
        import vtk
        from vtk.util import numpy_support as ns
        w = a.work
        # Figure 8: the large dataset, coarsened, curvature, one subdivision
        d = datasets.build(a.big, km, w)
        fig8 = os.path.join(w, "fig8.vtp")
        r = report([km, "pipeline", d["nrrd"], "-o", fig8, "--iso", str(d["iso"]), "--coarsen", "--curvature",
                    "--subdivide", "1", "--normals", "average", "-q"], os.path.join(w, "fig8.json"))
        poly = read(fig8)
        k = ns.vtk_to_numpy(poly.GetPointData().GetArray("mean_curvature"))
        lo, hi = np.percentile(k[np.isfinite(k)], [5, 95])
        lim = max(abs(lo), abs(hi))
        bar = vtk.vtkScalarBarActor()
        bar.SetTitle("mean curvature")
        bar.SetNumberOfLabels(3)
        bar.GetTitleTextProperty().SetColor(0, 0, 0)
        bar.GetLabelTextProperty().SetColor(0, 0, 0)
        bar.SetWidth(0.08)
        bar.SetHeight(0.5)
        act = surface_actor(poly, field="mean_curvature", lut_range=(-lim, lim))
        bar.SetLookupTable(act.GetMapper().GetLookupTable())
        path = os.path.join(a.out, "fig8-curvature.png")
        render([act], path, (640, 540), view=lambda c: (c.Azimuth(-60), c.Elevation(20)), bar=bar)
        rows.append({"bench": "figure", "figure": 8, "png": os.path.relpath(path, os.path.dirname(HERE)),
                     "dataset": a.big, "iso": d["iso"], "points": poly.GetNumberOfPoints(),
                     "cells": poly.GetNumberOfCells(), "curvature_range_shown": [-lim, lim],
                     "command": f"keymesh pipeline {a.big}.nrrd --iso {d['iso']} --coarsen --curvature "
                                "--subdivide 1 --normals average", "keymesh_report": r})
        # Figure 9: Bezier subdivision of a coarse sphere contour (left: input, right: 2 levels)
        s = os.path.join(w, "sphere12.vti")
        run([km, "generate", "sphere", "--size", "12", "-o", s, "-q"])
        coarse, fine = os.path.join(w, "fig9-coarse.vtp"), os.path.join(w, "fig9-bezier.vtp")
        run([km, "contour", s, "-o", coarse, "--iso", "4.3", "--normals", "average", "-q"])
        run([km, "subdivide", coarse, "-o", fine, "--levels", "2", "--scheme", "bezier", "-q"])
        pc, pf = read(coarse), read(fine)
        path = os.path.join(a.out, "fig9-bezier.png")
        render([[surface_actor(pc, (0.55, 0.75, 0.95), edges=True)], [surface_actor(pf, (0.55, 0.75, 0.95))]],
               path, (640, 320), view=lambda c: (c.Azimuth(30), c.Elevation(25)))
        rows.append({"bench": "figure", "figure": 9, "png": os.path.relpath(path, os.path.dirname(HERE)),
                     "dataset": "sphere12", "iso": 4.3, "input_cells": pc.GetNumberOfCells(),
                     "cells": pf.GetNumberOfCells(),
                     "command": "keymesh contour sphere12.vti --iso 4.3 --normals average; "
                                "keymesh subdivide --levels 2 --scheme bezier"})
        # Figure 10: dual (blue skeleton) over its contour (green), sphere 24^3
        s = os.path.join(w, "sphere24.vti")
        run([km, "generate", "sphere", "--size", "24", "-o", s, "-q"])
        cont, dual = os.path.join(w, "fig10-contour.vtp"), os.path.join(w, "fig10-dual.vtp")
        run([km, "contour", s, "-o", cont, "--iso", "9.3", "-q"])
        run([km, "dual", cont, "-o", dual, "-q"])
        pc, pd = read(cont), read(dual)
        # the dual's edges are chords between triangle centroids, just under
        # the surface: drawn 2% outward (about the field's centre) to be seen
        grow = vtk.vtkTransform()
        grow.Translate(12, 12, 12)
        grow.Scale(1.02, 1.02, 1.02)
        grow.Translate(-12, -12, -12)
        tf = vtk.vtkTransformPolyDataFilter()
        tf.SetTransform(grow)
        tf.SetInputData(pd)
        tf.Update()
        path = os.path.join(a.out, "fig10-dual.png")
        render([surface_actor(pc, (0.45, 0.8, 0.45)), wire_actor(tf.GetOutput(), (0.1, 0.2, 0.9), 2.0)], path,
               (480, 480),
               view=lambda c: (c.Azimuth(35), c.Elevation(25)))
        rows.append({"bench": "figure", "figure": 10, "png": os.path.relpath(path, os.path.dirname(HERE)),
                     "dataset": "sphere24", "iso": 9.3, "input_cells": pc.GetNumberOfCells(),
                     "cells": pd.GetNumberOfCells(), "command": "keymesh contour sphere24.vti --iso 9.3; keymesh dual"})
    except Exception as e:  # a picture is not worth failing the benchmark for
        rows.append({"bench": "skipped", "tool": "figures", "reason": f"{type(e).__name__}: {e}"})
    finally:
        if xvfb:
            xvfb.terminate()
            xvfb.wait()
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
