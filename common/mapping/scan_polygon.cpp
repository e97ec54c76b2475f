#include "mapping/scan_polygon.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/point.hpp"

namespace pex::mapping {

namespace {

struct Line {
  double cx, cy;  // a point on the line (centroid)
  double dx, dy;  // unit direction
};

// Orthogonal (total) least-squares line through points[first..last].
Line fit_line(const std::vector<Point>& points, std::size_t first, std::size_t last) {
  const double n = static_cast<double>(last - first + 1);
  double cx = 0, cy = 0;
  for (std::size_t i = first; i <= last; ++i) cx += points[i].x(), cy += points[i].y();
  cx /= n, cy /= n;
  double sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = first; i <= last; ++i) {
    const double x = points[i].x() - cx, y = points[i].y() - cy;
    sxx += x * x, syy += y * y, sxy += x * y;
  }
  const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  Line line{cx, cy, std::cos(angle), std::sin(angle)};
  // Degenerate spread (all points equal): take the chord direction.
  if (sxx + syy <= 1e-24) {
    const double ex = points[last].x() - points[first].x(), ey = points[last].y() - points[first].y();
    const double len = std::hypot(ex, ey);
    if (len > 0) line.dx = ex / len, line.dy = ey / len;
  }
  return line;
}

// Root-mean-square and largest orthogonal distance of points[first..last] from
// their least-squares line.
struct LineResidual {
  double rms = 0.0;
  double max = 0.0;
};
LineResidual line_residual(const std::vector<Point>& points, std::size_t first, std::size_t last) {
  const Line line = fit_line(points, first, last);
  LineResidual r;
  double sum = 0.0;
  for (std::size_t i = first; i <= last; ++i) {
    const double d = (points[i].x() - line.cx) * line.dy - (points[i].y() - line.cy) * line.dx;
    sum += d * d;
    r.max = std::max(r.max, std::abs(d));
  }
  r.rms = std::sqrt(sum / static_cast<double>(last - first + 1));
  return r;
}

// The merge step of split-and-merge: RDP splits at single noisy returns (with
// range noise near the tolerance, a densely sampled straight wall becomes a
// zigzag of short edges across the wall). A kept vertex is dropped while the
// points of its two segments together still fit one line: RMS residual at most
// max_rms (noise), and no point farther than max_dev from it (a real corner,
// even one with a short arm, has points far off the merged line); the
// cheapest vertex goes first.
void merge_collinear(const std::vector<Point>& points, double max_rms, double max_dev,
                     std::vector<std::size_t>& kept) {
  if (max_rms <= 0.0) return;
  while (kept.size() > 2) {
    std::size_t best = 0;
    double best_rms = max_rms;
    for (std::size_t j = 1; j + 1 < kept.size(); ++j) {
      const LineResidual r = line_residual(points, kept[j - 1], kept[j + 1]);
      if (r.rms <= best_rms && r.max <= max_dev) {
        best = j;
        best_rms = r.rms;
      }
    }
    if (best == 0) return;
    kept.erase(kept.begin() + static_cast<std::ptrdiff_t>(best));
  }
}

Point project(const Line& line, const Point& p) {
  const double t = (p.x() - line.cx) * line.dx + (p.y() - line.cy) * line.dy;
  return Point(line.cx + t * line.dx, line.cy + t * line.dy);
}

// Intersection of two lines; false if (nearly) parallel.
bool intersect(const Line& a, const Line& b, Point& out) {
  const double det = a.dx * b.dy - a.dy * b.dx;
  if (std::abs(det) < 1e-9) return false;
  const double t = ((b.cx - a.cx) * b.dy - (b.cy - a.cy) * b.dx) / det;
  out = Point(a.cx + t * a.dx, a.cy + t * a.dy);
  return true;
}

// The vertices of one cluster's polyline (sensor frame) at a given level.
std::vector<Point> cluster_polyline(const std::vector<Point>& points, int level,
                                    const ScanPolygonOptions& o) {
  if (points.size() <= 2 || level >= 2) return points;
  std::vector<bool> keep(points.size(), false);
  keep.front() = keep.back() = true;
  rdp_keep(points, 0, points.size() - 1, o.rdp_epsilon_m, keep);
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (keep[i]) kept.push_back(i);
  merge_collinear(points, o.merge_max_rms_m, o.merge_max_deviation_m, kept);
  std::vector<Point> out;
  out.reserve(kept.size());
  if (level == 1 || !o.least_squares_refit) {
    for (auto i : kept) out.push_back(points[i]);
    return out;
  }
  std::vector<Line> lines;
  for (std::size_t j = 0; j + 1 < kept.size(); ++j) lines.push_back(fit_line(points, kept[j], kept[j + 1]));
  auto bounded = [&](const Point& candidate, const Point& rdp_point) {
    return bg::distance(candidate, rdp_point) <= o.refit_max_shift_m ? candidate : rdp_point;
  };
  out.push_back(bounded(project(lines.front(), points[kept.front()]), points[kept.front()]));
  for (std::size_t j = 1; j + 1 < kept.size(); ++j) {
    Point v;
    if (!intersect(lines[j - 1], lines[j], v)) v = points[kept[j]];
    out.push_back(bounded(v, points[kept[j]]));
  }
  out.push_back(bounded(project(lines.back(), points[kept.back()]), points[kept.back()]));
  return out;
}

}  // namespace

