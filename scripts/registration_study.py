#!/usr/bin/python3
"""Registration study: how well does elastix recover deformations of increasing magnitude?

For each magnitude, the study scene's displacement loads are set to that length (direction
kept), `phantasm run` makes the phantom pair, Debian's elastix registers the deformed T1w image
(moving) onto the reference one (fixed) with the shipped affine + B-spline parameter files,
transformix turns the result into a displacement field, and `phantasm eval` scores it and the
identity (no registration) against the ground truth. Writes study.json, study.csv and study.png
(error against magnitude) into the output folder. See docs/registration-study.md.

The scaled loads do not change the anatomy, so every magnitude's `phantasm run` shares one anatomy
cache (--cache, default OUT/anatomy-cache): the organs are fitted and meshed once per study.

Usage: scripts/registration_study.py -o OUT [--magnitudes 2 4 6 8] [--scene FILE] [--cache DIR]
                                      [--phantasm BIN] [--iterations N] [--threads N] [--voxel-size MM]
"""

import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import time

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
STUDY = os.path.join(HERE, "registration_study")


# A landmark counts as moved when its true motion is at least this fraction of the load's length:
# most landmarks of a head lie far from a local load (the fixed scalp and skull, the far side of
# the brain), and their mean hides the error where the tissue moved.
MOVED_FRACTION = 0.25


def children_cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run(command, log, seconds=None, step=None):
    """Runs a command, its output appended to `log`; stops the study with the command's own
    message when it fails. Adds the command's wall and processor (user + system) times to
    seconds[step] and seconds[step + "_cpu"] when given: on a shared machine only the latter
    says what the step costs."""
    start = time.monotonic()
    start_cpu = children_cpu_seconds()
    with open(log, "a") as out:
        out.write("$ " + " ".join(command) + "\n")
        out.flush()
        result = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        with open(log) as text:
            tail = text.read()[-3000:]
        sys.exit(f"registration_study: {' '.join(command[:2])} failed (exit {result.returncode}); "
                 f"end of {log}:\n{tail}")
    if seconds is not None:
        seconds[step] = seconds.get(step, 0.0) + time.monotonic() - start
        seconds[step + "_cpu"] = seconds.get(step + "_cpu", 0.0) + children_cpu_seconds() - start_cpu


def scaled_scene(scene, magnitude):
    """The scene with every displacement load's vector set to `magnitude` mm, direction kept."""
    loads = scene.get("deformation", {}).get("loads", [])
    displacement_loads = [load for load in loads if load.get("type") == "displacement"]
    if not displacement_loads:
        sys.exit("registration_study: the scene has no displacement load to scale "
                 "(deformation.loads[].type: displacement)")
    for load in displacement_loads:
        vector = load["displacement_mm"]
        length = math.sqrt(sum(c * c for c in vector))
        if length == 0.0:
            sys.exit("registration_study: a displacement load of length 0 has no direction to scale")
        load["displacement_mm"] = [c * magnitude / length for c in vector]
    return scene


def with_voxel_size(scene, voxel_mm):
    """The scene on a grid of `voxel_mm` voxels: same centre, the field of view rounded up to a
    whole number of voxels (a coarse, quicker version of a scene)."""
    grid = scene.setdefault("grid", {})
    grid["voxel_size_mm"] = voxel_mm
    fov = grid.get("field_of_view_mm")
    if fov is not None:
        fov = fov if isinstance(fov, list) else [fov] * 3
        grid["field_of_view_mm"] = [math.ceil(f / voxel_mm - 1e-9) * voxel_mm for f in fov]
    # An acquired voxel smaller than the coarser grid's cannot be sampled on it: acquire at
    # the grid's voxel along such axes (the scene's k-space otherwise stays as it is).
    acquisition = scene.get("acquisition")
    if isinstance(acquisition, dict) and "acquired_voxel_mm" in acquisition:
        acquired = acquisition["acquired_voxel_mm"]
        acquired = acquired if isinstance(acquired, list) else [acquired] * 3
        acquisition["acquired_voxel_mm"] = [max(float(a), voxel_mm) for a in acquired]
    return scene


def with_iterations(source, target, iterations):
    """Copies an elastix parameter file, replacing MaximumNumberOfIterations when asked."""
    with open(source) as f:
        lines = f.readlines()
    if iterations is not None:
        lines = [f"(MaximumNumberOfIterations {iterations})\n"
                 if line.startswith("(MaximumNumberOfIterations") else line for line in lines]
    with open(target, "w") as f:
        f.writelines(lines)
    return target


