#!/usr/bin/env python3
"""Docs reviewed against the code: every function, file and configuration key that a document
names in backticks must exist in the source tree.

    python3 tools/check_doc_refs.py [REPO] [--docs 'docs/*.md']... [-v]

Checked, for each backticked span of the documents (--docs, a glob from REPO, may be given more
than once; default docs/*.md) that is exactly one of these:
  `name()`, `ns::Class::name(...)`  a function: each component is an identifier in the sources
                                     (src/, bench/, tests/, tools/, fuzz/), the last one
                                     followed by `(` somewhere
  `src/...`, `bench/...`, `tests/...`, `tools/...`, `docs/...`, `examples/...`, `fuzz/...`
                                     a path (globs allowed): it exists
  `name.cpp`, `name.hpp`, `name.py`   a file: one of that name exists in the repository
  `[section] key`, `[section]`       a configuration key: the section and the key appear as
                                     string literals in src/config/
Spans with spaces or other text (commands, formulas) are not checked. Prints every name that
is missing as DOC:LINE: error: ...; exit code 1 when there is one.
"""
import argparse
import glob
import os
import re
import sys

CODE_DIRS = ("src", "bench", "tests", "tools", "fuzz")
CODE_EXT = (".cpp", ".hpp", ".h", ".py", ".sh", ".txt", ".cmake")
PATH_ROOTS = ("src", "bench", "tests", "tools", "docs", "examples", "fuzz")
SPAN = re.compile(r"`([^`\n]+)`")
FUNCTION = re.compile(r"^((?:[A-Za-z_]\w*::)*~?[A-Za-z_]\w*)\((.*)\)$")
PATH = re.compile(r"^(%s)/[\w./*{}-]*$" % "|".join(PATH_ROOTS))
FILE = re.compile(r"^[\w.-]+\.(cpp|hpp|py|sh)$")
CONFIG = re.compile(r"^\[([\w.]+)\](?:\s+(\w+))?(?:\s*=.*)?$")


def read_tree(repo, dirs, ext):
    text = {}
    for d in dirs:
        for dirpath, dirnames, names in os.walk(os.path.join(repo, d)):
            dirnames[:] = [x for x in dirnames if not x.startswith((".", "build"))]
            for n in names:
                if n.endswith(ext):
                    p = os.path.join(dirpath, n)
                    with open(p, encoding="utf-8", errors="replace") as f:
                        text[p] = f.read()
    return text


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("repo", nargs="?", default=os.path.join(here, ".."))
    ap.add_argument("--docs", action="append")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args()
    repo = os.path.abspath(args.repo)
    patterns = args.docs or ["docs/*.md"]
    docs = sorted({d for p in patterns for d in glob.glob(os.path.join(repo, p))})
    if not docs:
        print(f"check_doc_refs: no documents match {patterns} in {repo}", file=sys.stderr)
        return 2
    code = "\n".join(read_tree(repo, CODE_DIRS, CODE_EXT).values())
    config = "\n".join(read_tree(repo, ("src/config",), (".cpp", ".hpp")).values())
    basenames = set()
    for dirpath, dirnames, names in os.walk(repo):
        dirnames[:] = [x for x in dirnames if not x.startswith((".", "build"))]
        basenames.update(names)
    identifiers = set(re.findall(r"[A-Za-z_]\w*", code))
    called = set(re.findall(r"([A-Za-z_]\w*)\s*\(", code))

    errors, checked = 0, 0
    for doc in docs:
        rel = os.path.relpath(doc, repo)
        with open(doc, encoding="utf-8") as f:
            lines = f.read().split("\n")
        for no, line in enumerate(lines, 1):
            for m in SPAN.finditer(line):
                span = m.group(1).strip()
                problem = None
                if (f := FUNCTION.match(span)):
                    parts = f.group(1).lstrip("~").split("::")
                    missing = [p for p in parts if p not in identifiers]
                    if missing:
                        problem = f"`{span}`: no {'::'.join(missing)} in the sources"
                    elif parts[-1] not in called:
                        problem = f"`{span}`: {parts[-1]} is never called or defined"
                elif PATH.match(span):
                    if not glob.glob(os.path.join(repo, span.rstrip("/"))):
                        problem = f"`{span}`: no such path"
                elif FILE.match(span):
                    if span not in basenames:
                        problem = f"`{span}`: no such file in the repository"
                elif (c := CONFIG.match(span)):
                    section, key = c.group(1), c.group(2)
                    for name in [section.split(".")[-1]] + ([key] if key else []):
                        if f'"{name}"' not in config:
                            problem = f"`{span}`: \"{name}\" is not read in src/config"
                            break
                else:
                    continue
                checked += 1
                if problem:
                    errors += 1
                    print(f"{rel}:{no}:{m.start(1)}: error: {problem}")
                elif args.verbose:
                    print(f"{rel}:{no}: ok `{span}`")
    print(f"check_doc_refs: {checked} names in {len(docs)} documents, {errors} missing")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
