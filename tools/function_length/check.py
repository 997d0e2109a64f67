#!/usr/bin/env python3
"""Functions longer than a limit (default 80 lines) in the Rust files under some folders.

A function's length is counted in lines of the file, from the line of its `fn` keyword to
the line of its closing brace, both included (doc comments and attributes above it are
not counted; blank lines and comments inside it are). Comments, string and character
literals are blanked out before the braces are matched, so a brace inside one does not
count. Test functions count too. The script prints each function over the limit with its
file, line and length, and exits 1 when there is any.

Usage: python3 tools/function_length/check.py [--max N] [DIR_OR_FILE ...]
       (default: crates/swarmpose-odometry/src, the engine, and 80 lines)
"""
import argparse
import re
import sys
from pathlib import Path

DEFAULT_DIRS = ["crates/swarmpose-odometry/src"]

# Comments, raw strings, strings and character literals (not lifetimes: `'a` has no
# closing quote right after one character or escape).
LITERAL = re.compile(
    r"//[^\n]*"
    r"|/\*.*?\*/"
    r"|\br(#*)\".*?\"\1"
    r"|\"(?:\\.|[^\"\\])*\""
    r"|'(?:\\u\{[0-9a-fA-F]+\}|\\x[0-9a-fA-F]{2}|\\.|[^\\'\n])'",
    re.S,
)
FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")


def blank(text: str) -> str:
    """`text` with comments and literals replaced by spaces, line breaks kept."""
    return LITERAL.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


def functions(text: str):
    """(name, first line, last line) of each function with a body, 1-based lines."""
    code = blank(text)
    for m in FN.finditer(code):
        # The body opens at the first `{` outside the signature's brackets; a `;` there
        # first ends a declaration without a body.
        depth, i = 0, m.end()
        while i < len(code):
            ch = code[i]
            if ch in "([":
                depth += 1
            elif ch in ")]":
                depth -= 1
            elif depth == 0 and ch in "{;":
                break
            i += 1
        if i >= len(code) or code[i] == ";":
            continue
        braces, j = 0, i
        while j < len(code):
            if code[j] == "{":
                braces += 1
            elif code[j] == "}":
                braces -= 1
                if braces == 0:
                    break
            j += 1
        first = code.count("\n", 0, m.start()) + 1
        last = code.count("\n", 0, j) + 1
        yield m.group(1), first, last


def rust_files(paths):
    for p in paths:
        p = Path(p)
        if p.is_dir():
            yield from sorted(p.rglob("*.rs"))
        else:
            yield p


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max", type=int, default=80, help="most lines a function may have")
    parser.add_argument("paths", nargs="*", help="folders or files (default: the engine's src)")
    args = parser.parse_args()
    root = Path(__file__).resolve().parents[2]
    paths = args.paths or [root / d for d in DEFAULT_DIRS]
    long = []
    for file in rust_files(paths):
        for name, first, last in functions(file.read_text(encoding="utf-8")):
            n = last - first + 1
            if n > args.max:
                long.append((file, first, name, n))
    for file, line, name, n in long:
        try:
            file = file.resolve().relative_to(root)
        except ValueError:
            pass
        print(f"{file}:{line}: fn {name} has {n} lines, more than {args.max}")
    if long:
        print(f"{len(long)} function(s) over {args.max} lines", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
