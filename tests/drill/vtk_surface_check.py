#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Checks a drilled surface (.vtp) with VTK's own filters, not ido's: prints as JSON the
boundary and non-manifold edge counts of vtkFeatureEdges and the volume of vtkMassProperties.

usage: vtk_surface_check.py FILE.vtp
"""
import json
import sys

from vtkmodules.vtkFiltersCore import vtkFeatureEdges, vtkMassProperties
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader


def count_edges(data, boundary, non_manifold):
    f = vtkFeatureEdges()
    f.SetInputData(data)
    f.SetBoundaryEdges(boundary)
    f.SetNonManifoldEdges(non_manifold)
    f.SetFeatureEdges(False)
    f.SetManifoldEdges(False)
    f.Update()
    return f.GetOutput().GetNumberOfCells()


def main():
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(sys.argv[1])
    reader.Update()
    data = reader.GetOutput()
    mass = vtkMassProperties()
    mass.SetInputData(data)
    mass.Update()
    print(json.dumps({"triangles": data.GetNumberOfCells(), "points": data.GetNumberOfPoints(),
                      "boundary_edges": count_edges(data, True, False),
                      "non_manifold_edges": count_edges(data, False, True),
                      "volume": mass.GetVolume()}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
