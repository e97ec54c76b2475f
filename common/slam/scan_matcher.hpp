#pragma once
// Scan matching and the improved proposal of Grisetti et al. 2007 over any
// ParticleMap: a hill climb on the matching score, then the likelihood sampled
// around the optimum to fit the Gaussian the new pose is drawn from.
#include <random>

#include "slam/particle_map.hpp"

namespace pex::slam {

struct MatcherOptions {
  // First step sizes of the hill climb; halved on every refinement.
  double linear_step_m = 0.05;
  double angular_step_rad = 0.05;
  int refinements = 5;
  // A match scoring at most this is not trusted (the motion sample is kept).
  double minimum_score = 0.0;
  // The hill climb scores every beam_step-th usable beam (the likelihood of the
  // proposal and the weights use all): neighbouring beams of a 1° scanner say
  // nearly the same about the pose, and the climb is most of the filter's time.
  int beam_step = 2;
  // When > 0, replaces beam_step by a rule in angle that holds for any
  // scanner: every n-th usable beam with n the smallest stride that puts
  // beams this far apart (2 on a 1° scanner for 1.5°, 3 on a 0.5° one).
  // Off: 1.5° and 2° lost a loop on FR079 (docs/slam.md, issue 13).
  double beam_spacing_rad = 0.0;
};

// Every step-th beam of `scan` (all for step <= 1).
ScanPoints subsample(const ScanPoints& scan, int step);

// The smallest stride n >= 1 with n * scan.beam_spacing_rad >= spacing_rad
// (1 for spacing_rad <= 0 or a scan whose spacing is unknown).
int beam_stride(const ScanPoints& scan, double spacing_rad);

// The beams the hill climb scores: by angle when options.beam_spacing_rad > 0,
// else every options.beam_step-th.
ScanPoints matcher_beams(const ScanPoints& scan, const MatcherOptions& options);

struct MatchResult {
  Pose2 pose;
  PoseEvaluation evaluation;
  int evaluations = 0;
};

// Hill climbing from `initial` on map.evaluate(...).score (GMapping's optimize).
MatchResult match_scan(const ParticleMap& map, const ScanPoints& scan, const Pose2& initial,
                       const MatcherOptions& options);

struct ProposalOptions {
  // The likelihood is sampled on a 3x3x3 grid of these half-widths around the match.
  double linear_offset_m = 0.01;
  double angular_offset_rad = 0.005;
  // Floors of the fitted standard deviations (the grid cannot resolve less).
  double min_linear_std_m = 0.002;
  double min_angular_std_rad = 0.001;
  // Weigh the samples also by the odometry prior p(x | x_prev, u) (Grisetti et al.).
  bool use_motion_prior = true;
  // Scale of the drawn deviation from the fitted mean (1 = a true sample of the
  // Gaussian, 0 = its mean).
  double sample_scale = 1.0;
  // The likelihood (the 27 samples, hence the weights) uses beams at least
  // this far apart (0: every beam). Neighbouring beams of a dense scanner say
  // nearly the same; counting each as independent evidence makes a 0.5°
  // scanner's weights twice as sharp as a 1° one's for the same scene.
  // Off: 1° cost FR079 2-6 mm (docs/slam.md, issue 13).
  double beam_spacing_rad = 0.0;
};

// The beams the likelihood uses (beam_stride of options.beam_spacing_rad).
ScanPoints proposal_beams(const ScanPoints& scan, const ProposalOptions& options);

struct ProposalResult {
  Pose2 pose;             // the drawn pose
  double log_weight_increment = 0.0;  // log sum_j p(z|x_j) p(x_j|x',u) (the eta of the paper)
};

// Fits a Gaussian to likelihood x prior over samples around `matched` and draws
// the new pose from it. `predicted` and `predicted_std` describe the motion prior.
ProposalResult sample_improved_proposal(const ParticleMap& map, const ScanPoints& scan,
                                        const Pose2& matched, const Pose2& predicted,
                                        const Pose2& predicted_std, const ProposalOptions& options,
                                        std::mt19937_64& rng);

}  // namespace pex::slam