def study_pair(args, base_scene, magnitude, folder):
    os.makedirs(folder, exist_ok=True)
    log = os.path.join(folder, "commands.log")
    open(log, "w").close()
    scene_path = os.path.join(folder, "scene.yaml")
    with open(scene_path, "w") as f:
        scene = scaled_scene(json.loads(json.dumps(base_scene)), magnitude)
        if args.voxel_size is not None:
            scene = with_voxel_size(scene, args.voxel_size)
        yaml.safe_dump(scene, f, sort_keys=False)
    dataset = os.path.join(folder, "dataset")
    seconds = {}
    run([args.phantasm, "run", scene_path, "-o", dataset, "--force", "-q", "--cache", args.cache], log, seconds,
        "phantasm_run")
    subject = "01"
    fixed = os.path.join(dataset, f"sub-{subject}", "ses-ref", "anat", f"sub-{subject}_ses-ref_T1w.nii.gz")
    moving = os.path.join(dataset, f"sub-{subject}", "ses-def", "anat", f"sub-{subject}_ses-def_T1w.nii.gz")
    elastix_out = os.path.join(folder, "elastix")
    transformix_out = os.path.join(folder, "transformix")
    os.makedirs(elastix_out, exist_ok=True)
    os.makedirs(transformix_out, exist_ok=True)
    affine = with_iterations(os.path.join(STUDY, "elastix-affine.txt"), os.path.join(folder, "affine.txt"),
                             args.iterations)
    bspline = with_iterations(os.path.join(STUDY, "elastix-bspline.txt"), os.path.join(folder, "bspline.txt"),
                              args.iterations)
    run([args.elastix, "-f", fixed, "-m", moving, "-p", affine, "-p", bspline, "-out", elastix_out,
         "-threads", str(args.threads)], log, seconds, "elastix")
    run([args.transformix, "-def", "all", "-tp", os.path.join(elastix_out, "TransformParameters.1.txt"),
         "-out", transformix_out], log, seconds, "transformix")
    field = os.path.join(transformix_out, "deformationField.nii.gz")
    results = {}
    for name, option in (("none", ["--identity"]), ("elastix", ["--field", field])):
        target = os.path.join(folder, f"eval-{name}.json")
        run([args.phantasm, "eval", dataset, *option, "--json", target, "-q"], log, seconds, "phantasm_eval")
        with open(target) as f:
            results[name] = json.load(f)
    return results, seconds


def mean(values):
    """The mean, None (JSON null) for no values."""
    return sum(values) / len(values) if values else None


def row_of(magnitude, results, seconds):
    row = {"magnitude_mm": magnitude,
           "landmark_motion_mean_mm": results["none"]["landmark_displacement_mm"]["mean"],
           "landmark_motion_max_mm": results["none"]["landmark_displacement_mm"]["max"]}
    # The moved landmarks, chosen by their true motion (the same for both results).
    moved = [i for i, landmark in enumerate(results["none"]["landmarks"])
             if landmark["true_displacement_mm"] >= MOVED_FRACTION * magnitude]
    row["landmarks"] = len(results["none"]["landmarks"])
    row["moved_landmarks"] = len(moved)
    for name, e in results.items():
        row[f"tre_mean_mm_{name}"] = e["tre_mm"]["mean"]
        row[f"tre_p95_mm_{name}"] = e["tre_mm"]["p95"]
        row[f"tre_mean_mm_moved_{name}"] = mean([e["landmarks"][i]["tre_mm"] for i in moved])
        row[f"endpoint_error_mean_mm_{name}"] = e["endpoint_error_mm"]["mean"]
        row[f"mean_dice_{name}"] = e["mean_dice"]
        row[f"folding_fraction_{name}"] = e["jacobian"]["folding_fraction"]
        for label in e["labels"]:
            row[f"dice_{label['name']}_{name}"] = label["dice"]
    for step, value in seconds.items():
        row[f"seconds_{step}"] = round(value, 2)
    return row


