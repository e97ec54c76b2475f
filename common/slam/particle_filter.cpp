#include "slam/particle_filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include "archive/byte_archive.hpp"
#include "slam/pose_archive.hpp"

namespace pex::slam {
namespace {

// SplitMix64 finaliser: decorrelates seeds that differ in few bits.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

TrajectoryNode::~TrajectoryNode() {
  std::shared_ptr<const TrajectoryNode> next = std::move(parent);
  while (next && next.use_count() == 1) {
    // Detach the grandparent before `next` dies so its destructor finds no chain.
    std::shared_ptr<const TrajectoryNode> after =
        std::move(const_cast<TrajectoryNode&>(*next).parent);
    next = std::move(after);
  }
}

ParticleFilter::ParticleFilter(const ParticleFilterOptions& options, ParticleMapFactory map_factory)
    : options_(options), map_factory_(std::move(map_factory)), rng_(options.seed), drift_(options.odometry_drift) {
  options_.particle_count = std::max(1, options_.particle_count);
  grid_maps_ = !map_factory_;
  if (!map_factory_) {
    const CowGridMapOptions grid = options_.grid;
    map_factory_ = [grid] { return std::make_unique<CowGridMap>(grid); };
  }
}

bool ParticleFilter::process(const RangeScan& scan, const Pose2& odometry) {
  if (!is_finite(odometry)) return false;
  const ScanPoints points = to_scan_points(scan, options_.scan);
  if (!initialized_) {
    if (points.beams.empty()) return false;
    initialize(points, odometry, scan.utime);
    return true;
  }
  const Pose2 step = relative(last_odometry_, odometry);
  last_odometry_ = odometry;
  linear_since_update_m_ += std::hypot(step.x_m, step.y_m);
  angular_since_update_rad_ += std::abs(step.theta_rad);
  for (Particle& p : particles_) p.pose = sample_motion(p.pose, step, options_.motion, rng_);
  track_standing(scan.utime, odometry);
  if (points.beams.empty()) return false;
  const bool gated = linear_since_update_m_ >= options_.linear_update_m ||
                     angular_since_update_rad_ >= options_.angular_update_rad;
  if (!gated && !standing_update_due(scan.utime, odometry)) return false;
  standing_updates_ += !gated;
  update(points, odometry);
  return true;
}

void ParticleFilter::track_standing(std::int64_t utime, const Pose2& odometry) {
  // Written so that a pose that is not finite (a restored checkpoint's)
  // moves the anchor rather than holds it.
  const Pose2 moved = relative(standing_odometry_, odometry);
  if (!(std::hypot(moved.x_m, moved.y_m) <= options_.standing_tolerance_m) ||
      !(std::abs(moved.theta_rad) <= options_.standing_tolerance_rad) || utime < standing_since_utime_) {
    standing_odometry_ = odometry;
    standing_since_utime_ = utime;
  }
}

bool ParticleFilter::standing_update_due(std::int64_t utime, const Pose2& odometry) const {
  if (!(options_.standing_update_s > 0.0)) return false;
  // In double: stamps of any value (a checkpoint's) cannot overflow.
  const double stood_us = static_cast<double>(utime) - static_cast<double>(standing_since_utime_);
  if (!(stood_us >= options_.standing_update_s * 1e6)) return false;
  const Pose2 net = relative(odometry_at_update_, odometry);
  return std::hypot(net.x_m, net.y_m) > options_.standing_update_min_m ||
         std::abs(net.theta_rad) > options_.standing_update_min_rad;
}

void ParticleFilter::initialize(const ScanPoints& points, const Pose2& odometry, std::int64_t utime) {
  auto map = map_factory_();
  points_beyond_map_extent_ += static_cast<std::int64_t>(map->insert(odometry, points));
  auto root = std::make_shared<const TrajectoryNode>(odometry, 0, nullptr);
  particles_.clear();
  particles_.resize(static_cast<std::size_t>(options_.particle_count));
  for (Particle& p : particles_) {
    p.pose = odometry;
    p.pose_at_update = odometry;
    p.map = map->clone();  // all share the first scan's tiles
    p.trajectory = root;
    p.parent = -1;
  }
  initialized_ = true;
  generation_ = 0;
  last_odometry_ = odometry;
  odometry_at_update_ = odometry;
  linear_since_update_m_ = 0.0;
  angular_since_update_rad_ = 0.0;
  standing_odometry_ = odometry;
  standing_since_utime_ = utime;
  last_update_ = UpdateStats{};
  last_update_.effective_sample_size = static_cast<double>(particles_.size());
}

double ParticleFilter::check_odometry_step(const ScanPoints& match_points, const Pose2& odometry_step,
                                           UpdateStats& stats, std::optional<MatchResult>& measured_match) const {
  const OdometryCheckOptions& check = options_.odometry_check;
  if (!check.enabled || std::hypot(odometry_step.x_m, odometry_step.y_m) < check.min_translation_m) return 1.0;
  const Particle& best = particles_[best_index()];
  // The best particle's own motion noise since the update, kept whatever the step.
  const Pose2 noise = relative(compose(best.pose_at_update, odometry_step), best.pose);
  auto score = [&](double scale) {
    const Pose2 step{scale * odometry_step.x_m, scale * odometry_step.y_m, odometry_step.theta_rad};
    return match_scan(*best.map, match_points, compose(compose(best.pose_at_update, step), noise), options_.matcher)
        .evaluation.score;
  };
  // The measured step is the best particle's own pose: its match is the one
  // the update makes for that particle when the step stays, so it is kept.
  measured_match = match_scan(*best.map, match_points, best.pose, options_.matcher);
  const double measured = measured_match->evaluation.score;
  double chosen = 1.0;
  double chosen_score = measured * (1.0 + check.margin);
  double best_other = 0.0;
  for (const double scale : check.translation_scales) {
    const double s = score(scale);
    best_other = std::max(best_other, s);
    if (s > chosen_score) {
      chosen = scale;
      chosen_score = s;
    }
  }
  stats.odometry_check_ratio = measured > 0.0 ? best_other / measured : 0.0;
  return chosen;
}

void ParticleFilter::update(const ScanPoints& points, const Pose2& odometry) {
  UpdateStats stats;
  const std::size_t n = particles_.size();
  const ScanPoints match_points = matcher_beams(points, options_.matcher);
  const ScanPoints likelihood_points = proposal_beams(points, options_.proposal);
  Pose2 odometry_step = relative(odometry_at_update_, odometry);
  // Every particle keeps its own motion noise, moved onto a corrected step.
  auto move_onto = [&](const Pose2& corrected) {
    for (Particle& p : particles_) {
      const Pose2 noise = relative(compose(p.pose_at_update, odometry_step), p.pose);
      p.pose = compose(compose(p.pose_at_update, corrected), noise);
    }
    odometry_step = corrected;
  };
  // The step as the odometry measured it: the drift's evidence below.
  const double odometry_turn = odometry_step.theta_rad;
  const double odometry_forward = odometry_step.x_m;
  if (options_.odometry_drift.correct) {
    const Pose2 corrected = drift_.correct(odometry_step);
    if (corrected.theta_rad != odometry_step.theta_rad) move_onto(corrected);
  }
  std::optional<MatchResult> measured_match;
  const std::size_t checked = best_index();
  stats.odometry_scale = check_odometry_step(match_points, odometry_step, stats, measured_match);
  if (stats.odometry_scale != 1.0) {
    measured_match.reset();  // the particles move: every one is matched again
    move_onto({stats.odometry_scale * odometry_step.x_m, stats.odometry_scale * odometry_step.y_m,
               odometry_step.theta_rad});
    ++corrected_odometry_steps_;
  }
  const Pose2 step_std = motion_noise_std(odometry_step, options_.motion);
  const ScanConstraint constraint =
      options_.constraint.enabled ? scan_constraint(points, options_.constraint) : ScanConstraint{};
  stats.unconstrained_directions = static_cast<int>(std::lround(constraint.unconstrained.trace()));
  std::vector<int> evaluations(n, 0);
  std::vector<char> failed(n, 0);
  const std::uint64_t generation_seed = mix(options_.seed ^ mix(static_cast<std::uint64_t>(generation_ + 1)));
  auto match_particles = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Particle& p = particles_[i];
      std::mt19937_64 rng(mix(generation_seed + i));
      const Pose2 predicted = compose(p.pose_at_update, odometry_step);
      MatchResult match = i == checked && measured_match ? *measured_match
                                                         : match_scan(*p.map, match_points, p.pose, options_.matcher);
      if (constraint.degenerate()) {
        // Along what the scan does not constrain, the particle's motion-model
        // sample (p.pose) is the estimate, not where the climb ended.
        const double c = std::cos(match.pose.theta_rad), s = std::sin(match.pose.theta_rad);
        Eigen::Matrix2d rotation;
        rotation << c, -s, s, c;
        const Eigen::Vector2d gap(p.pose.x_m - match.pose.x_m, p.pose.y_m - match.pose.y_m);
        const Eigen::Vector2d shift = rotation * constraint.unconstrained * rotation.transpose() * gap;
        match.pose.x_m += shift.x();
        match.pose.y_m += shift.y();
      }
      evaluations[i] = match.evaluations;
      double increment = 0.0;
      if (match.evaluation.score > options_.matcher.minimum_score) {
        const ProposalResult proposal = sample_improved_proposal(
            *p.map, likelihood_points, match.pose, predicted, step_std, options_.proposal, rng);
        p.pose = proposal.pose;
        increment = proposal.log_weight_increment;
      } else {
        failed[i] = 1;
        increment = p.map->log_likelihood(p.pose, likelihood_points);
      }
      p.log_weight += increment;
      p.lineage_log_likelihood += increment;
      p.parent = static_cast<int>(i);
    }
  };
  const std::size_t threads = std::clamp<std::size_t>(static_cast<std::size_t>(std::max(1, options_.threads)), 1, n);
  if (threads == 1) {
    match_particles(0, n);
  } else {
    std::vector<std::thread> workers;
    for (std::size_t t = 1; t < threads; ++t)
      workers.emplace_back(match_particles, n * t / threads, n * (t + 1) / threads);
    match_particles(0, n / threads);
    for (auto& w : workers) w.join();
  }
  for (std::size_t i = 0; i < n; ++i) {
    stats.matcher_evaluations += evaluations[i];
    stats.failed_matches += failed[i];
  }
  ++generation_;
  const std::vector<double> weights = normalized_weights();
  double sum_sq = 0.0;
  for (double w : weights) sum_sq += w * w;
  stats.effective_sample_size = 1.0 / sum_sq;
  if (stats.effective_sample_size < options_.resample_threshold * static_cast<double>(particles_.size())) {
    resample(weights);
    stats.resampled = true;
  }
  // The best lineage's matched turn is evidence of the drift where the scan
  // pinned the pose (no unconstrained direction, every match trusted) and
  // the odometry step stood as measured.
  if (stats.unconstrained_directions == 0 && stats.failed_matches == 0 && stats.odometry_scale == 1.0) {
    const Particle& best = particles_[best_index()];
    drift_.observe(odometry_forward, odometry_turn, geometry::wrap_angle(best.pose.theta_rad - best.pose_at_update.theta_rad));
  }
  for (Particle& p : particles_) {
    stats.points_beyond_map_extent += p.map->insert(p.pose, points);
    p.pose_at_update = p.pose;
    p.trajectory = std::make_shared<const TrajectoryNode>(p.pose, generation_, std::move(p.trajectory));
  }
  odometry_at_update_ = odometry;
  linear_since_update_m_ = 0.0;
  angular_since_update_rad_ = 0.0;
  stats.generation = generation_;
  points_beyond_map_extent_ += static_cast<std::int64_t>(stats.points_beyond_map_extent);
  unconstrained_updates_ += stats.unconstrained_directions > 0;
  last_update_ = stats;
}

