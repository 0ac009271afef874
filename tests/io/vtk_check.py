#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Reads a file with VTK's own readers (not ido's) and prints what it holds as JSON, so the
io tests can check ido's writers against an independent implementation.

usage: vtk_check.py KIND FILE     KIND: vtp vtu stl ply obj msh nii mha nrrd
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


def main():
    kind, path = sys.argv[1], sys.argv[2]
    readers = {"vtp": vtkXMLPolyDataReader, "vtu": vtkXMLUnstructuredGridReader,
               "stl": vtkSTLReader, "ply": vtkPLYReader, "obj": vtkOBJReader,
               "nii": vtkNIFTIImageReader, "mha": vtkMetaImageReader, "nrrd": vtkNrrdReader}
    if kind == "msh":
        try:
            from vtkmodules.vtkIOGmsh import vtkGmshReader  # not built into Debian 12's VTK 9.1
        except ImportError:
            print(json.dumps({"skipped": "this VTK has no vtkGmshReader"}))
            return 0
        readers["msh"] = vtkGmshReader
    reader = readers[kind]()
    reader.SetFileName(path)
    reader.Update()
    out = reader.GetOutput()
    summary = image_summary(out) if kind in ("nii", "mha", "nrrd") else mesh_summary(out)
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
