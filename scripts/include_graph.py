#!/usr/bin/env python3
"""The dependency graph of phantasm's libraries, from their #include lines, checked against
their CMake links.

Reads every `#include "folder/file.hpp"` of the library folders (those whose CMakeLists.txt
declares a phantasm_add_library; tests, apps, bench and python are not libraries) and the
phantasm_add_library calls (SOURCES, HEADERS, PUBLIC_LIBS, PRIVATE_LIBS). Prints

* the folder graph: which folder includes which, with the number of #include lines;
* the target graph, when a folder declares more than one target (a header belongs to the
  target that lists it in SOURCES or HEADERS, or that compiles the .cpp of the same name, or
  that alone compiles the .cpp files of its directory, else to the folder's main target);
* each target's depth (the longest include path down to a target that includes no other), so a
  straight line shows as depths 0, 1, 2, ... one target each;
* per target: links that no include needs, includes with no link (and whether another link
  provides them publicly), and public headers whose include is only a PRIVATE link;
* includes of a stage (anatomy, sim, voxelize, mri) by the file formats (io), which stand below
  every stage: the types they read and write live in core and geometry.

Each of these, and a cycle, is a finding; the last line counts them.

Usage: scripts/include_graph.py [--root DIR] [--dot FILE] [--check]
Exit status 0, or with --check 1 when there is a finding (no third-party modules needed).
"""

import argparse
import os
import re
import sys
from collections import defaultdict

INCLUDE = re.compile(r'^\s*#\s*include\s+"([A-Za-z0-9_]+)/([^"]+)"')
CALL = re.compile(r"phantasm_add_library\s*\(([^)]*)\)", re.S)
KEYWORDS = ("SOURCES", "HEADERS", "PUBLIC_LIBS", "PRIVATE_LIBS")
SOURCE_EXTENSIONS = (".hpp", ".cpp", ".h")
# Targets that may include no stage, and the stages' targets.
BELOW_THE_STAGES = ("io",)
STAGES = ("anatomy", "sim", "voxelize", "mri")


class Target:
    def __init__(self, name, folder):
        self.name = name
        self.folder = folder
        self.files = set()  # paths relative to the root, e.g. "core/grid.cpp"
        self.public_links = []
        self.private_links = []


def strip_cmake_comments(text):
    return "\n".join(line.split("#", 1)[0] for line in text.splitlines())


def parse_targets(root):
    """Targets by name, from every <folder>/CMakeLists.txt directly under the root."""
    targets = {}
    for folder in sorted(os.listdir(root)):
        cmake = os.path.join(root, folder, "CMakeLists.txt")
        if folder.startswith(".") or folder == "build" or not os.path.isfile(cmake):
            continue
        with open(cmake, encoding="utf-8") as f:
            text = strip_cmake_comments(f.read())
        for match in CALL.finditer(text):
            words = match.group(1).split()
            target = Target(words[0], folder)
            section = None
            for word in words[1:]:
                if word in KEYWORDS:
                    section = word
                elif section in ("SOURCES", "HEADERS"):
                    target.files.add(folder + "/" + word)
                elif section in ("PUBLIC_LIBS", "PRIVATE_LIBS"):
                    if word.startswith("phantasm::"):
                        links = target.public_links if section == "PUBLIC_LIBS" else target.private_links
                        links.append(word[len("phantasm::"):])
            targets[target.name] = target
    return targets


def library_files(root, folders):
    """Source files of the library folders, relative to the root."""
    files = []
    for folder in sorted(folders):
        for directory, _, names in os.walk(os.path.join(root, folder)):
            for name in sorted(names):
                if name.endswith(SOURCE_EXTENSIONS):
                    files.append(os.path.relpath(os.path.join(directory, name), root).replace(os.sep, "/"))
    return files


def owner_function(targets):
    """Maps a file path (existing or generated, e.g. core/version.hpp) to its target's name."""
    by_folder = defaultdict(list)
    listed = {}
    for target in targets.values():
        by_folder[target.folder].append(target)
        for path in target.files:
            listed[path] = target.name
            stem, extension = os.path.splitext(path)
            if extension == ".cpp":
                listed.setdefault(stem + ".hpp", target.name)

    # Per directory, the targets that compile its .cpp files: a header beside the sources of one
    # target alone (e.g. mri/sequences/) belongs to it.
    by_directory = defaultdict(set)
    for target in targets.values():
        for path in target.files:
            if path.endswith(".cpp"):
                by_directory[os.path.dirname(path)].add(target.name)

    def owner(path):
        if path in listed:
            return listed[path]
        if len(by_directory.get(os.path.dirname(path), ())) == 1:
            return next(iter(by_directory[os.path.dirname(path)]))
        folder = path.split("/", 1)[0]
        candidates = by_folder.get(folder, [])
        for target in candidates:
            if target.name == folder:
                return target.name
        return candidates[0].name if len(candidates) == 1 else None

    return owner


