#!/usr/bin/env python3
"""Size limits of the source tree: files over a line limit and functions over a line limit must
say why at their top, or the check fails.

    python3 tools/check_sizes.py [ROOT] [--file-limit 800] [--function-limit 100] [--list]
                                 [--known FILE]

ROOT defaults to the repository's src/. A file over the limit needs a line starting with
`// Size:` among its first 30 lines; a function over the limit needs a `// Size:` line in the
comment block right above its signature or among the first 3 lines of its body. The ones
listed in the known file (default tools/check_sizes_known.txt: `PATH` or `PATH FUNCTION` per
line, paths from the repository root) are reported but pass: they are to be split or given a
reason; an entry that no longer exceeds is reported so that it can be removed. --list prints
every file and function over the limits. Exit code 1 when one that is not known lacks a
reason, 0 otherwise.

Functions are found on clang-format's layout (the repository's .clang-format): a definition is a
signature ending in `{` (a constructor's initialiser list included), its end the matching `}`
(strings, character literals and comments skipped); lambdas, control statements, classes and
namespaces are not functions.
"""
import argparse
import os
import re
import sys

REASON = "// Size:"
SOURCE_EXT = (".cpp", ".hpp", ".h", ".cc")
NOT_FUNCTION = re.compile(
    r"^(if|for|while|switch|else|do|try|catch|return|namespace|class|struct|union|enum|extern)\b")
HEADER_END = re.compile(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(final)?\s*(->\s*[\w:<>, ]+)?\s*\{$")


def indent(line):
    return len(line) - len(line.lstrip(" "))


def signature_start(lines, i):
    """First line of the declaration whose header ends on line i (continuation lines back)."""
    j = i
    while j > 0:
        prev = lines[j - 1].strip()
        if prev.startswith("//"):
            # A comment inside a constructor's initialiser list: the list goes on above it.
            k = j - 1
            while k > 0 and lines[k].strip().startswith("//"):
                k -= 1
            if lines[k].strip().endswith(","):
                j = k + 1
                prev = lines[k].strip()
            else:
                break
        if (not prev or prev.endswith((";", "{", "}", ":")) or prev.startswith("#")
                or prev.endswith("*/")):
            break
        j -= 1
    return j


def closing_line(lines, i):
    """Index of the line where the brace opened at the end of line i closes (strings, character
    literals and comments skipped), None when it does not."""
    depth, k, in_block = 0, i, False
    while k < len(lines):
        text, c = lines[k], 0
        while c < len(text):
            two = text[c:c + 2]
            if in_block:
                if two == "*/":
                    in_block, c = False, c + 2
                    continue
                c += 1
                continue
            if two == "//":
                break
            if two == "/*":
                in_block, c = True, c + 2
                continue
            ch = text[c]
            if ch in "\"'":
                c += 1
                while c < len(text) and text[c] != ch:
                    c += 2 if text[c] == "\\" else 1
            elif ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
                if depth == 0:
                    return k
            c += 1
        k += 1
    return None


def has_reason_above(lines, start):
    j = start - 1
    while j >= 0 and lines[j].strip().startswith("//"):
        if lines[j].strip().startswith(REASON):
            return True
        j -= 1
    return False


def functions(lines):
    """(name, first line index, line count, has reason) of each function definition."""
    out = []
    for i, line in enumerate(lines):
        s = line.strip()
        if not s.endswith("{") or s.startswith(("//", "#")):
            continue
        is_init_list = s.startswith((":", ","))
        if not is_init_list and not HEADER_END.search(s):
            continue
        start = signature_start(lines, i)
        head = " ".join(x.strip() for x in lines[start:i + 1])
        if NOT_FUNCTION.match(head.lstrip("} ")) or "[" in head.split("(")[0] or "=" in head.split("(")[0]:
            continue
        if "(" not in head:
            continue
        end = closing_line(lines, i)
        if end is None:
            continue
        name = head.split("(")[0].split()[-1] if head.split("(")[0].split() else head[:40]
        body_top = lines[i + 1:i + 4]
        reason = has_reason_above(lines, start) or any(b.strip().startswith(REASON) for b in body_top)
        out.append((name, start, end - start + 1, reason))
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("root", nargs="?", default=os.path.join(here, "..", "src"))
    ap.add_argument("--file-limit", type=int, default=800)
    ap.add_argument("--function-limit", type=int, default=100)
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--known", default=os.path.join(here, "check_sizes_known.txt"))
    args = ap.parse_args()
    known = set()
    if os.path.exists(args.known):
        with open(args.known, encoding="utf-8") as f:
            known = {" ".join(x.split()) for x in f if x.strip() and not x.startswith("#")}
    seen_known = set()
    if not os.path.isdir(args.root):
        print(f"check_sizes: no directory {args.root}", file=sys.stderr)
        return 2
    failures, files_seen, functions_seen = [], 0, 0
    for dirpath, _, names in sorted(os.walk(args.root)):
        for n in sorted(names):
            if not n.endswith(SOURCE_EXT):
                continue
            path = os.path.join(dirpath, n)
            rel = os.path.relpath(path, os.path.join(args.root, ".."))
            with open(path, encoding="utf-8") as f:
                lines = f.read().split("\n")
            files_seen += 1
            count = len(lines) - (1 if lines and lines[-1] == "" else 0)
            if count > args.file_limit:
                ok = any(x.strip().startswith(REASON) for x in lines[:30])
                is_known = not ok and rel in known
                seen_known.add(rel)
                if args.list or not ok:
                    print(f"{rel}: {count} lines (limit {args.file_limit})"
                          + ("" if ok else f": no '{REASON}' line at its top")
                          + (" (known)" if is_known else ""))
                if not ok and not is_known:
                    failures.append(rel)
            for name, start, length, ok in functions(lines):
                functions_seen += 1
                if length <= args.function_limit:
                    continue
                key = f"{rel} {name}"
                is_known = not ok and key in known
                seen_known.add(key)
                if args.list or not ok:
                    print(f"{rel}:{start + 1}: {name}(): {length} lines (limit "
                          f"{args.function_limit})" + ("" if ok else f": no '{REASON}' line")
                          + (" (known)" if is_known else ""))
                if not ok and not is_known:
                    failures.append(key)
    for stale in sorted(known - seen_known):
        print(f"{stale}: listed in {os.path.relpath(args.known)} but within the limits now: "
              "remove the entry")
    print(f"check_sizes: {files_seen} files, {functions_seen} functions, "
          f"{len(failures)} over the limits without a reason and not known")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
