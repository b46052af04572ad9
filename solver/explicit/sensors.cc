#include "explicit/sensors.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/format.h"
#include "fem/hex8.h"
#include "signal/butterworth.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;

// True when reference point p lies in tetrahedron e (barycentric
// coordinates), with a relative tolerance.
bool TetContains(const Mesh& mesh, int e, const Eigen::Vector3d& p) {
  constexpr double kTol = 1e-9;
  const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
  Eigen::Matrix3d a;
  for (int k = 0; k < 3; ++k) a.col(k) = (x.row(k + 1) - x.row(0)).transpose();
  const Eigen::Vector3d l = a.partialPivLu().solve(p - x.row(0).transpose());
  return l.minCoeff() >= -kTol && l.sum() <= 1 + kTol;
}

// The same for hexahedron e (Newton on the trilinear map).
bool HexContains(const Mesh& mesh, int e, const Eigen::Vector3d& p) {
  constexpr double kTol = 1e-9;
  const Hex8Nodes x = HexCorners(mesh, e);
  const Eigen::Vector3d lo = x.colwise().minCoeff().transpose(),
                        hi = x.colwise().maxCoeff().transpose();
  if ((p.array() < lo.array() - kTol * (hi - lo).norm()).any() ||
      (p.array() > hi.array() + kTol * (hi - lo).norm()).any()) {
    return false;
  }
  Eigen::Vector3d xi = Eigen::Vector3d::Zero();
  for (int it = 0; it < 30; ++it) {
    const Eigen::Vector3d r = x.transpose() * Hex8ShapeFunctions(xi) - p;
    const Eigen::Matrix3d j = x.transpose() * Hex8NaturalGradients(xi);
    const Eigen::Vector3d step = j.partialPivLu().solve(r);
    xi -= step;
    if (step.norm() < 1e-12) break;
  }
  return xi.cwiseAbs().maxCoeff() <= 1 + 1e-7;
}

// True when reference point p lies in element e; a 10-node element is taken
// as its corners' straight-sided tetrahedron.
bool Contains(const Mesh& mesh, int e, const Eigen::Vector3d& p) {
  switch (mesh.shape()) {
    case ElementShape::kTet4:
    case ElementShape::kTet10:
      return TetContains(mesh, e, p);
    case ElementShape::kHex8:
      return HexContains(mesh, e, p);
  }
  return false;
}

// The mean of the corners.
Eigen::Vector3d Centroid(const Mesh& mesh, int e) {
  switch (mesh.shape()) {
    case ElementShape::kTet4:
    case ElementShape::kTet10:
      return TetCorners(mesh, e).colwise().mean().transpose();
    case ElementShape::kHex8:
      return HexCorners(mesh, e).colwise().mean().transpose();
  }
  return Eigen::Vector3d::Zero();
}

// The zero-phase filtered signal of a body that was at rest before the
// record began: `lead` copies of the first sample go before it (what the
// sensor read before t = 0), so that the filter starts from the true
// history rather than a reflection of the record; they are dropped again.
std::vector<double> FilterFromRest(const ButterworthLowPass& filter, const std::vector<double>& raw,
                                   std::size_t lead) {
  std::vector<double> padded(lead, raw.front());
  padded.insert(padded.end(), raw.begin(), raw.end());
  const std::vector<double> smooth = filter.FilterZeroPhase(padded);
  return std::vector<double>(smooth.begin() + static_cast<std::ptrdiff_t>(lead), smooth.end());
}

}  // namespace

namespace {

// The principal Green-Lagrange strains of F, ascending.
Eigen::Vector3d PrincipalStrains(const Eigen::Matrix3d& f) {
  const Eigen::Matrix3d e = 0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(e, Eigen::EigenvaluesOnly);
  return eig.eigenvalues();
}

}  // namespace

double LargestPrincipalStrain(const Eigen::Matrix3d& f) { return PrincipalStrains(f)(2); }

double LargestPrincipalStrainMagnitude(const Eigen::Matrix3d& f) {
  return PrincipalStrains(f).cwiseAbs().maxCoeff();
}

Status SensorArray::Locate(const std::vector<SensorSpec>& specs, const Mesh& mesh,
                           const TledModel& model, SensorArray* out) {
  *out = SensorArray();
  const int ne = mesh.num_elements();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const SensorSpec& spec = specs[i];
    const std::string path = Format("outputs.sensors[%zu]", i);
    const Eigen::Vector3d p =
        Eigen::Vector3d(spec.position_mm[0], spec.position_mm[1], spec.position_mm[2]) * kMm;
    Sensor s;
    s.name = spec.name;
    if (spec.radius_mm > 0) {
      const double r = spec.radius_mm * kMm;
      for (int e = 0; e < ne; ++e) {
        if ((Centroid(mesh, e) - p).norm() <= r) s.elements.push_back(e);
      }
      if (s.elements.empty()) {
        return Status::FailedPrecondition(
            path + ".radius_mm",
            Format("sensor %s: no element's centroid lies within %g mm of (%g, %g, %g) mm; "
                   "enlarge the radius or move the sensor into the body",
                   spec.name.c_str(), spec.radius_mm, spec.position_mm[0], spec.position_mm[1],
                   spec.position_mm[2]));
      }
    } else {
      for (int e = 0; e < ne && s.elements.empty(); ++e) {
        if (Contains(mesh, e, p)) s.elements.push_back(e);
      }
      if (s.elements.empty()) {
        return Status::FailedPrecondition(
            path + ".position_mm",
            Format("sensor %s at (%g, %g, %g) mm lies outside the body", spec.name.c_str(),
                   spec.position_mm[0], spec.position_mm[1], spec.position_mm[2]));
      }
    }
    double total = 0;
    for (int e : s.elements) total += model.reference_volume(e);
    for (int e : s.elements) {
      s.weights.push_back(model.reference_volume(e) / total);
      const int* nodes = model.element_nodes(e);
      s.nodes.insert(s.nodes.end(), nodes, nodes + model.nodes_per_element());
    }
    std::sort(s.nodes.begin(), s.nodes.end());
    s.nodes.erase(std::unique(s.nodes.begin(), s.nodes.end()), s.nodes.end());
    out->sensors_.push_back(std::move(s));
  }
  out->pressure_.resize(out->sensors_.size());
  out->speed_.resize(out->sensors_.size());
  out->strain_.resize(out->sensors_.size());
  return Status::Ok();
}

