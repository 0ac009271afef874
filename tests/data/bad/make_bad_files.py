#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Regenerates the bad-input catalogue's files (run from this folder). Each file breaks one
rule; catalogue.txt says which exception and message fragment ido must give for it."""
import os
import struct

def w(name, data):
    with open(name, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())

TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
w("empty.stl", b"")
w("short.stl", b"not an stl at all")
w("binary_truncated.stl", b"\0" * 80 + struct.pack("<I", 10) + b"\0" * 100)
w("ascii_truncated.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n")
w("ascii_nonnumeric.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 abc 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid x\n")
w("ascii_nan.stl", "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 nan 0\n  endloop\n endfacet\nendsolid x\n")
w("index_out_of_range.obj", TRI + "f 1 2 9\n")
w("nonnumeric.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n")
w("short_face.obj", TRI + "f 1 2\n")
w("infinite.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n")
w("wrong_magic.ply", "plx\nformat ascii 1.0\nelement vertex 0\nend_header\n")
w("no_end_header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n")
hdr = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
w("binary_truncated.ply", hdr.encode() + struct.pack("<6f", 0, 0, 0, 1, 0, 0))
ahdr = "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
w("count_mismatch.ply", ahdr.format(4) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
w("index_out_of_range.ply", ahdr.format(3) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")
w("not_xml.vtp", "this is not XML\n")
VTU = """<?xml version="1.0"?>
<VTKFile type="{type}" version="1.0" byte_order="LittleEndian"{extra}>
  <UnstructuredGrid>
    <Piece NumberOfPoints="{np}" NumberOfCells="1">
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="{fmt}">
          {points}
        </DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">{conn}</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">{offsets}</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">{ctype}</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"""
P = "0 0 0 1 0 0 0 1 0 0 0 1"
def vtu(**kw):
    d = dict(type="UnstructuredGrid", extra="", np=4, fmt="ascii", points=P, conn="0 1 2 3",
             offsets=4, ctype=10)
    d.update(kw)
    return VTU.format(**d)
w("wrong_type.vtp", vtu())
w("truncated.vtu", vtu()[:400])
w("count_mismatch.vtu", vtu(np=5))
w("inverted.vtu", vtu(conn="0 2 1 3"))
w("degenerate.vtu", vtu(points="0 0 0 1 0 0 0 1 0 1 1 0"))
w("index_out_of_range.vtu", vtu(conn="0 1 2 8"))
w("bad_base64.vtu", vtu(fmt="binary", points="!!!!not*base64"))
w("compressed.vtu", vtu(extra=' compressor="vtkLZMADataCompressor"'))
w("nonnumeric.vtu", vtu(points="0 0 0 1 0 0 0 1 0 0 0 one"))
w("nan.vtu", vtu(points="0 0 0 1 0 0 0 1 0 0 0 nan"))
w("hexahedron.vtu", vtu(np=8, points="0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1",
                        conn="0 1 2 3 4 5 6 7", offsets=8, ctype=12))
MSH2 = "$MeshFormat\n{ver} {ft} 8\n$EndMeshFormat\n$Nodes\n{nn}\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 {z}\n$EndNodes\n$Elements\n1\n1 4 2 0 1 1 2 3 {last}\n$EndElements\n"
def msh(**kw):
    d = dict(ver="2.2", ft=0, nn=4, z=1, last=4)
    d.update(kw)
    return MSH2.format(**d)
w("wrong_version.msh", msh(ver="3.0"))
w("binary.msh", msh(ft=1))
w("missing_node.msh", msh(last=99))
w("count_mismatch.msh", msh(nn=5))
w("nan.msh", msh(z="nan"))
w("no_meshformat.msh", "$Nodes\n0\n$EndNodes\n")
w("inverted.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n")
w("inverted.ele", "1 4 0\n1 1 3 2 4\n")
w("index_out_of_range.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n")
w("index_out_of_range.ele", "1 4 0\n1 1 2 3 9\n")
w("dimension2.node", "3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n")
w("dimension2.ele", "0 4 0\n")
w("garbage.nii", "this is not a NIfTI header" * 20)
# NIfTI-1 header for a 4x4x4 int16 volume whose voxel data is cut short.
h = bytearray(352)
struct.pack_into("<i", h, 0, 348)
struct.pack_into("<8h", h, 40, 3, 4, 4, 4, 1, 1, 1, 1)
struct.pack_into("<hh", h, 70, 4, 16)
struct.pack_into("<8f", h, 76, 1, 1, 1, 1, 1, 1, 1, 1)
struct.pack_into("<f", h, 108, 352.0)
h[344:348] = b"n+1\0"
w("truncated.nii", bytes(h) + b"\0" * 10)
w("bad_sizes.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2\nencoding: raw\n\n")
w("truncated.mha", "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n" + "\0" * 8)
os.makedirs("folder.vtu", exist_ok=True)
w("folder.vtu/.keep", "")

# Volumes whose header promises what the file does not hold (issue 30): each must be refused,
# not read as zeros, NaN or a made-up spacing.
import gzip
import math

def nifti1(dims=(4, 4, 4), datatype=4, bitpix=16, pixdim=(1, 1, 1), vox_offset=352.0):
    h = bytearray(352)
    struct.pack_into("<i", h, 0, 348)
    struct.pack_into("<8h", h, 40, len(dims), *dims, *([1] * (7 - len(dims))))
    struct.pack_into("<hh", h, 70, datatype, bitpix)
    struct.pack_into("<8f", h, 76, 1, *pixdim, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, vox_offset)
    h[344:348] = b"n+1\0"
    return bytes(h)

