#include "report/subject_record.hpp"

#include "core/error.hpp"
#include "core/parallel_tasks.hpp"
#include "io/dataset_layout.hpp"
#include "io/dataset_tables.hpp"
#include "io/json_file.hpp"
#include "io/nifti_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

namespace phantasm {
namespace {

std::string read_text(const std::filesystem::path& path, const char* what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": expected " + what + ", found no readable file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) lines.push_back(line);
  return lines;
}

std::vector<std::string> fields_of(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, separator);)
    fields.push_back(field);
  return fields;
}

double number_field(const std::string& text, const std::filesystem::path& file, std::size_t line,
                    const char* column) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(value))
    throw InputError(file.string() + ":" + std::to_string(line) + ": " + column +
                     ": expected a number, found '" + text + "'");
  return value;
}

/// Every volume of a subject lies on the scene's one grid.
void require_grid(SubjectRecord& record, const ImageGrid& grid, const std::filesystem::path& file) {
  if (record.dims == Eigen::Vector3i::Zero()) {
    record.dims = grid.dims;
    record.spacing_mm = grid.spacing_mm;
    return;
  }
  if (grid.dims != record.dims) {
    throw InputError(file.string() + ": expected a volume of " + std::to_string(record.dims.x()) + " x " +
                     std::to_string(record.dims.y()) + " x " + std::to_string(record.dims.z()) +
                     " voxels like the subject's other volumes, found " + std::to_string(grid.dims.x()) +
                     " x " + std::to_string(grid.dims.y()) + " x " + std::to_string(grid.dims.z()));
  }
}

/// A volume read by read_side_by_side: its grid is checked against the subject's afterwards.
template <typename Values>
struct ReadVolume {
  ImageGrid grid;
  Values values;
};

/// Reads the files side by side, one thread each (a compressed volume's decompression is one
/// stream, and the report's pictures wait for them), then checks their grids against the
/// subject's in the order given, so that a failure names the file a reading in turn would.
template <typename Values>
std::vector<Values>
read_side_by_side(SubjectRecord& record, const std::vector<std::filesystem::path>& files,
                  const std::function<ReadVolume<Values>(const std::filesystem::path&)>& read) {
  std::vector<ReadVolume<Values>> volumes(files.size());
  std::vector<std::exception_ptr> failures(files.size());
  run_tasks_in_parallel(files.size(), files.size(), [&](std::size_t i) {
    try {
      volumes[i] = read(files[i]);
    } catch (...) {
      failures[i] = std::current_exception();
    }
  });
  std::vector<Values> values;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (failures[i]) std::rethrow_exception(failures[i]);
    require_grid(record, volumes[i].grid, files[i]);
    values.push_back(std::move(volumes[i].values));
  }
  return values;
}

ReadVolume<std::vector<double>> read_values(const std::filesystem::path& file) {
  NiftiVolume volume = read_nifti(file);
  return {volume.grid, std::move(volume.values)};
}

ReadVolume<std::vector<double>> read_vectors(const std::filesystem::path& file) {
  NiftiVolume volume = read_nifti_vectors(file, 3);
  return {volume.grid, std::move(volume.values)};
}

ReadVolume<std::vector<std::int32_t>> read_labels(const std::filesystem::path& file) {
  ReadVolume<std::vector<std::int32_t>> volume;
  volume.values = read_nifti_labels(file, &volume.grid);
  return volume;
}

void read_label_table(SubjectRecord& record, const std::filesystem::path& file) {
  const std::vector<std::string> lines = lines_of(read_text(file, "the label table dseg.tsv"));
  if (lines.empty() || fields_of(lines.front(), '\t').size() < 3 ||
      fields_of(lines.front(), '\t')[0] != "index")
    throw InputError(file.string() + ":1: expected the header 'index<TAB>name<TAB>tissue...', found '" +
                     (lines.empty() ? std::string() : lines.front()) + "'");
  for (std::size_t n = 1; n < lines.size(); ++n) {
    const std::vector<std::string> f = fields_of(lines[n], '\t');
    if (f.size() < 3)
      throw InputError(file.string() + ":" + std::to_string(n + 1) + ": expected at least 3 fields, found " +
                       std::to_string(f.size()));
    const double index = number_field(f[0], file, n + 1, "index");
    if (index > 0) record.labels[static_cast<std::int32_t>(index)] = {f[1], f[2], {0, 0}};
  }
}

