#include "io/dataset_layout.hpp"

#include <algorithm>
#include <cctype>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/output_path.hpp"

namespace phantasm {

const char* session_label(PhantomState state) {
  return state == PhantomState::reference ? "ref" : "def";
}

std::string bids_entity_value(const std::string& name) {
  std::string value;
  bool new_word = false;
  for (const char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) {
      new_word = !value.empty();
      continue;
    }
    value += new_word ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
    new_word = false;
  }
  return value;
}

DatasetLayout::DatasetLayout(std::filesystem::path root, std::string subject)
    : m_root(std::move(root)), m_subject(std::move(subject)) {}

std::string DatasetLayout::prefix(PhantomState state) const {
  return "sub-" + m_subject + "_ses-" + session_label(state);
}

std::filesystem::path DatasetLayout::dataset_description() const {
  return m_root / "dataset_description.json";
}

std::filesystem::path DatasetLayout::anat_image(PhantomState state, const std::string& suffix) const {
  return output_file(output_file(m_root, "sub-" + m_subject) / (std::string("ses-") + session_label(state)) /
                         "anat",
                     prefix(state) + "_" + suffix + ".nii.gz");
}

std::filesystem::path DatasetLayout::readme() const {
  return m_root / "README";
}

std::filesystem::path DatasetLayout::derivatives() const {
  return m_root / "derivatives" / "phantasm";
}

std::filesystem::path dataset_anatomy_cache(const std::filesystem::path& dataset) {
  return DatasetLayout(dataset, "").derivatives() / "cache";
}

std::filesystem::path DatasetLayout::derivatives_description() const {
  return derivatives() / "dataset_description.json";
}

std::filesystem::path DatasetLayout::derivatives_readme() const {
  return derivatives() / "README";
}

std::filesystem::path DatasetLayout::derivatives_bidsignore() const {
  return derivatives() / ".bidsignore";
}

std::filesystem::path DatasetLayout::dseg_table() const {
  return derivatives() / "dseg.tsv";
}

std::filesystem::path DatasetLayout::subject_derivatives() const {
  return output_file(derivatives(), "sub-" + m_subject);
}

std::filesystem::path DatasetLayout::session_derivatives(PhantomState state) const {
  return subject_derivatives() / (std::string("ses-") + session_label(state));
}

std::filesystem::path DatasetLayout::dseg(PhantomState state) const {
  return session_derivatives(state) / "anat" / (prefix(state) + "_dseg.nii.gz");
}

std::filesystem::path DatasetLayout::probseg(PhantomState state, const std::string& tissue) const {
  return output_file(session_derivatives(state) / "anat",
                     prefix(state) + "_label-" + bids_entity_value(tissue) + "_probseg.nii.gz");
}

std::filesystem::path DatasetLayout::parameter_map(PhantomState state, const std::string& suffix) const {
  return output_file(dseg(state).parent_path(), prefix(state) + "_" + suffix + ".nii.gz");
}

std::filesystem::path DatasetLayout::transform(PhantomState from, PhantomState to) const {
  return subject_derivatives() / "xfm" /
         ("sub-" + m_subject + "_from-" + session_label(from) + "_to-" + session_label(to) +
          "_mode-image_xfm.nii.gz");
}

std::filesystem::path DatasetLayout::transform_mask(PhantomState from, PhantomState to) const {
  return subject_derivatives() / "xfm" /
         ("sub-" + m_subject + "_from-" + session_label(from) + "_to-" + session_label(to) +
          "_desc-exact_mask.nii.gz");
}

std::filesystem::path DatasetLayout::jacobian(PhantomState from, PhantomState to) const {
  return subject_derivatives() / "xfm" /
         ("sub-" + m_subject + "_from-" + session_label(from) + "_to-" + session_label(to) +
          "_jacobian.nii.gz");
}

std::filesystem::path DatasetLayout::landmarks(PhantomState state) const {
  return session_derivatives(state) / "landmarks" / (prefix(state) + "_landmarks.csv");
}

std::filesystem::path DatasetLayout::dense_landmarks(PhantomState state) const {
  return session_derivatives(state) / "landmarks" / (prefix(state) + "_desc-dense_landmarks.csv");
}

std::filesystem::path DatasetLayout::mesh(PhantomState state, const std::string& organ) const {
  return output_file(session_derivatives(state) / "meshes",
                     prefix(state) + "_organ-" + bids_entity_value(organ) + "_mesh.vtp");
}

std::filesystem::path DatasetLayout::tet_mesh(PhantomState state, const std::string& organ) const {
  return output_file(session_derivatives(state) / "meshes",
                     prefix(state) + "_organ-" + bids_entity_value(organ) + "_tetmesh.vtu");
}

std::filesystem::path DatasetLayout::vdb(PhantomState state) const {
  return session_derivatives(state) / "vdb" / (prefix(state) + "_grids.vdb");
}

std::filesystem::path DatasetLayout::preview(PhantomState state, const std::string& suffix) const {
  return output_file(session_derivatives(state) / "previews", prefix(state) + "_" + suffix + ".png");
}

std::filesystem::path DatasetLayout::provenance() const {
  return subject_derivatives() / "provenance.json";
}

std::filesystem::path DatasetLayout::log() const {
  return subject_derivatives() / "log.txt";
}

std::filesystem::path DatasetLayout::scene_copy() const {
  return subject_derivatives() / "scene.yaml";
}

std::filesystem::path sidecar_path(const std::filesystem::path& image) {
  std::string name = image.filename().string();
  for (const char* extension : {".nii.gz", ".nii", ".csv", ".tsv", ".vtp", ".vtu"}) {
    const std::string ext = extension;
    if (name.size() > ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0) {
      name.resize(name.size() - ext.size());
      break;
    }
  }
  return image.parent_path() / (name + ".json");
}

std::vector<std::string> complete_subjects(const std::filesystem::path& dataset) {
  const std::filesystem::path derivatives = dataset / "derivatives" / "phantasm";
  std::vector<std::string> subjects;
  std::error_code error;
  if (!std::filesystem::is_directory(derivatives, error)) return subjects;
  for (const auto& entry : std::filesystem::directory_iterator(derivatives)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("sub-", 0) == 0 && std::filesystem::exists(entry.path() / "provenance.json", error))
      subjects.push_back(name.substr(4));
  }
  std::sort(subjects.begin(), subjects.end());
  return subjects;
}

void prepare_output_folder(const std::filesystem::path& folder, bool force) {
  if (folder.empty()) throw InputError("expected an output folder, found an empty path");
  std::error_code error;
  if (std::filesystem::exists(folder, error)) {
    if (!std::filesystem::is_directory(folder, error)) {
      throw InputError(folder.string() + ": expected an output folder, found a file");
    }
    const bool empty = std::filesystem::is_empty(folder, error);
    if (!empty && !force) {
      throw InputError(folder.string() +
                       ": expected an empty or new output folder, found one with files in it "
                       "(use --force to write over them)");
    }
    remove_stale_temporaries(folder);
    return;
  }
  std::filesystem::create_directories(folder, error);
  if (error) {
    throw InputError(folder.string() + ": " + folder_creation_problem(folder, error));
  }
}

} // namespace phantasm
