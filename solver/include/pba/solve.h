// The solver's entry points: run one scene, write its result files.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pba/scene.h"
#include "pba/status.h"

namespace pba {

struct ProgressEvent {
  std::string phase;    // mesh, assemble, factorize, solve, estimate, write
  double fraction = 0;  // of the whole solve, 0..1, non-decreasing
  std::string message;  // for people
};

struct SolveOptions {
  // The threads the solve may use, and the bound of every library it
  // calls: its own OpenMP loops, CHOLMOD's OpenMP teams and OpenBLAS
  // (docs/performance.md). 0 = as many as OpenMP gives (OMP_NUM_THREADS,
  // else one per core).
  int threads = 0;
  // Called from the solving thread at each phase change and within long phases.
  std::function<void(const ProgressEvent&)> progress;
  // Polled between and within phases; when it becomes true the solve returns
  // Status::Cancelled.
  const std::atomic<bool>* cancel = nullptr;
  // A directory of built atlas meshes shared by solves (created if absent):
  // a solve whose atlas, options and solver version match an entry takes
  // its mesh instead of meshing again. Empty: no cache.
  std::filesystem::path atlas_cache_dir;
  // The bound of that directory [bytes]; least recently used entries go.
  std::uint64_t atlas_cache_max_bytes = std::uint64_t{2} << 30;
  // QUASI_STATIC: a directory (created if absent) that receives
  // checkpoint.h5 after converged steps, at most every checkpoint_every_s of
  // wall time and always after the last step, so that an interrupted run
  // can be resumed (restart_from). Empty: no checkpoints.
  std::filesystem::path checkpoint_dir;
  double checkpoint_every_s = 30;
  // QUASI_STATIC: a checkpoint.h5 to continue from. Its scene must have the
  // same mesh, materials, constraints and contacts; the time curve may run
  // further (an extended hold). Empty: start at t = 0.
  std::filesystem::path restart_from;
};

// The MPI job a solve may run in: `mpirun -np N pba-solve ...` starts N
// processes (ranks) that each run the same solve and share its linear
// solves (the PETSc backends: AMG, MUMPS, and AUTO's choice between them),
// so every rank ends with the same answer; rank 0 writes the results.
struct SolveRanks {
  int rank = 0;
  int size = 1;
  int on_node = 1;  // ranks on this machine: they share its cores
};
// In a process launched by mpirun or srun, starts MPI (and PETSc) on every
// rank, collectively, and reports this rank; in any other process starts
// nothing and reports rank 0 of 1. Call before SolveScene, on every rank.
Status JoinRanks(SolveRanks* ranks);
// Ends every rank of the MPI job with exit code `code`, when there are
// several: a rank that stops with an error must not leave the others
// waiting for it. In a process of its own, returns.
void EndRanksWith(int code);

struct PhaseTime {
  std::string phase;
  double seconds = 0;
};

struct Reaction {
  std::string set;
  std::array<double, 3> force_n{0, 0, 0};  // total reaction on the set [N]
};

// The estimate on one region (structure) of the model.
struct RegionErrorEstimate {
  std::string name;  // the region's (structure's) name; "body" when there is one
  int64_t elements = 0;
  double relative_error = 0;  // energy-norm relative error on the region, fraction
  double share = 0;           // the region's share of the squared total error, 0..1
};

struct ErrorEstimate {
  bool estimated = false;
  std::string method;                        // e.g. "Zienkiewicz-Zhu stress recovery"
  double relative_error = 0;                 // energy-norm relative error, fraction
  std::string note;                          // how to read it, or why it is not estimated
  std::vector<RegionErrorEstimate> regions;  // per region, in the mesh's order
};

// One converged load increment of a nonlinear analysis.
struct IncrementSummary {
  double load_factor = 0;        // at the end of the increment, 0..1
  int iterations = 0;            // Newton iterations it took
  double relative_residual = 0;  // final ||R|| / ||f_int||
  // Negative eigenvalues of the tangent at its end (0: a stable equilibrium;
  // -1: not known, the last iteration used an approximate tangent).
  int negative_eigenvalues = 0;
};

// A rigid body's contact at the end of the analysis (scene.contacts).
struct ContactSummary {
  std::string name;
  std::array<double, 3> force_n{0, 0, 0};  // force of the tissue on the body [N]
  double peak_force_n = 0;                 // largest |force| over the steps [N]
  double area_mm2 = 0;                     // tissue surface in contact [mm^2]
  double max_penetration_mm = 0;           // deepest penetration left [mm]
  double penalty_pa_per_mm = 0;            // penalty stiffness per area [Pa/mm]
  int augmentations = 0;                   // Uzawa updates over the analysis
};

// Displacement of one structure (region) at the end (outputs.structure_displacements).
struct StructureDisplacement {
  std::string name;
  std::array<double, 3> mean_mm{0, 0, 0};  // volume-weighted mean displacement [mm]
  double max_mm = 0;                       // largest nodal displacement magnitude [mm]
};

// A profile (outputs.profiles) at the end of the analysis: how much of the
// line lies in the body and its largest stress along the line.
struct ProfileSummary {
  std::string name;
  int points = 0;  // sampled
  int inside = 0;  // of them, in the body (the others have empty values)
  // t . sigma . t of largest magnitude over the inside points, signed
  // (negative: compression) [Pa]; where it is, as the distance from the
  // line's start [mm] and the point (reference configuration) [mm].
  double max_stress_along_pa = 0;
  double at_distance_mm = 0;
  std::array<double, 3> at_mm{0, 0, 0};
};

// One decision of `formulation: AUTO` (pba/scene.h).
struct ModelDecision {
  std::string aspect;    // "viscoelasticity", "finite strain", "structures"
  std::string decision;  // what was modelled, e.g. "long-term modulus"
  std::string reason;    // the quantity that drove it, e.g. "tau 0.5 s vs loading 80 s"
  bool reduces = false;  // true when it models less than the scene wrote
};

// What the reduced model of `formulation: AUTO` costs and saves, from the
// same scene on meshes twice as coarse, once reduced and once in full.
// One solve of an adaptive refinement (mesh.adapt).
struct AdaptCycle {
  int64_t elements = 0;
  int64_t nodes = 0;
  int64_t dofs = 0;           // unknowns after constraints
  double relative_error = 0;  // estimated energy-norm relative error, fraction
  double wall_time_s = 0;     // of this cycle's solve, meshing included
  int64_t marked = 0;         // elements marked for bisection after it (0: last)
  // The largest relative change of a result the cycle shares with the one
  // before (largest displacement, reactions, contact forces, structure
  // displacements), and which; 0 and empty for the first.
  double change = 0;
  std::string changed_quantity;
};

// The adaptive refinement that made the mesh (mesh.adapt), when asked for.
struct Adaptation {
  bool adapted = false;
  double target_error = 0;  // fraction
  int64_t max_elements = 0;
  int max_cycles = 0;
  double refine_fraction = 0;
  bool reached = false;     // the last cycle's estimate is within the target
  std::string stop_reason;  // why the cycles ended, for people
  std::vector<AdaptCycle> cycles;
};

struct ReductionEstimate {
  bool estimated = false;
  // Whether the reduced model was solved: only when estimated and the
  // difference is within `tolerance`; otherwise the scene as written was.
  bool kept = false;
  double tolerance = 0;            // formulation_tolerance as run (fraction)
  double relative_difference = 0;  // largest over the compared quantities
  std::string quantity;            // the one that differed most
  double reduced_coarse_s = 0;     // wall times of the two coarse runs [s]
  double full_coarse_s = 0;
  std::string note;
};

// One time step of a QUASI_STATIC analysis.
struct TimeStepSummary {
  double time_s = 0;
  double step_s = 0;
  double amplitude = 0;  // a(t)
  int iterations = 0;
  double relative_residual = 0;
};

// The peak of one sensor quantity over an EXPLICIT_DYNAMIC run.
struct SensorPeak {
  std::string sensor;
  std::string quantity;      // "pressure_pa", "speed_m_per_s", "strain"
  double peak_raw = 0;       // largest value of the raw samples
  double time_raw_s = 0;     // when [s]
  double peak_filtered = 0;  // largest value after the low-pass filter
  double time_filtered_s = 0;
};

// An explicit run (EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION).
struct ExplicitSummary {
  bool ran = false;
  int64_t steps = 0;
  double end_time_s = 0;            // simulated time reached [s]
  double stable_step_s = 0;         // smallest stable step at the start [s]
  double first_step_s = 0;          // step taken at the start (factor x stable) [s]
  double last_step_s = 0;           // step at the end (it may have shrunk) [s]
  int step_reductions = 0;          // times the step had to shrink
  std::string controlling_element;  // "element 812 (Putamen), length 0.41 mm"
  // Energies at the end [J] and the balance error
  // |kinetic + internal + hourglass + contact + damping + eroded - external
  //  - initial kinetic|, its largest value over the run relative to the
  // largest external work, kinetic or internal energy of the run.
  double kinetic_j = 0;
  double internal_j = 0;
  double hourglass_j = 0;
  double contact_j = 0;
  double damping_j = 0;
  double eroded_j = 0;
  double external_work_j = 0;
  double max_energy_error = 0;
  int eroded_elements = 0;
  double eroded_mass_kg = 0;
  // Selective mass scaling: elements given mass, the mass added and the
  // model's mass before it [kg].
  int mass_scaled_elements = 0;
  double added_mass_kg = 0;
  double model_mass_kg = 0;
  // Penalty stiffness of the impactors, per node [N/m]: the smallest and
  // largest over the contact nodes.
  double contact_stiffness_min_n_per_m = 0;
  double contact_stiffness_max_n_per_m = 0;
  // Speed: element updates (elements x steps) per second of the time loop.
  double element_updates_per_s = 0;
  // DYNAMIC_RELAXATION: whether it converged and the final out-of-balance
  // force relative to the largest reaction or load.
  bool converged = false;
  double relative_residual = 0;
};

// What a solve reports beside its fields. Mirrors pba.v1.Summary.
struct Summary {
  std::string scene_name;
  // What was modelled.
  std::string geometry;      // "box 10 x 10 x 20 mm"
  std::string element_type;  // "TET4"
  int64_t nodes = 0;
  int64_t elements = 0;
  int64_t dofs = 0;  // free unknowns
  int64_t constrained_dofs = 0;
  std::string material;       // "tissue: linear elastic, E = 3000 Pa, nu = 0.45"
  std::string analysis;       // "linear static (small strain)"
  std::string linear_solver;  // "CHOLMOD supernodal Cholesky"
  std::vector<std::string> notes;
  // Every option the analysis ran with, defaults included, as (scene field
  // path, value with its unit), e.g. ("analysis.nonlinear.increments", "5").
  std::vector<std::pair<std::string, std::string>> options;
  // Key results.
  double max_displacement_mm = 0;
  std::array<double, 3> max_displacement_at_mm{0, 0, 0};
  double max_von_mises_pa = 0;
  double strain_energy_j = 0;
  std::vector<Reaction> reactions;
  double relative_residual = 0;
  // Nonlinear analyses: converged increments, total Newton iterations and
  // the number of increments cut back and retried. Empty / 0 for linear ones.
  std::vector<IncrementSummary> increments;
  int newton_iterations = 0;
  int increment_cuts = 0;
  // Where the Newton phase's time went [s]: assembling tangents,
  // factorising and solving, evaluating residuals (line search included).
  double newton_assembly_s = 0;
  double newton_linear_solve_s = 0;
  double newton_residual_s = 0;
  // QUASI_STATIC: the converged time steps (their load factor in
  // `increments` is a(t)); contacts and structure displacements at the end.
  std::vector<TimeStepSummary> time_steps;
  std::vector<ContactSummary> contacts;
  std::vector<StructureDisplacement> structure_displacements;
  std::vector<ProfileSummary> profiles;  // outputs.profiles, in order
  // EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION.
  ExplicitSummary explicit_run;
  std::vector<SensorPeak> sensor_peaks;  // per sensor and quantity, in order
  // formulation: AUTO.
  std::vector<ModelDecision> decisions;
  ReductionEstimate reduction;
  Adaptation adaptation;  // mesh.adapt
  ErrorEstimate error;
  // Speed.
  double wall_time_s = 0;
  std::vector<PhaseTime> phases;
  int threads = 1;  // per process
  int ranks = 1;    // MPI processes that shared the solve (JoinRanks)
};

// The fields sampled along one line of outputs.profiles, written as
// profile_<name>.csv: one row per point, the columns named with their units
// (distance_mm, x_mm, ..., strain_along; docs/results.md). A point outside
// the body has NaN values past its position (empty cells in the file).
struct ProfileTable {
  std::string name;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

// The solved fields, in the units result.h5 uses.
struct Solution {
  // Mesh: node coordinates [mm], nodes x 3 row-major; element connectivity
  // (named `tets` after the first element type), elements x
  // nodes_per_element row-major, 0-based, positively oriented: 4 corners of
  // a tetrahedron, then for 10-node elements the mid-edge nodes of edges
  // (0,1) (1,2) (2,0) (0,3) (1,3) (2,3); for 8-node hexahedra one face
  // 0-1-2-3 and the opposite one, node 4 + i across from node i (the orders
  // of Abaqus C3D4 / C3D10 / C3D8, VTK and XDMF).
  std::vector<double> nodes_mm;
  std::vector<int64_t> tets;
  int nodes_per_element = 4;
  // Element regions (an atlas's structures): region_names[element_region[e]]
  // is element e's region. Both empty for a one-region body.
  std::vector<std::string> region_names;
  std::vector<int64_t> element_region;
  // Nodal displacement [mm], nodes x 3.
  std::vector<double> displacement_mm;
  // Per element, Voigt order xx yy zz yz xz xy (engineering shear strain).
  std::vector<double> stress_pa;     // elements x 6, Cauchy stress [Pa]
  std::vector<double> strain;        // elements x 6, small or Green-Lagrange strain [-]
  std::vector<double> von_mises_pa;  // elements, of the Cauchy stress [Pa]
  // Nonlinear analyses only (else empty): second Piola-Kirchhoff stress
  // (elements x 6 [Pa]), Euler-Almansi strain (elements x 6) and J = det F
  // (elements).
  std::vector<double> pk2_stress_pa;
  std::vector<double> almansi_strain;
  std::vector<double> jacobian;
  // Nonlinear analyses: the displacement at the end of every converged load
  // increment (steps x nodes x 3 [mm]) and its load factor (steps).
  std::vector<double> step_load_factor;
  std::vector<double> step_time_s;  // QUASI_STATIC: the time of each step [s]
  std::vector<double> step_displacement_mm;
  // QUASI_STATIC: one row per converged step (time first), written as
  // history.csv: time, amplitude, each reaction set's force, each contact's
  // force, area and penetration, each reported structure's mean displacement.
  // EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION: one row per output interval: time,
  // step, the energies and the balance error, each impactor's force.
  std::vector<std::string> history_columns;  // with units, e.g. "time_s"
  std::vector<std::vector<double>> history;
  // Element-wise estimated error share (ZZ), elements; empty if not estimated.
  std::vector<double> error_indicator;
  // outputs.profiles, sampled from the final fields above.
  std::vector<ProfileTable> profiles;
  // EXPLICIT_DYNAMIC with outputs.sensors: one row per sample, written as
  // sensors.csv: time_s, then per sensor its raw and filtered pressure,
  // speed and strain (docs/results.md).
  std::vector<std::string> sensor_columns;
  std::vector<std::vector<double>> sensor_rows;
  Summary summary;
};

// Validates, meshes and solves `scene`. On success fills `solution` (fields
// and summary except the write phase). Returns kInvalidArgument for bad
// input, kNumerical when the solve breaks down, kCancelled when asked to stop.
Status SolveScene(const SceneSpec& scene, const SolveOptions& options, Solution* solution);

// Writes result.h5 (mesh, fields, unit attributes) and result.xdmf (the
// ParaView view of result.h5) into the existing directory `dir` - with a
// history, also history.csv and history.png (its forces against time), and
// with profiles profile_<name>.csv each - and appends the write phase to
// solution.summary. Fields not requested in
// `scene.outputs` are left out.
Status WriteResultFiles(const SceneSpec& scene, Solution* solution,
                        const std::filesystem::path& dir);

// Writes the scene's model (mesh, node sets named as the face sets, material,
// resolved constraints, one static step printing reactions and
// displacements) as an Abaqus input deck that CalculiX runs (`ccx -i NAME`).
// SI units. Returns kInvalidArgument for a bad scene, kIo if it cannot write.
Status ExportAbaqusInput(const SceneSpec& scene, const std::filesystem::path& file);

// Version string of the solver library, e.g. "0.1.0".
const char* SolverVersion();

// The surfaces of the structures of the structure set in `set_dir`
// (atlas/structure_set.h) as glTF binary, surfaces.glb's format (one node
// per structure, no displacement; docs/results.md): the set meshed as an
// atlas scene's would be, with facets of at most `facet_mm`, but without
// ODT smoothing, sliver removal, improvement or validation, since no one
// solves on these tetrahedra and their surface triangles are what a view
// needs. kInvalidArgument for a set that cannot be meshed, naming why.
struct AtlasSurfaces {
  std::string glb;
  int structures = 0;
  int64_t triangles = 0;
};
Status MeshAtlasSurfaces(const std::filesystem::path& set_dir, double facet_mm,
                         AtlasSurfaces* surfaces);

}  // namespace pba
