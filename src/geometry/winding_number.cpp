// SPDX-License-Identifier: Apache-2.0
#include "ido/geometry/winding_number.h"

#include <cmath>

#include "bvh_build.h"
#include "ido/core/parallel.h"
#include "ido/geometry/mesh_topology.h"

namespace ido::geometry {

double solid_angle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Van Oosterom & Strackee: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)
  // with a, b, c relative to p. The determinant is positive when p lies behind the
  // triangle's normal (inside an outward surface).
  const Vec3 u = a - p;
  const Vec3 v = b - p;
  const Vec3 w = c - p;
  const double lu = u.norm(), lv = v.norm(), lw = w.norm();
  const double det = u.dot(v.cross(w));
  const double den = lu * lv * lw + u.dot(v) * lw + v.dot(w) * lu + w.dot(u) * lv;
  return 2.0 * std::atan2(det, den);
}

WindingNumber::WindingNumber(const TriangleMesh& mesh, const WindingNumberOptions& options)
    : m_beta(options.beta) {
  validate_mesh(mesh);
  const std::size_t nt = mesh.triangles.size();
  const detail::BvhTree tree = detail::build_triangle_bvh(mesh, options.leaf_size);
  m_corners.resize(nt);
  for (std::size_t s = 0; s < nt; ++s) {
    const Tri& tri = mesh.triangles[static_cast<std::size_t>(tree.order[s])];
    m_corners[s] = {mesh.vertices[static_cast<std::size_t>(tri[0])],
                    mesh.vertices[static_cast<std::size_t>(tri[1])],
                    mesh.vertices[static_cast<std::size_t>(tri[2])]};
  }
  m_nodes.resize(tree.nodes.size());
  // Children always have larger indices than their parent: fill bottom-up by reverse order.
  // First pass (reverse): slot ranges and first-order data.
  std::vector<std::int32_t> range_begin(tree.nodes.size());
  std::vector<std::int32_t> range_end(tree.nodes.size());
  for (std::size_t i = tree.nodes.size(); i-- > 0;) {
    const detail::BvhNode& bn = tree.nodes[i];
    Node& n = m_nodes[i];
    n.first = bn.first;
    n.count = bn.count;
    if (bn.leaf()) {
      range_begin[i] = bn.first;
      range_end[i] = bn.first + bn.count;
    } else {
      range_begin[i] = range_begin[static_cast<std::size_t>(bn.first)];
      range_end[i] = range_end[static_cast<std::size_t>(bn.first + 1)];
    }
  }
  // Per node: moments over its slot range (O(T log T) total, simple and exact).
  parallel_for(tree.nodes.size(), [&](std::size_t i) {
    Node& n = m_nodes[i];
    double area = 0.0;
    Vec3 weighted = Vec3::Zero();
    Vec3 na = Vec3::Zero();
    for (std::int32_t s = range_begin[i]; s < range_end[i]; ++s) {
      const auto& c = m_corners[static_cast<std::size_t>(s)];
      const Vec3 an = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]);
      const double ar = an.norm();
      area += ar;
      weighted += ar * (c[0] + c[1] + c[2]) / 3.0;
      na += an;
    }
    n.centre = area > 0.0 ? Vec3(weighted / area) : tree.nodes[i].box.centre();
    n.normal_area = na;
    n.moment.setZero();
    for (Mat3& m : n.second) m.setZero();
    double r2 = 0.0;
    for (std::int32_t s = range_begin[i]; s < range_end[i]; ++s) {
      const auto& c = m_corners[static_cast<std::size_t>(s)];
      const Vec3 an = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]);
      const Vec3 g = (c[0] + c[1] + c[2]) / 3.0;
      n.moment += (g - n.centre) * an.transpose();
      // ∫ (x − centre)(x − centre)ᵀ dA / area: shift of the centroid plus the covariance of
      // the uniform triangle, (1/12) Σ (v − g)(v − g)ᵀ.
      Mat3 cov = (g - n.centre) * (g - n.centre).transpose();
      for (const Vec3& x : c) cov += (x - g) * (x - g).transpose() / 12.0;
      for (int k = 0; k < 3; ++k) n.second[static_cast<std::size_t>(k)] += an[k] * cov;
      for (const Vec3& x : c) r2 = std::max(r2, (x - n.centre).squaredNorm());
    }
    n.radius = std::sqrt(r2);
  });
}

double WindingNumber::node_sum(const Vec3& p) const {
  double sum = 0.0;  // Σ solid angles (sr) of exact leaves, and 4π × far-field terms
  std::int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  const double beta2 = m_beta * m_beta;
  constexpr double kFourPi = 4.0 * kPi;
  while (top > 0) {
    const Node& n = m_nodes[static_cast<std::size_t>(stack[--top])];
    const Vec3 r = n.centre - p;  // from the query to the cluster
    const double d2 = r.squaredNorm();
    if (m_beta > 0.0 && d2 > beta2 * n.radius * n.radius) {
      // Solid angle of the cluster ≈ ∫ (x − p)·n / |x − p|³ dA, Taylor-expanded about the
      // centre to second order: Φ(r)·N + tr(J(r) M), Φ(r) = r/|r|³, J = ∇Φ = I/|r|³ − 3 r rᵀ/|r|⁵.
      const double d = std::sqrt(d2);
      const double inv3 = 1.0 / (d2 * d);
      const double inv5 = inv3 / d2;
      double term = r.dot(n.normal_area) * inv3;
      const Vec3 mr = n.moment * r;  // Σ area (c − centre) (n · r)
      term += n.moment.trace() * inv3 - 3.0 * r.dot(mr) * inv5;
      // Second-derivative term ½ Σ H_ijk T_ijk with
      // H_ijk = −3(δ_ij r_k + δ_ik r_j + δ_jk r_i)/|r|⁵ + 15 r_i r_j r_k/|r|⁷.
      double a1 = 0.0, a3 = 0.0, a4 = 0.0;
      for (int k = 0; k < 3; ++k) {
        const Mat3& t = n.second[static_cast<std::size_t>(k)];
        a1 += t.row(k).dot(r);
        a3 += r[k] * t.trace();
        a4 += r[k] * r.dot(t * r);
      }
      term += 0.5 * (-3.0 * inv5 * (2.0 * a1 + a3) + 15.0 * inv5 / d2 * a4);
      // Sign: Ω is positive for p behind the normal, where r·n > 0 — matches solid_angle().
      sum += term;
      continue;
    }
    if (n.count > 0) {
      for (std::int32_t s = n.first; s < n.first + n.count; ++s) {
        const auto& c = m_corners[static_cast<std::size_t>(s)];
        sum += solid_angle(p, c[0], c[1], c[2]);
      }
    } else {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
    }
  }
  return sum / kFourPi;
}

double WindingNumber::at(const Vec3& p) const {
  if (m_nodes.empty()) return 0.0;
  return node_sum(p);
}

std::vector<double> WindingNumber::at(const std::vector<Vec3>& points, bool threaded) const {
  std::vector<double> out(points.size());
  parallel_for(points.size(), [&](std::size_t i) { out[i] = at(points[i]); }, threaded, 64);
  return out;
}

double WindingNumber::exact_at(const Vec3& p) const {
  double sum = 0.0;
  for (const auto& c : m_corners) sum += solid_angle(p, c[0], c[1], c[2]);
  return sum / (4.0 * kPi);
}

}  // namespace ido::geometry
