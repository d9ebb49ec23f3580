#!/usr/bin/python3
"""How well a run's structures keep the shape of the labels they were fitted to.

Compares a phantasm dataset's reference-state labels (derivatives/phantasm/sub-XX/ses-ref/anat/
*_dseg.nii.gz, named by derivatives/phantasm/dseg.tsv) with a label volume written by
`phantasm atlas colin27 -o LABELS.nii.gz` (named by LABELS.tsv next to it), per structure:
  * Dice of the structure's voxels against the derived labels it stands for;
  * HD95: the symmetric 95th percentile surface distance in mm, the larger of the two directed
    95th percentiles of the distances from each surface voxel of one to the nearest surface voxel
    of the other (a surface voxel has a 6-neighbour outside its structure);
  * the volume (ml) of the derived labels lying more than --far-mm (3) from the nearest voxel of
    the structure, and of the structure lying that far from the derived labels; for each, which
    labels of the other set those voxels carry and where they lie (their centroid, RAS mm).

The two label sets are mapped through their names: a run label named like a derived label stands
for it; an organ of the run's scene (derivatives/phantasm/sub-XX/scene.yaml) stands for the
derived labels of its `label_volume` shape, less those its tissue regions take as labels of their
own; a tissue region with a name of its own (`name:`) stands for its atlas label. Run labels that
stand for the same derived labels make one structure, named after the first (the skull organ and
the region of the scalp's voxels the atlas labels skull: the skull). --map NAME=LABEL+LABEL
overrides either. The derived labels are resampled onto the run's grid (nearest, through both
affines: the same world space, RAS mm).

Usage: scripts/structure_fidelity.py DATASET LABELS.nii.gz [--subject 01] [--far-mm 3]
                                     [--map NAME=LABEL+LABEL ...] [--json FILE]
Exit status 2 on bad input (a missing file, a name neither set maps), nothing written.
"""

import argparse
import csv
import glob
import json
import os
import sys

import nibabel
import numpy
from scipy import ndimage


class BadInput(Exception):
    pass


def read_names(table, key):
    """label value -> name from a TSV with columns KEY and name."""
    if not os.path.exists(table):
        raise BadInput(f"{table}: not found (expected the label table of the volume next to it)")
    names = {}
    with open(table) as f:
        for line, row in enumerate(csv.DictReader(f, delimiter="\t"), start=2):
            try:
                names[int(row[key])] = row["name"]
            except (KeyError, TypeError, ValueError):
                raise BadInput(f"{table}:{line}: expected an integer '{key}' and a 'name' column, "
                               f"found {dict(row)}")
    return names


def scene_mapping(scene_file):
    """run label name -> derived label names, from the organs and tissue regions of the scene."""
    if not os.path.exists(scene_file):
        return {}
    import yaml
    with open(scene_file) as f:
        scene = yaml.safe_load(f) or {}
    taken = {}
    mapping = {}
    for region in scene.get("tissue_regions") or []:
        taken.setdefault(region.get("organ"), set()).add(region.get("label"))
        if region.get("name"):
            mapping[region["name"]] = [region.get("label")]
    for organ in (scene.get("anatomy") or {}).get("organs") or []:
        shape = organ.get("shape") or {}
        if shape.get("type") != "label_volume":
            continue
        labels = shape.get("label")
        labels = [labels] if isinstance(labels, str) else list(labels or [])
        mapping[organ["name"]] = [x for x in labels if x not in taken.get(organ["name"], set())]
    return mapping


def resample_nearest(image, target):
    """image's labels at the centres of target's voxels (world space through both affines)."""
    source_from_target = numpy.linalg.inv(image.affine) @ target.affine
    grid = numpy.indices(target.shape[:3]).reshape(3, -1)
    points = source_from_target[:3, :3] @ grid + source_from_target[:3, 3:4]
    values = ndimage.map_coordinates(numpy.asanyarray(image.dataobj).squeeze().astype(numpy.int32), points,
                                     order=0, mode="constant", cval=0)
    return values.reshape(target.shape[:3])


def surface(mask):
    """Voxels of mask with a 6-neighbour outside it."""
    return mask & ~ndimage.binary_erosion(mask, structure=ndimage.generate_binary_structure(3, 1),
                                          border_value=0)


