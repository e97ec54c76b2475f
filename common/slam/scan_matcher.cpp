#include "slam/scan_matcher.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

namespace pex::slam {

ScanPoints subsample(const ScanPoints& scan, int step) {
  if (step <= 1) return scan;
  ScanPoints out;
  out.utime = scan.utime;
  out.beam_spacing_rad = scan.beam_spacing_rad * step;
  out.beams.reserve(scan.beams.size() / static_cast<std::size_t>(step) + 1);
  for (std::size_t i = 0; i < scan.beams.size(); i += static_cast<std::size_t>(step)) out.beams.push_back(scan.beams[i]);
  return out;
}

int beam_stride(const ScanPoints& scan, double spacing_rad) {
  if (!(spacing_rad > 0.0) || !(scan.beam_spacing_rad > 0.0)) return 1;
  // The tolerance absorbs an increment sent as a float (1° is not exact).
  const double n = std::ceil(spacing_rad / scan.beam_spacing_rad - 1e-3);
  return static_cast<int>(std::clamp(n, 1.0, 1000.0));
}

ScanPoints matcher_beams(const ScanPoints& scan, const MatcherOptions& options) {
  return subsample(scan, options.beam_spacing_rad > 0.0 ? beam_stride(scan, options.beam_spacing_rad)
                                                        : options.beam_step);
}

ScanPoints proposal_beams(const ScanPoints& scan, const ProposalOptions& options) {
  return subsample(scan, beam_stride(scan, options.beam_spacing_rad));
}

MatchResult match_scan(const ParticleMap& map, const ScanPoints& scan, const Pose2& initial,
                       const MatcherOptions& options) {
  MatchResult result;
  Pose2 current = initial;
  PoseEvaluation current_eval = map.evaluate(current, scan);
  ++result.evaluations;
  double linear = options.linear_step_m;
  double angular = options.angular_step_rad;
  int refinement = 0;
  // The move taken in the last round (-1: none since the steps changed). Its
  // opposite (index ^ 1) leads back to the pose that move left, which scored
  // less than the current one, so it is not evaluated again.
  int last_move = -1;
  // Each round tries the six unit moves (world-frame x/y, turning) and takes
  // the best that improves; with no improvement the steps are halved.
  while (true) {
    Pose2 best = current;
    PoseEvaluation best_eval = current_eval;
    const std::array<Pose2, 6> moves = {{{current.x_m + linear, current.y_m, current.theta_rad},
                                         {current.x_m - linear, current.y_m, current.theta_rad},
                                         {current.x_m, current.y_m + linear, current.theta_rad},
                                         {current.x_m, current.y_m - linear, current.theta_rad},
                                         {current.x_m, current.y_m, current.theta_rad + angular},
                                         {current.x_m, current.y_m, current.theta_rad - angular}}};
    int best_move = -1;
    for (int m = 0; m < static_cast<int>(moves.size()); ++m) {
      if (last_move >= 0 && m == (last_move ^ 1)) continue;
      Pose2 candidate = moves[static_cast<std::size_t>(m)];
      candidate.theta_rad = geometry::wrap_angle(candidate.theta_rad);
      const PoseEvaluation e = map.evaluate(candidate, scan);
      ++result.evaluations;
      if (e.score > best_eval.score) {
        best_eval = e;
        best = candidate;
        best_move = m;
      }
    }
    if (best_eval.score > current_eval.score) {
      current = best;
      current_eval = best_eval;
      last_move = best_move;
      continue;
    }
    last_move = -1;
    if (++refinement > options.refinements) break;
    linear *= 0.5;
    angular *= 0.5;
  }
  result.pose = current;
  result.evaluation = current_eval;
  return result;
}

ProposalResult sample_improved_proposal(const ParticleMap& map, const ScanPoints& scan,
                                        const Pose2& matched, const Pose2& predicted,
                                        const Pose2& predicted_std, const ProposalOptions& options,
                                        std::mt19937_64& rng) {
  constexpr int kSamples = 27;
  std::array<Eigen::Vector3d, kSamples> offsets;
  std::array<double, kSamples> log_w;
  const double sx = std::max(predicted_std.x_m, 1e-3);
  const double sy = std::max(predicted_std.y_m, 1e-3);
  const double st = std::max(predicted_std.theta_rad, 1e-3);
  int n = 0;
  double max_log_w = -std::numeric_limits<double>::infinity();
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int k = -1; k <= 1; ++k) {
        const Eigen::Vector3d d(i * options.linear_offset_m, j * options.linear_offset_m,
                                k * options.angular_offset_rad);
        const Pose2 x{matched.x_m + d.x(), matched.y_m + d.y(), geometry::wrap_angle(matched.theta_rad + d.z())};
        double lw = map.log_likelihood(x, scan);
        if (options.use_motion_prior) {
          const double ex = (x.x_m - predicted.x_m) / sx;
          const double ey = (x.y_m - predicted.y_m) / sy;
          const double et = geometry::wrap_angle(x.theta_rad - predicted.theta_rad) / st;
          lw += -0.5 * (ex * ex + ey * ey + et * et);
        }
        offsets[n] = d;
        log_w[n] = lw;
        max_log_w = std::max(max_log_w, lw);
        ++n;
      }
  double sum = 0.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  std::array<double, kSamples> w;
  for (int s = 0; s < kSamples; ++s) {
    w[s] = std::exp(log_w[s] - max_log_w);
    sum += w[s];
    mean += w[s] * offsets[s];
  }
  mean /= sum;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int s = 0; s < kSamples; ++s) {
    const Eigen::Vector3d e = offsets[s] - mean;
    cov += (w[s] / sum) * e * e.transpose();
  }
  cov(0, 0) += options.min_linear_std_m * options.min_linear_std_m;
  cov(1, 1) += options.min_linear_std_m * options.min_linear_std_m;
  cov(2, 2) += options.min_angular_std_rad * options.min_angular_std_rad;
  const Eigen::Matrix3d l = cov.llt().matrixL();
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Vector3d z(normal(rng), normal(rng), normal(rng));
  const Eigen::Vector3d draw = mean + options.sample_scale * (l * z);
  ProposalResult result;
  result.pose = {matched.x_m + draw.x(), matched.y_m + draw.y(), geometry::wrap_angle(matched.theta_rad + draw.z())};
  result.log_weight_increment = max_log_w + std::log(sum);
  return result;
}

}  // namespace pex::slam