/// Adds each listed label's voxels in `labels` to its count for `state` (0 reference, 1
/// deformed): counted in a table over the labels' range when it is small (a look-up in the
/// label map per voxel took a tenth of a second per volume), else looked up voxel by voxel.
void count_label_voxels(SubjectRecord& record, const std::vector<std::int32_t>& labels, int state) {
  if (record.labels.empty()) return;
  const std::int64_t low = record.labels.begin()->first, high = record.labels.rbegin()->first;
  if (high - low < (std::int64_t{1} << 20)) {
    std::vector<std::int64_t> counts(static_cast<std::size_t>(high - low + 1), 0);
    for (const std::int32_t label : labels)
      if (label >= low && label <= high) ++counts[static_cast<std::size_t>(label - low)];
    for (auto& [label, volume] : record.labels)
      volume.voxels[static_cast<std::size_t>(state)] += counts[static_cast<std::size_t>(label - low)];
    return;
  }
  for (const std::int32_t label : labels)
    if (const auto found = record.labels.find(label); found != record.labels.end())
      ++found->second.voxels[static_cast<std::size_t>(state)];
}

void read_pictures(SubjectRecord& record, const DatasetLayout& layout, const std::set<std::string>& listed) {
  const auto is_listed = [&](const std::filesystem::path& file) {
    return listed.count(std::filesystem::relative(file, layout.root()).generic_string()) > 0;
  };
  // The images: every ses-ref anatomical image the run listed, with its ses-def twin.
  const std::string prefix = "sub-" + layout.subject() + "_ses-ref_";
  std::vector<std::string> suffixes;
  for (const std::string& file : listed) {
    const std::filesystem::path path(file);
    const std::string name = path.filename().string();
    if (path.parent_path() == std::filesystem::path("sub-" + layout.subject()) / "ses-ref" / "anat" &&
        name.rfind(prefix, 0) == 0 && name.size() > prefix.size() + 7 &&
        name.compare(name.size() - 7, 7, ".nii.gz") == 0)
      suffixes.push_back(name.substr(prefix.size(), name.size() - prefix.size() - 7));
  }
  std::optional<SliceMontage> montage;
  const auto montage_for = [&]() -> const SliceMontage& {
    if (!montage) montage.emplace(record.dims);
    return *montage;
  };
  // A run in which nothing deforms writes the reference state only.
  record.reference_only = !is_listed(layout.dseg(PhantomState::deformed));
  for (const std::string& suffix : suffixes) {
    // The volumes before the montage: the first volume read sets record.dims, which the montage is
    // made for.
    std::vector<std::filesystem::path> files{layout.anat_image(PhantomState::reference, suffix)};
    if (const std::filesystem::path deformed = layout.anat_image(PhantomState::deformed, suffix);
        is_listed(deformed))
      files.push_back(deformed);
    const std::vector<std::vector<double>> values =
        read_side_by_side<std::vector<double>>(record, files, read_values);
    const std::string reference = grey_slices_png(montage_for(), values[0]);
    record.images.push_back(
        {suffix, reference, values.size() > 1 ? grey_slices_png(montage_for(), values[1]) : reference});
  }
  // Labels: contours over the images, the organs' volumes; the pictures themselves when there
  // are no images.
  std::array<std::vector<std::int32_t>, 2> labels;
  std::vector<std::filesystem::path> label_files;
  std::vector<int> label_states;
  for (const PhantomState state : {PhantomState::reference, PhantomState::deformed})
    if (const std::filesystem::path file = layout.dseg(state); is_listed(file)) {
      label_files.push_back(file);
      label_states.push_back(state == PhantomState::reference ? 0 : 1);
    }
  std::vector<std::vector<std::int32_t>> read =
      read_side_by_side<std::vector<std::int32_t>>(record, label_files, read_labels);
  for (std::size_t n = 0; n < read.size(); ++n) {
    const int state = label_states[n];
    std::vector<std::int32_t>& l = labels[static_cast<std::size_t>(state)];
    l = std::move(read[n]);
    count_label_voxels(record, l, state);
    (state == 0 ? record.reference_contours_png : record.deformed_contours_png) =
        contour_slices_png(montage_for(), l);
  }
  if (suffixes.empty() && !labels[0].empty()) {
    const auto as_values = [](const std::vector<std::int32_t>& l) {
      return std::vector<double>(l.begin(), l.end());
    };
    const std::string reference = grey_slices_png(montage_for(), as_values(labels[0]));
    record.images.push_back(
        {"dseg", reference,
         labels[1].empty() ? reference : grey_slices_png(montage_for(), as_values(labels[1]))});
  }
  if (record.deformed_contours_png.empty()) record.deformed_contours_png = record.reference_contours_png;
  // The motion of each reference point: |u| of from-def_to-ref and its Jacobian determinant,
  // read side by side.
  const std::filesystem::path field_file = layout.transform(PhantomState::deformed, PhantomState::reference);
  const std::filesystem::path jacobian_file =
      layout.jacobian(PhantomState::deformed, PhantomState::reference);
  std::vector<std::filesystem::path> motion_files;
  for (const std::filesystem::path& file : {field_file, jacobian_file})
    if (is_listed(file)) motion_files.push_back(file);
  std::vector<std::vector<double>> motion =
      read_side_by_side<std::vector<double>>(record, motion_files, [&](const std::filesystem::path& file) {
        return file == field_file ? read_vectors(file) : read_values(file);
      });
  if (is_listed(field_file)) {
    const std::vector<double>& field = motion.front();
    const std::size_t n = field.size() / 3;
    std::vector<double> magnitude(n);
    // Extremes in locals: the record's member, written through a reference, was stored and
    // loaded again at every voxel.
    double largest = record.largest_displacement_mm;
    for (std::size_t v = 0; v < n; ++v) {
      magnitude[v] =
          std::sqrt(field[v] * field[v] + field[n + v] * field[n + v] + field[2 * n + v] * field[2 * n + v]);
      if (std::isfinite(magnitude[v])) largest = std::max(largest, magnitude[v]);
    }
    record.largest_displacement_mm = largest;
    ColourScale scale{ColourScale::Kind::magnitude, 0.0, std::max(record.largest_displacement_mm, 1e-3)};
    record.displacement = Overlay{colour_slices_png(montage_for(), magnitude, scale), scale};
  }
  if (is_listed(jacobian_file)) {
    const std::vector<double>& jacobian = motion.back();
    double smallest = jacobian.empty() ? 1.0 : jacobian.front();
    std::int64_t nonpositive = 0;
    for (const double j : jacobian) {
      if (!std::isfinite(j)) continue;
      smallest = std::min(smallest, j);
      if (j <= 0.0) ++nonpositive;
    }
    record.smallest_jacobian = smallest;
    record.nonpositive_jacobian_voxels += nonpositive;
    ColourScale scale{ColourScale::Kind::jacobian, 0.5, 2.0};
    record.jacobian = Overlay{colour_slices_png(montage_for(), jacobian, scale), scale};
  }
}

