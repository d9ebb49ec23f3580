"""Runs the blocks of docs/use-with-your-tools.md that are marked as tested (```python tested,
```sh tested), in order, in a folder that holds a phantasm run as out/. Exit 0 when every block
exits 0; prints each block's output.

Usage: check_tool_docs.py DOC FOLDER PHANTASM_DIR
"""
import os
import re
import subprocess
import sys

doc, folder, phantasm_dir = sys.argv[1], sys.argv[2], os.path.abspath(sys.argv[3])
blocks = re.findall(r"^```(python|sh) tested\n(.*?)^```$", open(doc).read(), re.S | re.M)
environment = dict(os.environ, PATH=phantasm_dir + os.pathsep + os.environ.get("PATH", ""))
failed = 0
for number, (language, code) in enumerate(blocks, 1):
    command = [sys.executable, "-c", code] if language == "python" else ["bash", "-euo", "pipefail", "-c", code]
    result = subprocess.run(command, cwd=folder, env=environment, capture_output=True, text=True)
    print(f"--- block {number} ({language}): exit {result.returncode}")
    print(result.stdout + result.stderr, end="")
    failed += result.returncode != 0
print(f"ran {len(blocks)} blocks, {failed} failed")
sys.exit(1 if failed or not blocks else 0)