VOX = bytes(range(128))  # 4x4x4 int16
w("pixdim_zero.nii", nifti1(pixdim=(1, 0, 1)) + VOX)
w("pixdim_negative.nii", nifti1(pixdim=(-1, 1, 1)) + VOX)
w("pixdim_nan.nii", nifti1(pixdim=(1, 1, math.nan)) + VOX)
w("vox_offset_past_end.nii", nifti1(vox_offset=1048576.0) + VOX)
w("all_nan.nii", nifti1(dims=(2, 2, 2), datatype=16, bitpix=32) + struct.pack("<8f", *([math.nan] * 8)))
w("huge.nii", nifti1(dims=(32767, 32767, 32767)) + VOX)
w("bad_dim.nii", nifti1(dims=(4, 0, 4)) + VOX)
# NIfTI-2: a 540-byte header (sizeof_hdr 540, magic "n+2").
h2 = bytearray(544)
struct.pack_into("<i", h2, 0, 540)
h2[4:12] = b"n+2\0\r\n\x1a\n"
struct.pack_into("<hh", h2, 12, 4, 16)
struct.pack_into("<8q", h2, 16, 3, 2, 2, 2, 1, 1, 1, 1)
struct.pack_into("<8d", h2, 104, 1, 1, 1, 1, 1, 1, 1, 1)
struct.pack_into("<q", h2, 168, 544)
w("nifti2.nii", bytes(h2) + b"\0" * 16)
# gzip: a stream cut short, and an intact stream holding fewer voxel bytes than declared.
full = gzip.compress(nifti1() + VOX, mtime=0)
w("cut_stream.nii.gz", full[: len(full) // 2])
w("short_stream.nii.gz", gzip.compress(nifti1() + VOX[:60], mtime=0))
w("cut_header.nii.gz", gzip.compress(nifti1() + VOX, mtime=0)[:40])
MHA = "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementSpacing = {sp}\nElementType = {et}\nElementDataFile = LOCAL\n"
w("unknown_element_type.mha", MHA.format(sp="1 1 1", et="MET_FOO").encode() + b"\0" * 8)
w("spacing_zero.mha", MHA.format(sp="1 0 1", et="MET_UCHAR").encode() + b"\0" * 8)
w("infinite.mha", MHA.format(sp="1 1 1", et="MET_FLOAT").encode() + struct.pack("<8f", 0, 0, 0, math.inf, 0, 0, 0, 0))
# A zlib-compressed .vtu whose block header declares far more bytes than its compressed
# block can inflate to (deflate's limit is 1032:1): refused before the payload is allocated.
import zlib
block = zlib.compress(b"\0" * 16)
appended = struct.pack("<4I", 1, 48000, 48000, len(block)) + block
w("zlib_bomb.vtu", ("""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" compressor="vtkZLibDataCompressor">
  <UnstructuredGrid>
    <Piece NumberOfPoints="2000" NumberOfCells="1">
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="appended" offset="0"/>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
  <AppendedData encoding="raw">
   _""").encode() + appended + b"\n  </AppendedData>\n</VTKFile>\n")
# Compressed MetaImage voxels that do not inflate, or inflate to fewer bytes than declared
# (MetaIO only prints "Uncompress failed" and hands back its buffer).
ZMHA = "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_SHORT\nCompressedData = True\nElementDataFile = LOCAL\n"
w("damaged_zlib.mha", ZMHA.encode() + b"this is not a zlib stream")
w("short_zlib.mha", ZMHA.encode() + zlib.compress(bytes(range(100))))
# Header/data pairs whose data file holds fewer bytes than the header declares (ITK reads a
# short one with whatever its buffer held, or fails with its internals), or is missing: the
# header is refused naming its data file. The data files are not catalogued themselves.
DETACHED_MHD = "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementSpacing = 1 1 1\nElementType = MET_FLOAT\n"
w("short_data.raw", b"\0" * 100)
w("short_data.mhd", DETACHED_MHD + "ElementDataFile = short_data.raw\n")
w("short_zlib_data.zraw", zlib.compress(b"\0" * 100))
w("short_zlib_data.mhd", DETACHED_MHD + "CompressedData = True\nElementDataFile = short_zlib_data.zraw\n")
DETACHED_NHDR = "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nspacings: 1 1 1\nendian: little\n"
w("short_data.nhdr", DETACHED_NHDR + "encoding: raw\ndata file: short_data.raw\n")
w("short_gzip_data.raw.gz", gzip.compress(b"\0" * 100, mtime=0))
w("short_gzip_data.nhdr", DETACHED_NHDR + "encoding: gzip\ndata file: short_gzip_data.raw.gz\n")
w("missing_data.nhdr", DETACHED_NHDR + "encoding: raw\ndata file: no_such_data.raw\n")
# DICOM series (folders) with a slice whose pixel data is missing or cut short are not made
# here (no DICOM writer in Python's standard library): dicom_missing_pixels/ and
# dicom_short_pixels/ hold a 4-slice 4x3 int16 series written by ITK's GDCMImageIO
# (tests/io/dicom_writer.cpp), with s1.dcm cut before its (7FE0,0010) element, or 6 bytes
# into the end of its 24 pixel bytes.
