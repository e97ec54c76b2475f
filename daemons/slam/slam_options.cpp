#include "slam_options.hpp"

#include <cmath>
#include <cstdint>

namespace pex::slam_daemon {

using runtime::in_range;
using runtime::non_negative;
using runtime::positive;

SlamNodeOptions load_options(runtime::ConfigReader& config) {
  SlamNodeOptions o;
  auto& f = o.filter;
  f.particle_count = config.get<int>("particles", f.particle_count, in_range(1, 1000));
  f.linear_update_m = config.get<double>("linear_update_m", f.linear_update_m, non_negative<double>());
  f.angular_update_rad = config.get<double>("angular_update_rad", f.angular_update_rad, non_negative<double>());
  f.standing_update_s = config.get<double>("standing_update_s", f.standing_update_s, non_negative<double>());
  f.resample_threshold = config.get<double>("resample_threshold", f.resample_threshold, in_range(0.0, 1.0));
  f.likelihood_gain = config.get<double>("likelihood_gain", f.likelihood_gain, positive<double>());
  f.threads = config.get<int>("threads", f.threads, in_range(1, 64));
  f.seed = static_cast<std::uint64_t>(
      config.get<std::int64_t>("seed", static_cast<std::int64_t>(f.seed), non_negative<std::int64_t>()));

  auto motion = config.section("motion");
  f.motion.srr = motion.get<double>("srr", f.motion.srr, non_negative<double>());
  f.motion.srt = motion.get<double>("srt", f.motion.srt, non_negative<double>());
  f.motion.str = motion.get<double>("str", f.motion.str, non_negative<double>());
  f.motion.stt = motion.get<double>("stt", f.motion.stt, non_negative<double>());

  auto scan = config.section("scan");
  f.scan.usable_range_m = scan.get<double>("usable_range_m", f.scan.usable_range_m, positive<double>());
  f.scan.free_offset_m = scan.get<double>("free_offset_m", f.scan.free_offset_m, positive<double>());

  auto grid = config.section("grid");
  f.grid.resolution_m = grid.get<double>("resolution_m", f.grid.resolution_m, in_range(0.005, 1.0));
  f.grid.kernel_radius_cells = grid.get<int>("kernel_radius_cells", f.grid.kernel_radius_cells, in_range(0, 5));
  f.grid.score_sigma_m2 = grid.get<double>("score_sigma_m2", f.grid.score_sigma_m2, positive<double>());
  f.grid.likelihood_sigma_m2 =
      grid.get<double>("likelihood_sigma_m2", f.grid.likelihood_sigma_m2, positive<double>());
  // An unmatched beam must not score better than a matched one (> 0), and a
  // huge penalty turns every weight into -inf and the poses into NaN (issue 12:
  // -1e308 made 1244 of 1318 poses NaN): GMapping's values are about -0.5.
  f.grid.null_log_likelihood =
      grid.get<double>("null_log_likelihood", f.grid.null_log_likelihood, in_range(-100.0, 0.0));
  f.grid.beam_step = grid.get<int>("beam_step", f.grid.beam_step, in_range(1, 100));
  f.grid.along_line_weight = grid.get<double>("along_line_weight", f.grid.along_line_weight, in_range(0.0, 1.0));
  f.grid.line_flatness = grid.get<double>("line_flatness", f.grid.line_flatness, in_range(0.0, 1.0));
  f.grid.check_free_before_hit = grid.get<bool>("check_free_before_hit", f.grid.check_free_before_hit);
  f.grid.max_extent_m = grid.get<double>("max_extent_m", f.grid.max_extent_m, in_range(10.0, 1000.0));

  auto matcher = config.section("matcher");
  f.matcher.linear_step_m = matcher.get<double>("linear_step_m", f.matcher.linear_step_m, positive<double>());
  f.matcher.angular_step_rad =
      matcher.get<double>("angular_step_rad", f.matcher.angular_step_rad, positive<double>());
  f.matcher.refinements = matcher.get<int>("refinements", f.matcher.refinements, in_range(0, 20));
  f.matcher.minimum_score = matcher.get<double>("minimum_score", f.matcher.minimum_score, non_negative<double>());
  f.matcher.beam_step = matcher.get<int>("beam_step", f.matcher.beam_step, in_range(1, 100));

  auto proposal = config.section("proposal");
  f.proposal.linear_offset_m =
      proposal.get<double>("linear_offset_m", f.proposal.linear_offset_m, positive<double>());
  f.proposal.angular_offset_rad =
      proposal.get<double>("angular_offset_rad", f.proposal.angular_offset_rad, positive<double>());
  f.proposal.min_linear_std_m =
      proposal.get<double>("min_linear_std_m", f.proposal.min_linear_std_m, positive<double>());
  f.proposal.min_angular_std_rad =
      proposal.get<double>("min_angular_std_rad", f.proposal.min_angular_std_rad, positive<double>());
  f.proposal.use_motion_prior = proposal.get<bool>("use_motion_prior", f.proposal.use_motion_prior);
  f.proposal.sample_scale = proposal.get<double>("sample_scale", f.proposal.sample_scale, in_range(0.0, 1.0));

  auto sync = config.section("sync");
  o.sync.max_wait_us = 1000 * sync.get<std::int64_t>("max_odometry_wait_ms", o.sync.max_wait_us / 1000,
                                                     non_negative<std::int64_t>());
  o.sync.max_odometry_age_us =
      1000 * sync.get<std::int64_t>("max_odometry_age_ms", o.sync.max_odometry_age_us / 1000, in_range<std::int64_t>(1, 60'000));
  auto& l = o.sync.limits;
  l.enabled = sync.get<bool>("check_odometry_steps", l.enabled);
  l.max_speed_mps = sync.get<double>("odometry_max_speed_mps", l.max_speed_mps, positive<double>());
  l.max_omega_radps = sync.get<double>("odometry_max_omega_radps", l.max_omega_radps, positive<double>());
  o.sync.odometry_lead_us = 1000 * sync.get<std::int64_t>("odometry_lead_ms", o.sync.odometry_lead_us / 1000,
                                                          in_range<std::int64_t>(0, 1000));
  o.sync.estimate_lead = sync.get<bool>("estimate_odometry_lead", o.sync.estimate_lead);
  o.sync.lag.max_lead_s =
      1e-3 * static_cast<double>(sync.get<std::int64_t>(
                 "odometry_lead_max_ms", std::llround(o.sync.lag.max_lead_s * 1e3), in_range<std::int64_t>(10, 1000)));
  o.sync.lag.min_updates =
      sync.get<int>("odometry_lead_min_updates", o.sync.lag.min_updates, in_range(1, 100000));

  auto check = config.section("odometry_check");
  f.odometry_check.enabled = check.get<bool>("enabled", f.odometry_check.enabled);
  f.odometry_check.min_translation_m =
      check.get<double>("min_translation_m", f.odometry_check.min_translation_m, non_negative<double>());
  f.odometry_check.margin = check.get<double>("margin", f.odometry_check.margin, non_negative<double>());
  auto drift = config.section("odometry_drift");
  f.odometry_drift.correct = drift.get<bool>("correct", f.odometry_drift.correct);
  f.odometry_drift.forgetting = drift.get<double>("forgetting", f.odometry_drift.forgetting, in_range(0.5, 1.0));
  f.odometry_drift.prior_travel_m =
      drift.get<double>("prior_travel_m", f.odometry_drift.prior_travel_m, in_range(0.001, 1e6));
  f.odometry_drift.prior_turn_rad =
      drift.get<double>("prior_turn_rad", f.odometry_drift.prior_turn_rad, in_range(0.001, 1e6));
  f.odometry_drift.max_drift_rad_per_m =
      drift.get<double>("max_drift_rad_per_m", f.odometry_drift.max_drift_rad_per_m, in_range(0.0, 1.0));
  f.odometry_drift.max_turn_scale =
      drift.get<double>("max_turn_scale", f.odometry_drift.max_turn_scale, in_range(0.0, 1.0));
  f.odometry_drift.max_step_residual_rad =
      drift.get<double>("max_step_residual_rad", f.odometry_drift.max_step_residual_rad, in_range(0.0, 1.0));
  auto constraint = config.section("constraint");
  f.constraint.enabled = constraint.get<bool>("enabled", f.constraint.enabled);
  f.constraint.neighbours = constraint.get<int>("neighbours", f.constraint.neighbours, in_range(1, 20));
  f.constraint.neighbour_radius_m =
      constraint.get<double>("neighbour_radius_m", f.constraint.neighbour_radius_m, in_range(0.01, 5.0));
  f.constraint.line_flatness = constraint.get<double>("line_flatness", f.constraint.line_flatness, in_range(0.0, 1.0));
  f.constraint.range_noise_m = constraint.get<double>("range_noise_m", f.constraint.range_noise_m, in_range(0.0, 1.0));
  f.constraint.min_information_beams =
      constraint.get<double>("min_information_beams", f.constraint.min_information_beams, in_range(0.0, 10000.0));
  o.republish_period_s = config.get<double>("republish_period_s", o.republish_period_s, non_negative<double>());
  o.republish_max_travel_m =
      config.get<double>("republish_max_travel_m", o.republish_max_travel_m, in_range(0.0, 10.0));
  o.republish_max_turn_rad =
      config.get<double>("republish_max_turn_rad", o.republish_max_turn_rad, in_range(0.0, 10.0));
  o.input_timeout_s = config.get<double>("input_timeout_s", o.input_timeout_s, positive<double>());
  o.checkpoint_file = config.get_path("checkpoint_file", o.checkpoint_file, /*must_exist=*/false);
  o.checkpoint_period_s =
      config.get<double>("checkpoint_period_s", o.checkpoint_period_s, in_range(0.1, 3600.0));
  o.max_beams = static_cast<std::size_t>(config.get<int>("max_beams", static_cast<int>(o.max_beams),
                                                         in_range(1, 1 << 20)));
  return o;
}

}  // namespace pex::slam_daemon
