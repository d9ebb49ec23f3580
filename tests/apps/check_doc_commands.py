"""Runs the bash blocks of docs/use-with-your-tools.md as they stand on a small run, and checks what
they made: transformix and the numpy resampling bring the deformed labels onto the reference grid
with the field named from-def_to-ref (BIDS: from the deformed state's space into the reference
state's) and get the reference labels. Arguments: phantasm executable, scene file, work folder,
the docs page. Exits non-zero on a failure."""
import os
import re
import shutil
import subprocess
import sys

import nibabel as nib
import numpy as np

phantasm, scene, work, page = sys.argv[1:5]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
run = subprocess.run([phantasm, "run", scene, "-o", os.path.join(work, "out"), "-q"], capture_output=True, text=True)
if run.returncode != 0:
    sys.exit("phantasm run failed: " + run.stderr)
blocks = re.findall(r"```bash\n(.*?)```", open(page).read(), re.S)
if len(blocks) < 2:
    sys.exit("%s: expected the transformix and numpy bash blocks, found %d" % (page, len(blocks)))
for number, block in enumerate(blocks, 1):
    result = subprocess.run(["bash", "-e", "-c", block], cwd=work, capture_output=True, text=True)
    print("block %d: exit %d\n%s" % (number, result.returncode, result.stdout[-2000:]))
    if result.returncode != 0:
        sys.exit("block %d failed:\n%s\n%s" % (number, block, result.stderr[-4000:]))

sub = os.path.join(work, "out", "derivatives", "phantasm", "sub-01")
load = lambda path: np.asanyarray(nib.load(path).dataobj).astype(int)
ref = load(sub + "/ses-ref/anat/sub-01_ses-ref_dseg.nii.gz")
dfm = load(sub + "/ses-def/anat/sub-01_ses-def_dseg.nii.gz")
failed = False


def dice(a, b, label):
    return 2.0 * ((a == label) & (b == label)).sum() / ((a == label).sum() + (b == label).sum())


# The label that moves most (lowest overlap between the states) must overlap better after
# resampling than without; every label within 0.98 Dice of the reference.
labels = [l for l in np.unique(ref) if l != 0]
moving = min(labels, key=lambda l: dice(dfm, ref, l))
for name in ("transformix-out/result.nii.gz", "def_dseg_on_ref.nii.gz"):
    resampled = load(os.path.join(work, name))
    worst = min(dice(resampled, ref, l) for l in labels)
    ok = worst >= 0.98 and dice(resampled, ref, moving) > dice(dfm, ref, moving)
    print("%s %s: smallest Dice with the reference labels %.4f; label %d %.4f (unresampled %.4f)"
          % ("ok  " if ok else "FAIL", name, worst, moving, dice(resampled, ref, moving), dice(dfm, ref, moving)))
    failed |= not ok
# The two ways agree but for rounding at exact half-voxel positions.
a = load(os.path.join(work, "transformix-out/result.nii.gz"))
b = load(os.path.join(work, "def_dseg_on_ref.nii.gz"))
agree = (a == b).mean()
print("%s transformix and numpy agree on %.5f of the voxels" % ("ok  " if agree > 0.999 else "FAIL", agree))
failed |= agree <= 0.999
sys.exit(1 if failed else 0)
