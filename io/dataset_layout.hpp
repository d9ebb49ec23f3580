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

/// The value of a BIDS entity (the part after "label-" or "organ-") for an organ or tissue name:
/// BIDS parsers split file names at '_' and '-', so the name's words are joined in camelCase
/// ("gray_matter" -> "grayMatter", "ventricle-left" -> "ventricleLeft"); any character but a
/// letter or digit separates words. dseg.tsv records the mapping (docs/volumes-and-images.md).
/// @param name an organ or tissue name as the scene gives it
std::string bids_entity_value(const std::string& name);

/// Where each output of one subject goes, in the BIDS-like layout of docs/architecture.md.
class DatasetLayout {
public:
  /// @param root the dataset folder (phantasm run -o)
  /// @param subject BIDS subject label, e.g. "01"
  DatasetLayout(std::filesystem::path root, std::string subject);

  const std::filesystem::path& root() const { return m_root; }
  const std::string& subject() const { return m_subject; }

  std::filesystem::path dataset_description() const;
  /// The raw dataset's README (BIDS asks for one at the root).
  std::filesystem::path readme() const;
  /// sub-<id>/ses-<ref|def>/anat/sub-<id>_ses-<ref|def>_<suffix>.nii.gz
  std::filesystem::path anat_image(PhantomState state, const std::string& suffix) const;

  /// derivatives/phantasm
  std::filesystem::path derivatives() const;
  std::filesystem::path derivatives_description() const;
  std::filesystem::path derivatives_readme() const;
  /// derivatives/phantasm/.bidsignore: the derivative files bids-validator 1.x (which knows the
  /// raw-data suffixes only) is told to pass over.
  std::filesystem::path derivatives_bidsignore() const;
  std::filesystem::path dseg_table() const;
  std::filesystem::path dseg(PhantomState state) const;
  /// The tissue's fraction map; the label entity is bids_entity_value(tissue).
  std::filesystem::path probseg(PhantomState state, const std::string& tissue) const;
  /// A ground-truth quantitative map next to the labels, suffix e.g. "T1map" (BIDS qMRI names).
  std::filesystem::path parameter_map(PhantomState state, const std::string& suffix) const;
  /// The field that brings an image in `from`'s space into `to`'s space, as BIDS derivatives
  /// name transforms (sub-<id>_from-<from>_to-<to>_mode-image_xfm.nii.gz): it lives on `to`'s grid
  /// and carries a point x of the `to` state to x + u(x) in the `from` state, so ITK, ANTs and
  /// transformix resample a `from` image onto the `to` grid with it (docs/use-with-your-tools.md).
  std::filesystem::path transform(PhantomState from, PhantomState to) const;
  /// Where the field is the solved motion (1) and where it is the smooth extension (0).
  std::filesystem::path transform_mask(PhantomState from, PhantomState to) const;
  /// det(I + grad u) of the field transform(from, to), on `to`'s grid.
  std::filesystem::path jacobian(PhantomState from, PhantomState to) const;
  /// derivatives/phantasm/sub-<id>/ses-<state>/landmarks/sub-<id>_ses-<state>_landmarks.csv
  std::filesystem::path landmarks(PhantomState state) const;
  /// The dense landmarks beside them: sub-<id>_ses-<state>_desc-dense_landmarks.csv
  std::filesystem::path dense_landmarks(PhantomState state) const;
  /// An organ's surface (the tessellated patch surface, or its sheet), VTK PolyData, in
  /// ses-<state>/meshes; the organ entity is bids_entity_value(organ).
  std::filesystem::path mesh(PhantomState state, const std::string& organ) const;
  /// A solid organ's tetrahedral mesh, VTK UnstructuredGrid, next to its surface.
  std::filesystem::path tet_mesh(PhantomState state, const std::string& organ) const;
  /// derivatives/phantasm/sub-<id>/ses-<state>/vdb/sub-<id>_ses-<state>_grids.vdb
  std::filesystem::path vdb(PhantomState state) const;
  /// derivatives/phantasm/sub-<id>/ses-<state>/previews/sub-<id>_ses-<state>_<suffix>.png
  std::filesystem::path preview(PhantomState state, const std::string& suffix) const;
  std::filesystem::path provenance() const;
  std::filesystem::path log() const;
  /// The scene file as it was run, copied for reproducibility.
  std::filesystem::path scene_copy() const;

private:
  std::filesystem::path subject_derivatives() const;
  /// derivatives/phantasm/sub-<id>/ses-<state>: BIDS wants a file named ses-<state> in that folder.
  std::filesystem::path session_derivatives(PhantomState state) const;
  std::string prefix(PhantomState state) const;

  std::filesystem::path m_root;
  std::string m_subject;
};

/// A dataset's anatomy cache folder, derivatives/phantasm/cache (pipeline/anatomy_cache.hpp):
/// where a batch keeps the anatomies its subjects share.
std::filesystem::path dataset_anatomy_cache(const std::filesystem::path& dataset);

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
