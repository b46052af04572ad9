#include "analysis/checkpoint.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <utility>

#include "core/atomic_write.h"
#include "core/format.h"
#include "core/sha256.h"
#include "io/h5_writer.h"

namespace pba {
namespace {

constexpr const char* kFormat = "pba checkpoint 1";

// Bytes for a digest: the values' own representation (a checkpoint is
// taken up by the solver that wrote it, so byte order and layout agree).
class Digest {
 public:
  template <typename T>
  void Add(const T& value) {
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.append(p, sizeof(T));
  }
  void Add(const std::string& text) {
    Add(static_cast<uint64_t>(text.size()));
    bytes_ += text;
  }
  template <typename T>
  void Add(const std::vector<T>& values) {
    Add(static_cast<uint64_t>(values.size()));
    for (const T& v : values) Add(v);
  }
  std::string Hex() const { return HexOf(Sha256Of(bytes_.data(), bytes_.size())); }

 private:
  std::string bytes_;
};

std::string Join(const std::vector<std::string>& lines) {
  std::string text;
  for (std::size_t i = 0; i < lines.size(); ++i) text += (i > 0 ? "\n" : "") + lines[i];
  return text;
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> lines;
  if (text.empty()) return lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// The HDF5 reading side: datasets back into vectors, string attributes.
class H5Reader {
 public:
  explicit H5Reader(const std::filesystem::path& path) : file_(Open(path), H5Fclose) {}
  bool ok() const { return file_.ok(); }

  // A 1-D or 2-D dataset; `cols` gets its second dimension (0 for 1-D).
  template <typename T>
  bool Read(const std::string& name, std::vector<T>* data, hsize_t* cols = nullptr) {
    bool read = false;
    H5E_BEGIN_TRY {
      Handle dataset(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
      Handle space(dataset.ok() ? H5Dget_space(dataset.get()) : -1, H5Sclose);
      const int rank = space.ok() ? H5Sget_simple_extent_ndims(space.get()) : -1;
      if (rank == 1 || rank == 2) {
        hsize_t dims[2] = {0, 0};
        H5Sget_simple_extent_dims(space.get(), dims, nullptr);
        data->resize(rank == 1 ? dims[0] : dims[0] * dims[1]);
        if (cols != nullptr) *cols = rank == 1 ? 0 : dims[1];
        const hid_t type = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
        read = data->empty() ||
               H5Dread(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data->data()) >= 0;
      }
    }
    H5E_END_TRY;
    return read;
  }

  bool Attribute(const char* object, const char* name, std::string* value) {
    bool read = false;
    H5E_BEGIN_TRY {
      Handle handle(H5Oopen(file_.get(), object, H5P_DEFAULT), H5Oclose);
      Handle attribute(handle.ok() ? H5Aopen(handle.get(), name, H5P_DEFAULT) : -1, H5Aclose);
      Handle type(attribute.ok() ? H5Aget_type(attribute.get()) : -1, H5Tclose);
      if (type.ok() && H5Tget_class(type.get()) == H5T_STRING) {
        std::string buffer(H5Tget_size(type.get()), '\0');
        read = H5Aread(attribute.get(), type.get(), buffer.data()) >= 0;
        value->assign(buffer.c_str());
      }
    }
    H5E_END_TRY;
    return read;
  }

 private:
  static hid_t Open(const std::filesystem::path& path) {
    hid_t id = -1;
    H5E_BEGIN_TRY { id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT); }
    H5E_END_TRY;
    return id;
  }
  Handle file_;
};

}  // namespace

ModelFingerprint FingerprintOf(const Mesh& mesh, const DofMap& dofs, const MaterialField& field,
                               const std::vector<const RigidContact*>& contacts) {
  ModelFingerprint f;
  f.nodes = mesh.num_nodes();
  f.elements = mesh.num_elements();
  f.dofs = dofs.num_dofs();
  f.free_dofs = dofs.num_free();
  f.materials = static_cast<int64_t>(field.entries().size());
  f.contacts = static_cast<int64_t>(contacts.size());
  Digest geometry;
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    for (int c = 0; c < 3; ++c) geometry.Add(mesh.nodes(i, c));
  }
  for (const auto& tet : mesh.tets) geometry.Add(tet);
  for (const auto& edges : mesh.midside) geometry.Add(edges);
  for (const auto& hex : mesh.hexes) geometry.Add(hex);
  f.mesh = geometry.Hex();
  Digest materials;
  for (const MaterialField::Entry& entry : field.entries()) {
    materials.Add(entry.name);
    materials.Add(entry.material->Describe());
    materials.Add(entry.material->ShearModulus());
    materials.Add(entry.material->BulkModulus());
    materials.Add(entry.relaxation.g);
    materials.Add(entry.relaxation.tau_s);
    materials.Add(entry.growth_strain);
    materials.Add(entry.isochoric_scale);
  }
  for (int e = 0; e < field.num_elements(); ++e) materials.Add(field.entry_of(e));
  f.materials_digest = materials.Hex();
  Digest constraints;
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    constraints.Add(dofs.prescribed(dof));
    constraints.Add(dofs.prescribed(dof) ? dofs.prescribed_value(dof) : 0.0);
  }
  f.constraints = constraints.Hex();
  Digest bodies;
  for (const RigidContact* c : contacts) {
    bodies.Add(c->nodes());
    bodies.Add(c->areas());
    const RigidBody& b = c->body();
    bodies.Add(static_cast<int>(b.shape));
    for (int k = 0; k < 3; ++k) {
      bodies.Add(b.position(k));
      bodies.Add(b.axis(k));
      bodies.Add(b.motion(k));
    }
    bodies.Add(b.radius);
    bodies.Add(c->penalty());
    bodies.Add(c->friction());
    bodies.Add(c->tolerance());
  }
  f.contacts_digest = bodies.Hex();
  return f;
}