def distance_to(mask, spacing):
    """Per voxel, the distance (mm) to the nearest voxel of mask."""
    return ndimage.distance_transform_edt(~mask, sampling=spacing)


def crop_box(a, b, margin=2):
    """The slices of the bounding box of a | b grown by margin voxels (within the volume)."""
    where = numpy.argwhere(a | b)
    low = numpy.maximum(where.min(axis=0) - margin, 0)
    high = numpy.minimum(where.max(axis=0) + margin + 1, a.shape)
    return tuple(slice(int(lo), int(hi)) for lo, hi in zip(low, high))


def compare(run, derived, spacing, far_mm):
    """Dice, HD95 and the volumes lying more than far_mm from the other of two boolean masks."""
    voxel_ml = float(numpy.prod(spacing)) / 1000.0
    result = {"run_ml": float(run.sum()) * voxel_ml, "derived_ml": float(derived.sum()) * voxel_ml}
    total = int(run.sum()) + int(derived.sum())
    result["dice"] = 2.0 * float((run & derived).sum()) / total if total else float("nan")
    if not run.any() or not derived.any():
        result.update(hd95_mm=float("inf"), derived_far_ml=result["derived_ml"], run_far_ml=result["run_ml"])
        return result, derived.copy(), run.copy()
    box = crop_box(run, derived)
    r, d = run[box], derived[box]
    r_surface, d_surface = surface(r), surface(d)
    r_to_d = distance_to(d_surface, spacing)[r_surface]
    d_to_r = distance_to(r_surface, spacing)[d_surface]
    result["hd95_mm"] = float(max(numpy.percentile(r_to_d, 95), numpy.percentile(d_to_r, 95)))
    derived_far = numpy.zeros_like(derived)
    derived_far[box] = d & (distance_to(r, spacing) > far_mm)
    result["derived_far_ml"] = float(derived_far.sum()) * voxel_ml
    run_far = numpy.zeros_like(run)
    run_far[box] = r & (distance_to(d, spacing) > far_mm)
    result["run_far_ml"] = float(run_far.sum()) * voxel_ml
    return result, derived_far, run_far


def where_far(far, run_labels, run_names, affine, voxel_ml):
    """Which run labels take the voxels in far (ml each, largest first) and their centroid (RAS mm)."""
    if not far.any():
        return {}
    values, counts = numpy.unique(run_labels[far], return_counts=True)
    order = numpy.argsort(-counts)
    taken = {run_names.get(int(values[i]), "background" if values[i] == 0 else str(int(values[i]))):
             float(counts[i]) * voxel_ml for i in order}
    centroid = affine[:3, :3] @ numpy.argwhere(far).mean(axis=0) + affine[:3, 3]
    return {"taken_by_ml": taken, "centroid_mm": [round(float(c), 1) for c in centroid]}


def structures(run_names, derived_names, mapping):
    """(run label values, name, derived label values) for every set of derived labels that run labels
    the mapping names stand for: those run labels united, named after the first."""
    by_name = {name: value for value, name in derived_names.items()}
    rows = []
    row_of = {}
    for value, name in sorted(run_names.items()):
        if value == 0:
            continue  # the background is no structure
        labels = mapping.get(name, [name] if name in by_name else None)
        if not labels:
            continue  # no derived label, or an organ whose every label a tissue region takes
        missing = [x for x in labels if x not in by_name]
        if missing:
            raise BadInput(f"structure '{name}': derived label(s) {', '.join(missing)} not in the derived "
                           f"label table (expected one of {', '.join(sorted(by_name))})")
        derived = [by_name[x] for x in labels]
        key = tuple(sorted(derived))
        if key in row_of:
            rows[row_of[key]][0].append(value)
            continue
        row_of[key] = len(rows)
        rows.append(([value], name, derived))
    if not rows:
        raise BadInput("no run label maps onto a derived label: expected names shared by dseg.tsv and the "
                       "derived table, organs of the run's scene.yaml, or --map NAME=LABEL+LABEL")
    return rows


def parse_map(items):
    mapping = {}
    for item in items:
        name, sep, labels = item.partition("=")
        if not sep or not name or not labels:
            raise BadInput(f"--map {item}: expected NAME=LABEL[+LABEL...]")
        mapping[name] = labels.split("+")
    return mapping


