#!/usr/bin/env python3
"""Finds file-level import circles in the project's Rust crates.

Each crate's files are nodes; file A depends on file B when A names a path into B: a `use`
line or a path written in code (`crate::x::y`, `super::y`, `self::y`), test code included (a
test module kept in a file of its own, `mod tests;`, is a node of its own). `mod` declarations
and the crate root's `pub mod`/`pub use` lines are not dependencies. The script
prints every strongly connected component of more than one file and exits 1 if there is one,
0 otherwise. `tests/contract/rules.rs` runs it.

Usage: scripts/import_cycles.py [REPO_ROOT]
"""

import os
import re
import sys

# The crates' source folders, relative to the repository root.
CRATES = ["common/src", "io/src", "cpu/src", "reference/src", "gpu/src", "testkit/src", "src"]

PATH_RE = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE_GROUP_RE = re.compile(r"\buse\s+(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)*)::\{")


def strip_comments(text):
    """The text without `//` comments and string literals (doc comments name paths too)."""
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    return "\n".join(line.split("//", 1)[0] for line in text.split("\n"))


def module_files(src):
    """Map of module path (tuple) to file."""
    files = {}
    for dirpath, dirnames, filenames in os.walk(src):
        dirnames[:] = [d for d in dirnames if not d.startswith(".")]
        for name in filenames:
            if not name.endswith(".rs"):
                continue
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, src)[: -len(".rs")].split(os.sep)
            if rel[-1] == "mod" or rel == ["lib"] or rel == ["main"]:
                rel = rel[:-1]
            files[tuple(rel)] = path
    return files


def resolve(files, here, head, tail):
    """The file a path `head::tail` written in module `here` points into, or None."""
    if head == "crate":
        base = ()
    elif head == "self":
        base = here
    else:
        base = here
        for _ in head.split("::"):
            base = base[:-1]
    parts = list(base) + tail
    for n in range(len(parts), 0, -1):
        if tuple(parts[:n]) in files:
            return files[tuple(parts[:n])]
    return None


def deps_of(files, mod, path):
    text = strip_comments(open(path, encoding="utf-8").read())
    is_root = mod == ()
    deps = set()
    body = "\n".join(
        line for line in text.split("\n") if not (is_root and re.match(r"\s*pub\s+(mod|use)\b", line))
    )
    # `super::super::x` is written as repeated heads.
    for m in re.finditer(r"\b((?:super::)+)((?:[A-Za-z_][A-Za-z0-9_]*)(?:::[A-Za-z_][A-Za-z0-9_]*)*)", body):
        heads = m.group(1).rstrip(":")
        tail = m.group(2).split("::")
        target = resolve(files, mod, heads, tail)
        if target and target != path:
            deps.add(target)
    for m in PATH_RE.finditer(body):
        if m.group(1) == "super":
            continue
        tail = m.group(2).split("::")[1:]
        target = resolve(files, mod, m.group(1), tail)
        if target and target != path:
            deps.add(target)
    # `use crate::{a::X, b::Y}` and `use super::{..}`: each item of the group.
    for m in USE_GROUP_RE.finditer(body):
        start = m.end()
        depth, k = 1, start
        while k < len(body) and depth:
            depth += {"{": 1, "}": -1}.get(body[k], 0)
            k += 1
        prefix = m.group(2).split("::")[1:] if m.group(2) else []
        for item in re.findall(r"[A-Za-z_][A-Za-z0-9_]*(?:::[A-Za-z_][A-Za-z0-9_]*)*", body[start:k - 1]):
            target = resolve(files, mod, m.group(1), prefix + item.split("::"))
            if target and target != path:
                deps.add(target)
    return deps


def components(graph):
    """Tarjan's strongly connected components."""
    index, low, on, stack, out = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
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
            out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
    found = []
    checked = 0
    for crate in CRATES:
        src = os.path.join(root, crate)
        if not os.path.isdir(src):
            continue
        files = module_files(src)
        graph = {}
        for mod, path in files.items():
            graph[path] = deps_of(files, mod, path)
            checked += 1
        for comp in components(graph):
            if len(comp) > 1:
                rel = {p: os.path.relpath(p, root) for p in graph}
                edges = {rel[a]: {rel[b] for b in graph[a]} for a in comp}
                found.append(([rel[p] for p in comp], edges))
    for comp, graph in found:
        print("import circle: " + " <-> ".join(comp))
        for a in comp:
            for b in sorted(graph[a]):
                if b in comp:
                    print(f"  {a} -> {b}")
    print(f"{checked} files checked, {len(found)} import circles")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
