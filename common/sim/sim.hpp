#pragma once
// Simulator logic: worlds as wall segments read from WKT, a ray-cast laser
// through a spatial index, and a differential-drive plant with an odometry
// error model. No I/O and no clock: text, time steps and seeds come in.
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "kinematics/kinematics.hpp"

namespace pex::sim {

using geometry::Pose2;

struct Wall {
  double x0, y0, x1, y1;  // m
  // A glass pane: it stops the robot as any wall, but the laser sees it only
  // near its normal (LaserOptions::glass_max_incidence_deg); a beam meeting it
  // more obliquely goes through to whatever stands behind.
  bool glass = false;
};

struct World {
  std::string origin;             // file name, for messages
  std::vector<Wall> walls;
  Pose2 start;                    // from the START line (origin, facing +x, if none)
  double min_x = 0, min_y = 0, max_x = 0, max_y = 0;  // bounds of all walls
};

struct WorldError {
  std::string message;  // "<origin>:<line>: what is wrong"
};

// Parses a world file's text (see worlds/*.wkt): '#' comment lines, an
// optional "START x y theta" line, and WKT geometries (LINESTRING,
// MULTILINESTRING, POLYGON, MULTIPOLYGON), each possibly over several lines
// and each possibly after the word GLASS ("GLASS LINESTRING (...)": its
// edges are glass panes). Every edge becomes a wall. Errors name the line; non-finite or absurd
// coordinates (|c| > 1e5 m), a POLYGON ring that is not closed, a world
// without walls, and a START outside the walls' extent or inside a solid
// POLYGON are errors; zero-length edges are dropped.
std::variant<World, WorldError> parse_world(std::string_view text, const std::string& origin);

// Casts rays against the walls through an R-tree over the wall segments.
class RayCaster {
 public:
  explicit RayCaster(const World& world);
  ~RayCaster();
  RayCaster(RayCaster&&) noexcept;
  RayCaster& operator=(RayCaster&&) noexcept;

  // Distance (m) from (x, y) along `angle_rad` to the nearest wall, glass
  // or not (what the robot's body runs into), or `max_range_m` when no wall
  // is closer.
  double cast(double x, double y, double angle_rad, double max_range_m) const;
  // What a laser beam sees: as cast(), but a glass pane stops the beam only
  // when the beam meets it within glass_max_incidence_rad of its normal (the
  // pane's specular reflection back to the scanner); beyond that the beam
  // passes through it.
  double cast_beam(double x, double y, double angle_rad, double max_range_m, double glass_max_incidence_rad) const;
  // Distance (m) from (x, y) to the nearest wall, or `max_m` when none is closer.
  double clearance(double x, double y, double max_m) const;
  std::size_t wall_count() const;

 private:
  struct Index;
  std::unique_ptr<Index> index_;
};

// "" if a robot of radius robot_radius_m at world.start touches no wall, else
// why not (naming the world file): the simulator refuses such a start.
std::string check_start_clearance(const World& world, const RayCaster& walls, double robot_radius_m);

// The LMS111 by default: 270 deg in 0.5 deg steps = 541 beams, 20 m, 25 Hz.
struct LaserOptions {
  double fov_deg = 270.0;
  double step_deg = 0.5;
  double max_range_m = 20.0;
  double min_range_m = 0.05;          // closer walls read as no return
  double range_noise_sigma_m = 0.012; // Gaussian, per beam
  double rate_hz = 25.0;
  // Sensor pose on the robot (m, m, rad).
  double mount_x_m = 0.0, mount_y_m = 0.0, mount_theta_rad = 0.0;
  // A glass pane returns a beam only within this angle of its normal; a
  // scanner like the LMS1xx sees clean glass head-on and looks through it
  // at a slant. 90: glass is seen as any wall; 0: never.
  double glass_max_incidence_deg = 10.0;

  int beam_count() const;             // fov / step + 1
  double first_angle_rad() const;     // -fov/2, relative to the sensor x axis
  std::string validate() const;       // "" when usable
};

// A laser scanner: ranges in metres for the beams from first_angle_rad()
// counter-clockwise; `max_range_m` for beams that hit nothing within range
// (or closer than min_range_m). Noise comes from its own seeded generator,
// so the same seed and poses give the same scans.
class Laser {
 public:
  Laser(LaserOptions options, std::uint64_t seed);
  std::vector<float> scan(const RayCaster& caster, const Pose2& robot_pose);
  const LaserOptions& options() const { return options_; }

 private:
  LaserOptions options_;
  std::mt19937_64 rng_;
};

// The ground truth of a differential-drive robot. The wheels turn as the
// drives say; the robot moves by the *true* geometry (nominal values with a
// bias) and each wheel's ground contact slips randomly, so odometry computed
// with the nominal geometry drifts from the truth as on a real base.
class DiffDrivePlant {
 public:
  struct Options {
    double wheel_radius_m = 0.1;     // nominal
    double wheel_base_m = 0.5;       // nominal
    double left_radius_bias = 0.0;   // true radius = nominal * (1 + bias)
    double right_radius_bias = 0.0;
    double wheel_base_bias = 0.0;    // true base = nominal * (1 + bias)
    double slip_sigma = 0.0;         // relative std-dev of each wheel's ground travel per step
    double robot_radius_m = 0.25;    // for collisions with walls
    std::string validate() const;
  };
  DiffDrivePlant(Options options, Pose2 start, std::uint64_t seed);

  // Advances by dt_s with the wheels turning at the given rates (rad/s).
  // With a caster, motion that would put the robot's centre within
  // robot_radius_m of a wall is refused (the robot stops at the wall), and
  // contacts with walls are counted.
  void step(double dt_s, double left_wheel_radps, double right_wheel_radps,
            const RayCaster* caster = nullptr);
  const Pose2& pose() const { return pose_; }
  double v_mps() const { return v_; }
  double omega_radps() const { return omega_; }
  // Steps in which a motion into a wall was refused (pressing on a wall for a
  // second at 200 Hz counts 200).
  std::uint64_t refused_steps() const { return refused_steps_; }
  // Contacts begun: steps in which the disk touches a wall (within
  // robot_radius_m, or a motion into one refused) after having been clear of
  // every wall by more than kContactClearanceM. Pressing on a wall, or
  // turning on the spot against it, is one contact.
  std::uint64_t contacts() const { return contacts_; }
  bool in_contact() const { return in_contact_; }
  // A refused step leaves the disk up to one step's travel (a few mm) short of
  // the wall; it is clear again only beyond this, so it cannot count one push twice.
  static constexpr double kContactClearanceM = 0.01;

 private:
  Options options_;
  Pose2 pose_;
  std::mt19937_64 rng_;
  double v_ = 0.0, omega_ = 0.0;
  std::uint64_t refused_steps_ = 0;
  std::uint64_t contacts_ = 0;
  bool in_contact_ = false;
};

}  // namespace pex::sim
