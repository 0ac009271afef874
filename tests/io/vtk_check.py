#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Reads a file with VTK's own readers (not ido's) and prints what it holds as JSON, so the
io tests can check ido's writers against an independent implementation.

usage: vtk_check.py KIND FILE     KIND: vtp vtu stl ply obj msh nii mha nrrd
       vtk_check.py write KIND MODE FILE
           writes a known mesh with VTK's writers (KIND vtu|vtp, MODE ascii|binary|appended,
           or binary-zlib|appended-zlib|base64-zlib for zlib-compressed data as ParaView saves;
           KIND ply, MODE ascii|binary; KIND stl, MODE ascii|binary) for ido's readers.
"""
import json
import sys

# Import the reader modules one by one: `import vtk` would load the MPI module too, whose
# factory overrides vtkNrrdReader with a parallel reader that fails without MPI.
from vtkmodules.vtkIOGeometry import vtkOBJReader, vtkSTLReader
from vtkmodules.vtkIOImage import vtkMetaImageReader, vtkNIFTIImageReader, vtkNrrdReader
from vtkmodules.vtkIOPLY import vtkPLYReader
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader, vtkXMLUnstructuredGridReader


def values(array):
    """All values of a vtkDataArray, component-interleaved (no numpy needed)."""
    nc = array.GetNumberOfComponents()
    return [array.GetComponent(t, c) for t in range(array.GetNumberOfTuples()) for c in range(nc)]


def arrays(data):
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        if a is None:
            continue
        out[a.GetName()] = {"components": a.GetNumberOfComponents(),
                            "values": values(a)}
    return out


def mesh_summary(ds):
    pts = ds.GetPoints()
    coords = values(pts.GetData()) if pts is not None else []
    cells = []
    types = []
    for c in range(ds.GetNumberOfCells()):
        cell = ds.GetCell(c)
        types.append(cell.GetCellType())
        cells.append([cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())])
    return {"points": ds.GetNumberOfPoints(), "cells": ds.GetNumberOfCells(),
            "coords": coords, "connectivity": cells, "cell_types": types,
            "point_data": arrays(ds.GetPointData()), "cell_data": arrays(ds.GetCellData())}


def image_summary(img):
    scalars = img.GetPointData().GetScalars()
    return {"dims": list(img.GetDimensions()), "spacing": list(img.GetSpacing()),
            "origin": list(img.GetOrigin()),
            "values": values(scalars) if scalars is not None else []}


def gmsh_summary(gmsh, path):
    """What Gmsh reads from a .msh file, in the same shape as mesh_summary: points in
    node-tag order, tetrahedra (Gmsh element type 4, reported as VTK_TETRA = 10) as 0-based
    point indices."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(path)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        order = sorted(range(len(tags)), key=lambda i: tags[i])
        index = {int(tags[i]): k for k, i in enumerate(order)}
        points = [float(coords[3 * i + c]) for i in order for c in range(3)]
        cells = []
        types, _, nodes = gmsh.model.mesh.getElements()
        for t, conn in zip(types, nodes):
            if t != 4:
                continue
            cells += [[index[int(conn[4 * e + k])] for k in range(4)] for e in range(len(conn) // 4)]
    finally:
        gmsh.finalize()
    return {"points": len(order), "cells": len(cells), "coords": points, "connectivity": cells,
            "cell_types": [10] * len(cells), "point_data": {}, "cell_data": {}}


def known_points():
    from vtkmodules.vtkCommonCore import vtkPoints
    pts = vtkPoints()
    pts.SetDataTypeToDouble()
    for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 1)]:
        pts.InsertNextPoint(*p)
    return pts


def add_fields(ds, cells):
    from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkFloatArray
    disp = vtkDoubleArray()
    disp.SetName("displacement_mm")
    disp.SetNumberOfComponents(3)
    for i in range(5):
        disp.InsertNextTuple3(0.5 * i, -0.25 * i, 0.125 * i)
    ds.GetPointData().AddArray(disp)
    stress = vtkFloatArray()
    stress.SetName("stress_pa")
    for c in range(cells):
        stress.InsertNextValue(10.0 + 2.5 * c)
    ds.GetCellData().AddArray(stress)


def write(kind, mode, path):
    """The known mesh: 5 points; vtu: tets (0,1,2,3) and (1,2,3,4)... oriented positively;
    vtp/ply/stl: triangles (0,2,1), (0,1,3), (1,2,4)."""
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData, vtkUnstructuredGrid, VTK_TETRA
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter, vtkXMLUnstructuredGridWriter
    from vtkmodules.vtkIOPLY import vtkPLYWriter
    from vtkmodules.vtkIOGeometry import vtkSTLWriter
    if kind == "vtu":
        ds = vtkUnstructuredGrid()
        ds.SetPoints(known_points())
        for tet in [(0, 1, 2, 3), (1, 4, 2, 3)]:
            ds.InsertNextCell(VTK_TETRA, 4, tet)
        add_fields(ds, 2)
        w = vtkXMLUnstructuredGridWriter()
    else:
        ds = vtkPolyData()
        ds.SetPoints(known_points())
        polys = vtkCellArray()
        for tri in [(0, 2, 1), (0, 1, 3), (1, 2, 4)]:
            polys.InsertNextCell(3, tri)
        ds.SetPolys(polys)
        if kind == "vtp":
            add_fields(ds, 3)
        w = {"vtp": vtkXMLPolyDataWriter, "ply": vtkPLYWriter, "stl": vtkSTLWriter}[kind]()
    w.SetInputData(ds)
    w.SetFileName(path)
    if kind in ("vtu", "vtp"):
        layout, _, compressor = mode.partition("-")
        if compressor == "zlib":
            w.SetCompressorTypeToZLib()
            w.SetBlockSize(64)  # several blocks even for the small known mesh
        else:
            w.SetCompressorTypeToNone()
        {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
         "appended": w.SetDataModeToAppended, "base64": w.SetDataModeToAppended}[layout]()
        if layout == "appended":
            w.EncodeAppendedDataOff()
        elif layout == "base64":
            w.EncodeAppendedDataOn()
    else:
        w.SetFileTypeToASCII() if mode == "ascii" else w.SetFileTypeToBinary()
    if not w.Write():
        return 1
    print(json.dumps({"written": path}))
    return 0


def main():
    if sys.argv[1] == "write":
        return write(sys.argv[2], sys.argv[3], sys.argv[4])
    kind, path = sys.argv[1], sys.argv[2]
    readers = {"vtp": vtkXMLPolyDataReader, "vtu": vtkXMLUnstructuredGridReader,
               "stl": vtkSTLReader, "ply": vtkPLYReader, "obj": vtkOBJReader,
               "nii": vtkNIFTIImageReader, "mha": vtkMetaImageReader, "nrrd": vtkNrrdReader}
    if kind == "msh":
        # Debian 12's VTK 9.1 has no vtkGmshReader: Gmsh itself (python3-gmsh) reads the file.
        try:
            import gmsh
        except ImportError:
            print(json.dumps({"skipped": "python3-gmsh is not installed"}))
            return 0
        print(json.dumps(gmsh_summary(gmsh, path)))
        return 0
    reader = readers[kind]()
    reader.SetFileName(path)
    reader.Update()
    out = reader.GetOutput()
    summary = image_summary(out) if kind in ("nii", "mha", "nrrd") else mesh_summary(out)
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
