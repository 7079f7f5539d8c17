#include "py_simulation.hpp"

#include <type_traits>
#include <variant>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "scene_input.hpp"
#include "seiche/output_files.hpp"
#include "seiche/runner.hpp"
#include "seiche/thread_count.hpp"

namespace py = pybind11;

namespace seiche_py {

PySimulation::PySimulation(const seiche::SceneDef& scene, int threads)
    : threads_(seiche::resolve_thread_count(threads)) {
  seiche::run_with_threads(threads_, [&] { sim_ = std::make_unique<seiche::Simulation>(scene); });
  exporters_ = seiche::family_exporters(sim_->scene());
  report_ = std::make_unique<seiche::RunReport>(sim_->scene(), sim_->particles().size(), 0, threads_,
                                                sim_->pipeline());
}

void PySimulation::step(int frames) {
  const std::lock_guard<std::mutex> lock(stepping_);
  for (int k = 0; k < frames; ++k) {
    seiche::FrameMetrics m;
    seiche::run_with_threads(threads_, [&] { m = sim_->step_frame(); });
    report_->add_frame(m, sim_->timer());
    try {
      seiche::throw_if_diverged(m, m.frame);
    } catch (const seiche::SimulationError& e) {
      report_->set_error(e.what());
      throw;
    }
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  }
}

std::string PySimulation::report() const {
  seiche::RunReport copy = *report_;
  copy.set_frames(sim_->frame());
  return copy.dump();
}

std::vector<std::string> PySimulation::write_frame(const std::filesystem::path& dir) const {
  const int frame = sim_->frame();
  for (const auto& e : exporters_) seiche::check_frame_files_inside(*e, dir, frame, frame);
  seiche::prepare_output_directory(dir);
  std::vector<std::string> written;
  const std::filesystem::path ply = dir / seiche::frame_file_name("particles", frame, "ply");
  seiche::write_file_atomically(ply, seiche::encode_particles_ply(sim_->particles()));
  written.push_back(ply.string());
  const std::vector<seiche::BodyPose> bodies = sim_->body_poses();
  for (const auto& e : exporters_) {
    e->write_frame({sim_->particles(), sim_->scene(), frame, sim_->time(), bodies}, dir);
    for (const std::filesystem::path& file : e->files(frame)) written.push_back((dir / file).string());
  }
  return written;
}

py::array PySimulation::column(const std::string& name, const py::object& owner) const {
  const seiche::StoreColumn* c = sim_->particles().find(name);
  if (!c || !c->enabled)
    throw py::key_error(fmt::format("no particle column \"{}\"; the columns are {}", name, fmt::join(column_names(), ", ")));
  const std::size_t n = sim_->particles().size();
  py::array view = std::visit(
      [&](const auto& data) -> py::array {
        using T = std::remove_cvref_t<decltype(*data.data())>;
        return py::array_t<T>({n}, {sizeof(T)}, data.data(), owner);
      },
      c->data);
  // Read-only: the store is the simulation's; a write would be lost or corrupt the next step.
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

std::vector<std::string> PySimulation::column_names() const {
  std::vector<std::string> names;
  for (const seiche::StoreColumn& c : sim_->particles().columns())
    if (c.enabled) names.push_back(c.name);
  return names;
}

namespace {

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

// The three columns `names` as a tuple of views.
py::tuple column_triple(const py::object& self, const char* a, const char* b, const char* c) {
  const PySimulation& s = self.cast<const PySimulation&>();
  return py::make_tuple(s.column(a, self), s.column(b, self), s.column(c, self));
}

}  // namespace

namespace {

// The rigid bodies' poses by name (Simulation::body_poses is in the order of the scene's
// rigid_bodies): small, so copied into Python tuples rather than viewed.
py::dict body_states(const PySimulation& s) {
  const std::vector<seiche::BodyPose> poses = s.simulation().body_poses();
  const std::vector<seiche::RigidBodyDef>& defs = s.simulation().scene().rigid_bodies;
  py::dict out;
  for (std::size_t i = 0; i < poses.size() && i < defs.size(); ++i) {
    const seiche::BodyPose& p = poses[i];
    py::dict body;
    body["position"] = py::make_tuple(p.position[0], p.position[1], p.position[2]);
    body["orientation"] = py::make_tuple(p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]);
    body["velocity"] = py::make_tuple(p.velocity[0], p.velocity[1], p.velocity[2]);
    body["angular_velocity"] = py::make_tuple(p.angular_velocity[0], p.angular_velocity[1], p.angular_velocity[2]);
    out[py::str(defs[i].name)] = body;
  }
  return out;
}

}  // namespace

void register_simulation(py::module_& m) {
  py::class_<PySimulation>(m, "Simulation", R"(A scene being stepped, frame by frame.

Simulation(scene=None, *, set=None, threads=0, max_memory=None, allow_huge_work=False, base_dir=None)
  scene: None (the built-in dam break), a dict (the scene as JSON) or a path to a scene file.
  set:   overrides as for the CLI's --set: ["solver.iterations=8"] or {"solver.iterations": 8}.
Particle arrays (column(), positions, velocities, ids) are read-only NumPy views of the store,
valid until the next step(); the store is reordered every substep, so match particles by ids.)")
      .def(py::init([](const py::object& scene, const py::object& set, int threads, const py::object& max_memory,
                       bool allow_huge_work, const py::object& base_dir) {
             const SceneInput input = scene_input(scene, base_dir);
             const seiche::SceneDef def = load_checked_scene(input, scene_overrides(set), scene_limits(max_memory, allow_huge_work));
             py::gil_scoped_release release;
             return std::make_unique<PySimulation>(def, threads);
           }),
           py::arg("scene") = py::none(), py::kw_only(), py::arg("set") = py::none(), py::arg("threads") = 0,
           py::arg("max_memory") = py::none(), py::arg("allow_huge_work") = false, py::arg("base_dir") = py::none())
      .def("step", &PySimulation::step, py::arg("frames") = 1, py::call_guard<py::gil_scoped_release>(),
           "Steps `frames` frames (the GIL is released). Raises SimulationError on NaN or inf.")
      .def_property_readonly("frame", [](const PySimulation& s) { return s.simulation().frame(); },
                             "Frames stepped so far.")
      .def_property_readonly("time", [](const PySimulation& s) { return s.simulation().time(); }, "Simulated time (s).")
      .def_property_readonly("particle_count", [](const PySimulation& s) { return s.simulation().particles().size(); })
      .def("__len__", [](const PySimulation& s) { return s.simulation().particles().size(); })
      .def("__repr__",
           [](const PySimulation& s) {
             return fmt::format("<seiche.Simulation {}: {} particles, frame {}, t = {:g} s>", s.simulation().scene().name,
                                s.simulation().particles().size(), s.simulation().frame(), s.simulation().time());
           })
      .def_property_readonly("scene_name", [](const PySimulation& s) { return s.simulation().scene().name; })
      .def_property_readonly("pipeline", [](const PySimulation& s) { return s.simulation().pipeline(); },
                             "The passes of a substep, in order.")
      .def_property_readonly("threads", &PySimulation::threads)
      .def_property_readonly("columns", &PySimulation::column_names, "Names of the particle columns.")
      .def("column", [](const py::object& self, const std::string& name) { return self.cast<const PySimulation&>().column(name, self); },
           py::arg("name"), "Column `name` as a read-only NumPy view, valid until the next step().")
      .def_property_readonly("positions", [](const py::object& self) { return column_triple(self, "x", "y", "z"); },
                             "(x, y, z): three read-only float32 views (m).")
      .def_property_readonly("velocities", [](const py::object& self) { return column_triple(self, "vx", "vy", "vz"); },
                             "(vx, vy, vz): three read-only float32 views (m/s).")
      .def_property_readonly("ids", [](const py::object& self) { return self.cast<const PySimulation&>().column("id", self); },
                             "Creation index of every particle (int32 view): the order of the PLY files.")
      .def_property_readonly("bodies", &body_states,
                             "The rigid bodies' state, a dict by body name in scene order, each a dict of tuples "
                             "(copies, double precision): position (m, the centre of mass), orientation (unit "
                             "quaternion [w, x, y, z], body to world), velocity (m/s), angular_velocity (rad/s, "
                             "world frame). Empty without rigid bodies.")
      .def("report", [](const PySimulation& s) { return json_loads(s.report()); },
           "The run report of the frames stepped so far, as `seiche run --report` writes it.")
      .def("write_frame", &PySimulation::write_frame, py::arg("out"),
           "Writes the current frame as `seiche run` does (particles.%04d.ply, each cloth's OBJ); returns the paths.");
}

}  // namespace seiche_py
