# SPDX-License-Identifier: Apache-2.0
"""ido.TriangleMesh / ido.TetMesh: marching cubes, checks, files, self-intersections, tetrahedra."""
import math

import numpy as np
import pytest

import ido


def sphere_field(radius_mm=10.0, spacing=0.5):
    """Signed distance to a sphere of radius_mm centred in a 30 mm box (negative inside)."""
    n = int(round(30.0 / spacing))
    idx = np.arange(n) * spacing
    z, y, x = np.meshgrid(idx, idx, idx, indexing="ij")
    c = 0.5 * (n - 1) * spacing
    d = np.sqrt((x - c) ** 2 + (y - c) ** 2 + (z - c) ** 2) - radius_mm
    return ido.Volume(d.astype(np.float32), spacing=(spacing,) * 3)


def signed_volume(vertices, triangles):
    a, b, c = (vertices[triangles[:, q]] for q in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def test_marching_cubes_sphere_is_closed_with_its_volume():
    surface = ido.marching_cubes(sphere_field(), iso=0.0)
    check = ido.check_mesh(surface)
    assert check["closed"] and check["edge_manifold"] and check["vertex_manifold"] and check["oriented"]
    assert check["euler_characteristic"] == 2 and check["genus"] == 0
    exact = 4.0 / 3.0 * math.pi * 10.0**3
    assert abs(check["volume_mm3"] - exact) / exact < 0.005
    # The dict's volume and one computed here from the arrays agree.
    assert signed_volume(surface.vertices, surface.triangles) == pytest.approx(check["volume_mm3"], rel=1e-9)
    radii = np.linalg.norm(surface.vertices - 0.5 * 59 * 0.5, axis=1)
    assert np.abs(radii - 10.0).max() < 0.05


def test_marching_cubes_of_a_mask_is_closed():
    voxels = np.zeros((8, 9, 10), np.uint8)
    voxels[2:6, 3:7, 2:8] = 1
    voxels[3:5, 4:6, :] = 0  # a tunnel through the box along i: genus 1
    surface = ido.marching_cubes(ido.Mask(voxels))
    check = ido.check_mesh(surface)
    assert check["closed"] and check["oriented"] and check["genus"] == 1


@pytest.mark.parametrize("ext", [".ply", ".obj", ".vtp"])
def test_surface_file_round_trip(tmp_path, ext):
    surface = ido.marching_cubes(sphere_field(spacing=1.0))
    ido.write_mesh(tmp_path / ("s" + ext), surface)
    back = ido.read_triangle_mesh(tmp_path / ("s" + ext))
    np.testing.assert_array_equal(back.triangles, surface.triangles)
    np.testing.assert_allclose(back.vertices, surface.vertices, rtol=0, atol=1e-5)


def test_constructor_validates_and_views_are_read_only():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    mesh = ido.TriangleMesh(v, t)
    assert ido.check_mesh(mesh)["closed"]
    assert signed_volume(mesh.vertices, mesh.triangles) == pytest.approx(1.0 / 6.0)
    with pytest.raises(ValueError):
        mesh.vertices[0, 0] = 5.0
    with pytest.raises(ValueError, match="row 1 names vertex 7"):
        ido.TriangleMesh(v, np.array([[0, 1, 2], [0, 1, 7]]))
    with pytest.raises(ValueError, match="not finite"):
        ido.TriangleMesh(np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        ido.TriangleMesh(np.zeros((4, 2)), t)
    with pytest.raises(ValueError, match="vertex 3"):
        mesh.vertices = v[:3]  # the triangles still name vertex 3
    mesh.vertices = v * 2.0
    assert signed_volume(mesh.vertices, mesh.triangles) == pytest.approx(8.0 / 6.0)


def test_self_intersections_crossing_and_touching():
    # Two triangles crossing through each other's interior: one pair.
    v = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0.5, 0.5, -1], [0.5, 0.5, 1], [1.5, 1.5, 0]], float)
    crossing = ido.TriangleMesh(v, np.array([[0, 1, 2], [3, 4, 5]]))
    assert ido.self_intersections(crossing).tolist() == [[0, 1]]
    # Two triangles sharing an edge only: none.
    w = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]], float)
    assert ido.self_intersections(ido.TriangleMesh(w, np.array([[0, 1, 2], [1, 3, 2]]))).shape == (0, 2)
    # A closed marching-cubes surface: none.
    assert len(ido.self_intersections(ido.marching_cubes(sphere_field(spacing=1.0)))) == 0


def test_tetrahedralize_fills_the_surface(tmp_path):
    surface = ido.marching_cubes(sphere_field(spacing=1.0))
    tets = ido.tetrahedralize(surface, edge_mm=2.0)
    x = tets.vertices
    a, b, c, d = (x[tets.tets[:, q]] for q in range(4))
    vol = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0
    assert (vol > 0).all()  # every tetrahedron positively oriented
    enclosed = ido.check_mesh(surface)["volume_mm3"]
    assert abs(vol.sum() - enclosed) / enclosed < 0.02
    ido.write_mesh(tmp_path / "t.vtu", tets)
    back = ido.read_tet_mesh(tmp_path / "t.vtu")
    np.testing.assert_array_equal(back.tets, tets.tets)
    np.testing.assert_allclose(back.vertices, tets.vertices, atol=1e-9)


def test_unreadable_mesh_names_the_file(tmp_path):
    bad = tmp_path / "broken.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n0 0\n")
    with pytest.raises((OSError, ValueError), match="broken.ply"):
        ido.read_triangle_mesh(bad)
