// SPDX-License-Identifier: Apache-2.0
// The scripted device: poses interpolated linearly and by slerp between keyframes and held
// beyond them, the session's end, the force record bounded by its capacity, the keyframe
// checks, and an 8-column CSV (threads_test covers the 4-column parser's line errors).
#include "ido/drill/haptic_device.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "ido/core/error.h"
#include "support/test_support.h"

namespace ido::drill {
namespace {

ToolPose pose(const Vec3& p, const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  ToolPose t;
  t.position_mm = p;
  t.orientation = q;
  return t;
}

TEST(ScriptedTrajectory, InterpolatesBetweenKeyframesAndHoldsBeyondThem) {
  const Eigen::Quaterniond q0(Eigen::AngleAxisd(0.0, Vec3::UnitZ())), q1(Eigen::AngleAxisd(1.2, Vec3::UnitZ()));
  ScriptedTrajectory s({0.5, 1.5, 3.5}, {pose(Vec3(0, 0, 0), q0), pose(Vec3(10, 0, 0), q1), pose(Vec3(10, 20, 0), q1)}, 16);
  EXPECT_EQ(s.duration(), 3.5);
  EXPECT_EQ(s.duration_s(), 3.5);
  EXPECT_TRUE(s.has_pose());
  // Linear in position; slerp in orientation (a quarter of the way: a quarter of the angle).
  const ToolPose a = s.pose_at(0.75);
  EXPECT_TRUE(a.position_mm.isApprox(Vec3(2.5, 0, 0), 1e-12));
  EXPECT_TRUE(test::near(Eigen::AngleAxisd(a.orientation).angle(), 0.3, 1e-12));
  EXPECT_TRUE(s.pose_at(3.0).position_mm.isApprox(Vec3(10, 15, 0), 1e-12));
  // At keyframes: the keyframe; before the first and after the last: held.
  EXPECT_EQ(s.pose_at(1.5).position_mm, Vec3(10, 0, 0));
  EXPECT_EQ(s.pose_at(-4.0).position_mm, Vec3(0, 0, 0));
  EXPECT_EQ(s.pose_at(0.5).position_mm, Vec3(0, 0, 0));
  EXPECT_EQ(s.pose_at(100.0).position_mm, Vec3(10, 20, 0));
  EXPECT_TRUE(s.pose_at(100.0).orientation.isApprox(q1));
  // read_pose is pose_at; the session ends after the last keyframe.
  EXPECT_EQ(s.read_pose(2.5).position_mm, s.pose_at(2.5).position_mm);
  EXPECT_FALSE(s.finished(3.5));
  EXPECT_TRUE(s.finished(3.5 + 1e-9));
  // One keyframe: a pose held for ever, duration its time.
  const ScriptedTrajectory still({0.0}, {pose(Vec3(1, 2, 3))}, 0);
  EXPECT_EQ(still.pose_at(7.0).position_mm, Vec3(1, 2, 3));
  EXPECT_EQ(still.duration(), 0.0);
}

TEST(ScriptedTrajectory, RecordsForcesUpToItsCapacity) {
  ScriptedTrajectory s({0.0, 1.0}, {pose(Vec3::Zero()), pose(Vec3::UnitX())}, 3);
  EXPECT_TRUE(s.forces().empty());
  for (int i = 0; i < 5; ++i) s.write_force(Vec3(i, 0, 0), 0.1 * i);
  ASSERT_EQ(s.forces().size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(s.forces()[i].t_s, 0.1 * double(i));
    EXPECT_EQ(s.forces()[i].force_n, Vec3(double(i), 0, 0));
  }
}

TEST(ScriptedTrajectory, BadKeyframesAreRefusedNamingTheKeyframe) {
  auto message = [](std::vector<double> t, std::vector<ToolPose> p) -> std::string {
    try {
      ScriptedTrajectory s(std::move(t), std::move(p), 1);
    } catch (const InvalidInput& e) {
      return e.what();
    }
    return "accepted";
  };
  const ToolPose p0 = pose(Vec3::Zero());
  EXPECT_NE(message({}, {}), "accepted");
  EXPECT_NE(message({0.0, 1.0}, {p0}), "accepted");
  EXPECT_NE(message({0.0, 1.0, 1.0}, {p0, p0, p0}).find("keyframe 2"), std::string::npos);
  EXPECT_NE(message({0.0, 2.0, 1.0}, {p0, p0, p0}).find("keyframe 2"), std::string::npos);
  EXPECT_NE(message({0.0, std::nan("")}, {p0, p0}).find("keyframe 1"), std::string::npos);
  ToolPose far = p0;
  far.position_mm.x() = std::numeric_limits<double>::infinity();
  EXPECT_NE(message({0.0, 1.0}, {p0, far}).find("keyframe 1"), std::string::npos);
  ToolPose zero = p0;
  zero.orientation = Eigen::Quaterniond(0, 0, 0, 0);
  EXPECT_NE(message({0.0, 1.0}, {p0, zero}).find("keyframe 1"), std::string::npos);
  const std::string too_long = message({0.0, 4000.0}, {p0, p0});
  EXPECT_NE(too_long.find("4000"), std::string::npos) << too_long;
  EXPECT_NE(too_long.find("keyframe 1"), std::string::npos) << too_long;
}

TEST(ScriptedTrajectory, EightColumnCsvCarriesTheOrientation) {
  const auto dir = test::scratch_dir("haptic_device_csv");
  {
    std::ofstream f(dir / "path.csv");
    // t, x, y, z, qx, qy, qz, qw: a half turn about z over 2 s (the quaternion need not be unit).
    f << "# burr path\nt,x,y,z,qx,qy,qz,qw\n\n0,0,0,5,0,0,0,2\n2,4,0,5,0,0,1,0\n";
  }
  const auto s = ScriptedTrajectory::load_csv(dir / "path.csv", 8);
  ASSERT_EQ(s.times().size(), 2U);
  EXPECT_EQ(s.duration(), 2.0);
  const ToolPose mid = s.pose_at(1.0);
  EXPECT_TRUE(mid.position_mm.isApprox(Vec3(2, 0, 5), 1e-12));
  EXPECT_TRUE(test::near(Eigen::AngleAxisd(mid.orientation.normalized()).angle(), kPi / 2, 1e-9));
  // A zero quaternion is refused at its line.
  {
    std::ofstream f(dir / "zero.csv");
    f << "0,0,0,5,0,0,0,1\n1,0,0,5,0,0,0,0\n";
  }
  try {
    (void)ScriptedTrajectory::load_csv(dir / "zero.csv", 1);
    FAIL() << "zero quaternion accepted";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), (dir / "zero.csv").string());
    EXPECT_EQ(e.location().line, 2);
  }
  // Five columns are neither form.
  {
    std::ofstream f(dir / "five.csv");
    f << "0,0,0,5,1\n";
  }
  try {
    (void)ScriptedTrajectory::load_csv(dir / "five.csv", 1);
    FAIL() << "five columns accepted";
  } catch (const IoError& e) {
    EXPECT_NE(e.problem().find("found 5"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "empty.csv") << "# nothing\n";
  EXPECT_THROW((void)ScriptedTrajectory::load_csv(dir / "empty.csv", 1), IoError);
}

}  // namespace
}  // namespace ido::drill
