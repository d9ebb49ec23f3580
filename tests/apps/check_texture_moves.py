"""Checks that texture moves with the tissue in a phantasm dataset (called by
tests/apps/test_material_maps_run.cpp; usable by hand on any dataset made with a texture).
Argument: the dataset folder. On the deformed grid, every voxel inside the exact mask of the
from-ref_to-def field (a deformed point x lies at x + u(x) in the reference state) whose reference
position lies inside one tissue (its 3x3x3 reference neighbourhood has one label, as has its own
deformed neighbourhood) and holds no partial voxel on either side (the untextured T2 map is
constant over both neighbourhoods: a voxel whose largest fraction is the label's may still hold a
little of another tissue, and its fraction-weighted parameters are no texture's) compares
  * the deformed T1 and PD maps with the reference maps warped through the field (trilinear),
  * and, to show that the comparison tells, with the reference maps at the same voxel (no warp).
Checks: within a tissue the reference maps vary (texture is there); among the voxels that moved
by more than half a voxel, the warped reference maps equal the deformed ones within 0.1 % at every
voxel, and the unwarped ones do not (they differ by more at a tenth of the voxels or more).
Prints the figures and exits non-zero when a check fails."""
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage

root = sys.argv[1]
sub = root + "/derivatives/phantasm/sub-01"
xfm = sub + "/xfm/sub-01_"


def image(path):
    return nib.load(path)


def volume(path):
    return np.asanyarray(nib.load(path).dataobj).astype(float)


dseg_ref = image(sub + "/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz")
affine = dseg_ref.affine
labels_ref = np.asanyarray(dseg_ref.dataobj).astype(int)
field = volume(xfm + "from-ref_to-def_mode-image_xfm.nii.gz")[:, :, :, 0, :]
field[..., 0] *= -1.0  # ITK's LPS components to RAS
field[..., 1] *= -1.0
exact = volume(xfm + "from-ref_to-def_desc-exact_mask.nii.gz") > 0
failures = []
shape = labels_ref.shape
ijk = np.indices(shape).reshape(3, -1).astype(float)
world = affine[:3, :3] @ ijk + affine[:3, 3:4]
reference_world = world + field.reshape(-1, 3).T
reference_ijk = np.linalg.solve(affine[:3, :3], reference_world - affine[:3, 3:4])
moved = np.linalg.norm(reference_ijk - ijk, axis=0) > 0.5
# One tissue around the reference position: the 3x3x3 neighbourhood of its nearest voxel.
one_label = (ndimage.maximum_filter(labels_ref, size=3) == ndimage.minimum_filter(labels_ref, size=3)) & (labels_ref > 0)
nearest = np.clip(np.rint(reference_ijk).astype(int), 0, np.array(shape)[:, None] - 1)
labels_def = np.asanyarray(image(sub + "/ses-def/anat/sub-01_ses-def_dseg.nii.gz").dataobj).astype(int)
one_label_def = ndimage.maximum_filter(labels_def, size=3) == ndimage.minimum_filter(labels_def, size=3)
# No partial voxel: T2 (which no texture varies) constant over both neighbourhoods.
T2_ref = volume(sub + "/ses-ref/anat/sub-01_ses-ref_T2map.nii.gz")
T2_def = volume(sub + "/ses-def/anat/sub-01_ses-def_T2map.nii.gz")
pure_ref = ndimage.maximum_filter(T2_ref, size=3) == ndimage.minimum_filter(T2_ref, size=3)
pure_def = (ndimage.maximum_filter(T2_def, size=3) == ndimage.minimum_filter(T2_def, size=3)).reshape(-1)
inside = (one_label[nearest[0], nearest[1], nearest[2]] & one_label_def.reshape(-1) & exact.reshape(-1)
          & pure_ref[nearest[0], nearest[1], nearest[2]] & pure_def)
for name in ("T1map", "PDmap"):
    ref = volume(sub + f"/ses-ref/anat/sub-01_ses-ref_{name}.nii.gz")
    deformed = volume(sub + f"/ses-def/anat/sub-01_ses-def_{name}.nii.gz").reshape(-1)
    warped = ndimage.map_coordinates(ref, reference_ijk, order=1, mode="nearest")
    unwarped = ref.reshape(-1)
    # Texture is there: the map varies within the tissue of the largest label.
    interior = one_label & (ref > 0)
    values = ref[interior & (labels_ref == np.bincount(labels_ref[interior]).argmax())]
    spread = float(values.std() / values.mean())
    chosen = inside & moved & (deformed > 0)
    scale = np.maximum(np.abs(deformed[chosen]), 1e-12)
    warped_error = np.abs(warped[chosen] - deformed[chosen]) / scale
    unwarped_error = np.abs(unwarped[chosen] - deformed[chosen]) / scale
    warped_off = float(np.mean(warped_error > 0.001))
    unwarped_off = float(np.mean(unwarped_error > 0.001))
    print(f"{name}: within-tissue variation {spread:.4f}; {int(chosen.sum())} moved voxels inside one tissue "
          f"and the exact mask: warped reference off by > 0.1 % at {100 * warped_off:.2f} % "
          f"(largest {float(warped_error.max()):.2e}), unwarped at {100 * unwarped_off:.2f} %")
    if spread < 0.005:
        failures.append(f"{name}: no texture (variation {spread:.4f})")
    if chosen.sum() < 100:
        failures.append(f"{name}: only {int(chosen.sum())} voxels to compare")
    if warped_off > 0.0:
        failures.append(f"{name}: the deformed map is not the warped reference map at {100 * warped_off:.2f} %")
    if unwarped_off < 0.1:
        failures.append(f"{name}: the unwarped map agrees about as well ({100 * unwarped_off:.2f} %): the check cannot tell")
for failure in failures:
    print("FAIL " + failure)
sys.exit(1 if failures else 0)