std::vector<double> ParticleFilter::normalized_weights() const {
  std::vector<double> weights(particles_.size());
  if (particles_.empty()) return weights;
  double max_lw = -std::numeric_limits<double>::infinity();
  for (const Particle& p : particles_) max_lw = std::max(max_lw, p.log_weight);
  const double gain = 1.0 / (options_.likelihood_gain * static_cast<double>(particles_.size()));
  double sum = 0.0;
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    weights[i] = std::isfinite(particles_[i].log_weight)
                     ? std::exp(gain * (particles_[i].log_weight - max_lw))
                     : 0.0;
    sum += weights[i];
  }
  if (!(sum > 0.0)) {
    std::fill(weights.begin(), weights.end(), 1.0 / static_cast<double>(weights.size()));
    return weights;
  }
  for (double& w : weights) w /= sum;
  return weights;
}

std::vector<int> systematic_resample(const std::vector<double>& weights, double first_pointer) {
  const std::size_t n = weights.size();
  std::vector<int> parents(n);
  if (n == 0) return parents;
  const double spacing = 1.0 / static_cast<double>(n);
  double target = first_pointer;
  double cumulative = weights[0];
  std::size_t source = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (target > cumulative && source + 1 < n) cumulative += weights[++source];
    parents[i] = static_cast<int>(source);
    target += spacing;
  }
  return parents;
}

