#!/usr/bin/python3
"""Baseline "syn": dipy's symmetric normalization (Debian's python3-dipy):
SymmetricDiffeomorphicRegistration with the cross-correlation metric (CCMetric, radius 4 voxels)
on a few modest levels. SyN returns both directions of a pair; each is written as dipy holds it:
the displacement in world (RAS) mm on the grid it is sampled on (the fixed image's for the
forward field, which carries fixed points into the moving image, and the same grid for the
backward one; the two images of a Learn2Reg pair share a grid), the MRtrix3 displacement
convention (docs/benchmark-tasks.md).

Usage: dipy_syn.py FIXED MOVING OUTPUT [--inverse INVERSE_OUTPUT] [--levels 40,20,10] [--radius 4]
Run by scripts/register_task.py --baseline syn.
"""

import sys

import nibabel
import numpy
from pair_arguments import pair_parser


def main():
    parser = pair_parser(__doc__)
    parser.add_argument("--inverse", help="write the reverse direction (moving image fixed) here")
    parser.add_argument("--levels", default="40,20,10",
                        help="iterations per level, coarsest first (default 40,20,10)")
    parser.add_argument("--radius", type=int, default=4, help="cross-correlation window radius, voxels")
    args = parser.parse_args()
    try:
        levels = [int(n) for n in args.levels.split(",")]
        if not levels or min(levels) < 0:
            raise ValueError
    except ValueError:
        sys.exit(f"dipy_syn.py: --levels: expected iterations per level such as 40,20,10, found '{args.levels}'")

    # Imported here so that --help works without dipy.
    from dipy.align.imwarp import SymmetricDiffeomorphicRegistration
    from dipy.align.metrics import CCMetric

    fixed, moving = nibabel.load(args.fixed), nibabel.load(args.moving)
    if fixed.shape[:3] != moving.shape[:3] or not numpy.allclose(fixed.affine, moving.affine, atol=1e-3):
        sys.exit(f"dipy_syn.py: {args.moving}: expected the fixed image's grid (a Learn2Reg pair shares one), "
                 "found another")
    static = numpy.asarray(fixed.dataobj, dtype=numpy.float64)
    mobile = numpy.asarray(moving.dataobj, dtype=numpy.float64)
    syn = SymmetricDiffeomorphicRegistration(CCMetric(3, radius=args.radius), levels)
    mapping = syn.optimize(static, mobile, fixed.affine, moving.affine)
    # The forward field, in world mm, on the fixed grid: a fixed point x is sampled in the moving
    # image at x + forward(x); the backward field carries moving points back the same way.
    fields = [(args.output, mapping.get_forward_field())]
    if args.inverse:
        fields.append((args.inverse, mapping.get_backward_field()))
    for path, field in fields:
        nibabel.save(nibabel.Nifti1Image(numpy.asarray(field, dtype=numpy.float32), fixed.affine), path)


if __name__ == "__main__":
    main()
