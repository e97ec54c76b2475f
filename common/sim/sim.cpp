#include "sim/sim.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include <boost/geometry.hpp>
#include <boost/geometry/geometries/linestring.hpp>
#include <boost/geometry/geometries/multi_linestring.hpp>
#include <boost/geometry/geometries/multi_polygon.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#include <boost/geometry/geometries/segment.hpp>
#include <boost/geometry/index/rtree.hpp>

#include "geometry/point.hpp"
#include "geometry/wkt_text.hpp"

namespace pex::sim {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;
using geometry::Point;
using geometry::Segment;
using Linestring = bg::model::linestring<Point>;
using MultiLinestring = bg::model::multi_linestring<Linestring>;
using Polygon = bg::model::polygon<Point>;
using MultiPolygon = bg::model::multi_polygon<Polygon>;

namespace {

using geometry::leading_keyword;
using geometry::trim_blanks;

// Adds the edges of a point sequence; false when a coordinate is bad.
template <class Range>
bool add_edges(const Range& points, std::vector<Wall>& walls) {
  const Point* previous = nullptr;
  for (const Point& p : points) {
    if (!geometry::file_coordinates_ok(p.x(), p.y())) return false;
    if (previous && (previous->x() != p.x() || previous->y() != p.y())) {
      walls.push_back(Wall{previous->x(), previous->y(), p.x(), p.y()});
    }
    previous = &p;
  }
  return true;
}

// A solid obstacle: its rings must be closed (a ring that is not would leave
// an edge out, a gap in the obstacle nobody meant), and it is kept to tell
// whether START is inside it.
std::string add_polygon(const Polygon& polygon, std::vector<Wall>& walls, std::vector<Polygon>& solids) {
  if (auto open = geometry::unclosed_ring(polygon); !open.empty()) return open;
  if (!add_edges(polygon.outer(), walls)) return geometry::kBadFileCoordinate;
  for (const auto& inner : polygon.inners()) {
    if (!add_edges(inner, walls)) return geometry::kBadFileCoordinate;
  }
  solids.push_back(polygon);
  return "";
}

// Parses one WKT geometry into walls (and solids); returns an error text or "".
std::string add_geometry(const std::string& wkt, std::vector<Wall>& walls, std::vector<Polygon>& solids) {
  const std::string keyword = leading_keyword(wkt);
  try {
    bool ok = true;
    if (keyword == "LINESTRING") {
      Linestring g;
      bg::read_wkt(wkt, g);
      ok = add_edges(g, walls);
    } else if (keyword == "MULTILINESTRING") {
      MultiLinestring g;
      bg::read_wkt(wkt, g);
      for (const auto& l : g) ok = ok && add_edges(l, walls);
    } else if (keyword == "POLYGON") {
      Polygon g;
      bg::read_wkt(wkt, g);
      return add_polygon(g, walls, solids);
    } else if (keyword == "MULTIPOLYGON") {
      MultiPolygon g;
      bg::read_wkt(wkt, g);
      for (const auto& p : g)
        if (std::string error = add_polygon(p, walls, solids); !error.empty()) return error;
    } else {
      return "unsupported geometry '" + keyword.substr(0, 24) +
             "' (use LINESTRING, MULTILINESTRING, POLYGON, MULTIPOLYGON, any of them after GLASS, or START)";
    }
    if (!ok) return "coordinate not finite or beyond 1e5 m";
  } catch (const std::exception& e) {
    return std::string("bad WKT: ") + e.what();
  }
  return "";
}

}  // namespace

std::variant<World, WorldError> parse_world(std::string_view text, const std::string& origin) {
  World world;
  world.origin = origin;
  bool have_start = false;
  int start_line = 0;
  std::vector<Polygon> solids;
  std::string pending;       // a geometry spread over several lines
  int pending_line = 0;
  bool pending_glass = false;  // the pending geometry came after GLASS
  int depth = 0;
  int line_number = 0;
  std::size_t pos = 0;
  auto fail = [&](int line, const std::string& what) {
    return WorldError{origin + ":" + std::to_string(line) + ": " + what};
  };
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string line = trim_blanks(text.substr(pos, end - pos));
    pos = end + 1;
    ++line_number;
    if (line.empty() || line[0] == '#') {
      if (end == text.size()) break;
      continue;
    }
    if (pending.empty() && leading_keyword(line) == "START" && line.size() > 5 && line[5] == ' ') {
      if (have_start) return fail(line_number, "second START line");
      std::istringstream in(line.substr(5));
      double x = NAN, y = NAN, theta = NAN;
      std::string rest;
      if (!(in >> x >> y >> theta) || (in >> rest) || !std::isfinite(x) || !std::isfinite(y) ||
          !std::isfinite(theta)) {
        return fail(line_number, "START needs three finite numbers: x_m y_m theta_rad");
      }
      world.start = Pose2{x, y, geometry::wrap_angle(theta)};
      have_start = true;
      start_line = line_number;
      continue;
    }
    std::string geometry_text = line;
    if (pending.empty()) {
      pending_line = line_number;
      pending_glass = leading_keyword(line) == "GLASS";
      if (pending_glass) {
        geometry_text = trim_blanks(std::string_view(line).substr(5));
        if (line.size() <= 5 || line[5] != ' ' || geometry_text.empty())
          return fail(line_number, "GLASS needs a geometry after it: GLASS LINESTRING (x y, ...)");
      }
    }
    pending += (pending.empty() ? "" : " ") + geometry_text;
    for (char c : geometry_text) {
      if (c == '(') ++depth;
      if (c == ')') --depth;
    }
    if (depth < 0) return fail(pending_line, "unbalanced ')'");
    if (depth > 0) {
      if (end == text.size()) break;
      continue;
    }
    const std::size_t first_wall = world.walls.size();
    const std::string error = add_geometry(pending, world.walls, solids);
    if (!error.empty()) return fail(pending_line, error);
    for (std::size_t i = first_wall; i < world.walls.size(); ++i) world.walls[i].glass = pending_glass;
    pending.clear();
    if (end == text.size()) break;
  }
  if (!pending.empty()) return fail(pending_line, "geometry not closed (missing ')')");
  if (world.walls.empty()) return WorldError{origin + ": no walls"};
  world.min_x = world.min_y = std::numeric_limits<double>::infinity();
  world.max_x = world.max_y = -std::numeric_limits<double>::infinity();
  for (const Wall& w : world.walls) {
    world.min_x = std::min({world.min_x, w.x0, w.x1});
    world.min_y = std::min({world.min_y, w.y0, w.y1});
    world.max_x = std::max({world.max_x, w.x0, w.x1});
    world.max_y = std::max({world.max_y, w.y0, w.y1});
  }
  // The robot must start on the floor: within the walls' extent, and not
  // inside a solid obstacle. (How close to a wall it may be is the robot's
  // size: the simulator checks that.)
  const Point start(world.start.x_m, world.start.y_m);
  const std::string where = "START (" + std::to_string(start.x()) + ", " + std::to_string(start.y()) + ")" +
                            (have_start ? "" : " (no START line: the origin)");
  if (start.x() < world.min_x || start.x() > world.max_x || start.y() < world.min_y || start.y() > world.max_y)
    return fail(start_line, where + " is outside the world: its walls span x " + std::to_string(world.min_x) + " .. " +
                                std::to_string(world.max_x) + ", y " + std::to_string(world.min_y) + " .. " +
                                std::to_string(world.max_y));
  for (const Polygon& solid : solids)
    if (bg::within(start, solid)) return fail(start_line, where + " is inside a solid obstacle (a POLYGON)");
  return world;
}