Status CompareFingerprints(const ModelFingerprint& checkpoint, const ModelFingerprint& model) {
  const auto refuse = [](const std::string& what) {
    return Status::FailedPrecondition("the checkpoint was written for another model: " + what);
  };
  if (checkpoint.nodes != model.nodes || checkpoint.elements != model.elements) {
    return refuse(Format(
        "its mesh has %lld nodes and %lld elements, this scene's %lld and %lld",
        static_cast<long long>(checkpoint.nodes), static_cast<long long>(checkpoint.elements),
        static_cast<long long>(model.nodes), static_cast<long long>(model.elements)));
  }
  if (checkpoint.mesh != model.mesh) {
    return refuse(
        "its mesh has as many nodes and elements but other node coordinates or "
        "connectivity (geometry or mesh options differ)");
  }
  if (checkpoint.materials != model.materials ||
      checkpoint.materials_digest != model.materials_digest) {
    return refuse(Format(
        "its materials differ (%lld distinct there, %lld here; models, "
        "parameters, relaxation, growth or their assignment to elements)",
        static_cast<long long>(checkpoint.materials), static_cast<long long>(model.materials)));
  }
  if (checkpoint.dofs != model.dofs || checkpoint.free_dofs != model.free_dofs ||
      checkpoint.constraints != model.constraints) {
    return refuse(Format(
        "its boundary conditions differ (%lld free unknowns there, %lld here, "
        "or other prescribed values)",
        static_cast<long long>(checkpoint.free_dofs), static_cast<long long>(model.free_dofs)));
  }
  if (checkpoint.contacts != model.contacts ||
      checkpoint.contacts_digest != model.contacts_digest) {
    return refuse(Format(
        "its contacts differ (%lld there, %lld here; sets, bodies, motion, "
        "penalty, friction or tolerance)",
        static_cast<long long>(checkpoint.contacts), static_cast<long long>(model.contacts)));
  }
  return Status::Ok();
}