void SensorArray::Before(const Eigen::VectorXd& v) {
  velocity_before_.clear();
  for (const Sensor& s : sensors_) {
    for (int n : s.nodes) {
      for (int c = 0; c < 3; ++c) velocity_before_.push_back(v(3 * n + c));
    }
  }
}

void SensorArray::Sample(double t, const TledModel& model, const Eigen::VectorXd& v) {
  if (sensors_.empty()) return;
  time_.push_back(t);
  std::size_t k = 0;
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    const Sensor& s = sensors_[i];
    double pressure = 0, strain = 0;
    for (std::size_t e = 0; e < s.elements.size(); ++e) {
      pressure += s.weights[e] * model.pressure(s.elements[e]);
      strain +=
          s.weights[e] * LargestPrincipalStrainMagnitude(model.DeformationGradient(s.elements[e]));
    }
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    for (int n : s.nodes) {
      for (int c = 0; c < 3; ++c, ++k) velocity(c) += 0.5 * (velocity_before_[k] + v(3 * n + c));
    }
    velocity /= static_cast<double>(s.nodes.size());
    pressure_[i].push_back(pressure);
    speed_[i].push_back(velocity.norm());
    strain_[i].push_back(strain);
  }
}

Status SensorArray::Finish(int order, double cutoff_hz, double interval, Solution* solution) const {
  if (sensors_.empty() || time_.empty()) return Status::Ok();
  // The uniform times, and for each the step record's bracket.
  std::vector<double> grid;
  for (std::size_t k = 0; k * interval <= time_.back() * (1 + 1e-12); ++k) {
    grid.push_back(k * interval);
  }
  const std::size_t n = grid.size();
  const auto resample = [&](const std::vector<double>& record) {
    std::vector<double> out(n);
    std::size_t j = 0;
    for (std::size_t k = 0; k < n; ++k) {
      while (j + 1 < time_.size() && time_[j + 1] < grid[k]) ++j;
      if (j + 1 >= time_.size() || grid[k] <= time_[j]) {
        out[k] = record[std::min(j, record.size() - 1)];
        continue;
      }
      const double w = (grid[k] - time_[j]) / (time_[j + 1] - time_[j]);
      out[k] = (1 - w) * record[j] + w * record[j + 1];
    }
    return out;
  };
  ButterworthLowPass filter;
  const bool filtered = n >= 2;
  if (filtered) {
    PBA_RETURN_IF_ERROR(ButterworthLowPass::Design(order, cutoff_hz, 1 / interval, &filter));
  }
  // Samples of rest put before the record: the filter's settling time,
  // about order / (2 pi fc), three times over.
  const std::size_t lead =
      filtered ? static_cast<std::size_t>(
                     std::ceil(3 * order / (2 * std::numbers::pi * cutoff_hz) / interval))
               : 0;
  std::vector<std::string>& columns = solution->sensor_columns;
  columns = {"time_s"};
  std::vector<std::vector<double>> series;
  struct Quantity {
    const char* key;
    const char* column;
    const std::vector<std::vector<double>>* values;
  };
  const Quantity quantities[] = {{"pressure_pa", "pressure [Pa]", &pressure_},
                                 {"speed_m_per_s", "speed [m/s]", &speed_},
                                 {"strain", "strain", &strain_}};
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    for (const Quantity& q : quantities) {
      const std::vector<double> raw = resample((*q.values)[i]);
      const std::vector<double> smooth = filtered ? FilterFromRest(filter, raw, lead) : raw;
      columns.push_back(sensors_[i].name + " " + q.column);
      columns.push_back(sensors_[i].name + " " + q.column + " filtered");
      SensorPeak peak;
      peak.sensor = sensors_[i].name;
      peak.quantity = q.key;
      peak.peak_raw = raw[0], peak.peak_filtered = smooth[0];
      for (std::size_t k = 0; k < n; ++k) {
        if (raw[k] > peak.peak_raw) peak.peak_raw = raw[k], peak.time_raw_s = grid[k];
        if (smooth[k] > peak.peak_filtered) {
          peak.peak_filtered = smooth[k], peak.time_filtered_s = grid[k];
        }
      }
      solution->summary.sensor_peaks.push_back(peak);
      series.push_back(raw);
      series.push_back(smooth);
    }
  }
  solution->sensor_rows.assign(n, std::vector<double>());
  for (std::size_t k = 0; k < n; ++k) {
    std::vector<double>& row = solution->sensor_rows[k];
    row.reserve(1 + series.size());
    row.push_back(grid[k]);
    for (const std::vector<double>& s : series) row.push_back(s[k]);
  }
  return Status::Ok();
}

}  // namespace pba
