#!/usr/bin/env python3
"""Import circles between the modules of each crate, and imports that run back up the module tree.

Each `.rs` file is a module (`mod.rs` and `lib.rs`/`main.rs` name their folder's module). A module
depends on another when it names it in a path: `use crate::a::b::Item`, `crate::a::b::f()`,
`super::b::Item`. A path is resolved to the deepest module file it names; an item that a module
re-exports (`pub use sub::Item`) is followed to the module that defines it, so that a parent's
re-exports make no circle by themselves. Test modules (`#[cfg(test)] mod tests { ... }` to the end of
the file, and modules declared `#[cfg(test)] mod name;`) are left out.

    python3 scripts/module-graph.py            # circles and upward imports of every crate
    python3 scripts/module-graph.py --counts   # one line of counts (for docs/architecture.md)
"""
import os
import re
import sys

CRATES = ["core", "frame", "scene", "host-cpu", "host-vulkan", "cli", "gpu-kernel"]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def module_files(crate):
    src = os.path.join(ROOT, crate, "src")
    files = {}
    for dirpath, _, names in os.walk(src):
        for n in names:
            if not n.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(dirpath, n), src)[:-3].split(os.sep)
            if rel[-1] in ("mod", "lib", "main"):
                rel = rel[:-1]
            files[tuple(rel)] = os.path.join(dirpath, n)
    return files


def strip(text):
    """The file without comments, strings, and its trailing test module."""
    m = re.search(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{", text)
    if m:
        text = text[: m.start()]
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'"(\\.|[^"\\])*"', '""', text)
    return inline_modules_as_self(text)


def inline_modules_as_self(text):
    """Inside an inline `mod name { ... }`, `super::` names the file's own module: written `self::`."""
    out, i = [], 0
    for m in re.finditer(r"\bmod\s+\w+\s*\{", text):
        if m.start() < i:
            continue
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        out.append(text[i : m.end()])
        out.append(text[m.end() : j].replace("super::", "self::"))
        i = j
    out.append(text[i:])
    return "".join(out)


PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE = re.compile(r"\buse\s+([^;]+);")


def paths_in(text):
    """Every `crate::`, `super::` or `self::` path, brace groups of `use` expanded."""
    out = []
    for m in USE.finditer(text):
        out.extend(expand(m.group(1).replace("\n", " ")))
    rest = USE.sub("", text)
    for m in PATH.finditer(rest):
        out.append(m.group(1) + m.group(2))
    return [p for p in out if p.split("::")[0] in ("crate", "super", "self")]


def expand(tree):
    tree = re.sub(r"\s+", "", tree)
    m = re.match(r"^(.*?)::\{(.*)\}$", tree)
    if not m:
        return [re.sub(r"as\w+$", "", tree).split(" as ")[0]]
    prefix, inner = m.group(1), m.group(2)
    parts, depth, cur = [], 0, ""
    for ch in inner:
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    if cur:
        parts.append(cur)
    out = []
    for p in parts:
        for e in expand(p):
            out.append(prefix if e == "self" else prefix + "::" + e)
    return out


def absolute(path, here):
    segs = path.split("::")
    if segs[0] == "crate":
        return segs[1:]
    base = list(here)
    if segs[0] == "self":
        segs = segs[1:]
    while segs and segs[0] == "super":
        base = base[:-1]
        segs = segs[1:]
    return base + segs


def resolve(segs, files, reexports):
    """The module a path's item lives in: the deepest module file it names, through re-exports."""
    for _ in range(8):
        k = len(segs)
        while k > 0 and tuple(segs[:k]) not in files:
            k -= 1
        module = tuple(segs[:k])
        rest = segs[k:]
        if rest and (module, rest[0]) in reexports:
            segs = reexports[(module, rest[0])] + rest[1:]
            continue
        return module
    return module


TEST_MODULE = re.compile(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;")


def graph(crate):
    files = module_files(crate)
    # Modules declared `#[cfg(test)] mod name;` (and theirs) are test code: left out.
    test_only = set()
    for m, p in files.items():
        for t in TEST_MODULE.finditer(open(p, encoding="utf-8").read()):
            test_only.add(m + (t.group(1),))
    files = {m: p for m, p in files.items() if not any(m[: len(t)] == t for t in test_only)}
    texts = {m: strip(open(p, encoding="utf-8").read()) for m, p in files.items()}
    reexports = {}
    for m, text in texts.items():
        for u in re.finditer(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]+);", text):
            for p in expand(u.group(1)):
                segs = p.split("::")
                if segs[0] not in ("crate", "super", "self"):
                    segs = ["self"] + segs
                target = absolute("::".join(segs), m)
                name = target[-1]
                if name != "*":
                    reexports[(m, name)] = target
    edges = {m: set() for m in files}
    for m, text in texts.items():
        for p in paths_in(text):
            target = resolve(absolute(p, m), files, reexports)
            if target != m and target in files:
                edges[m].add(target)
    return files, edges


def circles(edges):
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
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
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def name(m):
    return "::".join(m) if m else "(root)"


def main():
    counts = "--counts" in sys.argv
    total_circles, total_up = 0, 0
    for crate in CRATES:
        if not os.path.isdir(os.path.join(ROOT, crate, "src")):
            continue
        files, edges = graph(crate)
        found = circles(edges)
        # Upward: a module importing from its own ancestor's other children through the ancestor
        # is fine; importing from an ancestor module itself (the parent's own items) runs back up.
        up = sorted(
            (m, t) for m in edges for t in edges[m] if len(t) < len(m) and m[: len(t)] == t and t
        )
        total_circles += len(found)
        total_up += len(up)
        if counts:
            continue
        for comp in found:
            print(f"{crate}: circle: {' <-> '.join(name(m) for m in comp)}")
        for m, t in up:
            print(f"{crate}: upward: {name(m)} imports from its ancestor {name(t)}")
    print(f"circles: {total_circles}, upward imports: {total_up}")


if __name__ == "__main__":
    main()
