// Where each output of a subject goes in the BIDS-like dataset (sessions ses-ref and ses-def,
// derivatives/phantasm), and the preparation of an output folder. Writers and readers share it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// The two states of a phantom: before and after deformation (BIDS sessions ses-ref, ses-def).
enum class PhantomState { reference, deformed };

/// "ref" or "def".
const char* session_label(PhantomState state);

/// Where each output of one subject goes, in the BIDS-like layout of docs/architecture.md.
class DatasetLayout {
public:
  /// @param root the dataset folder (phantasm run -o)
  /// @param subject BIDS subject label, e.g. "01"
  DatasetLayout(std::filesystem::path root, std::string subject);

  const std::filesystem::path& root() const { return m_root; }
  const std::string& subject() const { return m_subject; }

  std::filesystem::path dataset_description() const;
  /// sub-<id>/ses-<ref|def>/anat/sub-<id>_ses-<ref|def>_<suffix>.nii.gz
  std::filesystem::path anat_image(PhantomState state, const std::string& suffix) const;

  /// derivatives/phantasm
  std::filesystem::path derivatives() const;
  std::filesystem::path derivatives_description() const;
  std::filesystem::path dseg_table() const;
  std::filesystem::path dseg(PhantomState state) const;
  std::filesystem::path probseg(PhantomState state, const std::string& tissue) const;
  /// A ground-truth quantitative map next to the labels, suffix e.g. "T1map" (BIDS qMRI names).
  std::filesystem::path parameter_map(PhantomState state, const std::string& suffix) const;
  /// The field that maps `from` positions to `to` positions (see docs/architecture.md, units and frames).
  std::filesystem::path transform(PhantomState from, PhantomState to) const;
  /// Where the field is the solved motion (1) and where it is the smooth extension (0).
  std::filesystem::path transform_mask(PhantomState from, PhantomState to) const;
  std::filesystem::path jacobian() const;
  std::filesystem::path landmarks(PhantomState state) const;
  /// An organ's surface (the tessellated patch surface, or its sheet), VTK PolyData.
  std::filesystem::path mesh(PhantomState state, const std::string& organ) const;
  /// A solid organ's tetrahedral mesh, VTK UnstructuredGrid.
  std::filesystem::path tet_mesh(PhantomState state, const std::string& organ) const;
  /// derivatives/phantasm/sub-<id>/vdb/sub-<id>_ses-<state>_grids.vdb
  std::filesystem::path vdb(PhantomState state) const;
  /// derivatives/phantasm/sub-<id>/previews/sub-<id>_ses-<state>_<suffix>.png
  std::filesystem::path preview(PhantomState state, const std::string& suffix) const;
  std::filesystem::path provenance() const;
  std::filesystem::path log() const;
  /// The scene file as it was run, copied for reproducibility.
  std::filesystem::path scene_copy() const;

private:
  std::filesystem::path subject_derivatives() const;
  std::string prefix(PhantomState state) const;

  std::filesystem::path m_root;
  std::string m_subject;
};

/// Labels of the complete subjects of a dataset (derivatives/phantasm/sub-<id>/provenance.json
/// present, since it is written last), sorted; empty when there are none.
std::vector<std::string> complete_subjects(const std::filesystem::path& dataset);

/// Replaces the .nii.gz (or other) extension of an image path by .json.
std::filesystem::path sidecar_path(const std::filesystem::path& image);

/// Makes sure a run may write into `folder`: creates it when missing; refuses (InputError) when
/// it holds anything and `force` is false; with `force`, removes temporary files an earlier
/// killed run left there. Files are then replaced one by one, atomically.
void prepare_output_folder(const std::filesystem::path& folder, bool force);

} // namespace phantasm
