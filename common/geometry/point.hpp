#pragma once
// Points and segments in the plane (Boost.Geometry's models, so every
// Boost.Geometry algorithm takes them), and poses applied to points.
#include <cmath>

#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/segment.hpp>

#include "geometry/pose2.hpp"

namespace pex::geometry {

using Point = boost::geometry::model::d2::point_xy<double>;
using Segment = boost::geometry::model::segment<Point>;

// A pose as a map of points: p in the pose's frame -> the same point in the
// frame the pose is expressed in (R(theta) p + (x, y)). The cosine and sine
// are computed once, for applying one pose to many points.
class PoseTransform {
 public:
  explicit PoseTransform(const Pose2& pose)
      : x_m_(pose.x_m), y_m_(pose.y_m), cos_(std::cos(pose.theta_rad)), sin_(std::sin(pose.theta_rad)) {}

  Point operator()(const Point& p) const {
    return Point(x_m_ + cos_ * p.x() - sin_ * p.y(), y_m_ + sin_ * p.x() + cos_ * p.y());
  }

 private:
  double x_m_, y_m_, cos_, sin_;
};

// One point through one pose (compose's translation for a point).
inline Point transform(const Pose2& pose, const Point& p) { return PoseTransform(pose)(p); }

}  // namespace pex::geometry