void read_landmark_moves(SubjectRecord& record, const DatasetLayout& layout,
                         const std::set<std::string>& listed) {
  const std::filesystem::path ref_file = layout.landmarks(PhantomState::reference);
  const std::filesystem::path def_file = layout.landmarks(PhantomState::deformed);
  if (!listed.count(std::filesystem::relative(ref_file, layout.root()).generic_string()) ||
      !listed.count(std::filesystem::relative(def_file, layout.root()).generic_string()))
    return;
  const std::vector<LandmarkRow> reference = read_landmarks(ref_file);
  const std::vector<LandmarkRow> deformed = read_landmarks(def_file);
  std::map<std::string, const LandmarkRow*> deformed_by_name;
  for (const LandmarkRow& row : deformed)
    deformed_by_name[row.name] = &row;
  for (const LandmarkRow& row : reference) {
    const auto found = deformed_by_name.find(row.name);
    if (found == deformed_by_name.end())
      throw InputError(def_file.string() + ": expected the landmark '" + row.name + "' of " +
                       ref_file.filename().string() + ", found no row of that name");
    record.landmarks.push_back({row.name, row.organ, row.ras_mm, found->second->ras_mm});
  }
}

std::vector<StageTiming> read_timings(const std::filesystem::path& file) {
  std::vector<StageTiming> timings;
  std::error_code error;
  if (!std::filesystem::exists(file, error)) return timings;
  const nlohmann::json json =
      parse_json_text(read_text(file, "the run's stage times"), file, "the run's stage times");
  try {
    for (const nlohmann::json& stage : json.at("stages"))
      timings.push_back({stage.at("stage").get<std::string>(), stage.at("wall_seconds").get<double>(),
                         stage.at("cpu_seconds").get<double>()});
  } catch (const nlohmann::json::exception&) {
    throw InputError(file.string() +
                     ": expected 'stages', a list of {stage, wall_seconds, cpu_seconds}, found " +
                     json_text(json, -1).substr(0, 80));
  }
  return timings;
}

} // namespace

