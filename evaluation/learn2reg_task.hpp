// A registration task in the Learn2Reg format made from a phantasm dataset (docs/benchmark-tasks.md):
// the task folder a method sees, and a ground-truth folder it never sees.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace phantasm {

/// What `phantasm task` makes.
struct TaskRequest {
  std::filesystem::path dataset; ///< a folder `phantasm run` or `phantasm batch` wrote
  std::filesystem::path task;    ///< the task folder (made; must be new or empty)
  std::filesystem::path truth;   ///< the ground-truth folder (made; must be new or empty)
  std::string name;              ///< the task's name: file prefix, letters and digits
  std::string fixed_contrast;    ///< fixed images (reference state); empty: T1w, else the first
  std::string moving_contrast;   ///< moving images (deformed state); empty: the fixed contrast
};

/// One pair of the task: case index (1-based) and the subject it comes from.
struct TaskPair {
  int case_index = 0;
  std::string subject;
  std::string fixed_id, moving_id; ///< "CCCC_0000", "CCCC_0001"
};

/// Where a task's ground truth goes unless told: TASK-truth beside the task folder.
inline std::filesystem::path default_truth_folder(std::string task) {
  while (task.size() > 1 && task.back() == '/')
    task.pop_back();
  return task + "-truth";
}

/// The Learn2Reg result name of a pair: disp_<fixed id>_<moving id>.nii.gz.
std::string learn2reg_result_name(const TaskPair& pair);

/// Makes the task: TASK/<name>_dataset.json, imagesTr/, labelsTr/, masksTr/, keypointsTr/ (one
/// file per image: <name>_CCCC_MMMM, MMMM 0000 the fixed image of case CCCC, 0001 its moving
/// image), and TRUTH/truth.json with, per pair, disp_CCCC_0000_CCCC_0001.nii.gz (the true
/// displacement in the Learn2Reg convention: voxels on the fixed grid), mask_... (where it is
/// exact) and keypoints_....csv (corresponding landmarks in voxel coordinates of both images).
/// Every input is checked before anything is written.
/// @return what was made: the pairs and the folders
/// @throws InputError naming the dataset file or option that does not fit
nlohmann::json make_learn2reg_task(const TaskRequest& request);

} // namespace phantasm
