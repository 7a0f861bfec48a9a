#!/usr/bin/env python3
"""Renders the force chains of a `powder run` output: the contact network of its last
snapshot as tubes (radius and colour by normal force; red compressive, blue adhesive
tension) in a vertical slab, with the slab's particles as pale spheres.

    python3 tools/force_chains.py OUT_DIR PICTURE.png|.jpg [--slab 0.004] [--size 1200x760]

Needs VTK's Python package (`pip install vtk`); off screen it uses OSMesa
(`apt-get install libosmesa6`). What it does is what the README's ParaView recipe does by
hand: Cell Data to Point Data, Tube (radius by |normal_force|), Glyph for the particles.
"""

import argparse
import glob
import os
import sys

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")
import vtk  # noqa: E402


def latest(pattern):
    files = sorted(glob.glob(pattern))
    if not files:
        sys.exit(f"no file matches {pattern}: run `powder run SCENE --out DIR` first")
    return files[-1]


def reader(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("picture")
    ap.add_argument("--slab", type=float, default=0.004, help="slab thickness along y, m")
    ap.add_argument("--size", default="1200x760")
    a = ap.parse_args()
    contacts = reader(latest(os.path.join(a.out_dir, "contacts", "*.vtp")))
    particles = reader(latest(os.path.join(a.out_dir, "snapshots", "*.vtp")))
    net = contacts.GetOutput()
    print(f"{net.GetNumberOfCells()} contacts in {contacts.GetFileName()}")
    x0, x1, y0, y1, z0, z1 = particles.GetOutput().GetBounds()
    yc = 0.5 * (y0 + y1)
    box = vtk.vtkBox()
    box.SetBounds(x0 - 1, x1 + 1, yc - a.slab / 2, yc + a.slab / 2, z0 - 1, z1 + 1)

    # the slab's contacts (both ends inside), as tubes
    cut = vtk.vtkExtractPolyDataGeometry()
    cut.SetInputConnection(contacts.GetOutputPort())
    cut.SetImplicitFunction(box)
    cut.ExtractInsideOn()
    cut.ExtractBoundaryCellsOff()
    to_points = vtk.vtkCellDataToPointData()
    to_points.SetInputConnection(cut.GetOutputPort())
    to_points.Update()
    data = to_points.GetOutput()
    force = data.GetPointData().GetArray("normal_force")
    fmax = max(abs(v) for v in force.GetRange()) or 1.0
    data.GetPointData().SetActiveScalars("normal_force")
    tubes = vtk.vtkTubeFilter()
    tubes.SetInputData(data)
    tubes.SetVaryRadiusToVaryRadiusByAbsoluteScalar()
    r_min = 2e-5
    tubes.SetRadius(r_min)
    # VTK's absolute-scalar radius is the scalar itself: scale the forces to metres
    scaled = vtk.vtkArrayCalculator()
    scaled.SetInputData(data)
    scaled.SetAttributeTypeToPointData()
    scaled.AddScalarArrayName("normal_force")
    scaled.SetFunction(f"{r_min} + abs(normal_force) * {3.5e-4 / fmax}")
    scaled.SetResultArrayName("tube_radius")
    scaled.Update()
    out = scaled.GetOutput()
    out.GetPointData().SetActiveScalars("tube_radius")
    tubes.SetInputData(out)
    tubes.SetNumberOfSides(12)
    tubes.CappingOn()
    colours = vtk.vtkColorTransferFunction()
    colours.SetColorSpaceToDiverging()
    colours.AddRGBPoint(-fmax, 0.23, 0.30, 0.75)
    colours.AddRGBPoint(0.0, 0.87, 0.87, 0.87)
    colours.AddRGBPoint(fmax, 0.71, 0.02, 0.15)
    tube_map = vtk.vtkPolyDataMapper()
    tube_map.SetInputConnection(tubes.GetOutputPort())
    tube_map.SetScalarModeToUsePointFieldData()
    tube_map.SelectColorArray("normal_force")
    tube_map.SetLookupTable(colours)
    tube_map.SetUseLookupTableScalarRange(True)
    tube_actor = vtk.vtkActor()
    tube_actor.SetMapper(tube_map)

    # the slab's particles, pale and translucent
    pcut = vtk.vtkExtractPolyDataGeometry()
    pcut.SetInputConnection(particles.GetOutputPort())
    pcut.SetImplicitFunction(box)
    pcut.Update()
    pdata = pcut.GetOutput()
    pdata.GetPointData().SetActiveScalars("radius")
    sphere = vtk.vtkSphereSource()
    sphere.SetRadius(1.0)
    sphere.SetThetaResolution(20)
    sphere.SetPhiResolution(14)
    glyphs = vtk.vtkGlyph3D()
    glyphs.SetInputData(pdata)
    glyphs.SetSourceConnection(sphere.GetOutputPort())
    glyphs.SetScaleModeToScaleByScalar()
    glyphs.SetScaleFactor(1.0)
    glyph_map = vtk.vtkPolyDataMapper()
    glyph_map.SetInputConnection(glyphs.GetOutputPort())
    glyph_map.ScalarVisibilityOff()
    glyph_actor = vtk.vtkActor()
    glyph_actor.SetMapper(glyph_map)
    glyph_actor.GetProperty().SetColor(0.80, 0.78, 0.72)
    glyph_actor.GetProperty().SetOpacity(0.10)

    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(colours)
    bar.SetTitle("normal force, N\n(+ compression, - adhesion)")
    bar.SetNumberOfLabels(5)
    bar.SetLabelFormat("%.1e")
    bar.SetOrientationToHorizontal()
    bar.SetPosition(0.25, 0.02)
    bar.SetWidth(0.5)
    bar.SetHeight(0.1)
    for p in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        p.SetColor(0.1, 0.1, 0.1)
        p.ShadowOff()
        p.ItalicOff()

    ren = vtk.vtkRenderer()
    ren.SetBackground(1.0, 1.0, 1.0)
    ren.AddActor(glyph_actor)
    ren.AddActor(tube_actor)
    ren.AddViewProp(bar)
    w, h = (int(v) for v in a.size.split("x"))
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetSize(w, h)
    win.AddRenderer(ren)
    cam = ren.GetActiveCamera()
    # (the bed a little above the middle: the colour bar goes below it)
    zc = 0.5 * (z0 + z1) - 0.12 * (z1 - z0)
    cam.SetFocalPoint(0.5 * (x0 + x1), yc, zc)
    cam.SetPosition(0.5 * (x0 + x1), yc - 1.0, zc)
    cam.SetViewUp(0, 0, 1)
    ren.ResetCamera()
    cam.SetFocalPoint(0.5 * (x0 + x1), yc, zc)
    cam.SetPosition(0.5 * (x0 + x1), cam.GetPosition()[1], zc)
    cam.Zoom(1.45)
    win.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.Update()
    if a.picture.lower().endswith((".jpg", ".jpeg")):
        out_file = vtk.vtkJPEGWriter()
        out_file.SetQuality(90)
    else:
        out_file = vtk.vtkPNGWriter()
    out_file.SetFileName(a.picture)
    out_file.SetInputConnection(grab.GetOutputPort())
    out_file.Write()
    print(f"{a.picture}: {out.GetNumberOfCells()} contacts and {pdata.GetNumberOfPoints()} particles in the slab, |F| <= {fmax:.3e} N")


if __name__ == "__main__":
    main()