std::string check_start_clearance(const World& world, const RayCaster& walls, double robot_radius_m) {
  const double clearance = walls.clearance(world.start.x_m, world.start.y_m, robot_radius_m + 1.0);
  if (clearance >= robot_radius_m) return "";
  return world.origin + ": START (" + std::to_string(world.start.x_m) + ", " + std::to_string(world.start.y_m) +
         ") is " + std::to_string(clearance) + " m from a wall, less than the robot's radius " +
         std::to_string(robot_radius_m) + " m: the robot would start in a wall";
}

// ---------------------------------------------------------------- ray caster --

struct RayCaster::Index {
  bgi::rtree<std::pair<Segment, std::size_t>, bgi::quadratic<16>> tree;
  std::vector<Wall> walls;
};

RayCaster::RayCaster(const World& world) : index_(std::make_unique<Index>()) {
  index_->walls = world.walls;
  std::vector<std::pair<Segment, std::size_t>> values;
  values.reserve(world.walls.size());
  for (std::size_t i = 0; i < world.walls.size(); ++i) {
    const Wall& w = world.walls[i];
    values.emplace_back(Segment(Point(w.x0, w.y0), Point(w.x1, w.y1)), i);
  }
  index_->tree = decltype(index_->tree)(values);  // packing constructor: a balanced tree
}
RayCaster::~RayCaster() = default;
RayCaster::RayCaster(RayCaster&&) noexcept = default;
RayCaster& RayCaster::operator=(RayCaster&&) noexcept = default;