std::filesystem::path timing_path(const std::filesystem::path& dataset, const std::string& subject) {
  return DatasetLayout(dataset, subject).provenance().parent_path() / "timing.json";
}

void write_timings(const std::filesystem::path& dataset, const std::string& subject,
                   const std::vector<StageTiming>& timings) {
  nlohmann::json stages = nlohmann::json::array();
  for (const StageTiming& t : timings)
    stages.push_back({{"stage", t.stage}, {"wall_seconds", t.wall_seconds}, {"cpu_seconds", t.cpu_seconds}});
  write_json_file(timing_path(dataset, subject), {{"stages", stages}});
}

std::string read_dataset_text(const std::filesystem::path& file, const char* what) {
  return read_text(file, what);
}

std::vector<StageTiming> read_stage_timings(const std::filesystem::path& dataset,
                                            const std::string& subject) {
  return read_timings(timing_path(dataset, subject));
}

SubjectRecord read_subject_record(const std::filesystem::path& dataset, const std::string& subject) {
  const DatasetLayout layout(dataset, subject);
  SubjectRecord record;
  record.subject = subject;
  record.provenance = parse_json_text(read_text(layout.provenance(), "the provenance.json phantasm writes"),
                                      layout.provenance(), "the provenance.json phantasm writes");
  std::set<std::string> listed;
  try {
    for (const nlohmann::json& file : record.provenance.at("files"))
      listed.insert(file.get<std::string>());
    record.provenance.at("settings").at("anatomy").at("organs");
    record.provenance.at("stages").at(0);
  } catch (const nlohmann::json::exception&) {
    throw InputError(layout.provenance().string() + ": expected the provenance phantasm writes ('files', "
                                                    "'settings', 'stages'), found a file without them");
  }
  // Every file the run listed must be there: a report of a damaged dataset would mislead.
  for (const std::string& file : listed) {
    std::error_code error;
    if (!std::filesystem::exists(layout.root() / file, error))
      throw InputError((layout.root() / file).string() + ": expected the file " +
                       layout.provenance().string() + " lists, found none");
  }
  if (listed.count(std::filesystem::relative(layout.log(), layout.root()).generic_string()))
    record.log_lines = lines_of(read_text(layout.log(), "the run's log"));
  if (listed.count(std::filesystem::relative(layout.scene_copy(), layout.root()).generic_string()))
    record.scene_text = read_text(layout.scene_copy(), "the scene file as run");
  if (listed.count(std::filesystem::relative(layout.dseg_table(), layout.root()).generic_string()))
    read_label_table(record, layout.dseg_table());
  read_pictures(record, layout, listed);
  read_landmark_moves(record, layout, listed);
  record.timings = read_timings(timing_path(dataset, subject));
  return record;
}

} // namespace phantasm
