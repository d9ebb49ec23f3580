// The Python module: load a scene, change values, run the stages, and get volumes, fields and
// metadata as numpy arrays (indexed (i, j, k) like nibabel's get_fdata()). A thin layer over
// the pipeline, as the command line is.

#include "batch/sweep.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/progress.hpp"
#include "geometry/ras_lps.hpp"
#include "io/dataset_layout.hpp"
#include "io/json_file.hpp"
#include "pipeline/run_pipeline.hpp"
#include "scene/scene_json.hpp"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <iostream>
#include <memory>

namespace py = pybind11;
using namespace phantasm;

namespace {

Scene parsed(const std::string& text, const std::filesystem::path& file) {
  SceneLoadResult result = parse_scene(text, file);
  if (!result.scene) throw InputError(format_diagnostics(result.problems));
  return *result.scene;
}

/// The scene with one value set; a value the scene rejects is named in the message.
Scene with_value(const Scene& scene, const std::string& key, const std::string& value) {
  try {
    return parsed(scene_text_with_value(scene.source_text, key, value), scene.file);
  } catch (const InputError& error) {
    throw InputError("setting " + key + " = " + value + " gives a scene that does not validate:\n" +
                     error.what());
  }
}

/// A value as YAML text: JSON is YAML, and Python's json module writes any plain value.
std::string yaml_text(const py::object& value) {
  return py::module_::import("json").attr("dumps")(value).cast<std::string>();
}

py::object json_to_python(const nlohmann::json& value) {
  return py::module_::import("json").attr("loads")(json_text(value, -1));
}

/// A (X, Y, Z[, components]) numpy array of values stored i fastest (component-major).
template <class Out, class In>
py::array_t<Out> volume_array(const ImageGrid& grid, const std::vector<In>& values, int components = 1) {
  const auto nx = static_cast<py::ssize_t>(grid.dims.x()), ny = static_cast<py::ssize_t>(grid.dims.y()),
             nz = static_cast<py::ssize_t>(grid.dims.z());
  const auto count = static_cast<std::size_t>(nx * ny * nz);
  if (values.size() != count * static_cast<std::size_t>(components))
    throw std::runtime_error("volume of unexpected size");
  std::vector<py::ssize_t> shape{nx, ny, nz};
  std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(sizeof(Out)),
                                   static_cast<py::ssize_t>(sizeof(Out)) * nx,
                                   static_cast<py::ssize_t>(sizeof(Out)) * nx * ny};
  if (components > 1) {
    shape.push_back(components);
    strides.push_back(static_cast<py::ssize_t>(sizeof(Out) * count));
  }
  py::array_t<Out> array(shape, strides);
  Out* data = array.mutable_data();
  for (std::size_t v = 0; v < values.size(); ++v)
    data[v] = static_cast<Out>(values[v]);
  return array;
}

py::array_t<double> affine_array(const ImageGrid& grid) {
  py::array_t<double> affine({4, 4});
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      affine.mutable_at(r, c) = grid.world_from_voxel(r, c);
  return affine;
}

bool is_deformed(const std::string& state) {
  if (state == "ref" || state == "reference") return false;
  if (state == "def" || state == "deformed") return true;
  throw py::value_error("state: expected 'ref' or 'def', found '" + state + "'");
}

/// A simulation with the scene it refers to (images point at the scene's sequences).
struct PySimulation {
  std::shared_ptr<const Scene> scene;
  Simulation result;
  std::string until;

  const TissueVolumes& volumes(const std::string& state) const {
    if (until == "anatomy" || until == "deformation")
      throw py::value_error("the simulation stopped before voxelization");
    if (!is_deformed(state)) return result.volumes.reference;
    if (!result.volumes.deformed) throw py::value_error("the scene does not deform: there is no 'def' state");
    return *result.volumes.deformed;
  }
};

SimulationStage stage_of(const std::string& until) {
  if (until == "anatomy") return SimulationStage::anatomy;
  if (until == "deformation") return SimulationStage::deformation;
  if (until == "voxelization") return SimulationStage::voxelization;
  if (until == "mri") return SimulationStage::mri;
  throw py::value_error("until: expected anatomy, deformation, voxelization or mri, found '" + until + "'");
}

/// A Python progress callable as the stages' ProgressCallback. The stages call it from their
/// threads with the GIL released: it takes the GIL, and what the callable raises (an exception,
/// or KeyboardInterrupt from Ctrl-C, which Python delivers on the main thread when the callable
/// runs there) is kept and cancels the run; simulate() raises it once the stages have stopped.
class PythonProgress {
public:
  explicit PythonProgress(py::object callable) : m_callable(std::move(callable)) {}
  ~PythonProgress() {
    py::gil_scoped_acquire gil;
    m_callable = py::object();
    m_error.reset();
  }

  ProgressCallback callback() {
    return [this](const std::string& stage, double fraction, const std::string& detail) {
      py::gil_scoped_acquire gil;
      if (m_error) return; // already stopping: call no more
      try {
        m_callable(stage, fraction, detail);
        // Ctrl-C while the stages ran: Python runs its handler here on the main thread.
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      } catch (py::error_already_set& error) {
        m_error = std::make_unique<py::error_already_set>(std::move(error));
        request_cancellation();
      }
    };
  }

