"""Runs bids-validator (npm, 1.x; scripts/install-deps.sh installs it) on a dataset phantasm wrote:
the raw dataset and derivatives/phantasm must have no error, and only the warnings
docs/use-with-your-tools.md explains. Arguments: phantasm executable, scene file, output folder,
bids-validator executable. Prints what the validator found; exits non-zero on a failure."""
import json
import shutil
import subprocess
import sys

phantasm, scene, out, validator = sys.argv[1:5]
# TOO_FEW_AUTHORS: the only author is the program that made the data (the scene names no people).
EXPLAINED_WARNINGS = {"TOO_FEW_AUTHORS"}

shutil.rmtree(out, ignore_errors=True)
run = subprocess.run([phantasm, "run", scene, "-o", out, "-q"], capture_output=True, text=True)
if run.returncode != 0:
    sys.exit("phantasm run failed: " + run.stderr)
failed = False
for dataset in (out, out + "/derivatives/phantasm"):
    result = subprocess.run([validator, "--json", dataset], capture_output=True, text=True)
    try:
        issues = json.loads(result.stdout)["issues"]
    except (ValueError, KeyError):
        sys.exit("%s: bids-validator gave no JSON report (exit %d): %s" % (dataset, result.returncode, result.stderr))
    errors = issues["errors"]
    warnings = issues["warnings"]
    unexplained = [w for w in warnings if w["key"] not in EXPLAINED_WARNINGS]
    print("%s: exit %d, %d errors, warnings %s" % (dataset, result.returncode, len(errors),
                                                  [w["key"] for w in warnings]))
    for issue in errors + unexplained:
        files = [f["file"]["relativePath"] for f in issue.get("files", []) if f.get("file")][:5]
        print("  %s %s: %s %s" % (issue["severity"], issue["key"], issue["reason"], files))
    failed |= result.returncode != 0 or bool(errors) or bool(unexplained)
sys.exit(1 if failed else 0)