Status WriteCheckpoint(const std::filesystem::path& file, const Checkpoint& c) {
  return AtomicWrite(file, ".h5", [&](int, const std::string& temporary) {
    H5Writer w(temporary);
    w.Attribute("/", "format", kFormat);
    w.Attribute("/", "solver_version", c.solver_version);
    w.Attribute("/", "scene_name", c.scene_name);
    w.Group("/fingerprint");
    const ModelFingerprint& f = c.fingerprint;
    w.Dataset<int64_t>("/fingerprint/sizes",
                       {f.nodes, f.elements, f.dofs, f.free_dofs, f.materials, f.contacts}, 0, "1",
                       "nodes elements dofs free_dofs materials contacts");
    w.Attribute("/fingerprint", "mesh_sha256", f.mesh);
    w.Attribute("/fingerprint", "materials_sha256", f.materials_digest);
    w.Attribute("/fingerprint", "constraints_sha256", f.constraints);
    w.Attribute("/fingerprint", "contacts_sha256", f.contacts_digest);
    w.Group("/state");
    w.Dataset<double>("/state/time", {c.time_s, c.duration_s, c.load_factor, c.next_step}, 0, "",
                      "time_s duration_s load_factor next_step");
    w.Dataset("/state/u", c.u, 0, "m");
    w.Dataset("/state/material_history", c.material_history, 0, "Pa");
    std::vector<double> contact_values;
    std::vector<int64_t> contact_sizes;
    for (const auto& s : c.contact_states) {
      contact_values.insert(contact_values.end(), s.begin(), s.end());
      contact_sizes.push_back(static_cast<int64_t>(s.size()));
    }
    w.Dataset("/state/contact_state", contact_values, 0, "Pa, m");
    w.Dataset("/state/contact_state_sizes", contact_sizes, 0, "1");
    w.Dataset("/state/peak_contact_force", c.peak_contact_force_n, 0, "N");
    w.Group("/history");
    std::vector<double> rows;
    for (const auto& row : c.history) rows.insert(rows.end(), row.begin(), row.end());
    w.Dataset("/history/rows", rows, c.history_columns.size(), "", Join(c.history_columns));
    w.Group("/steps");
    w.Dataset("/steps/time", c.step_time_s, 0, "s");
    w.Dataset("/steps/load_factor", c.step_load_factor, 0, "1");
    w.Dataset("/steps/displacement", c.step_displacement_mm,
              static_cast<hsize_t>(std::max<std::size_t>(c.u.size(), 1)), "mm");
    w.Group("/newton");
    std::vector<double> increments;
    for (const IncrementRecord& r : c.report.increments) {
      increments.insert(increments.end(),
                        {r.load_factor, r.step, static_cast<double>(r.iterations),
                         r.relative_residual, static_cast<double>(r.negative_eigenvalues)});
    }
    w.Dataset("/newton/increments", increments, 5, "",
              "load_factor step iterations relative_residual negative_eigenvalues");
    const NewtonReport& r = c.report;
    w.Dataset<int64_t>("/newton/counters",
                       {r.total_iterations, r.cuts, r.approximate_iterations, r.modified_iterations,
                        r.indefinite_iterations, r.augmentations},
                       0, "1", "iterations cuts approximate modified indefinite augmentations");
    w.Dataset<double>("/newton/times", {r.assembly_s, r.linear_solve_s, r.residual_s}, 0, "s",
                      "assembly linear_solve residual");
    w.Attribute("/newton", "cut_reasons", Join(r.cut_reasons));
    if (!w.ok()) return Status::Io("cannot write the checkpoint " + file.string());
    return Status::Ok();
  });
}

