"""Volume change of atlas regions between the two states of a phantasm dataset, from the
ground-truth field: the mean of det(I + grad u) - 1 of from-def_to-ref (on the reference grid)
over the region's reference voxels. The regions are those of an atlas label volume in the same
world space as the dataset (the AAL of Debian's mricron-data for the Colin 27 scenes), sampled at
the dataset's voxel centres (nearest voxel).
Usage: /usr/bin/python3 scripts/region_volume_changes.py DATASET REGION[=CHANGE] ...
  [--atlas /usr/share/mricron/templates/aal.nii.gz] [--names .../aal.nii.txt] [--subject 01]
A REGION is a name of the names file, one without its side (_L, _R) for both sides together, or
cortex (the cerebral cortex: AAL labels 1-90 but the hippocampi, amygdalae and deep nuclei);
with =CHANGE (e.g. Hippocampus=-0.05) the line says how far the measure is from it.
Prints one line per region: voxels, volume in ml, and the volume change in %."""
import argparse
import sys

import nibabel as nib
import numpy as np

parser = argparse.ArgumentParser()
parser.add_argument("dataset")
parser.add_argument("regions", nargs="+")
parser.add_argument("--atlas", default="/usr/share/mricron/templates/aal.nii.gz")
parser.add_argument("--names", default="/usr/share/mricron/templates/aal.nii.txt")
parser.add_argument("--subject", default="01")
args = parser.parse_args()

sub = "%s/derivatives/phantasm/sub-%s" % (args.dataset, args.subject)
field_image = nib.load("%s/xfm/sub-%s_from-def_to-ref_jacobian.nii.gz" % (sub, args.subject))
jacobian = np.asanyarray(field_image.dataobj).astype(float)
atlas_image = nib.load(args.atlas)
atlas = np.asanyarray(atlas_image.dataobj).astype(int)
names = {}
for line in open(args.names):
    fields = line.split()
    if len(fields) >= 2:
        names[fields[1]] = int(fields[0])

# The atlas label at each voxel centre of the dataset's grid (nearest atlas voxel).
ijk = np.indices(jacobian.shape[:3]).reshape(3, -1).T
world = nib.affines.apply_affine(field_image.affine, ijk)
index = np.rint(nib.affines.apply_affine(np.linalg.inv(atlas_image.affine), world)).astype(int)
inside = np.all((index >= 0) & (index < np.array(atlas.shape)), axis=1)
labels = np.zeros(len(ijk), dtype=int)
labels[inside] = atlas[index[inside, 0], index[inside, 1], index[inside, 2]]
labels = labels.reshape(jacobian.shape[:3])
voxel_ml = abs(np.linalg.det(field_image.affine[:3, :3])) / 1000.0

for spec in args.regions:
    name, _, change = spec.partition("=")
    members = [name] if name in names else [n for n in (name + "_L", name + "_R") if n in names]
    if name == "cortex":  # as the scenes' group: AAL 1-90 but hippocampi, amygdalae, deep nuclei
        deep = ("Hippocampus", "Amygdala", "Caudate", "Putamen", "Pallidum", "Thalamus")
        members = [n for n, label in names.items() if label <= 90 and n[:-2] not in deep]
    if not members:
        sys.exit("%s: expected a region of %s, found none named so" % (name, args.names))
    mask = np.isin(labels, [names[m] for m in members])
    measured = jacobian[mask].mean() - 1.0
    line = "%s: %d voxels (%.2f ml), volume change %+.2f %%" % (name, mask.sum(), mask.sum() * voxel_ml,
                                                                100.0 * measured)
    if change:
        line += " (prescribed %+.2f %%, off by %.2f %%)" % (100.0 * float(change),
                                                          100.0 * abs(measured - float(change)))
    print(line)
