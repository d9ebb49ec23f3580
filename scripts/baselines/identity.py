#!/usr/bin/python3
"""Baseline "none": no registration. Writes a zero displacement on the fixed image's grid in the
Learn2Reg convention ((X, Y, Z, 3) float32, voxels), and the same for the reverse direction when
a second output is named (a field of zeros is its own inverse).

Usage: identity.py FIXED OUTPUT [INVERSE_OUTPUT]
Run by scripts/register_task.py --baseline none (docs/benchmark-tasks.md).
"""

import sys

import nibabel
import numpy


def main(argv):
    if len(argv) not in (3, 4):
        sys.exit("usage: identity.py FIXED OUTPUT [INVERSE_OUTPUT]")
    fixed = nibabel.load(argv[1])
    zeros = numpy.zeros(fixed.shape[:3] + (3,), dtype=numpy.float32)
    for output in argv[2:]:
        nibabel.save(nibabel.Nifti1Image(zeros, fixed.affine), output)


if __name__ == "__main__":
    main(sys.argv)