Status ReadCheckpoint(const std::filesystem::path& file, Checkpoint* c) {
  const auto bad = [&](const std::string& what) {
    return Status::InvalidArgument("restart_from",
                                   file.string() + " is not a readable checkpoint: " + what);
  };
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return bad("no such file");
  H5Reader r(file);
  if (!r.ok()) return bad("not an HDF5 file (truncated or corrupt?)");
  std::string format;
  if (!r.Attribute("/", "format", &format) || format != kFormat) {
    return bad("no checkpoint format attribute \"" + std::string(kFormat) + "\"");
  }
  *c = Checkpoint();
  std::string cut_reasons;
  if (!r.Attribute("/", "solver_version", &c->solver_version) ||
      !r.Attribute("/", "scene_name", &c->scene_name)) {
    return bad("no solver version or scene name");
  }
  ModelFingerprint& f = c->fingerprint;
  std::vector<int64_t> sizes;
  if (!r.Read("/fingerprint/sizes", &sizes) || sizes.size() != 6 ||
      !r.Attribute("/fingerprint", "mesh_sha256", &f.mesh) ||
      !r.Attribute("/fingerprint", "materials_sha256", &f.materials_digest) ||
      !r.Attribute("/fingerprint", "constraints_sha256", &f.constraints) ||
      !r.Attribute("/fingerprint", "contacts_sha256", &f.contacts_digest)) {
    return bad("no model fingerprint");
  }
  f.nodes = sizes[0], f.elements = sizes[1], f.dofs = sizes[2], f.free_dofs = sizes[3];
  f.materials = sizes[4], f.contacts = sizes[5];
  std::vector<double> time, contact_values, rows, increments, times;
  std::vector<int64_t> contact_sizes, counters;
  hsize_t history_cols = 0, increment_cols = 0, step_cols = 0;
  std::string columns;
  if (!r.Read("/state/time", &time) || time.size() != 4) return bad("no /state/time");
  c->time_s = time[0], c->duration_s = time[1], c->load_factor = time[2], c->next_step = time[3];
  if (!r.Read("/state/u", &c->u) || static_cast<int64_t>(c->u.size()) != f.dofs) {
    return bad("no /state/u of the fingerprint's unknowns");
  }
  if (!r.Read("/state/material_history", &c->material_history)) {
    return bad("no /state/material_history");
  }
  if (!r.Read("/state/contact_state", &contact_values) ||
      !r.Read("/state/contact_state_sizes", &contact_sizes) ||
      static_cast<int64_t>(contact_sizes.size()) != f.contacts ||
      !r.Read("/state/peak_contact_force", &c->peak_contact_force_n) ||
      c->peak_contact_force_n.size() != contact_sizes.size()) {
    return bad("no contact state for its contacts");
  }
  std::size_t at = 0;
  for (int64_t n : contact_sizes) {
    if (n < 0 || at + static_cast<std::size_t>(n) > contact_values.size()) {
      return bad("a contact state of the wrong length");
    }
    c->contact_states.emplace_back(contact_values.begin() + static_cast<std::ptrdiff_t>(at),
                                   contact_values.begin() + static_cast<std::ptrdiff_t>(at + n));
    at += static_cast<std::size_t>(n);
  }
  if (!r.Read("/history/rows", &rows, &history_cols) ||
      !r.Attribute("/history/rows", "components", &columns)) {
    return bad("no /history/rows");
  }
  c->history_columns = Split(columns);
  if (history_cols != c->history_columns.size()) return bad("history columns do not match rows");
  for (std::size_t i = 0; history_cols > 0 && i < rows.size(); i += history_cols) {
    c->history.emplace_back(rows.begin() + static_cast<std::ptrdiff_t>(i),
                            rows.begin() + static_cast<std::ptrdiff_t>(i + history_cols));
  }
  if (!r.Read("/steps/time", &c->step_time_s) ||
      !r.Read("/steps/load_factor", &c->step_load_factor) ||
      !r.Read("/steps/displacement", &c->step_displacement_mm, &step_cols) ||
      c->step_time_s.size() != c->step_load_factor.size() ||
      c->step_displacement_mm.size() != c->step_time_s.size() * c->u.size()) {
    return bad("step records of different lengths");
  }
  if (!r.Read("/newton/increments", &increments, &increment_cols) || increment_cols != 5 ||
      !r.Read("/newton/counters", &counters) || counters.size() != 6 ||
      !r.Read("/newton/times", &times) || times.size() != 3 ||
      !r.Attribute("/newton", "cut_reasons", &cut_reasons)) {
    return bad("no Newton records");
  }
  NewtonReport& report = c->report;
  for (std::size_t i = 0; i + 5 <= increments.size(); i += 5) {
    report.increments.push_back({increments[i], increments[i + 1],
                                 static_cast<int>(increments[i + 2]), increments[i + 3],
                                 static_cast<int>(increments[i + 4])});
  }
  report.total_iterations = static_cast<int>(counters[0]);
  report.cuts = static_cast<int>(counters[1]);
  report.approximate_iterations = static_cast<int>(counters[2]);
  report.modified_iterations = static_cast<int>(counters[3]);
  report.indefinite_iterations = static_cast<int>(counters[4]);
  report.augmentations = static_cast<int>(counters[5]);
  report.assembly_s = times[0], report.linear_solve_s = times[1], report.residual_s = times[2];
  report.cut_reasons = Split(cut_reasons);
  return Status::Ok();
}

Checkpointer::Checkpointer(const SolveOptions& options, std::string scene_name, double duration_s,
                           const Mesh& mesh, const DofMap& dofs, DiscreteBody* body,
                           const MaterialField& field, std::vector<RigidContact*> contacts)
    : options_(options),
      scene_name_(std::move(scene_name)),
      duration_s_(duration_s),
      body_(body),
      contacts_(std::move(contacts)),
      last_write_(std::chrono::steady_clock::now()) {
  // Only checkpoints and restarts need it (it reads the whole mesh).
  if (!writes() && !restarts()) return;
  fingerprint_ = FingerprintOf(
      mesh, dofs, field, std::vector<const RigidContact*>(contacts_.begin(), contacts_.end()));
}

