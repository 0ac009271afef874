# SPDX-License-Identifier: Apache-2.0
"""ido.Volume / ido.Mask: numpy layout, geometry, file round trips, errors."""
import gc
import math
import os

import numpy as np
import pytest

import ido


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = math.radians(degrees)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k


def make_volume():
    """A 5 x 6 x 7 (i, j, k) volume with anisotropic spacing, an origin and a rotation; voxel
    value = i + 10 j + 100 k so every index can be read back from the value."""
    k, j, i = np.meshgrid(np.arange(7), np.arange(6), np.arange(5), indexing="ij")
    voxels = (i + 10 * j + 100 * k).astype(np.float32)
    return ido.Volume(voxels, spacing=(0.7, 0.9, 1.6), origin=(-12.5, 40.0, 3.25), direction=rotation((1, 2, 3), 30))


def test_array_is_indexed_k_j_i_and_size_is_i_j_k():
    v = make_volume()
    assert v.size == (5, 6, 7)
    assert v.array.shape == (7, 6, 5)
    assert v.array.dtype == np.float32
    assert v.array[6, 2, 4] == 4 + 10 * 2 + 100 * 6


def test_index_to_world_is_origin_plus_direction_times_scaled_index():
    v = make_volume()
    d, s, o = np.asarray(v.direction), np.asarray(v.spacing), np.asarray(v.origin)
    for ijk in [(0, 0, 0), (4, 5, 6), (1.5, 2.25, 3.75)]:
        expected = o + d @ (s * np.asarray(ijk))
        np.testing.assert_allclose(v.index_to_world(ijk), expected, atol=1e-12)
        np.testing.assert_allclose(v.world_to_index(expected), ijk, atol=1e-9)


def test_array_is_a_writable_view_that_outlives_its_volume():
    v = make_volume()
    v.array[3, 2, 1] = -5.0
    assert v.array[3, 2, 1] == -5.0  # the same memory, read again through a new view
    view = make_volume().array  # the temporary volume must stay alive through the view
    gc.collect()
    assert view[6, 5, 4] == 4 + 50 + 600


@pytest.mark.parametrize("ext", [".nii.gz", ".nrrd", ".mha"])
def test_file_round_trip_keeps_voxels_and_geometry(tmp_path, ext):
    v = make_volume()
    path = tmp_path / ("v" + ext)
    ido.write_volume(path, v)
    back = ido.read_volume(path)
    np.testing.assert_array_equal(back.array, v.array)
    np.testing.assert_allclose(back.spacing, v.spacing, atol=1e-6)
    np.testing.assert_allclose(back.origin, v.origin, atol=1e-5)
    np.testing.assert_allclose(back.direction, v.direction, atol=1e-6)
    assert back.same_grid(v)


def test_a_reader_that_is_not_ours_sees_the_same_voxel_at_the_same_index(tmp_path):
    vtk = pytest.importorskip("vtkmodules.vtkIOImage")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    v = make_volume()
    path = tmp_path / "v.mha"
    ido.write_volume(path, v)
    reader = vtk.vtkMetaImageReader()
    reader.SetFileName(str(path))
    reader.Update()
    image = reader.GetOutput()
    assert image.GetDimensions() == (5, 6, 7)
    flat = vtk_to_numpy(image.GetPointData().GetScalars())
    for i, j, k in [(0, 0, 0), (4, 0, 0), (0, 5, 0), (0, 0, 6), (3, 2, 5)]:
        assert flat[i + 5 * (j + 6 * k)] == v.array[k, j, i] == i + 10 * j + 100 * k


def test_mask_round_trip_is_uint8(tmp_path):
    voxels = np.zeros((4, 5, 6), np.uint8)
    voxels[1:3, 2:4, 1:5] = 1
    m = ido.Mask(voxels, spacing=(1.0, 1.0, 2.0))
    assert m.array.dtype == np.uint8
    ido.write_volume(tmp_path / "m.nii.gz", m)
    back = ido.read_volume(tmp_path / "m.nii.gz")  # read as float32
    np.testing.assert_array_equal(back.array, voxels.astype(np.float32))


def test_bad_input_raises_with_what_is_wrong(tmp_path):
    missing = tmp_path / "missing.nii.gz"
    with pytest.raises(FileNotFoundError, match="missing.nii.gz"):  # an OSError, as open() raises
        ido.read_volume(missing)
    with pytest.raises(ValueError, match="3-D"):
        ido.Volume(np.zeros((3, 3), np.float32))
    with pytest.raises(ValueError, match="spacing"):
        ido.Volume(np.zeros((2, 2, 2), np.float32), spacing=(0.0, 1.0, 1.0))
    bad = tmp_path / "garbage.nii.gz"
    bad.write_bytes(b"not a nifti file")
    with pytest.raises(OSError, match="garbage.nii.gz") as unreadable:
        ido.read_volume(bad)
    assert not isinstance(unreadable.value, FileNotFoundError)  # it exists: not "not found"
    with pytest.raises(FileNotFoundError):
        ido.write_volume(tmp_path / "no-such-dir" / "v.nii.gz", make_volume())
    assert not (tmp_path / "no-such-dir").exists()


def test_read_mask_by_nonzero_label_and_level(tmp_path):
    labels = np.zeros((3, 4, 5), np.float32)
    labels[0, 1, 2] = 2.0
    labels[1, 2, 3] = 1.0
    labels[2, 3, 4] = -0.5
    ido.write_volume(tmp_path / "l.nrrd", ido.Volume(labels, spacing=(0.5, 0.5, 2.0)))
    nonzero = ido.read_mask(tmp_path / "l.nrrd")
    assert nonzero.array.dtype == np.uint8 and nonzero.spacing[2] == pytest.approx(2.0)
    np.testing.assert_array_equal(nonzero.array, (labels != 0).astype(np.uint8))
    np.testing.assert_array_equal(ido.read_mask(tmp_path / "l.nrrd", label=2).array, (labels == 2).astype(np.uint8))
    np.testing.assert_array_equal(ido.read_mask(tmp_path / "l.nrrd", below=0.0).array, (labels < 0).astype(np.uint8))
    with pytest.raises(ValueError, match="not both"):
        ido.read_mask(tmp_path / "l.nrrd", label=1, below=0.0)


def test_the_package_is_typed_and_its_names_are_ido_names():
    # PEP 561: a typed distribution is a package with a py.typed marker; the stubs sit beside
    # the extension, and every class is named as users import it (ido.Volume, not ido._ido.Volume).
    folder = os.path.dirname(ido.__file__)
    assert os.path.basename(folder) == "ido"
    assert os.path.isfile(os.path.join(folder, "py.typed"))
    assert os.path.isfile(os.path.join(folder, "__init__.pyi"))
    for cls in (ido.Volume, ido.Mask, ido.TriangleMesh, ido.TetMesh, ido.World, ido.Segmentation):
        assert cls.__module__ == "ido"
        assert repr(cls) == f"<class 'ido.{cls.__name__}'>"
    assert "ct: ido.Volume" in ido.segment.__doc__
    assert ido.__version__