def plot(rows, target, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = [r["magnitude_mm"] for r in rows]
    figure, (tre, dice) = plt.subplots(1, 2, figsize=(10, 4))
    for name, colour in (("none", "tab:grey"), ("elastix", "tab:blue")):
        label = "no registration" if name == "none" else "elastix affine + B-spline"
        tre.plot(m, [r[f"tre_mean_mm_{name}"] for r in rows], "o-", color=colour, label=f"{label}, mean")
        tre.plot(m, [r[f"tre_p95_mm_{name}"] for r in rows], "s--", color=colour, label=f"{label}, 95th pct")
        tre.plot(m, [r[f"tre_mean_mm_moved_{name}"] for r in rows], "^:", color=colour,
                 label=f"{label}, mean of moved landmarks")
        dice.plot(m, [r[f"mean_dice_{name}"] for r in rows], "o-", color=colour, label=label)
    tre.set_xlabel("deformation magnitude (mm)")
    tre.set_ylabel("target registration error (mm)")
    tre.set_title("Landmark error")
    tre.legend(fontsize=8)
    tre.grid(alpha=0.3)
    dice.set_xlabel("deformation magnitude (mm)")
    dice.set_ylabel("mean Dice over labels")
    dice.set_title("Label overlap")
    dice.legend(fontsize=8)
    dice.grid(alpha=0.3)
    figure.suptitle(title)
    figure.tight_layout()
    figure.savefig(target + ".tmp.png", dpi=100)
    os.replace(target + ".tmp.png", target)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", required=True, help="study folder")
    parser.add_argument("--magnitudes", type=float, nargs="+", default=[2, 4, 6, 8],
                        help="displacement load lengths in mm (default 2 4 6 8)")
    parser.add_argument("--scene", default=os.path.join(STUDY, "scene.yaml"), help="base scene")
    parser.add_argument("--cache", default=None,
                        help="anatomy cache folder shared by the magnitudes' runs (default OUT/anatomy-cache)")
    parser.add_argument("--phantasm", default=os.path.join(HERE, "..", "build", "release", "apps", "phantasm",
                                                           "phantasm"), help="phantasm executable")
    parser.add_argument("--elastix", default="/usr/bin/elastix")
    parser.add_argument("--transformix", default="/usr/bin/transformix")
    parser.add_argument("--iterations", type=int, default=None,
                        help="override MaximumNumberOfIterations of both stages (quick runs)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--voxel-size", type=float, default=None,
                        help="run the scene on voxels of this size in mm (a coarse, quicker version)")
    args = parser.parse_args()
    if args.voxel_size is not None and not args.voxel_size > 0:
        sys.exit("registration_study: --voxel-size: expected a size > 0 mm")
    if any(m <= 0 for m in args.magnitudes):
        sys.exit("registration_study: --magnitudes: expected lengths > 0 mm")
    with open(args.scene) as f:
        base_scene = yaml.safe_load(f)
    os.makedirs(args.output, exist_ok=True)
    if args.cache is None:
        args.cache = os.path.join(args.output, "anatomy-cache")
    rows = []
    for magnitude in args.magnitudes:
        folder = os.path.join(args.output, f"magnitude-{magnitude:g}mm")
        print(f"magnitude {magnitude:g} mm: phantasm run, elastix, transformix, phantasm eval", flush=True)
        rows.append(row_of(magnitude, *study_pair(args, base_scene, magnitude, folder)))
        r = rows[-1]
        print(f"  TRE mean {r['tre_mean_mm_none']:.3f} mm without registration, "
              f"{r['tre_mean_mm_elastix']:.3f} mm with elastix ({r['moved_landmarks']} of {r['landmarks']} "
              f"landmarks moved: {r['tre_mean_mm_moved_none'] or 0:.3f} -> "
              f"{r['tre_mean_mm_moved_elastix'] or 0:.3f} mm); "
              f"mean Dice {r['mean_dice_none']:.3f} -> {r['mean_dice_elastix']:.3f}; "
              + ", ".join(f"{k[len('seconds_'):]} {v:.1f} s ({r[k + '_cpu']:.1f} s processor)"
                          for k, v in r.items() if k.startswith("seconds_") and not k.endswith("_cpu")),
              flush=True)
    with open(os.path.join(args.output, "study.json"), "w") as f:
        json.dump({"scene": os.path.abspath(args.scene), "rows": rows}, f, indent=2)
    with open(os.path.join(args.output, "study.csv"), "w", newline="") as f:
        # Every row's columns (a label may appear at one magnitude only).
        fields = list(dict.fromkeys(key for row in rows for key in row))
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, os.path.join(args.output, "study.png"), base_scene.get("name", os.path.basename(args.scene)))
    print(f"wrote study.json, study.csv and study.png to {args.output}")


if __name__ == "__main__":
    main()
