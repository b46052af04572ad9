// Checkpoints of a QUASI_STATIC solve (checkpoint.h5, docs/results.md):
// everything a converged step hands to the next - the displacement, the
// viscoelastic history of every element, the rigid contacts' multipliers
// and stick points, the history rows and step records so far, the Newton
// solver's next step size and its records - so that an interrupted run, or
// one whose time curve is extended, resumes with the answer an
// uninterrupted run gives.
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/newton_static.h"
#include "analysis/rigid_contact.h"
#include "analysis/step_observer.h"
#include "assembly/discrete_body.h"
#include "assembly/dof_map.h"
#include "material/material_field.h"
#include "mesh/mesh.h"
#include "pba/solve.h"
#include "pba/status.h"

namespace pba {

// What a checkpoint must agree with to be taken up: the sizes of the model
// and SHA-256 digests (hex) of its parts. The time curve is left out, so a
// run may be extended past its checkpoint.
struct ModelFingerprint {
  int64_t nodes = 0;
  int64_t elements = 0;
  int64_t dofs = 0;  // all unknowns, 3 per node
  int64_t free_dofs = 0;
  int64_t materials = 0;  // distinct materials of the field
  int64_t contacts = 0;
  std::string mesh;              // node coordinates and connectivity
  std::string materials_digest;  // materials, relaxation, growth, per-element assignment
  std::string constraints;       // prescribed unknowns and their values
  std::string contacts_digest;   // each contact's nodes, areas, body, penalty, friction
};

ModelFingerprint FingerprintOf(const Mesh& mesh, const DofMap& dofs, const MaterialField& field,
                               const std::vector<const RigidContact*>& contacts);

// FailedPrecondition naming the first part in which the model a checkpoint
// was written for (`checkpoint`) differs from this one (`model`).
Status CompareFingerprints(const ModelFingerprint& checkpoint, const ModelFingerprint& model);

struct Checkpoint {
  std::string solver_version;
  std::string scene_name;
  ModelFingerprint fingerprint;
  double time_s = 0;                                // reached
  double duration_s = 0;                            // the analysis' end time when written
  double load_factor = 0;                           // reached, t / duration
  double next_step = 0;                             // the next increment's size (load factor)
  std::vector<double> u;                            // full displacement [m]
  std::vector<double> material_history;             // MaterialField::SaveHistory
  std::vector<std::vector<double>> contact_states;  // RigidContact::SaveState, per contact
  std::vector<double> peak_contact_force_n;         // per contact, so far
  std::vector<std::string> history_columns;
  std::vector<std::vector<double>> history;
  std::vector<double> step_time_s;
  std::vector<double> step_load_factor;
  std::vector<double> step_displacement_mm;
  // The converged increments, counters, timings and cut reasons so far.
  NewtonReport report;
};

// Writes `checkpoint` as HDF5 to `file` atomically (a temporary file
// renamed over it). kIo when it cannot.
Status WriteCheckpoint(const std::filesystem::path& file, const Checkpoint& checkpoint);
// Reads a file WriteCheckpoint wrote. InvalidArgument (field
// "restart_from") naming what is missing when the file is not a readable
// checkpoint.
Status ReadCheckpoint(const std::filesystem::path& file, Checkpoint* checkpoint);

// Checkpoints and restarts within a QUASI_STATIC solve, after
// SolveOptions::checkpoint_dir, checkpoint_every_s and restart_from.
class Checkpointer {
 public:
  // `body` (whose history a checkpoint holds), `field` (its materials, in
  // the model's fingerprint) and `contacts` must outlive the checkpointer.
  Checkpointer(const SolveOptions& options, std::string scene_name, double duration_s,
               const Mesh& mesh, const DofMap& dofs, DiscreteBody* body, const MaterialField& field,
               std::vector<RigidContact*> contacts);

  bool writes() const { return !options_.checkpoint_dir.empty(); }
  bool restarts() const { return !options_.restart_from.empty(); }

  // Reads options.restart_from, refuses it when it is of another solver
  // version or model, or whose time is at or past this analysis' end, and restores
  // the field's history, the contacts' states, the history rows and step
  // records into `solution`, the peak contact forces and Newton's start
  // (start_load, start_u, start_step).
  Status Restore(Solution* solution, NewtonOptions* newton,
                 std::vector<double>* peak_contact_force);

  // After a converged increment: writes the checkpoint when the last one is
  // checkpoint_every_s old or the analysis has reached its end.
  Status AfterIncrement(double load, double next_step, const Eigen::VectorXd& u,
                        const Solution& solution, const NewtonReport& report,
                        const std::vector<double>& peak_contact_force);

  // Puts the restored checkpoint's increments and counters before those of
  // `report` (the increments solved since), so the summary covers the
  // whole analysis.
  void Merge(NewtonReport* report) const;

  double restored_time_s() const { return restored_.time_s; }

 private:
  const SolveOptions& options_;
  std::string scene_name_;
  double duration_s_;
  DiscreteBody* body_;
  std::vector<RigidContact*> contacts_;
  ModelFingerprint fingerprint_;
  Checkpoint restored_;
  std::chrono::steady_clock::time_point last_write_;
};

// The checkpoints as an observer of Newton's converged increments
// (NewtonOptions::observers): after each, Checkpointer::AfterIncrement with
// the run's solution, report and peak contact forces as they stand. All
// must outlive it.
class CheckpointObserver final : public StepObserver {
 public:
  CheckpointObserver(Checkpointer* checkpoints, const Solution* solution,
                     const NewtonReport* report, const std::vector<double>* peak_contact_force)
      : checkpoints_(checkpoints),
        solution_(solution),
        report_(report),
        peak_contact_force_(peak_contact_force) {}
  Status AfterStep(const StepState& state) override {
    return checkpoints_->AfterIncrement(state.time_s, state.next_step, *state.u, *solution_,
                                        *report_, *peak_contact_force_);
  }

 private:
  Checkpointer* checkpoints_;
  const Solution* solution_;
  const NewtonReport* report_;
  const std::vector<double>* peak_contact_force_;
};

}  // namespace pba
