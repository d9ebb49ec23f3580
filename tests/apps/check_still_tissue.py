"""Checks that tissue which does not move is still in phantasm's ground-truth fields, and that
the reference-grid Jacobian tells each organ's volume change as its labels do (called by
test_ground_truth_fields; usable by hand on any dataset).
Arguments: dataset folder, then the names of the organs the scene leaves where they are (fixed or
rigid). Checks:
* every voxel a still organ labels carries zero displacement in the field of its state
  (from-def_to-ref on the reference grid, from-ref_to-def on the deformed grid), inside or outside
  the exact mask;
* for every organ of at least 20 ml (reference labels), the volume change from the labels
  (deformed over reference voxel count) and from the from-def_to-ref Jacobian (mean of det - 1 over
  the organ's reference voxels) agree within 1 % of the organ's volume.
Prints one line per check with its figures and exits non-zero when one fails."""
import sys

import nibabel as nib
import numpy as np

root = sys.argv[1]
still_names = sys.argv[2:]
sub = root + "/derivatives/phantasm/sub-01"
xfm = sub + "/xfm/sub-01_"


def volume(path):
    return np.asanyarray(nib.load(path).dataobj)


labels = {"ref": volume(sub + "/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz").astype(int),
          "def": volume(sub + "/ses-def/anat/sub-01_ses-def_dseg.nii.gz").astype(int)}
# The field on each state's grid: from-def_to-ref lives on the reference grid, from-ref_to-def on
# the deformed one (BIDS: from-A_to-B brings an image of A onto B's grid).
fields = {"ref": volume(xfm + "from-def_to-ref_mode-image_xfm.nii.gz")[:, :, :, 0, :].astype(float),
          "def": volume(xfm + "from-ref_to-def_mode-image_xfm.nii.gz")[:, :, :, 0, :].astype(float)}
exact = {"ref": volume(xfm + "from-def_to-ref_desc-exact_mask.nii.gz") > 0,
         "def": volume(xfm + "from-ref_to-def_desc-exact_mask.nii.gz") > 0}
jacobian = volume(xfm + "from-def_to-ref_jacobian.nii.gz").astype(float)
voxel_ml = abs(np.linalg.det(nib.load(sub + "/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz").affine[:3, :3])) / 1000.0
table = {}
for line in open(root + "/derivatives/phantasm/dseg.tsv").read().split("\n")[1:]:
    if line.strip():
        index, name = line.split()[:2]
        table[name] = int(index)
failed = False


def check(name, ok, detail):
    global failed
    print(("ok   " if ok else "FAIL ") + name + ": " + detail)
    failed |= not ok


for name in still_names:
    if name not in table:
        check(name + " is an organ of the dataset", False, "not in dseg.tsv")
        continue
    for state, field_name in (("ref", "from-def_to-ref"), ("def", "from-ref_to-def")):
        inside = labels[state] == table[name]
        length = np.linalg.norm(fields[state], axis=-1)[inside]
        moved = length > 0.0
        outside_mask = inside & ~exact[state]
        check("%s is still in %s" % (name, field_name), inside.any() and not moved.any(),
              "%d of %d voxels (%.2f %%) moved, by up to %.2f mm; %d of its voxels outside the exact mask"
              % (moved.sum(), inside.sum(), 100.0 * moved.sum() / max(1, inside.sum()),
                 length.max() if length.size else 0.0, outside_mask.sum()))

for name, label in sorted(table.items(), key=lambda item: item[1]):
    if label == 0 or name == "gap":  # not organs: the background, the space a moved organ left
        continue
    reference = labels["ref"] == label
    if reference.sum() * voxel_ml < 20.0:
        continue
    from_labels = (labels["def"] == label).sum() / reference.sum() - 1.0
    from_jacobian = (jacobian[reference] - 1.0).mean()
    check("%s: volume change from the labels and from the Jacobian agree within 1 %%" % name,
          abs(from_labels - from_jacobian) <= 0.01,
          "%.1f ml; labels %+.2f %%, Jacobian %+.2f %%" % (reference.sum() * voxel_ml, 100.0 * from_labels,
                                                        100.0 * from_jacobian))
sys.exit(1 if failed else 0)