void ParticleFilter::resample(const std::vector<double>& weights) {
  const std::size_t n = particles_.size();
  std::uniform_real_distribution<double> uniform(0.0, 1.0 / static_cast<double>(n));
  const std::vector<int> parents = systematic_resample(weights, uniform(rng_));
  std::vector<Particle> next(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Particle& parent = particles_[static_cast<std::size_t>(parents[i])];
    Particle& child = next[i];
    child.pose = parent.pose;
    child.pose_at_update = parent.pose_at_update;
    child.log_weight = 0.0;
    child.lineage_log_likelihood = parent.lineage_log_likelihood;
    child.parent = parents[i];
    child.map = parent.map->clone();  // shares every tile until one side writes
    child.trajectory = parent.trajectory;
  }
  particles_ = std::move(next);
}

std::size_t ParticleFilter::best_index() const {
  std::size_t best = 0;
  for (std::size_t i = 1; i < particles_.size(); ++i)
    if (particles_[i].lineage_log_likelihood > particles_[best].lineage_log_likelihood) best = i;
  return best;
}

Pose2 ParticleFilter::best_pose(const Pose2& odometry) const {
  if (particles_.empty()) return odometry;
  const Particle& best = particles_[best_index()];
  return compose(best.pose_at_update, relative(odometry_at_update_, odometry));
}