  /// Raises what the callable raised, if it did.
  void rethrow() {
    if (!m_error) return;
    std::unique_ptr<py::error_already_set> error = std::move(m_error);
    throw std::move(*error);
  }

private:
  py::object m_callable;
  std::unique_ptr<py::error_already_set> m_error;
};

} // namespace

PYBIND11_MODULE(phantasm, m) {
  m.doc() = "phantasm: deformable anatomical MRI phantoms with exact ground truth";
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A validated scene (docs/scene-format.md)")
      .def_property_readonly("name", [](const Scene& s) { return s.name; })
      .def_property_readonly("file", [](const Scene& s) { return s.file.string(); })
      .def_property_readonly("sha256", [](const Scene& s) { return s.sha256; })
      .def_property_readonly(
          "text", [](const Scene& s) { return s.source_text; }, "The scene's YAML text")
      .def_property(
          "seed", [](const Scene& s) { return s.seed; },
          [](Scene& s, std::uint64_t seed) { s = with_value(s, "seed", std::to_string(seed)); },
          "The anatomy and noise seed; setting it re-validates the scene")
      .def(
          "set",
          [](Scene& s, const std::string& key, const py::object& value) {
            s = with_value(s, key, yaml_text(value));
          },
          py::arg("key"), py::arg("value"),
          "Sets a value by key path, as a sweep does (e.g. 'acquisition.noise_percent', "
          "'deformation.loads[0].displacement_mm', 'deformation.scale'), and re-validates the scene")
      .def(
          "settings", [](const Scene& s) { return json_to_python(scene_settings_json(s)); },
          "Every setting with defaults filled in, as provenance.json records them");

  m.def(
      "load_scene",
      [](const std::string& path) {
        SceneLoadResult result = load_scene(path);
        if (!result.scene) throw InputError(format_diagnostics(result.problems));
        return std::make_shared<Scene>(*result.scene);
      },
      py::arg("path"), "Reads and validates a scene file");

  py::class_<PySimulation>(m, "Simulation", "The stages' results, in memory")
      .def_property_readonly(
          "affine", [](const PySimulation& s) { return affine_array(s.result.volumes.grid); },
          "4 x 4 voxel (i, j, k, 1) -> RAS mm")
      .def_property_readonly("shape",
                             [](const PySimulation& s) {
                               const Eigen::Vector3i& d = s.result.volumes.grid.dims;
                               return py::make_tuple(d.x(), d.y(), d.z());
                             })
      .def_property_readonly("deformed",
                             [](const PySimulation& s) { return s.result.deformation.has_value(); })
      .def_property_readonly("tissues", [](const PySimulation& s) { return s.result.volumes.tissues; })
      .def_property_readonly("sequences",
                             [](const PySimulation& s) {
                               std::vector<std::string> names;
                               for (const auto& image : s.result.images.reference)
                                 names.push_back(image.sequence->name);
                               return names;
                             })
      .def_property_readonly("stages",
                             [](const PySimulation& s) {
                               py::list stages;
                               for (const auto& r : s.result.stages) {
                                 py::dict d;
                                 d["stage"] = r.stage;
                                 d["status"] = r.status;
                                 d["modelled"] = r.modelled;
                                 d["skipped"] = r.skipped;
                                 d["warnings"] = r.warnings;
                                 d["accuracy"] = r.accuracy;
                                 stages.append(d);
                               }
                               return stages;
                             })
      .def(
          "image",
          [](const PySimulation& s, const std::string& sequence, const std::string& state) {
            const auto& list = is_deformed(state) ? s.result.images.deformed : s.result.images.reference;
            for (const auto& image : list)
              if (image.sequence->name == sequence)
                return volume_array<float>(s.result.volumes.grid, image.magnitude);
            throw py::key_error("no image '" + sequence + "' in state '" + state + "'");
          },
          py::arg("sequence"), py::arg("state") = "ref", "Magnitude image (X, Y, Z) float32")
      .def(
          "labels",
          [](const PySimulation& s, const std::string& state) {
            return volume_array<std::int32_t>(s.result.volumes.grid, s.volumes(state).labels);
          },
          py::arg("state") = "ref", "Organ labels (X, Y, Z) int32, as dseg.tsv numbers them")
      .def(
          "fractions",
          [](const PySimulation& s, const std::string& tissue, const std::string& state) {
            const auto& tissues = s.result.volumes.tissues;
            const auto found = std::find(tissues.begin(), tissues.end(), tissue);
            if (found == tissues.end()) throw py::key_error("no tissue '" + tissue + "'");
            return volume_array<float>(s.result.volumes.grid, s.volumes(state).fraction_volume(
                                                                  static_cast<int>(found - tissues.begin())));
          },
          py::arg("tissue"), py::arg("state") = "ref", "Tissue fraction (X, Y, Z) float32")
      .def(
          "field",
          [](const PySimulation& s, const std::string& name) {
            if (!s.result.volumes.motion)
              throw py::value_error("the scene does not deform: there is no field");
            // The BIDS names of the dataset's files: from-def_to-ref brings a deformed image onto
            // the reference grid, so it carries reference points into the deformed state.
            if (name != "from-def_to-ref" && name != "from-ref_to-def")
              throw py::value_error("field: expected 'from-def_to-ref' or 'from-ref_to-def', found '" + name +
                                    "'");
            const std::vector<float> lps =
                lps_from_ras_components(name == "from-def_to-ref" ? s.result.volumes.motion->ref_to_def
                                                                  : s.result.volumes.motion->def_to_ref);
            return volume_array<float>(s.result.volumes.grid, lps, 3);
          },
          py::arg("name") = "from-def_to-ref",
          "Displacement field (X, Y, Z, 3) float32 of the dataset's sub-<id>_<name>_mode-image_xfm.nii.gz: "
          "it brings an image of the 'from' state onto the 'to' grid; ITK convention, LPS mm, a point x of "
          "the 'to' state is at x + u(x) in the 'from' state")
      .def(
          "jacobian",
          [](const PySimulation& s, const std::string& name) {
            if (!s.result.volumes.motion)
              throw py::value_error("the scene does not deform: there is no field");
            if (name != "from-def_to-ref" && name != "from-ref_to-def")
              throw py::value_error("jacobian: expected 'from-def_to-ref' or 'from-ref_to-def', found '" +
                                    name + "'");
            return volume_array<float>(s.result.volumes.grid,
                                       name == "from-def_to-ref"
                                           ? s.result.volumes.motion->jacobian
                                           : s.result.volumes.motion->def_to_ref_jacobian);
          },
          py::arg("name") = "from-def_to-ref", "det(I + grad u) (X, Y, Z) float32 of the field of that name")
      .def(
          "landmarks",
          [](const PySimulation& s) {
            py::list rows;
            for (const auto& l : s.result.volumes.landmarks) {
              py::dict d;
              d["name"] = l.name;
              d["organ"] = l.organ;
              d["ref_mm"] = std::vector<double>{l.reference_mm.x(), l.reference_mm.y(), l.reference_mm.z()};
              d["def_mm"] = std::vector<double>{l.deformed_mm.x(), l.deformed_mm.y(), l.deformed_mm.z()};
              rows.append(d);
            }
            return rows;
          },
          "Landmarks with their reference and deformed positions (RAS mm)")
      .def(
          "write",
          [](const PySimulation& s, const std::string& output, bool force) {
            if (s.until != "mri")
              throw py::value_error("write needs a simulation of every stage (until='mri')");
            prepare_output_folder(output, force);
            Reporter quiet = Reporter::silent();
            std::vector<std::string> files;
            {
              py::gil_scoped_release release;
              for (const auto& f : write_dataset(*s.scene, s.result, output, quiet).files)
                files.push_back(f.generic_string());
            }
            return files;
          },
          py::arg("output"), py::arg("force") = false,
          "Writes the dataset as `phantasm run` would; returns the files written (relative paths)");

  m.def(
      "simulate",
      [](const std::shared_ptr<Scene>& scene, const std::string& until, bool verbose,
         const py::object& progress) {
        auto result = std::make_unique<PySimulation>();
        result->scene = std::make_shared<const Scene>(*scene);
        result->until = until;
        const SimulationStage stage = stage_of(until);
        if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
          throw py::type_error("progress: expected a callable (stage, fraction, detail), found " +
                               py::repr(progress).cast<std::string>());
        std::unique_ptr<PythonProgress> observer =
            progress.is_none() ? nullptr : std::make_unique<PythonProgress>(progress);
        {
          py::gil_scoped_release release;
          Reporter reporter = verbose ? Reporter(std::cerr, ProgressStyle::lines) : Reporter::silent();
          if (observer) reporter.set_progress_callback(observer->callback());
          reset_cancellation();
          try {
            result->result = simulate(*result->scene, reporter, stage);
          } catch (const Cancelled&) {
            // Only the callback requests cancellation in this process: raise what it raised.
            reset_cancellation();
            py::gil_scoped_acquire gil;
            if (observer) observer->rethrow();
            throw;
          }
          reset_cancellation();
        }
        // The callable raised after the last poll of the stages: the run finished, but the
        // caller asked to stop (Ctrl-C), so that is what it gets.
        if (observer) observer->rethrow();
        return result;
      },
      py::arg("scene"), py::arg("until") = "mri", py::arg("verbose") = false,
      py::arg("progress") = py::none(),
      "Runs the scene's stages in memory up to `until` (anatomy, deformation, voxelization, mri). "
      "`progress`, when given, is called as progress(stage, fraction, detail) while they run (stage: "
      "anatomy, deform, voxelize, mri; fraction 0..1; detail: what is being done), at most every 0.1 s "
      "per stage; an exception it raises, or Ctrl-C, stops the run and is raised here");
}
