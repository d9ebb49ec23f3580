#!/usr/bin/python3
"""Baseline "elastix": Debian's elastix, affine then B-spline (the parameter files of
scripts/registration_study/: mean squares, adaptive stochastic gradient descent, B-spline control
points every 10 mm, or every five voxels where those are larger than 2 mm), and transformix
-def all for the displacement. The field is written as transformix writes it: the ITK convention
(5-D (X, Y, Z, 1, 3), LPS mm, on the fixed grid).

Usage: elastix.py FIXED MOVING OUTPUT WORK [--iterations N] [--grid-spacing MM] [--threads N]
Run by scripts/register_task.py --baseline elastix (docs/benchmark-tasks.md).
"""

import os
import shutil
import subprocess
import sys

import nibabel
from pair_arguments import pair_parser

STUDY = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "registration_study")


def parameter_file(name, work, settings):
    """The study's parameter file `name` copied into `work`, each (Key value) line of a key in
    `settings` given that value instead."""
    with open(os.path.join(STUDY, name)) as f:
        lines = f.readlines()
    for key, value in settings.items():
        lines = [f"({key} {value})\n" if line.startswith(f"({key} ") else line for line in lines]
    target = os.path.join(work, name)
    with open(target, "w") as f:
        f.writelines(lines)
    return target


def run(command, log):
    with open(log, "a") as out:
        result = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        with open(log) as text:
            sys.exit(f"elastix baseline: {command[0]} failed (exit {result.returncode}); end of {log}:\n"
                     + text.read()[-2000:])


def main():
    parser = pair_parser(__doc__)
    parser.add_argument("work", help="a folder for elastix's files")
    parser.add_argument("--iterations", type=int, help="iterations of each stage (default: the files')")
    parser.add_argument("--grid-spacing", type=float,
                        help="B-spline control point spacing at the finest level, mm (default: 10 or five of the "
                             "fixed image's largest voxel size, whichever is larger)")
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    log = os.path.join(args.work, "elastix.log")
    settings = {"MaximumNumberOfIterations": args.iterations} if args.iterations else {}
    affine = parameter_file("elastix-affine.txt", args.work, settings)
    # Control points closer than five voxels fit the noise of a coarse image: at 4 mm voxels the
    # study's 10 mm folded the Colin pair's B-spline (NDV 0.2 %) and took its landmarks no closer.
    voxel = max(float(z) for z in nibabel.load(args.fixed).header.get_zooms()[:3])
    settings["FinalGridSpacingInPhysicalUnits"] = args.grid_spacing or max(10.0, 5.0 * voxel)
    bspline = parameter_file("elastix-bspline.txt", args.work, settings)
    run(["elastix", "-f", args.fixed, "-m", args.moving, "-p", affine, "-p", bspline, "-out", args.work,
         "-threads", str(args.threads)], log)
    run(["transformix", "-def", "all", "-tp", os.path.join(args.work, "TransformParameters.1.txt"), "-out",
         args.work], log)
    shutil.copyfile(os.path.join(args.work, "deformationField.nii.gz"), args.output)


if __name__ == "__main__":
    main()
