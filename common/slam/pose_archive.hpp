#pragma once
// Poses in the filter's and the odometry pairing's checkpoints
// (archive/byte_archive.hpp): three doubles, bit for bit.
#include "archive/byte_archive.hpp"
#include "geometry/pose2.hpp"

namespace pex::slam {

using geometry::Pose2;

inline void put_pose(archive::ByteWriter& out, const Pose2& pose) {
  out.put<double>(pose.x_m);
  out.put<double>(pose.y_m);
  out.put<double>(pose.theta_rad);
}

inline Pose2 get_pose(archive::ByteReader& in) {
  Pose2 pose;
  pose.x_m = in.get<double>();
  pose.y_m = in.get<double>();
  pose.theta_rad = in.get<double>();
  return pose;
}

}  // namespace pex::slam