def load_inputs(args):
    derivatives = os.path.join(args.dataset, "derivatives", "phantasm")
    pattern = os.path.join(derivatives, f"sub-{args.subject}", "ses-ref", "anat", "*_ses-ref_dseg.nii.gz")
    matches = sorted(glob.glob(pattern))
    if not matches:
        raise BadInput(f"{args.dataset}: no {os.path.relpath(pattern, args.dataset)} (expected a phantasm dataset)")
    if not os.path.exists(args.labels):
        raise BadInput(f"{args.labels}: not found (expected the volume of `phantasm atlas colin27 -o FILE`)")
    run_image = nibabel.load(matches[0])
    derived_image = nibabel.load(args.labels)
    run_names = read_names(os.path.join(derivatives, "dseg.tsv"), "index")
    table = args.labels[:-len(".nii.gz")] + ".tsv" if args.labels.endswith(".nii.gz") else \
        os.path.splitext(args.labels)[0] + ".tsv"
    derived_names = read_names(table, "label")
    mapping = scene_mapping(os.path.join(derivatives, f"sub-{args.subject}", "scene.yaml"))
    mapping.update(parse_map(args.map))
    return run_image, derived_image, run_names, derived_names, mapping


def measure(args):
    run_image, derived_image, run_names, derived_names, mapping = load_inputs(args)
    rows = structures(run_names, derived_names, mapping)
    run_labels = numpy.rint(numpy.asanyarray(run_image.dataobj).squeeze()).astype(numpy.int32)
    derived_labels = resample_nearest(derived_image, run_image)
    spacing = tuple(float(s) for s in run_image.header.get_zooms()[:3])
    voxel_ml = float(numpy.prod(spacing)) / 1000.0
    report = {"dataset": os.path.abspath(args.dataset), "labels": os.path.abspath(args.labels),
              "far_mm": args.far_mm, "structures": []}
    for values, name, derived_values in rows:
        result, far, run_far = compare(numpy.isin(run_labels, values), numpy.isin(derived_labels, derived_values),
                                       spacing, args.far_mm)
        result.update(name=name, derived=[derived_names[v] for v in derived_values],
                      run=[run_names[v] for v in values])
        result["derived_far"] = where_far(far, run_labels, run_names, run_image.affine, voxel_ml)
        result["run_far"] = where_far(run_far, derived_labels, derived_names, run_image.affine, voxel_ml)
        report["structures"].append(result)
    return report


def print_report(report):
    far = report["far_mm"]
    print(f"{'structure':<18} {'Dice':>6} {'HD95 mm':>8} {'run ml':>8} {'derived ml':>10} "
          f"{'derived >' + str(far) + ' mm ml':>18} {'run >' + str(far) + ' mm ml':>14}")
    for row in report["structures"]:
        print(f"{row['name']:<18} {row['dice']:6.3f} {row['hd95_mm']:8.1f} {row['run_ml']:8.1f} "
              f"{row['derived_ml']:10.1f} {row['derived_far_ml']:18.2f} {row['run_far_ml']:14.2f}")
    print(f"Voxels more than {far} mm from the other set (ml by the label the other set gives them; centroid RAS mm):")
    for row in report["structures"]:
        for key, what in (("derived_far", "derived, run labels"), ("run_far", "run, derived labels")):
            taken = row[key].get("taken_by_ml", {})
            if sum(taken.values()) >= 0.05:
                labels = ", ".join(f"{name} {ml:.2f}" for name, ml in list(taken.items())[:3])
                print(f"  {row['name']:<18} {what}: {labels} (centroid {row[key]['centroid_mm']})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", help="a phantasm output folder (e.g. out of scripts/run.sh)")
    parser.add_argument("labels", help="the derived labels, e.g. of `phantasm atlas colin27 -o FILE.nii.gz`")
    parser.add_argument("--subject", default="01")
    parser.add_argument("--far-mm", type=float, default=3.0, help="distance beyond which a voxel is misplaced")
    parser.add_argument("--map", action="append", default=[], metavar="NAME=LABEL+LABEL",
                        help="the derived labels a run label stands for (repeatable)")
    parser.add_argument("--json", default=None, help="write the figures here")
    args = parser.parse_args()
    try:
        report = measure(args)
    except BadInput as error:
        print(f"structure_fidelity: {error}", file=sys.stderr)
        sys.exit(2)
    print_report(report)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
