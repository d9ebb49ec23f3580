#!/usr/bin/env python3
"""The functions of phantasm's libraries longer than a limit (120 lines by default).

Reads the .cpp and .hpp files of the library folders (those whose CMakeLists.txt declares a
phantasm_add_library: tests, apps, bench, fuzz and python are not libraries) and finds every
function body at namespace or class scope by its braces, after removing comments, string and
character literals. A function's length runs from the line of its name to its closing brace;
the lambdas and local classes inside it count as part of it. Prints one line per function over
the limit, longest first: its length, file:line and name, then how many there are.

Usage: scripts/long_functions.py [--root DIR] [--limit LINES] [--check]
Exit status 0, or with --check 1 when a function is over the limit (no third-party modules).
"""

import argparse
import os
import re
import sys

CALL = re.compile(r"phantasm_add_library\s*\(\s*(\w+)")
EXTENSIONS = (".cpp", ".hpp", ".h")
TYPE_HEAD = re.compile(r"\b(struct|class|union|enum)\b[^()]*$")
NAMESPACE_HEAD = re.compile(r"\bnamespace\b[\w:\s]*$|\bextern\s*$")
NAME = re.compile(r"(operator\s*(?:\(\)|[^\s(]+)|~?[A-Za-z_]\w*(?:\s*::\s*~?[A-Za-z_]\w*)*)\s*(?:<[^()]*>)?\s*\(")
NOT_NAMES = {"if", "for", "while", "switch", "return", "sizeof", "decltype", "alignas", "static_assert",
             "catch", "noexcept", "requires"}


def library_folders(root):
    folders = []
    for folder in sorted(os.listdir(root)):
        cmake = os.path.join(root, folder, "CMakeLists.txt")
        if folder.startswith(".") or folder == "build" or not os.path.isfile(cmake):
            continue
        with open(cmake, encoding="utf-8") as f:
            if CALL.search("\n".join(line.split("#", 1)[0] for line in f)):
                folders.append(folder)
    return folders


def strip_code(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            open_paren = text.find("(", i + 2)
            delimiter = text[i + 2:open_paren]
            j = text.find(")" + delimiter + '"', open_paren)
            j = n if j < 0 else j + len(delimiter) + 2
            out.append('""' + "".join(ch for ch in text[i:j] if ch == "\n"))
            i = j
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            # A digit separator (1'000) is not a character literal: handled by the test above.
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """(name, first line, last line) of each function body at namespace or class scope."""
    code = strip_code(text)
    found = []
    stack = []  # per open brace: "namespace", "type", "function", "init" or "block"
    head, head_line = "", 1
    line = 1
    starts = []  # per open brace: (name, line) of a function
    for c in code:
        if c == "\n":
            line += 1
            head += " "
            continue
        if c == "{":
            scope = stack[-1] if stack else "namespace"
            stripped = head.strip()
            if scope in ("function", "block", "init"):
                kind = "block"
            elif NAMESPACE_HEAD.search(stripped):
                kind = "namespace"
            elif TYPE_HEAD.search(stripped):
                kind = "type"
            elif re.search(r"\)\s*:", stripped) and re.search(r"[\w>]\s*$", stripped) and \
                    not re.search(r"\)\s*(const\s*)?(noexcept\s*)?(override\s*)?(final\s*)?$", stripped):
                kind = "init"  # a member initialised with braces in a constructor's list
            elif ")" in stripped and not stripped.endswith("="):
                kind = "function"
            else:
                kind = "block"
            stack.append(kind)
            if kind == "function":
                names = [m.group(1) for m in NAME.finditer(stripped)
                         if m.group(1).split("::")[-1].strip() not in NOT_NAMES]
                starts.append((re.sub(r"\s+", "", names[0]) if names else "?", head_line))
            if kind != "init":
                head, head_line = "", line
            continue
        if c == "}":
            kind = stack.pop() if stack else "block"
            if kind == "function":
                name, first = starts.pop()
                found.append((name, first, line))
            if kind != "init":
                head, head_line = "", line
            continue
        if c == ";":
            head, head_line = "", line
            continue
        if not head.strip() and not c.isspace():
            head_line = line
        head += c
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    parser.add_argument("--limit", type=int, default=120, help="longest allowed function, lines")
    parser.add_argument("--check", action="store_true", help="exit with status 1 when a function is over the limit")
    args = parser.parse_args()
    root = os.path.abspath(args.root)

    long = []
    for folder in library_folders(root):
        for directory, _, names in os.walk(os.path.join(root, folder)):
            for file_name in sorted(names):
                if not file_name.endswith(EXTENSIONS):
                    continue
                path = os.path.join(directory, file_name)
                with open(path, encoding="utf-8", errors="replace") as f:
                    text = f.read()
                relative = os.path.relpath(path, root).replace(os.sep, "/")
                for name, first, last in functions(text):
                    if last - first + 1 > args.limit:
                        long.append((last - first + 1, relative, first, name))
    long.sort(key=lambda item: (-item[0], item[1], item[2]))
    for length, path, first, name in long:
        print(f"{length:5d}  {path}:{first}  {name}")
    print(f"{len(long)} functions over {args.limit} lines")
    return 1 if args.check and long else 0


if __name__ == "__main__":
    sys.exit(main())
