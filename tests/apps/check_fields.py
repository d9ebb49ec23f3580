"""Checks phantasm's ground-truth fields against transformix results (called by
test_ground_truth_fields). Arguments: dataset folder, transformix result of the deformed labels
through from-def_to-ref, transformix result of the reference labels through from-ref_to-def (the
BIDS names: from-A_to-B brings an image of state A onto the grid of state B).
Prints one line per check and exits non-zero when one fails."""
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage

root, forward_result, backward_result = sys.argv[1:4]
sub = root + "/derivatives/phantasm/sub-01"
ref = np.asanyarray(nib.load(sub + "/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz").dataobj).astype(int)
dfm = np.asanyarray(nib.load(sub + "/ses-def/anat/sub-01_ses-def_dseg.nii.gz").dataobj).astype(int)
failed = False


def check(name, ok, detail):
    global failed
    print(("ok   " if ok else "FAIL ") + name + ": " + detail)
    failed |= not ok


def compare(name, resampled, target):
    # A voxel farther than 2 voxels from a label boundary of the target has the same label all
    # around: a wrong sign, axis or direction moves whole regions and fails this.
    near_boundary = ndimage.maximum_filter(target, size=5) != ndimage.minimum_filter(target, size=5)
    wrong = (resampled != target) & ~near_boundary
    check(name + ": no disagreement away from boundaries", wrong.sum() == 0,
          "%d of %d voxels disagree, %d of them farther than 2 voxels from a boundary"
          % ((resampled != target).sum(), target.size, wrong.sum()))
    for label in np.unique(target):
        if label == 0 or (target == label).sum() < 10000:
            continue
        a, b = resampled == label, target == label
        dice = 2.0 * (a & b).sum() / (a.sum() + b.sum())
        check(name + ": Dice of label %d" % label, dice >= 0.98, "%.4f" % dice)


# Every NIfTI of the subject, as nibabel reads it: the grid's affine in qform and sform (code 1),
# mm, and the datatype and intent of its kind.
import glob
reference_affine = nib.load(sub + "/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz").affine
paths = sorted(glob.glob(sub + "/**/*.nii.gz", recursive=True)) + sorted(glob.glob(root + "/sub-01/**/*.nii.gz", recursive=True))
check("the subject has images of both states", any("ses-ref_T1w" in p for p in paths) and any("ses-def_T1w" in p for p in paths), "%d NIfTI files" % len(paths))
for path in paths:
    image = nib.load(path)
    h = image.header
    name = path.split("/")[-1]
    if name.endswith("_xfm.nii.gz"):
        expected = (ref.shape + (1, 3), np.float32, "vector")
    elif name.endswith("_dseg.nii.gz"):
        expected = (ref.shape, np.uint8, "label")
    elif name.endswith("_mask.nii.gz"):
        expected = (ref.shape, np.uint8, "label")  # 0/1: a label map of where the field is exact
    else:
        expected = (ref.shape, np.float32, "none")
    ok = (image.shape == expected[0] and image.get_data_dtype() == expected[1] and h.get_intent()[0] == expected[2]
          and int(h["qform_code"]) == 1 and int(h["sform_code"]) == 1 and np.allclose(image.affine, reference_affine)
          and np.allclose(h.get_qform(), reference_affine, atol=1e-4) and h.get_xyzt_units()[0] == "mm")
    check("nibabel reads " + name, ok, "shape %s, %s, intent %s" % (image.shape, image.get_data_dtype(), h.get_intent()[0]))

compare("def labels through from-def_to-ref vs ref labels",
        np.asanyarray(nib.load(forward_result).dataobj).astype(int), ref)
compare("ref labels through from-ref_to-def vs def labels",
        np.asanyarray(nib.load(backward_result).dataobj).astype(int), dfm)


def field(name):
    image = nib.load(sub + "/xfm/sub-01_" + name + "_mode-image_xfm.nii.gz")
    u = np.asanyarray(image.dataobj)[:, :, :, 0, :].astype(float)
    u[..., 0] *= -1.0  # LPS -> RAS
    u[..., 1] *= -1.0
    return u, image.affine


