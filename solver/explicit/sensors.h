// Sensors of an explicit analysis (outputs.sensors): the pressure
// -tr(sigma)/3, the speed |v| and the largest principal Green-Lagrange
// strain in magnitude (a compression counts) at points (or small balls) of the body, sampled at a
// fixed rate, then low-pass filtered without phase shift (signal/butterworth.h) and reduced to
// peaks.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "explicit/tled_model.h"
#include "mesh/mesh.h"
#include "pba/scene.h"
#include "pba/solve.h"

namespace pba {

class SensorArray {
 public:
  // Finds each sensor's elements: the one holding the point, or those whose
  // centroid lies within its radius. Fails naming
  // outputs.sensors[i].position_mm (outside the body) or .radius_mm (a
  // ball that holds no centroid).
  static Status Locate(const std::vector<SensorSpec>& specs, const Mesh& mesh,
                       const TledModel& model, SensorArray* out);

  bool empty() const { return sensors_.empty(); }
  std::size_t samples() const { return time_.size(); }
  // Keeps the sensors' nodal velocities v^(n-1/2) before a step's update.
  void Before(const Eigen::VectorXd& v);
  // Records the state at time t^n from the model's evaluation at t^n and
  // v^(n+1/2) (the velocity the mean of the half steps around t^n).
  void Sample(double t, const TledModel& model, const Eigen::VectorXd& v);
  // Resamples the record every `interval` [s] from t = 0 (linear
  // interpolation between steps), filters it at that rate (order, cutoff
  // [Hz]; the body at rest before t = 0, so the record starts from a
  // history of its first value, not a reflection) and fills
  // solution->sensor_columns / sensor_rows and the summary's sensor_peaks
  // (the raw peaks from the resampled record).
  Status Finish(int order, double cutoff_hz, double interval, Solution* solution) const;

 private:
  struct Sensor {
    std::string name;
    std::vector<int> elements;
    std::vector<double> weights;  // volume fractions, summing to 1
    std::vector<int> nodes;       // the elements' nodes, for the velocity
  };
  std::vector<Sensor> sensors_;
  std::vector<double> time_;
  std::vector<double> velocity_before_;  // per sensor node, 3 each, in order
  // Per sensor: pressure, speed, strain series.
  std::vector<std::vector<double>> pressure_, speed_, strain_;
};

// Largest principal value of the Green-Lagrange strain of F, and the
// largest magnitude of the three.
double LargestPrincipalStrain(const Eigen::Matrix3d& f);
double LargestPrincipalStrainMagnitude(const Eigen::Matrix3d& f);

}  // namespace pba
