#pragma once
// A long run made of a real log (issue 13: memory over an 80-minute run, with
// only shorter logs at hand): the log driven forwards, then back along the
// same path (its laser lines in reverse order, each scan with the odometry pose
// it was taken at), then forwards again, and so on. Every scan is a real scan
// at the pose the robot had when it took it, and the odometry is continuous
// (a pass starts where the last one ended), so the filter sees the building
// driven `laps` times, the way a robot patrolling it would, and the relations
// of the log hold in every pass.
#include <vector>

#include "evaluation/carmen_log.hpp"
#include "evaluation/relations.hpp"

namespace pex::evaluation {

struct LapTiming {
  double first_s = 0.0;  // the earliest laser time stamp of the log
  double last_s = 0.0;   // the latest
  double gap_s = 1.0;    // between the end of a pass and the start of the next
  // Where time t of the log falls in pass `lap` (0: the log as it is; odd
  // passes run backwards: the log's last scan comes first).
  double map(double t_s, int lap) const;
};

// The timing of `log`'s laser lines, with `gap_s` between passes.
LapTiming lap_timing(const CarmenLog& log, double gap_s);

// The log driven `laps` times (>= 1), passes alternately forwards and
// backwards. With laps == 1 the log is returned unchanged; with more, only
// the laser lines are kept (their own odometry poses are the odometry; ODOM
// lines have their own clock and rate and are not run backwards).
CarmenLog lap_log(const CarmenLog& log, int laps, double gap_s);

// The log's relations in every pass: pass k's copy of (t1, t2) is
// (map(t1, k), map(t2, k)) with the same relative pose (the robot was at the
// same two poses). Grouped by pass: laps * relations.size() in all.
std::vector<Relation> lap_relations(const std::vector<Relation>& relations, const LapTiming& timing, int laps);

}  // namespace pex::evaluation