std::size_t RayCaster::wall_count() const { return index_->walls.size(); }

double RayCaster::cast(double x, double y, double angle_rad, double max_range_m) const {
  return cast_beam(x, y, angle_rad, max_range_m, std::numbers::pi / 2);
}

double RayCaster::cast_beam(double x, double y, double angle_rad, double max_range_m,
                            double glass_max_incidence_rad) const {
  const double dx = std::cos(angle_rad), dy = std::sin(angle_rad);
  // A pane returns the beam when |cos| of the angle between beam and pane is
  // at most sin(max incidence): the beam is within that angle of the normal.
  const double glass_max_cos = std::sin(std::clamp(glass_max_incidence_rad, 0.0, std::numbers::pi / 2));
  const Segment ray(Point(x, y), Point(x + dx * max_range_m, y + dy * max_range_m));
  double best = max_range_m;
  // The R-tree yields the walls whose boxes the ray crosses and that intersect
  // it; the exact distance along the ray is computed here.
  for (auto it = index_->tree.qbegin(bgi::intersects(ray)); it != index_->tree.qend(); ++it) {
    const Wall& w = index_->walls[it->second];
    const double ex = w.x1 - w.x0, ey = w.y1 - w.y0;
    if (w.glass && glass_max_cos < 1.0 &&
        std::abs(dx * ex + dy * ey) > glass_max_cos * std::hypot(ex, ey))
      continue;  // a pane met at a slant: the beam goes through
    const double denom = dx * ey - dy * ex;
    const double qx = w.x0 - x, qy = w.y0 - y;
    if (std::abs(denom) < 1e-12) {
      // Parallel and touching (collinear): the nearer endpoint in front of us.
      for (double t : {qx * dx + qy * dy, (w.x1 - x) * dx + (w.y1 - y) * dy}) {
        if (t >= 0.0 && t < best) best = t;
      }
      continue;
    }
    const double t = (qx * ey - qy * ex) / denom;   // distance along the ray
    const double u = (qx * dy - qy * dx) / denom;   // position along the wall
    if (t >= 0.0 && u >= -1e-9 && u <= 1.0 + 1e-9 && t < best) best = t;
  }
  return best;
}

double RayCaster::clearance(double x, double y, double max_m) const {
  const bg::model::box<Point> near(Point(x - max_m, y - max_m), Point(x + max_m, y + max_m));
  double best = max_m;
  for (auto it = index_->tree.qbegin(bgi::intersects(near)); it != index_->tree.qend(); ++it) {
    const Wall& w = index_->walls[it->second];
    // Distance to the segment: to its closest point, the projection clamped to it.
    const double ex = w.x1 - w.x0, ey = w.y1 - w.y0;
    const double len2 = ex * ex + ey * ey;
    const double u = len2 > 0.0 ? std::clamp(((x - w.x0) * ex + (y - w.y0) * ey) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(w.x0 + u * ex - x, w.y0 + u * ey - y));
  }
  return best;
}

// --------------------------------------------------------------------- laser --

int LaserOptions::beam_count() const { return static_cast<int>(std::lround(fov_deg / step_deg)) + 1; }
double LaserOptions::first_angle_rad() const { return -0.5 * fov_deg * std::numbers::pi / 180.0; }
std::string LaserOptions::validate() const {
  if (!(fov_deg > 0.0 && fov_deg <= 360.0)) return "fov_deg must be in (0, 360]";
  if (!(step_deg > 0.0) || fov_deg / step_deg > 10000.0) return "step_deg must be > 0 and give <= 10000 beams";
  if (!(max_range_m > 0.0 && max_range_m < 1000.0)) return "max_range_m must be in (0, 1000)";
  if (!(min_range_m >= 0.0 && min_range_m < max_range_m)) return "min_range_m must be in [0, max_range_m)";
  if (!(range_noise_sigma_m >= 0.0 && range_noise_sigma_m < 1.0)) return "range_noise_sigma_m must be in [0, 1)";
  if (!(rate_hz > 0.0 && rate_hz <= 100.0)) return "rate_hz must be in (0, 100]";
  if (!(glass_max_incidence_deg >= 0.0 && glass_max_incidence_deg <= 90.0))
    return "glass_max_incidence_deg must be in [0, 90]";
  return "";
}

Laser::Laser(LaserOptions options, std::uint64_t seed) : options_(options), rng_(seed) {}