std::optional<double> ParticleFilter::best_turn_at_last_update() const {
  if (particles_.empty()) return std::nullopt;
  const TrajectoryNode* node = particles_[best_index()].trajectory.get();
  if (!node || !node->parent || node->generation != generation_ || node->parent->generation != generation_ - 1)
    return std::nullopt;
  return geometry::wrap_angle(node->pose.theta_rad - node->parent->pose.theta_rad);
}

std::vector<Pose2> ParticleFilter::best_trajectory() const {
  if (particles_.empty()) return {};
  std::vector<Pose2> poses(static_cast<std::size_t>(generation_ + 1));
  for (const TrajectoryNode* node = particles_[best_index()].trajectory.get(); node;
       node = node->parent.get())
    if (node->generation >= 0 && node->generation <= generation_)
      poses[static_cast<std::size_t>(node->generation)] = node->pose;
  return poses;
}

namespace {
constexpr std::string_view kCheckpointMagic = "PEXSLAMF";
// 2: corrected odometry steps, check statistics; 3: odometry drift; 4: where the robot stands
constexpr std::uint32_t kCheckpointVersion = 4;
}  // namespace

std::string ParticleFilter::checkpoint() const {
  if (!grid_maps_) throw std::logic_error("a filter with a custom map factory cannot be checkpointed");
  archive::ByteWriter out;
  // What the saved state only makes sense with; restore() refuses another.
  out.put<std::uint32_t>(static_cast<std::uint32_t>(options_.particle_count));
  out.put<double>(options_.grid.resolution_m);
  out.put<std::int32_t>(CowGridMap::kTileBits);

  out.put_bool(initialized_);
  out.put<std::int64_t>(generation_);
  std::ostringstream rng;  // the standard's text form of the engine: its whole state
  rng << rng_;
  out.put_string(rng.str());
  put_pose(out, last_odometry_);
  put_pose(out, odometry_at_update_);
  out.put<double>(linear_since_update_m_);
  out.put<double>(angular_since_update_rad_);
  out.put<std::int64_t>(last_update_.generation);
  out.put_bool(last_update_.resampled);
  out.put<double>(last_update_.effective_sample_size);
  out.put<std::int32_t>(last_update_.matcher_evaluations);
  out.put<std::int32_t>(last_update_.failed_matches);
  out.put<double>(last_update_.odometry_scale);
  out.put<double>(last_update_.odometry_check_ratio);
  out.put<std::int64_t>(corrected_odometry_steps_);
  drift_.write(out);
  put_pose(out, standing_odometry_);
  out.put<std::int64_t>(standing_since_utime_);
  out.put<std::int64_t>(standing_updates_);

  // The trajectory tree: every node a particle reaches, once, parents before
  // their children (a particle's chain is walked up to the first node already
  // written, then written from the oldest down).
  std::unordered_map<const TrajectoryNode*, std::int64_t> node_index;
  std::vector<const TrajectoryNode*> nodes, chain;
  for (const Particle& p : particles_) {
    chain.clear();
    for (const TrajectoryNode* n = p.trajectory.get(); n && !node_index.contains(n); n = n->parent.get())
      chain.push_back(n);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      node_index.emplace(*it, static_cast<std::int64_t>(nodes.size()));
      nodes.push_back(*it);
    }
  }
  out.put<std::uint64_t>(nodes.size());
  for (const TrajectoryNode* n : nodes) {
    put_pose(out, n->pose);
    out.put<std::int64_t>(n->generation);
    out.put<std::int64_t>(n->parent ? node_index.at(n->parent.get()) : -1);
  }

  std::vector<const CowGridMap*> maps;
  for (const Particle& p : particles_) maps.push_back(&dynamic_cast<const CowGridMap&>(*p.map));
  CowGridMap::write_shared(out, maps);

  out.put<std::uint64_t>(particles_.size());
  for (const Particle& p : particles_) {
    put_pose(out, p.pose);
    put_pose(out, p.pose_at_update);
    out.put<double>(p.log_weight);
    out.put<double>(p.lineage_log_likelihood);
    out.put<std::int32_t>(p.parent);
    out.put<std::int64_t>(p.trajectory ? node_index.at(p.trajectory.get()) : -1);
  }
  return archive::seal(kCheckpointMagic, kCheckpointVersion, out.bytes());
}

