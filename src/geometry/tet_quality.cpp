// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/tet_quality.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "ido/core/error.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/predicates.h"

namespace ido::geometry {
namespace {

/// Local faces of a tetrahedron (a, b, c, d) = (0, 1, 2, 3), each outward for a positive one.
constexpr std::array<std::array<int, 3>, 4> kFaces{{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};

void validate_tets(const TetMesh& mesh) {
  const auto n = static_cast<std::int64_t>(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!mesh.vertices[v].allFinite()) {
      throw InvalidInput("tetrahedral mesh: vertex " + std::to_string(v) +
                         " has a coordinate that is not finite");
    }
  }
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    for (const std::int32_t v : mesh.tets[t]) {
      if (v < 0 || v >= n) {
        throw InvalidInput("tetrahedral mesh: tetrahedron " + std::to_string(t) +
                           " has vertex index " + std::to_string(v) + " outside [0, " +
                           std::to_string(n) + ")");
      }
    }
  }
}

double angle_at_edge(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const Vec3 e = q - p;
  const double len2 = e.squaredNorm();
  if (len2 == 0.0) return 0.0;
  // Components of r − p and s − p orthogonal to the edge; the angle between them is the
  // dihedral angle at the edge.
  const Vec3 u = (r - p) - e * ((r - p).dot(e) / len2);
  const Vec3 w = (s - p) - e * ((s - p).dot(e) / len2);
  const double cross = u.cross(w).norm();
  const double dot = u.dot(w);
  if (cross == 0.0 && dot == 0.0) return 0.0;
  return std::atan2(cross, dot) * 180.0 / kPi;
}

struct FaceRecord {
  std::array<std::int32_t, 3> key;  // sorted vertex ids
  std::int32_t tet;
  std::int8_t local;
};

}  // namespace

double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

std::array<double, 6> dihedral_angles_deg(const Vec3& a, const Vec3& b, const Vec3& c,
                                          const Vec3& d) {
  return {angle_at_edge(a, b, c, d), angle_at_edge(a, c, b, d), angle_at_edge(a, d, b, c),
          angle_at_edge(b, c, a, d), angle_at_edge(b, d, a, c), angle_at_edge(c, d, a, b)};
}

double mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double sum_l2 = (b - a).squaredNorm() + (c - a).squaredNorm() + (d - a).squaredNorm() +
                        (c - b).squaredNorm() + (d - b).squaredNorm() + (d - c).squaredNorm();
  if (sum_l2 == 0.0) return 0.0;
  const double v = tet_signed_volume(a, b, c, d);
  const double eta = 12.0 * std::pow(3.0 * std::abs(v), 2.0 / 3.0) / sum_l2;
  return v < 0.0 ? -eta : eta;
}

TriangleMesh tet_boundary(const TetMesh& mesh) {
  validate_tets(mesh);
  std::vector<FaceRecord> faces;
  faces.reserve(mesh.tets.size() * 4);
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<std::int32_t, 3> k{};
      for (int i = 0; i < 3; ++i) {
        k[static_cast<std::size_t>(i)] =
            mesh.tets[t][static_cast<std::size_t>(kFaces[static_cast<std::size_t>(f)][static_cast<std::size_t>(i)])];
      }
      std::sort(k.begin(), k.end());
      faces.push_back({k, static_cast<std::int32_t>(t), static_cast<std::int8_t>(f)});
    }
  }
  std::vector<FaceRecord> sorted = faces;
  std::sort(sorted.begin(), sorted.end(),
            [](const FaceRecord& x, const FaceRecord& y) { return x.key < y.key; });
  std::vector<char> single(faces.size(), 0);
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i;
    while (j < sorted.size() && sorted[j].key == sorted[i].key) ++j;
    if (j - i == 1) {
      single[static_cast<std::size_t>(sorted[i].tet) * 4 + static_cast<std::size_t>(sorted[i].local)] = 1;
    }
    i = j;
  }
  TriangleMesh out;
  out.vertices = mesh.vertices;
  out.point_fields = mesh.point_fields;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!single[i]) continue;
    const Tet& tet = mesh.tets[static_cast<std::size_t>(faces[i].tet)];
    const auto& lf = kFaces[static_cast<std::size_t>(faces[i].local)];
    out.triangles.push_back({tet[static_cast<std::size_t>(lf[0])], tet[static_cast<std::size_t>(lf[1])],
                             tet[static_cast<std::size_t>(lf[2])]});
  }
  return out;
}

TetMeshReport check_tet_mesh(const TetMesh& mesh) {
  validate_tets(mesh);
  TetMeshReport r;
  r.vertices = mesh.vertices.size();
  r.tets = mesh.tets.size();
  if (mesh.tets.empty()) return r;
  r.min_dihedral_deg = std::numeric_limits<double>::infinity();
  r.max_dihedral_deg = -std::numeric_limits<double>::infinity();
  r.min_mean_ratio = std::numeric_limits<double>::infinity();
  double sum_ratio = 0.0;
  for (const Tet& t : mesh.tets) {
    const Vec3& a = mesh.vertices[static_cast<std::size_t>(t[0])];
    const Vec3& b = mesh.vertices[static_cast<std::size_t>(t[1])];
    const Vec3& c = mesh.vertices[static_cast<std::size_t>(t[2])];
    const Vec3& d = mesh.vertices[static_cast<std::size_t>(t[3])];
    const double o = orient3d(a, b, c, d);
    if (o < 0.0) ++r.inverted;
    if (o == 0.0) ++r.degenerate;
    r.volume_mm3 += tet_signed_volume(a, b, c, d);
    for (const double ang : dihedral_angles_deg(a, b, c, d)) {
      r.min_dihedral_deg = std::min(r.min_dihedral_deg, ang);
      r.max_dihedral_deg = std::max(r.max_dihedral_deg, ang);
    }
    const double q = mean_ratio(a, b, c, d);
    r.min_mean_ratio = std::min(r.min_mean_ratio, q);
    sum_ratio += q;
  }
  r.mean_mean_ratio = sum_ratio / static_cast<double>(mesh.tets.size());

  // Faces shared by more than two tetrahedra make the boundary non-manifold.
  std::vector<std::array<std::int32_t, 3>> keys;
  keys.reserve(mesh.tets.size() * 4);
  for (const Tet& t : mesh.tets) {
    for (const auto& f : kFaces) {
      std::array<std::int32_t, 3> k{t[static_cast<std::size_t>(f[0])], t[static_cast<std::size_t>(f[1])],
                                    t[static_cast<std::size_t>(f[2])]};
      std::sort(k.begin(), k.end());
      keys.push_back(k);
    }
  }
  std::sort(keys.begin(), keys.end());
  bool faces_ok = true;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    if (j - i > 2) faces_ok = false;
    i = j;
  }
  const TriangleMesh boundary = tet_boundary(mesh);
  r.boundary_faces = boundary.triangles.size();
  const MeshCheckReport surf = check_mesh(boundary);
  r.boundary_closed = surf.closed;
  r.boundary_manifold = faces_ok && surf.edge_manifold && surf.vertex_manifold;
  return r;
}

}  // namespace ido::geometry