Status Checkpointer::Restore(Solution* solution, NewtonOptions* newton,
                             std::vector<double>* peak_contact_force) {
  Checkpoint& c = restored_;
  PBA_RETURN_IF_ERROR(ReadCheckpoint(options_.restart_from, &c));
  if (c.solver_version != SolverVersion()) {
    return Status::FailedPrecondition("the checkpoint " + options_.restart_from.string() +
                                      " was written by solver version " + c.solver_version +
                                      ", this is " + SolverVersion());
  }
  const Status same = CompareFingerprints(c.fingerprint, fingerprint_);
  if (!same.ok()) {
    return Status::FailedPrecondition(options_.restart_from.string() + ": " + same.message());
  }
  if (c.time_s > duration_s_ * (1 + 1e-12)) {
    return Status::FailedPrecondition(Format(
        "the checkpoint reached t = %g s, past this analysis' end at %g s", c.time_s, duration_s_));
  }
  // A run that has ended leaves nothing to solve (and its last step's
  // viscous response, which the final stresses come from, is not kept).
  if (c.time_s >= duration_s_ * (1 - 1e-12)) {
    return Status::FailedPrecondition(
        Format("the checkpoint is at this analysis' end (t = %g s): nothing is left to solve; a "
               "later analysis.time.end_time_s continues it",
               c.time_s));
  }
  PBA_RETURN_IF_ERROR(body_->RestoreHistory(c.material_history));
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const Status restored = contacts_[i]->RestoreState(c.contact_states[i]);
    if (!restored.ok()) {
      return Status::FailedPrecondition(Format("contacts[%zu]: ", i) + restored.message());
    }
  }
  *peak_contact_force = c.peak_contact_force_n;
  solution->history_columns = c.history_columns;
  solution->history = c.history;
  solution->step_time_s = c.step_time_s;
  solution->step_load_factor = c.step_load_factor;
  solution->step_displacement_mm = c.step_displacement_mm;
  // The same end: the load factor reached, exactly; an extended one: the
  // time reached on the new curve, with the step scaled to keep its length
  // in seconds.
  const bool same_end = c.duration_s == duration_s_;
  newton->start_load = same_end ? c.load_factor : c.time_s / duration_s_;
  newton->start_step = same_end ? c.next_step : c.next_step * c.duration_s / duration_s_;
  if (!same_end) {
    for (IncrementRecord& r : c.report.increments) {
      r.load_factor *= c.duration_s / duration_s_;
      r.step *= c.duration_s / duration_s_;
    }
  }
  newton->start_u =
      Eigen::Map<const Eigen::VectorXd>(c.u.data(), static_cast<Eigen::Index>(c.u.size()));
  return Status::Ok();
}

Status Checkpointer::AfterIncrement(double load, double next_step, const Eigen::VectorXd& u,
                                    const Solution& solution, const NewtonReport& report,
                                    const std::vector<double>& peak_contact_force) {
  if (!writes()) return Status::Ok();
  const auto now = std::chrono::steady_clock::now();
  const bool last = load >= 1.0;
  if (!last &&
      std::chrono::duration<double>(now - last_write_).count() < options_.checkpoint_every_s) {
    return Status::Ok();
  }
  std::error_code ec;
  std::filesystem::create_directories(options_.checkpoint_dir, ec);
  if (ec) {
    return Status::Io("cannot create the checkpoint directory " + options_.checkpoint_dir.string() +
                      ": " + ec.message());
  }
  Checkpoint c;
  c.solver_version = SolverVersion();
  c.scene_name = scene_name_;
  c.fingerprint = fingerprint_;
  c.time_s = load * duration_s_;
  c.duration_s = duration_s_;
  c.load_factor = load;
  c.next_step = next_step;
  c.u.assign(u.data(), u.data() + u.size());
  c.material_history = body_->SaveHistory();
  for (const RigidContact* contact : contacts_) c.contact_states.push_back(contact->SaveState());
  c.peak_contact_force_n = peak_contact_force;
  c.history_columns = solution.history_columns;
  c.history = solution.history;
  c.step_time_s = solution.step_time_s;
  c.step_load_factor = solution.step_load_factor;
  c.step_displacement_mm = solution.step_displacement_mm;
  c.report = report;
  Merge(&c.report);
  PBA_RETURN_IF_ERROR(WriteCheckpoint(options_.checkpoint_dir / "checkpoint.h5", c));
  last_write_ = now;
  return Status::Ok();
}

void Checkpointer::Merge(NewtonReport* report) const {
  const NewtonReport& before = restored_.report;
  report->increments.insert(report->increments.begin(), before.increments.begin(),
                            before.increments.end());
  report->cut_reasons.insert(report->cut_reasons.begin(), before.cut_reasons.begin(),
                             before.cut_reasons.end());
  report->total_iterations += before.total_iterations;
  report->cuts += before.cuts;
  report->approximate_iterations += before.approximate_iterations;
  report->modified_iterations += before.modified_iterations;
  report->indefinite_iterations += before.indefinite_iterations;
  report->augmentations += before.augmentations;
  report->assembly_s += before.assembly_s;
  report->linear_solve_s += before.linear_solve_s;
  report->residual_s += before.residual_s;
}

}  // namespace pba