std::string ParticleFilter::restore(std::string_view checkpoint) {
  if (!grid_maps_) return "this filter's maps come from a custom map factory: it cannot take up a checkpoint";
  try {
    const std::string payload = archive::unseal(kCheckpointMagic, kCheckpointVersion, checkpoint);
    archive::ByteReader in(payload);
    const auto particle_count = in.get<std::uint32_t>();
    if (particle_count != static_cast<std::uint32_t>(options_.particle_count))
      return "the checkpoint has " + std::to_string(particle_count) + " particles, the configuration " +
             std::to_string(options_.particle_count);
    const auto resolution_m = in.get<double>();
    const auto tile_bits = in.get<std::int32_t>();
    if (resolution_m != options_.grid.resolution_m || tile_bits != CowGridMap::kTileBits)
      return "the checkpoint's maps have " + std::to_string(resolution_m) + " m cells in tiles of 2^" +
             std::to_string(tile_bits) + ", this filter's " + std::to_string(options_.grid.resolution_m) +
             " m cells in tiles of 2^" + std::to_string(CowGridMap::kTileBits);

    // Everything is read into a new filter, which replaces this one only once
    // all of it was read and checked.
    ParticleFilter restored(options_, map_factory_);
    restored.grid_maps_ = grid_maps_;
    restored.initialized_ = in.get_bool();
    restored.generation_ = in.get<std::int64_t>();
    std::istringstream rng(in.get_string());
    rng >> restored.rng_;
    if (rng.fail()) throw archive::ArchiveError("the random generator's state does not read");
    restored.last_odometry_ = get_pose(in);
    restored.odometry_at_update_ = get_pose(in);
    restored.linear_since_update_m_ = in.get<double>();
    restored.angular_since_update_rad_ = in.get<double>();
    restored.last_update_.generation = in.get<std::int64_t>();
    restored.last_update_.resampled = in.get_bool();
    restored.last_update_.effective_sample_size = in.get<double>();
    restored.last_update_.matcher_evaluations = in.get<std::int32_t>();
    restored.last_update_.failed_matches = in.get<std::int32_t>();
    restored.last_update_.odometry_scale = in.get<double>();
    restored.last_update_.odometry_check_ratio = in.get<double>();
    restored.corrected_odometry_steps_ = in.get<std::int64_t>();
    restored.drift_.read(in);
    restored.standing_odometry_ = get_pose(in);
    restored.standing_since_utime_ = in.get<std::int64_t>();
    restored.standing_updates_ = in.get<std::int64_t>();

    constexpr std::size_t kNodeBytes = 3 * sizeof(double) + 2 * sizeof(std::int64_t);
    const std::uint64_t node_count = in.get_count(kNodeBytes);
    std::vector<std::shared_ptr<const TrajectoryNode>> nodes;
    nodes.reserve(node_count);
    for (std::uint64_t i = 0; i < node_count; ++i) {
      const Pose2 pose = get_pose(in);
      const auto generation = in.get<std::int64_t>();
      const auto parent = in.get<std::int64_t>();
      if (parent < -1 || parent >= static_cast<std::int64_t>(i))
        throw archive::ArchiveError("trajectory node " + std::to_string(i) + " has parent " + std::to_string(parent));
      nodes.push_back(std::make_shared<const TrajectoryNode>(
          pose, generation, parent >= 0 ? nodes[static_cast<std::size_t>(parent)] : nullptr));
    }

    std::vector<std::unique_ptr<CowGridMap>> maps = CowGridMap::read_shared(in, options_.grid);
    const std::uint64_t count = in.get_count(2 * 3 * sizeof(double) + 2 * sizeof(double));
    const std::uint64_t expected = restored.initialized_ ? particle_count : 0;
    if (count != expected || maps.size() != count)
      throw archive::ArchiveError(std::to_string(count) + " particles and " + std::to_string(maps.size()) +
                                  " maps where " + std::to_string(expected) + " belong");
    restored.particles_.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      Particle& p = restored.particles_[i];
      p.pose = get_pose(in);
      p.pose_at_update = get_pose(in);
      p.log_weight = in.get<double>();
      p.lineage_log_likelihood = in.get<double>();
      p.parent = in.get<std::int32_t>();
      const auto node = in.get<std::int64_t>();
      if (p.parent < -1 || p.parent >= static_cast<std::int32_t>(count) || node < -1 ||
          node >= static_cast<std::int64_t>(nodes.size()))
        throw archive::ArchiveError("particle " + std::to_string(i) + " has parent " + std::to_string(p.parent) +
                                    " and trajectory node " + std::to_string(node));
      if (node >= 0) p.trajectory = nodes[static_cast<std::size_t>(node)];
      p.map = std::move(maps[i]);
    }
    in.expect_end();
    *this = std::move(restored);
    return "";
  } catch (const archive::ArchiveError& e) {
    return e.what();
  }
}

}  // namespace pex::slam
