#!/usr/bin/env python3
"""Fails when a source file is over 500 lines or a function body over 80 lines.

Files: every .h/.cpp under the library folders, apps/ and tests/. Functions: a body that opens
with `{` after a closing parenthesis at the outermost level of a namespace or class (lambdas and
nested blocks count as part of their function). A deliberate heuristic, not a C++ parser: strings,
character literals and comments are skipped before braces are counted.
Usage: check_sizes.py [ROOT] [--max-file 500] [--max-function 80]
"""
import argparse
import os
import re
import sys

FOLDERS = ["core", "integrators", "latent", "autodiff", "vae", "refiner", "pipeline", "apps", "python", "tests"]
CONTROL = re.compile(r"\b(if|for|while|switch|catch|do|else)\b\s*(\(.*\))?\s*$")
CONTAINER = re.compile(r"\b(namespace|class|struct|union|enum)\b")


def strip_code(text):
    """The text with comments, strings and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c in "\"'":
            if c == '"' and i > 0 and text[i - 1] == "R":  # raw string R"(...)"
                j = text.find(')"', i)
                j = n if j < 0 else j + 2
            else:
                j = i + 1
                while j < n and text[j] != c:
                    j += 2 if text[j] == "\\" else 1
                j += 1
            out.append(" " + "\n" * text.count("\n", i, j))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def long_functions(path, limit):
    with open(path, encoding="utf-8", errors="replace") as f:
        code = strip_code(f.read())
    found = []
    stack = []  # per open brace: ("function", start line) | ("scope", None) | ("block", None)
    line = 1
    last = 0
    for i, c in enumerate(code):
        if c == "\n":
            line += 1
        elif c == "{":
            head = code[last:i]
            head_line = head.strip().split("\n")[-1] if head.strip() else ""
            inside_function = any(kind == "function" for kind, _ in stack)
            if inside_function:
                stack.append(("block", None))
            elif CONTAINER.search(head) and ")" not in head.split(CONTAINER.search(head).group(0))[-1]:
                stack.append(("scope", None))
            elif ")" in head and not CONTROL.search(head_line) and "=" not in head.rsplit(")", 1)[-1]:
                stack.append(("function", line))
            else:
                stack.append(("block", None))
            last = i + 1
        elif c == "}":
            if stack:
                kind, start = stack.pop()
                if kind == "function" and line - start + 1 > limit:
                    found.append((start, line - start + 1))
            last = i + 1
        elif c == ";":
            last = i + 1
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("root", nargs="?", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--max-file", type=int, default=500)
    ap.add_argument("--max-function", type=int, default=80)
    args = ap.parse_args()
    problems = []
    for top in FOLDERS:
        for dirpath, _, files in os.walk(os.path.join(args.root, top)):
            for name in sorted(files):
                if not name.endswith((".h", ".cpp")):
                    continue
                path = os.path.join(dirpath, name)
                rel = os.path.relpath(path, args.root)
                with open(path, encoding="utf-8", errors="replace") as f:
                    lines = sum(1 for _ in f)
                if lines > args.max_file:
                    problems.append(f"{rel}: {lines} lines (limit {args.max_file})")
                for start, length in long_functions(path, args.max_function):
                    problems.append(f"{rel}:{start}: function of {length} lines (limit {args.max_function})")
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} size limit(s) exceeded")
        return 1
    print(f"sizes: every file <= {args.max_file} lines, every function <= {args.max_function} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main())