# forward: on the reference grid, carries reference points into the deformed state (it brings
# deformed images onto the reference grid); backward: the way back, on the deformed grid.
forward, affine = field("from-def_to-ref")
backward, _ = field("from-ref_to-def")
exact_f = np.asanyarray(nib.load(sub + "/xfm/sub-01_from-def_to-ref_desc-exact_mask.nii.gz").dataobj) > 0
exact_b = np.asanyarray(nib.load(sub + "/xfm/sub-01_from-ref_to-def_desc-exact_mask.nii.gz").dataobj) > 0
# Compose: x -> x + u_f(x) -> x + u_f(x) + u_b(x + u_f(x)), trilinear in u_b; identity expected
# where u_f is exact at x and u_b at all 8 voxels of the interpolation stencil.
shape = ref.shape
ijk = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), -1).reshape(-1, 3).astype(float)
world = ijk @ affine[:3, :3].T + affine[:3, 3]
moved = world + forward.reshape(-1, 3)
moved_index = np.linalg.solve(affine[:3, :3], (moved - affine[:3, 3]).T)
back = np.stack([ndimage.map_coordinates(backward[..., c], moved_index, order=1, mode="nearest") for c in range(3)], -1)
stencil_exact = ndimage.minimum_filter(exact_b.astype(np.uint8), size=3)
exact_back = ndimage.map_coordinates(stencil_exact.astype(float), moved_index, order=0, mode="nearest") > 0
residual = np.linalg.norm(forward.reshape(-1, 3) + back, axis=1)
voxel = np.abs(np.linalg.det(affine[:3, :3])) ** (1.0 / 3.0)
mask = exact_f.reshape(-1) & exact_back
moving = np.linalg.norm(forward.reshape(-1, 3), axis=1) > 0
check("composition of both fields is the identity where exact", (residual[mask] < 0.1 * voxel).all(),
      "largest residual %.4f voxel over %d exact voxels (%d of them moving)"
      % (residual[mask].max() / voxel, mask.sum(), (mask & moving).sum()))
# Every voxel of either exact mask, with no condition on its neighbours: composing the field
# with the other one (trilinear) returns within a tenth of a voxel (#16).
def compose_miss(u_first, u_second):
    there = world + u_first.reshape(-1, 3)
    there_index = np.linalg.solve(affine[:3, :3], (there - affine[:3, 3]).T)
    u_back = np.stack([ndimage.map_coordinates(u_second[..., c], there_index, order=1, mode="nearest")
                       for c in range(3)], -1)
    return np.linalg.norm(u_first.reshape(-1, 3) + u_back, axis=1)


for name, miss, exact in (("from-def_to-ref", compose_miss(forward, backward), exact_f),
                          ("from-ref_to-def", compose_miss(backward, forward), exact_b)):
    inside = exact.reshape(-1)
    check("every voxel of the %s exact mask composes to identity within 0.1 voxel" % name,
          (miss[inside] <= 0.1 * voxel + 1e-6).all(),
          "largest miss %.4f voxel over %d exact voxels, %d of them beyond 0.1"
          % (miss[inside].max() / voxel, inside.sum(), (miss[inside] > 0.1 * voxel + 1e-6).sum()))
# Landmarks: each reference landmark carried by the from-def_to-ref field (on the reference grid) lands on its deformed
# position (where the field is exact around it), and the two files name the same points.
def landmarks(state):
    rows = [line.split(",") for line in open(sub + "/ses-%s/landmarks/sub-01_ses-%s_landmarks.csv" % (state, state)).read().split("\n")[1:] if line]
    return [r[0] for r in rows], np.array([[float(v) for v in r[2:5]] for r in rows])


names_ref, points_ref = landmarks("ref")
names_def, points_def = landmarks("def")
check("landmark files name the same points", names_ref == names_def and len(names_ref) > 0, "%d landmarks" % len(names_ref))
index = np.linalg.solve(affine[:3, :3], (points_ref - affine[:3, 3]).T)
carried = points_ref + np.stack([ndimage.map_coordinates(forward[..., c], index, order=1) for c in range(3)], -1)
usable = ndimage.map_coordinates(ndimage.minimum_filter(exact_f.astype(np.uint8), size=3).astype(float), index, order=0) > 0
error = np.linalg.norm(carried - points_def, axis=1)[usable] / voxel
moved = np.linalg.norm(points_def - points_ref, axis=1)[usable] > 0
# Trilinear interpolation of the piecewise-linear field between 2 mm voxels costs up to about
# |jump of the gradient| x h / 4 next to the pushed region: 0.17 voxel here, hence 0.25.
check("landmarks carried by the field land on their deformed positions", (error < 0.25).all() and moved.any(),
      "largest error %.4f voxel over %d landmarks (%d of them moved)" % (error.max(), usable.sum(), moved.sum()))
sys.exit(1 if failed else 0)