int count_returns(std::span<const float> ranges, double range_min_m, double range_max_m) {
  int n = 0;
  for (const float r : ranges) n += is_return(r, range_min_m, range_max_m) ? 1 : 0;
  return n;
}

ScanPolygonResult scan_to_polygon(std::span<const float> ranges, double angle_min,
                                  double angle_increment, const geometry::Pose2& pose,
                                  const ScanPolygonOptions& o, std::span<const float> no_return_extent_m) {
  ScanPolygonResult result;
  auto fail = [&](std::string why) {
    result.ok = false;
    result.error = std::move(why);
    return result;
  };
  if (ranges.size() < 2) return fail("fewer than 2 beams");
  if (ranges.size() > static_cast<std::size_t>(o.max_beams)) return fail("too many beams");
  if (!no_return_extent_m.empty() && no_return_extent_m.size() != ranges.size())
    return fail("no_return_extent_m has " + std::to_string(no_return_extent_m.size()) + " values for " +
                std::to_string(ranges.size()) + " beams");
  if (!std::isfinite(angle_min) || !std::isfinite(angle_increment) || angle_increment == 0.0)
    return fail("angle_min / angle_increment not finite or increment zero");
  if (!geometry::is_finite(pose))
    return fail("pose not finite");
  if (!(o.free_range_m > 0.0) || !(o.range_max_m > o.range_min_m) || !(o.obstacle_range_m >= 0.0) ||
      !(o.return_margin_m >= 0.0))
    return fail("bad range options");

  // Beams in counter-clockwise order; at most one turn (a 360-degree scanner
  // repeats its first beam: the rest are dropped).
  const double step = std::abs(angle_increment);
  std::size_t n = ranges.size();
  const double two_pi = 2.0 * std::numbers::pi;
  if (static_cast<double>(n - 1) * step >= two_pi - 0.5 * step) {
    // Beams within one turn; negative (a step beyond 4 pi) or fewer than 2
    // is refused before it becomes a count (the scan_polygon fuzz finding:
    // -1 converted to size_t).
    const double within_a_turn = std::floor((two_pi - 0.5 * step) / step);
    if (!(within_a_turn >= 2.0)) return fail("angle_increment too large");
    n = static_cast<std::size_t>(within_a_turn);
  }
  const bool reversed = angle_increment < 0.0;
  const double first_angle = reversed ? angle_min + angle_increment * static_cast<double>(n - 1) : angle_min;
  auto range_at = [&](std::size_t k) { return ranges[reversed ? n - 1 - k : k]; };
  // A beam without a return stopped short of the free range (at a wall the
  // map holds): its extent, else 0.
  auto stopped_at = [&](std::size_t k) -> double {
    if (no_return_extent_m.empty()) return 0.0;
    const double e = no_return_extent_m[reversed ? n - 1 - k : k];
    return std::isfinite(e) && e > 0.0 && e < o.free_range_m ? e : 0.0;
  };
  auto angle_at = [&](std::size_t k) { return first_angle + step * static_cast<double>(k); };

  // What each beam gives: an obstacle point, free space to the free range (no
  // return), or free space to the obstacle range (a return beyond it).
  enum class Beam : std::uint8_t { kReturn, kNoReturn, kFar };
  const bool far_cut = o.obstacle_range_m > 0.0 && o.obstacle_range_m < o.range_max_m;
  std::vector<Beam> beam(n);
  std::vector<Point> sensor_points(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double r = range_at(k);
    const bool returned = is_return(r, o.range_min_m, o.range_max_m);
    if (returned && far_cut && r >= o.obstacle_range_m) {
      beam[k] = Beam::kFar;
      ++result.beams_beyond_obstacle_range;
    } else if (returned) {
      beam[k] = Beam::kReturn;
      const double taken = std::max(o.range_min_m, r - o.return_margin_m);
      sensor_points[k] = Point(taken * std::cos(angle_at(k)), taken * std::sin(angle_at(k)));
      ++result.beams_returned;
    } else {
      beam[k] = Beam::kNoReturn;
      ++result.beams_no_return;
    }
  }

  // Pieces in angular order: clusters (obstacle polylines) and runs of beams
  // that give free space only (an arc at their free extent).
  struct Piece {
    Beam kind;
    std::size_t first, last;  // beam indices
    bool cluster() const { return kind == Beam::kReturn; }
  };
  std::vector<Piece> pieces;
  const double sin_step = std::sin(step);
  const double sin_gap = std::sin(std::max(o.break_lambda_rad - step, 1e-6));
  for (std::size_t k = 0; k < n; ++k) {
    const bool continues = !pieces.empty() && pieces.back().last + 1 == k && pieces.back().kind == beam[k];
    bool joins = continues;
    if (continues && beam[k] == Beam::kReturn) {
      const double r_prev = range_at(k - 1);
      double break_m = r_prev * sin_step / sin_gap + 3.0 * o.break_sigma_m;
      if (o.break_max_gap_m > 0.0) break_m = std::min(break_m, o.break_max_gap_m);
      joins = bg::distance(sensor_points[k - 1], sensor_points[k]) <= break_m;
    }
    if (joins) {
      pieces.back().last = k;
    } else {
      pieces.push_back({beam[k], k, k});
    }
  }
  for (const auto& p : pieces) result.clusters += p.cluster() ? 1 : 0;

  const geometry::PoseTransform to_map(pose);

  for (int level = 0; level <= 2; ++level) {
    std::vector<Point> vertices{Point(0.0, 0.0)};
    std::vector<EdgeType> types{EdgeType::kFrontier};  // type of the edge leaving each vertex
    for (const auto& piece : pieces) {
      std::vector<Point> chain;
      EdgeType inner_type = EdgeType::kFrontier;
      if (piece.cluster()) {
        std::vector<Point> points(sensor_points.begin() + piece.first,
                                  sensor_points.begin() + piece.last + 1);
        chain = cluster_polyline(points, level, o);
        inner_type = EdgeType::kObstacle;
      } else {
        const double extent = piece.kind == Beam::kFar ? o.obstacle_range_m : o.free_range_m;
        // An arc at the extent over beams first..last.
        auto arc = [&](std::size_t first, std::size_t last) {
          const double a0 = angle_at(first), a1 = angle_at(last);
          const int steps = std::max(1, static_cast<int>(std::ceil((a1 - a0) / o.free_arc_step_rad)));
          for (int j = 0; j <= steps; ++j) {
            const double a = (first == last) ? a0 : a0 + (a1 - a0) * j / steps;
            chain.emplace_back(extent * std::cos(a), extent * std::sin(a));
            if (first == last) break;
          }
        };
        if (piece.kind == Beam::kFar) {
          arc(piece.first, piece.last);
        } else {
          // Runs of beams at the free range get their arc; a beam stopped at
          // a wall its own vertex (the polygon stays a star around the sensor).
          for (std::size_t k = piece.first; k <= piece.last;) {
            if (const double e = stopped_at(k); e > 0.0) {
              chain.emplace_back(e * std::cos(angle_at(k)), e * std::sin(angle_at(k)));
              ++k;
              continue;
            }
            std::size_t last = k;
            while (last + 1 <= piece.last && stopped_at(last + 1) == 0.0) ++last;
            arc(k, last);
            k = last + 1;
          }
        }
      }
      for (std::size_t j = 0; j < chain.size(); ++j) {
        vertices.push_back(chain[j]);
        types.push_back(j + 1 < chain.size() ? inner_type : EdgeType::kFrontier);
      }
    }
    // Drop consecutive duplicates (the edge leaving the dropped vertex goes).
    std::vector<Point> ring_points;
    std::vector<EdgeType> ring_types;
    for (std::size_t j = 0; j < vertices.size(); ++j) {
      const Point p = to_map(vertices[j]);
      if (!ring_points.empty() && bg::distance(ring_points.back(), p) < 1e-9) {
        ring_types.back() = types[j];  // the zero-length edge vanishes
        continue;
      }
      ring_points.push_back(p);
      ring_types.push_back(types[j]);
    }
    while (ring_points.size() > 1 && bg::distance(ring_points.back(), ring_points.front()) < 1e-9) {
      ring_points.pop_back();
      ring_types.pop_back();
    }
    if (ring_points.size() < 3) return fail("scan gives fewer than 3 distinct vertices");
    TypedPolygon polygon;
    polygon.geometry.outer().assign(ring_points.begin(), ring_points.end());
    polygon.geometry.outer().push_back(ring_points.front());
    polygon.edge_types.push_back(std::move(ring_types));
    std::string why;
    if (is_valid(polygon, &why) && bg::area(polygon.geometry) > 0.0) {
      result.ok = true;
      result.polygon = std::move(polygon);
      result.fallback_level = level;
      return result;
    }
    result.error = why;
  }
  return fail("no valid polygon at any level: " + result.error);
}

}  // namespace pex::mapping