std::vector<float> Laser::scan(const RayCaster& caster, const Pose2& robot) {
  const int n = options_.beam_count();
  const Point sensor = geometry::transform(robot, Point(options_.mount_x_m, options_.mount_y_m));
  const double base = robot.theta_rad + options_.mount_theta_rad + options_.first_angle_rad();
  const double step = options_.step_deg * std::numbers::pi / 180.0;
  std::normal_distribution<double> noise(0.0, options_.range_noise_sigma_m);
  std::vector<float> ranges(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double r = caster.cast_beam(sensor.x(), sensor.y(), base + i * step, options_.max_range_m,
                                      options_.glass_max_incidence_deg * std::numbers::pi / 180.0);
    // Draw noise for every beam, hit or not, so one beam's outcome never
    // shifts the random sequence of the others.
    const double e = options_.range_noise_sigma_m > 0.0 ? noise(rng_) : 0.0;
    double reading = r >= options_.max_range_m ? options_.max_range_m : r + e;
    if (reading < options_.min_range_m) reading = options_.max_range_m;
    ranges[static_cast<std::size_t>(i)] = static_cast<float>(std::min(reading, options_.max_range_m));
  }
  return ranges;
}

// --------------------------------------------------------------------- plant --

std::string DiffDrivePlant::Options::validate() const {
  if (!(wheel_radius_m > 0.0) || !(wheel_base_m > 0.0)) return "wheel radius and base must be > 0";
  for (double b : {left_radius_bias, right_radius_bias, wheel_base_bias}) {
    if (!(std::abs(b) < 0.5)) return "biases must be within +-0.5";
  }
  if (!(slip_sigma >= 0.0 && slip_sigma < 0.5)) return "slip_sigma must be in [0, 0.5)";
  if (!(robot_radius_m >= 0.0)) return "robot_radius_m must be >= 0";
  return "";
}

DiffDrivePlant::DiffDrivePlant(Options options, Pose2 start, std::uint64_t seed)
    : options_(options), pose_(start), rng_(seed) {}

void DiffDrivePlant::step(double dt_s, double left_radps, double right_radps, const RayCaster* caster) {
  if (!(dt_s > 0.0) || !std::isfinite(left_radps) || !std::isfinite(right_radps)) {
    v_ = omega_ = 0.0;
    return;
  }
  std::normal_distribution<double> slip(0.0, options_.slip_sigma);
  const double slip_l = options_.slip_sigma > 0.0 ? slip(rng_) : 0.0;
  const double slip_r = options_.slip_sigma > 0.0 ? slip(rng_) : 0.0;
  const double dl = left_radps * dt_s * options_.wheel_radius_m * (1.0 + options_.left_radius_bias) * (1.0 + slip_l);
  const double dr = right_radps * dt_s * options_.wheel_radius_m * (1.0 + options_.right_radius_bias) * (1.0 + slip_r);
  const double base = options_.wheel_base_m * (1.0 + options_.wheel_base_bias);
  const double ds = 0.5 * (dl + dr);
  const double dtheta = (dr - dl) / base;
  const double mid = pose_.theta_rad + 0.5 * dtheta;
  Pose2 next{pose_.x_m + ds * std::cos(mid), pose_.y_m + ds * std::sin(mid),
             geometry::wrap_angle(pose_.theta_rad + dtheta)};
  bool refused = false;
  if (caster && std::abs(ds) > 0.0) {
    // Refuse translation into a wall (rotation in place is always allowed).
    const double heading = ds >= 0.0 ? mid : mid + std::numbers::pi;
    const double free = caster->cast(pose_.x_m, pose_.y_m, heading, std::abs(ds) + options_.robot_radius_m + 1.0);
    if (free < std::abs(ds) + options_.robot_radius_m) {
      ++refused_steps_;
      refused = true;
      next.x_m = pose_.x_m;
      next.y_m = pose_.y_m;
    }
  }
  if (caster) {
    // The refusal looks along the heading only: a disk sliding sideways or
    // turning near a corner can still touch, which the clearance sees.
    const double reach = options_.robot_radius_m + kContactClearanceM;
    const double clearance = caster->clearance(next.x_m, next.y_m, reach + 1.0);
    const bool touching = refused || clearance <= options_.robot_radius_m;
    if (touching && !in_contact_) ++contacts_;
    if (touching) in_contact_ = true;
    else if (clearance > reach) in_contact_ = false;
  }
  v_ = std::hypot(next.x_m - pose_.x_m, next.y_m - pose_.y_m) / dt_s * (ds < 0.0 ? -1.0 : 1.0);
  omega_ = dtheta / dt_s;
  pose_ = next;
}

}  // namespace pex::sim
