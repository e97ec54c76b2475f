// pex-eval-slam --poses P --relations R: the Kümmerle et al. 2009 relations
// metric of a trajectory (`timestamp_s x y theta` per line), printed as one JSON line.
#include <CLI/CLI.hpp>
#include <sysexits.h>  // EX_USAGE 64, EX_DATAERR 65, EX_NOINPUT 66, EX_UNAVAILABLE 69, EX_CANTCREAT 73, EX_CONFIG 78

#include <cstdio>
#include <fstream>
#include <iostream>

#include "cli/command_line.hpp"
#include "evaluation/relations.hpp"

int main(int argc, char** argv) {
  CLI::App app{"SLAM accuracy by the relations metric (Kümmerle et al. 2009)"};
  std::string poses_path;
  std::string relations_path;
  pex::evaluation::MetricOptions options;
  app.add_option("--poses", poses_path, "trajectory: timestamp_s x y theta per line")->required();
  app.add_option("--relations", relations_path, "relations: t1 t2 x y z roll pitch yaw per line")
      ->required();
  app.add_option("--max-time-difference-s", options.max_time_difference_s,
                 "a relation counts when both times have an estimated pose this close")
      ->capture_default_str();
  app.add_option("--split-gap-s", options.split_gap_s,
                 "also summarise relations less than this many s apart (near: local accuracy) and the "
                 "others (far: loops) apart; 0: no split")
      ->capture_default_str();
  if (const auto code = pex::cli::parse_command_line(app, "pex-eval-slam", argc, argv)) return *code;

  std::ifstream poses_in(poses_path);
  if (!poses_in) {
    std::fprintf(stderr, "pex-eval-slam: cannot open %s\n", poses_path.c_str());
    return EX_NOINPUT;
  }
  std::ifstream relations_in(relations_path);
  if (!relations_in) {
    std::fprintf(stderr, "pex-eval-slam: cannot open %s\n", relations_path.c_str());
    return EX_NOINPUT;
  }
  const auto poses = pex::evaluation::read_poses(poses_in);
  const auto relations = pex::evaluation::read_relations(relations_in);
  if (poses.malformed_lines > 0 || relations.malformed_lines > 0)
    std::fprintf(stderr, "pex-eval-slam: skipped %zu malformed pose lines, %zu malformed relation lines\n",
                 poses.malformed_lines, relations.malformed_lines);
  const auto result = pex::evaluation::evaluate_relations(poses.poses, relations.relations, options);
  if (result.unmatched > 0)
    std::fprintf(stderr, "pex-eval-slam: %zu relations without an estimated pose within %.3f s\n",
                 result.unmatched, options.max_time_difference_s);
  std::cout << pex::evaluation::to_json_line(result) << '\n';
  return result.relations > 0 ? 0 : 1;
}
