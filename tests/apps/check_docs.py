"""Checks that the documentation a newcomer reads holds together:
  * README.md has at most 200 lines (depth goes to docs/);
  * every page of docs/ (docs/*.md) is linked from docs/index.md;
  * every relative link of README.md and docs/*.md (Markdown links and images, reference
    definitions) names a file or folder that exists.
Code blocks and inline code are not read as links. Prints each problem as FILE:LINE: message.

Usage: check_docs.py ROOT        check the repository at ROOT; exit 1 on any problem
       check_docs.py --self-test build small trees with each kind of problem and require each to
                                 be reported (and a sound tree to pass); exit 1 otherwise
"""
import os
import re
import shutil
import sys
import tempfile

README_MAX_LINES = 200
INLINE_LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?([^\s>]+)>?", re.M)


def without_code(text):
    """The text with fenced code blocks and inline code blanked out, line breaks kept."""
    blank = lambda match: re.sub(r"[^\n]", " ", match.group(0))
    text = re.sub(r"^(```|~~~).*?^\1[^\n]*$", blank, text, flags=re.M | re.S)
    text = re.sub(r"^(    |\t)[^\n]*$", blank, text, flags=re.M)  # indented code blocks
    return re.sub(r"`[^`\n]*`", blank, text)


def links(text):
    """(line number, target) of every link in the text outside code."""
    prose = without_code(text)
    found = []
    for pattern in (INLINE_LINK, REFERENCE_DEFINITION):
        for match in pattern.finditer(prose):
            found.append((prose.count("\n", 0, match.start()) + 1, match.group(1)))
    return sorted(found)


def is_relative(target):
    return not (re.match(r"^[A-Za-z][A-Za-z0-9+.-]*:", target) or target.startswith("#") or target.startswith("/"))


def problems(root):
    found = []
    readme = os.path.join(root, "README.md")
    docs = os.path.join(root, "docs")
    index = os.path.join(docs, "index.md")
    if not os.path.isfile(readme):
        return ["README.md: expected the README, found no such file"]
    lines = open(readme, encoding="utf-8").read().count("\n")
    if lines > README_MAX_LINES:
        found.append("README.md: expected at most %d lines, found %d (move depth to docs/)" % (README_MAX_LINES, lines))
    pages = sorted(name for name in os.listdir(docs) if name.endswith(".md")) if os.path.isdir(docs) else []
    markdown = [readme] + [os.path.join(docs, name) for name in pages]
    linked_from_index = set()
    for path in markdown:
        where = os.path.relpath(path, root)
        text = open(path, encoding="utf-8").read()
        for line, target in links(text):
            if not is_relative(target):
                continue
            file_part = target.split("#", 1)[0].split("?", 1)[0]
            resolved = os.path.normpath(os.path.join(os.path.dirname(path), file_part))
            if not os.path.exists(resolved):
                found.append("%s:%d: link to %s: expected an existing file, found none at %s"
                             % (where, line, target, os.path.relpath(resolved, root)))
            elif path == index:
                linked_from_index.add(resolved)
    if os.path.isdir(docs) and not os.path.isfile(index):
        found.append("docs/index.md: expected an index of the docs pages, found no such file")
    else:
        for name in pages:
            page = os.path.normpath(os.path.join(docs, name))
            if name != "index.md" and page not in linked_from_index:
                found.append("docs/index.md: expected a link to %s, found none" % name)
    return found


def self_test():
    """Each kind of problem in a small tree is reported; the sound tree passes."""
    def tree(readme, pages):
        root = tempfile.mkdtemp(prefix="check-docs-")
        os.makedirs(os.path.join(root, "docs", "images"))
        open(os.path.join(root, "docs", "images", "a.png"), "w").close()
        open(os.path.join(root, "README.md"), "w").write(readme)
        for name, text in pages.items():
            open(os.path.join(root, "docs", name), "w").write(text)
        return root

    sound_readme = "# x\n\n[index](docs/index.md) ![p](docs/images/a.png) [web](https://example.org)\n"
    sound_pages = {"index.md": "| [a.md](a.md) | a |\n| [b](b.md#part) | b |\n",
                   "a.md": "[back](../README.md) [b](b.md)\n\n    [not a link](missing.md)\n\n`[nor](this.md)`\n",
                   "b.md": "[ref]: a.md\n[anchor](#top)\n"}
    cases = {
        "sound": (sound_readme, sound_pages, []),
        "long README": (sound_readme + "line\n" * README_MAX_LINES, sound_pages, ["expected at most 200 lines"]),
        "page not in the index": (sound_readme, dict(sound_pages, **{"c.md": "# c\n"}),
                                  ["docs/index.md: expected a link to c.md"]),
        "broken link in a page": (sound_readme, dict(sound_pages, **{"a.md": "x\n[gone](gone.md)\n"}),
                                  ["docs/a.md:2: link to gone.md"]),
        "broken image in the README": (sound_readme + "![i](docs/images/none.png)\n", sound_pages,
                                       ["README.md:4: link to docs/images/none.png"]),
        "broken reference definition": (sound_readme, dict(sound_pages, **{"b.md": "[ref]: nowhere.md\n"}),
                                        ["docs/b.md:1: link to nowhere.md"]),
        "no index": (sound_readme.replace("[index](docs/index.md)", ""),
                     {k: v for k, v in sound_pages.items() if k != "index.md"}, ["no such file"]),
    }
    failed = 0
    for name, (readme, pages, expected) in cases.items():
        root = tree(readme, pages)
        reported = problems(root)
        shutil.rmtree(root)
        ok = (not reported) if not expected else all(any(e in r for r in reported) for e in expected)
        ok = ok and (len(reported) == len(expected) or name == "no index")
        print("%s %s: %s" % ("ok  " if ok else "FAIL", name, reported))
        failed += not ok
    return failed


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(1 if self_test() else 0)
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    reported = problems(sys.argv[1])
    for problem in reported:
        print(problem)
    print("%d problems" % len(reported))
    sys.exit(1 if reported else 0)