def read_includes(root, path):
    includes = []
    with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
        for line in f:
            match = INCLUDE.match(line)
            if match:
                includes.append(match.group(1) + "/" + match.group(2))
    return includes


def depths(nodes, edges):
    """Longest path from each node down to a node without out-edges; None on a cycle."""
    memo, active = {}, set()

    def depth(node):
        if node in memo:
            return memo[node]
        if node in active:
            raise ValueError(node)
        active.add(node)
        value = max((depth(n) + 1 for n in edges.get(node, {})), default=0)
        active.discard(node)
        memo[node] = value
        return value

    try:
        return {node: depth(node) for node in nodes}
    except ValueError as cycle:
        print(f"cycle through {cycle}", file=sys.stderr)
        return None


def print_graph(title, nodes, edges):
    print(f"{title}: {sum(len(e) for e in edges.values())} edges, "
          f"{sum(sum(e.values()) for e in edges.values())} #include lines")
    for node in sorted(nodes):
        out = edges.get(node, {})
        listing = ", ".join(f"{n} ({out[n]})" for n in sorted(out))
        print(f"  {node:<14} -> {listing if listing else '(nothing)'}")
    level = depths(nodes, edges)
    if level is None:
        print("  not a DAG")
        return False
    by_level = defaultdict(list)
    for node, d in level.items():
        by_level[d].append(node)
    print("  depth (longest include path down): " +
          "; ".join(f"{d}: {' '.join(sorted(by_level[d]))}" for d in sorted(by_level)))
    return True


def write_dot(path, nodes, edges):
    with open(path, "w", encoding="utf-8") as f:
        f.write("digraph phantasm {\n  rankdir=BT;\n  node [shape=box, fontname=Helvetica];\n")
        for node in sorted(nodes):
            f.write(f'  "{node}";\n')
        for node in sorted(edges):
            for other, count in sorted(edges[node].items()):
                f.write(f'  "{node}" -> "{other}" [label="{count}"];\n')
        f.write("}\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    parser.add_argument("--dot", help="also write the target graph as Graphviz dot to this file")
    parser.add_argument("--check", action="store_true", help="exit with status 1 when there is a finding")
    args = parser.parse_args()
    root = os.path.abspath(args.root)

    targets = parse_targets(root)
    owner = owner_function(targets)
    folders = {t.folder for t in targets.values()}

    folder_edges = defaultdict(lambda: defaultdict(int))
    target_edges = defaultdict(lambda: defaultdict(int))
    # Per target, the targets its public headers (.hpp) include: those need PUBLIC links.
    public_needs = defaultdict(set)
    for path in library_files(root, folders):
        source = owner(path)
        if source is None:
            continue
        for include in read_includes(root, path):
            folder = include.split("/", 1)[0]
            if folder not in folders:
                continue
            if folder != path.split("/", 1)[0]:
                folder_edges[path.split("/", 1)[0]][folder] += 1
            destination = owner(include)
            if destination is None or destination == source:
                continue
            target_edges[source][destination] += 1
            if path.endswith((".hpp", ".h")):
                public_needs[source].add(destination)

    problems = 0
    if not print_graph("folder graph", folders, folder_edges):
        problems += 1
    if len(targets) != len(folders):
        print()
        if not print_graph("target graph", set(targets), target_edges):
            problems += 1
    if args.dot:
        write_dot(args.dot, set(targets), target_edges)
        print(f"\nwrote {args.dot}")

    def public_closure(name, seen=None):
        """Targets reachable through PUBLIC links (what linking `name` provides)."""
        seen = set() if seen is None else seen
        for link in targets[name].public_links if name in targets else []:
            if link not in seen:
                seen.add(link)
                public_closure(link, seen)
        return seen

    print("\nlinks against includes (per target):")
    for name in sorted(targets):
        target = targets[name]
        links = set(target.public_links) | set(target.private_links)
        needed = set(target_edges.get(name, {}))
        lines = []
        for link in sorted(links - needed):
            lines.append(f"link with no include: {link}")
        for include in sorted(needed - links):
            through = [link for link in sorted(links) if include in public_closure(link)]
            via = f" (provided publicly by {', '.join(through)})" if through else " (NOT provided by any link)"
            lines.append(f"include with no link: {include}{via}")
        for include in sorted(public_needs[name] & set(target.private_links)):
            lines.append(f"public header includes {include}, linked PRIVATE")
        problems += len(lines)
        print(f"  {name}: " + ("ok" if not lines else ""))
        for line in lines:
            print(f"    {line}")

    print("\nformats below the stages:")
    for name in BELOW_THE_STAGES:
        stages = sorted(set(target_edges.get(name, {})) & set(STAGES))
        problems += len(stages)
        print(f"  {name}: " + ("ok" if not stages else ""))
        for stage in stages:
            print(f"    includes the stage {stage} ({target_edges[name][stage]} #include lines)")
    print(f"{problems} findings")
    return 1 if args.check and problems else 0


if __name__ == "__main__":
    sys.exit(main())
