#!/usr/bin/env python3
"""Module cycles among the files of each crate, from their `use` paths and `crate::` paths.

A file's module is named by its path (src/window/solve.rs -> window::solve; mod.rs and
lib.rs name their folder's module). A reference `crate::a::b::c` (in `use` or inline),
`super::x` or `self::x` is an edge to the deepest module file that exists on that path.
Edges between a module and its own ancestors or descendants do not count: a parent
declares its children (`mod x;`) and children use their parent's types. A cycle is a
strongly connected group of two or more files; the script prints each one with the
references that close it, and exits 1 when there is any.

Usage: python3 tools/module_cycles/check.py [CRATE_DIR ...]   (default: every crates/*)
"""
import re
import sys
from pathlib import Path

# `crate::`, `super::` or `self::` paths; a `use crate::{a, b::c}` group is expanded.
PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+|::\{)")


def module_of(src: Path, file: Path) -> tuple:
    parts = list(file.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("mod", "lib", "main"):
        parts = parts[:-1]
    return tuple(parts)


def strip_comments(text: str) -> str:
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//")[0] for line in text.splitlines())


def expand_groups(text: str) -> list:
    """Every path in the file, with `use a::{b, c::d}` groups written out."""
    paths = []
    for m in re.finditer(r"\buse\s+([^;]+);", text):
        paths.extend(expand(m.group(1).replace("\n", " ")))
    rest = re.sub(r"\buse\s+[^;]+;", "", text)
    for m in PATH.finditer(rest):
        if m.group(2) != "::{":
            paths.append(m.group(1) + m.group(2))
    return paths


def expand(tree: str) -> list:
    tree = tree.strip()
    depth, brace = 0, -1
    for i, ch in enumerate(tree):
        if ch == "{" and depth == 0:
            brace = i
            break
    if brace < 0:
        return [tree.split(" as ")[0].strip()]
    prefix = tree[:brace]
    inner = tree[brace + 1 : tree.rindex("}")]
    items, depth, start = [], 0, 0
    for i, ch in enumerate(inner):
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "," and depth == 0:
            items.append(inner[start:i])
            start = i + 1
    items.append(inner[start:])
    out = []
    for item in items:
        if item.strip():
            out.extend(expand(prefix + item.strip()))
    return out


def resolve(path: str, here: tuple, modules: set):
    segs = [s for s in path.split("::") if s]
    if not segs:
        return None
    if segs[0] == "crate":
        base, segs = (), segs[1:]
    elif segs[0] in ("super", "self"):
        base = here
        while segs and segs[0] in ("super", "self"):
            if segs[0] == "super":
                base = base[:-1]
            segs = segs[1:]
    else:
        return None
    best = None
    for k in range(len(segs) + 1):
        cand = base + tuple(segs[:k])
        if cand in modules:
            best = cand
    return best


def related(a: tuple, b: tuple) -> bool:
    n = min(len(a), len(b))
    return a[:n] == b[:n]


def cycles(src: Path):
    files = {module_of(src, f): f for f in sorted(src.rglob("*.rs"))}
    modules = set(files)
    edges = {m: {} for m in modules}
    for m, f in files.items():
        for p in expand_groups(strip_comments(f.read_text(encoding="utf-8"))):
            # A file's `self::` is its own module; a mod.rs's `super::` is its parent's.
            t = resolve(p, m, modules)
            if t is not None and t != m and not related(m, t):
                edges[m].setdefault(t, p)
    # Tarjan's strongly connected components.
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(modules):
        if v not in index:
            visit(v)
    return out, edges, files


def main(argv):
    root = Path(__file__).resolve().parents[2]
    crates = [Path(a) for a in argv] or sorted(p for p in (root / "crates").iterdir() if (p / "src").is_dir())
    found = 0
    for crate in crates:
        comps, edges, files = cycles(crate / "src")
        for comp in comps:
            found += 1
            print(f"{crate.name}: cycle among {', '.join(str(files[m].relative_to(crate)) for m in comp)}")
            for a in comp:
                for b, p in edges[a].items():
                    if b in comp:
                        print(f"    {files[a].relative_to(crate)} -> {files[b].relative_to(crate)} ({p})")
    if found:
        print(f"{found} module cycle(s)")
        return 1
    print(f"no module cycle in {len(crates)} crate(s)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
