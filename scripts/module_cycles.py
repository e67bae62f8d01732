#!/usr/bin/env python3
"""Lists the cycles between the modules of each workspace crate (issue 18: "no module cycle").

A module uses another when its code names it by path: `use crate::a::b`, `use super::x`,
`crate::a::f()` or `super::y::Z` in an expression, grouped `use` lists included. Test modules
(`#[cfg(test)] mod tests`, from that line to the end of the file) are left out, as are the
`mod x;` declarations themselves (owning a child is not using it). A path resolves to the
longest module it names; naming an item of one's own ancestor counts (`use super::Item` in a
child is a use of the parent), so a parent that re-exports from a child while the child takes
items from the parent is a cycle, the kind issue 18 asked to remove.

Usage: scripts/module_cycles.py [CRATE_DIR ...]   (default: every crates/*)
Exit code 1 and the cycles when there are any, 0 and a one-line summary otherwise.

KNOWN lists the cycles that are known and not yet removed, each with the reason: they are
printed, and fail the check only when they grow beyond the subtree named.
"""
import os
import re
import sys


# (crate, module subtree): why its cycle is still there. Empty: the last one (the G-code
# rewriter's, issue 18) is gone; a new entry needs a reason and an issue.
KNOWN = {}


def module_files(src):
    """{module path tuple: file} for the files of one crate's src folder."""
    mods = {}
    for dirpath, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(dirpath, f), src)
            parts = rel[:-3].split(os.sep)
            if parts[-1] in ("lib", "main") and len(parts) == 1:
                parts = []
            elif parts[-1] == "mod":
                parts = parts[:-1]
            elif parts[0] == "bin":
                continue
            mods[tuple(parts)] = os.path.join(dirpath, f)
    return mods


def strip_noise(text):
    """The code without comments, string literals and the trailing test module."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'r#*"(?:.|\n)*?"#*', '""', text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    m = re.search(r"#\[cfg\(test\)\]\s*mod\s+\w+\s*\{", text)
    if m:
        text = text[: m.start()]
    return text


def expand_use(tree):
    """`a::{b, c::{d, e}}` -> ["a::b", "a::c::d", "a::c::e"]."""
    tree = tree.strip()
    i = tree.find("{")
    if i < 0:
        return [tree.split(" as ")[0].strip()]
    prefix = tree[:i]
    inner = tree[i + 1 : tree.rfind("}")]
    items, depth, cur = [], 0, ""
    for ch in inner:
        if ch == "," and depth == 0:
            items.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    items.append(cur)
    out = []
    for it in items:
        if it.strip():
            out += [prefix + p for p in expand_use(it)]
    return out


def reexports(code):
    """`pub use a::b::C;` -> {"C": "a::b::C"} (also grouped lists and `as` renames)."""
    out = {}
    for m in re.finditer(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]+);", code):
        for full in expand_use(m.group(1)):
            alias = re.search(r"\bas\s+(\w+)\s*$", full)
            path = full.split(" as ")[0].strip()
            out[alias.group(1) if alias else path.split("::")[-1]] = path
    return out


def paths_in(code):
    """Every path the code names, less its own `pub use` re-exports (a facade is not a use)."""
    paths = []
    body = re.sub(r"\bpub(?:\([^)]*\))?\s+use\s+[^;]+;", "", code)
    for m in re.finditer(r"\buse\s+([^;]+);", body):
        paths += expand_use(m.group(1))
    for m in re.finditer(r"\b((?:crate|super|self)(?:::\w+)+)", body):
        paths.append(m.group(1))
    return paths


def resolve(path, here, mods, exports=None, depth=0):
    """The module a path names (the longest existing prefix, followed through the re-exports
    of the module it lands in), or None (another crate)."""
    parts = [p for p in path.replace(" ", "").split("::") if p]
    if not parts:
        return None
    if parts[0] == "crate":
        base, rest = (), parts[1:]
    elif parts[0] in ("super", "self"):
        base = list(here)
        while parts and parts[0] in ("super", "self"):
            if parts[0] == "super":
                base = base[:-1]
            parts = parts[1:]
        base, rest = tuple(base), parts
    else:
        # a path relative to this module: a child module of it, else outside the crate
        if (here + (parts[0],)) in mods:
            base, rest = here, parts
        else:
            return None
    best, k = base, 0
    while k < len(rest) and (base + tuple(rest[: k + 1])) in mods:
        k += 1
        best = base + tuple(rest[:k])
    if exports and k < len(rest) and depth < 8:
        target = exports.get(best, {}).get(rest[k])
        if target is not None:
            via = resolve(target, best, mods, exports, depth + 1)
            if via is not None:
                return via
    return best


def sccs(graph):
    """Tarjan's strongly connected components."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
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
            out.append(comp)

    sys.setrecursionlimit(10000)
    for v in list(graph):
        if v not in index:
            visit(v)
    return out


def name(m):
    return "crate" if not m else "::".join(m)


def main():
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    crates = sys.argv[1:] or sorted(
        os.path.join(root, "crates", c) for c in os.listdir(os.path.join(root, "crates"))
    )
    found, n_mods = [], 0
    for c in crates:
        src = os.path.join(c, "src")
        if not os.path.isdir(src):
            continue
        mods = module_files(src)
        n_mods += len(mods)
        graph = {m: set() for m in mods}
        why = {}
        codes = {m: strip_noise(open(f, encoding="utf-8").read()) for m, f in mods.items()}
        exports = {m: reexports(code) for m, code in codes.items()}
        for m, code in codes.items():
            for p in paths_in(code):
                t = resolve(p, m, mods, exports)
                if t is not None and t != m:
                    graph[m].add(t)
                    why.setdefault((m, t), p)
        crate = os.path.basename(os.path.normpath(c))
        for comp in sccs(graph):
            names = [name(m) for m in comp]
            known = [
                why
                for (kc, sub), why in KNOWN.items()
                if kc == crate and all(n == sub or n.startswith(sub + "::") for n in names)
            ]
            if len(comp) > 1 and known:
                print(f"known cycle in {crate}: {', '.join(sorted(names))}: {known[0]}")
                continue
            if len(comp) > 1:
                edges = [
                    f"    {name(a)} -> {name(b)} ({why[(a, b)]})"
                    for a in sorted(comp)
                    for b in sorted(graph[a])
                    if b in comp
                ]
                found.append(f"{os.path.basename(c)}: " + ", ".join(sorted(map(name, comp))) + "\n" + "\n".join(edges))
    if found:
        print("module cycles:\n" + "\n".join(found))
        sys.exit(1)
    print(f"no module cycle in {len(crates)} crates ({n_mods} modules)")


if __name__ == "__main__":
    main()
