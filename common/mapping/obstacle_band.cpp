// Boost.Geometry 1.74 buffer code trips -Wmaybe-uninitialized when inlined
// into our code; the warning is in Boost, not here.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "mapping/obstacle_band.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/angle.hpp"
#include "mapping/typed_ops.hpp"

namespace pex::mapping {

namespace {

namespace bs = bg::strategy::buffer;

// Points closer than this are one point.
constexpr double kGridSnap = 1e-9;

// Points within kGridSnap of the point before them, but for the closing point.
void drop_repeated_points(Ring& ring) {
  if (ring.size() < 3) return;
  Ring out;
  out.reserve(ring.size());
  for (std::size_t i = 0; i + 1 < ring.size(); ++i)
    if (out.empty() || bg::distance(out.back(), ring[i]) > kGridSnap) out.push_back(ring[i]);
  while (out.size() > 1 && bg::distance(out.back(), out.front()) <= kGridSnap) out.pop_back();
  out.push_back(out.front());
  ring = std::move(out);
}

}  // namespace

Chains obstacle_chains(const TypedPolygon& scan) {
  Chains chains;
  auto add_ring_chains = [&](const Ring& ring, const std::vector<EdgeType>& types) {
    const std::size_t n = types.size();
    if (n == 0) return;
    // Start right after a non-obstacle edge so no chain wraps around.
    std::size_t start = 0;
    while (start < n && types[start] == EdgeType::kObstacle) ++start;
    if (start == n) {  // a ring of obstacle edges only
      chains.emplace_back(ring.begin(), ring.end());
      return;
    }
    Chain chain;
    for (std::size_t j = 1; j <= n; ++j) {
      const std::size_t i = (start + j) % n;
      if (types[i] == EdgeType::kObstacle) {
        if (chain.empty()) chain.push_back(ring[i]);
        chain.push_back(ring[i + 1]);
      } else if (!chain.empty()) {
        chains.push_back(std::move(chain));
        chain.clear();
      }
    }
    if (!chain.empty()) chains.push_back(std::move(chain));
  };
  add_ring_chains(scan.geometry.outer(), scan.edge_types[0]);
  for (std::size_t k = 0; k < scan.geometry.inners().size(); ++k)
    add_ring_chains(scan.geometry.inners()[k], scan.edge_types[1 + k]);
  return chains;
}

namespace {

constexpr int kBandPointsPerCircle = 8;

// The offset of an open polyline `distance_m` to its right: round joins
// where the polyline turns left (the right side is convex there), the
// offset lines' meeting point where it turns right. Appends to `out`; false
// if a concave join's offset lines do not meet within both segments (a
// segment shorter than the offset: Boost's buffer handles that).
template <class It>
bool append_right_offset(It first, It last, double distance_m, Ring& out) {
  const auto n = static_cast<std::size_t>(std::distance(first, last));
  if (n < 2) return false;
  auto unit = [](const Point& a, const Point& b, double& length) {
    const double dx = b.x() - a.x(), dy = b.y() - a.y();
    length = std::hypot(dx, dy);
    return Point(dx / length, dy / length);
  };
  auto push = [&](const Point& p) {
    if (out.empty() || bg::distance(out.back(), p) > kGridSnap) out.push_back(p);
  };
  double length = 0.0;
  It a = first, b = std::next(first);
  Point d = unit(*a, *b, length);
  if (!(length > 0.0)) return false;
  push(Point(a->x() + d.y() * distance_m, a->y() - d.x() * distance_m));
  for (It c = std::next(b); c != last; ++a, ++b, ++c) {
    double next_length = 0.0;
    const Point e = unit(*b, *c, next_length);
    if (!(next_length > 0.0)) return false;
    const Point from(b->x() + d.y() * distance_m, b->y() - d.x() * distance_m);
    const Point to(b->x() + e.y() * distance_m, b->y() - e.x() * distance_m);
    const double turn = d.x() * e.y() - d.y() * e.x();
    if (turn > 1e-12) {  // left turn: an arc around b from `from` to `to`
      const double a0 = std::atan2(from.y() - b->y(), from.x() - b->x());
      const double sweep = geometry::wrap_angle_positive(std::atan2(to.y() - b->y(), to.x() - b->x()) - a0);
      const int steps = static_cast<int>(std::ceil(sweep / (2.0 * M_PI / kBandPointsPerCircle)));
      push(from);
      for (int k = 1; k < steps; ++k) {
        const double angle = a0 + sweep * k / steps;
        push(Point(b->x() + distance_m * std::cos(angle), b->y() + distance_m * std::sin(angle)));
      }
      push(to);
    } else if (turn < -1e-12) {  // right turn: where the two offset lines meet
      const double t = ((to.x() - from.x()) * e.y() - (to.y() - from.y()) * e.x()) / turn;  // along d from `from`
      const double u = ((to.x() - from.x()) * d.y() - (to.y() - from.y()) * d.x()) / turn;  // along e from `to`
      if (t > 0.0 || -t > length || u < 0.0 || u > next_length) return false;
      push(Point(from.x() + t * d.x(), from.y() + t * d.y()));
    } else {
      push(from);
    }
    d = e;
    length = next_length;
  }
  push(Point(b->x() + d.y() * distance_m, b->y() - d.x() * distance_m));
  return true;
}

// The band of one open chain: its right offset by outer_m forward, then the
// right offset of the reversed chain (its left side) by inner_m, flat ends.
// Counter-clockwise. nullopt if a join cannot be built this way.
std::optional<Polygon> chain_band(const Chain& chain, double inner_m, double outer_m) {
  Polygon band;
  Ring& ring = band.outer();
  if (!append_right_offset(chain.begin(), chain.end(), outer_m, ring) ||
      !append_right_offset(chain.rbegin(), chain.rend(), inner_m, ring))
    return std::nullopt;
  while (ring.size() > 1 && bg::distance(ring.back(), ring.front()) <= kGridSnap) ring.pop_back();
  if (ring.size() < 3) return std::nullopt;
  ring.push_back(ring.front());
  return band;
}

}  // namespace

std::optional<MultiPolygon> direct_obstacle_band(const Chains& chains, double inner_m, double outer_m) {
  TypedMultiPolygon band;
  std::vector<Box> boxes;
  TypedOpOptions union_options;
  union_options.uniform_type = EdgeType::kObstacle;  // and validate: the union's result is checked
  for (const auto& chain : chains) {
    if (chain.size() < 2 || bg::equals(chain.front(), chain.back())) return std::nullopt;  // closed: a ring
    auto polygon = chain_band(chain, inner_m, outer_m);
    if (!polygon) return std::nullopt;
    TypedPolygon typed{std::move(*polygon), {}};
    typed.edge_types.push_back(std::vector<EdgeType>(typed.geometry.outer().size() - 1, EdgeType::kObstacle));
    if (!is_clearly_valid(std::span(&typed, 1))) return std::nullopt;  // the chain's band folds
    const Box box = bg::return_envelope<Box>(typed.geometry);
    const bool meets = std::any_of(boxes.begin(), boxes.end(), [&](const Box& b) { return !bg::disjoint(b, box); });
    if (!meets) {
      band.push_back(std::move(typed));
      boxes.push_back(box);
      continue;
    }
    // Chains closer than the band's width (a gap in a wall, a corner): their
    // bands overlap and are united.
    auto united = typed_union(band, {typed}, union_options);
    if (!united.ok) return std::nullopt;
    band = std::move(united.polygons);
    boxes.clear();
    for (const auto& p : band) boxes.push_back(bg::return_envelope<Box>(p.geometry));
  }
  if (!is_clearly_valid(band) && !bg::is_valid(geometry_of(band))) return std::nullopt;
  return geometry_of(band);
}

void trim_chain_ends(Chains& chains, double end_trim_m) {
  if (!(end_trim_m > 0.0)) return;
  for (auto& chain : chains) {
    if (chain.size() < 2 || bg::equals(chain.front(), chain.back())) continue;  // closed: no ends
    const double cut = std::min(end_trim_m, 0.25 * static_cast<double>(bg::length(chain)));
    // Walks from the front, dropping `cut` of length; then the same reversed.
    auto trim_front = [cut](Chain& c) {
      double left = cut;
      std::size_t i = 0;
      while (i + 1 < c.size()) {
        const double d = bg::distance(c[i], c[i + 1]);
        if (d > left) {
          const double t = left / d;
          c[i] = Point(c[i].x() + t * (c[i + 1].x() - c[i].x()), c[i].y() + t * (c[i + 1].y() - c[i].y()));
          break;
        }
        left -= d;
        ++i;
      }
      c.erase(c.begin(), c.begin() + static_cast<std::ptrdiff_t>(i));
    };
    trim_front(chain);
    std::reverse(chain.begin(), chain.end());
    trim_front(chain);
    std::reverse(chain.begin(), chain.end());
  }
}

MultiPolygon obstacle_band(const TypedPolygon& scan, double inner_m, double outer_m, std::string* why,
                           double end_trim_m) {
  Chains chains = obstacle_chains(scan);
  trim_chain_ends(chains, end_trim_m);
  MultiPolygon band;
  if (chains.empty()) return band;
  if (auto direct = direct_obstacle_band(chains, inner_m, outer_m)) return std::move(*direct);  // checked there
  // A closed chain, a chain whose band folds, a failed union: Boost's buffer.
  bg::buffer(chains, band, bs::distance_asymmetric<double>(inner_m, outer_m), bs::side_straight(),
             bs::join_round(kBandPointsPerCircle), bs::end_flat(), bs::point_circle(kBandPointsPerCircle));
  // It leaves repeated points where a side meets a flat end; without them
  // the band passes the cheap validity test.
  for (auto& polygon : band) {
    drop_repeated_points(polygon.outer());
    for (auto& inner : polygon.inners()) drop_repeated_points(inner);
  }
  std::string reason;
  if (!is_clearly_valid(with_uniform_type(band, EdgeType::kObstacle)) && !bg::is_valid(band, reason)) {
    if (why) *why = "obstacle band invalid: " + reason;
    band.clear();
  }
  return band;
}

}  // namespace pex::mapping
