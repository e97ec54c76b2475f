#include "slam/scan_constraint.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace pex::slam {

ScanConstraint scan_constraint(const ScanPoints& scan, const ScanConstraintOptions& options) {
  ScanConstraint result;
  const auto& beams = scan.beams;
  const int n = static_cast<int>(beams.size());
  const double radius2 = options.neighbour_radius_m * options.neighbour_radius_m;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d p(beams[i].hit_x_m, beams[i].hit_y_m);
    Eigen::Vector2d sum = p;
    Eigen::Matrix2d outer = p * p.transpose();
    int count = 1;
    for (int j = std::max(0, i - options.neighbours); j <= std::min(n - 1, i + options.neighbours); ++j) {
      if (j == i) continue;
      const Eigen::Vector2d q(beams[j].hit_x_m, beams[j].hit_y_m);
      if ((q - p).squaredNorm() > radius2) continue;
      sum += q;
      outer += q * q.transpose();
      ++count;
    }
    if (count < 3) continue;  // an isolated return: no surface to speak of
    const Eigen::Vector2d mean = sum / count;
    const Eigen::Matrix2d scatter = outer / count - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
    const double small = eig.eigenvalues()(0), large = eig.eigenvalues()(1);
    if (large <= 0.0) continue;
    if (small <= options.line_flatness * large || small <= options.range_noise_m * options.range_noise_m) {
      const Eigen::Vector2d normal = eig.eigenvectors().col(0);
      result.information += normal * normal.transpose();
      ++result.line_points;
    } else {
      result.information += Eigen::Matrix2d::Identity();
      ++result.corner_points;
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(result.information);
  for (int k = 0; k < 2; ++k)
    if (eig.eigenvalues()(k) < options.min_information_beams)
      result.unconstrained += eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose();
  return result;
}

}  // namespace pex::slam
