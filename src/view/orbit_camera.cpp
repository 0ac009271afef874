// SPDX-License-Identifier: Apache-2.0
#include "ido/view/orbit_camera.h"

#include <algorithm>
#include <cmath>

namespace ido::view {
namespace {
constexpr double kDegPerPixel = 0.4;
constexpr double kFovYDeg = 30.0;
}  // namespace

void OrbitCamera::frame(const Vec3& lo, const Vec3& hi, double azimuth_deg, double elevation_deg) {
  const viz::Camera c = viz::Camera::orbit(lo, hi, azimuth_deg, elevation_deg, viz::Projection::Perspective, 1.0);
  m_target = c.target;
  m_distance_mm = 1.3 * c.distance_mm;  // room for views narrower than they are tall (down to 3:4)
  m_radius_mm = std::max(0.5 * (hi - lo).norm(), 1e-3);
  m_azimuth_deg = azimuth_deg;
  m_elevation_deg = elevation_deg;
}

void OrbitCamera::rotate(double dx_px, double dy_px) {
  m_azimuth_deg = std::fmod(m_azimuth_deg - kDegPerPixel * dx_px, 360.0);
  m_elevation_deg = std::clamp(m_elevation_deg + kDegPerPixel * dy_px, -89.0, 89.0);
}

void OrbitCamera::pan(double dx_px, double dy_px, double view_height_px) {
  const viz::Camera c = camera();
  const Mat4 v = c.view_matrix();
  const Vec3 right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
  const double mm_per_px =
      2.0 * m_distance_mm * std::tan(0.5 * kFovYDeg * kPi / 180.0) / std::max(1.0, view_height_px);
  m_target += mm_per_px * (-dx_px * right + dy_px * up);
}

void OrbitCamera::zoom(double notches) { m_distance_mm = std::max(1.0, m_distance_mm * std::pow(0.9, notches)); }

viz::Camera OrbitCamera::camera() const {
  viz::Camera c;
  const double az = m_azimuth_deg * kPi / 180.0, el = m_elevation_deg * kPi / 180.0;
  c.target = m_target;
  c.direction = Vec3(std::cos(el) * std::sin(az), -std::cos(el) * std::cos(az), std::sin(el));
  c.up = Vec3(0, 0, 1);
  c.distance_mm = m_distance_mm;
  c.projection = viz::Projection::Perspective;
  c.fov_y_deg = kFovYDeg;
  c.near_mm = std::max(1e-2 * m_distance_mm, m_distance_mm - 3.0 * m_radius_mm);
  c.far_mm = m_distance_mm + 3.0 * m_radius_mm;
  return c;
}

std::array<Vec3, 2> OrbitCamera::pick_ray(double x_px, double y_px, double width_px, double height_px) const {
  const viz::Camera c = camera();
  const Mat4 v = c.view_matrix();
  const Vec3 right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
  const Vec3 back = v.block<1, 3>(2, 0).transpose();  // the eye looks along −back
  const double t = std::tan(0.5 * kFovYDeg * kPi / 180.0);
  const double aspect = width_px / std::max(1.0, height_px);
  const double nx = 2.0 * x_px / width_px - 1.0, ny = 1.0 - 2.0 * y_px / height_px;
  const Vec3 dir = (-back + nx * t * aspect * right + ny * t * up).normalized();
  return {c.eye(), dir};
}

}  // namespace ido::view
